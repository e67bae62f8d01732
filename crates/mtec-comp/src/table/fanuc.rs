//! FANUC stored pitch error compensation: parameters 3620–3625 and the incremental compensation
//! data, as a parameter/pitch-error tape (`%`, `N03620A1P…`, `N1nnnnP…`, `%`).
//!
//! Documented rules (FANUC Series 16i/18i-MA/TA *Bidirectional pitch error compensation*,
//! A-77810E, table (a); FANUC Series 0i-PB Parameter Manual B-63980EN/01 p. 100, parameters
//! 3620–3625; the GSK983Ma manual's appendix 8 for the same scheme):
//! - 3620 number of the compensation point of the reference position, 3621/3622 numbers of the
//!   farthest points on the − / + side, 3623 magnification, 3624 interval between compensation
//!   points, 3625 travel per rotation (rotary axes).
//! - Each compensation point holds the *increment* of compensation over the interval that ends at
//!   it ("the compensation value is output at the compensation position No. corresponding to each
//!   section"): number R (3620) holds the interval ending at the reference position, R + k the
//!   interval ending k intervals further in +. Values are in detection units × magnification.
//! - 3621 ≤ 3620 ≤ 3622: with the reference at the − end of the table (and on rotary axes) the
//!   farthest − point is the reference point itself; on a linear axis its value is 0 (its
//!   interval lies outside the compensated travel).
//! - Rotary axes: the farthest − point equals the reference number, the farthest + point is
//!   R + travel/interval; the values R+1…R+m must sum to zero (otherwise the error accumulates per
//!   turn), and point R is given the same value as point R+m.
//!
//! mtec's rounding: the absolute compensation C(x) = c(x) − c(x_ref) is rounded at each point and
//! the increments taken from the rounded values, so rounding never accumulates along the axis.
//! Tape layout (FANUC Series 15i/150i-MA Parameter Manual B-63330EN/03 §3, "Inputting and
//! outputting parameters using external input/output devices"): a record begins and ends with
//! `%`; an axis-type parameter block is `N<5-digit number>A<axis>P<value>` ended by the
//! end-of-block character (LF in ISO code, written `;` in the manual); "when parameters and pitch
//! error compensation data are collected into a single file, the file begins and ends with %".
//! The pitch-data block of point n is `N<10000 + n>P<value>` (mtec's reading of the pitch-error
//! data numbering; check against the control's own punched output before the first load). Value range per point: ±`max_increment`
//! (the range depends on the control model — older ones allow ±7, 16i/0i ±127 — so it is an
//! option, default 127).

use super::bidirectional::BidirectionalProfile;
use super::{AxisProfile, TableError};

const FORMAT: &str = "FANUC pitch error";

/// Settings of the FANUC table.
#[derive(Debug, Clone, PartialEq)]
pub struct FanucOptions {
    /// Axis number in the parameter tape (A1 = first axis).
    pub axis_number: u8,
    /// Machine position of the reference point (mm or deg); must be a table point.
    pub reference_mm: f64,
    /// Parameter 3620: compensation point number of the reference position.
    pub reference_number: u32,
    /// Parameter 3623: magnification (1–100).
    pub magnification: u32,
    /// Detection unit (µm, or 0.001 deg for rotary axes: give 1.0).
    pub detection_unit_um: f64,
    /// Largest |value| per point (in units of detection unit × magnification).
    pub max_increment: i64,
    /// Largest compensation point number of the control.
    pub max_number: u32,
    /// Bidirectional tables: parameter 3626, the number of the farthest − point of the
    /// negative-direction data; `None`: right after the positive-direction points.
    pub reverse_first_number: Option<u32>,
}

impl Default for FanucOptions {
    fn default() -> Self {
        FanucOptions {
            axis_number: 1,
            reference_mm: 0.0,
            reference_number: 0,
            magnification: 1,
            detection_unit_um: 1.0,
            max_increment: 127,
            max_number: 1023,
            reverse_first_number: None,
        }
    }
}

