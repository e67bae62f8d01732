//! Line-set identification (the 9-line method and its relatives): the error elements of a
//! three-axis machine from laser-interferometer readings along straight lines.
//!
//! Pipeline: [`data`] reads the SPEC §4 line file and infers each line's geometry from its
//! points (the design is data); [`model`] parameterises the 21 error functions as polynomials
//! and builds the linear observation model from the first-order kinematics of `mtec-model`;
//! [`identifiability`] finds, by SVD of the column-scaled design, what the design cannot
//! determine and names it; [`solve`] fits the rest by least squares with covariance-based
//! uncertainties; [`report`] renders the result.
//!
//! # Decisions (where the spec is silent)
//! - The identification uses the linearised model (first-order Jacobian); the simulator uses the
//!   exact kinematics. Second-order terms of realistic errors (≤ 50 µrad) are below 0.01 µm.
//! - Conventions of the error functions: see [`model`]; they are the conventions of the
//!   virtual machine's truth, so that identified and true elements are comparable.
//! - Straightness channels carry a free alignment slope each: it is estimated and reported
//!   (`alignment`), never turned into squareness. Consequence: a straightness channel only
//!   informs the curvature (degree ≥ 2) of what it sees.
//! - Elements that the design cannot separate are dropped by the rule in [`identifiability`];
//!   their partners absorb them *at the measured tool offset*: the identified set predicts the
//!   volumetric error for that tool offset (e.g. `EXZ` then holds EXZ + L·EBZ).
//! - The element functions are written as polynomials in the axis position q (expanded from the
//!   normalised basis), zero at the travel's lower end.

pub mod basis;
pub mod data;
pub mod identifiability;
pub mod model;
pub mod report;
pub mod select;
pub mod solve;
pub mod spline;
pub mod validity;

pub use data::{Channel, ChannelKind, LineData};
pub use identifiability::{Analysis, Dropped};
pub use model::{Layout, ModelError};
pub use report::{ElementReport, LinesReport, SlopeReport, UnidentifiableReport};
pub use solve::Fit;

use mtec_io::InputError;
use mtec_model::{ErrorFunction, ErrorSet, Machine};
use nalgebra::{DMatrix, DVector};

/// Default degree of the error functions: chosen by cross-validation ([`select`]).
pub const DEFAULT_DEGREE: Degree = Degree::Auto;

/// The degree `auto` means for a design analysed without readings.
pub const AUTO_WITHOUT_READINGS: usize = 3;

/// How the polynomial degree of the error functions is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Degree {
    /// Per kind of element by cross-validation over the measured points ([`select`]).
    Auto,
    /// The same degree (2..=12) for every element.
    Fixed(usize),
    /// Per kind of element the better of the `Auto` degree and a smoothing spline whose
    /// penalty is chosen by the same cross-validation ([`select::Family::Hybrid`]).
    Smooth,
}

impl std::fmt::Display for Degree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Degree::Auto => f.write_str("auto"),
            Degree::Smooth => f.write_str("smooth"),
            Degree::Fixed(d) => write!(f, "{d}"),
        }
    }
}

impl std::str::FromStr for Degree {
    type Err = String;
    fn from_str(s: &str) -> Result<Degree, String> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Degree::Auto);
        }
        if s.eq_ignore_ascii_case("smooth") {
            return Ok(Degree::Smooth);
        }
        match s.parse::<usize>() {
            Ok(d) if (model::MIN_DEGREE..=model::MAX_DEGREE).contains(&d) => Ok(Degree::Fixed(d)),
            _ => Err(format!(
                "`{s}` is not a degree: give `auto` (chosen by cross-validation), `smooth` (smoothing splines where they cross-validate better) or a whole number from {} to {}",
                model::MIN_DEGREE,
                model::MAX_DEGREE
            )),
        }
    }
}

