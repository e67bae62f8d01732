//! The C ABI called from Rust: load, corrections (checked against the closed-form answer of a
//! map whose error is affine), error codes, free.

use mtec_comp::map::{GridMap, Outside};
use mtec_rt::*;
use std::ffi::{CStr, CString};

/// e = (5 + 0.01·x, −2, 0) µm: the correction for target t solves p + e(p)·1e-3 = t, i.e.
/// p_x = (t_x − 0.005)/(1 + 1e-5), c_x = (p_x − t_x)·1e3; c_y = +2 µm, c_z = 0.
fn write_map(dir: &std::path::Path, outside: Outside) -> CString {
    let axes = [vec![0.0, 100.0], vec![0.0, 100.0], vec![0.0, 100.0]];
    let mut values = Vec::new();
    for &x in &axes[0] {
        for _ in 0..2 {
            for _ in 0..2 {
                values.push([5.0 + 0.01 * x, -2.0, 0.0]);
            }
        }
    }
    let map = GridMap::new(axes, values, outside, "abi test").unwrap();
    let path = dir.join("map.json");
    std::fs::write(&path, serde_json::to_string(&map.to_file()).unwrap()).unwrap();
    CString::new(path.to_str().unwrap()).unwrap()
}

/// Loads `path` (must succeed) and asks for the correction at `p` (must be OK).
///
/// # Safety
/// The returned handle must be freed with `mtec_rt_free`.
unsafe fn load_and_correct(path: &CString, p: [f64; 3]) -> (*mut MtecRt, [f64; 3]) {
    let h = mtec_rt_load(path.as_ptr());
    assert!(!h.is_null());
    let mut out = [9.0; 3];
    assert_eq!(
        mtec_rt_correction(h, p[0], p[1], p[2], out.as_mut_ptr()),
        MTEC_RT_OK
    );
    (h, out)
}

#[test]
fn load_correct_free() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_map(dir.path(), Outside::Refuse);
    unsafe {
        let (h, mut out) = load_and_correct(&path, [40.0, 50.0, 60.0]);
        let px = (40.0 - 0.005) / (1.0 + 1e-5);
        let cx = (px - 40.0) * 1e3;
        assert!((out[0] - cx).abs() < 1e-4, "{} vs {cx}", out[0]);
        assert!((out[1] - 2.0).abs() < 1e-4);
        assert!(out[2].abs() < 1e-9);
        // outside a refusing map: code 1 and zeros
        assert_eq!(
            mtec_rt_correction(h, 400.0, 50.0, 60.0, out.as_mut_ptr()),
            MTEC_RT_ERR_UNDEFINED
        );
        assert_eq!(out, [0.0; 3]);
        assert_eq!(
            mtec_rt_correction(h, 1.0, 1.0, 1.0, std::ptr::null_mut()),
            MTEC_RT_ERR_NULL
        );
        mtec_rt_free(h);
        mtec_rt_free(std::ptr::null_mut());
    }
}

#[test]
fn load_failure_reports_why() {
    let missing = CString::new("/nonexistent/map.json").unwrap();
    unsafe {
        assert!(mtec_rt_load(missing.as_ptr()).is_null());
        let msg = CStr::from_ptr(mtec_rt_last_error()).to_str().unwrap();
        assert!(
            msg.contains("/nonexistent/map.json") && msg.contains("cannot read"),
            "{msg}"
        );
        assert!(mtec_rt_load(std::ptr::null()).is_null());
    }
}

/// A BPNN map (`mtec.bpnn/1`, as `mtec map fit --model bpnn` writes it) loads like a grid map.
/// The 3-1-3 ReLU net below is affine where it is evaluated: e = (5 + 0.005·x, −2, 0) µm, so
/// p_x = (t_x − 0.005)/(1 + 5e-6), c_x = (p_x − t_x)·1e3, c_y = +2 µm, c_z = 0.
#[test]
fn bpnn_map_loads_and_corrects() {
    use mtec_comp::bpnn::{Activation, Affine, Bpnn};
    let inorm = Affine {
        offset: vec![0.0; 3],
        scale: vec![100.0; 3],
    };
    let onorm = Affine {
        offset: vec![0.0; 3],
        scale: vec![1.0; 3],
    };
    // h = relu(x/100 + 1); e = (0.5·h + 4.5, −2, 0)
    let theta = [1.0, 0.0, 0.0, 1.0, 0.5, 0.0, 0.0, 4.5, -2.0, 0.0];
    let net = Bpnn::from_params(3, 1, 3, Activation::Relu, &inorm, &onorm, &theta);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bpnn.json");
    std::fs::write(&path, net.to_json()).unwrap();
    let path = CString::new(path.to_str().unwrap()).unwrap();
    unsafe {
        let (h, out) = load_and_correct(&path, [40.0, 50.0, 60.0]);
        let px = (40.0 - 0.005) / (1.0 + 5e-6);
        let cx = (px - 40.0) * 1e3;
        assert!((out[0] - cx).abs() < 1e-4, "{} vs {cx}", out[0]);
        assert!(
            (out[1] - 2.0).abs() < 1e-4 && out[2].abs() < 1e-9,
            "{out:?}"
        );
        mtec_rt_free(h);
    }
    // a thermal network (not 3 inputs and 3 outputs) is refused with the reason
    let thermal = Bpnn::from_params(
        2,
        1,
        1,
        Activation::Sigmoid,
        &Affine {
            offset: vec![0.0; 2],
            scale: vec![1.0; 2],
        },
        &Affine {
            offset: vec![0.0],
            scale: vec![1.0],
        },
        &[1.0, 1.0, 0.0, 1.0, 0.0],
    );
    let p2 = dir.path().join("thermal.json");
    std::fs::write(&p2, thermal.to_json()).unwrap();
    let p2 = CString::new(p2.to_str().unwrap()).unwrap();
    unsafe {
        assert!(mtec_rt_load(p2.as_ptr()).is_null());
        let msg = CStr::from_ptr(mtec_rt_last_error()).to_str().unwrap();
        assert!(msg.contains("3 inputs"), "{msg}");
    }
}
