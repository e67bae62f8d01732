//! Reading a LinuxCNC tool table (`.tbl`), for the tool lengths that `G43` applies.
//!
//! **What it is for**: the rewriter must know where the machine is when a program runs with a
//! tool length offset (`T1 M6 G43`): `machine Z = program Z + work offset + tool length`
//! ([`super::offsets`]). This module reads the table LinuxCNC itself loads, so the lengths are
//! the ones the machine uses, and merges them into [`Offsets`] ([`Offsets::with_tool_table`]).
//! **Not for**: writing or editing tables, tool-changer pockets, wear offsets, or anything
//! LinuxCNC only knows at run time (`G10 L1/L10/L11` changing the table, `G43.1` dynamic
//! offsets).
//!
//! It follows LinuxCNC's documentation, *Tool Compensation*, section "Tool Table Format"
//! (docs/src/gcode/tool-compensation.adoc): one tool per line, words separated by blanks, each a
//! letter and its value without a blank between: `T` tool number, `P` pocket, `X Y Z A B C U V
//! W` offsets, `D` diameter, `I` front angle, `J` back angle, `Q` orientation; `;` starts a
//! comment to the end of the line; letters in either case. Values are in the **machine's
//! units** (the `[TRAJ] LINEAR_UNITS` of the INI file), whatever G20/G21 a program uses: hence
//! the `units` argument. A, B, C are angles and are not converted.
//!
//! Checked against LinuxCNC 2.9's `rs274 -t tool.tbl` (whose stand-alone machine is in inches):
//! `T1 P1 Z85.25 D6`, then `T1 M6 G43` prints `USE_TOOL_LENGTH_OFFSET(0 0 2165.3500, …)`, the
//! value [`parse_tool_table`] gives with `MachineUnits::Inch` (test below); and on 60 random
//! tables (`tests/data/tooltable_random_rs274.tsv`: word order, case, signs, exponents,
//! comments) every length agrees with the one rs274 applies.
//!
//! Where LinuxCNC is lenient, this reader refuses with line and column, because a table read
//! differently from the controller moves the tool by the difference: LinuxCNC skips a line
//! with an unknown letter or an unreadable value ("Unrecognized line skipped"), reads `Z1.5.2`
//! as 1.5, `T1.5` as tool 1 and `T1P1Z7` as something else entirely, takes the later of two
//! `Z` words and one of two lines for the same tool. Here each of those is an error, as is a
//! line without a `T` word. Exponents (`Z1e1`) are read as LinuxCNC's `strtod` reads them.
//! The documentation calls `P` required and pockets unique; `rs274` reads a line without `P`,
//! and pockets do not change a tool's length, so neither is checked here.

use super::offsets::Offsets;
use std::collections::BTreeMap;

/// The machine's linear units, in which a LinuxCNC tool table is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MachineUnits {
    Mm,
    Inch,
}

impl MachineUnits {
    fn to_mm(self) -> f64 {
        match self {
            MachineUnits::Mm => 1.0,
            MachineUnits::Inch => 25.4,
        }
    }
}

/// The axes of the offset words, in this order in [`ToolEntry::offsets`].
pub const OFFSET_AXES: [u8; 9] = *b"XYZABCUVW";

/// One tool of the table; linear values in mm, angles in degrees.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolEntry {
    pub tool: u32,
    pub pocket: Option<u32>,
    /// Offsets X Y Z A B C U V W ([`OFFSET_AXES`]): X Y Z U V W in mm, A B C in degrees;
    /// 0 where the table gives none.
    pub offsets: [f64; 9],
    pub diameter_mm: Option<f64>,
    pub front_angle: Option<f64>,
    pub back_angle: Option<f64>,
    pub orientation: Option<u32>,
    /// The comment after `;`, if any (lossy UTF-8, trimmed).
    pub comment: Option<String>,
    /// 1-based line of the table.
    pub line: usize,
}

impl ToolEntry {
    /// The tool length (Z offset) in mm.
    pub fn z_length_mm(&self) -> f64 {
        self.offsets[2]
    }

