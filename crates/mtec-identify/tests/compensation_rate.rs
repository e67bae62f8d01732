//! Issue #8 acceptance: compensation rate on the simulated machine after 9-line identification.
//!
//! The whole loop with nothing shared but files' contents: the virtual machine (exact kinematics,
//! ripple, laser noise) writes the 9-line measurement; identification builds the first-order
//! model; `mtec-comp` solves p + e(p) = target for each target with that model; the virtual
//! machine, commanded to p, lands at p + e_true(p). Rate = 1 − RMS(landed − target) /
//! RMS(e_true(target)) per axis and for the volumetric error, at 1000 random workspace points
//! (the same measurement, before and after, as SPEC §1 C defines it).

use crate::support;
use mtec_comp::kinematic::KinematicModel;
use mtec_comp::{command_for_target, CorrectionOptions};

use mtec_identify::lines::{identify_with, DEFAULT_DEGREE};
use mtec_model::{Formalism, Order, VolumetricModel};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn rates(seed: u64) -> ([f64; 3], f64, [f64; 3]) {
    let (machine, data, truth) = support::vmc_9line(seed);
    let id = identify_with(&machine, &data, DEFAULT_DEGREE).unwrap();
    let model = KinematicModel::new(&machine, &id.errors, "9-line identification").unwrap();
    let vm = VolumetricModel::new(&machine, &truth);
    let mut rng = StdRng::seed_from_u64(seed ^ 0xc0de);
    let (mut before, mut after) = ([0.0; 3], [0.0; 3]);
    let n = 1000;
    for _ in 0..n {
        // 5 mm inside the travel so the corrected command stays inside it
        let t: [f64; 3] = [0, 1, 2].map(|i| {
            let [lo, hi] = machine.travel(machine.axes[i]);
            rng.random_range(lo + 5.0..hi - 5.0)
        });
        let e0 = vm.error(&t, Formalism::Htm, Order::Exact).position_um;
        let p = command_for_target(&model, t, &CorrectionOptions::default()).unwrap();
        let e1 = vm.error(&p, Formalism::Htm, Order::Exact).position_um;
        for i in 0..3 {
            let landed_um = (p[i] - t[i]) * 1e3 + e1[i];
            before[i] += e0[i] * e0[i];
            after[i] += landed_um * landed_um;
        }
    }
    let rms = |v: f64| (v / n as f64).sqrt();
    let per_axis = [0, 1, 2].map(|i| 1.0 - rms(after[i]) / rms(before[i]));
    let vol = 1.0 - rms(after.iter().sum()) / rms(before.iter().sum());
    (per_axis, vol, [0, 1, 2].map(|i| rms(before[i])))
}

#[test]
fn compensation_rate_after_nine_line_identification_is_at_least_90_percent_per_axis() {
    for seed in [1, 2, 3] {
        let (per_axis, vol, before) = rates(seed);
        println!("seed {seed}: before RMS {before:.2?} µm, rates X {:.1} % Y {:.1} % Z {:.1} %, volumetric {:.1} %", per_axis[0] * 100.0, per_axis[1] * 100.0, per_axis[2] * 100.0, vol * 100.0);
        for (i, r) in per_axis.iter().enumerate() {
            assert!(
                *r >= 0.90,
                "seed {seed}: axis {i} rate {:.1} % below 90 %",
                r * 100.0
            );
        }
        // the machine must really have had something to compensate
        assert!(before.iter().all(|b| *b > 5.0), "{before:?}");
    }
}
