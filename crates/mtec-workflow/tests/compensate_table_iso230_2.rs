//! `compensate table --from-iso230-2` in-process: the hand-worked run read from its file
//! (means by the reader and ISO 230-2 evaluation), the simulated axis against its truth and
//! against means computed here from the file, and refusals that name the run file and line.

use mtec_workflow::ops::compensate_table::{self, Format, Options};
use mtec_workflow::{Error, Silent};
use std::path::{Path, PathBuf};

/// The run of `mtec-comp/tests/bidirectional_tables.rs` (5 targets, 2 runs each way), as a
/// file in the ISO 230-2 run format; its means are worked in that file's table.
const RUN: &str = "target_mm,run,direction,deviation_um\n\
    0,1,+,1\n50,1,+,3\n100,1,+,-2\n150,1,+,-5\n200,1,+,0\n\
    200,1,-,2\n150,1,-,-3\n100,1,-,0\n50,1,-,6\n0,1,-,4\n\
    0,2,+,2\n50,2,+,4\n100,2,+,-1\n150,2,+,-4\n200,2,+,1\n\
    200,2,-,3\n150,2,-,-2\n100,2,-,1\n50,2,-,7\n0,2,-,5\n";

fn options(run: &Path, format: Format, out: PathBuf) -> Options {
    let mut o = Options::new("", format, Some(out));
    o.from_iso230_2 = Some(run.to_path_buf());
    o
}

#[test]
fn the_run_file_gives_the_hand_worked_tables() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run.csv");
    std::fs::write(&run, RUN).unwrap();
    let out = dir.path().join("x.comp");
    let o =
        compensate_table::run(&options(&run, Format::Linuxcnc, out.clone()), &mut Silent).unwrap();
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        "0.000000 -0.001500 -0.004500\n\
         50.000000 -0.003500 -0.006500\n\
         100.000000 0.001500 -0.000500\n\
         150.000000 0.004500 0.002500\n\
         200.000000 -0.000500 -0.002500\n"
    );
    assert_eq!(o.points, 5);
    // B_i = x̄↑ − x̄↓ = −3, −3, −2, −2, −2: max |B_i| = 3
    assert_eq!(o.reversal_max_um, Some(3.0));
    // 2 runs per direction and 5 targets: the reader's warnings are passed on
    assert_eq!(o.warnings.len(), 2, "{:?}", o.warnings);
    for format in [
        Format::SinumerikCec,
        Format::Fanuc,
        Format::Heidenhain,
        Format::Beckhoff,
    ] {
        let out = dir.path().join(format!("t.{}", format.name()));
        compensate_table::run(&options(&run, format, out.clone()), &mut Silent)
            .unwrap_or_else(|e| panic!("{}: {e}", format.name()));
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
    }
    // the CEC file is the golden one of mtec-comp's test, read back: table 1 holds c↓
    let cec = std::fs::read_to_string(dir.path().join("t.sinumerik-cec")).unwrap();
    assert!(
        cec.contains("$AN_CEC[1,3]=0.0025\n$AN_CEC[1,4]=-0.0025\n"),
        "{cec}"
    );
    // the run file is never overwritten
    let e = compensate_table::run(&options(&run, Format::Linuxcnc, run.clone()), &mut Silent)
        .unwrap_err();
    assert!(matches!(e, Error::Usage(_)), "{e}");
    assert_eq!(std::fs::read_to_string(&run).unwrap(), RUN);
}

#[test]
fn refusals_name_the_run_file_and_the_targets_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run.csv");
    std::fs::write(&run, RUN).unwrap();
    let input = |e: Error| match e {
        Error::Input(i) => i,
        other => panic!("expected an input error, got {other}"),
    };
    // LEC has one table for both directions and the run reverses by 3 um at 0 mm (line 2)
    let e = input(
        compensate_table::run(
            &options(&run, Format::SinumerikLec, dir.path().join("x.ini")),
            &mut Silent,
        )
        .unwrap_err(),
    );
    assert_eq!((e.file.as_path(), e.line), (run.as_path(), Some(2)), "{e}");
    assert!(e.message.contains("sinumerik-cec"), "{e}");
    // a correction over the bound: c↓ = −6.5 um at 50 mm, first named on line 3
    let mut o = options(&run, Format::Linuxcnc, dir.path().join("y.comp"));
    o.max_correction_um = 5.0;
    let e = input(compensate_table::run(&o, &mut Silent).unwrap_err());
    assert_eq!(e.line, Some(3), "{e}");
    assert!(e.message.contains("-6.500 um"), "{e}");
    // unequal spacing: 100 → 120 mm, refused by the equidistant formats at that target
    let uneven = RUN.replace("\n100,", "\n120,");
    std::fs::write(&run, &uneven).unwrap();
    for format in [Format::SinumerikCec, Format::Fanuc] {
        let e = input(
            compensate_table::run(&options(&run, format, dir.path().join("z")), &mut Silent)
                .unwrap_err(),
        );
        assert_eq!(e.line, Some(4), "{}: {e}", format.name());
        assert!(e.message.contains("equally spaced"), "{e}");
    }
    // 257 targets: more than a LinuxCNC joint holds
    let mut big = String::from("target_mm,run,direction,deviation_um\n");
    for run_no in 1..=2 {
        for d in ["+", "-"] {
            for t in 0..257 {
                big.push_str(&format!("{t},{run_no},{d},0.5\n"));
            }
        }
    }
    std::fs::write(&run, &big).unwrap();
    let e = input(
        compensate_table::run(
            &options(&run, Format::Linuxcnc, dir.path().join("big.comp")),
            &mut Silent,
        )
        .unwrap_err(),
    );
    assert_eq!(e.file, run);
    assert!(e.message.contains("257 targets"), "{e}");
    assert!(!dir.path().join("big.comp").exists());
}

