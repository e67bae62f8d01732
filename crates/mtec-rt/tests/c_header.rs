//! The generated header (include/mtec_rt.h) against the built library: compiles a small C program with gcc,
//! links it to libmtec_rt.so and runs it on a map. Skipped (with a message) when no C compiler
//! is installed.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Compiles `c_src` against the header and libmtec_rt.so, runs it with `args`, and returns its
/// stdout (the program must exit 0).
fn compile_and_run(dir: &Path, c_src: &str, args: &[PathBuf]) -> String {
    // the cdylib is built beside the test binary (target/<profile>/deps) or one level up
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap().to_path_buf();
    let lib_dir = [deps.clone(), deps.parent().unwrap().to_path_buf()]
        .into_iter()
        .find(|d| d.join("libmtec_rt.so").exists())
        .expect("libmtec_rt.so was not built next to the test binary");
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let src = dir.join("prog.c");
    std::fs::write(&src, c_src).unwrap();
    let bin = dir.join("prog");
    let status = Command::new("gcc")
        .args(["-std=c99", "-Wall", "-Werror", "-o"])
        .arg(&bin)
        .arg(&src)
        .arg("-I")
        .arg(crate_dir.join("include"))
        .arg("-L")
        .arg(&lib_dir)
        .args(["-lmtec_rt", "-lm"])
        .status()
        .unwrap();
    assert!(status.success(), "gcc failed");
    let out = Command::new(&bin)
        .args(args)
        .env("LD_LIBRARY_PATH", &lib_dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "C program failed: {:?} {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn have_gcc() -> bool {
    if Command::new("gcc").arg("--version").output().is_err() {
        eprintln!("gcc not found: C header test skipped");
        return false;
    }
    true
}

#[test]
fn c_program_uses_the_header() {
    if !have_gcc() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // e = (5 + 0.01·x, −2, 0) µm on a 2×2×2 grid over 0..100 mm (clamp)
    let map = r#"{"format":"mtec.map/1","model":"trilinear","outside":"clamp","source":"c test",
        "x_mm":[0,100],"y_mm":[0,100],"z_mm":[0,100],
        "ex_um":[5,5,5,5,6,6,6,6],"ey_um":[-2,-2,-2,-2,-2,-2,-2,-2],"ez_um":[0,0,0,0,0,0,0,0]}"#;
    std::fs::write(dir.path().join("map.json"), map).unwrap();
    let c_src = r#"
#include <stdio.h>
#include <math.h>
#include "mtec_rt.h"
int main(int argc, char **argv) {
    MtecRt *rt = mtec_rt_load(argv[1]);
    if (!rt) { fprintf(stderr, "load: %s\n", mtec_rt_last_error()); return 10; }
    double c[3];
    int rc = mtec_rt_correction(rt, 50.0, 10.0, 10.0, c);
    mtec_rt_free(rt);
    if (rc != MTEC_RT_OK) return 11;
    /* c_x = -e_x(p) = -(5.5 - tiny) um, c_y = +2 um */
    if (fabs(c[0] + 5.5) > 1e-3 || fabs(c[1] - 2.0) > 1e-9 || fabs(c[2]) > 1e-9) {
        fprintf(stderr, "%f %f %f\n", c[0], c[1], c[2]);
        return 12;
    }
    if (mtec_rt_load("/nonexistent.json") != NULL) return 13;
    printf("ok %.6f %.6f %.6f\n", c[0], c[1], c[2]);
    return 0;
}
"#;
    let out = compile_and_run(dir.path(), c_src, &[dir.path().join("map.json")]);
    assert!(out.starts_with("ok "), "{out}");
}

