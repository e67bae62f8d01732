//! Siemens SINUMERIK 840D interpolatory compensation: sag/cross-axis tables (CEC,
//! `%_N_NC_CEC_INI`, `$AN_CEC…`) and leadscrew/measuring-system error tables (LEC,
//! `%_N_AX_EEC_INI`, `$AA_ENC_COMP…`).
//!
//! Documented format (SINUMERIK 840D sl Function Manual *Extended Functions*, K3 Compensation,
//! "Interpolatory compensation", 6FC5397-1BP40-3BA1 (03/2013) pp. 242–249, and the 802D sl
//! Function Manual 6FC5397-1CP10-5BA0 §11.3 table example):
//! - CEC: `$AN_CEC[t,n]` compensation value n of table t, `$AN_CEC_INPUT_AXIS[t]` basic axis,
//!   `$AN_CEC_OUTPUT_AXIS[t]` compensation axis (machine axis names such as `(AX1)`),
//!   `$AN_CEC_STEP[t]` distance between interpolation points, `$AN_CEC_MIN[t]`/`_MAX[t]` first and
//!   last point, `$AN_CEC_DIRECTION[t]` (0 both directions, 1 positive only, −1 negative only),
//!   `$AN_CEC_MULT_BY_TABLE[t]` (0 = no multiplication), `$AN_CEC_IS_MODULO[t]`. The value is
//!   added to the position setpoint of the compensation axis, so it is the correction c = −e.
//! - LEC: `$AA_ENC_COMP[0,n,AX]`, `$AA_ENC_COMP_STEP[0,AX]`, `_MIN`, `_MAX`, `_IS_MODULO`.
//!   "A positive compensation value causes the corresponding machine axis to move in the
//!   negative direction" (808D Function Manual, LEC): the value written is −c = e.
//! - Both files start with the `%_N_…_INI` name line and `CHANDATA(1)`, end with `M17`; values
//!   and positions in mm. The number of points is MAX = MIN + STEP·(N − 1), which the checker
//!   verifies, with N ≤ the configured MD18342 `MM_CEC_MAX_POINTS` / MD38000
//!   `MM_ENC_COMP_MAX_POINTS` when a limit is given. With modulo, first and last value must match.
//!
//! Values are written in mm with 6 decimals (trailing zeros dropped), as in the manual's examples.

use super::bidirectional::BidirectionalProfile;
use super::{decimal_number, trim_number, AxisProfile, TableError};

const CEC: &str = "Siemens CEC";
const LEC: &str = "Siemens LEC";

/// Options of a CEC table.
#[derive(Debug, Clone, PartialEq)]
pub struct CecOptions {
    /// Table index t.
    pub table_index: usize,
    /// Machine axis names of X, Y, Z as the controller knows them, e.g. `AX1`.
    pub machine_axes: [String; 3],
    /// `$AN_CEC_DIRECTION`: 0, 1 or −1.
    pub direction: i8,
    /// Largest number of points (MD18342), if known.
    pub max_points: Option<usize>,
}

impl Default for CecOptions {
    fn default() -> Self {
        CecOptions {
            table_index: 0,
            machine_axes: ["AX1".into(), "AX2".into(), "AX3".into()],
            direction: 0,
            max_points: None,
        }
    }
}

/// Writes a CEC table (`%_N_NC_CEC_INI`) for `profile`.
pub fn write_cec(profile: &AxisProfile, opts: &CecOptions) -> Result<String, TableError> {
    if ![-1, 0, 1].contains(&opts.direction) {
        return Err(TableError::rule(CEC, None, "_DIRECTION must be 0, 1 or -1"));
    }
    let mut out = String::from("%_N_NC_CEC_INI\nCHANDATA(1)\n");
    cec_table(
        &mut out,
        opts,
        opts.table_index,
        profile.checked_values()?,
        [profile.input_axis, profile.output_axis],
        [profile.start_mm, profile.step_mm, profile.end_mm()],
        opts.direction,
        profile.rotary,
    );
    out.push_str("M17\n");
    check_cec(&out, opts.max_points)?;
    Ok(out)
}