    /// The axes other than Z with a non-zero offset (G43 applies them too).
    pub fn non_z_offsets(&self) -> Vec<char> {
        OFFSET_AXES
            .iter()
            .zip(self.offsets)
            .filter(|(a, v)| **a != b'Z' && *v != 0.0)
            .map(|(a, _)| *a as char)
            .collect()
    }
}

/// The tools of a table, by tool number.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ToolTable {
    pub tools: BTreeMap<u32, ToolEntry>,
}

/// A line of the table that cannot be read; `line` and `column` are 1-based (bytes).
#[derive(Debug, Clone, PartialEq)]
pub struct ToolTableError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl std::fmt::Display for ToolTableError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.message)
    }
}

impl std::error::Error for ToolTableError {}

fn is_blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | 0x0b | 0x0c)
}

/// Reads a LinuxCNC tool table written in `units`.
pub fn parse_tool_table(text: &[u8], units: MachineUnits) -> Result<ToolTable, ToolTableError> {
    let mut table = ToolTable::default();
    for (ln, raw) in text.split(|&b| b == b'\n').enumerate() {
        let line_no = ln + 1;
        let e = |col: usize, message: String| ToolTableError {
            line: line_no,
            column: col + 1,
            message,
        };
        let (data, comment) = match raw.iter().position(|&b| b == b';') {
            Some(p) => (&raw[..p], Some(&raw[p + 1..])),
            None => (raw, None),
        };
        let mut words: [Option<(usize, &[u8])>; 26] = [None; 26];
        let mut any = false;
        let mut i = 0;
        while i < data.len() {
            if is_blank(data[i]) {
                i += 1;
                continue;
            }
            let start = i;
            while i < data.len() && !is_blank(data[i]) {
                i += 1;
            }
            let word = &data[start..i];
            let letter = word[0].to_ascii_uppercase();
            if !b"TPXYZABCUVWDIJQ".contains(&letter) {
                let shown = String::from_utf8_lossy(&word[..1]).into_owned();
                return Err(e(
                    start,
                    format!(
                        "'{shown}' is not a tool table word (T P X Y Z A B C U V W D I J Q); \
                         LinuxCNC skips such a line"
                    ),
                ));
            }
            if word.len() == 1 {
                return Err(e(
                    start,
                    format!(
                        "{} without a value (no blank may stand between the letter and its value)",
                        letter as char
                    ),
                ));
            }
            let slot = &mut words[(letter - b'A') as usize];
            if slot.is_some() {
                return Err(e(
                    start,
                    format!("two {} words on one line", letter as char),
                ));
            }
            *slot = Some((start, &word[1..]));
            any = true;
        }
        if !any {
            continue; // blank or comment-only line
        }
        let get = |l: u8| words[(l - b'A') as usize];
        let real = |l: u8| -> Result<Option<f64>, ToolTableError> {
            let Some((col, v)) = get(l) else {
                return Ok(None);
            };
            std::str::from_utf8(v)
                .ok()
                .filter(|s| {
                    s.bytes().all(|b| {
                        b.is_ascii_digit() || matches!(b, b'.' | b'+' | b'-' | b'e' | b'E')
                    })
                })
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|x| x.is_finite())
                .map(Some)
                .ok_or_else(|| {
                    e(
                        col,
                        format!(
                            "{}{} is not a number",
                            l as char,
                            String::from_utf8_lossy(v)
                        ),
                    )
                })
        };
        let int = |l: u8| -> Result<Option<u32>, ToolTableError> {
            let Some((col, v)) = get(l) else {
                return Ok(None);
            };
            let digits = v.strip_prefix(b"+").unwrap_or(v);
            std::str::from_utf8(digits)
                .ok()
                .filter(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|s| s.parse::<u32>().ok())
                .map(Some)
                .ok_or_else(|| {
                    e(
                        col,
                        format!(
                            "{}{} is not a whole number ≥ 0",
                            l as char,
                            String::from_utf8_lossy(v)
                        ),
                    )
                })
        };
        let Some(tool) = int(b'T')? else {
            return Err(e(
                0,
                "a tool line without a T word (tool number)".to_string(),
            ));
        };
        let mut offsets = [0.0; 9];
        for (k, &axis) in OFFSET_AXES.iter().enumerate() {
            if let Some(v) = real(axis)? {
                offsets[k] = if matches!(axis, b'A' | b'B' | b'C') {
                    v
                } else {
                    v * units.to_mm()
                };
            }
        }
        let entry = ToolEntry {
            tool,
            pocket: int(b'P')?,
            offsets,
            diameter_mm: real(b'D')?.map(|d| d * units.to_mm()),
            front_angle: real(b'I')?,
            back_angle: real(b'J')?,
            orientation: int(b'Q')?,
            comment: comment
                .map(|c| String::from_utf8_lossy(c).trim().to_string())
                .filter(|c| !c.is_empty()),
            line: line_no,
        };
        if let Some(prev) = table.tools.get(&tool) {
            let col = get(b'T').map(|(c, _)| c).unwrap_or(0);
            return Err(e(
                col,
                format!(
                    "tool {tool} is also on line {}: which one LinuxCNC uses is not documented",
                    prev.line
                ),
            ));
        }
        table.tools.insert(tool, entry);
    }
    Ok(table)
}

