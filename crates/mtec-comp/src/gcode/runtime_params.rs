//! Parameters whose value on the running machine differs from stand-alone rs274's.
//!
//! Flattening (`--flatten-with rs274`) runs the program in LinuxCNC's interpreter without a
//! machine. Most parameters then read as on the machine: the program's own, the parameter file
//! given, the tool table given. A few read the machine's state instead, and stand-alone rs274
//! gives them its own: `#<_task>` is 0 there (the program is being previewed) and 1 in a real
//! run, so `o100 while [... and [#<_task> ne 0]]` runs zero times in rs274 and five times on
//! the machine. A program that reads one of these would be flattened along a path the machine
//! never takes, so it is refused, naming the line and column.
//!
//! The list (LinuxCNC documentation, "Parameters", sections "Predefined Named Parameters" and
//! "Numbered Parameters"): `_task`; the loaded and selected tool and pocket
//! (`_current_tool`, `_current_pocket`, `_selected_tool`, `_selected_pocket`, `#5400`), which
//! rs274 starts at 0; the spindle, coolant and override switches (`_spindle_on`, `_spindle_cw`,
//! `_mist`, `_flood`, `_speed_override`, `_feed_override`, `_adaptive_feed`, `_feed_hold`,
//! `_rpm`, `_feed`); INI and HAL values (`_ini[…]`, `_hal[…]`); the result of the last M66 input
//! (`#5399`) and of the last probe (`#5061`–`#5070`). The current position (`#5420`–`#5428`,
//! `_x` …) is not listed: [`super::start_probe`] catches a path that depends on it.

/// Predefined named parameters (lower case, without blanks) that read the machine's state.
const NAMED: [&str; 14] = [
    "_task",
    "_current_tool",
    "_current_pocket",
    "_selected_tool",
    "_selected_pocket",
    "_spindle_on",
    "_spindle_cw",
    "_mist",
    "_flood",
    "_speed_override",
    "_feed_override",
    "_adaptive_feed",
    "_feed_hold",
    "_rpm",
];

/// Named parameters read by prefix (an INI or HAL item), and `_feed` (exactly).
const PREFIXES: [&str; 2] = ["_ini[", "_hal["];

fn numbered(n: u32) -> bool {
    n == 5399 || n == 5400 || (5061..=5070).contains(&n)
}

/// A parameter of the list above that the program reads: its 1-based line and column and its
/// name as written (`#<_task>`, `#5400`). Comments are skipped.
pub fn machine_state_parameter(program: &[u8]) -> Option<(usize, usize, String)> {
    first_named_or_numbered(program, is_machine_state)
}

/// A reference to a named parameter that reads the position in machine coordinates
/// (`#<_abs_x>` … `#<_abs_w>`): program position plus every offset in effect, so it takes the
/// work offsets mtec hands rs274 (all zero when none were given; checked with rs274, a G54 X of
/// 50.8 mm gives `_abs_x` = 51.8 after `G0 X1`).
pub fn machine_position_parameter(program: &[u8]) -> Option<(usize, usize, String)> {
    first_named_or_numbered(program, |name| name.starts_with("_abs_"))
}

/// A reference to `#<_metric_machine>`: 1 on a metric machine, 0 in stand-alone rs274 (an inch
/// machine), so a program that branches on it would be flattened along the inch branch.
pub fn metric_machine_parameter(program: &[u8]) -> Option<(usize, usize, String)> {
    first_named_or_numbered(program, |name| name == "_metric_machine")
}

/// The first parameter reference (`#<name>` or `#n`, outside comments) whose name (lower
/// case, blanks removed; the digits of a numbered one) passes `wanted`.
fn first_named_or_numbered(
    program: &[u8],
    wanted: impl Fn(&str) -> bool,
) -> Option<(usize, usize, String)> {
    first_reference(program, |at, _| {
        let (name, end) = parameter_at(program, at)?;
        wanted(&name).then_some((end, ()))
    })
    .map(|(line, column, text, ())| (line, column, text))
}