/// Writes the parameter and pitch-error tape for `profile` (input = output axis).
pub fn write(profile: &AxisProfile, opts: &FanucOptions) -> Result<String, TableError> {
    if profile.input_axis != profile.output_axis {
        return Err(TableError::rule(
            FORMAT,
            None,
            "pitch error compensation corrects the axis's own position (input axis = output axis)",
        ));
    }
    if opts.axis_number == 0 {
        return Err(TableError::rule(
            FORMAT,
            None,
            "the axis number (--axis-number) starts at 1 (A1 = the first axis)",
        ));
    }
    if !(1..=127).contains(&opts.max_increment) {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "the value range per point (--max-increment) must be 1..127 (±7 on older controls, ±127 on 16i/0i), not {}",
                opts.max_increment
            ),
        ));
    }
    if !(1..=100).contains(&opts.magnification) {
        return Err(TableError::rule(
            FORMAT,
            None,
            "magnification (3623) must be 1..100",
        ));
    }
    if opts.detection_unit_um.is_nan() || opts.detection_unit_um <= 0.0 {
        return Err(TableError::rule(
            FORMAT,
            None,
            "the detection unit must be positive",
        ));
    }
    // the size bound first: a huge constant offset has increments of 0 and would pass 3620…
    let comp_um = profile.checked_values()?;
    let n = comp_um.len();
    let m_f = (opts.reference_mm - profile.start_mm) / profile.step_mm;
    let m = m_f.round();
    if !m_f.is_finite() || (m_f - m).abs() > 1e-6 || m < 0.0 || m as usize >= n {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "the reference position {} must be one of the table points {}..{} step {}",
                opts.reference_mm,
                profile.start_mm,
                profile.end_mm(),
                profile.step_mm
            ),
        ));
    }
    let m = m as usize;
    if profile.rotary && m != 0 {
        return Err(TableError::rule(
            FORMAT,
            None,
            "a rotary axis table starts at its reference position (farthest − point = reference number)",
        ));
    }
    let interval_units = profile.step_mm * 1000.0 / opts.detection_unit_um;
    if (interval_units - interval_units.round()).abs() > 1e-6 {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "the interval {} mm is not a whole number of detection units",
                profile.step_mm
            ),
        ));
    }
    let r = opts.reference_number as i64;
    // the farthest − point: for rotary axes and for a reference at the − end of the table it is
    // the reference point itself (its interval lies before the table: value 0 on linear axes)
    let n_min = if profile.rotary || m == 0 {
        r
    } else {
        r + 1 - m as i64
    };
    let n_max = r + (n - 1 - m) as i64;
    if n_min < 0 || n_max > opts.max_number as i64 {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "compensation points {n_min}..{n_max} fall outside 0..{}: choose another reference number (3620)",
                opts.max_number
            ),
        ));
    }
    // absolute compensation relative to the reference, rounded per point (no accumulation)
    let unit_um = opts.detection_unit_um * opts.magnification as f64;
    let c_ref = comp_um[m];
    let abs_units: Vec<i64> = comp_um
        .iter()
        .map(|c| ((c - c_ref) / unit_um).round() as i64)
        .collect();
    let mut values: Vec<(i64, i64)> = Vec::with_capacity(n);
    for j in 1..n {
        values.push((r + j as i64 - m as i64, abs_units[j] - abs_units[j - 1]));
    }
    if profile.rotary {
        // point R repeats point R + m
        let last = values.last().map(|v| v.1).unwrap_or(0);
        values.insert(0, (r, last));
    } else if m == 0 {
        // reference at the − end: point R covers travel before the table, no compensation
        values.insert(0, (r, 0));
    }
    let a = opts.axis_number;
    let mut out = String::from("%\n");
    out.push_str(&format!("N03620A{a}P{r}\n"));
    out.push_str(&format!("N03621A{a}P{n_min}\n"));
    out.push_str(&format!("N03622A{a}P{n_max}\n"));
    out.push_str(&format!("N03623A{a}P{}\n", opts.magnification));
    out.push_str(&format!("N03624A{a}P{}\n", interval_units.round() as i64));
    if profile.rotary {
        let travel = (profile.end_mm() - profile.start_mm) * 1000.0 / opts.detection_unit_um;
        out.push_str(&format!("N03625A{a}P{}\n", travel.round() as i64));
    }
    for (num, v) in &values {
        out.push_str(&format!("N{}P{v}\n", 10000 + num));
    }
    out.push_str("%\n");
    check(&out, opts.max_increment)?;
    Ok(out)
}

