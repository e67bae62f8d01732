//! Fuzz target for the machine description reader (issue 10): any bytes must give a validated
//! `Machine` or a typed error (TOML syntax/type error with its location, or a `MachineError`) —
//! never a panic or a hang. A machine that validates is also asked for its first-order Jacobian
//! at the middle of its travels, which must not panic.
//!
//! Run for 10 minutes:
//!   cd fuzz && cargo +nightly fuzz run machine_toml seeds/machine_toml -- -max_total_time=600 -max_len=4096
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let spec = match mtec_io::parse_toml::<mtec_model::MachineSpec>(Path::new("fuzz.toml"), text) {
        Ok(s) => s,
        Err(e) => {
            assert!(e.to_string().starts_with("fuzz.toml"));
            return;
        }
    };
    let Ok(machine) = mtec_model::Machine::from_spec(spec) else {
        return;
    };
    let q: Vec<f64> = machine
        .axes
        .iter()
        .map(|a| {
            let [lo, hi] = machine.specs[a].travel;
            0.5 * (lo + hi)
        })
        .collect();
    // must not panic (values may be non-finite when the travels are, which from_spec allows)
    let model = mtec_model::VolumetricModel::new(&machine, &mtec_model::ErrorSet::new("fuzz"));
    let _ = model.first_order_jacobian(&q);
});
