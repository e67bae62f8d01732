//! Thermal compensation for controllers without a real-time hook: the model's drift *now*,
//! written as part-program lines a shop runs at each tool change — a work-offset update
//! (LinuxCNC `G10 L2`, FANUC `G10 L2` or `#52xx`, Siemens `$P_UIFR` fine offset) or the Siemens
//! temperature-compensation setting data (SD43900/SD43910/SD43920).
//!
//! Method (mtec's error convention: the tool reaches commanded + e):
//! 1. The thermal model runs over the temperature log up to now ([`run_log`], the same
//!    [`crate::MachineErrorModel`] the real-time library uses): e(x) = k·x + b (µm) along the
//!    axis at the last row, with the envelope weight w of that row.
//! 2. Work offset: with offset O (the machine coordinate of the program zero along the axis) a
//!    programmed w is commanded at M = w + O and reached at M + e. The offset O₀ that is right
//!    when e = 0 gives the part's zero at w + O₀, so M + e = w + O₀ needs O = O₀ − e: the
//!    update is c = −e (µm). A predicted drift of +12 µm moves the offset, and with it the tool
//!    relative to the part, by −12 µm. An offset set (touched off, probed) at log time t_z
//!    absorbed the drift then, O_z = O₀ − e(t_z), so relative to it the update is
//!    c = −(e(now) − e(t_z)) (`zeroed_at_min`).
//! 3. Siemens temperature compensation: the control computes ΔK_x = K₀ + tanβ·(P_x − P₀)
//!    itself (SINUMERIK 840D sl Function Manual Extended Functions, K3, 6FC5397-1BP40-3BA1,
//!    03/2013, p. 225); mtec writes the model's error line: K₀ = b (mm) at P₀ = the machine
//!    position of the model's x = 0, tanβ = k (mm/mm). See [`sinumerik`] for units and sign.
//! 4. Envelope: an input outside its training range makes w < 1 (`crate::machine`). The
//!    update is then refused unless the caller accepts the documented safe fallback, the fade:
//!    c = −w·(e(now) − e(t_z)), which reaches "no update" (the offset stays as the shop set
//!    it; no temperature compensation for the setting data) at w = 0. The zeroing moment must
//!    itself be inside the envelope.
//! 5. Bound: |c| (for the setting data: |ΔK| at both ends of the axis travel) must not exceed
//!    `max_correction_um` ([`crate::table::DEFAULT_MAX_CORRECTION_UM`] unless told), the rule
//!    of the tables and of `compensate gcode`: a 10 mm "thermal drift" is a model in the wrong
//!    units or a broken fit, never an offset to give a machine.
//!
//! History: a model's state at now depends on the log before it. Lag filters and exp-ambient's
//! temperature rises start at the first row of the log, as if the machine were at rest in
//! equilibrium with the room there (as in training). A log that does not start at rest is
//! accepted only when it spans [`HISTORY_TAUS`] slowest time constants (the start is then
//! forgotten to e^(−5) < 1 %); exp-ambient's rises never forget their start, so its log must
//! start at rest (`starts_at_rest`).

pub mod fanuc;
pub mod linuxcnc;
mod run;
pub mod sinumerik;
mod source;

pub use run::{run_log, DriftLine, LogRun, Moment, Outside, RunOptions, HISTORY_TAUS};
pub use source::{History, LoadOptions, OffsetModel};

use crate::table::Axis;
use mtec_io::{InputError, Table};

/// Why an update cannot be written.
#[derive(Debug, Clone, PartialEq)]
pub enum OffsetError {
    /// An input file is wrong (located).
    Input(InputError),
    /// The options do not fit the model or each other.
    Usage(String),
}

impl From<InputError> for OffsetError {
    fn from(e: InputError) -> Self {
        OffsetError::Input(e)
    }
}

impl std::fmt::Display for OffsetError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OffsetError::Input(e) => write!(f, "{e}"),
            OffsetError::Usage(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for OffsetError {}

/// What to do when an input is outside its training range now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutsidePolicy {
    /// Refuse (exit 2): the default.
    Refuse,
    /// Scale the update by the envelope weight (module docs, 4).
    Fade,
}

/// Options shared by both kinds of output.
#[derive(Debug, Clone, Copy)]
pub struct UpdateOptions {
    /// Machine coordinate (mm) of the model's position x = 0 along the axis.
    pub origin_mm: f64,
    pub outside: OutsidePolicy,
    /// Largest |correction| (µm).
    pub max_correction_um: f64,
}

/// A work-offset update along one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetUpdate {
    pub axis: Axis,
    /// Machine position (mm) the drift was evaluated at (the model's x = at − origin).
    pub at_mm: f64,
    /// e(now) − e(t_z) (µm, before the envelope weight).
    pub drift_um: f64,
    /// w.
    pub weight: f64,
    /// c = −w·drift (µm): the change of the offset relative to the one set at t_z (or right
    /// with no drift).
    pub correction_um: f64,
    /// The drift depends on the position (`at_mm` matters).
    pub position_dependent: bool,
}