/// Writes the direction-dependent form of an axis's own error (K3, 4.4, `$AN_CEC_DIRECTION`:
/// "position-dependent backlash compensation can be implemented using two tables"): table
/// t = `opts.table_index` with `_DIRECTION = 1` holds c↑, table t + 1 with `_DIRECTION = -1`
/// holds c↓; both have the axis as basic and compensation axis. The targets must be equally
/// spaced (a CEC table is `_MIN` + n·`_STEP`).
pub fn write_cec_bidirectional(
    profile: &BidirectionalProfile,
    opts: &CecOptions,
) -> Result<String, TableError> {
    let (start, step) = profile.uniform_step(CEC)?;
    let (fwd, rev) = profile.checked_values()?;
    let end = profile.positions_mm[profile.len() - 1];
    let axes = [profile.axis, profile.axis];
    let t = opts.table_index;
    let mut out = String::from("%_N_NC_CEC_INI\nCHANDATA(1)\n");
    out.push_str(&format!(
        "; table {t}: travel in + (_DIRECTION 1), table {}: travel in - (_DIRECTION -1)\n",
        t + 1
    ));
    cec_table(&mut out, opts, t, fwd, axes, [start, step, end], 1, false);
    cec_table(
        &mut out,
        opts,
        t + 1,
        rev,
        axes,
        [start, step, end],
        -1,
        false,
    );
    out.push_str("M17\n");
    check_cec(&out, opts.max_points)?;
    Ok(out)
}

/// One table t of a CEC file: values c (µm) written in mm, axes [input, output], range
/// [min, step, max].
#[allow(clippy::too_many_arguments)]
fn cec_table(
    out: &mut String,
    opts: &CecOptions,
    t: usize,
    values_um: &[f64],
    axes: [super::Axis; 2],
    range: [f64; 3],
    direction: i8,
    modulo: bool,
) {
    for (n, &c_um) in values_um.iter().enumerate() {
        out.push_str(&format!(
            "$AN_CEC[{t},{n}]={}\n",
            trim_number(c_um * 1e-3, 6)
        ));
    }
    let name = |a: super::Axis| &opts.machine_axes[a.index()];
    out.push_str(&format!(
        "$AN_CEC_INPUT_AXIS[{t}]=({})\n$AN_CEC_OUTPUT_AXIS[{t}]=({})\n",
        name(axes[0]),
        name(axes[1])
    ));
    out.push_str(&format!(
        "$AN_CEC_STEP[{t}]={}\n$AN_CEC_MIN[{t}]={}\n$AN_CEC_MAX[{t}]={}\n",
        decimal_number(range[1], 6),
        decimal_number(range[0], 6),
        decimal_number(range[2], 6)
    ));
    out.push_str(&format!(
        "$AN_CEC_DIRECTION[{t}]={direction}\n$AN_CEC_MULT_BY_TABLE[{t}]=0\n$AN_CEC_IS_MODULO[{t}]={}\n",
        u8::from(modulo)
    ));
}

/// Options of an LEC table.
#[derive(Debug, Clone, PartialEq)]
pub struct LecOptions {
    /// Machine axis names of X, Y, Z, e.g. `X1`.
    pub machine_axes: [String; 3],
    /// Largest number of points (MD38000), if known.
    pub max_points: Option<usize>,
}

impl Default for LecOptions {
    fn default() -> Self {
        LecOptions {
            machine_axes: ["X1".into(), "Y1".into(), "Z1".into()],
            max_points: None,
        }
    }
}

/// Writes an LEC table (`%_N_AX_EEC_INI`) for `profile` (input = output axis).
pub fn write_lec(profile: &AxisProfile, opts: &LecOptions) -> Result<String, TableError> {
    if profile.input_axis != profile.output_axis {
        return Err(TableError::rule(
            LEC,
            None,
            "leadscrew error compensation corrects the axis's own position: use sinumerik-cec for cross-axis tables",
        ));
    }
    let ax = &opts.machine_axes[profile.input_axis.index()];
    let mut out = String::from("%_N_AX_EEC_INI\nCHANDATA(1)\n");
    for (n, &c_um) in profile.checked_values()?.iter().enumerate() {
        // a positive value moves the axis negative: write −c = e
        out.push_str(&format!(
            "$AA_ENC_COMP[0,{n},{ax}]={}\n",
            trim_number(-c_um * 1e-3, 6)
        ));
    }
    out.push_str(&format!(
        "$AA_ENC_COMP_STEP[0,{ax}]={}\n$AA_ENC_COMP_MIN[0,{ax}]={}\n$AA_ENC_COMP_MAX[0,{ax}]={}\n$AA_ENC_COMP_IS_MODULO[0,{ax}]={}\nM17\n",
        decimal_number(profile.step_mm, 6),
        decimal_number(profile.start_mm, 6),
        decimal_number(profile.end_mm(), 6),
        u8::from(profile.rotary)
    ));
    check_lec(&out, opts.max_points)?;
    Ok(out)
}

