//! Replaying a recorded day through the real-time compensation (`mtec machine replay`): how
//! much of the measured error the controller would have removed.
//!
//! Inputs: the controller's state log (`time_min` and the model's state inputs, one row per
//! reading) and probe readings of the error at the tool tip (`time_min,x_mm,y_mm,z_mm,
//! ex_um,ey_um,ez_um`, optionally `probe`, actual − commanded, taken without compensation).
//! Every probe reading is compensated exactly as the real-time library would do it at that
//! moment: the [`Compensator`] has received every state reading up to the probe's time through
//! [`Compensator::update_state`] (the same call `mtec_rt_update_state` makes), then
//! [`Compensator::correction_um`] gives the correction c for the probe point. The compensated
//! error is e + c: the command moves by c, and the error field changes by far less than a
//! micrometre over a few micrometres of travel (e(p + c) = e(p) to first order in |c|).
//!
//! Summary: RMS and largest magnitude of the error before and after, per axis and as the 3-D
//! vector, the compensation rate 1 − RMS_after / RMS_before (the `Metrics` definition), the
//! reduction of the worst moment 1 − max|e_after| / max|e_before|, the readings made worse
//! (|e_after| > |e_before| as vectors) and the readings whose thermal part was faded.

use crate::model::StateStatus;
use crate::Compensator;
use mtec_io::{InputError, Table};
use serde::Serialize;

/// One compensated probe reading.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySample {
    pub time_min: f64,
    pub probe: String,
    pub position_mm: [f64; 3],
    pub before_um: [f64; 3],
    pub correction_um: [f64; 3],
    pub after_um: [f64; 3],
    /// Thermal weight of the state the correction used.
    pub thermal_weight: f64,
    /// The input furthest outside the training envelope, if any.
    pub outside: Option<String>,
}

/// RMS and largest magnitude of one component (or of the vector) before and after.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Reduction {
    pub rms_before_um: f64,
    pub rms_after_um: f64,
    pub max_before_um: f64,
    pub max_after_um: f64,
    /// 1 − RMS_after / RMS_before.
    pub compensation_rate: f64,
    /// 1 − max_after / max_before.
    pub worst_reduction: f64,
}

impl Reduction {
    fn of(before: &[f64], after: &[f64]) -> Reduction {
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        let max = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let (rb, ra, mb, ma) = (rms(before), rms(after), max(before), max(after));
        Reduction {
            rms_before_um: rb,
            rms_after_um: ra,
            max_before_um: mb,
            max_after_um: ma,
            compensation_rate: 1.0 - ra / rb,
            worst_reduction: 1.0 - ma / mb,
        }
    }
}

/// The summary of a replay (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySummary {
    pub readings: usize,
    pub state_rows: usize,
    /// Along X, Y, Z and of the vector.
    pub x: Reduction,
    pub y: Reduction,
    pub z: Reduction,
    pub vector: Reduction,
    /// Readings with |e_after| > |e_before| (vectors).
    pub worse: usize,
    /// The largest |e_after| − |e_before| (µm; ≤ 0 when no reading got worse).
    pub largest_worsening_um: f64,
    /// Readings taken with a faded thermal part (weight < 1), and the smallest weight.
    pub faded: usize,
    pub min_thermal_weight: f64,
}

/// The probe file's columns.
struct Probes {
    time: usize,
    probe: Option<usize>,
    pos: [usize; 3],
    err: [usize; 3],
}

