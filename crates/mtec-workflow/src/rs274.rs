//! `compensate gcode --flatten-with rs274`: runs LinuxCNC's interpreter on the program and turns
//! its canonical moves into a plain program ([`mtec_comp::gcode::flatten`]) for the rewriter.
//!
//! All process spawning lives here. rs274 runs in a fresh temporary folder (it rewrites its
//! parameter file on exit, so the `--var-file` and `--tool-table` given are copied there first
//! and the user's files are never touched), with the program's absolute path, and with HOME set
//! to that folder (rs274 writes its tool data to `$HOME/.tool.mmap`).

use crate::Error as CliError;
use mtec_comp::gcode::flatten::{
    axes_named, flatten, rotary_axes_named, work_offsets_from_probe, FlattenOptions, FlattenReport,
    WORK_OFFSET_PROBE,
};
use mtec_comp::gcode::offsets::Offsets;
use mtec_comp::gcode::runtime_params::{
    machine_position_parameter, machine_state_parameter, machine_units_parameter_reference,
    metric_machine_parameter, UnitsSource,
};
use mtec_comp::gcode::start_probe::{
    held_axes, probe_program, spindle_tool_probe_program, tool_length_offsets, PROBE_TOOL_LINE,
};
use mtec_comp::gcode::tooltable::MachineUnits;
use mtec_io::InputError;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How to run LinuxCNC's interpreter (`compensate gcode --flatten-with rs274`).
#[derive(Debug, Clone)]
pub struct Rs274 {
    /// The rs274 binary (default: `rs274` on PATH).
    pub bin: Option<PathBuf>,
    /// Parameter file (`-v`): work offsets and other parameters (copied, never written).
    pub var_file: Option<PathBuf>,
    /// Stop rs274 after this many seconds (a program that loops forever).
    pub timeout_s: f64,
}

impl Default for Rs274 {
    fn default() -> Self {
        Rs274 {
            bin: None,
            var_file: None,
            timeout_s: 300.0,
        }
    }
}

/// What flattening needs besides the interpreter: the tool table, the machine's units and
/// the block delete switch (shared with the rewriter).
pub struct FlattenInputs<'a> {
    pub rs274: &'a Rs274,
    pub tool_table: Option<&'a Path>,
    /// Without `tool_table`: the tool lengths of `--offsets` (`[tool_lengths_mm]`), handed to
    /// rs274 as its table. Stand-alone rs274 given no table uses a built-in one (T1 = 0.511 in):
    /// lengths no machine has, baked into every coordinate after a G43. So rs274 always gets a
    /// table, empty when the user gave no lengths: a program that selects or measures a tool
    /// then stops at that line ("Requested tool N not found in the tool table").
    pub tool_lengths_mm: &'a std::collections::BTreeMap<u32, f64>,
    /// Without `rs274.var_file`: the work offsets of `--offsets` (the system active at start
    /// and each system's entry), handed to rs274 as its parameter file. Without either, rs274
    /// starts in a system that stands for the machine's active one (G59.3, table zero), which
    /// the output never names, and a program that changes a table entry is refused: the
    /// flattened coordinates fold the change relative to a table nobody gave.
    pub start_offsets: Option<&'a Offsets>,
    pub machine_units: MachineUnits,
    /// `Some(true)`: block delete on (`-b`).
    pub block_delete: Option<bool>,
}

