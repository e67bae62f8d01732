//! The knobs of a rewrite ([`RewriteOptions`]) and the words they are given in: what to do
//! with an unsupported construct, the block-delete switch, the program's units, the rounding
//! of a written position. A leaf: it uses no other module of the rewriter.

use super::super::offsets::Offsets;

/// What to do with a construct that cannot be compensated safely.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OnUnsupported {
    /// Stop with an error naming the line and column (the default).
    #[default]
    Refuse,
    /// Copy the line unchanged, record a warning, and stop compensating whatever the construct
    /// may have changed (positions, modes) until the program sets it again explicitly.
    PassThroughWithWarning,
}

/// The operator's block-delete switch (`--block-delete`): what a block starting with `/` does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BlockDelete {
    /// Not given: a `/` block that moves or changes a mode is unsupported (whether it runs
    /// depends on the switch).
    #[default]
    Unknown,
    /// Switch on: the controller skips `/` blocks; they are copied and not interpreted.
    On,
    /// Switch off: `/` blocks run like any other block.
    Off,
}

/// Length units of the program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Units {
    Mm,
    Inch,
}

impl Units {
    pub(super) fn mm_per_unit(self) -> f64 {
        match self {
            Units::Mm => 1.0,
            Units::Inch => 25.4,
        }
    }
}

/// Largest `--tolerance-um` and `--chord-tolerance-um` (µm): a path allowed to leave the
/// compensated one by a millimetre is no compensation of µm errors.
pub const MAX_TOLERANCE_UM: f64 = 1000.0;

/// Range of `--check-step-mm` and `--check-step-deg` (mm or deg): finer than a µm the dense
/// path check samples a real program for hours; coarser than 10 it samples past the features
/// of any error model (the default is 0.5).
pub const MIN_CHECK_STEP: f64 = 1e-3;
pub const MAX_CHECK_STEP: f64 = 10.0;

/// The knobs of the rewriter (every one has a CLI flag of the same name).
#[derive(Debug, Clone)]
pub struct RewriteOptions {
    /// Largest change of the correction along one output piece, µm (`--tolerance-um`).
    pub tolerance_um: f64,
    /// Longest output piece of a compensated feed move, mm (`--max-segment-mm`).
    pub max_segment_mm: f64,
    /// Largest sagitta of a chord when an arc is linearised, µm (`--chord-tolerance-um`).
    pub chord_tolerance_um: f64,
    /// Corrections larger than this are refused, µm (`--max-correction-um`).
    pub max_correction_um: f64,
    pub on_unsupported: OnUnsupported,
    /// Digits after the point of rewritten words in mm and in inch programs.
    pub decimals_mm: usize,
    pub decimals_inch: usize,
    /// Units in effect before the program's first G20/G21 (the controller's power-on default).
    pub default_units: Units,
    pub offsets: Offsets,
    /// A single move split into more pieces than this is an error (a runaway model).
    pub max_pieces_per_move: usize,
    /// Machine position (mm) at program start, when known (e.g. the home position; on a lathe
    /// the Y position that programs never state). `None`: unknown until programmed.
    pub start_position_mm: Option<[f64; 3]>,
    /// Sample spacing (mm) of the dense path check for models that are not grid maps
    /// (`--check-step-mm`); grid maps are bounded exactly (see [`super::bound`]).
    pub check_step_mm: f64,
    /// Longest line the target controller reads (`--max-line-chars`; LinuxCNC: 251). A
    /// rewritten or added line longer than this is refused; the header comment is shortened.
    pub max_line_chars: usize,
    /// The operator's block-delete switch (`--block-delete on|off`).
    pub block_delete: BlockDelete,
    /// Machine angles (deg) of the rotary axes A, B, C at program start, when known
    /// (`--start-rotary-deg`). `None`: unknown until programmed.
    pub start_rotary_deg: Option<[f64; 3]>,
    /// Largest turn (deg) of any rotary axis between two samples of the dense path check of a
    /// move that turns a rotary axis (`--check-step-deg`).
    pub check_step_deg: f64,
}

impl Default for RewriteOptions {
    fn default() -> Self {
        RewriteOptions {
            tolerance_um: 0.5,
            max_segment_mm: 10.0,
            chord_tolerance_um: 0.5,
            max_correction_um: 500.0,
            on_unsupported: OnUnsupported::Refuse,
            decimals_mm: default_decimals(Units::Mm, 0.5),
            decimals_inch: default_decimals(Units::Inch, 0.5),
            default_units: Units::Mm,
            offsets: Offsets::default(),
            max_pieces_per_move: 100_000,
            start_position_mm: None,
            check_step_mm: 0.5,
            max_line_chars: LINUXCNC_MAX_LINE_CHARS,
            block_delete: BlockDelete::Unknown,
            start_rotary_deg: None,
            check_step_deg: 0.5,
        }
    }
}

impl RewriteOptions {
    /// The defaults with `tolerance_um`, written with the digits that tolerance needs
    /// ([`default_decimals`]): what the CLI, the Python module and a project give when the user
    /// names no digits.
    pub fn with_tolerance(tolerance_um: f64) -> RewriteOptions {
        RewriteOptions {
            tolerance_um,
            decimals_mm: default_decimals(Units::Mm, tolerance_um),
            decimals_inch: default_decimals(Units::Inch, tolerance_um),
            ..RewriteOptions::default()
        }
    }