/// The machine state from C: a map plus a thermal part δ_z = 3·L₂₀[t1] − 60 µm (lag of 20 min);
/// t1 steps from 20 to 30 °C, then one update of 20 min: δ_z = 3·(20 + 10(1 − e⁻¹)) − 60; the
/// correction cancels it; a reading 3 °C above the range fades the thermal part to 0.
#[test]
fn c_program_updates_the_machine_state() {
    use mtec_thermal::{linear_model::LinearMethod, Split};
    use mtec_thermal::{Feature, LinearModel, Metrics, ModelFile, ThermalModel, MODEL_FORMAT};
    if !have_gcc() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let map = r#"{"format":"mtec.map/1","model":"trilinear","outside":"clamp","source":"c test",
        "x_mm":[0,100],"y_mm":[0,100],"z_mm":[0,100],
        "ex_um":[0,0,0,0,0,0,0,0],"ey_um":[-2,-2,-2,-2,-2,-2,-2,-2],"ez_um":[0,0,0,0,0,0,0,0]}"#;
    std::fs::write(dir.path().join("map.json"), map).unwrap();
    let thermal = ModelFile {
        format: MODEL_FORMAT.into(),
        target: "ez_um".into(),
        model: ThermalModel::Linear(LinearModel {
            method: LinearMethod::Mlr,
            features: vec![Feature::Lag {
                sensor: "t1_c".into(),
                tau_min: 20.0,
            }],
            intercept_um: -60.0,
            coefficients: vec![3.0],
            std_errors: None,
            ridge: None,
            warnings: Vec::new(),
        }),
        split: Split::default(),
        train_metrics: Metrics::new(&[0.0, 1.0], &[0.0, 1.0], 1),
        test_metrics: None,
        validation: None,
        envelope: Vec::new(),
        candidates: Vec::new(),
        warnings: Vec::new(),
    };
    std::fs::write(
        dir.path().join("thermal.json"),
        serde_json::to_string(&thermal).unwrap(),
    )
    .unwrap();
    let machine = r#"{"format":"mtec.machine-error/1","geometric":"map.json","thermal":[
        {"axis":"z","model":"thermal.json","envelope":{"t1_c":[18,31]}}]}"#;
    std::fs::write(dir.path().join("machine.json"), machine).unwrap();
    let c_src = r#"
#include <stdio.h>
#include <string.h>
#include <math.h>
#include "mtec_rt.h"
int main(int argc, char **argv) {
    MtecRt *rt = mtec_rt_load(argv[1]);
    if (!rt) { fprintf(stderr, "load: %s\n", mtec_rt_last_error()); return 10; }
    if (mtec_rt_state_input_count(rt) != 1) return 11;
    if (strcmp(mtec_rt_state_input_name(rt, 0), "t1_c") != 0) return 12;
    if (mtec_rt_state_input_name(rt, 1) != NULL) return 13;
    double t = 20.0, c[3];
    if (mtec_rt_update_state(rt, &t, 1, 0.0) != MTEC_RT_OK) return 14;
    t = 30.0;
    if (mtec_rt_update_state(rt, &t, 1, 1200.0) != MTEC_RT_OK) return 15;
    if (mtec_rt_correction(rt, 50.0, 50.0, 50.0, c) != MTEC_RT_OK) return 16;
    double dz = 3.0 * (20.0 + 10.0 * (1.0 - exp(-1.0))) - 60.0;
    if (fabs(c[2] + dz) > 1e-6 || fabs(c[1] - 2.0) > 1e-9) {
        fprintf(stderr, "%f %f %f vs %f\n", c[0], c[1], c[2], -dz); return 17;
    }
    /* refused updates leave the state alone */
    if (mtec_rt_update_state(rt, &t, 2, 1.0) != MTEC_RT_ERR_STATE) return 18;
    if (mtec_rt_update_state(rt, &t, 1, -1.0) != MTEC_RT_ERR_STATE) return 19;
    if (mtec_rt_update_state(NULL, &t, 1, 1.0) != MTEC_RT_ERR_NULL) return 20;
    /* 3 degC above the range (fade width 2 degC): no thermal correction, the map still applies */
    t = 34.0;
    if (mtec_rt_update_state(rt, &t, 1, 0.0) != MTEC_RT_ENVELOPE) return 21;
    if (mtec_rt_thermal_weight(rt) != 0.0) return 22;
    if (mtec_rt_correction(rt, 50.0, 50.0, 50.0, c) != MTEC_RT_OK) return 23;
    if (fabs(c[2]) > 1e-12 || fabs(c[1] - 2.0) > 1e-9) return 24;
    mtec_rt_free(rt);
    printf("ok %.6f\n", dz);
    return 0;
}
"#;
    let out = compile_and_run(dir.path(), c_src, &[dir.path().join("machine.json")]);
    assert!(out.starts_with("ok "), "{out}");
}