/// Why an identification cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinesError {
    /// A located problem with the data file.
    #[error("{0}")]
    Input(#[from] InputError),
    /// The machine or the options do not fit the method.
    #[error("{0}")]
    Model(#[from] ModelError),
    /// Not enough readings for the parameters.
    #[error("{readings} readings cannot determine {parameters} parameters: lower the polynomial degree or measure more points")]
    TooFewReadings { readings: usize, parameters: usize },
}

/// Everything an identification produces.
#[derive(Debug, Clone)]
pub struct LineIdentification {
    /// The identified error set (`mtec.errors/1`), dropped elements listed as unidentifiable.
    pub errors: ErrorSet,
    /// The report (identifiability, fit statistics, uncertainties).
    pub report: LinesReport,
    pub layout: Layout,
    pub analysis: Analysis,
    pub fit: Fit,
}

impl LineIdentification {
    /// Value and 1σ (µm or µrad) of an identified element at axis position q; None if dropped.
    pub fn value_sigma(&self, e: &mtec_model::ErrorElement, q: f64) -> Option<(f64, f64)> {
        if self.analysis.dropped.iter().any(|d| d.element == *e) {
            return None;
        }
        let b = self.layout.block(e)?;
        Some(self.fit.value_sigma(&self.analysis, b, q))
    }
}

/// Identifies the error elements of `machine` from line readings with polynomials of `degree`
/// (every element), with the pitch-error pairs of the axes whose `period_mm` is given.
pub fn identify(
    machine: &Machine,
    data: &LineData,
    degree: usize,
) -> Result<LineIdentification, LinesError> {
    identify_layout(
        machine,
        data,
        Layout::with_degrees(machine, data, &|_| degree, true)?,
    )
}

/// Identifies with the degree chosen as `degree` says (the CLI's `--degree auto|N`); the
/// selection, when made, is in the report.
pub fn identify_with(
    machine: &Machine,
    data: &LineData,
    degree: Degree,
) -> Result<LineIdentification, LinesError> {
    match degree {
        Degree::Fixed(d) => identify(machine, data, d),
        // a design without readings (`--design` alone) has nothing to cross-validate
        Degree::Auto | Degree::Smooth
            if data
                .channels
                .iter()
                .all(|c| c.readings_um.iter().all(|r| *r == 0.0)) =>
        {
            identify(machine, data, AUTO_WITHOUT_READINGS)
        }
        Degree::Auto => identify_auto(machine, data, false),
        Degree::Smooth => identify_family(machine, data, select::Family::Hybrid),
    }
}

/// Identifies with the bases chosen by cross-validation ([`select`]): Legendre degrees, and
/// with `splines` cubic splines with knots from the data as candidates too. The selection is in
/// the report.
pub fn identify_auto(
    machine: &Machine,
    data: &LineData,
    splines: bool,
) -> Result<LineIdentification, LinesError> {
    model::check_machine(machine)?;
    let family = if splines {
        select::Family::WithSplines
    } else {
        select::Family::Legendre
    };
    identify_family(machine, data, family)
}

/// Identifies with the bases of `family` chosen by cross-validation ([`select`]); the
/// selection is in the report.
pub fn identify_family(
    machine: &Machine,
    data: &LineData,
    family: select::Family,
) -> Result<LineIdentification, LinesError> {
    model::check_machine(machine)?;
    let sel = select::select_among(machine, data, true, family)?;
    let layout = Layout::with_bases(machine, data, &|e| sel.of(e), true)?;
    let mut id = identify_layout(machine, data, layout)?;
    id.report.selection = Some(sel);
    Ok(id)
}

/// Identifies with a given parameter layout.
pub fn identify_layout(
    machine: &Machine,
    data: &LineData,
    layout: Layout,
) -> Result<LineIdentification, LinesError> {
    let degree = layout.blocks.iter().map(|b| b.degree()).max().unwrap_or(0);
    model::check_travels(machine, data).map_err(|(ci, k, e)| match &data.path {
        Some(p) => LinesError::Input(InputError::at(
            p,
            data.channels[ci].file_lines[k],
            data.point_column,
            e.to_string(),
        )),
        None => LinesError::Model(e),
    })?;
    let (a, y) = model::design_matrix(machine, &layout, data);
    let too_few = |(readings, parameters)| LinesError::TooFewReadings {
        readings,
        parameters,
    };
    let smooth = layout.blocks.iter().any(|b| b.penalty.is_some());
    let m = y.len();
    // a smoothing spline: the design with its penalty rows (the elements the design cannot
    // identify are those of the polynomials: the penalty must not make a confounded element
    // look determined)
    let structural = if smooth {
        Some(structural_drops(
            machine,
            data,
            layout.blocks.iter().any(|b| b.period_mm.is_some()),
        )?)
    } else {
        None
    };
    let penalised_fit = |a: &DMatrix<f64>,
                         y: &DVector<f64>,
                         scale: f64,
                         dropped: Option<&[Dropped]>|
     -> Result<(Analysis, Fit), LinesError> {
        let (aa, ya) = model::penalised(a.clone(), y.clone(), &layout, scale);
        let mut an = identifiability::analyse_with(&aa, &ya, &layout, dropped).map_err(too_few)?;
        if dropped.is_some() {
            // the singular values of the kept (penalised) design, for its condition number
            let mut sv: Vec<f64> = an.kept_r.singular_values().iter().copied().collect();
            sv.sort_by(|a, b| b.total_cmp(a));
            an.kept_singular_values = sv.clone();
            an.singular_values = sv;
        }
        let mut fit = solve::solve(&aa, &ya, &an);
        // residuals and σ̂ of the readings (the penalty rows are no readings)
        fit.residual_um = y - a * &fit.theta;
        fit.dof = m.saturating_sub(an.active.len());
        fit.sigma_um = (fit.residual_um.norm_squared() / fit.dof.max(1) as f64).sqrt();
        Ok((an, fit))
    };
    // ordinary least squares first, then weighted by the noise each kind of optics shows
    let (analysis, fit) = match &structural {
        Some(d) => penalised_fit(&a, &y, 1.0, Some(d))?,
        None => {
            let analysis = identifiability::analyse(&a, &y, &layout).map_err(too_few)?;
            let fit = solve::solve(&a, &y, &analysis);
            (analysis, fit)
        }
    };
    let weights = kind_weights(data, &fit);
    let (analysis, fit) = match &weights {
        None => (analysis, fit),
        Some(w) => {
            let aw = DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] * w[i]);
            let yw = y.component_mul(w);
            if smooth {
                // the penalty weighted as the readings are on average, so that the λ chosen on
                // the unweighted readings keeps its balance against them
                let w_rms = (w.norm_squared() / m as f64).sqrt();
                let (an, mut fit) = penalised_fit(&aw, &yw, w_rms, Some(&analysis.dropped))?;
                fit.residual_um = &y - &a * &fit.theta;
                fit.sigma_um = (fit.residual_um.norm_squared() / fit.dof.max(1) as f64).sqrt();
                let errors = error_set(machine, data, degree, &layout, &an, &fit);
                let report = report::build(machine, data, degree, &layout, &an, &fit);
                return Ok(LineIdentification {
                    errors,
                    report,
                    layout,
                    analysis: an,
                    fit,
                });
            }
            let analysis_w =
                identifiability::analyse_with(&aw, &yw, &layout, Some(&analysis.dropped))
                    .map_err(too_few)?;
            // rank and singular values of the design itself (weights do not change the rank)
            let mut analysis_w = analysis_w;
            analysis_w.singular_values = analysis.singular_values.clone();
            analysis_w.kept_singular_values = analysis.kept_singular_values.clone();
            analysis_w.rank = analysis.rank;
            let analysis = analysis_w;
            let mut fit = solve::solve(&aw, &yw, &analysis);
            // report residuals in µm (unweighted); σ̂ is the weighted fit's scale (≈ 1)
            fit.residual_um = &y - &a * &fit.theta;
            fit.sigma_um = (fit.residual_um.norm_squared() / fit.dof.max(1) as f64).sqrt();
            (analysis, fit)
        }
    };
    let errors = error_set(machine, data, degree, &layout, &analysis, &fit);
    let report = report::build(machine, data, degree, &layout, &analysis, &fit);
    Ok(LineIdentification {
        errors,
        report,
        layout,
        analysis,
        fit,
    })
}