/// The simulated axis (scenario `iso230-2`: 11 irregular targets, 5 runs, lost motion 3.5 um):
/// the LinuxCNC, HEIDENHAIN and Beckhoff tables (formats that take any spacing) read back give
/// −(the means computed here from the file) to their resolution, and the truth to 4 standard
/// errors of a 5-run mean (4·0.2/√5 = 0.36 um) plus that resolution.
#[test]
fn simulated_axis_round_trip_against_the_means_and_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let sim = mtec_sim::run_scenario("iso230-2", 7).unwrap();
    let run = dir.path().join("iso230-2.csv");
    std::fs::write(&run, &sim.files[0].contents).unwrap();
    let truth = &sim.truth;
    let targets: Vec<f64> = serde_json::from_value(truth["targets_mm"].clone()).unwrap();
    let true_up: Vec<f64> = serde_json::from_value(truth["mean_up_um"].clone()).unwrap();
    let true_down: Vec<f64> = serde_json::from_value(truth["mean_down_um"].clone()).unwrap();
    // the means, independently: sum and count per (target, direction) of the file's rows
    let mut sums = vec![[0.0f64; 2]; targets.len()];
    let mut counts = vec![[0usize; 2]; targets.len()];
    for line in sim.files[0].contents.lines() {
        let f: Vec<&str> = line.split(',').collect();
        let Ok(t) = f[0].parse::<f64>() else { continue };
        let i = targets.iter().position(|&x| (x - t).abs() < 1e-9).unwrap();
        let d = usize::from(f[2] == "-");
        sums[i][d] += f[3].parse::<f64>().unwrap();
        counts[i][d] += 1;
    }
    let mean = |i: usize, d: usize| sums[i][d] / counts[i][d] as f64;
    assert!(counts.iter().all(|c| *c == [5, 5]));
    let standard_error = 4.0 * 0.2 / 5f64.sqrt();

    let read = |format: Format, name: &str| -> Vec<[f64; 3]> {
        let out = dir.path().join(name);
        compensate_table::run(&options(&run, format, out.clone()), &mut Silent).unwrap();
        std::fs::read_to_string(&out)
            .unwrap()
            .lines()
            .filter_map(|l| {
                let v: Vec<f64> = l
                    .split_whitespace()
                    .filter_map(|s| s.parse().ok())
                    .collect();
                (v.len() == 3 || v.len() == 4).then(|| {
                    let v = &v[v.len() - 3..];
                    [v[0], v[1], v[2]]
                })
            })
            .collect()
    };
    // LinuxCNC trims (mm) = c = −x̄; resolution 1 nm
    let lin = read(Format::Linuxcnc, "x.comp");
    // HEIDENHAIN rows NR AXISPOS X BACKLASH: errors x̄ in mm, 0.1 um
    let hh = read(Format::Heidenhain, "X.COM");
    assert_eq!((lin.len(), hh.len()), (targets.len(), targets.len()));
    let (mut worst_mean, mut worst_truth) = (0.0f64, 0.0f64);
    for i in 0..targets.len() {
        assert!((lin[i][0] - targets[i]).abs() < 1e-9 && (hh[i][0] - targets[i]).abs() < 1e-9);
        for d in 0..2 {
            let by_linuxcnc = -lin[i][1 + d] * 1e3;
            let by_heidenhain = hh[i][1 + d] * 1e3;
            assert!((by_linuxcnc - mean(i, d)).abs() <= 5e-4, "{i} {d}");
            assert!((by_heidenhain - mean(i, d)).abs() <= 0.05 + 1e-9, "{i} {d}");
            let t = [true_up[i], true_down[i]][d];
            worst_mean = worst_mean.max((by_linuxcnc - mean(i, d)).abs());
            worst_truth = worst_truth.max((by_linuxcnc - t).abs());
            assert!(
                (by_linuxcnc - t).abs() < standard_error + 5e-4,
                "target {i} dir {d}"
            );
        }
    }
    eprintln!(
        "linuxcnc: |table - means| <= {worst_mean:.1e} um, |table - truth| <= {worst_truth:.3} um"
    );
    // Beckhoff: pos/neg in 0.1 um = x̄
    let out = dir.path().join("x.lis");
    compensate_table::run(&options(&run, Format::Beckhoff, out.clone()), &mut Silent).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    for i in 0..targets.len() {
        for (d, field) in ["pos", "neg"].iter().enumerate() {
            let key = format!("kw.ssfk.table[{i}].{field}");
            let v: f64 = text
                .lines()
                .find_map(|l| l.strip_prefix(&key))
                .unwrap()
                .trim()
                .parse()
                .unwrap();
            assert!((v / 10.0 - mean(i, d)).abs() <= 0.05 + 1e-9, "{key}");
        }
    }
    // the reversal the table carries is the simulated lost motion, −3.5 um
    for (i, row) in lin.iter().enumerate() {
        let b = (-row[1] + row[2]) * 1e3; // x̄↑ − x̄↓
        assert!((b + 3.5).abs() < 2.0 * standard_error, "B at {i}: {b}");
    }
}