/// A temporary folder removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> std::io::Result<Self> {
        let base = std::env::temp_dir();
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        for k in 0..100u32 {
            let p = base.join(format!("mtec-flatten-{}-{nanos}-{k}", std::process::id()));
            match std::fs::create_dir(&p) {
                Ok(()) => return Ok(TempDir(p)),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
        Err(std::io::Error::other("cannot create a temporary folder"))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn find_on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

const INSTALL_HINT: &str = "install LinuxCNC's interpreter (Debian/Ubuntu package linuxcnc-uspace: apt install linuxcnc-uspace) or give its path with --rs274";

/// rs274's output is read into memory up to this size (about 6 M canonical calls).
const MAX_OUTPUT_BYTES: u64 = 512 << 20;

struct Run {
    status: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs `rs274 -g [flags] file` in `dir`, with a time limit.
fn run_rs274(
    bin: &Path,
    dir: &Path,
    flags: &[String],
    file: &Path,
    timeout: Duration,
) -> Result<Run, CliError> {
    let mut child = Command::new(bin)
        .current_dir(dir)
        // rs274 keeps its tool data in $HOME/.tool.mmap, truncated at start: concurrent runs
        // with one HOME read each other's tool tables. Each run gets its own.
        .env("HOME", dir)
        .arg("-g")
        .args(flags)
        .arg(file)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                CliError::usage(format!("{} not found: {INSTALL_HINT}", bin.display()))
            } else {
                CliError::usage(format!("cannot run {}: {e}", bin.display()))
            }
        })?;
    let mut out = child.stdout.take();
    let mut err = child.stderr.take();
    let too_long = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&too_long);
    let t_out = std::thread::spawn(move || {
        let mut v = Vec::new();
        if let Some(o) = out.as_mut() {
            let _ = o.take(MAX_OUTPUT_BYTES + 1).read_to_end(&mut v);
            if v.len() as u64 > MAX_OUTPUT_BYTES {
                flag.store(true, Ordering::Relaxed);
            }
        }
        v
    });
    let t_err = std::thread::spawn(move || {
        let mut v = Vec::new();
        if let Some(e) = err.as_mut() {
            let _ = e.take(1 << 20).read_to_end(&mut v);
        }
        v
    });
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait()? {
            break s;
        }
        if too_long.load(Ordering::Relaxed) {
            let _ = child.kill();
            let _ = child.wait();
            let _ = t_out.join();
            let _ = t_err.join();
            return Err(CliError::usage(format!(
                "rs274 printed more than {} MB of canonical calls (a program that loops forever?)",
                MAX_OUTPUT_BYTES >> 20
            )));
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            let _ = t_out.join();
            let _ = t_err.join();
            return Err(CliError::usage(format!(
                "rs274 did not finish within {} s (a program that loops forever?); raise --rs274-timeout-s",
                timeout.as_secs_f64()
            )));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = t_out.join().unwrap_or_default();
    let stderr = t_err.join().unwrap_or_default();
    Ok(Run {
        status: status.code(),
        stdout: String::from_utf8_lossy(&stdout).into_owned(),
        stderr: String::from_utf8_lossy(&stderr).into_owned(),
    })
}

/// rs274's error message: its standard error without the `executing` banner.
fn rs274_message(stderr: &str) -> String {
    let lines: Vec<&str> = stderr
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && *l != "executing")
        .collect();
    if lines.is_empty() {
        "no message".into()
    } else {
        lines.join(" | ")
    }
}

/// The name of the spindle-tool probe's run (its table gets the probe tool).
const SPINDLE_TOOL_PROBE: &str = "spindle-tool-probe";

/// A G word of a program, outside comments.
#[derive(Debug, Clone, Copy)]
struct GWord {
    /// Line and column of the G, 1-based.
    line: usize,
    column: usize,
    /// The code ×10: `G043`, `g 43` and `G43.0` are all 430, `G41.1` is 411.
    code: i64,
    /// Whether the block has an `H` word.
    has_h: bool,
    /// The block's `L` word, when it is a plain number.
    l: Option<i64>,
}

/// A plain number after `letter` in a comment-free block (blanks allowed), if any.
fn word_value(code: &str, letter: char) -> Option<f64> {
    let k = code.find(|c: char| c.eq_ignore_ascii_case(&letter))?;
    let number: String = code[k + 1..]
        .chars()
        .filter(|c| !c.is_whitespace())
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    number.parse().ok()
}

/// Every G word of `program` outside comments. Where refusals after an rs274 run point.
fn g_words(program: &[u8]) -> Vec<GWord> {
    let text = String::from_utf8_lossy(program);
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = without_comments(line);
        let has_h = code.chars().any(|c| c.eq_ignore_ascii_case(&'h'));
        let l = word_value(&code, 'l').map(|v| v.round() as i64);
        for (k, c) in code.char_indices() {
            if !c.eq_ignore_ascii_case(&'g') {
                continue;
            }
            let number: String = code[k + 1..]
                .chars()
                .filter(|c| !c.is_whitespace())
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            if let Ok(v) = number.parse::<f64>() {
                out.push(GWord {
                    line: i + 1,
                    column: code[..k].chars().count() + 1,
                    code: (v * 10.0).round() as i64,
                    has_h,
                    l,
                });
            }
        }
    }
    out
}

/// What flattening does about the G92 offset LinuxCNC keeps between programs (stand-alone
/// rs274 always starts with none; mtec does not know the machine's): the original's first
/// G92-family word before its first move being G92.1/G92.2 gives that cancel for the preamble;
/// no G92-family word, or a G92 that sets the offset from the current position, needs none
/// (the kept offset carries through both programs alike); a cancel after the first move, or
/// G52/G92.3 (which set the offset outright) with no cancel first, is refused: the flattened
/// program would keep a kept offset that the original drops.
fn g92_family(input: &Path, program: &[u8]) -> Result<Option<&'static str>, CliError> {
    let words = g_words(program);
    // moves: G0–G3, splines, G28/G30, threading, probing, canned cycles (not G80)
    let motion = |w: &GWord| matches!(w.code, 0 | 10 | 20 | 30 | 50 | 51 | 52 | 280 | 300 | 330 | 331 | 382..=385 | 730 | 740 | 760 | 810..=890);
    let first_motion = words.iter().find(|w| motion(w)).map(|w| w.line);
    // a G92.x runs before the move of its own block (LinuxCNC's order of execution)
    let before_motion = |w: &GWord| first_motion.is_none_or(|m| w.line <= m);
    let family = |w: &GWord| matches!(w.code, 520 | 920 | 921 | 922 | 923);
    let cancel = words
        .iter()
        .find(|w| family(w))
        .filter(|w| matches!(w.code, 921 | 922) && before_motion(w))
        .map(|w| if w.code == 921 { "G92.1" } else { "G92.2" });
    if cancel.is_none() {
        if let Some(w) = words
            .iter()
            .find(|w| matches!(w.code, 520 | 921 | 922 | 923))
        {
            return Err(InputError::at(input, w.line, w.column, "this G52/G92.x replaces the G92 offset that LinuxCNC keeps between programs, which stand-alone rs274 does not have: the flattened program could keep an offset the original drops. Put G92.1 before the first move (or compensate without flattening)").into());
        }
    }
    Ok(cancel)
}