/// The elements the design cannot identify, from the rank of its degree-3 polynomial model
/// (with the pitch pairs when `pitch`): what a confounding of whole functions drops, for the
/// layouts whose penalty would hide it.
pub fn structural_drops(
    machine: &Machine,
    data: &LineData,
    pitch: bool,
) -> Result<Vec<Dropped>, ModelError> {
    let layout = Layout::with_degrees(machine, data, &|_| 3, pitch)?;
    let (a, y) = model::design_matrix(machine, &layout, data);
    Ok(identifiability::analyse(&a, &y, &layout)
        .map(|an| an.dropped)
        .unwrap_or_default())
}

/// Row weights 1/σ_kind from the residuals of a first fit: displacement optics and straightness
/// optics have different noise (a laser's straightness reading is typically 1.5–2× noisier), so
/// the weighted least-squares estimate (Aitken / Gauss–Markov) needs the ratio. Each kind's
/// variance is its residual sum of squares over its share of the degrees of freedom.
/// None when only one kind is present.
fn kind_weights(data: &LineData, fit: &Fit) -> Option<DVector<f64>> {
    let m = fit.residual_um.len();
    let mut ss = [0.0f64; 2];
    let mut n = [0usize; 2];
    let mut kinds = Vec::with_capacity(m);
    let mut row = 0;
    for c in &data.channels {
        let k = (c.kind == ChannelKind::Straightness) as usize;
        for _ in 0..c.readings_um.len() {
            ss[k] += fit.residual_um[row].powi(2);
            n[k] += 1;
            kinds.push(k);
            row += 1;
        }
    }
    if n[0] == 0 || n[1] == 0 || fit.dof == 0 {
        return None;
    }
    let share = fit.dof as f64 / m as f64;
    let var = [0, 1].map(|k| ss[k] / (n[k] as f64 * share));
    if !(var[0] > 0.0 && var[1] > 0.0) {
        return None;
    }
    Some(DVector::from_iterator(
        m,
        kinds.into_iter().map(|k| 1.0 / var[k].sqrt()),
    ))
}