/// Reads a tool table file; errors are `path:line:column: message`.
pub fn load_tool_table(path: &std::path::Path, units: MachineUnits) -> Result<ToolTable, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    parse_tool_table(&bytes, units).map_err(|e| format!("{}:{e}", path.display()))
}

impl Offsets {
    /// These offsets with the tool lengths of a LinuxCNC tool table added.
    ///
    /// - A tool in both the offsets file and the table must have the same length (to 1e-9 mm):
    ///   otherwise it is an error naming both, since only one of them is what the machine uses.
    /// - A tool with a non-zero offset on another axis (X, Y, …: a lathe tool or a probe) is
    ///   left out, because `G43` applies those offsets too and the offsets model here is along
    ///   Z only: a `G43` with that tool is then refused like any tool of unknown length. The
    ///   returned notes name each tool left out.
    pub fn with_tool_table(mut self, table: &ToolTable) -> Result<(Offsets, Vec<String>), String> {
        let mut notes = Vec::new();
        for (t, entry) in &table.tools {
            let non_z = entry.non_z_offsets();
            if !non_z.is_empty() {
                let axes: String = non_z.iter().collect();
                notes.push(format!(
                    "tool {t} (tool table line {}) has offsets along {axes}, which G43 applies \
                     and mtec does not model: left out, so G43 with tool {t} is refused",
                    entry.line
                ));
                continue;
            }
            let len = entry.z_length_mm();
            if let Some(&have) = self.tool_length_mm.get(t) {
                if (have - len).abs() > 1e-9 * have.abs().max(1.0) {
                    return Err(format!(
                        "tool {t}: the offsets file gives length {have} mm, the tool table \
                         (line {}) {len} mm; remove one of them",
                        entry.line
                    ));
                }
            }
            self.tool_length_mm.insert(*t, len);
        }
        Ok((self, notes))
    }
}

