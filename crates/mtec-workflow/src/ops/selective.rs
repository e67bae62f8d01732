//! Selective compensation (issue 19): compensate only some error elements of a kinematic model,
//! the key ones by default as the literature does (the elements a global sensitivity analysis
//! ranks first), and say what that costs.
//!
//! - `all`: the model as it is (the model file is loaded exactly as without the option);
//! - `key`: EFAST ([`mtec_sensitivity::efast`], 1200 points per curve, M = 4, seed 1) of Ex, Ey,
//!   Ez over a 4 × 4 × 4 grid of the travels, the inputs being the model's own error functions
//!   as statistics over their travels ([`ErrorStatistics::of_identified`], what `identify lines
//!   --stats` writes) taken with mean 0 and their RMS √(mean² + std²) as spread, so that S1 is
//!   an element's share of the mean square of E, which the compensation rate measures; the key elements are, for each of Ex, Ey, Ez, the fewest in the order of
//!   their first-order index S1 whose S1 add up to [`KEY_SHARE`] of the sum of all S1, and
//!   together the union of the three (listed in the order of S1 of |E|);
//! - a list of element names (`EXX,EYY,EC0Y`): those; a name the model does not have is refused.
//!
//! The rates: at the same grid, the machine is taken to have the model's errors with *all*
//! elements; the commanded point for each target is computed from the selected elements
//! (`mtec_comp::command_for_target`), and the rate is 1 − RMS(landed − target)/RMS(E) per axis
//! (the compensation rate of SPEC §1 C). With all elements it is 100 % by construction, so the
//! loss is 100 % minus the selected rate; against a real machine both are lower, and
//! `tests/selective.rs` measures them against the simulator's truth.

use crate::{Error, Result};
use mtec_comp::kinematic::{KinematicFile, KinematicModel, KINEMATIC_FORMAT};
use mtec_comp::{command_for_target, CorrectionOptions, ErrorModel};
use mtec_io::InputError;
use mtec_model::{ErrorElement, ErrorSet, Formalism, Machine, Order, VolumetricModel};
use mtec_sensitivity::efast::EfastSettings;
use mtec_sensitivity::error_model::{self, ErrorModelProblem, ErrorStatistics, Method};
use serde::Serialize;
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// Share of the sum of the first-order indices of each of Ex, Ey, Ez the key elements carry:
/// what they leave, 1 − share of the variance, is a residual of √(1 − share) = 10 % of the
/// error's spread, a compensation rate near 90 % (docs/methods.md).
pub const KEY_SHARE: f64 = 0.99;
/// Grid points per axis of the key ranking and of the rates.
const GRID: usize = 4;

/// (element, S1 of |E|), largest first.
pub type Ranking = Vec<(String, f64)>;

/// Which elements to compensate (`--elements`).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum Elements {
    #[default]
    All,
    Key,
    List(Vec<String>),
}

impl FromStr for Elements {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.trim() {
            "all" => Ok(Elements::All),
            "key" => Ok(Elements::Key),
            "" => Err("--elements: give key, all or a list of element names (EXX,EYY,...)".into()),
            list => Ok(Elements::List(
                list.split(',').map(|n| n.trim().to_string()).collect(),
            )),
        }
    }
}

/// What a selective compensation compensates and what it costs.
#[derive(Debug, Clone, Serialize)]
pub struct Selective {
    /// `key` or `list`.
    pub selection: String,
    /// The elements compensated, in the order of the file (key: of their rank).
    pub elements: Vec<String>,
    /// The model's elements not compensated.
    pub left_out: Vec<String>,
    /// Key only: (element, S1 of |E|) of every element, largest first.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ranking: Ranking,
    /// Compensation rate per axis (X, Y, Z), %, with all elements and with the selected ones.
    pub rate_all_pct: [f64; 3],
    pub rate_selected_pct: [f64; 3],
    /// rate_all − rate_selected per axis, percentage points.
    pub loss_pct: [f64; 3],
}

