//! Issue #8 acceptance: a compensated NC program, pushed through the virtual machine (exact
//! rigid-body kinematics of the ground-truth errors), lands on its programmed path.
//!
//! The rewriter compensates with the first-order kinematic model of the truth (what an
//! identification would deliver at best); the machine that runs the output is the exact one.

use crate::gcode_support;
use gcode_support::*;
use mtec_comp::gcode::{rewrite, RewriteOptions};
use mtec_comp::kinematic::KinematicModel;
use mtec_comp::ErrorModel;
use mtec_model::{Formalism, Machine, Order, VolumetricModel};
use std::collections::BTreeMap;

/// The virtual machine as an error model: exact HTM kinematics of the truth.
struct VirtualMachine(VolumetricModel);

impl ErrorModel for VirtualMachine {
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        self.0
            .error(&p_mm, Formalism::Htm, Order::Exact)
            .position_um
    }
    fn describe(&self) -> String {
        "mtec-sim exact virtual machine".into()
    }
}

const PROGRAM: &str = "%
(pocket, slot and arcs inside the 600 x 800 x 300 mm travel)
N10 G21 G90 G17
N20 G0 Z250
N30 G0 X40 Y40
N40 G1 Z200 F500
N50 G1 X560 Y40 F1500
N60 G1 X560 Y760
N70 G2 X460 Y660 I-100 J0
N80 G1 X40 Y760
N90 G3 X40 Y560 I0 J-100
N100 G1 X40 Y40 Z150
N110 G0 Z290
M30
%
";

#[test]
fn compensated_program_lands_on_target_on_the_virtual_machine() {
    let machine = Machine::vmc_xyfz(100.0);
    let truth = mtec_sim::truth::geometric_truth(&machine, 1);
    let model = KinematicModel::new(&machine, &truth, "truth, first order").unwrap();
    let vm = VirtualMachine(VolumetricModel::new(&machine, &truth));
    let opts = RewriteOptions::default();
    let mut out = Vec::new();
    rewrite(PROGRAM.as_bytes(), &mut out, &model, &opts).unwrap();
    let output = String::from_utf8(out).unwrap();
    assert!(
        output.lines().count() > PROGRAM.lines().count(),
        "long moves are split where the error changes"
    );
    // 4 decimals in mm: rounding ≤ 0.05 µm per axis; first-order vs exact ≤ 0.01 µm here
    let round = 0.05e-3 * 3f64.sqrt();
    let (end, path) = check_lands_on_target(
        PROGRAM,
        &output,
        &vm,
        &[[0.0; 3]; 6],
        &BTreeMap::new(),
        None,
        round + 0.01e-3,
        opts.tolerance_um * 1e-3 + opts.chord_tolerance_um * 1e-3 + round + 0.01e-3,
    );
    println!(
        "worst end {:.3} µm, worst path {:.3} µm, {} -> {} lines",
        end * 1e3,
        path * 1e3,
        PROGRAM.lines().count(),
        output.lines().count()
    );
    // and without compensation the same machine misses by micrometres
    let (raw_end, _) = std::panic::catch_unwind(|| {
        check_lands_on_target(
            PROGRAM,
            PROGRAM,
            &vm,
            &[[0.0; 3]; 6],
            &BTreeMap::new(),
            None,
            1.0,
            1.0,
        )
    })
    .unwrap();
    assert!(
        raw_end > 5e-3,
        "uncompensated worst end {raw_end} mm: the truth must matter"
    );
}