/// The identified functions as an error set.
fn error_set(
    machine: &Machine,
    data: &LineData,
    degree: usize,
    layout: &Layout,
    an: &Analysis,
    fit: &Fit,
) -> ErrorSet {
    let mut set = ErrorSet::new(format!(
        "mtec identify lines: {} ({} lines, degree {degree}); valid at tool offset {:?} mm",
        data.source,
        data.line_names().len(),
        machine.tool_offset_mm
    ));
    for b in &layout.blocks {
        if an.dropped.iter().any(|d| d.element == b.element) {
            continue;
        }
        let theta: Vec<f64> = b.cols().map(|c| fit.theta[c]).collect();
        let f = if b.kind == model::ElementKind::Squareness {
            ErrorFunction::constant(theta[0])
        } else if b.period_mm.is_some() || b.spline.is_some() {
            sampled_table(b, &theta)
        } else {
            let coeffs = b.power_terms(&theta);
            ErrorFunction::polynomial(solve::polynomial_in_q(&coeffs, b.travel))
        };
        set.insert(b.element, f);
    }
    set.unidentifiable = an.dropped.iter().map(|d| d.element.name()).collect();
    set
}

/// A function with a pitch-error pair or a spline as a table every P/20 (at most 1 mm): every
/// consumer of an error set (compensation tables, G-code, the real-time library) evaluates
/// tables already; linear interpolation of a sinusoid at P/20 is within 1.2 % of its amplitude
/// ((π/20)²/2), and of a cubic spline whose knots are ≥ 10 mm apart at 1 mm within h²/8·|f''|.
fn sampled_table(b: &model::Block, theta: &[f64]) -> ErrorFunction {
    let [lo, hi] = b.travel;
    let step = b.period_mm.map_or(1.0, |p| p / 20.0).min(1.0);
    let n = ((hi - lo) / step).ceil().max(1.0) as usize;
    let positions: Vec<f64> = (0..=n)
        .map(|i| lo + (hi - lo) * i as f64 / n as f64)
        .collect();
    let values = positions
        .iter()
        .map(|&q| b.basis(q).zip(theta).map(|(v, c)| v * c).sum())
        .collect();
    ErrorFunction::table(positions, values)
}

/// What a design can identify, without readings (rank, singular values, unidentifiable elements).
pub fn analyse_design(
    machine: &Machine,
    data: &LineData,
    degree: usize,
) -> Result<LinesReport, LinesError> {
    identify(machine, data, degree).map(|id| id.report)
}

/// Checks that the data contain every line and channel of a design (e.g. a preset), by geometry:
/// same name, same direction, same reading directions. Returns the first mismatch.
pub fn check_design(data: &LineData, design: &[mtec_model::LineSpec]) -> Result<(), String> {
    for l in design {
        let chans: Vec<&Channel> = data.channels.iter().filter(|c| c.line == l.name).collect();
        if chans.is_empty() {
            return Err(format!(
                "the design has line `{}` but the data do not",
                l.name
            ));
        }
        let d = l.direction();
        if data::dot(d, chans[0].direction).abs() < 0.999 {
            return Err(format!(
                "line `{}` runs along {:?} in the data but along {:?} in the design",
                l.name, chans[0].direction, d
            ));
        }
        for u in &l.channels {
            if !chans.iter().any(|c| data::dot(c.u, *u) > 0.999) {
                return Err(format!(
                    "line `{}` has no channel reading along {:?}, which the design measures",
                    l.name, u
                ));
            }
        }
    }
    Ok(())
}