/// An LEC table holds one value per point for both directions (`$AA_ENC_COMP` has no direction
/// index), so a run whose forward and reverse corrections differ (at the file's 1 nm) is
/// refused: the direction-dependent form is `sinumerik-cec` ([`write_cec_bidirectional`]).
pub fn write_lec_bidirectional(
    profile: &BidirectionalProfile,
    opts: &LecOptions,
) -> Result<String, TableError> {
    let (start, step) = profile.uniform_step(LEC)?;
    let (fwd, rev) = profile.checked_values()?;
    for (n, (f, r)) in fwd.iter().zip(rev).enumerate() {
        if trim_number(f * 1e-3, 6) != trim_number(r * 1e-3, 6) {
            return Err(TableError::rule(
                LEC,
                None,
                format!(
                    "at {} mm the forward correction {f:.4} um and the reverse one {r:.4} um differ (reversal B = {:.4} um); an LEC table has one value for both directions: use --format sinumerik-cec, which writes one table per direction ($AN_CEC_DIRECTION 1 and -1)",
                    profile.positions_mm[n],
                    r - f
                ),
            ));
        }
    }
    let one = profile.uniform_axis_profile(start, step, fwd);
    write_lec(&one, opts)
}

/// One `$NAME[index list]=value` line.
struct Assignment<'a> {
    line: usize,
    name: &'a str,
    index: Vec<&'a str>,
    value: &'a str,
}

fn assignments<'a>(text: &'a str, format: &'static str) -> Result<Vec<Assignment<'a>>, TableError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split(';').next().unwrap_or("").trim();
        if line.is_empty() || line.starts_with('%') || line == "CHANDATA(1)" || line == "M17" {
            continue;
        }
        let parsed = (|| {
            let rest = line.strip_prefix('$')?;
            let (lhs, value) = rest.split_once('=')?;
            let (name, idx) = lhs.split_once('[')?;
            let idx = idx.strip_suffix(']')?;
            Some(Assignment {
                line: i + 1,
                name: name.trim(),
                index: idx.split(',').map(str::trim).collect(),
                value: value.trim(),
            })
        })();
        match parsed {
            Some(a) => out.push(a),
            None => {
                return Err(TableError::rule(
                    format,
                    Some(i + 1),
                    format!("`{line}` is not a `$NAME[index]=value` assignment"),
                ))
            }
        }
    }
    Ok(out)
}

/// Checks the table rules shared by CEC and LEC: values 0..N−1 all present, finite, and
/// MAX = MIN + STEP·(N − 1); modulo tables start and end on the same value.
fn check_equidistant(
    format: &'static str,
    values: &[(usize, f64, usize)],
    step: Option<f64>,
    min: Option<f64>,
    max: Option<f64>,
    modulo: bool,
    max_points: Option<usize>,
) -> Result<(), TableError> {
    let (Some(step), Some(min), Some(max)) = (step, min, max) else {
        return Err(TableError::rule(
            format,
            None,
            "_STEP, _MIN and _MAX must all be given",
        ));
    };
    let n = values.len();
    for (k, &(idx, _, line)) in values.iter().enumerate() {
        if idx != k {
            return Err(TableError::rule(
                format,
                Some(line),
                format!("interpolation point {idx} where {k} was expected (points must be 0, 1, 2, … in order)"),
            ));
        }
    }
    if n < 2 {
        return Err(TableError::rule(
            format,
            None,
            "a table needs at least 2 points",
        ));
    }
    if step.is_nan() || step <= 0.0 {
        return Err(TableError::rule(format, None, "_STEP must be positive"));
    }
    let expect_max = min + step * (n - 1) as f64;
    if (expect_max - max).abs() > 1e-6 * step.max(1.0) {
        return Err(TableError::rule(
            format,
            None,
            format!("{n} points from _MIN {min} with _STEP {step} end at {expect_max}, but _MAX is {max}"),
        ));
    }
    if let Some(limit) = max_points {
        if n > limit {
            return Err(TableError::rule(
                format,
                None,
                format!("{n} points; the controller is configured for at most {limit}"),
            ));
        }
    }
    if modulo && (values[0].1 - values[n - 1].1).abs() > 1e-9 {
        return Err(TableError::rule(
            format,
            Some(values[n - 1].2),
            "with _IS_MODULO = 1 the last value must equal the first (the table repeats)",
        ));
    }
    Ok(())
}