/// Writes the bidirectional pitch error tape of an ISO 230-2 profile (A-77810E, table (a)):
/// parameters 3620–3624 as for [`write`], the positive-direction increments of c↑ on points
/// 3621..3622, and for travel in the negative direction parameter 3626 (farthest − point of the
/// negative-direction data, which covers as many points as the positive one, section for
/// section) and 3627, the absolute compensation at the reference position when it is approached
/// in the direction opposite to reference return. mtec takes reference return to be in the
/// positive direction (parameter 1006#5 = 0): the positive table is relative to c↑ at the
/// reference (0 there), 3627 = c↓ − c↑ at the reference, and the negative increments follow
/// c↓. Parameter 3605#0 (bidirectional pitch error compensation) must be set to 1 on the control;
/// the tape does not write it (a bit parameter shared with other functions).
pub fn write_bidirectional(
    profile: &BidirectionalProfile,
    opts: &FanucOptions,
) -> Result<String, TableError> {
    let (start, step) = profile.uniform_step(FORMAT)?;
    let (fwd, rev) = profile.checked_values()?;
    let forward = profile.uniform_axis_profile(start, step, fwd);
    // the positive-direction tape, with every rule of the unidirectional one
    let plain = write(&forward, opts)?;
    let n = fwd.len();
    let m = ((opts.reference_mm - start) / step).round() as usize;
    let r = opts.reference_number as i64;
    let n_min = if m == 0 { r } else { r + 1 - m as i64 };
    let n_max = r + (n - 1 - m) as i64;
    let neg_min = opts
        .reverse_first_number
        .map(i64::from)
        .unwrap_or(n_max + 1);
    let neg_max = neg_min + (n_max - n_min);
    if !(neg_min > n_max || neg_max < n_min) || neg_max > opts.max_number as i64 {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "negative-direction points {neg_min}..{neg_max} must lie within 0..{} and not overlap the positive-direction points {n_min}..{n_max}: choose another 3626",
                opts.max_number
            ),
        ));
    }
    let unit_um = opts.detection_unit_um * opts.magnification as f64;
    // 3627: c↓ − c↑ at the reference, absolute, in units
    let p3627 = ((rev[m] - fwd[m]) / unit_um).round() as i64;
    // negative-direction increments: rounded absolute c↓ − c↓(ref), section by section
    let abs_units: Vec<i64> = rev
        .iter()
        .map(|c| ((c - rev[m]) / unit_um).round() as i64)
        .collect();
    let mut negative: Vec<i64> = (1..n).map(|j| abs_units[j] - abs_units[j - 1]).collect();
    if m == 0 {
        negative.insert(0, 0);
    }
    let a = opts.axis_number;
    let mut out = String::new();
    for line in plain.lines() {
        if line == "%" && !out.is_empty() {
            for (k, v) in negative.iter().enumerate() {
                out.push_str(&format!("N{}P{v}\n", 10000 + neg_min + k as i64));
            }
        }
        out.push_str(line);
        out.push('\n');
        if line.starts_with("N03624A") {
            out.push_str(&format!("N03626A{a}P{neg_min}\nN03627A{a}P{p3627}\n"));
        }
    }
    check(&out, opts.max_increment)?;
    Ok(out)
}

