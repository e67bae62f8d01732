//! Issue 25: `-o` through mtec-io's one output routine, end to end. `-o -` streams the output to
//! stdout for every command that writes one file (its report then goes to stderr); a FIFO and a
//! character device are written through and stay what they are; a symlink stays a link and its
//! target gets the content; a directory and a block device are refused with exit code 2, and so
//! is an input however it is spelled, before any work.

#![cfg(unix)]

mod support;

use std::ffi::CString;
use std::io::Read;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::FileTypeExt;
use std::path::Path;
use support::{mtec, stderr, text};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

fn mknod(p: &Path, kind: libc::mode_t, major: u32, minor: u32) -> bool {
    let c = CString::new(p.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path; mknod only creates a file system node.
    unsafe { libc::mknod(c.as_ptr(), kind | 0o666, libc::makedev(major, minor)) == 0 }
}

/// A 3×2×2 grid (µm errors of a few µm), a poly model of 5 µm in X, a short program.
fn inputs(dir: &Path) {
    let mut g = String::from("x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n");
    for x in [0.0, 50.0, 100.0] {
        for y in [0.0, 100.0] {
            for z in [0.0, 100.0] {
                g.push_str(&format!(
                    "{x},{y},{z},{},{},{}\n",
                    1.0 + 0.02 * x,
                    0.01 * y,
                    -0.005 * z
                ));
            }
        }
    }
    std::fs::write(dir.join("grid.csv"), g).unwrap();
    std::fs::write(
        dir.join("poly.json"),
        r#"{"format": "mtec.poly-model/1", "terms": [{"powers": [0,0,0], "coef_um": [5, 0, 0]}]}"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("part.ngc"),
        "G21 G90\nG0 X0 Y0 Z0\nG1 X10 Y5 F100\nG1 X20\nM30\n",
    )
    .unwrap();
}

/// Runs `args` once with `-o FILE` and once with `-o -`: stdout of the second is the file of
/// the first, byte for byte, and the report printed with a file went to stderr.
fn same_on_stdout(dir: &Path, name: &str, args: &[&str]) -> Vec<u8> {
    let file = dir.join(name);
    let mut a: Vec<&str> = args.to_vec();
    a.extend(["-o", s(&file)]);
    let o = mtec(&a);
    assert!(o.status.success(), "{args:?}: {}", text(&o));
    let written = std::fs::read(&file).unwrap();
    let mut a: Vec<&str> = args.to_vec();
    a.extend(["-o", "-"]);
    let o = mtec(&a);
    assert!(o.status.success(), "{args:?} -o -: {}", text(&o));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&written),
        "{args:?}: stdout of -o - is the file"
    );
    assert!(!dir.join("-").exists(), "{args:?}: no file named -");
    o.stderr
}

