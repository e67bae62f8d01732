//! Siemens SINUMERIK part-program lines: the fine offset of a settable frame, or the axial
//! temperature-compensation setting data.
//!
//! Settable frame (work offset), `$P_UIFR[n,<axis>,FI]=<c>`:
//! - "$P_UIFR[n,…,…]: specify the frame number n …; TR translation, FI translation fine", the
//!   geometry axis X, Y or Z in the brackets (SINUMERIK ONE Programming Manual NC programming,
//!   6FC5398-2EP40-0BA0, 12/2019, p. 636); the fine offset adds to the coarse one (same manual,
//!   p. 315: `$P_PFRAME[X,FI]` and CFINE set the fine offset V_F, TRANS and CTRANS the coarse
//!   V_C).
//! - Frame numbers: G500 activates `$P_UIFR[0]`, "G54 to G57 call the second to fifth settable
//!   zero offset", "G505 … G599 call the 6th to the 99th" (SINUMERIK 840Di sl Programming
//!   Manual Fundamentals, 6FC5398-1BP10-2BA0, 11/2006, p. 100).
//! - "The frame is not activated simultaneously when writing a field element, but rather
//!   activation only takes place on execution of a G500, G54 to G599 instruction" (Function
//!   Manual Basic logic functions K2, 6FC5397-0BP10-2BA0, 11/2006, §2.4.5.2, p. 71): mtec ends
//!   with the G code of frame n, which must be the frame the program runs in.
//!
//! mtec writes the whole thermal update c (mm, 4 decimals) into the fine offset and leaves the
//! coarse offset (the touched-off value) alone, so the line is idempotent; the fine offset must
//! be enabled on the control and 0 when the offset is touched off.
//!
//! Temperature compensation (SINUMERIK 840D sl Function Manual Extended Functions, K3
//! Compensations §4.2, 6FC5397-1BP40-3BA1, 03/2013):
//! - ΔK_x = K₀(T) + tanβ(T)·(P_x − P₀) (p. 225), K₀ `SD43900 $SA_TEMP_COMP_ABS_VALUE`, tanβ
//!   `SD43910 $SA_TEMP_COMP_SLOPE`, P₀ `SD43920 $SA_TEMP_COMP_REF_POSITION`.
//! - Enabled by `MD32750 $MA_TEMP_COMP_TYPE`: bit 0 the position-independent part (SD43900),
//!   bit 1 the position-dependent part (SD43920, SD43910) (p. 228; also the 808D parameter
//!   list, where it is a power-on datum). A part program cannot set it: mtec states the value
//!   needed in a comment (1 for a model whose drift does not depend on the position, else 3).
//! - Units: P₀ in mm ("P₀ = 320 mm → SD43920 $SA_TEMP_COMP_REF_POSITION = 320", p. 230); tanβ
//!   a ratio: "tanβ(T) = (T − T₀)·TK_max·10⁻⁶/(T_max − T₀)" with TK in µm/m (p. 230), so an
//!   error slope of k µm/mm is tanβ = k·10⁻³; K₀ in mm (mtec's reading: the manual's example
//!   has K₀ = 0; every Siemens length datum is in mm).
//! - Sign (mtec's reading): the manual derives the parameters from the measured error curves —
//!   P₀ where the curves cross, tanβ "the gradient of the approximated error line" (pp. 225,
//!   230) — and the control compensates that error. So mtec writes the error line itself,
//!   K₀ = b and tanβ = k of the model's e = k·x + b (tool reaches commanded + e), like the
//!   leadscrew table (`crate::table::sinumerik`, where a positive value moves the axis
//!   negative). Not checked on a control: before relying on it, write a small K₀ (0.010) alone
//!   and check with a dial gauge that the axis moves by −10 µm.
//! - Limits: `MD32760 $MA_COMP_ADD_VELO_FACTOR` (default 0.01, at most 0.1, 808D parameter
//!   list) caps the compensation's travel per interpolation cycle at that fraction of the
//!   maximum axis velocity "and also limits the maximum gradient of the error line (tan β)"
//!   (p. 228). Derived: ΔK changes by tanβ·v while the axis moves at v, so the cap means
//!   |tanβ| ≤ MD32760; mtec refuses a larger slope. Abrupt changes of the data are smoothed by
//!   the control over several cycles (no alarm).
//! - Syntax: `$SA_<name>[<machine axis>]=<value>`, the form of axial system variables in the
//!   manuals (`$P_UIFR[n,X,TR]`, `$MA_…`); not checked on a control. K₀ with 6 decimals (1 nm),
//!   tanβ with 10, P₀ with 4.
//!
//! Both outputs start with `STOPRE` (stop preprocessing) so that the values are written when
//! the program reaches them, not while earlier blocks still run.