/// The first `G43` block without an `H` word (not G43.1/G43.2): line and column.
fn bare_g43(program: &[u8]) -> Option<(usize, usize)> {
    g_words(program)
        .into_iter()
        .find(|w| w.code == 430 && !w.has_h)
        .map(|w| (w.line, w.column))
}

/// A line with its `( … )` comments blanked and cut at a `;` comment (columns kept).
fn without_comments(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut depth = 0;
    for c in line.chars() {
        match c {
            ';' if depth == 0 => break,
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            _ if depth == 0 => {
                out.push(c);
                continue;
            }
            _ => {}
        }
        out.push(' ');
    }
    out
}

/// The length (inches) a tool not in `--offsets` gets in the table mtec makes without
/// `--tool-table`: `T5 M6` then needs the tool in the table (rs274 stops at "Requested tool 5
/// not found" otherwise), while a length offset that uses it must not pass unnoticed, so it is
/// absurd (254 m) and any offset of 5000 program units or more is refused
/// ([`unknown_tool_length_used`]). Found 2026-11-28: public programs with a plain `T1` and no
/// G43 were refused by flattening only.
const UNKNOWN_TOOL_LENGTH_IN: f64 = 9999.125;

/// A LinuxCNC tool table of `lengths` (tool → length in mm), in inches as stand-alone rs274
/// reads it; each tool in the pocket of its number; tools 1–999 that `lengths` lacks get
/// [`UNKNOWN_TOOL_LENGTH_IN`].
fn tool_table_in_inches(lengths: &std::collections::BTreeMap<u32, f64>) -> String {
    (1..1000u32)
        .chain(lengths.keys().copied().filter(|&t| t >= 1000))
        .map(|t| match lengths.get(&t) {
            Some(mm) => format!("T{t} P{t} Z{} ;\n", mm / 25.4),
            None => format!("T{t} P{t} Z{UNKNOWN_TOOL_LENGTH_IN} ;\n"),
        })
        .collect()
}

/// The canonical line (rs274's sequence number) of the first tool length offset that uses a
/// length of [`UNKNOWN_TOOL_LENGTH_IN`] (5000 program units or more on any axis).
fn unknown_tool_length_used(canon: &str) -> Option<usize> {
    canon.lines().find_map(|l| {
        let (head, args) = l.split_once("USE_TOOL_LENGTH_OFFSET(")?;
        let huge = args
            .split([',', ' ', ')'])
            .filter_map(|v| v.parse::<f64>().ok())
            .any(|v| v.abs() >= 5000.0);
        huge.then(|| head.split_whitespace().next()?.parse().ok())?
    })
}

/// The canonical numbers of the tool length offsets (`USE_TOOL_LENGTH_OFFSET`) taken after an
/// M61 (`CHANGE_TOOL_NUMBER`) with no tool change (`CHANGE_TOOL`) between. For a G43 without H
/// there, stand-alone rs274 takes the length of the tool loaded before the M61 and LinuxCNC the
/// M61 tool's (checked in LinuxCNC's simulation, 2026-11-28).
fn offsets_after_m61(canon: &str) -> Vec<usize> {
    let mut after_m61 = false;
    let mut out = Vec::new();
    for l in canon.lines() {
        if l.contains("CHANGE_TOOL_NUMBER(") {
            after_m61 = true;
        } else if l.contains("CHANGE_TOOL(") {
            after_m61 = false;
        } else if after_m61 && l.contains("USE_TOOL_LENGTH_OFFSET(") {
            if let Some(k) = l.split_whitespace().next().and_then(|k| k.parse().ok()) {
                out.push(k);
            }
        }
    }
    out
}

