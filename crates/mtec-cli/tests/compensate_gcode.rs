//! `mtec compensate gcode` end to end: exit codes, located messages, byte-identical zero model,
//! never overwriting the input, no partial output on failure.

use std::path::Path;
use std::process::Command;

fn mtec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mtec"))
}

/// `mtec compensate gcode --model MODEL PROGRAM -o OUT`.
fn compensate(model: &Path, program: &Path, out: impl AsRef<Path>) -> std::process::Output {
    mtec()
        .args(["compensate", "gcode", "--model"])
        .arg(model)
        .arg(program)
        .arg("-o")
        .arg(out.as_ref())
        .output()
        .unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const PROGRAM: &str = "%\nO0001 (TEST)\nN10 G21 G90 G17\nN20 G0 X0 Y0 Z5\nN30 G1 Z-1 F200 ; plunge\nN40 X120 Y30\nN50 G2 X150 Y0 R30\nM30\n%\n";

#[test]
fn zero_model_copies_the_program_and_poly_model_corrects_it() {
    let dir = tempfile::tempdir().unwrap();
    let prog = write(dir.path(), "part.ngc", PROGRAM);
    let zero = write(
        dir.path(),
        "zero.json",
        r#"{"format": "mtec.zero-model/1"}"#,
    );
    let out = dir.path().join("out.ngc");
    let st = compensate(&zero, &prog, &out).status;
    assert_eq!(st.code(), Some(0));
    assert_eq!(std::fs::read(&out).unwrap(), PROGRAM.as_bytes());

    // e_x = 10 um + 0.05 um/mm · x: the correction grows along X, the long move is split
    let poly = write(
        dir.path(),
        "poly.json",
        r#"{"format": "mtec.poly-model/1", "description": "scale error",
            "terms": [{"powers": [0,0,0], "coef_um": [10.0, 0.0, 0.0]},
                      {"powers": [1,0,0], "coef_um": [0.05, 0.0, 0.0]}]}"#,
    );
    let o = compensate(&poly, &prog, &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.starts_with("%\nO0001 (TEST)\nN10 G21 G90 G17\n(mtec compensate gcode"),
        "{text}"
    );
    // X0 → c = -0.01 mm; the last piece of N40 ends at 120 + c(120) = 120 - 0.016/1.00005
    assert!(text.contains("N20 G0 X-0.01 Y0 Z5"), "{text}");
    assert!(
        text.contains("\nG1 X119.984 Y30.0\nN50 G1 X120.3279 Y29.998\n"),
        "{text}"
    );
    assert!(text.contains("N30 G1 Z-1 F200 ; plunge"), "{text}");
    assert!(text.ends_with("M30\n%\n"));
}

#[test]
fn unsupported_line_exits_2_with_file_line_column_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    // a named parameter that was never set: LinuxCNC stops there too
    let prog = write(
        dir.path(),
        "p.ngc",
        "G21\nG0 X0 Y0 Z0\nG1 X[#<depth>*2] F100\n",
    );
    let zero = write(
        dir.path(),
        "zero.json",
        r#"{"format": "mtec.zero-model/1"}"#,
    );
    let out = dir.path().join("out.ngc");
    let o = compensate(&zero, &prog, &out);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("p.ngc:3:6:") && err.contains("depth"), "{err}");
    assert!(!out.exists(), "a refused run must leave no output");
    assert!(std::fs::read_dir(dir.path()).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .contains("mtec-tmp")));
    // pass-through: copied, with a warning, exit 0
    let o = mtec()
        .args([
            "compensate",
            "gcode",
            "--on-unsupported",
            "pass-through-with-warning",
            "--model",
        ])
        .arg(&zero)
        .arg(&prog)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("warning:"));
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&prog).unwrap());

    // a script that printed 0.00001 as 1e-05: a controller would go to X1, mtec refuses it
    std::fs::remove_file(&out).unwrap();
    let prog = write(dir.path(), "e.ngc", "G21\nG0 X0 Y0 Z0\nG1 X1e-05 F100\n");
    let o = compensate(&zero, &prog, &out);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("e.ngc:3:6:") && err.contains("exponent"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn bad_model_bad_offsets_and_overwriting_the_input_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let prog = write(dir.path(), "p.ngc", "G21\n");
    let bad = write(dir.path(), "bad.json", "{\"format\": \"mtec.poly-model/1\",\n \"terms\": [{\"powers\": [1,0], \"coef_um\": [1,2,3]}]}");
    let o = compensate(&bad, &prog, dir.path().join("o.ngc"));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("bad.json:2:"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );

    let zero = write(
        dir.path(),
        "zero.json",
        r#"{"format": "mtec.zero-model/1"}"#,
    );
    let offs = write(
        dir.path(),
        "o.toml",
        "[work_offsets_mm]\nG60 = [1.0, 2.0, 3.0]\n",
    );
    let o = mtec()
        .args(["compensate", "gcode", "--model"])
        .arg(&zero)
        .arg(&prog)
        .arg("--offsets")
        .arg(&offs)
        .arg("-o")
        .arg(dir.path().join("o.ngc"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("G60"));

    let o = compensate(&zero, &prog, &prog);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("overwrite"));
    assert_eq!(std::fs::read_to_string(&prog).unwrap(), "G21\n");
}