    /// Refuses the rotary options for a model without rotary axes, where they change nothing
    /// (the rotary words pass through): a user must not believe the start angles or the
    /// angular check step took effect.
    pub fn check_for(&self, model: &dyn crate::ErrorModel) -> Result<(), String> {
        let view = crate::gcode::rotary::RotaryView::new(model);
        if view.rotary_axes() != [false; 3] {
            return Ok(());
        }
        let given = [
            ("--start-rotary-deg", self.start_rotary_deg.is_some()),
            (
                "--check-step-deg",
                self.check_step_deg != RewriteOptions::default().check_step_deg,
            ),
        ];
        match given.iter().find(|(_, g)| *g) {
            Some((flag, _)) => Err(format!(
                "{flag} is read only with a model that has rotary axes (a kinematic model with A, B or C); this model has none: leave it out"
            )),
            None => Ok(()),
        }
    }

    /// Checks that the numbers make sense; the message names the option. Every one is bounded
    /// above too: a huge tolerance, correction limit or check step would switch a safety
    /// check off, and a check step below [`MIN_CHECK_STEP`] runs for hours on a real program.
    pub fn validate(&self) -> Result<(), String> {
        use mtec_io::plausible::{positive_option, MAX_CORRECTION_LIMIT_UM, MAX_POSITION_MM};
        positive_option("--tolerance-um", self.tolerance_um, MAX_TOLERANCE_UM, "um")?;
        positive_option(
            "--chord-tolerance-um",
            self.chord_tolerance_um,
            MAX_TOLERANCE_UM,
            "um",
        )?;
        positive_option(
            "--max-correction-um",
            self.max_correction_um,
            MAX_CORRECTION_LIMIT_UM,
            "um",
        )?;
        positive_option(
            "--max-segment-mm",
            self.max_segment_mm,
            MAX_POSITION_MM,
            "mm",
        )?;
        for (flag, v, unit) in [
            ("--check-step-mm", self.check_step_mm, "mm"),
            ("--check-step-deg", self.check_step_deg, "deg"),
        ] {
            positive_option(flag, v, MAX_CHECK_STEP, unit)?;
            if v < MIN_CHECK_STEP {
                return Err(format!(
                    "{flag} {v:e} {unit} is below {MIN_CHECK_STEP} {unit}: the path check would sample a long program for hours"
                ));
            }
        }
        // 100 m is a unit mistake, not where a machine stands (a rotary angle is not bounded:
        // an axis without limits may stand many turns from zero)
        let limit = MAX_POSITION_MM;
        if let Some(x) = self
            .start_position_mm
            .and_then(|p| p.into_iter().find(|x| !x.is_finite() || x.abs() >= limit))
        {
            return Err(format!(
                "--start-position-mm: {x:e} is implausible (each must be finite and below {limit:e} mm in magnitude)"
            ));
        }
        if let Some(r) = self.start_rotary_deg {
            if !r.iter().all(|v| v.is_finite()) {
                return Err("--start-rotary-deg must be three finite angles".into());
            }
        }
        if self.decimals_mm > 9 || self.decimals_inch > 9 {
            return Err("--decimals must be at most 9".into());
        }
        // rounding a written word moves the command by up to half a unit of its last digit on
        // each axis; that must leave room for the correction's own path error
        for (d, units, flag) in [
            (self.decimals_mm, Units::Mm, "--decimals-mm"),
            (self.decimals_inch, Units::Inch, "--decimals-inch"),
        ] {
            let r = rounding_um(d, units);
            if r > self.tolerance_um / 2.0 {
                let need = (0..=9)
                    .find(|&k| rounding_um(k, units) <= self.tolerance_um / 2.0)
                    .map(|k| format!("use {flag} {k} or more"))
                    .unwrap_or_else(|| "raise --tolerance-um".into());
                return Err(format!(
                    "{flag} {d} rounds every corrected word by up to {r:.3} um (half a unit of the last digit, on three axes), more than half of --tolerance-um {}: the correction would be lost in rounding; {need}",
                    self.tolerance_um
                ));
            }
        }
        if self.max_line_chars < 80 {
            return Err(format!(
                "--max-line-chars {} is too short for a rewritten block (at least 80)",
                self.max_line_chars
            ));
        }
        Ok(())
    }
}

/// LinuxCNC's interpreter refuses longer lines ("Command too long"): rs274 of LinuxCNC 2.9
/// accepts 252 characters and refuses 253, a CR counting as one, so 251 is safe with either
/// line ending (measured; its LINELEN of 255 includes the terminators).
pub const LINUXCNC_MAX_LINE_CHARS: usize = 251;

/// Largest distance (µm) a written position moves when its words are rounded to `decimals`
/// digits: half a unit of the last digit on each of three axes, √3·½·10⁻ᵈ program units.
pub fn rounding_um(decimals: usize, units: Units) -> f64 {
    3f64.sqrt() * 0.5 * 10f64.powi(-(decimals as i32)) * units.mm_per_unit() * 1e3
}

/// The digits written when the user gives none: 4 in mm and 5 in inch (LinuxCNC's own
/// precision and one more), or the fewest whose rounding leaves half of `tolerance_um` to
/// the correction when the tolerance asks for more (`--tolerance-um 0.2` writes 6 inch
/// decimals instead of refusing a program that may never switch to inch).
pub fn default_decimals(units: Units, tolerance_um: f64) -> usize {
    let base = match units {
        Units::Mm => 4,
        Units::Inch => 5,
    };
    (base..=9)
        .find(|&k| rounding_um(k, units) <= tolerance_um / 2.0)
        .unwrap_or(base)
}

/// [`rounding_um`] of the digits written in `units` (mm unless known to be inch).
pub(super) fn rounding_in_effect_um(opt: &RewriteOptions, units: Option<Units>) -> f64 {
    match units {
        Some(Units::Inch) => rounding_um(opt.decimals_inch, Units::Inch),
        _ => rounding_um(opt.decimals_mm, Units::Mm),
    }
}
