//! mtec-rt: the C ABI of mtec's real-time compensation, for controller components (a LinuxCNC
//! HAL component, a PLC runtime, a motion card driver) that call it once per servo or
//! interpolation cycle.
//!
//! What it is for: `mtec_rt_load(path)` loads a grid map, kinematic model or BPNN map (`mtec.map/1`, …) outside
//! the real-time loop; `mtec_rt_correction(handle, x, y, z, out_um)` then returns the correction
//! (µm, to add to the X, Y, Z axis commands) that makes the tool reach (x, y, z) mm, without
//! allocating, locking or blocking; `mtec_rt_free(handle)` releases it. The header is
//! `include/mtec_rt.h` (hand-written, kept in step with this file; a test compiles a C program
//! against it).
//!
//! What it is not for: fitting models or writing tables (use the `mtec` command).
//!
//! Decisions: corrections use the default solver settings (tolerance 1e-7 mm, at most 500 µm,
//! see `mtec_comp::correction`); on any failure the output is set to zero (no compensation is
//! the safe fallback for a running machine) and the return code says why.

use mtec_comp::{Compensator, CorrectionError, CorrectionOptions};
use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr, CString};
use std::path::Path;

/// Success.
pub const MTEC_RT_OK: c_int = 0;
/// A null handle or output pointer.
pub const MTEC_RT_ERR_NULL: c_int = -1;
/// The model has no value there (outside a map that refuses points beyond its grid).
pub const MTEC_RT_ERR_UNDEFINED: c_int = 1;
/// The correction did not converge.
pub const MTEC_RT_ERR_NOT_CONVERGED: c_int = 2;
/// The correction exceeds the allowed maximum (500 µm).
pub const MTEC_RT_ERR_TOO_LARGE: c_int = 3;

/// An opaque loaded model.
pub struct MtecRt {
    comp: Compensator,
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(msg: &str) {
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

/// Loads a model file. Returns NULL on failure; `mtec_rt_last_error()` then says why.
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn mtec_rt_load(path: *const c_char) -> *mut MtecRt {
    if path.is_null() {
        set_last_error("mtec_rt_load: path is NULL");
        return std::ptr::null_mut();
    }
    let path = match CStr::from_ptr(path).to_str() {
        Ok(p) => p.to_owned(),
        Err(_) => {
            set_last_error("mtec_rt_load: path is not UTF-8");
            return std::ptr::null_mut();
        }
    };
    let loaded = std::panic::catch_unwind(|| {
        Compensator::load(Path::new(&path), CorrectionOptions::default())
    });
    match loaded {
        Ok(Ok(comp)) => Box::into_raw(Box::new(MtecRt { comp })),
        Ok(Err(e)) => {
            set_last_error(&e.to_string());
            std::ptr::null_mut()
        }
        Err(_) => {
            set_last_error("mtec_rt_load: internal error while loading");
            std::ptr::null_mut()
        }
    }
}

/// The message of the last failed `mtec_rt_load` on this thread ("" if none). The pointer stays
/// valid until the next `mtec_rt_load` on the same thread.
#[no_mangle]
pub extern "C" fn mtec_rt_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// Writes the correction (µm) for target (x, y, z) mm into `out_um[0..3]`. Real-time safe: no
/// allocation, no locks. Returns `MTEC_RT_OK` or an error code (and zeros in `out_um`).
///
/// # Safety
/// `handle` must come from `mtec_rt_load` and not be freed; `out_um` must point to 3 doubles.
#[no_mangle]
pub unsafe extern "C" fn mtec_rt_correction(
    handle: *const MtecRt,
    x_mm: f64,
    y_mm: f64,
    z_mm: f64,
    out_um: *mut f64,
) -> c_int {
    if handle.is_null() || out_um.is_null() {
        return MTEC_RT_ERR_NULL;
    }
    let out = std::slice::from_raw_parts_mut(out_um, 3);
    match (*handle).comp.correction_um([x_mm, y_mm, z_mm]) {
        Ok(c) => {
            out.copy_from_slice(&c);
            MTEC_RT_OK
        }
        Err(e) => {
            out.fill(0.0);
            match e {
                CorrectionError::ModelUndefined { .. } => MTEC_RT_ERR_UNDEFINED,
                CorrectionError::NotConverged { .. } => MTEC_RT_ERR_NOT_CONVERGED,
                CorrectionError::TooLarge { .. } => MTEC_RT_ERR_TOO_LARGE,
            }
        }
    }
}

/// Releases a model loaded by `mtec_rt_load` (NULL is ignored).
///
/// # Safety
/// `handle` must be NULL or come from `mtec_rt_load`, and not be used afterwards.
#[no_mangle]
pub unsafe extern "C" fn mtec_rt_free(handle: *mut MtecRt) {
    if !handle.is_null() {
        drop(Box::from_raw(handle));
    }
}
