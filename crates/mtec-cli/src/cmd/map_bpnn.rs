//! `mtec map fit --model bpnn`: fits a one-hidden-layer BPNN (3-hidden-3, sigmoid, trained by
//! Levenberg–Marquardt with early stopping on a seeded 15 % validation split) to a volumetric
//! error grid and writes it as an `mtec.bpnn/1` model that `mtec map eval` and compensation
//! evaluate without any neural-network library.
//!
//! Grid file (SPEC §4): `x_mm,y_mm,z_mm,ex_um,ey_um,ez_um`, one row per grid point (any order;
//! the network does not need a regular grid). Prints the fit-error statistics per axis (model −
//! grid value over every grid point: min, max, mean, std in µm) and the parameter count next to
//! the number of values the grid table stores (e.g. 73 parameters against 3993 values for an
//! 11 × 11 × 11 grid).
//!
//! Wiring (in `map.rs`): `map_bpnn::fit_bpnn(&args.grid, args.hidden, &args.out)`.

use crate::error::CliError;
use mtec_io::{Destination, InputError, Table};
use mtec_nn::{fit_grid_monitored, GridFitConfig};
use std::io::Write;
use std::path::Path;

/// Reads the grid, fits the BPNN, prints the report and writes the model to `dest` (`out` as the
/// user gave it, checked by the caller before any work).
pub fn fit_bpnn(
    grid_path: &Path,
    hidden: usize,
    out: &Path,
    dest: &Destination,
) -> Result<(), CliError> {
    if hidden == 0 || hidden > 1000 {
        return Err(CliError::usage(format!(
            "--hidden must be between 1 and 1000, got {hidden}"
        )));
    }
    let table = Table::read(grid_path)?;
    let cols = ["x_mm", "y_mm", "z_mm", "ex_um", "ey_um", "ez_um"];
    table.require(&cols)?;
    let c: Vec<Vec<f64>> = cols
        .iter()
        .map(|n| table.f64_column(n))
        .collect::<Result<_, _>>()?;
    let n = table.rows.len();
    if n < 8 {
        return Err(InputError::file(
            grid_path,
            format!("a grid needs at least 8 points, the file has {n}"),
        )
        .into());
    }
    let p: Vec<[f64; 3]> = (0..n).map(|i| [c[0][i], c[1][i], c[2][i]]).collect();
    let e: Vec<[f64; 3]> = (0..n).map(|i| [c[3][i], c[4][i], c[5][i]]).collect();
    let config = GridFitConfig {
        hidden,
        ..GridFitConfig::default()
    };
    let mut term = super::terminal::Terminal::new(false);
    let fitted = fit_grid_monitored(&p, &e, &config, &mut term);
    term.done();
    let (mut net, report) = fitted.map_err(|e| match e {
        mtec_nn::NnError::Data(m) => CliError::Input(InputError::file(grid_path, m)),
        other => CliError::Internal(anyhow::anyhow!(other)),
    })?;
    net.provenance = serde_json::json!({
        "grid": grid_path.display().to_string(),
        "fit": &report,
        "training": net.provenance,
    });
    let mut say = super::messages(dest);
    let _ = writeln!(
        say,
        "BPNN 3-{hidden}-3 ({:?}) fitted to {} grid points: {} parameters instead of {} grid values",
        net.activation, report.points, report.parameters, report.grid_values
    );
    let _ = writeln!(
        say,
        "fit error (model - grid), um:   min      max     mean      std"
    );
    for (axis, s) in [
        ("x", report.fit_error_x),
        ("y", report.fit_error_y),
        ("z", report.fit_error_z),
    ] {
        let _ = writeln!(
            say,
            "  e{axis}                       {:8.3} {:8.3} {:8.3} {:8.3}",
            s.min_um, s.max_um, s.mean_um, s.std_um
        );
    }
    let _ = writeln!(
        say,
        "training: {} Levenberg-Marquardt iterations, best {}, {}",
        report.training.epochs, report.training.best_epoch, report.training.stop_reason
    );
    dest.write(net.to_json().as_bytes())?;
    let _ = writeln!(say, "wrote {}", out.display());
    Ok(())
}
