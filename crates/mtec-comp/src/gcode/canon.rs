//! LinuxCNC's canonical machining calls as `rs274 -g` prints them, one call a line
//! (`   17 N..... STRAIGHT_FEED(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)`): the parsed
//! call and the error that names its line. Read by [`super::flatten`] and
//! [`super::start_probe`].

/// A canonical line that cannot be written as a plain program.
#[derive(Debug, Clone, PartialEq)]
pub struct FlattenError {
    /// The line's sequence number as rs274 printed it (the 1-based line of its output).
    pub line: usize,
    /// The call, shortened.
    pub call: String,
    pub message: String,
}

impl std::fmt::Display for FlattenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "rs274 canonical line {} `{}`: {}",
            self.line, self.call, self.message
        )
    }
}

impl std::error::Error for FlattenError {}

/// One parsed canonical line.
pub struct Call<'a> {
    pub line: usize,
    pub raw: &'a str,
    pub name: &'a str,
    /// The text between the outer parentheses.
    pub inner: &'a str,
    /// `inner` split at commas and blanks.
    pub args: Vec<&'a str>,
}

impl Call<'_> {
    pub fn err(&self, message: impl Into<String>) -> FlattenError {
        FlattenError {
            line: self.line,
            call: shorten(self.raw.trim()),
            message: message.into(),
        }
    }

    /// The first `n` arguments as finite numbers (more may follow).
    pub fn numbers(&self, n: usize) -> Result<Vec<f64>, FlattenError> {
        if self.args.len() < n {
            return Err(self.err(format!(
                "{} needs {n} arguments, rs274 printed {}",
                self.name,
                self.args.len()
            )));
        }
        self.args[..n]
            .iter()
            .map(|a| match a.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(self.err(format!("'{a}' is not a finite number"))),
            })
            .collect()
    }

    /// A 1-based index argument (work system, spindle) turned into 0-based, below `n`.
    pub fn index(&self, v: f64, n: usize) -> Result<usize, FlattenError> {
        if v.fract() == 0.0 && v >= 1.0 && v <= n as f64 {
            Ok(v as usize - 1)
        } else {
            Err(self.err(format!("index {v} is not between 1 and {n}")))
        }
    }

    /// The quoted text argument of COMMENT/MESSAGE.
    pub fn text(&self) -> &str {
        let t = self.inner.trim();
        let t = t.strip_prefix('"').unwrap_or(t);
        t.strip_suffix('"').unwrap_or(t)
    }
}

fn shorten(s: &str) -> String {
    if s.chars().count() <= 100 {
        s.to_string()
    } else {
        let mut t: String = s.chars().take(97).collect();
        t.push_str("...");
        t
    }
}

/// Splits `   17 N..... NAME(args)` into its call; `None` for a blank line.
pub fn parse_line(raw: &str, text_line: usize) -> Result<Option<Call<'_>>, FlattenError> {
    let t = raw.trim();
    if t.is_empty() {
        return Ok(None);
    }
    let bad = |m: &str| FlattenError {
        line: text_line,
        call: shorten(t),
        message: m.to_string(),
    };
    let digits = t.len() - t.trim_start_matches(|c: char| c.is_ascii_digit()).len();
    if digits == 0 {
        // rs274 numbers every canonical call; a line without the number is text the program
        // printed itself, a `(PRINT, …)` comment, which the machine's log gets, not motion
        return Ok(None);
    }
    let (line, rest) = (
        t[..digits].parse::<usize>().unwrap_or(text_line),
        t[digits..].trim_start(),
    );
    // the block's line number field: `N.....`, `N0080`, or from six digits on no blank before
    // the call (`N100000STRAIGHT_FEED(`)
    let rest = match rest.strip_prefix('N') {
        Some(r) if !r.starts_with(|c: char| c.is_ascii_uppercase() || c == '_') => r
            .trim_start_matches(|c: char| c.is_ascii_digit() || c == '.')
            .trim_start(),
        _ => rest,
    };
    let Some(open) = rest.find('(') else {
        return Err(bad("not a canonical call (no '(')"));
    };
    let name = rest[..open].trim();
    if name.is_empty()
        || !name
            .bytes()
            .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_')
    {
        return Err(bad("not a canonical call (no call name)"));
    }
    let Some(close) = rest.rfind(')').filter(|&c| c > open) else {
        return Err(bad("not a canonical call (no closing ')')"));
    };
    let inner = &rest[open + 1..close];
    let args = inner
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .collect();
    Ok(Some(Call {
        line,
        raw: t,
        name,
        inner,
        args,
    }))
}

#[cfg(test)]
mod tests {
    use super::parse_line;

    /// rs274 prints a block number of six digits or more without a blank before the call
    /// (`N100000STRAIGHT_FEED(`; found 2026-11-30 on a dxf2gcode program numbered past N99999,
    /// which flattening refused): the call is read all the same.
    #[test]
    fn calls_after_six_digit_block_numbers_are_read() {
        for raw in [
            "   11 N100000STRAIGHT_FEED(600.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "   11 N99990 STRAIGHT_FEED(600.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "   11 N..... STRAIGHT_FEED(600.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
        ] {
            let c = parse_line(raw, 11).unwrap().unwrap();
            assert_eq!(
                (c.line, c.name, c.args.len()),
                (11, "STRAIGHT_FEED", 6),
                "{raw}"
            );
            assert_eq!(c.args[0], "600.0000");
        }
        let c = parse_line("   14 N1000000ON_RESET()", 14).unwrap().unwrap();
        assert_eq!(c.name, "ON_RESET");
    }

    /// `(PRINT, hello)` makes rs274 write ` hello` between its numbered calls: not a call,
    /// and not a reason to refuse (found on LinuxCNC's tests/interp/g52 programs); a numbered
    /// line that is not a call is still refused.
    #[test]
    fn printed_text_is_skipped_and_numbered_garbage_refused() {
        assert!(matches!(parse_line(" hello", 8), Ok(None)));
        assert!(matches!(parse_line("hello (world)", 8), Ok(None)));
        let call = parse_line(
            "    8 N..... STRAIGHT_TRAVERSE(10.0000, 10.0000, 5.0000)",
            9,
        )
        .unwrap()
        .unwrap();
        assert_eq!(call.name, "STRAIGHT_TRAVERSE");
        assert!(parse_line("    9 N..... hello", 10).is_err());
    }
}
