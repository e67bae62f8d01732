//! The C header is generated: cbindgen, run on this crate with `cbindgen.toml`, must give exactly
//! the checked-in `include/mtec_rt.h`, so that the header can never drift from the functions and
//! return codes the library exports (issue 18). `MTEC_BLESS=1 cargo test -p mtec-rt --test
//! header` rewrites the file after a deliberate change of the C interface.

use std::path::PathBuf;

#[test]
fn the_checked_in_header_is_cbindgens_output() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_crate(&dir)
        .with_config(config)
        .generate()
        .expect("cbindgen could not read crates/mtec-rt/src/lib.rs")
        .write(&mut generated);
    let generated = String::from_utf8(generated).unwrap();
    let path = dir.join("include/mtec_rt.h");
    if std::env::var_os("MTEC_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let checked_in = std::fs::read_to_string(&path).unwrap();
    if checked_in != generated {
        let first = checked_in
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(checked_in.lines().count().min(generated.lines().count()));
        panic!(
            "include/mtec_rt.h differs from cbindgen's output from line {}:\n  checked in: {:?}\n  generated:  {:?}\n\
             regenerate it with MTEC_BLESS=1 cargo test -p mtec-rt --test integration header::, and review the diff",
            first + 1,
            checked_in.lines().nth(first),
            generated.lines().nth(first)
        );
    }
}
