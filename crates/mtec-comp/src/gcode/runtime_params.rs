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
    let mut line = 1;
    let mut line_start = 0;
    let mut depth = 0usize;
    let mut i = 0;
    while i < program.len() {
        let c = program[i];
        match c {
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
                if let Some((name, end)) = parameter_at(program, i) {
                    let column = String::from_utf8_lossy(&program[line_start..i])
                        .chars()
                        .count()
                        + 1;
                    let text = String::from_utf8_lossy(&program[i..end]).into_owned();
                    if is_machine_state(&name) {
                        return Some((line, column, text));
                    }
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
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
    fn the_program_s_own_parameters_and_comments_pass() {
        let p = b"#<_feedrate> = 100 ; #<_task>\n#5401 = 2 (#5400)\nG1 X#1 F#<_feedrate>\n#<_tasks> = 1\n";
        assert_eq!(machine_state_parameter(p), None);
        assert_eq!(machine_state_parameter(b"#54000 = 1\nG0 X#5220\n"), None);
    }
}
