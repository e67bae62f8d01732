//! mtec-rt: the C ABI of mtec's real-time compensation, for controller components (a LinuxCNC
//! HAL component, a PLC runtime, a motion card driver) that call it once per servo or
//! interpolation cycle.
//!
//! What it is for: `mtec_rt_load(path)` loads a grid map, kinematic model or BPNN map (`mtec.map/1`, …) outside
//! the real-time loop; `mtec_rt_correction(handle, x, y, z, out_um)` then returns the correction
//! (µm, to add to the X, Y, Z axis commands) that makes the tool reach (x, y, z) mm, without
//! allocating, locking or blocking; `mtec_rt_free(handle)` releases it. The header is
//! `include/mtec_rt.h`, generated from this file by cbindgen (`cbindgen.toml`; `tests/header.rs`
//! fails when the checked-in header differs, and `tests/c_header.rs` compiles C programs against it).
//!
//! Machine state: a `mtec.machine-error/1` model (a geometric map plus thermal models) has a
//! state. `mtec_rt_update_state(handle, readings, n, dt_s)` advances it with the readings of this
//! cycle (temperatures °C, spindle speed, … in the order `mtec_rt_state_input_name(handle, i)`
//! gives, `mtec_rt_state_input_count(handle)` of them) and the seconds since the last update;
//! `mtec_rt_correction` then uses the new state. The first update starts the thermal filters at
//! its readings (the machine in equilibrium); before it the thermal part is zero. It returns
//! `MTEC_RT_ENVELOPE` when a reading is outside the model's training range: the thermal part is
//! then faded towards no correction (`mtec_rt_thermal_weight`), the safe value.
//!
//! Thread rules: a handle belongs to one thread at a time. `mtec_rt_update_state` changes the
//! state, so it must not run while another thread calls `mtec_rt_correction` on the same handle;
//! the usual servo thread calls update then correction in the same cycle. Different handles are
//! independent. `mtec_rt_load` and `mtec_rt_free` allocate and belong outside the real-time loop.
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
/// The state was updated, but a reading is outside the training envelope: the thermal part is
/// faded (see `mtec_rt_thermal_weight`).
pub const MTEC_RT_ENVELOPE: c_int = 4;
/// The state update was refused (wrong reading count, a NaN or infinite reading, a negative or
/// non-finite time step); the state is unchanged.
pub const MTEC_RT_ERR_STATE: c_int = 5;

/// An opaque loaded model.
pub struct MtecRt {
    comp: Compensator,
    /// The state inputs' names as C strings (made at load, so lookups do not allocate).
    input_names: Vec<CString>,
    thermal_weight: f64,
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
        Ok(Ok(comp)) => {
            let input_names = comp
                .state_inputs()
                .iter()
                .map(|n| CString::new(n.replace('\0', " ")).unwrap_or_default())
                .collect();
            Box::into_raw(Box::new(MtecRt {
                comp,
                input_names,
                thermal_weight: 1.0,
            }))
        }
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

/// Number of state readings `mtec_rt_update_state` takes (0 for a static model or NULL).
///
/// # Safety
/// `handle` must be NULL or come from `mtec_rt_load` and not be freed.
#[no_mangle]
pub unsafe extern "C" fn mtec_rt_state_input_count(handle: *const MtecRt) -> usize {
    if handle.is_null() {
        return 0;
    }
    (*handle).input_names.len()
}

/// Name of state reading `i` (`t3_c`, `spindle_rpm`, …), or NULL when `i` is out of range. The
/// pointer lives as long as the handle.
///
/// # Safety
/// `handle` must be NULL or come from `mtec_rt_load` and not be freed.
#[no_mangle]
pub unsafe extern "C" fn mtec_rt_state_input_name(
    handle: *const MtecRt,
    i: usize,
) -> *const c_char {
    if handle.is_null() {
        return std::ptr::null();
    }
    let h = &*handle;
    match h.input_names.get(i) {
        Some(n) => n.as_ptr(),
        None => std::ptr::null(),
    }
}

/// Advances the model's state by `dt_s` seconds with `n` readings (module docs). Real-time safe:
/// no allocation, no locks. Returns `MTEC_RT_OK`, `MTEC_RT_ENVELOPE` (updated, thermal part
/// faded), `MTEC_RT_ERR_STATE` (refused, state unchanged) or `MTEC_RT_ERR_NULL`.
///
/// # Safety
/// `handle` must come from `mtec_rt_load` and not be freed, and no other thread may use it during
/// the call; `readings` must point to `n` doubles (it may be NULL when `n` is 0).
#[no_mangle]
pub unsafe extern "C" fn mtec_rt_update_state(
    handle: *mut MtecRt,
    readings: *const f64,
    n: usize,
    dt_s: f64,
) -> c_int {
    if handle.is_null() || (readings.is_null() && n > 0) {
        return MTEC_RT_ERR_NULL;
    }
    let values: &[f64] = if n == 0 {
        &[]
    } else {
        std::slice::from_raw_parts(readings, n)
    };
    let h = &mut *handle;
    match h.comp.update_state(values, dt_s) {
        Ok(status) => {
            h.thermal_weight = status.thermal_weight;
            if status.outside.is_some() {
                MTEC_RT_ENVELOPE
            } else {
                MTEC_RT_OK
            }
        }
        Err(_) => MTEC_RT_ERR_STATE,
    }
}

/// Weight of the thermal part after the last update: 1 inside the training envelope, down to 0
/// (no thermal correction) outside it. 1 for a static model; 0 for NULL.
///
/// # Safety
/// `handle` must be NULL or come from `mtec_rt_load` and not be freed.
#[no_mangle]
pub unsafe extern "C" fn mtec_rt_thermal_weight(handle: *const MtecRt) -> f64 {
    if handle.is_null() {
        return 0.0;
    }
    (*handle).thermal_weight
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
