//! The kinematic model file (`mtec.kinematic-model/1`) that `identify lines --kinematic-model`
//! and `mtec run` write through [`KinematicFile::new`]: it loads back through the same loader
//! `compensate` uses and predicts what the machine and error set it was made from predict; a
//! machine the compensation cannot evaluate is refused before anything is written.

use mtec_comp::kinematic::{KinematicFile, KINEMATIC_FORMAT};
use mtec_comp::load::load_error_model;
use mtec_model::{Formalism, Machine, MachineSpec, Order, VolumetricModel};

#[test]
fn written_file_loads_and_predicts_the_machine_and_error_set_it_was_made_from() {
    let machine = Machine::vmc_xyfz(100.0);
    let truth = mtec_sim::truth::geometric_truth(&machine, 1);
    let file = KinematicFile::new(&machine, &truth).unwrap();
    assert_eq!(file.format, KINEMATIC_FORMAT);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("km.json");
    std::fs::write(&path, file.to_json().unwrap()).unwrap();
    let loaded = load_error_model(&path).unwrap();
    let direct = VolumetricModel::new(&machine, &truth);
    let (mut checked, mut largest) = (0, 0.0f64);
    for p in [
        [0.0, 0.0, 0.0],
        [100.0, 200.0, 50.0],
        [500.0, 700.0, 250.0],
        [600.0, 800.0, 300.0],
    ] {
        let want = direct
            .error(&p, Formalism::Htm, Order::FirstOrder)
            .position_um;
        let got = loaded.error_um(p);
        for a in 0..3 {
            // JSON keeps every f64 to its shortest round-trip text: agreement to rounding
            assert!(
                (got[a] - want[a]).abs() <= 1e-9 * want[a].abs().max(1.0),
                "{p:?}: {got:?} vs {want:?}"
            );
        }
        largest = want.iter().fold(largest, |m, v| m.max(v.abs()));
        checked += 1;
    }
    assert_eq!(checked, 4);
    assert!(
        largest > 10.0,
        "the truth has errors of tens of µm ({largest} µm)"
    );
}

#[test]
fn machine_without_y_is_refused_before_writing() {
    // the vertical machining centre with its Y axis taken out: a valid machine (X on the
    // workpiece side, Z on the tool side) that the three-axis compensation cannot evaluate
    let mut spec: MachineSpec = Machine::vmc_xyfz(100.0).to_spec();
    spec.chain = "WXFZT".into();
    spec.axes.remove("Y");
    let machine = Machine::from_spec(spec).unwrap();
    let set = mtec_model::ErrorSet::new("empty");
    let e = KinematicFile::new(&machine, &set).unwrap_err();
    assert!(e.contains('Y'), "{e}");
}