/// Where in `program` rs274 stopped: rs274 prints the offending line last on stderr; when
/// exactly one line of the program reads the same (blanks around it ignored), its 1-based line
/// and the column of the first non-blank, or of the character a "Bad character 'c' used" names.
fn rs274_error_at(program: &[u8], stderr: &str) -> Option<(usize, usize)> {
    let last = last_line(stderr)?;
    let text = String::from_utf8_lossy(program);
    let mut found = text.lines().enumerate().filter(|(_, l)| l.trim() == last);
    let (i, line) = found.next()?;
    if found.next().is_some() {
        // a tape mark is a block only where the first one is not the first line: rs274 reads
        // the program from its top, so the first `%` that is not the first line is where it
        // stopped
        if last == "%" {
            let first = text.lines().position(|l| !l.trim().is_empty())?;
            let (i, line) = text
                .lines()
                .enumerate()
                .find(|&(k, l)| k != first && l.trim() == "%")?;
            return Some((i + 1, error_column(line, stderr)));
        }
        return None;
    }
    Some((i + 1, error_column(line, stderr)))
}

/// rs274's message for a program that ends without M2, M30 or a closing `%`.
const FILE_ENDED: &str = "File ended with no percent sign or program end";

/// Where a program without an end stopped: after its last non-blank line (column 1).
fn end_of_file_at(program: &[u8], stderr: &str) -> Option<(usize, usize)> {
    if !stderr.contains(FILE_ENDED) {
        return None;
    }
    let text = String::from_utf8_lossy(program);
    let last = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .last()?
        .0;
    Some((last + 1, 1))
}

/// Where a call of an O-word that rs274 did not find was made: its message names the line
/// ("EOF in file: … seeking o-word: o<name> from line: 2"); the column is the line's first
/// non-blank character, when that line of the program calls that O-word.
fn o_word_call_at(program: &[u8], stderr: &str) -> Option<(usize, usize)> {
    let (_, after) = stderr.split_once("seeking o-word")?;
    let (name, number) = after.split_once("from line:")?;
    let name = name.trim_start_matches(':').trim().to_ascii_lowercase();
    let line: usize = number
        .trim_start()
        .split(|c: char| !c.is_ascii_digit())
        .next()?
        .parse()
        .ok()?;
    let text = String::from_utf8_lossy(program);
    let body = text.lines().nth(line.checked_sub(1)?)?;
    // the line is the program's own only if it calls that O-word (a call from another file
    // names that file's line)
    let lower = body.to_ascii_lowercase().replace(' ', "");
    if name.is_empty() || !lower.contains(&name.replace(' ', "")) || !lower.contains("call") {
        return None;
    }
    Some((line, body.len() - body.trim_start().len() + 1))
}

/// The error at `at` (line, column) of `input`, or of the file when it is not known.
fn located(input: &Path, at: Option<(usize, usize)>, message: impl Into<String>) -> InputError {
    match at {
        Some((line, column)) => InputError::at(input, line, column, message),
        None => InputError::file(input, message),
    }
}

/// The last line of rs274's standard error that is not blank, trimmed.
fn last_line(stderr: &str) -> Option<&str> {
    stderr.lines().rev().map(str::trim).find(|l| !l.is_empty())
}

/// The column of `line` where rs274's error points: the character a "Bad character 'c' used"
/// names, else the first non-blank.
fn error_column(line: &str, stderr: &str) -> usize {
    let bad = stderr
        .lines()
        .find_map(|l| l.trim().strip_prefix("Bad character '"))
        .and_then(|r| r.chars().next());
    if let Some(k) = bad.and_then(|c| line.find(|x: char| x.eq_ignore_ascii_case(&c))) {
        return line[..k].chars().count() + 1;
    }
    line.len() - line.trim_start().len() + 1
}

/// Where rs274 stopped when the text it echoes is on several lines of `program` (or on none):
/// the same run again on the program with every line numbered by its N word
/// (`mtec_comp::gcode::line_numbers`, `prepare` making the same probe of it), whose echo names
/// the line. Only a stop at the same block text with the same message counts.
fn numbered_error_at(
    program: &[u8],
    stderr: &str,
    run: impl FnOnce(&[u8]) -> Result<Run, CliError>,
) -> Option<(usize, usize)> {
    use mtec_comp::gcode::line_numbers::{block_text, numbered_line, numbered_program};
    let echo = last_line(stderr)?;
    let numbered = run(&numbered_program(program)?).ok()?;
    if numbered.status == Some(0) {
        return None;
    }
    let (line, text) = numbered_line(last_line(&numbered.stderr)?)?;
    let original = String::from_utf8_lossy(program);
    let at = original.lines().nth(line.checked_sub(1)?)?;
    // the message without the echoed block
    fn same_message(s: &str) -> Vec<&str> {
        let mut lines: Vec<&str> = s
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && *l != "executing")
            .collect();
        lines.pop();
        lines
    }
    (block_text(at)? == text
        && block_text(echo)? == text
        && same_message(stderr) == same_message(&numbered.stderr))
    .then(|| (line, error_column(at, stderr)))
}