/// Walks the program's `#` outside comments (parenthesised, or after `;`) and returns the first
/// for which `found(position of the #, end of its line)` gives the end of the reference's text
/// and a value: its 1-based line and column, its text and the value.
fn first_reference<T>(
    program: &[u8],
    mut found: impl FnMut(usize, usize) -> Option<(usize, T)>,
) -> Option<(usize, usize, String, T)> {
    let mut line = 1;
    let mut line_start = 0;
    let mut depth = 0usize;
    let mut i = 0;
    while i < program.len() {
        match program[i] {
            b'\n' => {
                line += 1;
                line_start = i + 1;
                depth = 0;
            }
            b'(' => depth += 1,
            b')' => depth = depth.saturating_sub(1),
            b';' if depth == 0 => {
                while i < program.len() && program[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'#' if depth == 0 => {
                let line_end = program[i..]
                    .iter()
                    .position(|&b| b == b'\n')
                    .map_or(program.len(), |k| i + k);
                if let Some((end, value)) = found(i, line_end) {
                    let column = String::from_utf8_lossy(&program[line_start..i])
                        .chars()
                        .count()
                        + 1;
                    let text = String::from_utf8_lossy(&program[i..end]).into_owned();
                    return Some((line, column, text, value));
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// Numbered parameters LinuxCNC keeps in the machine's length units, and the file they come
/// from: the parameter file's machine position (#5021–#5029), tool length offset in effect
/// (#5081–#5089), G28 and G30 homes (#5161–#5169, #5181–#5189), G52/G92 offset
/// (#5210–#5219) and G54–G59.3 work offsets and rotations (#5221–#5390); the tool table's
/// offsets and geometry of the loaded tool (#5401–#5413). Stand-alone rs274 reads both files
/// as inches and gives a program the raw value (a G21 program reading a 1-inch tool's #5403
/// gets 1, checked with rs274): on a metric machine a program that reads or writes one of them
/// (`X[#5221 + 10]`, `#5242 = 3`) would be flattened with a value 25.4 times off, or with the
/// zeros of a file mtec makes up, and the path would differ from the machine's without any
/// check seeing it (rs274 is the checker's reference too). Found 2026-11-28 with
/// hand-written programs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnitsSource {
    ParameterFile,
    ToolTable,
    /// An indirect reference whose index reads a parameter: it may address either.
    Either,
}

fn machine_units_parameter(n: u32) -> Option<UnitsSource> {
    match n {
        5021..=5029 | 5081..=5089 | 5161..=5169 | 5181..=5189 | 5210..=5219 | 5221..=5390 => {
            Some(UnitsSource::ParameterFile)
        }
        5401..=5413 => Some(UnitsSource::ToolTable),
        _ => None,
    }
}

fn numbered_machine_units(n: f64) -> Option<UnitsSource> {
    if n.fract() == 0.0 && (0.0..1e6).contains(&n) {
        machine_units_parameter(n as u32)
    } else {
        None
    }
}

/// The first reference to a parameter of [`machine_units_parameter`], read or written, with
/// its 1-based line and column and its text: a literal number (`#5221`), or an indirect one
/// (`#[5200 + 21]` evaluated when its index is literal). An indirect reference whose index
/// reads a parameter (`#[5201 + 20 * #5220]`, `##1`) may address any of them, so it is
/// reported too. Comments are skipped.
pub fn machine_units_parameter_reference(
    program: &[u8],
) -> Option<(usize, usize, String, UnitsSource)> {
    first_reference(program, |at, line_end| {
        indirect_reference(&program[..line_end], at).or_else(|| {
            let (name, end) = parameter_at(program, at)?;
            let source = name.parse::<f64>().ok().and_then(numbered_machine_units)?;
            Some((end, source))
        })
    })
}

/// An indirect reference at the `#` at `i` (`#[…]` or `##…`) that can address a parameter of
/// [`machine_units_parameter`]: the end of its text. A literal index is evaluated; an index
/// that reads a parameter counts as able to.
fn indirect_reference(line: &[u8], i: usize) -> Option<(usize, UnitsSource)> {
    let mut j = i + 1;
    while j < line.len() && (line[j] == b' ' || line[j] == b'\t') {
        j += 1;
    }
    match line.get(j)? {
        b'#' => Some((j + 1, UnitsSource::Either)),
        b'[' => {
            let mut level = 0usize;
            let mut k = j;
            while k < line.len() {
                match line[k] {
                    b'[' => level += 1,
                    b']' => {
                        level -= 1;
                        if level == 0 {
                            break;
                        }
                    }
                    _ => {}
                }
                k += 1;
            }
            let end = (k + 1).min(line.len());
            let index = &line[j..end];
            if index.contains(&b'#') {
                return Some((end, UnitsSource::Either));
            }
            let n = super::expr::eval_value(line, j..end, &super::expr::Params::new()).ok()?;
            numbered_machine_units(n.round()).map(|source| (end, source))
        }
        _ => None,
    }
}

/// The parameter that starts at the `#` at `i`: its name (lower case, blanks removed; digits
/// for a numbered one) and the end of its text.
fn parameter_at(p: &[u8], i: usize) -> Option<(String, usize)> {
    let mut j = i + 1;
    while j < p.len() && (p[j] == b' ' || p[j] == b'\t') {
        j += 1;
    }
    match p.get(j)? {
        b'<' => {
            let close = p[j..].iter().position(|&b| b == b'>' || b == b'\n')? + j;
            if p[close] != b'>' {
                return None;
            }
            let name: String = String::from_utf8_lossy(&p[j + 1..close])
                .chars()
                .filter(|c| !c.is_whitespace())
                .collect::<String>()
                .to_ascii_lowercase();
            Some((name, close + 1))
        }
        d if d.is_ascii_digit() => {
            let mut k = j;
            while k < p.len() && (p[k].is_ascii_digit() || p[k] == b'.') {
                k += 1;
            }
            Some((String::from_utf8_lossy(&p[j..k]).into_owned(), k))
        }
        _ => None,
    }
}

fn is_machine_state(name: &str) -> bool {
    if let Ok(n) = name.parse::<f64>() {
        return n.fract() == 0.0 && (0.0..1e6).contains(&n) && numbered(n as u32);
    }
    NAMED.contains(&name) || name == "_feed" || PREFIXES.iter().any(|p| name.starts_with(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn machine_state_reads_are_found_with_line_and_column() {
        let p = b"#<ct> = 0\no100 while [[#<ct> lt 5] and [#< _Task > ne 0]]\n";
        assert_eq!(
            machine_state_parameter(p),
            Some((2, 31, "#< _Task >".to_string()))
        );
        assert_eq!(
            machine_state_parameter(b"G0 X1\n(debug, #5400)\nT#5400 M6\n"),
            Some((3, 2, "#5400".to_string()))
        );
        assert_eq!(
            machine_state_parameter(b"#1 = #<_hal[motion.spindle-speed-out]>\n").map(|r| r.1),
            Some(6)
        );
        assert!(machine_state_parameter(b"F#<_feed>\n").is_some());
    }

    #[test]
    fn machine_positions_and_the_machine_s_units_are_found() {
        assert_eq!(
            machine_position_parameter(b"G0 X1\nG1 X#<_abs_x> F1\n"),
            Some((2, 5, "#<_abs_x>".to_string()))
        );
        assert_eq!(machine_position_parameter(b"G1 X#<_x> (#<_abs_y>)\n"), None);
        assert_eq!(
            metric_machine_parameter(b"o1 if [#<_metric_machine>]\n").map(|r| r.1),
            Some(8)
        );
        assert_eq!(metric_machine_parameter(b"G1 X#<_metric>\n"), None);
    }

    #[test]
    fn the_program_s_own_parameters_and_comments_pass() {
        let p = b"#<_feedrate> = 100 ; #<_task>\n#5401 = 2 (#5400)\nG1 X#1 F#<_feedrate>\n#<_tasks> = 1\n";
        assert_eq!(machine_state_parameter(p), None);
        assert_eq!(machine_state_parameter(b"#54000 = 1\nG0 X#5220\n"), None);
    }

    #[test]
    fn offsets_homes_and_machine_position_are_found_read_or_written() {
        assert_eq!(
            machine_units_parameter_reference(b"G0 X0\nG1 X[#5221 + 10] F5\n"),
            Some((2, 6, "#5221".to_string(), UnitsSource::ParameterFile))
        );
        assert_eq!(
            machine_units_parameter_reference(b"#5242 = 3\n").map(|r| r.1),
            Some(1)
        );
        assert!(machine_units_parameter_reference(b"G1 X#5161\n").is_some());
        assert!(machine_units_parameter_reference(b"G1 X#5390\n").is_some());
        assert!(machine_units_parameter_reference(b"#1 = #5081\n").is_some());
        assert_eq!(
            machine_units_parameter_reference(b"#<y> = #[5202 + [20 * #5220]]\n"),
            Some((
                1,
                8,
                "#[5202 + [20 * #5220]]".to_string(),
                UnitsSource::Either
            ))
        );
        assert!(machine_units_parameter_reference(b"#1 = 5221\nG1 X##1\n").is_some());
        assert!(machine_units_parameter_reference(b"G1 X#[5200 + 21]\n").is_some());
        assert_eq!(
            machine_units_parameter_reference(b"G1 X#5403 Y#5410\n").map(|r| r.3),
            Some(UnitsSource::ToolTable)
        );
    }

    #[test]
    fn other_parameters_and_comments_are_not_offsets() {
        let p = b"G1 X#5220 Y#5420 Z#5400 A#5414\n#[100 + 2] = 1\n(#5221) ; #5221\n#52210 = 1\nG1 X#[2 * 50]\n";
        assert_eq!(machine_units_parameter_reference(p), None);
        assert_eq!(
            machine_units_parameter_reference(b"#5220 = 1\n#5391 = 2\n"),
            None
        );
    }
}