/// A tool table's text with its lengths (X Y Z U V W offsets and the D diameter) divided by
/// 25.4, everything else kept: stand-alone `rs274` (LinuxCNC 2.9) reads tool tables as inches
/// whatever the machine's units, so a metric table is handed to it converted. Comments after
/// `;` are kept as they are.
pub fn to_inch_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 64);
    for line in text.split_inclusive('\n') {
        let (code, rest) = match line.find(';') {
            Some(i) => line.split_at(i),
            None => {
                let body = line.trim_end_matches(['\n', '\r']);
                (body, &line[body.len()..])
            }
        };
        let mut first = true;
        for word in code.split_whitespace() {
            if !first {
                out.push(' ');
            }
            first = false;
            let mut chars = word.chars();
            let letter = chars.next().map(|c| c.to_ascii_uppercase());
            let value: Option<f64> = chars.as_str().parse().ok();
            match (letter, value) {
                (Some(l @ ('X' | 'Y' | 'Z' | 'U' | 'V' | 'W' | 'D')), Some(v)) => {
                    out.push(l);
                    out.push_str(&format!("{}", v / 25.4));
                }
                _ => out.push_str(word),
            }
        }
        if !rest.is_empty() && !rest.starts_with(['\n', '\r']) && !first {
            out.push(' ');
        }
        out.push_str(rest);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_match_rs274() {
        // rs274 -g -t tool.tbl on "G21 / T1 M6 / G43 / G0 X0 Y0 Z10 / T7 M6 / G43 / G0 Z10 /
        // G43 H4 / G0 Z11" printed (its stand-alone machine is in inches):
        //   USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 2165.3500, …)   (T1)
        //   USE_TOOL_LENGTH_OFFSET(2.5400 0.0000 -38.1000, …)    (T7)
        //   USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 2590.8000, …)   (H4)
        let text = b"T1 P1 Z85.25 D6 ;comment\nT4 P2 Z102.0 D10\nt7 p3 z-1.5 x0.1\n";
        let t = parse_tool_table(text, MachineUnits::Inch).unwrap();
        for (tool, x, z) in [(1, 0.0, 2165.35), (7, 2.54, -38.1), (4, 0.0, 2590.8)] {
            let e = &t.tools[&tool];
            assert!((e.z_length_mm() - z).abs() < 5e-5, "T{tool}: {e:?}");
            assert!((e.offsets[0] - x).abs() < 5e-5, "T{tool}: {e:?}");
        }
        let e = &t.tools[&1];
        assert_eq!(e.pocket, Some(1));
        assert_eq!(e.diameter_mm, Some(6.0 * 25.4));
        assert_eq!(e.comment.as_deref(), Some("comment"));
        assert_eq!(e.line, 1);
        // the same table on a millimetre machine
        let t = parse_tool_table(text, MachineUnits::Mm).unwrap();
        assert_eq!(t.tools[&1].z_length_mm(), 85.25);
        // every letter, comment-only and blank lines, exponents, CRLF
        let t = parse_tool_table(
            b"; header\r\n\r\nT2 P5 X0 Y0 Z+2. A1 B2 C3 U0 V0 W0 D6 I10 J20 Q3;c\r\nT3 Z1e1\n",
            MachineUnits::Mm,
        )
        .unwrap();
        let e = &t.tools[&2];
        assert_eq!(e.offsets, [0.0, 0.0, 2.0, 1.0, 2.0, 3.0, 0.0, 0.0, 0.0]);
        assert_eq!(
            (e.front_angle, e.back_angle, e.orientation),
            (Some(10.0), Some(20.0), Some(3))
        );
        assert_eq!(e.non_z_offsets(), vec!['A', 'B', 'C']);
        assert_eq!(t.tools[&3].z_length_mm(), 10.0);
        assert_eq!(t.tools[&3].pocket, None);
    }

    #[test]
    fn random_tables_agree_with_rs274() {
        let text = include_str!("../../tests/data/tooltable_random_rs274.tsv");
        let mut n = 0;
        for row in text.lines().filter(|l| !l.starts_with("%%")) {
            let f: Vec<&str> = row.split('\t').collect();
            assert!(f[3].is_empty(), "{row}");
            let table = f[0].replace("\\n", "\n");
            let t = parse_tool_table(table.as_bytes(), MachineUnits::Inch)
                .unwrap_or_else(|e| panic!("{table:?}: {e}"));
            let tools = f[1].split_whitespace().map(|t| t.parse::<u32>().unwrap());
            let zs = f[2].split_whitespace().map(|z| z.parse::<f64>().unwrap());
            for (tool, z) in tools.zip(zs) {
                let got = t.tools[&tool].z_length_mm();
                assert!(
                    (got - z).abs() <= 5e-5,
                    "{table:?} T{tool}: mtec {got}, rs274 {z}"
                );
                n += 1;
            }
        }
        assert!(n >= 150, "{n} tools");
    }

    #[test]
    fn bad_lines_are_located() {
        // (table, line, column, message fragment); rs274's reading noted where it is lenient
        for (text, line, col, frag) in [
            ("T1 P1 Z1.5\nT1 P2 Z2.5\n", 2, 1, "also on line 1"), // rs274 takes one silently
            ("T1 P1 Z1.5 K3\n", 1, 12, "not a tool table word"),  // rs274 skips the line
            ("T1 P1 Zabc\n", 1, 7, "not a number"),               // rs274 skips the line
            ("T1 P1 Z1.5.2\n", 1, 7, "not a number"),             // rs274 reads 1.5
            ("P1 Z1.5\n", 1, 1, "without a T word"),              // rs274 ignores the line
            ("  t1   p1  z  1.5\n", 1, 12, "without a value"),    // rs274 skips the line
            ("T1 P1 Z1 Z2\n", 1, 10, "two Z words"),              // rs274 takes Z2
            ("T1.5 P1 Z1\n", 1, 1, "whole number"),               // rs274 reads tool 1
            ("T1P1Z7\n", 1, 1, "whole number"),                   // rs274 reads Z0
            ("T-1 P1 Z1\n", 1, 1, "whole number"),
            ("T1 Zinf\n", 1, 4, "not a number"),
            ("T1 ZNaN\n", 1, 4, "not a number"),
            (
                "T1 Z1\n\nT2 P1 Z1 garbage\n",
                3,
                10,
                "not a tool table word",
            ),
            ("T1 Q1.5\n", 1, 4, "whole number"),
            ("T1 Z\u{e9}\n", 1, 4, "not a number"),
        ] {
            let e = parse_tool_table(text.as_bytes(), MachineUnits::Mm).unwrap_err();
            assert_eq!((e.line, e.column), (line, col), "{text:?}: {e}");
            assert!(e.message.contains(frag), "{text:?}: {e}");
        }
    }

    #[test]
    fn merge_into_offsets() {
        let table = parse_tool_table(
            b"T1 Z85.25\nT4 Z102\nT9 X1.5 Z50 ;lathe-like\n",
            MachineUnits::Mm,
        )
        .unwrap();
        let mut o = Offsets::default();
        o.tool_length_mm.insert(4, 102.0); // equal: fine
        o.tool_length_mm.insert(5, 7.0); // only in the file: kept
        let (m, notes) = o.clone().with_tool_table(&table).unwrap();
        assert_eq!(m.tool_length_mm[&1], 85.25);
        assert_eq!(m.tool_length_mm[&4], 102.0);
        assert_eq!(m.tool_length_mm[&5], 7.0);
        assert!(!m.tool_length_mm.contains_key(&9));
        assert_eq!(notes.len(), 1);
        assert!(
            notes[0].contains("tool 9") && notes[0].contains("along X"),
            "{notes:?}"
        );
        // a conflict is refused, naming both values
        o.tool_length_mm.insert(1, 85.0);
        let err = o.with_tool_table(&table).unwrap_err();
        assert!(
            err.contains("tool 1") && err.contains("85.25") && err.contains("85 mm"),
            "{err}"
        );
        // an inch table against an mm offsets file: equal after conversion
        let t = parse_tool_table(b"T1 Z85.25\n", MachineUnits::Inch).unwrap();
        let mut o = Offsets::default();
        o.tool_length_mm.insert(1, 2165.35);
        assert!(o.with_tool_table(&t).is_ok());
    }

    #[test]
    fn files_are_named_in_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("tool.tbl");
        std::fs::write(&p, "T1 P1 Z10\nT2 P2 Zx\n").unwrap();
        let e = load_tool_table(&p, MachineUnits::Mm).unwrap_err();
        assert!(e.ends_with("tool.tbl:2:7: Zx is not a number"), "{e}");
        std::fs::write(&p, "T1 P1 Z10\n").unwrap();
        assert_eq!(
            load_tool_table(&p, MachineUnits::Mm).unwrap().tools.len(),
            1
        );
        assert!(load_tool_table(&dir.path().join("none.tbl"), MachineUnits::Mm).is_err());
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..300)) {
            let _ = parse_tool_table(&bytes, MachineUnits::Mm);
        }

        #[test]
        fn never_panics_on_table_like_text(s in "([TPXYZABCUVWDIJQKtz][-+0-9.eE]{0,6}[ ;\n]{1,2}){0,12}") {
            if let Ok(t) = parse_tool_table(s.as_bytes(), MachineUnits::Inch) {
                for e in t.tools.values() {
                    proptest::prop_assert!(e.offsets.iter().all(|v| v.is_finite()));
                }
            }
        }
    }
}
