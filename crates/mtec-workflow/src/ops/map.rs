//! `map fit` and `map eval`: a volumetric error map from a measured grid, and an error model's
//! values at points.

use crate::{Error, Observer, Result};
use mtec_comp::map::{GridLimits, GridMap, Outside};
use mtec_io::{CsvReader, Destination, InputError, OutputGuard};
use serde::Serialize;
use std::fmt;
use std::io::Write as _;
use std::path::PathBuf;

/// The kind of map `fit` builds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapKind {
    /// Trilinear interpolation between grid nodes (a controller's 3-D compensation).
    Trilinear,
    /// A one-hidden-layer network (needs the `neural` feature).
    Bpnn {
        /// Hidden neurons, 1 to 1000.
        hidden: usize,
    },
}

/// Options of [`fit`].
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Grid CSV: x_mm,y_mm,z_mm,ex_um,ey_um,ez_um, one row per node.
    pub grid: PathBuf,
    pub kind: MapKind,
    /// What the map does beyond the grid box.
    pub outside: Outside,
    /// Grid limits of a controller: `none`, `fanuc-3d` or `linuxcnc`.
    pub controller: String,
    /// At most this many points per axis (overrides the controller's limit).
    pub max_points_per_axis: Option<usize>,
    /// The map file to write (`mtec.map/1`, or `mtec.bpnn/1` for a BPNN).
    pub out: PathBuf,
}

impl FitOptions {
    /// A trilinear map of `grid` written to `out`, clamped outside the box, no controller limit.
    pub fn trilinear(grid: impl Into<PathBuf>, out: impl Into<PathBuf>) -> Self {
        FitOptions {
            grid: grid.into(),
            kind: MapKind::Trilinear,
            outside: Outside::Clamp,
            controller: "none".into(),
            max_points_per_axis: None,
            out: out.into(),
        }
    }
}

/// What [`fit`] did.
#[derive(Debug, Clone, Serialize)]
pub struct FitOutcome {
    /// `trilinear` or `bpnn`.
    pub model: &'static str,
    /// Nodes per axis of a trilinear map.
    pub nodes: Option<[usize; 3]>,
    /// The outside policy of a trilinear map.
    pub outside: Option<&'static str>,
    /// A BPNN's activation and fit report (fit errors per axis, parameters, training).
    #[cfg(feature = "neural")]
    pub bpnn: Option<BpnnFit>,
    pub out: PathBuf,
}

impl fmt::Display for FitOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        #[cfg(feature = "neural")]
        if let Some(b) = &self.bpnn {
            return write_bpnn_report(f, b, &self.out);
        }
        let n = self.nodes.unwrap_or_default();
        writeln!(
            f,
            "map: {}×{}×{} nodes, outside = {} -> {}",
            n[0],
            n[1],
            n[2],
            self.outside.unwrap_or("clamp"),
            self.out.display()
        )
    }
}

/// A fitted BPNN map: its activation and fit report.
#[cfg(feature = "neural")]
#[derive(Debug, Clone, Serialize)]
pub struct BpnnFit {
    pub hidden: usize,
    pub activation: String,
    pub report: mtec_nn::GridFitReport,
}

/// Builds a map from a measured grid and writes it.
pub fn fit(opts: &FitOptions, obs: &mut dyn Observer) -> Result<FitOutcome> {
    let mut limits = GridLimits::for_controller(&opts.controller)
        .ok_or_else(|| Error::usage(format!("unknown --controller `{}`", opts.controller)))?;
    if let Some(n) = opts.max_points_per_axis {
        if n < 1 {
            return Err(Error::usage("--max-points-per-axis must be at least 1"));
        }
        limits.max_points_per_axis = Some(n);
    }
    // where the map goes is settled before any work (an input, a directory: exit 2)
    let dest = OutputGuard::new(&[&opts.grid]).check(&opts.out)?;
    let map = match opts.kind {
        MapKind::Trilinear => GridMap::read_csv(&opts.grid, &limits, opts.outside)?,
        MapKind::Bpnn { hidden } => return fit_bpnn(opts, hidden, &dest, obs),
    };
    let mut json = serde_json::to_string_pretty(&map.to_file())?;
    json.push('\n');
    dest.write(json.as_bytes())?;
    let n = map.axes_mm();
    Ok(FitOutcome {
        model: "trilinear",
        nodes: Some([n[0].len(), n[1].len(), n[2].len()]),
        outside: Some(opts.outside.name()),
        #[cfg(feature = "neural")]
        bpnn: None,
        out: opts.out.clone(),
    })
}

#[cfg(not(feature = "neural"))]
fn fit_bpnn(_: &FitOptions, _: usize, _: &Destination, _: &mut dyn Observer) -> Result<FitOutcome> {
    Err(crate::neural_unavailable("`map fit --model bpnn`"))
}