fn number(a: &Assignment<'_>, format: &'static str) -> Result<f64, TableError> {
    a.value
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            TableError::rule(
                format,
                Some(a.line),
                format!("`{}` is not a number", a.value),
            )
        })
}

/// Constraint checker of a CEC file (one or more tables).
pub fn check_cec(text: &str, max_points: Option<usize>) -> Result<(), TableError> {
    if text.lines().next() != Some("%_N_NC_CEC_INI") {
        return Err(TableError::rule(
            CEC,
            Some(1),
            "the file must start with %_N_NC_CEC_INI",
        ));
    }
    let all = assignments(text, CEC)?;
    let mut tables: std::collections::BTreeSet<usize> = Default::default();
    for a in &all {
        let t = a.index[0].parse::<usize>().map_err(|_| {
            TableError::rule(
                CEC,
                Some(a.line),
                format!("table index `{}` is not a number", a.index[0]),
            )
        })?;
        tables.insert(t);
    }
    for t in tables {
        let mine: Vec<&Assignment<'_>> = all
            .iter()
            .filter(|a| a.index[0].parse::<usize>().ok() == Some(t))
            .collect();
        let get = |name: &str| mine.iter().find(|a| a.name == name && a.index.len() == 1);
        let mut values = Vec::new();
        for a in mine.iter().filter(|a| a.name == "AN_CEC") {
            let n = a
                .index
                .get(1)
                .and_then(|s| s.parse::<usize>().ok())
                .ok_or_else(|| {
                    TableError::rule(CEC, Some(a.line), "$AN_CEC needs [table,point]")
                })?;
            values.push((n, number(a, CEC)?, a.line));
        }
        for key in ["AN_CEC_INPUT_AXIS", "AN_CEC_OUTPUT_AXIS"] {
            match get(key) {
                Some(a) if a.value.starts_with('(') && a.value.ends_with(')') => {}
                Some(a) => {
                    return Err(TableError::rule(
                        CEC,
                        Some(a.line),
                        format!("${key} must name a machine axis in parentheses, e.g. (AX1)"),
                    ))
                }
                None => {
                    return Err(TableError::rule(
                        CEC,
                        None,
                        format!("table {t}: ${key} missing"),
                    ))
                }
            }
        }
        if let Some(d) = get("AN_CEC_DIRECTION") {
            if !["0", "1", "-1"].contains(&d.value) {
                return Err(TableError::rule(
                    CEC,
                    Some(d.line),
                    "_DIRECTION must be 0, 1 or -1",
                ));
            }
        }
        let f = |k: &str| get(k).map(|a| number(a, CEC)).transpose();
        let modulo = f("AN_CEC_IS_MODULO")?.unwrap_or(0.0) == 1.0;
        check_equidistant(
            CEC,
            &values,
            f("AN_CEC_STEP")?,
            f("AN_CEC_MIN")?,
            f("AN_CEC_MAX")?,
            modulo,
            max_points,
        )?;
    }
    Ok(())
}

/// Constraint checker of an LEC file (one axis).
pub fn check_lec(text: &str, max_points: Option<usize>) -> Result<(), TableError> {
    if text.lines().next() != Some("%_N_AX_EEC_INI") {
        return Err(TableError::rule(
            LEC,
            Some(1),
            "the file must start with %_N_AX_EEC_INI",
        ));
    }
    let all = assignments(text, LEC)?;
    let mut values = Vec::new();
    for a in all.iter().filter(|a| a.name == "AA_ENC_COMP") {
        let n = (a.index.len() == 3)
            .then(|| a.index[1].parse::<usize>().ok())
            .flatten()
            .ok_or_else(|| {
                TableError::rule(LEC, Some(a.line), "$AA_ENC_COMP needs [encoder,point,axis]")
            })?;
        values.push((n, number(a, LEC)?, a.line));
    }
    let f = |k: &str| {
        all.iter()
            .find(|a| a.name == k)
            .map(|a| number(a, LEC))
            .transpose()
    };
    let modulo = f("AA_ENC_COMP_IS_MODULO")?.unwrap_or(0.0) == 1.0;
    check_equidistant(
        LEC,
        &values,
        f("AA_ENC_COMP_STEP")?,
        f("AA_ENC_COMP_MIN")?,
        f("AA_ENC_COMP_MAX")?,
        modulo,
        max_points,
    )
}