impl fmt::Display for Selective {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "selective compensation ({}): {} of {} elements: {}",
            self.selection,
            self.elements.len(),
            self.elements.len() + self.left_out.len(),
            self.elements.join(", ")
        )?;
        let p = |v: [f64; 3]| format!("X {:.1} %, Y {:.1} %, Z {:.1} %", v[0], v[1], v[2]);
        writeln!(
            f,
            "  compensation rate over the travels against the model: all elements {}; these {}; loss {:.1}/{:.1}/{:.1} points",
            p(self.rate_all_pct),
            p(self.rate_selected_pct),
            self.loss_pct[0],
            self.loss_pct[1],
            self.loss_pct[2]
        )
    }
}

/// Loads the model of `path` with only the selected elements: with [`Elements::All`] exactly
/// `mtec_comp::load_error_model`; otherwise the file must be a kinematic model.
pub fn load(path: &Path, elements: &Elements) -> Result<(Box<dyn ErrorModel>, Option<Selective>)> {
    if *elements == Elements::All {
        return Ok((mtec_comp::load_error_model(path)?, None));
    }
    let text = mtec_io::read_text(path)?;
    let file: KinematicFile = match serde_json::from_str::<KinematicFile>(&text) {
        Ok(f) if f.format == KINEMATIC_FORMAT => f,
        _ => {
            return Err(Error::usage(format!(
                "--elements key|LIST needs a kinematic model ({KINEMATIC_FORMAT}, what `identify lines --kinematic-model` writes); {} is not one (use --elements all)",
                path.display()
            )))
        }
    };
    let machine = Machine::from_spec(file.machine.clone())
        .map_err(|e| InputError::file(path, e.to_string()))?;
    if machine.axes.iter().map(|a| a.letter()).collect::<String>() != "XYZ" {
        return Err(Error::usage(format!(
            "--elements key|LIST is for machines with the linear axes X, Y, Z ({} has {:?})",
            path.display(),
            machine.axes
        )));
    }
    let full = file.errors;
    let (selection, chosen, ranking) = match elements {
        Elements::All => unreachable!("returned above"),
        Elements::Key => {
            let (key, ranking) =
                key_elements(&machine, &full).map_err(|e| InputError::file(path, e))?;
            ("key", key, ranking)
        }
        Elements::List(names) => {
            let mut chosen = Vec::new();
            for n in names {
                let e = ErrorElement::parse(n)
                    .ok()
                    .filter(|e| full.elements.contains_key(e))
                    .ok_or_else(|| {
                        Error::usage(format!(
                            "--elements: {} has no element `{n}`; it has {}",
                            path.display(),
                            full.elements
                                .keys()
                                .map(|e| e.name())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ))
                    })?;
                if !chosen.contains(&e) {
                    chosen.push(e);
                }
            }
            ("list", chosen, Vec::new())
        }
    };
    let mut part = full.clone();
    part.elements.retain(|e, _| chosen.contains(e));
    let model = KinematicModel::new(&machine, &part, path.display().to_string())
        .map_err(|e| InputError::file(path, e))?;
    let (rate_all, rate_sel) =
        rates(&machine, &full, &part).map_err(|e| InputError::file(path, e))?;
    let sel = Selective {
        selection: selection.into(),
        elements: chosen.iter().map(|e| e.name()).collect(),
        left_out: full
            .elements
            .keys()
            .filter(|e| !chosen.contains(e))
            .map(|e| e.name())
            .collect(),
        ranking,
        rate_all_pct: rate_all.map(|r| 100.0 * r),
        rate_selected_pct: rate_sel.map(|r| 100.0 * r),
        loss_pct: [0, 1, 2].map(|i| 100.0 * (rate_all[i] - rate_sel[i])),
    };
    Ok((Box::new(model), Some(sel)))
}

/// The grid of poses over the travels of the linear axes (rotary axes at 0).
fn grid(machine: &Machine) -> Vec<Vec<f64>> {
    let mut poses = vec![Vec::new()];
    for a in &machine.axes {
        let [lo, hi] = machine.travel(*a);
        let values: Vec<f64> = if a.is_rotary() {
            vec![0.0]
        } else {
            (0..GRID)
                .map(|k| lo + (hi - lo) * k as f64 / (GRID - 1) as f64)
                .collect()
        };
        poses = poses
            .into_iter()
            .flat_map(|p| {
                values.iter().map(move |v| {
                    let mut q = p.clone();
                    q.push(*v);
                    q
                })
            })
            .collect();
    }
    poses
}