use super::{comment_text, update_line, OffsetError, OffsetUpdate, TempCompSetting};
use crate::table::{decimal_number, trim_number};

/// The G code that activates settable frame `n` (module docs).
fn frame_code(n: u32) -> Option<String> {
    match n {
        0 => Some("G500".into()),
        1..=4 => Some(format!("G{}", 53 + n)),
        5..=99 => Some(format!("G{}", 500 + n)),
        _ => None,
    }
}

fn comments(lines: &[String]) -> String {
    lines
        .iter()
        .map(|h| format!("; {}\n", comment_text(h)))
        .collect()
}

/// `$P_UIFR[n,<axis>,FI]=<c>` and the frame's G code (module docs).
pub fn write_frame(u: &OffsetUpdate, n: u32, header: &[String]) -> Result<String, OffsetError> {
    let code = frame_code(n).ok_or_else(|| {
        OffsetError::Usage(format!(
            "--offset {n}: Siemens settable frames are 0 (G500), 1-4 (G54-G57) and 5-99 (G505-G599)"
        ))
    })?;
    let mut lines = header.to_vec();
    lines.push(update_line(u));
    lines.push(format!(
        "the update goes into the fine offset of frame {n}, {code} activates it"
    ));
    Ok(format!(
        "{}STOPRE\n$P_UIFR[{n},{},FI]={}\n{code}\n",
        comments(&lines),
        u.axis.letter(),
        trim_number(u.correction_um * 1e-3, 4)
    ))
}

/// A machine axis name as the control knows it (`AX3`, `Z1`).
fn valid_axis_name(s: &str) -> bool {
    let mut c = s.chars();
    c.next().is_some_and(|f| f.is_ascii_uppercase())
        && c.all(|ch| ch.is_ascii_uppercase() || ch.is_ascii_digit() || ch == '_')
}

/// The three setting data of the axis `machine_axis` (module docs).
pub fn write_temp_comp(
    s: &TempCompSetting,
    machine_axis: &str,
    header: &[String],
) -> Result<String, OffsetError> {
    if !valid_axis_name(machine_axis) {
        return Err(OffsetError::Usage(format!(
            "--machine-axis `{machine_axis}`: expected the control's machine axis name, e.g. AX3 or Z1"
        )));
    }
    let md = if s.position_dependent { 3 } else { 1 };
    let mut lines = header.to_vec();
    lines.push(format!(
        "{} temperature compensation now: K0 = {} um at P0 = {} mm, slope {} um/m, envelope weight {}",
        s.axis.letter(),
        trim_number(s.k0_mm * 1e3, 3),
        trim_number(s.p0_mm, 4),
        trim_number(s.tan_beta * 1e6, 3),
        trim_number(s.weight, 3)
    ));
    lines.push(format!(
        "needs MD32750 $MA_TEMP_COMP_TYPE[{machine_axis}] = {md}, set at commissioning"
    ));
    Ok(format!(
        "{}STOPRE\n$SA_TEMP_COMP_ABS_VALUE[{machine_axis}]={}\n$SA_TEMP_COMP_SLOPE[{machine_axis}]={}\n$SA_TEMP_COMP_REF_POSITION[{machine_axis}]={}\n",
        comments(&lines),
        trim_number(s.k0_mm, 6),
        trim_number(s.tan_beta, 10),
        decimal_number(s.p0_mm, 4)
    ))
}
