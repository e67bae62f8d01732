//! The real-time path allocates nothing per call: a counting global allocator watches
//! `Compensator::correction_um` over many cycles.

use mtec_comp::map::{GridMap, Outside};
use mtec_comp::{Compensator, CorrectionOptions};
use std::alloc::{GlobalAlloc, Layout, System};

struct Counting;

thread_local! {
    // only the measuring test's own thread counts: this allocator serves the whole test binary
    // (tests/main.rs), whose tests run in parallel
    static COUNTING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    static MINE: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(|c| c.get()) {
            MINE.with(|m| m.set(m.get() + 1));
        }
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn correction_does_not_allocate() {
    let axes = [
        vec![0.0, 100.0, 200.0],
        vec![0.0, 50.0, 100.0],
        vec![-50.0, 0.0],
    ];
    let values: Vec<[f64; 3]> = (0..18)
        .map(|i| [i as f64, -(i as f64) * 0.5, 2.0])
        .collect();
    let map = GridMap::new(axes, values, Outside::Refuse, "rt test").unwrap();
    let comp = Compensator::new(Box::new(map), CorrectionOptions::default());
    let mut acc = 0.0;
    COUNTING.with(|c| c.set(true));
    let before = MINE.with(|m| m.get());
    for i in 0..10_000 {
        // targets at least 1 mm inside the grid: with `refuse`, a target on the edge whose
        // corrected command falls outside is refused (see map docs)
        let t = [1.0 + (i % 198) as f64, 1.0 + (i % 98) as f64, -25.0];
        let c = comp.correction_um(t).unwrap();
        acc += c[0];
    }
    // error paths too: outside the grid (refuse) and too large
    let outside = comp.correction_um([500.0, 0.0, 0.0]);
    let after = MINE.with(|m| m.get());
    COUNTING.with(|c| c.set(false));
    assert!(outside.is_err());
    assert!(acc.is_finite());
    assert_eq!(after - before, 0, "allocations during 10 001 corrections");
}

/// The state update of a machine model (map + a heat-input thermal part) and the corrections in
/// that state allocate nothing either.
#[test]
fn state_update_does_not_allocate() {
    use mtec_thermal::heat_input::HeatInputModel;
    use mtec_thermal::Split;
    use mtec_thermal::{Metrics, ModelFile, ThermalModel, MODEL_FORMAT};
    let dir = tempfile::tempdir().unwrap();
    let map = r#"{"format":"mtec.map/1","model":"trilinear","outside":"clamp","source":"t",
      "x_mm":[0,100],"y_mm":[0,100],"z_mm":[0,100],
      "ex_um":[1,2,1,2,1,2,1,2],"ey_um":[0,0,0,0,0,0,0,0],"ez_um":[0,0,0,0,1,1,1,1]}"#;
    std::fs::write(dir.path().join("map.json"), map).unwrap();
    let model = ThermalModel::HeatInput(HeatInputModel {
        input: "spindle_rpm".into(),
        input_ref: 1000.0,
        alpha: 1.5,
        taus_min: vec![30.0, 90.0],
        rest_tau_factor: 2.0,
        ambient_sensors: vec!["t1_c".into()],
        k: 0.0,
        intercept_um: 1.0,
        heat_coefficients_um: vec![2.0, 3.0],
        ambient_coefficients_um_per_c: vec![0.5],
        ambient_lag_min: Some(60.0),
        ambient_lag_coefficients_um_per_c: vec![-0.2],
        inner_cv_rmse_um: None,
        warnings: Vec::new(),
    });
    let f = ModelFile {
        format: MODEL_FORMAT.into(),
        target: "ez_um".into(),
        model,
        split: Split::default(),
        train_metrics: Metrics::new(&[0.0, 1.0], &[0.0, 1.0], 1),
        test_metrics: None,
        validation: None,
        envelope: Vec::new(),
        candidates: Vec::new(),
        warnings: Vec::new(),
    };
    std::fs::write(
        dir.path().join("th.json"),
        serde_json::to_string(&f).unwrap(),
    )
    .unwrap();
    let machine = r#"{"format":"mtec.machine-error/1","geometric":"map.json","thermal":[
      {"axis":"z","model":"th.json","envelope":{"spindle_rpm":[0,5000],"t1_c":[15,30]}}]}"#;
    let path = dir.path().join("machine.json");
    std::fs::write(&path, machine).unwrap();
    let mut comp = Compensator::load(&path, CorrectionOptions::default()).unwrap();
    assert_eq!(comp.state_inputs(), ["spindle_rpm", "t1_c"]);
    let mut acc = 0.0;
    COUNTING.with(|c| c.set(true));
    let before = MINE.with(|m| m.get());
    for i in 0..10_000 {
        let rpm = if (i / 500) % 2 == 0 { 3000.0 } else { 0.0 };
        // every 7th reading outside the envelope (fading path), every 11th refused
        let t1 = if i % 7 == 0 { 31.0 } else { 22.0 };
        let dt = if i % 11 == 0 { -1.0 } else { 0.1 };
        let _ = comp.update_state(&[rpm, t1], dt);
        let c = comp
            .correction_um([(i % 100) as f64, 50.0, (i % 90) as f64])
            .unwrap();
        acc += c[2];
    }
    let after = MINE.with(|m| m.get());
    COUNTING.with(|c| c.set(false));
    assert!(acc.is_finite() && acc != 0.0);
    assert_eq!(after - before, 0, "allocations during 10 000 updates");
}
