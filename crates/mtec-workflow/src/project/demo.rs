//! `mtec demo`: the virtual machine's measurements of every kind, a project over them, its run,
//! and the one thing only a simulation can add: the compensation rate measured against the
//! known truth.

use super::{run_with, Pipeline, RunOptions, RunOutcome};
use crate::{Error, Observer, Result};
use mtec_comp::{command_for_target, CorrectionOptions};
use mtec_io::CsvWriter;
use mtec_model::{Formalism, Order, VolumetricModel};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};

/// The demo's NC program: a rectangular pocket contour and a drilled pattern inside the travel.
const DEMO_GCODE: &str = "%
(mtec demo part: contour and hole pattern, mm)
G21 G90 G17
G0 Z250
G0 X50 Y50
G1 Z200 F500
G1 X550 Y50 F1200
G1 X550 Y750
G1 X50 Y750
G1 X50 Y50
G0 Z250
G0 X300 Y400
G1 Z180 F300
G0 Z250
M30
%
";

fn write(dir: &Path, name: &str, text: &str) -> Result<()> {
    mtec_io::write_output(&dir.join(name), text.as_bytes())?;
    Ok(())
}

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct Options {
    /// Output folder: the simulated measurements go to `<out>/data`, the results beside.
    pub out: PathBuf,
    /// Random seed of the simulation.
    pub seed: u64,
}

/// Simulates the machine's measurements, writes the project file, runs it and adds the
/// compensation rate against the simulation's truth.
pub fn run(opts: &Options, obs: &mut dyn Observer) -> Result<RunOutcome> {
    let data = opts.out.join("data");
    let mut project = String::from("name = \"mtec demo: simulated vertical machining centre\"\n");
    obs.progress("simulating the virtual machine ...");
    for sc in [
        "vmc-9line",
        "volumetric-grid",
        "dbb-rotary",
        "spindle-sensors",
        "feed-axis-ambient",
        "iso230-2",
        "circular-test",
    ] {
        let Ok(o) = mtec_sim::run_scenario(sc, opts.seed) else {
            continue;
        };
        let dir = data.join(sc);
        for f in &o.files {
            write(&dir, &f.name, &f.contents)?;
        }
        write(
            &dir,
            "truth.json",
            &serde_json::to_string_pretty(&o.truth).unwrap_or_default(),
        )?;
    }
    write(&data, "part.ngc", DEMO_GCODE)?;
    project.push_str("machine = \"vmc-9line/machine.toml\"\n");
    project.push_str("[[iso230_2]]\ndata = \"iso230-2/iso230-2.csv\"\n");
    project
        .push_str("[lines]\ndata = \"vmc-9line/lines.csv\"\n[sensitivity]\nmethod = \"efast\"\n");
    project.push_str("[[circular]]\ndata = \"circular-test/circular.csv\"\n");
    project.push_str("[ballbar]\nsetup = \"dbb-rotary/setup.toml\"\ndata = \"dbb-rotary/dbb.csv\"\ntemps = \"dbb-rotary/temps.csv\"\n");
    project.push_str("[[thermal]]\ndata = \"spindle-sensors/thermal.csv\"\ntarget = \"radial_um\"\nmodel = \"ridge-select\"\n");
    project.push_str(
        "[map]\ngrid = \"volumetric-grid/grid.csv\"\ncheck = \"volumetric-grid/diagonals.csv\"\n",
    );
    project.push_str("[compensation]\ngcode = [\"part.ngc\"]\ntables = [\"linuxcnc\"]\n");
    // acceptance limits of a machining centre of this size (ISO 230-2 values as a typical
    // VDI/ISO 10791 acceptance sheet gives them for ≤ 1 m axes; circularity and the residual
    // limits as a customer would set them): the summary judges every figure that has one
    project.push_str(DEMO_TOLERANCES);
    write(&data, "project.toml", &project)?;
    let project_path = data.join("project.toml");
    let run = RunOptions {
        project: project_path,
        out: Some(opts.out.clone()),
        title: Some("mtec demo".into()),
    };
    run_with(&run, obs, |p| {
        compensation_rate_section(p, &data, opts.seed)
    })
}

