//! The virtual machine's geometric truth and its line and grid instruments.

use mtec_model::*;
use mtec_sim::instruments::LaserInterferometer;
use mtec_sim::truth::geometric_truth;
use mtec_sim::vmc_9line::measure_lines;

#[test]
fn truth_has_the_magnitudes_of_a_real_machine_and_follows_the_conventions() {
    let m = Machine::vmc_xyfz(100.0);
    for seed in 1..6 {
        let t = geometric_truth(&m, seed);
        assert_eq!(t.elements.len(), 21);
        for (el, f) in &t.elements {
            let [lo, hi] = m.travel(el.axis);
            let peak = (0..=200)
                .map(|k| f.value(lo + (hi - lo) * k as f64 / 200.0).abs())
                .fold(0.0, f64::max);
            let (min, max) = if el.location {
                (10.0, 50.0)
            } else if el.direction == el.axis {
                (10.0, 20.5)
            } else if !el.is_angular() {
                (2.0, 8.5)
            } else {
                (5.0, 30.5)
            };
            assert!(
                peak >= min * 0.99 && peak <= max,
                "seed {seed} {el}: peak {peak} outside [{min}, {max}]"
            );
            if !el.location {
                assert!(
                    f.value(lo).abs() < 1e-12,
                    "{el} must be zero at the axis origin"
                );
            }
        }
    }
}

#[test]
fn noiseless_laser_reads_the_exact_projection_computed_independently_by_poe() {
    let m = Machine::vmc_xyfz(100.0);
    let truth = geometric_truth(&m, 7);
    let lines = line_preset("nine-line", &m, 10, 10.0).unwrap();
    let laser = LaserInterferometer {
        noise_um: 0.0,
        straightness_noise_um: 0.0,
        alignment_urad: 0.0,
    };
    let (csv, _) = measure_lines(&m, &truth, &lines, &laser, 1);
    let vm = VolumetricModel::new(&m, &truth);
    let mut first: std::collections::HashMap<String, [f64; 3]> = Default::default();
    let mut rows = 0;
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let v: Vec<f64> = f[2..].iter().map(|s| s.parse().unwrap()).collect();
        let e = vm.error(&v[0..3], Formalism::Poe, Order::Exact).position_um;
        let e0 = *first.entry(f[0].to_string()).or_insert(e);
        let expected: f64 = (0..3).map(|i| v[3 + i] * (e[i] - e0[i])).sum();
        assert!((expected - v[6]).abs() < 2e-4, "{row}: expected {expected}");
        rows += 1;
    }
    // 6 axial lines × 3 channels + 3 diagonals × 1 channel, 11 points each
    assert_eq!(rows, (6 * 3 + 3) * 11);
}

#[test]
fn scenarios_are_deterministic_by_seed() {
    for name in ["vmc-9line", "volumetric-grid"] {
        let a = mtec_sim::run_scenario(name, 3).unwrap();
        let b = mtec_sim::run_scenario(name, 3).unwrap();
        let c = mtec_sim::run_scenario(name, 4).unwrap();
        assert_eq!(a.files[1].contents, b.files[1].contents);
        assert_ne!(a.files[1].contents, c.files[1].contents);
    }
    assert!(mtec_sim::run_scenario("nope", 1).is_err());
}
