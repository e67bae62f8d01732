//! Fuzz target for the CSV table reader (issue 10): any bytes, decoded as UTF-8 when they are
//! UTF-8 (the reader's caller rejects other bytes with a located error first), must give a table
//! or a located `InputError` — never a panic or a hang. A table that parses must keep the shape
//! promises `Table::parse` makes: every row as wide as the header, rows in line order.
//!
//! Run for 10 minutes:
//!   cd fuzz && cargo +nightly fuzz run csv_table -- -max_total_time=600 -max_len=4096
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("fuzz.csv");
    match mtec_io::Table::parse(path, text) {
        Ok(t) => {
            assert!(!t.rows.is_empty(), "a table without data rows was accepted");
            let mut last = t.header_line;
            for r in &t.rows {
                assert_eq!(r.fields.len(), t.header.len(), "ragged row accepted");
                assert!(r.line > last, "rows out of line order");
                last = r.line;
            }
            // typed access on every column must be Ok or a located error, never a panic
            for name in t.header.clone() {
                let _ = t.f64_column(&name);
                let _ = t.i64_column(&name);
                let _ = t.str_column(&name);
            }
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.starts_with("fuzz.csv"),
                "error does not name the file: {msg}"
            );
        }
    }
});
