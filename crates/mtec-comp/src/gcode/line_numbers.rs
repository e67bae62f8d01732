//! Finding the line where LinuxCNC's interpreter stopped.
//!
//! Stand-alone `rs274` prints the text of the block it stopped at, not its line number. When that
//! text occurs on more than one line of the program (a repeated `G1 X0`, a block inside a
//! subroutine called twice), the line is found by running the interpreter once more on
//! [`numbered_program`]: every line carries its own line number as its `N` word, which LinuxCNC
//! ignores for execution and echoes with the block ([`numbered_line`]).

/// LinuxCNC refuses a line number above 99999 (`NCE_LINE_NUMBER_GREATER_THAN_99999`).
pub const MAX_LINE_NUMBER: usize = 99_999;

/// `program` with every line that holds a block numbered by its 1-based line: `N17 ` in front
/// of the block, after a block-delete `/`, an `N` word already there replaced. Blank lines and
/// `%` tape marks stay as they are, and so does a line whose `N` word has a fraction. `None`
/// when the program has more lines than LinuxCNC numbers.
pub fn numbered_program(program: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(program.len() + program.len() / 4);
    for (i, line) in program.split_inclusive(|&b| b == b'\n').enumerate() {
        let number = i + 1;
        if number > MAX_LINE_NUMBER {
            return None;
        }
        out.extend_from_slice(&numbered(line, number));
    }
    Some(out)
}

fn numbered(line: &[u8], number: usize) -> Vec<u8> {
    let blank = |b: &u8| b == &b' ' || b == &b'\t';
    let lead = line.iter().take_while(|b| blank(b)).count();
    let mut at = lead;
    match line.get(at) {
        None | Some(b'\n' | b'\r' | b'%') => return line.to_vec(),
        Some(b'/') => at += 1 + line[at + 1..].iter().take_while(|b| blank(b)).count(),
        _ => {}
    }
    let head = &line[..at];
    let mut rest = &line[at..];
    if matches!(rest.first(), Some(b'N' | b'n')) {
        // LinuxCNC reads blanks inside a word: `N 1 0` is N10
        let digits = rest[1..]
            .iter()
            .take_while(|b| b.is_ascii_digit() || blank(b))
            .count();
        if rest.get(1 + digits) == Some(&b'.') {
            return line.to_vec();
        }
        rest = &rest[1 + digits..];
    }
    let mut out = head.to_vec();
    out.extend_from_slice(format!("N{number} ").as_bytes());
    out.extend_from_slice(rest);
    out
}

/// The line number and the block text of a line [`numbered_program`] wrote, as the interpreter
/// echoes it (`N17 G1 X0`): `(17, "G1 X0")`.
pub fn numbered_line(echo: &str) -> Option<(usize, &str)> {
    let t = echo.trim_start();
    let t = t.strip_prefix('/').map_or(t, str::trim_start);
    let t = t.strip_prefix(['N', 'n'])?;
    let digits = t.bytes().take_while(u8::is_ascii_digit).count();
    let number = t[..digits].parse().ok()?;
    Some((number, t[digits..].trim()))
}

/// The block text of `line` as [`numbered_line`] returns it for its numbered copy: the line
/// after its blanks, block-delete slash and `N` word, trimmed.
pub fn block_text(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let t = t.strip_prefix('/').map_or(t, str::trim_start);
    let t = match t.strip_prefix(['N', 'n']) {
        Some(r) => r.trim_start_matches(|c: char| c.is_ascii_digit() || c == ' ' || c == '\t'),
        None => t,
    };
    Some(t.trim())
}

/// The source line of canonical line `k` (rs274's sequence number) of a run, read from the
/// same run on the [`numbered_program`]: the block's line number is the N field of its calls
/// (`   10 N123   TURN_PROBE_ON()`). `None` unless both runs print line `k` with the same call
/// after the N field.
pub fn canonical_source_line(original: &str, numbered: &str, k: usize) -> Option<usize> {
    // (N field, call) of line k
    let find = |out: &str| -> Option<(String, String)> {
        out.lines().find_map(|l| {
            let t = l.trim_start();
            let digits = t.bytes().take_while(u8::is_ascii_digit).count();
            if digits == 0 || t[..digits].parse::<usize>().ok()? != k {
                return None;
            }
            let rest = t[digits..].trim_start().strip_prefix('N')?;
            // from six digits on rs274 prints no blank before the call (`N100000TURN_PROBE_ON(`)
            let end = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .unwrap_or(rest.len());
            Some((rest[..end].to_string(), rest[end..].trim().to_string()))
        })
    };
    let (_, call) = find(original)?;
    let (field, numbered_call) = find(numbered)?;
    (call == numbered_call).then_some(())?;
    field.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_block_line_gets_its_number_and_keeps_its_text() {
        let p = b"%\nG21 G90\n\n  /G1 X10\r\nN0040 G0 Z5\nn 5 0 (c)\n/ N7 M3\nN10.1 G1 X1\n%\n";
        let n = numbered_program(p).unwrap();
        assert_eq!(
            String::from_utf8(n).unwrap(),
            "%\nN2 G21 G90\n\n  /N4 G1 X10\r\nN5 G0 Z5\nN6 (c)\n/ N7 M3\nN10.1 G1 X1\n%\n"
        );
        // no final newline: the last line is numbered all the same
        assert_eq!(numbered_program(b"G0 X1").unwrap(), b"N1 G0 X1".to_vec());
    }

    #[test]
    fn an_echo_gives_back_line_and_text() {
        assert_eq!(numbered_line("N12 G33 X5 K1"), Some((12, "G33 X5 K1")));
        assert_eq!(numbered_line("  /N3 G1 X1 "), Some((3, "G1 X1")));
        assert_eq!(numbered_line("G1 X1"), None);
        assert_eq!(numbered_line("N G1"), None);
        assert_eq!(block_text(" /N0040 G1 X1 "), Some("G1 X1"));
        assert_eq!(block_text("G1 X1"), Some("G1 X1"));
    }

    #[test]
    fn a_canonical_line_is_traced_to_its_source_line_by_the_numbered_run() {
        let original = "    9 N.....  SET_FEED_RATE(10.0000)\n   10 N.....  TURN_PROBE_ON()\n";
        let numbered = "    9 N3     SET_FEED_RATE(10.0000)\n   10 N123   TURN_PROBE_ON()\n";
        assert_eq!(canonical_source_line(original, numbered, 10), Some(123));
        assert_eq!(canonical_source_line(original, numbered, 9), Some(3));
        assert_eq!(canonical_source_line(original, numbered, 11), None);
        // another call on that line: the runs differ, nothing is claimed
        let other = "   10 N123   TURN_PROBE_OFF()\n";
        assert_eq!(canonical_source_line(original, other, 10), None);
        // no line number in the N field
        assert_eq!(canonical_source_line(original, original, 10), None);
        // six digits: no blank before the call
        let long = "   10 N100000TURN_PROBE_ON()\n";
        assert_eq!(canonical_source_line(original, long, 10), Some(100000));
    }

    #[test]
    fn a_program_longer_than_linuxcnc_numbers_is_not_numbered() {
        let p = "G0 X1\n".repeat(MAX_LINE_NUMBER + 1);
        assert!(numbered_program(p.as_bytes()).is_none());
        let p = "G0 X1\n".repeat(MAX_LINE_NUMBER);
        assert!(numbered_program(p.as_bytes()).is_some());
    }
}