#[test]
fn dash_streams_to_stdout_for_every_command_that_writes_one_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let p = |n: &str| d.join(n).to_str().unwrap().to_string();
    let (grid, poly, part) = (p("grid.csv"), p("poly.json"), p("part.ngc"));

    same_on_stdout(d, "map.json", &["map", "fit", "--grid", &grid]);
    let map = p("map.json");
    same_on_stdout(
        d,
        "eval.csv",
        &["map", "eval", "--map", &map, "--points", &grid],
    );
    let err = same_on_stdout(
        d,
        "part-c.ngc",
        &["compensate", "gcode", "--model", &poly, &part],
    );
    assert!(
        String::from_utf8_lossy(&err).contains("lines read"),
        "the summary goes to stderr"
    );
    same_on_stdout(
        d,
        "x.comp",
        &[
            "compensate",
            "table",
            "--model",
            &map,
            "--format",
            "linuxcnc",
            "--axis",
            "X",
        ],
    );
    same_on_stdout(
        d,
        "x.ini",
        &[
            "compensate",
            "table",
            "--model",
            &map,
            "--format",
            "beckhoff",
        ],
    );
    // heidenhain writes two files: `-` is refused
    let o = mtec(&[
        "compensate",
        "table",
        "--model",
        &map,
        "--format",
        "heidenhain",
        "-o",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));

    // the BPNN map: its fit report goes to stderr; a build without the neural models refuses
    // it with exit 2 and says how to build them, and writes nothing on stdout
    let o = mtec(&[
        "map", "fit", "--grid", &grid, "--model", "bpnn", "--hidden", "2", "-o", "-",
    ]);
    if cfg!(feature = "neural") {
        assert!(o.status.success(), "{}", text(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("only the model");
        assert_eq!(v["format"], "mtec.bpnn/1");
        assert!(stderr(&o).contains("wrote -"), "{}", stderr(&o));
    } else {
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        assert!(o.stdout.is_empty() && stderr(&o).contains("--features neural"));
    }

    support::write_scenario("vmc-9line", 1, d);
    let err = same_on_stdout(
        d,
        "errors.json",
        &[
            "identify",
            "lines",
            "--machine",
            &p("machine.toml"),
            "--data",
            &p("lines.csv"),
        ],
    );
    assert!(!err.is_empty(), "the report goes to stderr");

    let thermal = d.join("thermal.csv");
    std::fs::write(
        &thermal,
        &mtec_sim::run_scenario("spindle-sensors", 1).unwrap().files[0].contents,
    )
    .unwrap();
    let t = s(&thermal);
    same_on_stdout(
        d,
        "tm.json",
        &[
            "thermal",
            "fit",
            "--data",
            t,
            "--target",
            "radial_um",
            "--model",
            "ridge-select",
            "--train",
            "1",
            "--test",
            "2",
        ],
    );
    let tm = p("tm.json");
    same_on_stdout(
        d,
        "pred.csv",
        &["thermal", "predict", "--model", &tm, "--data", t],
    );
}

/// `-o FIFO` (as `-o >(gzip > f.gz)` gives): the program goes through the pipe, which stays a
/// pipe.
#[test]
fn a_fifo_output_is_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let fifo = d.join("pipe");
    let c = CString::new(fifo.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo only creates a node.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut s = String::new();
            std::fs::File::open(fifo)
                .unwrap()
                .read_to_string(&mut s)
                .unwrap();
            s
        })
    };
    let o = mtec(&[
        "compensate",
        "gcode",
        "--model",
        s(&d.join("poly.json")),
        s(&d.join("part.ngc")),
        "-o",
        s(&fifo),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    let got = reader.join().unwrap();
    assert!(got.contains("M30"), "{got}");
    assert!(got.contains("X9.995"), "corrected by -5 um: {got}");
}

/// A symlinked output stays a link; the file it points to gets the table.
#[test]
fn a_symlink_output_writes_its_target() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    std::fs::create_dir(d.join("tables")).unwrap();
    std::fs::write(d.join("tables/x.comp"), "old").unwrap();
    let link = d.join("current.comp");
    std::os::unix::fs::symlink("tables/x.comp", &link).unwrap();
    let o = mtec(&[
        "compensate",
        "table",
        "--model",
        s(&d.join("poly.json")),
        "--format",
        "linuxcnc",
        "--range",
        "0:100:50",
        "-o",
        s(&link),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(
        std::fs::read_to_string(d.join("tables/x.comp")).unwrap(),
        "0.000000 -0.005000 -0.005000\n50.000000 -0.005000 -0.005000\n100.000000 -0.005000 -0.005000\n"
    );
}

/// A twin of /dev/null made with mknod in a temporary folder (root only): `map fit -o` writes
/// through it and it stays a character device (issue 25's report).
#[test]
fn a_character_device_output_stays_a_device() {
    if !is_root() {
        eprintln!("note: not root, mknod is not permitted: character-device case skipped (the FIFO case covers the logic)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let null = d.join("null");
    assert!(mknod(&null, libc::S_IFCHR, 1, 3));
    let o = mtec(&[
        "map",
        "fit",
        "--grid",
        s(&d.join("grid.csv")),
        "-o",
        s(&null),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::symlink_metadata(&null)
        .unwrap()
        .file_type()
        .is_char_device());
}

/// A directory and a block device are refused with exit code 2, naming the path; so is an
/// input reached through a symlink or another spelling, before any work (no output appears).
#[test]
fn directories_block_devices_and_inputs_are_refused_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let grid = d.join("grid.csv");
    let sub = d.join("sub");
    std::fs::create_dir(&sub).unwrap();
    let o = mtec(&["map", "fit", "--grid", s(&grid), "-o", s(&sub)]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        stderr(&o).contains(&format!("{} is a directory", s(&sub))),
        "{}",
        stderr(&o)
    );
    assert!(sub.is_dir());

    if is_root() {
        let disk = d.join("disk");
        assert!(mknod(&disk, libc::S_IFBLK, 7, 201));
        let o = mtec(&[
            "compensate",
            "table",
            "--model",
            s(&d.join("poly.json")),
            "--format",
            "linuxcnc",
            "--range",
            "0:100:50",
            "-o",
            s(&disk),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        assert!(stderr(&o).contains("block device"), "{}", stderr(&o));
        assert!(std::fs::symlink_metadata(&disk)
            .unwrap()
            .file_type()
            .is_block_device());
    } else {
        eprintln!("note: not root, mknod is not permitted: block-device case skipped");
    }

    let part = d.join("part.ngc");
    let before = std::fs::read(&part).unwrap();
    let link = d.join("link.ngc");
    std::os::unix::fs::symlink(&part, &link).unwrap();
    for out in [link.clone(), sub.join("../part.ngc")] {
        let o = mtec(&[
            "compensate",
            "gcode",
            "--model",
            s(&d.join("poly.json")),
            s(&part),
            "-o",
            s(&out),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        assert!(
            stderr(&o).contains(&format!("refusing to overwrite the input file {}", s(&out))),
            "{}",
            stderr(&o)
        );
        assert!(o.stdout.is_empty(), "refused before any work");
    }
    assert_eq!(std::fs::read(&part).unwrap(), before);
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    // the same for map fit through a symlink to its grid
    let glink = d.join("glink.csv");
    std::os::unix::fs::symlink(&grid, &glink).unwrap();
    let o = mtec(&["map", "fit", "--grid", s(&grid), "-o", s(&glink)]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}

#[test]
fn an_output_its_folder_cannot_take_is_refused_once_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let part = d.join("part.ngc");
    let poly = d.join("poly.json");
    // a file where a folder should be; /proc takes no new files, even from root
    let under_a_file = part.join("out.ngc");
    for (out, says) in [
        (under_a_file.as_path(), "choose another path"),
        (
            Path::new("/proc/mtec-out.ngc"),
            "the folder /proc does not take new files",
        ),
    ] {
        let o = mtec(&[
            "compensate",
            "gcode",
            "--model",
            s(&poly),
            s(&part),
            "-o",
            s(out),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        let e = stderr(&o);
        assert!(e.starts_with("error: cannot write "), "{e}");
        assert!(e.contains(says), "{e}");
        // the OS's reason once, not repeated by the error chain
        assert_eq!(e.matches("(os error").count(), 1, "{e}");
        assert!(o.stdout.is_empty(), "refused before any work");
    }
    assert!(part.is_file());
    // a folder that does not exist yet is created when the output is written
    let deep = d.join("new/sub/out.ngc");
    let o = mtec(&[
        "compensate",
        "gcode",
        "--model",
        s(&poly),
        s(&part),
        "-o",
        s(&deep),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(deep.is_file());
    // the probe leaves nothing behind
    let names: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(names.is_empty(), "{names:?}");
}

/// A German spreadsheet's export (semicolons, decimal commas, trailing separators) gives the same
/// numbers as the comma file, and the command says how it read it.
#[test]
fn spreadsheet_export_reads_like_the_comma_file_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let map = r#"{"format":"mtec.map/1","model":"trilinear","outside":"clamp","source":"t",
      "x_mm":[0,100],"y_mm":[0,100],"z_mm":[0,100],
      "ex_um":[1,2,1,2,1,2,1,2],"ey_um":[0,0,0,0,0,0,0,0],"ez_um":[0,0,0,0,1,1,1,1]}"#;
    std::fs::write(d.join("map.json"), map).unwrap();
    std::fs::write(d.join("de.csv"), "x_mm;y_mm;z_mm;;\r\n10,5;20;30,25;;\r\n").unwrap();
    std::fs::write(d.join("en.csv"), "x_mm,y_mm,z_mm\n10.5,20,30.25\n").unwrap();
    let run = |pts: &str| {
        let p = |n: &str| d.join(n).to_str().unwrap().to_string();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_mtec"))
            .args(["map", "eval", "--map", &p("map.json"), "--points", &p(pts)])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (o.stdout, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (de, note) = run("de.csv");
    let (en, quiet) = run("en.csv");
    assert_eq!(de, en);
    assert!(
        note.contains("note:") && note.contains("decimal comma"),
        "{note}"
    );
    assert!(note.contains("empty column(s)"), "{note}");
    assert!(!quiet.contains("note:"), "{quiet}");
}