/// The key elements (see the module docs) and the ranking by S1 of |E|.
pub fn key_elements(
    machine: &Machine,
    set: &ErrorSet,
) -> std::result::Result<(Vec<ErrorElement>, Ranking), String> {
    // inputs of mean 0 and the RMS over the travel as spread: S1 is then each element's share
    // of the mean square of E that the compensation rate measures, not only of its variance
    let mut stats = ErrorStatistics::of_identified(set, machine);
    for e in &mut stats.elements {
        e.std = e.mean.hypot(e.std);
        e.mean = 0.0;
    }
    let emp = ErrorModelProblem::new(machine, &stats, &grid(machine)).map_err(|e| e.to_string())?;
    // one design: the ranking needs the estimates, not their intervals
    let method = Method::Efast(EfastSettings {
        n: 1200,
        resamples: 1,
        ..EfastSettings::default()
    });
    let report = error_model::analyze(&emp, &method, 1, 25.0, 2.0).map_err(|e| e.to_string())?;
    let names = &emp.problem.names;
    let mut key: Vec<String> = Vec::new();
    // per axis Ex, Ey, Ez: the fewest elements, largest S1 first, that carry KEY_SHARE of ΣS1
    for out in report.outputs.iter().take(3) {
        let Some(s1) = &out.s1 else { continue };
        let mut order: Vec<usize> = (0..names.len()).collect();
        order.sort_by(|a, b| s1[*b].total_cmp(&s1[*a]));
        let total: f64 = s1.iter().map(|v| v.max(0.0)).sum();
        let mut sum = 0.0;
        for i in order {
            if sum >= KEY_SHARE * total {
                break;
            }
            sum += s1[i].max(0.0);
            if !key.contains(&names[i]) {
                key.push(names[i].clone());
            }
        }
    }
    let ranking: Ranking = report
        .key_errors
        .iter()
        .map(|r| (r.element.clone(), r.value))
        .collect();
    // in the order of the ranking of |E|
    let mut ordered: Vec<ErrorElement> = Vec::new();
    for (n, _) in &ranking {
        if key.contains(n) {
            ordered.push(ErrorElement::parse(n).map_err(|e| e.to_string())?);
        }
    }
    Ok((ordered, ranking))
}

/// Compensation rates per axis on the grid, the machine's errors being `full`'s: commanded
/// from `full` and from `part`.
pub fn rates(
    machine: &Machine,
    full: &ErrorSet,
    part: &ErrorSet,
) -> std::result::Result<([f64; 3], [f64; 3]), String> {
    Ok((rate(machine, full, full)?, rate(machine, full, part)?))
}

/// The compensation rate per axis on the grid of a machine whose errors are `truth`'s, commanded
/// from the model with the error set `compensated`: 1 − RMS(landed − target)/RMS(E(target)).
pub fn rate(
    machine: &Machine,
    truth: &ErrorSet,
    compensated: &ErrorSet,
) -> std::result::Result<[f64; 3], String> {
    let truth = VolumetricModel::new(machine, truth);
    let model = KinematicModel::new(machine, compensated, "")?;
    let (mut before, mut after) = ([0.0; 3], [0.0; 3]);
    for q in grid(machine) {
        let t = [q[0], q[1], q[2]];
        let e = truth.error(&q, Formalism::Htm, Order::Exact).position_um;
        let p = command_for_target(&model, t, &CorrectionOptions::default())
            .map_err(|e| e.to_string())?;
        let e1 = truth.error(&p, Formalism::Htm, Order::Exact).position_um;
        for i in 0..3 {
            before[i] += e[i] * e[i];
            after[i] += ((p[i] - t[i]) * 1e3 + e1[i]).powi(2);
        }
    }
    Ok([0, 1, 2].map(|i| {
        if before[i] > 0.0 {
            1.0 - (after[i] / before[i]).sqrt()
        } else {
            1.0
        }
    }))
}
