//! `mtec compensate thermal-offset`: golden outputs per controller (each worked from the
//! documentation its module cites, see `tests/data/thermal_offset/README.md`), the sign proved
//! with LinuxCNC's own interpreter, the exp-ambient line against its equation, the envelope
//! rule, the bound, the history rule and refusals (exit 2, file:line:col).

mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/thermal_offset")
}

fn mtec(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mtec"))
        .arg("compensate")
        .arg("thermal-offset")
        .args(args)
        .output()
        .unwrap()
}

fn path(name: &str) -> String {
    data().join(name).display().to_string()
}

fn stdout(o: &Output) -> String {
    assert!(
        o.status.success(),
        "mtec failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout.clone()).unwrap()
}

/// Exit code 2 and every expected piece in the message.
fn refused(o: &Output, expect: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expect {
        assert!(err.contains(e), "`{e}` not in: {err}");
    }
}

fn golden(name: &str) -> String {
    std::fs::read_to_string(data().join("golden").join(name)).unwrap()
}

/// The linear model (e = +12 µm now) on the G54 Z offset touched off at −312.4501 mm.
fn linear(format: &str, extra: &[&str]) -> Output {
    let (m, t) = (path("machine.json"), path("now.csv"));
    let mut a = vec!["--model", &m, "--temps", &t, "--format", format];
    a.extend_from_slice(extra);
    mtec(&a)
}

// LinuxCNC G-code reference, G10 L2: P1 = G54, the value is the origin in machine coordinates.
#[test]
fn golden_linuxcnc_g10() {
    let out = stdout(&linear("g10", &["--base-mm", "-312.4501"]));
    assert_eq!(out, golden("linuxcnc.ngc"));
}

// Allen-Bradley 8520 p. 11-8 (G10 L2 P1 = G54, machine coordinates); G90 makes it absolute.
#[test]
fn golden_fanuc_g10() {
    let out = stdout(&linear("fanuc", &["--base-mm", "-312.4501"]));
    assert_eq!(out, golden("fanuc.nc"));
}

// HAAS 96-8000 p. 113: #5221-#5225 = G54 X, Y, Z, A, B, so G54 Z (axis 3) is #5223.
#[test]
fn golden_fanuc_macro() {
    let out = stdout(&linear("fanuc-macro", &["--base-mm", "-312.4501"]));
    assert_eq!(out, golden("fanuc_macro.nc"));
    // G56 (offset 3) Z on a lathe whose Z is axis 2: #5261 + 1
    let out = stdout(&linear(
        "fanuc-macro",
        &["--base-mm", "0", "--offset", "3", "--axis-number", "2"],
    ));
    assert!(out.ends_with("#5262=-0.012\n"), "{out}");
}

// SINUMERIK ONE Programming Manual p. 636 ($P_UIFR[n,Z,FI]), 840Di sl Programming Manual p. 100
// (G54 = settable frame 1, G505 = frame 5), K2 p. 71 (active after G54...).
#[test]
fn golden_sinumerik_frame() {
    let out = stdout(&linear("sinumerik", &[]));
    assert_eq!(out, golden("sinumerik_frame.spf"));
    let out = stdout(&linear("sinumerik", &["--offset", "5"]));
    assert!(out.ends_with("$P_UIFR[5,Z,FI]=-0.012\nG505\n"), "{out}");
    let out = stdout(&linear("sinumerik", &["--offset", "0"]));
    assert!(out.ends_with("G500\n"), "{out}");
}

/// exp-ambient e = k·x + b (module docs of mtec-thermal): b = b_a·(1 − exp(−ΔT_up/b_b)),
/// k = k_a·(1 − exp(−ΔT_nut/k_b)), written out here from the test model's parameters.
fn exp_line() -> (f64, f64) {
    let b = 20.0 * (1.0 - (-5.0_f64 / 5.0).exp());
    let k = 0.04 * (1.0 - (-4.0_f64 / 4.0).exp());
    (k, b)
}

fn exp(format: &str, extra: &[&str]) -> Output {
    let (m, t) = (path("exp_machine.json"), path("exp_now.csv"));
    let mut a = vec![
        "--model",
        &m,
        "--temps",
        &t,
        "--format",
        format,
        "--starts-at-rest",
    ];
    a.extend_from_slice(extra);
    mtec(&a)
}

// 840D sl Function Manual Extended Functions K3 pp. 225, 228, 230: ΔK = K0 + tanβ·(P − P0),
// K0 and P0 in mm, tanβ a ratio, MD32750 bits 0 and 1.
#[test]
fn golden_sinumerik_temperature_compensation() {
    let out = stdout(&exp(
        "sinumerik-sd",
        &["--position-origin-mm", "-500", "--travel-mm", "-500:0"],
    ));
    assert_eq!(out, golden("sinumerik_sd.spf"));
    // the written numbers are the equation's, in the manual's units
    let (k, b) = exp_line();
    let value = |name: &str| -> f64 {
        let l = out.lines().find(|l| l.starts_with(name)).unwrap();
        l.split('=').nth(1).unwrap().parse().unwrap()
    };
    assert!((value("$SA_TEMP_COMP_ABS_VALUE") - b * 1e-3).abs() <= 5e-7);
    assert!((value("$SA_TEMP_COMP_SLOPE") - k * 1e-3).abs() <= 5e-11);
    assert_eq!(value("$SA_TEMP_COMP_REF_POSITION"), -500.0);
    // the control's ΔK at the far end of the travel is the model's error there
    let dk_um = (value("$SA_TEMP_COMP_ABS_VALUE") + value("$SA_TEMP_COMP_SLOPE") * 500.0) * 1e3;
    assert!((dk_um - (k * 500.0 + b)).abs() < 1e-3, "{dk_um}");
    // a position-dependent model needs the travel for its bound
    refused(&exp("sinumerik-sd", &[]), &["--travel-mm"]);
    // MD32760 caps tanβ (2.5e-5 here)
    refused(
        &exp(
            "sinumerik-sd",
            &["--travel-mm", "-500:0", "--comp-add-velo-factor", "1e-5"],
        ),
        &["exp_now.csv:4:", "MD32760"],
    );
}

#[test]
fn exp_ambient_offset_depends_on_where_it_is_used() {
    let (k, b) = exp_line();
    // the offset at Z = -200 mm with the model's x = 0 at Z = -500 mm: x = 300 mm
    let out = stdout(&exp(
        "g10",
        &[
            "--base-mm",
            "0",
            "--position-origin-mm",
            "-500",
            "--at-mm",
            "-200",
        ],
    ));
    let z: f64 = out
        .lines()
        .last()
        .unwrap()
        .strip_prefix("G10 L2 P1 Z")
        .unwrap()
        .parse()
        .unwrap();
    // c = −e(x) = −(k·x + b)
    assert!((z - -(k * 300.0 + b) * 1e-3).abs() <= 5e-5, "{z}");
    refused(&exp("g10", &["--base-mm", "0"]), &["--at-mm"]);
    // exp-ambient's rises start at the first row: the log must start at rest
    let (m, t) = (path("exp_machine.json"), path("exp_now.csv"));
    refused(
        &mtec(&[
            "--model",
            &m,
            "--temps",
            &t,
            "--base-mm",
            "0",
            "--at-mm",
            "0",
        ]),
        &["exp_now.csv:2:", "--starts-at-rest"],
    );
}

fn rs274() -> Option<PathBuf> {
    support::tool_on_path(
        &["rs274"],
        "linuxcnc-uspace",
        "the G10 output is not checked by LinuxCNC",
    )
}

/// Machine Z of each STRAIGHT_TRAVERSE (canonical Z + the G5x Z offset in force, as rs274
/// prints them) of `program` run by LinuxCNC's interpreter.
fn machine_z(bin: &Path, program: &str) -> Vec<f64> {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("p.ngc");
    std::fs::write(&f, program).unwrap();
    let o = Command::new(bin)
        .current_dir(dir.path())
        .env("HOME", dir.path())
        .arg("-g")
        .arg(&f)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let args = |l: &str, call: &str| -> Option<Vec<f64>> {
        let s = l.split(call).nth(1)?;
        Some(
            s.trim_start_matches('(')
                .trim_end_matches(')')
                .split(',')
                .map(|v| v.trim().parse().unwrap())
                .collect(),
        )
    };
    let mut g5x_z = 0.0;
    let mut out = Vec::new();
    for l in text.lines() {
        if let Some(v) = args(l, "SET_G5X_OFFSET") {
            g5x_z = v[3];
        } else if let Some(v) = args(l, "STRAIGHT_TRAVERSE") {
            out.push(v[2] + g5x_z);
        }
    }
    assert!(!out.is_empty(), "rs274 printed no move: {text}");
    out
}

/// The sign, proved with LinuxCNC's interpreter: the model predicts the tool will be 12 µm too
/// high (+Z), so the written G10 must command the programmed Z0 12 µm lower in machine
/// coordinates than the touched-off offset does; the tool then reaches machine −312.4621 +
/// 0.012 = −312.4501, the part's zero. Also: G10 L2 is absolute even in G91, so the line run
/// twice (or at every tool change) never accumulates.
#[test]
fn sign_the_offset_moves_the_tool_against_the_drift_in_linuxcnc() {
    let Some(bin) = rs274() else { return };
    let update = stdout(&linear("g10", &["--base-mm", "-312.4501"]));
    let base = "G10 L2 P1 Z-312.4501\nG54 G0 X0 Y0 Z0\n";
    let program = format!("{base}{update}G0 Z0\nG91\n{update}G90 G0 Z0\nM2\n");
    let z = machine_z(&bin, &program);
    assert_eq!(z.len(), 3, "{z:?}");
    let drift_mm = 0.012;
    assert!((z[0] - -312.4501).abs() < 1e-9, "{z:?}");
    assert!((z[1] - z[0] - -drift_mm).abs() < 1e-9, "{z:?}");
    assert!(
        (z[1] + drift_mm - -312.4501).abs() < 1e-9,
        "tool reaches {}",
        z[1] + drift_mm
    );
    assert!(
        (z[2] - z[1]).abs() < 1e-9,
        "a second run moved the offset: {z:?}"
    );
}

#[test]
fn zeroed_warm_the_update_is_the_drift_since() {
    // offset set at 30 min (e = 6 µm then), now e = 12 µm: c = −6 µm
    let out = stdout(&linear(
        "g10",
        &["--base-mm", "-312.4501", "--zeroed-at-min", "30"],
    ));
    assert!(out.ends_with("G10 L2 P1 Z-312.4561\n"), "{out}");
    // between rows: the state of the last row at or before it (t = 30 at 45 min)
    let out = stdout(&linear("g10", &["--base-mm", "0", "--zeroed-at-min", "45"]));
    assert!(out.ends_with("G10 L2 P1 Z-0.006\n"), "{out}");
    refused(
        &linear("g10", &["--base-mm", "0", "--zeroed-at-min", "61"]),
        &["--zeroed-at-min 61", "0 to 60 min"],
    );
    refused(
        &linear("sinumerik-sd", &["--zeroed-at-min", "30"]),
        &["--zeroed-at-min is read by the work-offset formats (not sinumerik-sd) only; --format sinumerik-sd does not use it"],
    );
}

fn with_temps(csv: &str, format: &str, extra: &[&str]) -> (tempfile::TempDir, Output) {
    let dir = tempfile::tempdir().unwrap();
    let t = dir.path().join("now.csv");
    std::fs::write(&t, csv).unwrap();
    let m = path("machine.json");
    let t = t.display().to_string();
    let mut a = vec!["--model", &m, "--temps", &t, "--format", format];
    a.extend_from_slice(extra);
    let o = mtec(&a);
    (dir, o)
}

#[test]
fn outside_the_envelope_refused_or_faded() {
    // t1 = 27 °C, 1 °C above the training range [18, 26]: e = 12·27 − 228 = 96 µm
    let csv = "time_min,t1_c\n0,19\n60,27\n";
    let (_d, o) = with_temps(csv, "g10", &["--base-mm", "0"]);
    refused(
        &o,
        &["now.csv:3:2:", "`t1_c` = 27", "[18, 26]", "--outside fade"],
    );
    // fade width 2 °C: w = 1 − 1/2 = 0.5, c = −0.5·96 = −48 µm
    let (_d, o) = with_temps(csv, "g10", &["--base-mm", "0", "--outside", "fade"]);
    let out = stdout(&o);
    assert!(out.ends_with("G10 L2 P1 Z-0.048\n"), "{out}");
    assert!(out.contains("weight 0.500"), "{out}");
    // 2 °C or more outside: no update at all (the safe fallback)
    let (_d, o) = with_temps(
        "time_min,t1_c\n0,19\n60,28.5\n",
        "g10",
        &["--base-mm", "-312.4501", "--outside", "fade"],
    );
    assert!(stdout(&o).ends_with("G10 L2 P1 Z-312.4501\n"));
    // the moment the offset was set must be inside the envelope whatever the policy
    let (_d, o) = with_temps(
        "time_min,t1_c\n0,27\n60,20\n",
        "g10",
        &[
            "--base-mm",
            "0",
            "--zeroed-at-min",
            "0",
            "--outside",
            "fade",
        ],
    );
    refused(&o, &["now.csv:2:2:", "--zeroed-at-min"]);
}

#[test]
fn too_large_an_update_is_refused() {
    refused(
        &linear("g10", &["--base-mm", "0", "--max-correction-um", "10"]),
        &["now.csv:4:", "-12.000 um", "--max-correction-um 10"],
    );
    refused(
        &linear("g10", &["--base-mm", "0", "--max-correction-um", "0"]),
        &["--max-correction-um must be a positive number"],
    );
    // the limit cannot be switched off: 1e308 let a 25 m offset through (issue 17's guard
    // rails; docs/formats.md, "Bounded options")
    refused(
        &linear("g10", &["--base-mm", "0", "--max-correction-um=1e308"]),
        &["--max-correction-um must be a positive number of at most 10000 um"],
    );
    // positions that reach the controller are machine positions: 1e9 wrote Z999999999.9965
    for (flag, format) in [
        ("--base-mm=1e9", "g10"),
        ("--base-mm=1e308", "fanuc"),
        ("--base-mm=inf", "fanuc-macro"),
    ] {
        refused(
            &linear(format, &[flag]),
            &["--base-mm", "is not a machine position"],
        );
    }
    refused(
        &linear("g10", &["--base-mm", "0", "--position-origin-mm=1e9"]),
        &["--position-origin-mm 1e9 mm is not a machine position"],
    );
}

#[test]
fn lag_filters_need_history_or_a_start_at_rest() {
    let m = path("lag_machine.json");
    let run = |csv: &str, extra: &[&str]| {
        let dir = tempfile::tempdir().unwrap();
        let t = dir.path().join("now.csv");
        std::fs::write(&t, csv).unwrap();
        let t = t.display().to_string();
        let mut a = vec!["--model", m.as_str(), "--temps", &t, "--base-mm", "0"];
        a.extend_from_slice(extra);
        (dir, mtec(&a))
    };
    // τ = 20 min: 60 min of log is less than 5τ
    let short = "time_min,t1_c\n0,20\n60,20\n";
    let (_d, o) = run(short, &[]);
    refused(
        &o,
        &[
            "now.csv:2:",
            "tau = 20.0 min",
            "100 min",
            "--starts-at-rest",
        ],
    );
    let (_d, o) = run(short, &["--starts-at-rest"]);
    assert!(stdout(&o).ends_with("G10 L2 P1 Z-0.012\n"));
    // 100 min is enough without it; the lag follows the step from 19 to 20 °C at t = 0:
    // L(100) = 20 − e^(−100/20) (exact step response), e = 12·L − 228
    let (_d, o) = run("time_min,t1_c\n0,19\n0.0001,20\n100,20\n", &[]);
    let out = stdout(&o);
    let z: f64 = out
        .lines()
        .last()
        .unwrap()
        .strip_prefix("G10 L2 P1 Z")
        .unwrap()
        .parse()
        .unwrap();
    let l = 20.0 - (-100.0 / 20.0_f64).exp();
    let expect = -(12.0 * l - 228.0) * 1e-3;
    assert!((z - expect).abs() <= 5e-5, "{z} vs {expect}");
}

#[test]
fn bad_logs_are_refused_with_their_place() {
    let (_d, o) = with_temps("time_min,t1_c\n0,19\n30,warm\n", "g10", &["--base-mm", "0"]);
    refused(&o, &["now.csv:3:2:", "`t1_c` is `warm`"]);
    let (_d, o) = with_temps("time_min,t1_c\n30,19\n0,19\n", "g10", &["--base-mm", "0"]);
    refused(&o, &["now.csv:3:1:", "time goes back"]);
    let (_d, o) = with_temps("time_min,t2_c\n0,19\n", "g10", &["--base-mm", "0"]);
    refused(&o, &["now.csv:1:", "missing column `t1_c`"]);
    let (_d, o) = with_temps(
        "experiment,time_min,t1_c\na,0,19\nb,10,19\n",
        "g10",
        &["--base-mm", "0"],
    );
    refused(&o, &["now.csv:3:1:", "one continuous record"]);
}

#[test]
fn model_and_option_mistakes_are_refused() {
    let t = path("now.csv");
    // a bare thermal model has no envelope
    let lin = path("linear.json");
    refused(
        &mtec(&["--model", &lin, "--temps", &t, "--base-mm", "0"]),
        &["linear.json", "--training"],
    );
    // ... unless its training log gives it (t1 from 19 to 20 here: now = 20 is inside)
    let out = stdout(&mtec(&[
        "--model",
        &lin,
        "--temps",
        &t,
        "--training",
        &t,
        "--base-mm",
        "0",
    ]));
    assert!(out.ends_with("G10 L2 P1 Z-0.012\n"), "{out}");
    // the opposite sign convention flips the update
    let out = stdout(&mtec(&[
        "--model",
        &lin,
        "--temps",
        &t,
        "--training",
        &t,
        "--sign",
        "-1",
        "--base-mm",
        "0",
    ]));
    assert!(out.ends_with("G10 L2 P1 Z0.012\n"), "{out}");
    refused(&linear("g10", &[]), &["--base-mm is required"]);
    refused(
        &linear("sinumerik", &["--base-mm", "0"]),
        &["--base-mm is read by --format g10, fanuc and fanuc-macro only"],
    );
    // the setting data have no work offset, the offsets no slope limit: refused, not ignored
    refused(
        &linear("sinumerik-sd", &["--offset", "2"]),
        &["--offset is read by the work-offset formats (not sinumerik-sd) only; --format sinumerik-sd does not use it"],
    );
    refused(
        &linear("sinumerik", &["--comp-add-velo-factor", "0.02"]),
        &["--comp-add-velo-factor is read by --format sinumerik-sd only; --format sinumerik does not use it"],
    );
    refused(
        &linear("g10", &["--base-mm", "0", "--axis", "x"]),
        &["no thermal part acts along X"],
    );
    refused(
        &linear("fanuc", &["--base-mm", "0", "--offset", "7"]),
        &["--offset 7"],
    );
    refused(
        &linear("g10", &["--base-mm", "0", "--offset", "10"]),
        &["--offset 10"],
    );
    refused(
        &linear("sinumerik", &["--offset", "100"]),
        &["--offset 100"],
    );
    refused(
        &linear("sinumerik-sd", &["--machine-axis", "ax3"]),
        &["--machine-axis `ax3`"],
    );
    let bad = path("now.csv");
    refused(
        &mtec(&["--model", &bad, "--temps", &t, "--base-mm", "0"]),
        &["now.csv"],
    );
}

#[test]
fn written_atomically_and_never_over_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("update.ngc");
    let o = linear(
        "g10",
        &["--base-mm", "-312.4501", "-o", &out.display().to_string()],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        golden("linuxcnc.ngc")
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("-12.000 um"));
    let before = std::fs::read(data().join("now.csv")).unwrap();
    refused(
        &linear("g10", &["--base-mm", "0", "-o", &path("now.csv")]),
        &[],
    );
    assert_eq!(std::fs::read(data().join("now.csv")).unwrap(), before);
}