/// Constraint checker: tape framing, parameters present, points 3621..3622 all present in order,
/// |value| ≤ `max_increment`, and for rotary axes (3625 given) the sum-to-zero rule.
pub fn check(text: &str, max_increment: i64) -> Result<(), TableError> {
    let lines: Vec<&str> = text.lines().collect();
    if lines.first() != Some(&"%") || lines.last() != Some(&"%") || lines.len() < 2 {
        return Err(TableError::rule(
            FORMAT,
            Some(1),
            "a tape starts and ends with a `%` line",
        ));
    }
    let mut params = std::collections::BTreeMap::new();
    let mut points: Vec<(i64, i64, usize)> = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(1).take(lines.len() - 2) {
        let bad = || TableError::rule(FORMAT, Some(i + 1), format!("`{line}` is not N…P… data"));
        let rest = line.strip_prefix('N').ok_or_else(bad)?;
        let (num, val) = rest.split_once('P').ok_or_else(bad)?;
        let value: i64 = val.parse().map_err(|_| bad())?;
        if let Some((param, _axis)) = num.split_once('A') {
            let p: u32 = param.parse().map_err(|_| bad())?;
            params.insert(p, value);
        } else {
            let n: i64 = num.parse().map_err(|_| bad())?;
            if n < 10000 {
                return Err(bad());
            }
            if value.abs() > max_increment {
                return Err(TableError::rule(
                    FORMAT,
                    Some(i + 1),
                    format!(
                        "value {value} exceeds ±{max_increment}: raise the magnification (3623)"
                    ),
                ));
            }
            points.push((n - 10000, value, i + 1));
        }
    }
    let param = |p: u32| {
        params
            .get(&p)
            .copied()
            .ok_or_else(|| TableError::rule(FORMAT, None, format!("parameter {p} missing")))
    };
    let (r, n_min, n_max) = (param(3620)?, param(3621)?, param(3622)?);
    param(3623)?;
    if param(3624)? <= 0 {
        return Err(TableError::rule(
            FORMAT,
            None,
            "interval (3624) must be positive",
        ));
    }
    if !(n_min <= r && r <= n_max) {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!("reference number {r} must lie within {n_min}..{n_max}"),
        ));
    }
    let mut expect: Vec<i64> = (n_min..=n_max).collect();
    if let Some(&neg_min) = params.get(&3626) {
        // bidirectional: the negative-direction data follow, as many points as the positive
        let neg_max = neg_min + (n_max - n_min);
        if !(neg_min > n_max || neg_max < n_min) {
            return Err(TableError::rule(
                FORMAT,
                None,
                format!("negative-direction points {neg_min}..{neg_max} overlap {n_min}..{n_max}"),
            ));
        }
        if param(3627)?.abs() > 32767 {
            return Err(TableError::rule(
                FORMAT,
                None,
                "parameter 3627 must lie within -32767..32767",
            ));
        }
        expect.extend(neg_min..=neg_max);
    }
    let got: Vec<i64> = points.iter().map(|p| p.0).collect();
    if got != expect {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!("pitch data must cover points {n_min}..{n_max} (and the negative-direction points from 3626) once each, in order"),
        ));
    }
    if params.contains_key(&3625) {
        if n_min != r {
            return Err(TableError::rule(
                FORMAT,
                None,
                "rotary axis: the farthest − point (3621) must equal the reference number (3620)",
            ));
        }
        let sum: i64 = points.iter().filter(|p| p.0 > r).map(|p| p.1).sum();
        if sum != 0 {
            return Err(TableError::rule(
                FORMAT,
                None,
                format!("rotary axis: the values of points {}..{n_max} sum to {sum}, not 0 (the error would accumulate every turn)", r + 1),
            ));
        }
        let at = |n: i64| points.iter().find(|p| p.0 == n).map(|p| p.1);
        if at(r) != at(n_max) {
            return Err(TableError::rule(
                FORMAT,
                None,
                format!("rotary axis: point {r} must repeat the value of point {n_max}"),
            ));
        }
    }
    Ok(())
}