/// The demo project's `[tolerances]` (docs/formats.md "Project TOML").
const DEMO_TOLERANCES: &str = "[tolerances]\n\
thermal_residual_rms_um = 2.0\n\
map_check_rms_um = 2.0\n\
volumetric_after_rms_um = 3.0\n\
[tolerances.iso230_2]\n\
a_um = 16.0\ne_um = 12.0\nr_um = 6.0\nb_um = 5.0\nm_um = 10.0\n\
[tolerances.circular]\n\
g_um = 20.0\nh_um = 8.0\n";

/// Compensation rate on the virtual machine: 1 − RMS(error after)/RMS(error before) per axis at
/// 1000 random workspace points, where "after" is the true error when the machine is commanded
/// to the corrected point (the map model's correction), measured against the truth.
fn compensation_rate_section(p: &mut Pipeline, data: &Path, seed: u64) -> Result<()> {
    let map_path = p.out.join("map.json");
    let truth_path = data.join("volumetric-grid/truth.json");
    let machine = crate::inputs::read_machine(&data.join("volumetric-grid/machine.toml"))?;
    let truth = crate::inputs::read_errors(&truth_path)?;
    let vm = VolumetricModel::new(&machine, &truth);
    let model = mtec_comp::load_error_model(&map_path)?;
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed ^ 0xc0de);
    let tr: Vec<[f64; 2]> = machine.axes.iter().map(|a| machine.travel(*a)).collect();
    let (mut before, mut after) = ([0.0; 3], [0.0; 3]);
    let n = 1000;
    let opts = CorrectionOptions::default();
    for _ in 0..n {
        // stay 5 mm inside the travel so the corrected command is inside too
        let t: [f64; 3] = [0, 1, 2].map(|i| rng.random_range(tr[i][0] + 5.0..tr[i][1] - 5.0));
        let e0 = vm.error(&t, Formalism::Htm, Order::Exact).position_um;
        let cmd = command_for_target(model.as_ref(), t, &opts)
            .map_err(|e| Error::Internal(anyhow::anyhow!("correction failed: {e}")))?;
        let e1 = vm.error(&cmd, Formalism::Htm, Order::Exact).position_um;
        for i in 0..3 {
            // where the tool lands relative to the target
            let landed = (cmd[i] - t[i]) * 1e3 + e1[i];
            before[i] += e0[i] * e0[i];
            after[i] += landed * landed;
        }
    }
    let rms = |v: f64| (v / n as f64).sqrt();
    let mut rows = Vec::new();
    let mut csv = CsvWriter::new(["axis", "rms_before_um", "rms_after_um", "compensation_rate"]);
    for (i, a) in ["X", "Y", "Z"].iter().enumerate() {
        let (b, af) = (rms(before[i]), rms(after[i]));
        rows.push(vec![
            a.to_string(),
            format!("{b:.2}"),
            format!("{af:.2}"),
            format!("{:.1} %", 100.0 * (1.0 - af / b)),
        ]);
        csv.row(rate_row(a, b, af));
    }
    let (b, af) = (rms(before.iter().sum()), rms(after.iter().sum()));
    rows.push(vec![
        "volumetric".into(),
        format!("{b:.2}"),
        format!("{af:.2}"),
        format!("{:.1} %", 100.0 * (1.0 - af / b)),
    ]);
    csv.row(rate_row("volumetric", b, af));
    mtec_io::write_output(
        &p.out.join("compensation-rate.csv"),
        csv.finish().as_bytes(),
    )?;
    let tol = p.tolerances.volumetric_after_rms_um;
    p.summary.figure(
        "Compensation",
        "volumetric error RMS before",
        b,
        "µm",
        2,
        None,
    );
    p.summary.figure(
        "Compensation",
        "volumetric error RMS after",
        af,
        "µm",
        2,
        tol,
    );
    let arrows = error_arrows(&vm, model.as_ref(), &tr, &opts)?;
    let sec = p.report.section("Compensation rate on the virtual machine");
    sec.source(
        "the simulator's exact kinematics (mtec docs/methods.md §11) commanded to the corrected \
         points; compensation rate = 1 − RMS after / RMS before",
    );
    sec.text(format!("The machine commanded to 1000 random points with and without the map's correction; errors measured against the simulation's truth ({}). Rate = 1 − RMS after / RMS before.", model.describe()));
    sec.table(&["axis", "RMS before (µm)", "RMS after (µm)", "rate"], rows);
    let ([before, after], scale, reference) = arrows;
    let label = format!("{reference} µm");
    for (title, set, what) in [
        (
            "Volumetric error in XY, before compensation",
            &before,
            "before",
        ),
        (
            "Volumetric error in XY, after compensation",
            &after,
            "after",
        ),
    ] {
        let caption = format!(
            "The error of the tool tip in X and Y {what} compensation on a grid over the XY \
             travel at mid Z, one arrow a point, both plots at the same scale (the arrow beside \
             the plot is {reference} µm): after compensation the arrows should be too short to \
             see."
        );
        let svg =
            mtec_report::quiver_chart(title, "X (mm)", "Y (mm)", set, scale, (reference, &label));
        sec.figure(svg, caption);
    }
    Ok(())
}