/// Replays `probes` against `state` through `comp` (module docs).
pub fn replay(
    comp: &mut Compensator,
    state: &Table,
    probes: &Table,
) -> Result<(Vec<ReplaySample>, ReplaySummary), InputError> {
    let names: Vec<String> = comp.state_inputs().to_vec();
    let st_time = state.column("time_min")?;
    let st_cols: Vec<usize> = names
        .iter()
        .map(|n| state.column(n))
        .collect::<Result<_, _>>()?;
    let c = Probes {
        time: probes.column("time_min")?,
        probe: probes
            .has("probe")
            .then(|| probes.column("probe"))
            .transpose()?,
        pos: [
            probes.column("x_mm")?,
            probes.column("y_mm")?,
            probes.column("z_mm")?,
        ],
        err: [
            probes.column("ex_um")?,
            probes.column("ey_um")?,
            probes.column("ez_um")?,
        ],
    };
    let mut readings = vec![0.0; names.len()];
    let mut next = 0; // next state row to feed
    let mut last_t: Option<f64> = None;
    let mut status = StateStatus::default();
    let mut last_probe_t = f64::NEG_INFINITY;
    let mut samples = Vec::with_capacity(probes.rows.len());
    for row in &probes.rows {
        let t = probes.cell_f64(row, c.time)?;
        if t < last_probe_t {
            return Err(InputError::at(
                &probes.path,
                row.line,
                c.time + 1,
                format!(
                    "time goes back ({t} after {last_probe_t} min): rows must be in time order"
                ),
            ));
        }
        last_probe_t = t;
        // every reading the controller has by time t
        while next < state.rows.len() {
            let srow = &state.rows[next];
            let ts = state.cell_f64(srow, st_time)?;
            if ts > t {
                break;
            }
            let dt_min = match last_t {
                Some(p) if ts < p => {
                    return Err(InputError::at(
                        &state.path,
                        srow.line,
                        st_time + 1,
                        format!("time goes back ({ts} after {p} min): rows must be in time order"),
                    ))
                }
                Some(p) => ts - p,
                None => 0.0,
            };
            for (r, &col) in readings.iter_mut().zip(&st_cols) {
                *r = state.cell_f64(srow, col)?;
            }
            status = comp
                .update_state(&readings, dt_min * 60.0)
                .map_err(|e| InputError::line(&state.path, srow.line, e.to_string()))?;
            last_t = Some(ts);
            next += 1;
        }
        if last_t.is_none() && !names.is_empty() {
            return Err(InputError::at(
                &probes.path,
                row.line,
                c.time + 1,
                format!(
                    "this reading (time {t} min) comes before the first state reading: the \
                     model has no state yet"
                ),
            ));
        }
        let mut p = [0.0; 3];
        let mut e = [0.0; 3];
        for k in 0..3 {
            p[k] = probes.cell_f64(row, c.pos[k])?;
            e[k] = probes.cell_f64(row, c.err[k])?;
        }
        let corr = comp
            .correction_um(p)
            .map_err(|err| InputError::line(&probes.path, row.line, err.to_string()))?;
        samples.push(ReplaySample {
            time_min: t,
            probe: c.probe.map(|i| row.fields[i].clone()).unwrap_or_default(),
            position_mm: p,
            before_um: e,
            correction_um: corr,
            after_um: [e[0] + corr[0], e[1] + corr[1], e[2] + corr[2]],
            thermal_weight: status.thermal_weight,
            outside: status.outside.map(|j| names[j].clone()),
        });
    }
    if samples.is_empty() {
        return Err(InputError::file(&probes.path, "no probe readings"));
    }
    let summary = summarise(&samples, next);
    Ok((samples, summary))
}

fn summarise(s: &[ReplaySample], state_rows: usize) -> ReplaySummary {
    let comp = |k: usize, after: bool| -> Vec<f64> {
        s.iter()
            .map(|r| if after { r.after_um[k] } else { r.before_um[k] })
            .collect()
    };
    let norm = |v: &[f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let nb: Vec<f64> = s.iter().map(|r| norm(&r.before_um)).collect();
    let na: Vec<f64> = s.iter().map(|r| norm(&r.after_um)).collect();
    let worsening: Vec<f64> = na.iter().zip(&nb).map(|(a, b)| a - b).collect();
    ReplaySummary {
        readings: s.len(),
        state_rows,
        x: Reduction::of(&comp(0, false), &comp(0, true)),
        y: Reduction::of(&comp(1, false), &comp(1, true)),
        z: Reduction::of(&comp(2, false), &comp(2, true)),
        vector: Reduction::of(&nb, &na),
        worse: worsening.iter().filter(|&&w| w > 0.0).count(),
        largest_worsening_um: worsening.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        faded: s.iter().filter(|r| r.thermal_weight < 1.0).count(),
        min_thermal_weight: s.iter().map(|r| r.thermal_weight).fold(1.0, f64::min),
    }
}

/// The samples as CSV: `time_min,probe,x_mm,y_mm,z_mm,ex_um,ey_um,ez_um,cx_um,cy_um,cz_um,
/// ex_after_um,ey_after_um,ez_after_um,thermal_weight,outside`.
pub fn to_csv(samples: &[ReplaySample], provenance: &str) -> String {
    let mut w = mtec_io::CsvWriter::commented(
        [format!("mtec machine replay: {provenance}")],
        [
            "time_min",
            "probe",
            "x_mm",
            "y_mm",
            "z_mm",
            "ex_um",
            "ey_um",
            "ez_um",
            "cx_um",
            "cy_um",
            "cz_um",
            "ex_after_um",
            "ey_after_um",
            "ez_after_um",
            "thermal_weight",
            "outside",
        ],
    );
    for r in samples {
        let mut row = vec![r.time_min.to_string(), r.probe.to_string()];
        row.extend(r.position_mm.iter().map(|v| v.to_string()));
        let um = r
            .before_um
            .iter()
            .chain(&r.correction_um)
            .chain(&r.after_um);
        row.extend(um.chain([&r.thermal_weight]).map(|v| format!("{v:.4}")));
        row.push(r.outside.clone().unwrap_or_default());
        w.row(row);
    }
    w.finish()
}
