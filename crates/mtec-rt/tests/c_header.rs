//! The hand-written header against the built library: compiles a small C program with gcc,
//! links it to libmtec_rt.so and runs it on a map. Skipped (with a message) when no C compiler
//! is installed.

use std::path::PathBuf;
use std::process::Command;

#[test]
fn c_program_uses_the_header() {
    if Command::new("gcc").arg("--version").output().is_err() {
        eprintln!("gcc not found: C header test skipped");
        return;
    }
    // the cdylib is built beside the test binary (target/<profile>/deps) or one level up
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap().to_path_buf();
    let lib_dir = [deps.clone(), deps.parent().unwrap().to_path_buf()]
        .into_iter()
        .find(|d| d.join("libmtec_rt.so").exists())
        .expect("libmtec_rt.so was not built next to the test binary");
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
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
    let src = dir.path().join("smoke.c");
    std::fs::write(&src, c_src).unwrap();
    let bin = dir.path().join("smoke");
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
        .arg(dir.path().join("map.json"))
        .env("LD_LIBRARY_PATH", &lib_dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "C program failed: {:?} {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("ok "));
}