/// Fits a one-hidden-layer BPNN (3-hidden-3, sigmoid, Levenberg–Marquardt with early stopping on
/// a seeded 15 % validation split) to the grid and writes it as `mtec.bpnn/1`, which compensation
/// evaluates without any neural-network library. The grid need not be regular.
#[cfg(feature = "neural")]
fn fit_bpnn(
    opts: &FitOptions,
    hidden: usize,
    dest: &Destination,
    obs: &mut dyn Observer,
) -> Result<FitOutcome> {
    use mtec_nn::{fit_grid_monitored, GridFitConfig};
    let grid_path = &opts.grid;
    if hidden == 0 || hidden > 1000 {
        return Err(Error::usage(format!(
            "--hidden must be between 1 and 1000, got {hidden}"
        )));
    }
    let table = mtec_io::Table::read(grid_path)?;
    let cols = ["x_mm", "y_mm", "z_mm", "ex_um", "ey_um", "ez_um"];
    table.require(&cols)?;
    let c: Vec<Vec<f64>> = cols
        .iter()
        .map(|n| table.f64_column(n))
        .collect::<std::result::Result<_, _>>()?;
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
    obs.progress(&format!("training a 3-{hidden}-3 BPNN on {n} grid points"));
    let config = GridFitConfig {
        hidden,
        ..GridFitConfig::default()
    };
    let fitted = fit_grid_monitored(&p, &e, &config, &mut crate::observer::Relay(obs));
    let (mut net, report) = fitted.map_err(|e| match e {
        mtec_nn::NnError::Data(m) => Error::Input(InputError::file(grid_path, m)),
        other => Error::Internal(anyhow::anyhow!(other)),
    })?;
    net.provenance = serde_json::json!({
        "grid": grid_path.display().to_string(),
        "fit": &report,
        "training": net.provenance,
    });
    dest.write(net.to_json().as_bytes())?;
    Ok(FitOutcome {
        model: "bpnn",
        nodes: None,
        outside: None,
        bpnn: Some(BpnnFit {
            hidden,
            activation: format!("{:?}", net.activation),
            report,
        }),
        out: opts.out.clone(),
    })
}

#[cfg(feature = "neural")]
fn write_bpnn_report(
    f: &mut fmt::Formatter<'_>,
    b: &BpnnFit,
    out: &std::path::Path,
) -> fmt::Result {
    let r = &b.report;
    writeln!(
        f,
        "BPNN 3-{}-3 ({}) fitted to {} grid points: {} parameters instead of {} grid values",
        b.hidden, b.activation, r.points, r.parameters, r.grid_values
    )?;
    writeln!(
        f,
        "fit error (model - grid), um:   min      max     mean      std"
    )?;
    for (axis, s) in [
        ("x", &r.fit_error_x),
        ("y", &r.fit_error_y),
        ("z", &r.fit_error_z),
    ] {
        writeln!(
            f,
            "  e{axis}                       {:8.3} {:8.3} {:8.3} {:8.3}",
            s.min_um, s.max_um, s.mean_um, s.std_um
        )?;
    }
    writeln!(
        f,
        "training: {} Levenberg-Marquardt iterations, best {}, {}",
        r.training.epochs, r.training.best_epoch, r.training.stop_reason
    )?;
    writeln!(f, "wrote {}", out.display())
}

/// Options of [`eval`].
#[derive(Debug, Clone)]
pub struct EvalOptions {
    /// Any model file mtec reads (`mtec_comp::load_error_model`).
    pub model: PathBuf,
    /// Points CSV with at least x_mm,y_mm,z_mm.
    pub points: PathBuf,
    /// Output CSV; `None` writes to stdout.
    pub out: Option<PathBuf>,
}

/// What [`eval`] did.
#[derive(Debug, Clone, Serialize)]
pub struct EvalOutcome {
    /// Points evaluated (rows written).
    pub points: usize,
    pub out: Option<PathBuf>,
}

/// Rows `eval` reads, evaluates ([`mtec_comp::ErrorModel::eval_batch`]) and writes at a time:
/// large enough that the batch and the write calls pay off, small enough (≈ 300 kB of text)
/// to stay in cache.
const EVAL_CHUNK_ROWS: usize = 4096;

