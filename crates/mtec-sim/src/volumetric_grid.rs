//! Scenario `volumetric-grid`: a laser-tracker measurement of the XYFZ machine's volumetric
//! error on an 11 × 11 × 11 grid (tool length 100 mm), the input of map fitting (trilinear,
//! BPNN). Files: `machine.toml`, `grid.csv` (`x_mm,y_mm,z_mm,ex_um,ey_um,ez_um`),
//! `diagonals.csv` (the four body diagonals PPP, NPP, NPN, PPN, 51 points each, measured the
//! same way, for checking predictions off the grid), `truth.json`.

use crate::instruments::{exact_error_um, gauss, Tracker};
use crate::output::{OutputFile, ScenarioOutput};
use crate::truth::geometric_truth;
use mtec_io::CsvWriter;
use mtec_model::{Axis, Machine, VolumetricModel};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// Points per axis of the grid.
pub const GRID_POINTS: usize = 11;

/// The four body diagonals (name, start corner, end corner) as fractions of the travel.
pub const DIAGONALS: [(&str, [f64; 3], [f64; 3]); 4] = [
    ("PPP", [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    ("NPP", [1.0, 0.0, 0.0], [0.0, 1.0, 1.0]),
    ("NPN", [1.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
    ("PPN", [0.0, 0.0, 1.0], [1.0, 1.0, 0.0]),
];

/// The scenario.
pub fn run(seed: u64) -> ScenarioOutput {
    let machine = Machine::vmc_xyfz(100.0);
    let truth = geometric_truth(&machine, seed);
    let vm = VolumetricModel::new(&machine, &truth);
    let tracker = Tracker { noise_um: 0.3 };
    let mut rng = StdRng::seed_from_u64(seed ^ 0x7472_6163);
    let tr = [Axis::X, Axis::Y, Axis::Z].map(|a| machine.travel(a));
    let mut grid = CsvWriter::commented(
        [format!(
            "volumetric-grid: laser tracker, {GRID_POINTS}^3 points, noise {} um, seed {seed}",
            tracker.noise_um
        )],
        ["x_mm", "y_mm", "z_mm", "ex_um", "ey_um", "ez_um"],
    );
    let n = GRID_POINTS - 1;
    for i in 0..=n {
        for j in 0..=n {
            for k in 0..=n {
                let p = [i, j, k]
                    .iter()
                    .enumerate()
                    .map(|(a, &t)| tr[a][0] + (tr[a][1] - tr[a][0]) * t as f64 / n as f64)
                    .collect::<Vec<_>>();
                let e = exact_error_um(&vm, &p);
                let m = e.map(|v| v + gauss(&mut rng, tracker.noise_um));
                let mut row: Vec<String> = p.iter().map(|v| format!("{v:.3}")).collect();
                row.extend(m.map(|v| format!("{v:.4}")));
                grid.row(row);
            }
        }
    }
    let mut diag = CsvWriter::new([
        "diagonal",
        "x_mm",
        "y_mm",
        "z_mm",
        "ex_um",
        "ey_um",
        "ez_um",
        "true_ex_um",
        "true_ey_um",
        "true_ez_um",
    ]);
    for (name, s, e) in DIAGONALS {
        for k in 0..=50 {
            let t = k as f64 / 50.0;
            let p: Vec<f64> = (0..3)
                .map(|a| tr[a][0] + (tr[a][1] - tr[a][0]) * (s[a] + t * (e[a] - s[a])))
                .collect();
            let te = exact_error_um(&vm, &p);
            let m = te.map(|v| v + gauss(&mut rng, tracker.noise_um));
            let mut row = vec![name.to_string()];
            row.extend(p.iter().map(|v| format!("{v:.3}")));
            row.extend(m.iter().chain(&te).map(|v| format!("{v:.4}")));
            diag.row(row);
        }
    }
    let machine_toml = toml::to_string(&machine.to_spec()).expect("machine spec serialises");
    ScenarioOutput {
        files: vec![
            OutputFile {
                name: "machine.toml".into(),
                contents: machine_toml,
            },
            OutputFile {
                name: "grid.csv".into(),
                contents: grid.finish(),
            },
            OutputFile {
                name: "diagonals.csv".into(),
                contents: diag.finish(),
            },
        ],
        truth: serde_json::json!({ "format": "mtec.truth/1", "scenario": "volumetric-grid", "seed": seed, "errors": truth, "tracker_noise_um": tracker.noise_um }),
    }
}