/// Issue 24 item 10: a program that leaves the map's box is compensated with clamped values and
/// says so, with the count and the first place; without --offsets it says that program
/// coordinates were taken as machine coordinates, and with them it does not.
#[test]
fn points_outside_the_map_and_assumed_coordinates_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    // a 2×2×2 map over X 0..100, Y 0..50, Z -10..10: e_x = 5 um + 0.1 um/mm · x
    let map = write(
        dir.path(),
        "map.json",
        r#"{"format": "mtec.map/1", "model": "trilinear", "outside": "clamp",
            "x_mm": [0.0, 100.0], "y_mm": [0.0, 50.0], "z_mm": [-10.0, 10.0],
            "ex_um": [5, 5, 5, 5, 15, 15, 15, 15], "ey_um": [0, 0, 0, 0, 0, 0, 0, 0],
            "ez_um": [0, 0, 0, 0, 0, 0, 0, 0]}"#,
    );
    let inside = write(
        dir.path(),
        "inside.ngc",
        "G21 G90 G17\nG0 X10 Y10 Z5\nG1 X90 F300\nM30\n",
    );
    // line 3 goes to X150 (outside from column 6), line 4 to Y-20 (outside too)
    let outside = write(
        dir.path(),
        "outside.ngc",
        "G21 G90 G17\nG0 X10 Y10 Z5\nG1 X150 F300\nG1 Y-20\nM30\n",
    );
    let out = dir.path().join("out.ngc");

    let o = compensate(&map, &inside, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("outside the model's box"), "{err}");
    assert!(
        err.contains("no --offsets: program coordinates were taken as machine coordinates"),
        "{err}"
    );

    let o = compensate(&map, &outside, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let line = err
        .lines()
        .find(|l| l.contains("outside the model's box"))
        .unwrap_or_else(|| panic!("no outside warning: {err}"));
    assert!(
        line.contains("outside.ngc:3:"),
        "first point not at line 3: {line}"
    );
    // the move to X150 (end and split points beyond X100) and the move to Y-20: at least the
    // two end points, all of them counted
    let n: usize = line
        .split("warning: ")
        .nth(1)
        .and_then(|l| l.split(": ").nth(1))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count: {line}"));
    assert!(n >= 2, "{line}");
    assert!(line.contains("X 0..100 Y 0..50 Z -10..10"), "{line}");
    assert!(line.contains("X 150.000 Y 10.000 Z 5.000"), "{line}");

    // with --offsets the assumption note goes away (G54 at X0: the same program, same points)
    let offsets = write(
        dir.path(),
        "offsets.toml",
        "format = \"mtec.gcode-offsets/1\"\n[work_offsets_mm]\nG54 = [0.0, 0.0, 0.0]\n",
    );
    let o = mtec()
        .args(["compensate", "gcode", "--model"])
        .arg(&map)
        .arg(&inside)
        .arg("-o")
        .arg(&out)
        .arg("--offsets")
        .arg(&offsets)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("no --offsets"), "{err}");
}

/// A tighter `--tolerance-um` writes more digits where the user named none, instead of refusing
/// an mm program for the inch digits it never writes; digits the user names are still checked.
#[test]
fn a_tight_tolerance_raises_the_default_digits_and_named_digits_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let poly = write(
        dir.path(),
        "poly.json",
        r#"{"format": "mtec.poly-model/1", "description": "offset",
            "terms": [{"powers": [0,0,0], "coef_um": [10.0, 0.0, 0.0]}]}"#,
    );
    let run = |name: &str, text: &str, extra: &[&str]| {
        let prog = write(dir.path(), name, text);
        let out = dir.path().join(format!("out-{name}"));
        let o = mtec()
            .args(["compensate", "gcode", "--model"])
            .arg(&poly)
            .arg(&prog)
            .args(["-o"])
            .arg(&out)
            .args(["--tolerance-um", "0.2"])
            .args(extra)
            .output()
            .unwrap();
        let written = std::fs::read_to_string(&out).ok();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
            written,
        )
    };
    // mm: 4 digits hold 0.2 um (rounding 0.087 um); before, the default 5 inch digits
    // (0.22 um) refused this program although it never switches to inch
    let (code, err, out) = run("mm.ngc", "G21 G90\nG0 X0 Y0 Z0\nG1 X12.5 F100\nM2\n", &[]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.unwrap().contains("X12.49"), "X12.5 corrected by -10 um");
    // inch: 6 digits (rounding 0.022 um), the correction of -10 um = -0.000394 in visible
    let (code, err, out) = run("in.ngc", "G20 G90\nG0 X0 Y0 Z0\nG1 X1 F10\nM2\n", &[]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.unwrap().contains("X0.999606"), "six inch digits");
    // named digits too coarse for the tolerance: refused before any work, exit 2
    let (code, err, out) = run(
        "in2.ngc",
        "G20 G90\nG0 X0 Y0 Z0\nG1 X1 F10\nM2\n",
        &["--decimals-inch", "5"],
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("use --decimals-inch 6 or more"), "{err}");
    assert!(out.is_none());
}