/// Siemens temperature-compensation setting data of one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct TempCompSetting {
    pub axis: Axis,
    /// SD43900 K₀ (mm).
    pub k0_mm: f64,
    /// SD43910 tanβ (mm/mm).
    pub tan_beta: f64,
    /// SD43920 P₀ (mm, machine coordinate).
    pub p0_mm: f64,
    /// w.
    pub weight: f64,
    /// The model's drift depends on the position (MD32750 needs bit 1 as well as bit 0).
    pub position_dependent: bool,
}

fn check_options(o: &UpdateOptions) -> Result<(), OffsetError> {
    use mtec_io::plausible::{position_option, positive_option, MAX_CORRECTION_LIMIT_UM};
    positive_option(
        "--max-correction-um",
        o.max_correction_um,
        MAX_CORRECTION_LIMIT_UM,
        "um",
    )
    .map_err(OffsetError::Usage)?;
    position_option("--position-origin-mm", o.origin_mm).map_err(OffsetError::Usage)?;
    Ok(())
}

/// The located refusal of a reading outside the envelope (or `Ok` under the fade policy).
fn check_envelope(
    m: &Moment,
    log: &Table,
    policy: OutsidePolicy,
    what: &str,
) -> Result<(), OffsetError> {
    let Some(o) = &m.outside else { return Ok(()) };
    if policy == OutsidePolicy::Fade {
        return Ok(());
    }
    let msg = format!(
        "{what}: `{}` = {} is outside the model's training range [{}, {}]; the model would extrapolate. Give --outside fade to accept the safe fallback (the update scaled by the envelope weight, here {:.3}, down to no update at 0: docs/methods.md)",
        o.input, o.value, o.range[0], o.range[1], m.weight
    );
    Err(match log.column(&o.input) {
        Ok(c) => InputError::at(&log.path, m.line, c + 1, msg),
        Err(_) => InputError::line(&log.path, m.line, msg),
    }
    .into())
}

/// The work-offset update now at machine position `at_mm` (`None`: the drift must not depend
/// on the position) — module docs, 2, 4, 5.
pub fn offset_update(
    run: &LogRun,
    log: &Table,
    axis: Axis,
    at_mm: Option<f64>,
    opts: UpdateOptions,
) -> Result<OffsetUpdate, OffsetError> {
    check_options(&opts)?;
    check_envelope(&run.now, log, opts.outside, "the state now")?;
    if let Some(z) = &run.zeroed {
        check_envelope(
            z,
            log,
            OutsidePolicy::Refuse,
            "the moment the offset was set (--zeroed-at-min)",
        )?;
    }
    let at_mm = match at_mm {
        Some(a) => mtec_io::plausible::position_option("--at-mm", a).map_err(OffsetError::Usage)?,
        None if run.position_dependent => {
            return Err(OffsetError::Usage(format!(
                "the model's {} drift depends on the axis position (k = {:.6} um/mm now): give --at-mm, the machine position the offset is used at (e.g. the height of the machined face)",
                axis.letter(),
                run.now.drift.k_um_per_mm
            )))
        }
        None => opts.origin_mm,
    };
    let x = at_mm - opts.origin_mm;
    // e(now) − e(t_z)  (module docs, 2)
    let drift_um = run.now.drift.at(x) - run.zeroed.as_ref().map_or(0.0, |z| z.drift.at(x));
    let weight = run.now.weight;
    // c = −w·(e(now) − e(t_z))  (module docs, 2 and 4)
    let correction_um = -weight * drift_um;
    if !(correction_um.is_finite() && correction_um.abs() <= opts.max_correction_um) {
        return Err(InputError::line(
            &log.path,
            run.now.line,
            format!(
                "the {} offset update here would be {correction_um:.3} um: more than --max-correction-um {} um (a model in the wrong units or a broken fit?)",
                axis.letter(),
                opts.max_correction_um
            ),
        )
        .into());
    }
    Ok(OffsetUpdate {
        axis,
        at_mm,
        drift_um,
        weight,
        correction_um,
        position_dependent: run.position_dependent,
    })
}

/// Options of [`temp_comp_setting`].
#[derive(Debug, Clone, Copy)]
pub struct SettingOptions {
    pub update: UpdateOptions,
    /// The axis travel [from, to] (machine coordinates, mm): the bound is checked at both ends.
    /// Required when the drift depends on the position.
    pub travel_mm: Option<[f64; 2]>,
    /// MD32760 $MA_COMP_ADD_VELO_FACTOR, the largest |tanβ| (see [`sinumerik`]).
    pub max_slope: f64,
}