/// A flattened program.
pub struct Flattened {
    pub text: Vec<u8>,
    pub report: FlattenReport,
    /// The work-offset table at program start (G54…G59.3, mm) as rs274 read it: the flattened
    /// program's coordinates are machine positions minus these.
    pub work_offsets_mm: [[f64; 3]; 9],
    /// Whether the work offsets at start were given (`--var-file` or `--offsets`); if not, the
    /// output names no system until the program selects one, and only G54 counts as known.
    pub start_known: bool,
}

/// Flattens `input` with rs274; returns the plain program and what flattening did.
pub fn flatten_input(input: &Path, args: &FlattenInputs) -> Result<Flattened, CliError> {
    if !(args.rs274.timeout_s.is_finite() && args.rs274.timeout_s > 0.0) {
        return Err(CliError::usage(
            "--rs274-timeout-s must be a positive number",
        ));
    }
    let bin = match &args.rs274.bin {
        Some(p) => {
            if !p.exists() {
                return Err(CliError::usage(format!(
                    "--rs274 {}: no such file; {INSTALL_HINT}",
                    p.display()
                )));
            }
            p.clone()
        }
        None => find_on_path("rs274").ok_or_else(|| {
            CliError::usage(format!(
                "--flatten-with rs274: rs274 was not found on PATH; {INSTALL_HINT}"
            ))
        })?,
    };
    let program =
        std::fs::read(input).map_err(|e| InputError::file(input, format!("cannot read: {e}")))?;
    // a parameter that reads the machine's state takes another value in stand-alone rs274: the
    // flattened path would be one the machine never runs
    if let Some((line, column, name)) = machine_state_parameter(&program) {
        return Err(InputError::at(
            input,
            line,
            column,
            format!("{name} reads the machine's state, which stand-alone rs274 does not have (it gives its own value, e.g. #<_task> = 0): the flattened path could differ from what the machine runs. Replace it with the value the machine will have, or compensate without flattening"),
        )
        .into());
    }
    // the work offsets, homes and G92 offset live in the controller's parameter file, the
    // tool geometry in its tool table, both in machine units; stand-alone rs274 reads those
    // files as inches and, without them, mtec makes them up: only an inch machine's own file
    // gives the values the machine reads (runtime_params::machine_units_parameter_reference)
    let inch = args.machine_units == MachineUnits::Inch;
    if let Some((line, column, name)) = metric_machine_parameter(&program).filter(|_| !inch) {
        return Err(InputError::at(input, line, column, format!("{name} is 1 on this metric machine and 0 in stand-alone rs274 (an inch machine): the flattened path would follow the inch branch. Write the branch the machine takes, or compensate without flattening")).into());
    }
    let offsets_unstated = args.rs274.var_file.is_none() && args.start_offsets.is_none();
    if let Some((line, column, name)) =
        machine_position_parameter(&program).filter(|_| offsets_unstated)
    {
        return Err(InputError::at(input, line, column, format!("{name} reads the position in machine coordinates, which adds the work offsets, and none were given (stand-alone rs274 would take them as 0): give them with --offsets or --var-file")).into());
    }
    let var_own = inch && args.rs274.var_file.is_some();
    let table_own = inch && args.tool_table.is_some();
    if let Some((line, column, name, source)) = machine_units_parameter_reference(&program) {
        let (own, what, file) = match source {
            UnitsSource::ParameterFile => (var_own, "a work offset, home, G92 offset or machine position (#5021-#5029, #5081-#5089, #5161-#5189, #5210-#5390)", "parameter file (--var-file)"),
            UnitsSource::ToolTable => (table_own, "the loaded tool's offsets or geometry (#5401-#5413)", "tool table (--tool-table)"),
            UnitsSource::Either => (var_own && table_own, "a parameter chosen at run time, which may be a work offset, home, G92 offset, machine position or tool geometry (#5021-#5413)", "parameter file and tool table (--var-file, --tool-table)"),
        };
        if !own {
            let given = if inch {
                "mtec has to make up without the file"
            } else {
                "(this machine's are mm)"
            };
            return Err(InputError::at(
                input,
                line,
                column,
                format!("{name} reads or sets {what}, which the controller keeps in machine units and stand-alone rs274 reads as inches {given}: the flattened path could differ from what the machine runs. Write the value itself, set offsets with G10 L2/L20, or for an inch machine give its {file} with --machine-units inch"),
            )
            .into());
        }
    }
    let abs_input = std::path::absolute(input)?;
    let tmp = TempDir::new()?;
    // stand-alone rs274 reads tool tables and parameter files as inches: a metric machine's
    // files are handed to it converted (lengths / 25.4), an inch machine's as they are
    let metric = args.machine_units == MachineUnits::Mm;
    let copy = |src: &Path, name: &str| -> Result<PathBuf, CliError> {
        let dst = tmp.0.join(name);
        let text = std::fs::read_to_string(src)
            .map_err(|e| InputError::file(src, format!("cannot read: {e}")))?;
        let text = match (metric, name.ends_with(".tbl")) {
            (false, _) => text,
            (true, true) => mtec_comp::gcode::tooltable::to_inch_text(&text),
            (true, false) => mtec_comp::gcode::flatten::var_file_to_inch(&text),
        };
        std::fs::write(&dst, text)?;
        Ok(dst)
    };
    let timeout = Duration::from_secs_f64(args.rs274.timeout_s.min(1e6));
    // the parameter file: the user's, else one made of --offsets, else the unknown start
    let unstated = args.rs274.var_file.is_none() && args.start_offsets.is_none();
    if unstated {
        let words = g_words(&program);
        if let Some(w) = words.iter().find(|w| w.code == 593) {
            return Err(InputError::at(input, w.line, w.column, "G59.3 with no --offsets or --var-file: flattening stands G59.3 for the machine's unknown active system; give the work offsets").into());
        }
    }
    let var_file = |name: &str| -> Result<PathBuf, CliError> {
        if let Some(v) = &args.rs274.var_file {
            return copy(v, name);
        }
        let dst = tmp.0.join(name);
        std::fs::write(&dst, var_file_in_inches(args.start_offsets))?;
        Ok(dst)
    };

    // 1. the work-offset table at program start, read by rs274 itself from the same var file
    let probe_flags = vec![
        "-v".to_string(),
        var_file("probe.var")?.display().to_string(),
    ];
    let probe = tmp.0.join("work-offsets.ngc");
    std::fs::write(&probe, WORK_OFFSET_PROBE)?;
    let run = run_rs274(&bin, &tmp.0, &probe_flags, &probe, timeout)?;
    if run.status != Some(0) {
        return Err(CliError::usage(format!(
            "rs274 could not read the work offsets{}: {}",
            args.rs274
                .var_file
                .as_ref()
                .map(|v| format!(" from {}", v.display()))
                .unwrap_or_default(),
            rs274_message(&run.stderr)
        )));
    }
    let table = work_offsets_from_probe(&run.stdout)
        .map_err(|e| CliError::usage(format!("rs274 work-offset probe: {e}")))?;

    // 2. the program itself; each run gets fresh copies of the tool table and parameter file
    // (rs274 writes the parameter file back when it ends)
    let program_flags = |name: &str| -> Result<Vec<String>, CliError> {
        let mut flags = Vec::new();
        flags.push("-t".to_string());
        let table = match &args.tool_table {
            Some(t) => copy(t, &format!("{name}.tbl"))?,
            None => {
                let table = tmp.0.join(format!("{name}.tbl"));
                std::fs::write(&table, tool_table_in_inches(args.tool_lengths_mm))?;
                table
            }
        };
        if name == SPINDLE_TOOL_PROBE {
            let mut text = std::fs::read_to_string(&table)?;
            if !text.is_empty() && !text.ends_with('\n') {
                text.push('\n');
            }
            text.push_str(PROBE_TOOL_LINE);
            std::fs::write(&table, text)?;
        }
        flags.push(table.display().to_string());
        flags.push("-v".to_string());
        flags.push(var_file(&format!("{name}.var"))?.display().to_string());
        if args.block_delete == Some(true) {
            flags.push("-b".to_string());
        }
        Ok(flags)
    };
    // rs274 on a variant of the program (a probe, a numbered copy): `{name}.ngc` with the
    // program's flags and its own copies of the tables
    let run_variant = |name: &str, text: &[u8]| -> Result<Run, CliError> {
        let file = tmp.0.join(format!("{name}.ngc"));
        std::fs::write(&file, text)?;
        run_rs274(&bin, &tmp.0, &program_flags(name)?, &file, timeout)
    };
    let flags = program_flags("program")?;
    let run = run_rs274(&bin, &tmp.0, &flags, &abs_input, timeout)?;
    if run.status != Some(0) {
        let mut message = format!(
            "rs274 stopped with an error (exit {}): {}",
            run.status.map_or("by a signal".into(), |c| c.to_string()),
            rs274_message(&run.stderr)
        );
        if args.tool_table.is_none() && run.stderr.contains("not found in the tool table") {
            message.push_str(" (give the controller's tool table with --tool-table, or the tool's length under [tool_lengths_mm] in --offsets: without them mtec does not let rs274 use its built-in lengths)");
        }
        // a missing O-word names its call's line; rs274 echoes the line it read last
        let at = o_word_call_at(&program, &run.stderr)
            .or_else(|| rs274_error_at(&program, &run.stderr))
            .or_else(|| {
                numbered_error_at(&program, &run.stderr, |numbered| {
                    run_variant("numbered", numbered)
                })
            })
            .or_else(|| end_of_file_at(&program, &run.stderr));
        if run.stderr.contains(FILE_ENDED) {
            message.push_str(" (add M2 at the end; a subroutine file is run by a call from a program, not on its own)");
        }
        return Err(located(input, at, message).into());
    }
    // G41/G42 take the cutter radius from the tool table (D); a table mtec made from
    // --offsets lengths (or an empty one) has none, and rs274 then offsets the path by 0
    if args.tool_table.is_none() && run.stdout.contains("cutter radius compensation on") {
        let words = g_words(&program);
        let at = words.iter().find(|w| w.code == 410 || w.code == 420);
        if at.is_some() || !words.iter().any(|w| w.code == 411 || w.code == 421) {
            let message = "G41/G42 take the cutter radius from the controller's tool table, which was not given (without it rs274 offsets the path by a radius of 0): give it with --tool-table, or write G41.1/G42.1 D<diameter>";
            return Err(located(input, at.map(|w| (w.line, w.column)), message).into());
        }
    }
    // 3. the same program started elsewhere: which axes each move leaves where the machine
    // stood, and whether anything else depends on it (mtec_comp::gcode::start_probe)
    let probe_run = run_variant("start-probe", &probe_program(&program))?;
    if probe_run.status != Some(0) {
        let message = format!(
            "cannot flatten: rs274 stopped when the program was started at another position ({}), so whether its path depends on the start position cannot be checked",
            rs274_message(&probe_run.stderr)
        );
        let at = rs274_error_at(&program, &probe_run.stderr).or_else(|| {
            numbered_error_at(&program, &probe_run.stderr, |numbered| {
                run_variant("numbered-start-probe", &probe_program(numbered))
            })
        });
        return Err(located(input, at, message).into());
    }
    // 4. the same program started with another tool in the spindle: a G43 without H (or an M6
    // without T) before the first tool change takes the tool the machine happens to hold, which
    // stand-alone rs274 takes for tool 0 (length 0)
    // the source line and column of canonical line `k` of the run: the numbered run prints the
    // block's line in the call's N field
    let source_of = |k: usize| {
        let line = mtec_comp::gcode::line_numbers::numbered_program(&program)
            .and_then(|numbered| run_variant("numbered", &numbered).ok())
            .and_then(|n| {
                mtec_comp::gcode::line_numbers::canonical_source_line(&run.stdout, &n.stdout, k)
            });
        let text = String::from_utf8_lossy(&program);
        line.and_then(|l| Some((l, error_column(text.lines().nth(l.checked_sub(1)?)?, ""))))
    };
    if let Some(k) = unknown_tool_length_used(&run.stdout).filter(|_| args.tool_table.is_none()) {
        let at = source_of(k);
        let message = "a tool length offset (G43, G43.2) uses a tool whose length is not known: give the controller's tool table with --tool-table, or the tool's length under [tool_lengths_mm] in --offsets";
        return Err(located(input, at, message).into());
    }
    let offsets = tool_length_offsets(&run.stdout);
    if !offsets.is_empty() {
        let tool_run = run_variant(SPINDLE_TOOL_PROBE, &spindle_tool_probe_program(&program))?;
        if tool_run.status != Some(0) || tool_length_offsets(&tool_run.stdout) != offsets {
            let message = "a tool length offset depends on the tool in the spindle when the program starts (a G43 without H, or an M6 without T, before the first T… M6), which mtec does not know and stand-alone rs274 takes for tool 0: write G43 Hn, or a T… M6 before it";
            return Err(located(input, bare_g43(&program), message).into());
        }
    }
    // 5. a G43 without H after an M61 Q: rs274 and LinuxCNC take different tools' lengths
    let bare_g43_lines: Vec<(usize, usize)> = g_words(&program)
        .into_iter()
        .filter(|w| w.code == 430 && !w.has_h)
        .map(|w| (w.line, w.column))
        .collect();
    if !bare_g43_lines.is_empty() {
        for k in offsets_after_m61(&run.stdout) {
            let at = match source_of(k) {
                Some((line, _)) => bare_g43_lines.iter().find(|&&(l, _)| l == line).copied(),
                // not traced to its block: any G43 without H may be it
                None => bare_g43_lines.first().copied(),
            };
            if let Some(at) = at {
                let message = "a G43 without H after an M61 Q: LinuxCNC takes the length of the M61 tool, stand-alone rs274 that of the tool loaded before, so the flattened program would move to another height: write G43 Hn (n the M61 tool), or compensate without --flatten-with (the rewriter follows M61)";
                return Err(located(input, Some(at), message).into());
            }
        }
    }
    let held = held_axes(&run.stdout, &probe_run.stdout);
    let name = input
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name: String = name
        .chars()
        .map(|c| {
            if c == '(' || c == ')' || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .take(80)
        .collect();
    // the G92 offset at start: in the controller's parameter file (rs274 reads it and
    // flattening cancels and folds it), else unknown
    let g92 = match &args.rs274.var_file {
        Some(_) => Ok(None),
        None => g92_family(input, &program),
    };
    let options = FlattenOptions {
        work_offsets_mm: Some(table),
        axes_named: axes_named(&program),
        rotary_named: rotary_axes_named(&program),
        header: Some(format!(
            "(mtec: {name} flattened by rs274 -g: LinuxCNC-only plain program; cutter comp, tool lengths and G92 baked in for the tool table given)"
        )),
        held: None,
        unstated_start_system: unstated.then_some(UNSTATED_SYSTEM),
        g92_cancel_at_start: g92.as_ref().ok().copied().flatten(),
    };
    // a refused canonical call is traced to its block: the numbered run prints the block's
    // line in the call's N field
    let cannot = |e: mtec_comp::gcode::flatten::FlattenError| {
        located(input, source_of(e.line), format!("cannot flatten: {e}"))
    };
    let (text, report) = match held {
        Ok(h) => flatten(
            &run.stdout,
            &FlattenOptions {
                held: Some(h),
                ..options
            },
        )
        .map_err(cannot)?,
        // a call flattening refuses anyway is the plainer reason (a probe, a rigid tap)
        Err(e) => return Err(cannot(flatten(&run.stdout, &options).err().unwrap_or(e)).into()),
    };
    g92?;
    // G10 L2/L20 sets an entry of a table nobody gave (P1… a system that may or may not be
    // the active one): what the flattened coordinates should fold is unknown
    if let Some(w) = g_words(&program)
        .iter()
        .find(|w| unstated && w.code == 100 && matches!(w.l, Some(2 | 20)))
    {
        return Err(InputError::at(input, w.line, w.column, "G10 L2/L20 with no --offsets or --var-file: the work-offset table and the active system at start are not known, so what the change does to later moves is not known; give the work offsets").into());
    }
    if unstated && report.table_change_folded {
        let message = "the program changes a work offset (G10 L2/L20) and the flattened program folds the change into its coordinates, relative to the work-offset table at start, which was not given: give --offsets (the setup's work offsets) or --var-file (the controller's parameter file)";
        return Err(located(
            input,
            g_words(&program)
                .iter()
                .find(|w| w.code == 100)
                .map(|w| (w.line, w.column)),
            message,
        )
        .into());
    }
    Ok(Flattened {
        text: text.into_bytes(),
        report,
        work_offsets_mm: table,
        start_known: !unstated,
    })
}

/// The work system rs274 starts in when nobody gave the machine's (G59.3: the last one a
/// program would select; one that does is refused).
const UNSTATED_SYSTEM: usize = 8;

/// A LinuxCNC parameter file (inches, as stand-alone rs274 reads it) of the work offsets at
/// start: `offsets` (the active system as 5220, each entry at 5221 + 20·k), or, without them,
/// G59.3 active and every entry zero ([`UNSTATED_SYSTEM`]).
fn var_file_in_inches(offsets: Option<&Offsets>) -> String {
    let (active, table) = match offsets {
        Some(o) => (o.active, o.work_mm),
        None => (UNSTATED_SYSTEM, [[0.0; 3]; 9]),
    };
    let mut text = format!("5220\t{}\n", active + 1);
    for (k, xyz) in table.iter().enumerate() {
        for (a, mm) in xyz.iter().enumerate() {
            text.push_str(&format!("{}\t{}\n", 5221 + 20 * k + a, mm / 25.4));
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bare_g43_is_found_past_comments_blanks_and_its_dotted_forms() {
        let p = b"G21 (G43 in a comment)\nG43.1 Z2\nG43 H1\ng0 x1 ; G43\nX2  g 4 3 (here)\n";
        assert_eq!(bare_g43(p), Some((5, 5)));
        assert_eq!(bare_g43(b"G43 H2\nG430\n"), None);
        assert_eq!(bare_g43(b"(\xc3\xa9\xc3\xa9) G043\n"), Some((1, 6)));
        let codes: Vec<i64> = g_words(b"G41.1 D6 G042 (G41)\ng 4 1 ; G42\n")
            .iter()
            .map(|w| w.code)
            .collect();
        assert_eq!(codes, [411, 420, 410]);
        let table = tool_table_in_inches(&[(1, 25.4), (12, 50.8), (1200, 101.6)].into());
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines.len(), 1000);
        assert_eq!(lines[0], "T1 P1 Z1 ;");
        assert_eq!(lines[1], "T2 P2 Z9999.125 ;");
        assert_eq!(lines[11], "T12 P12 Z2 ;");
        assert_eq!(lines[999], "T1200 P1200 Z4 ;");
        // a length offset of a made-up tool, in mm or inch, alone or added by G43.2
        let canon = "   11 N..... CHANGE_TOOL(2)\n   12 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 253977.7750, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n";
        assert_eq!(unknown_tool_length_used(canon), Some(12));
        let canon = "    9 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 1.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n   10 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 10000.1250, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n";
        assert_eq!(unknown_tool_length_used(canon), Some(10));
        let canon = "    9 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 4999.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n";
        assert_eq!(unknown_tool_length_used(canon), None);
    }
}