/// Evaluates an error model at the points of a CSV file and writes
/// x_mm,y_mm,z_mm,ex_um,ey_um,ez_um, one row per input row, in the same order.
///
/// Streamed in chunks of [`EVAL_CHUNK_ROWS`] rows: memory does not grow with the file. A bad
/// row is reported at its line and column as soon as its chunk is read (a point the model has
/// no value at before a later unreadable row); the output file is then left untouched. To
/// standard output the rows before a bad one have been written already (as `compensate gcode`
/// does).
pub fn eval(opts: &EvalOptions, _obs: &mut dyn Observer) -> Result<EvalOutcome> {
    let dest = match &opts.out {
        Some(path) => OutputGuard::new(&[&opts.model, &opts.points]).check(path)?,
        None => Destination::Stdout,
    };
    let model = mtec_comp::load_error_model(&opts.model)?;
    // streamed: a bad point is reported without reading the rest, and the file is never held
    let mut points = CsvReader::open(&opts.points)?;
    let cols = [
        points.column("x_mm")?,
        points.column("y_mm")?,
        points.column("z_mm")?,
    ];
    // dropped on error, an unfinished output leaves the target untouched
    let mut out = dest.open()?;
    let mut chunk = EvalChunk::default();
    chunk
        .text
        .extend_from_slice(b"x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n");
    let mut n = 0;
    loop {
        // a row read and parsed, or the error it gave (reported after the points before it)
        let read: std::result::Result<bool, InputError> = match points.next_row() {
            Ok(None) => Ok(false),
            Err(e) => Err(e),
            Ok(Some(row)) => {
                let mut p = [0.0; 3];
                let mut bad = None;
                for (pa, &c) in p.iter_mut().zip(&cols) {
                    match row.f64(c) {
                        Ok(v) => *pa = v,
                        Err(e) => {
                            bad = Some(e);
                            break;
                        }
                    }
                }
                match bad {
                    Some(e) => Err(e),
                    None => {
                        chunk.push(
                            row.line(),
                            p,
                            [row.str(cols[0]), row.str(cols[1]), row.str(cols[2])],
                        );
                        Ok(true)
                    }
                }
            }
        };
        match read {
            Ok(true) if chunk.points.len() < EVAL_CHUNK_ROWS => continue,
            Ok(more) => {
                n += chunk.write(model.as_ref(), &opts.points, cols[0], &mut out)?;
                if !more {
                    break;
                }
            }
            Err(e) => {
                chunk.write(model.as_ref(), &opts.points, cols[0], &mut out)?;
                return Err(e.into());
            }
        }
    }
    out.commit()?;
    Ok(EvalOutcome {
        points: n,
        out: opts.out.clone(),
    })
}

/// The rows of `eval` read but not yet written: their lines, points, and the output text up
/// to the errors (`x,y,z,` as given in the file).
#[derive(Default)]
struct EvalChunk {
    lines: Vec<usize>,
    points: Vec<[f64; 3]>,
    errors: Vec<[f64; 3]>,
    /// The echoed `x,y,z,` of all rows, row i ending at `echo_end[i]`.
    echo: Vec<u8>,
    echo_end: Vec<usize>,
    /// Output bytes waiting to be written.
    text: Vec<u8>,
}

impl EvalChunk {
    fn push(&mut self, line: usize, p: [f64; 3], given: [&str; 3]) {
        self.lines.push(line);
        self.points.push(p);
        for s in given {
            self.echo.extend_from_slice(s.as_bytes());
            self.echo.push(b',');
        }
        self.echo_end.push(self.echo.len());
    }

    /// Evaluates the chunk's points, writes their rows (refusing the first point the model has
    /// no value at, located at line and `x_col`), empties the chunk; returns the rows written.
    fn write(
        &mut self,
        model: &dyn mtec_comp::ErrorModel,
        path: &std::path::Path,
        x_col: usize,
        out: &mut mtec_io::Output,
    ) -> Result<usize> {
        let n = self.points.len();
        if n == 0 {
            return Ok(0);
        }
        self.errors.resize(n, [0.0; 3]);
        model.eval_batch(&self.points, &mut self.errors);
        if let Some(i) = self
            .errors
            .iter()
            .position(|e| !e.iter().all(|v| v.is_finite()))
        {
            let p = self.points[i];
            return Err(InputError::at(
                path,
                self.lines[i],
                x_col + 1,
                format!(
                    "the model has no value at ({}, {}, {}) mm (outside the map's grid, whose policy is refuse; see `mtec map fit --outside`)",
                    p[0], p[1], p[2]
                ),
            )
            .into());
        }
        let mut start = 0;
        for (e, &end) in self.errors.iter().zip(&self.echo_end) {
            self.text.extend_from_slice(&self.echo[start..end]);
            start = end;
            mtec_io::number::push_f64(&mut self.text, e[0]);
            self.text.push(b',');
            mtec_io::number::push_f64(&mut self.text, e[1]);
            self.text.push(b',');
            mtec_io::number::push_f64(&mut self.text, e[2]);
            self.text.push(b'\n');
        }
        out.write_all(&self.text)
            .map_err(|error| mtec_io::OutputError::Io {
                path: out.path().to_path_buf(),
                error,
            })?;
        self.text.clear();
        self.lines.clear();
        self.points.clear();
        self.echo.clear();
        self.echo_end.clear();
        Ok(n)
    }
}