/// The Siemens temperature-compensation setting data now (module docs, 3, 4, 5).
pub fn temp_comp_setting(
    run: &LogRun,
    log: &Table,
    axis: Axis,
    opts: SettingOptions,
) -> Result<TempCompSetting, OffsetError> {
    check_options(&opts.update)?;
    if run.zeroed.is_some() {
        return Err(OffsetError::Usage(
            "--zeroed-at-min goes with work-offset updates: the temperature compensation corrects the axis against the model's reference state itself (set work offsets with it active)".into(),
        ));
    }
    check_envelope(&run.now, log, opts.update.outside, "the state now")?;
    let w = run.now.weight;
    let line = run.now.drift;
    // ΔK(P) = K₀ + tanβ·(P − P₀) = w·(b + k·(P − origin)): K₀ = w·b, tanβ = w·k, P₀ = origin
    let setting = TempCompSetting {
        axis,
        k0_mm: w * line.b_um * 1e-3,
        tan_beta: w * line.k_um_per_mm * 1e-3,
        p0_mm: opts.update.origin_mm,
        weight: w,
        position_dependent: run.position_dependent,
    };
    let ends: Vec<f64> = match opts.travel_mm {
        Some([a, b]) if a < b => {
            for end in [a, b] {
                mtec_io::plausible::position_option("--travel-mm", end)
                    .map_err(OffsetError::Usage)?;
            }
            vec![a, b]
        }
        Some([a, b]) => {
            return Err(OffsetError::Usage(format!(
                "--travel-mm {a}:{b}: expected FROM:TO with FROM < TO"
            )))
        }
        None if run.position_dependent => {
            return Err(OffsetError::Usage(format!(
                "the model's {} drift depends on the axis position (k = {:.6} um/mm now): give --travel-mm FROM:TO, the axis travel, so the compensation can be bounded over it",
                axis.letter(),
                line.k_um_per_mm
            )))
        }
        None => vec![opts.update.origin_mm],
    };
    for p in ends {
        let c_um = w * line.at(p - opts.update.origin_mm);
        if !(c_um.is_finite() && c_um.abs() <= opts.update.max_correction_um) {
            return Err(InputError::line(
                &log.path,
                run.now.line,
                format!(
                    "the {} temperature compensation at {p} mm would be {c_um:.3} um: more than --max-correction-um {} um (a model in the wrong units or a broken fit?)",
                    axis.letter(),
                    opts.update.max_correction_um
                ),
            )
            .into());
        }
    }
    if !(opts.max_slope.is_finite() && opts.max_slope > 0.0) {
        return Err(OffsetError::Usage(format!(
            "--comp-add-velo-factor must be a positive number, not {}",
            opts.max_slope
        )));
    }
    if setting.tan_beta.abs() > opts.max_slope {
        return Err(InputError::line(
            &log.path,
            run.now.line,
            format!(
                "the slope tan(beta) = {:.3e} exceeds MD32760 $MA_COMP_ADD_VELO_FACTOR = {}, which limits it on the control",
                setting.tan_beta, opts.max_slope
            ),
        )
        .into());
    }
    Ok(setting)
}

/// Provenance comment lines (plain ASCII, no parentheses: they go inside G-code comments).
pub fn provenance(run: &LogRun, log: &Table, source: &str) -> Vec<String> {
    let file = log
        .path
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let model = std::path::Path::new(source)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut out = vec![
        format!("mtec compensate thermal-offset, model {model}"),
        format!(
            "state now: {file} line {} at {} min, run from line {} at {} min{}",
            run.now.line,
            run.now.time_min,
            run.first_line,
            run.first_time_min,
            match (run.history, run.starts_at_rest) {
                (History::None, _) => "",
                (_, true) => ", state started there at rest",
                (_, false) => ", over 5 slowest time constants",
            }
        ),
    ];
    if let Some(o) = &run.now.outside {
        out.push(format!(
            "{} = {} outside training range {} to {}: thermal part faded to weight {:.3}",
            o.input, o.value, o.range[0], o.range[1], run.now.weight
        ));
    }
    out
}

/// Text safe inside a G-code comment of any of the controllers: printable ASCII without
/// parentheses (they would end a `( )` comment) and without `;`.
pub fn comment_text(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_graphic() && !"();".contains(c) || c == ' ' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// `+12.000` style (sign always shown) for comments.
fn signed(v: f64, decimals: usize) -> String {
    let s = format!("{v:+.decimals$}");
    // no "-0.000"
    if s.trim_start_matches(['+', '-'])
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        format!("+{}", &s[1..])
    } else {
        s
    }
}

/// The comment line that states the update and its sign (module docs, 2).
fn update_line(u: &OffsetUpdate) -> String {
    let at = if u.position_dependent {
        format!(
            " at {} = {} mm",
            u.axis.letter(),
            crate::table::trim_number(u.at_mm, 4)
        )
    } else {
        String::new()
    };
    format!(
        "{} thermal drift {} um{at}, envelope weight {}: the offset moves {} um",
        u.axis.letter(),
        signed(u.drift_um, 2),
        crate::table::trim_number(u.weight, 3),
        signed(u.correction_um, 2)
    )
}