/// The (Ex, Ey) error at a 7 × 9 grid over the XY travel at mid Z, before and after the
/// correction, with the largest error before (µm: both charts' full scale) and a round
/// reference length (µm).
fn error_arrows(
    vm: &VolumetricModel,
    model: &dyn mtec_comp::ErrorModel,
    tr: &[[f64; 2]],
    opts: &CorrectionOptions,
) -> Result<([Vec<mtec_report::Arrow>; 2], f64, f64)> {
    let (nx, ny) = (7, 9);
    let mut before = Vec::new();
    let mut after = Vec::new();
    let z = 0.5 * (tr[2][0] + tr[2][1]);
    for i in 0..nx {
        for j in 0..ny {
            let x = tr[0][0] + 5.0 + (tr[0][1] - tr[0][0] - 10.0) * i as f64 / (nx - 1) as f64;
            let y = tr[1][0] + 5.0 + (tr[1][1] - tr[1][0] - 10.0) * j as f64 / (ny - 1) as f64;
            let t = [x, y, z];
            let e0 = vm.error(&t, Formalism::Htm, Order::Exact).position_um;
            let cmd = command_for_target(model, t, opts)
                .map_err(|e| Error::Internal(anyhow::anyhow!("correction failed: {e}")))?;
            let e1 = vm.error(&cmd, Formalism::Htm, Order::Exact).position_um;
            // where the tool lands relative to the target
            let landed = [0, 1].map(|k| (cmd[k] - t[k]) * 1e3 + e1[k]);
            before.push(mtec_report::Arrow {
                x,
                y,
                dx: e0[0],
                dy: e0[1],
            });
            after.push(mtec_report::Arrow {
                x,
                y,
                dx: landed[0],
                dy: landed[1],
            });
        }
    }
    let largest = before.iter().map(|a| a.dx.hypot(a.dy)).fold(1e-9, f64::max);
    // a round reference length at most the largest error: 1, 2 or 5 × 10^k µm
    let top = largest;
    let p = 10f64.powf(top.log10().floor());
    let reference = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .rfind(|r| *r <= top)
        .unwrap_or(p);
    Ok(([before, after], largest, reference))
}

/// One row of `compensation-rate.csv`: the RMS before and after (µm) and the rate, 4 decimals.
fn rate_row(axis: &str, before: f64, after: f64) -> [String; 4] {
    [
        axis.to_string(),
        format!("{before:.4}"),
        format!("{after:.4}"),
        format!("{:.4}", 1.0 - after / before),
    ]
}
