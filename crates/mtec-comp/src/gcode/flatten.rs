//! Flattening: LinuxCNC's interpreter output (`rs274 -g`, its *canonical machining calls*)
//! written back as a plain program that the rewriter ([`super::rewrite`]) compensates.
//!
//! Programs with O-word subroutines and loops, canned cycles, cutter radius compensation, polar
//! coordinates, parameters or G92 cannot be compensated word by word. LinuxCNC's own
//! interpreter can run them to a list of straight moves and arcs; this module turns that list
//! into an equivalent program of `G0`/`G1`/`G2`/`G3` lines. It spawns nothing: the CLI runs
//! `rs274` and passes its standard output here. The result is **LinuxCNC-only**: the cutter
//! compensation and tool lengths of the tool table given to `rs274` are baked in.
//!
//! What rs274 prints, as checked with LinuxCNC 2.9.0~pre1 (Debian `linuxcnc-uspace`):
//! - one call a line: `   17 N..... STRAIGHT_FEED(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)`
//!   (sequence number, the block's line number or `N.....`, the call); numbers with 4 decimals
//!   in the program's units at that moment (inch after `USE_LENGTH_UNITS(CANON_UNITS_INCHES)`).
//! - positions are in the **current work frame without the tool length**: machine = canonical +
//!   G5x offset + G92/G52 offset + tool length offset (`SET_G5X_OFFSET`, `SET_G92_OFFSET`,
//!   `USE_TOOL_LENGTH_OFFSET`, each printed in the units in effect when it is printed and not
//!   printed again when the units change). The interpreter starts at machine 0.
//! - `ARC_FEED(first_end, second_end, first_centre, second_centre, rotation, axis_end, a, b, c)`
//!   with (first, second, axis) = (X, Y, Z) in G17, (Z, X, Y) in G18, (Y, Z, X) in G19;
//!   rotation > 0 is counter-clockwise (G3), < 0 clockwise (G2), |rotation| turns (G2/G3 P).
//! - inverse-time feed (G93) is already turned into a units-per-minute `SET_FEED_RATE` before
//!   each move, so it needs no special case.
//!
//! Decisions:
//! - **Frame**: the flattened program selects the same work system (G54…G59.3) as the original
//!   at each point and writes, for every move, the machine position minus that system's entry
//!   in the *work-offset table at program start* ([`FlattenOptions::work_offsets_mm`]). So it
//!   drives the machine to the same positions when run with the same offset table, G92/G52
//!   offsets, work offsets changed by the program (G10 L2/L20) and tool length offsets (G43,
//!   G43.1, G43.2) are folded into the coordinates, and the program runs with G49 and no G92.
//!   (`G43.1` would be the literal choice, but the rewriter cannot follow it; folding is exact
//!   and what the rewriter compensates.) Without a table, each system's entry is the first value
//!   rs274 prints for it (exact unless the program changes a table entry before selecting it).
//! - **Units**: G20/G21 as rs274 prints them; every number is written with 6 decimals (trailing
//!   zeros trimmed), so a value rs274 printed with 4 decimals is written exactly.
//! - **Axes**: an axis is written in a move once the original program names it (see
//!   [`axes_named`]) or its position leaves the interpreter's start position (machine 0), so a
//!   lathe program still never commands Y. Every move line carries its motion code.
//! - **Rotary axes** A, B, C of straight moves are written as rs274 prints them (degrees, its
//!   4 decimals exactly) when the program turns that axis somewhere: from the first move if
//!   the original names it ([`FlattenOptions::rotary_named`]), else from the move where it
//!   leaves 0. A program that names A but never leaves A0 stays a three-axis program. The
//!   rewriter then compensates them with a model whose chain has them. Inverse-time feeds need no
//!   care: rs274 has already turned them into per-minute rates by LinuxCNC's own rule (XYZ
//!   length when X, Y or Z moves, else the rotary length), which the G94 output keeps.
//! - **Arcs** are written with incremental centres (G91.1 I J K) and their helical end point.
//! - **Refused** (error naming the canonical line): spindle-synchronised motion (G33, G76:
//!   `START_SPEED_FEED_SYNCH`), probing (`STRAIGHT_PROBE`: the result is only known at run
//!   time), rigid tapping, NURBS/spline feeds, any non-zero U/V/W position (no chain mtec
//!   models has them), a non-zero A/B/C offset (G5x, G92, tool length: the angles are written
//!   as machine angles), an arc that turns a rotary axis, a non-zero XY rotation (G10 L2 R),
//!   spindles other than 0,
//!   constant surface speed with an X origin that flattening moved, and any call it does not
//!   know. rs274's own errors are the CLI's to pass on (rs274 stops and prints them).

pub use super::canon::FlattenError;
use super::canon::{parse_line, Call};
use super::format::format_number;
use super::offsets::WORK_SYSTEMS;

/// Digits after the point of every written number.
const DECIMALS: usize = 6;

/// What a flattening needs besides the canonical text.
#[derive(Debug, Clone)]
pub struct FlattenOptions {
    /// Work-offset table at program start, G54…G59.3, in mm (see [`work_offsets_from_probe`]).
    /// `None`: each system's entry is the first value rs274 prints for it.
    pub work_offsets_mm: Option<[[f64; 3]; 9]>,
    /// X, Y, Z named by the original program (written from the first move on).
    pub axes_named: [bool; 3],
    /// A, B, C named by the original program (written from the first move on when the
    /// program turns them somewhere; see [`rotary_axes_named`]).
    pub rotary_named: [bool; 3],
    /// First line of the output (a comment), without newline, cut to 254 characters.
    pub header: Option<String>,
    /// For every motion call of the canonical text, which of X Y Z A B C the program has not
    /// commanded yet ([`super::start_probe::held_axes`]): those are not written, as in the
    /// original. `None`: the rules of `axes_named` and `rotary_named` alone.
    pub held: Option<Vec<[bool; 6]>>,
    /// The work system rs274 started in (0 = G54 … 8 = G59.3) stands for the machine's active
    /// one, which nobody gave: it is not written, so the output runs in whatever system the
    /// machine is in, as the original does, until the program selects another one.
    pub unstated_start_system: Option<usize>,
    /// `G92.1` or `G92.2` when the original cancels the G92 offset before its first move:
    /// written in the preamble. LinuxCNC keeps a G92 offset between programs, which
    /// stand-alone rs274 never has; a program that cancels it first runs the same whatever
    /// the machine held, and so does its flattened form only if it cancels it too.
    pub g92_cancel_at_start: Option<&'static str>,
}

impl Default for FlattenOptions {
    fn default() -> Self {
        FlattenOptions {
            work_offsets_mm: None,
            axes_named: [true; 3],
            rotary_named: [true; 3],
            header: None,
            held: None,
            unstated_start_system: None,
            g92_cancel_at_start: None,
        }
    }
}

/// What a flattening did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct FlattenReport {
    pub canonical_lines: usize,
    pub lines_written: usize,
    pub straight_moves: usize,
    pub arcs: usize,
    /// Whether any offset (G92/G52, changed work offset, tool length) was folded into the
    /// coordinates of some move.
    pub offsets_folded: bool,
    /// Whether a work-offset table entry changed by the program (G10 L2/L20) was folded in:
    /// the output is then right only where the table at start is the one rs274 read.
    pub table_change_folded: bool,
}

/// The program the CLI runs through rs274 (with the same parameter file) to learn the
/// work-offset table: it selects every system in mm, so rs274 prints each entry.
pub const WORK_OFFSET_PROBE: &str = "G21\nG54\nG55\nG56\nG57\nG58\nG59\nG59.1\nG59.2\nG59.3\nM2\n";

/// Reads the work-offset table (mm) from rs274's output for [`WORK_OFFSET_PROBE`].
pub fn work_offsets_from_probe(canon: &str) -> Result<[[f64; 3]; 9], FlattenError> {
    let mut table = [[0.0; 3]; 9];
    let mut seen = [false; 9];
    let mut inch = false;
    for (i, raw) in canon.lines().enumerate() {
        let Some(c) = parse_line(raw, i + 1)? else {
            continue;
        };
        match c.name {
            "USE_LENGTH_UNITS" => inch = c.args.first() == Some(&"CANON_UNITS_INCHES"),
            "SET_G5X_OFFSET" => {
                let v = c.numbers(7)?;
                let idx = c.index(v[0], 9)?;
                let s = if inch { 25.4 } else { 1.0 };
                // the first print is the table (the program end prints G54 again)
                if !seen[idx] {
                    table[idx] = [v[1] * s, v[2] * s, v[3] * s];
                    seen[idx] = true;
                }
            }
            _ => {}
        }
    }
    match seen.iter().position(|s| !s) {
        Some(i) => Err(FlattenError {
            line: canon.lines().count(),
            call: String::new(),
            message: format!(
                "the work-offset probe did not print {} (rs274 stopped early?)",
                WORK_SYSTEMS[i]
            ),
        }),
        None => Ok(table),
    }
}

/// Which of X, Y, Z a program names as words (outside comments), read loosely: a letter X/Y/Z
/// followed by a number, `[`, `#` or `-`/`+`. Used only to decide which axes the flattened
/// program writes from its first move.
pub fn axes_named(program: &[u8]) -> [bool; 3] {
    letters_named(program, *b"XYZ")
}

/// Which of A, B, C a program names as words, read as [`axes_named`] reads X, Y, Z.
pub fn rotary_axes_named(program: &[u8]) -> [bool; 3] {
    letters_named(program, *b"ABC")
}

fn letters_named(program: &[u8], letters: [u8; 3]) -> [bool; 3] {
    let mut named = [false; 3];
    let mut depth = 0usize;
    let mut i = 0;
    while i < program.len() {
        let c = program[i];
        match c {
            b'(' => depth += 1,
            b')' => depth = depth.saturating_sub(1),
            b';' if depth == 0 => {
                while i < program.len() && program[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'\n' => depth = 0,
            _ if depth == 0 => {
                let axis = letters.iter().position(|l| *l == c.to_ascii_uppercase());
                if let Some(a) = axis {
                    // the previous byte must not be a letter (o<xyz> names, words like "MAX")
                    let prev_letter = i > 0 && program[i - 1].is_ascii_alphabetic();
                    let mut j = i + 1;
                    while j < program.len() && (program[j] == b' ' || program[j] == b'\t') {
                        j += 1;
                    }
                    let next = program.get(j).copied().unwrap_or(b' ');
                    if !prev_letter
                        && (next.is_ascii_digit()
                            || matches!(next, b'.' | b'-' | b'+' | b'[' | b'#'))
                    {
                        named[a] = true;
                    }
                }
            }
            _ => {}
        }
        i += 1;
    }
    named
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum PathMode {
    ExactStop,
    ExactPath,
    Continuous(f64, f64),
}

/// The flattening state machine.
struct Flattener {
    out: String,
    report: FlattenReport,
    // --- interpreter state, as rs274 printed it ---
    inch: bool,
    /// Active work system (0-based) and its offset, mm.
    work: usize,
    work_offset_mm: [f64; 3],
    g92_mm: [f64; 3],
    tool_mm: [f64; 3],
    table_mm: [[f64; 3]; 9],
    table_known: [bool; 9],
    plane: usize, // 0 XY, 1 XZ, 2 YZ
    feed: f64,
    feed_per_rev: bool,
    path: Option<PathMode>,
    css_max: Option<f64>,
    spindle_speed: f64,
    mist: bool,
    flood: bool,
    selected_tool: Option<u64>,
    pallet: bool,
    ended: bool,
    /// Machine position (mm) after the last move; starts at machine 0 as rs274 does.
    machine_mm: [f64; 3],
    /// Half a unit of the 4 decimals that position was printed with (mm per axis).
    machine_print_mm: f64,
    live: [bool; 3],
    /// Machine angles A, B, C (deg) after the last move.
    rotary_deg: [f64; 3],
    /// Rotary axes written in moves from here on.
    rotary_live: [bool; 3],
    /// Rotary axes the program turns somewhere.
    rotary_turned: [bool; 3],
    /// Rotary axes the original program names (FlattenOptions::rotary_named).
    rotary_named: [bool; 3],
    // --- what the output has set ---
    out_inch: Option<bool>,
    out_work: Option<usize>,
    /// FlattenOptions::unstated_start_system, until rs274 prints the start system.
    unstated_start_system: Option<usize>,
    out_plane: Option<usize>,
    out_feed: Option<f64>,
    out_feed_per_rev: Option<bool>,
    out_path: Option<PathMode>,
    out_css: Option<Option<f64>>,
    /// Held axes of every motion call (see [`FlattenOptions::held`]) and the next one's index.
    held: Option<Vec<[bool; 6]>>,
    motion: usize,
    /// A lone MIST_OFF (true) or FLOOD_OFF (false): the first half of an M9, or part of the
    /// reset of the program end that follows.
    pending_off: Option<(bool, FlattenError)>,
    /// The output ends at a closing `%` (rs274 printed FINISH without PROGRAM_END).
    percent: bool,
}

fn num(v: f64, out: &mut String) {
    format_number(v, DECIMALS, out);
}

impl Flattener {
    fn new(opt: &FlattenOptions) -> Self {
        Flattener {
            out: String::new(),
            report: FlattenReport::default(),
            inch: false,
            work: 0,
            work_offset_mm: [0.0; 3],
            g92_mm: [0.0; 3],
            tool_mm: [0.0; 3],
            table_mm: opt.work_offsets_mm.unwrap_or([[0.0; 3]; 9]),
            table_known: [opt.work_offsets_mm.is_some(); 9],
            plane: 0,
            feed: 0.0,
            feed_per_rev: false,
            path: None,
            css_max: None,
            spindle_speed: 0.0,
            mist: false,
            flood: false,
            selected_tool: None,
            pallet: false,
            ended: false,
            machine_mm: [0.0; 3],
            machine_print_mm: 0.0,
            live: if opt.held.is_some() {
                [false; 3]
            } else {
                opt.axes_named
            },
            rotary_deg: [0.0; 3],
            rotary_live: [false; 3],
            rotary_turned: [false; 3],
            rotary_named: opt.rotary_named,
            out_inch: None,
            out_work: None,
            unstated_start_system: opt.unstated_start_system,
            out_plane: None,
            out_feed: None,
            out_feed_per_rev: None,
            out_path: None,
            out_css: Some(None),
            held: opt.held.clone(),
            motion: 0,
            pending_off: None,
            percent: false,
        }
    }

    /// The held axes of the next motion call (none held without a start probe).
    fn next_held(&mut self, c: &Call) -> Result<[bool; 6], FlattenError> {
        let Some(h) = &self.held else {
            return Ok([false; 6]);
        };
        let m = h.get(self.motion).copied().ok_or_else(|| {
            c.err("more moves than the start-position check saw (the two rs274 runs differ)")
        })?;
        self.motion += 1;
        Ok(m)
    }

    fn scale(&self) -> f64 {
        if self.inch {
            25.4
        } else {
            1.0
        }
    }

    fn line(&mut self, s: &str) {
        self.out.push_str(s);
        self.out.push('\n');
        self.report.lines_written += 1;
    }

    /// Writes pending modal changes (units, work system, plane, path mode) before a
    /// line that depends on them.
    fn sync_modes(&mut self, motion: bool) {
        if self.out_inch != Some(self.inch) {
            self.line(if self.inch { "G20" } else { "G21" });
            self.out_inch = Some(self.inch);
        }
        if self.out_work != Some(self.work) {
            let w = WORK_SYSTEMS[self.work];
            self.line(w);
            self.out_work = Some(self.work);
        }
        if self.out_plane != Some(self.plane) {
            self.line(["G17", "G18", "G19"][self.plane]);
            self.out_plane = Some(self.plane);
        }
        if motion && self.path.is_some() && self.out_path != self.path {
            let mut s = String::new();
            match self.path {
                Some(PathMode::ExactStop) => s.push_str("G61.1"),
                Some(PathMode::ExactPath) => s.push_str("G61"),
                Some(PathMode::Continuous(p, q)) => {
                    s.push_str("G64 P");
                    num(p, &mut s);
                    s.push_str(" Q");
                    num(q, &mut s);
                }
                None => {}
            }
            self.line(&s);
            self.out_path = self.path;
        }
    }

    /// Spindle mode (G96/G97) and speed: written together, as LinuxCNC wants G96 with S.
    fn sync_css(&mut self, with_speed: bool) {
        let mut s = String::new();
        if self.out_css != Some(self.css_max) {
            match self.css_max {
                Some(d) => {
                    s.push_str("G96");
                    if d < 1e29 {
                        s.push_str(" D");
                        num(d, &mut s);
                    }
                }
                None => s.push_str("G97"),
            }
            self.out_css = Some(self.css_max);
            if self.css_max.is_some() && !with_speed {
                s.push_str(" S");
                num(self.spindle_speed, &mut s);
            }
        }
        if with_speed {
            if !s.is_empty() {
                s.push(' ');
            }
            s.push('S');
            num(self.spindle_speed, &mut s);
        }
        if !s.is_empty() {
            self.sync_modes(false);
            self.line(&s);
        }
    }

    /// Offset (program units) added to canonical coordinates to get the output coordinates.
    fn fold(&self, c: &Call) -> Result<[f64; 3], FlattenError> {
        let w = self.work;
        if !self.table_known[w] {
            return Err(c.err(format!(
                "{} is active but rs274 never printed its offset",
                WORK_SYSTEMS[w]
            )));
        }
        let s = self.scale();
        let mut f = [0.0; 3];
        for (a, v) in f.iter_mut().enumerate() {
            let mm =
                self.work_offset_mm[a] + self.g92_mm[a] + self.tool_mm[a] - self.table_mm[w][a];
            *v = if mm.abs() < 1e-12 { 0.0 } else { mm / s };
        }
        Ok(f)
    }

    /// Offsets (G5x, G92, tool length) of A B C U V W must be zero.
    fn check_rotary(&self, c: &Call, values: &[f64]) -> Result<(), FlattenError> {
        for (i, v) in values.iter().enumerate() {
            if v.abs() > 5e-5 {
                let l = ["A", "B", "C", "U", "V", "W"][i.min(5)];
                return Err(c.err(format!(
                    "an offset of axis {l} ({v}): flattening writes machine angles and no U, V, W"
                )));
            }
        }
        Ok(())
    }

    /// The U, V, W values of a move (after A, B, C) must be zero: no chain mtec models has them.
    fn check_uvw(&self, c: &Call, values: &[f64]) -> Result<(), FlattenError> {
        for (i, v) in values.iter().enumerate() {
            if v.abs() > 5e-5 {
                let l = ["U", "V", "W"][i.min(2)];
                return Err(c.err(format!(
                    "axis {l} at {v}: U, V and W are in no machine chain mtec models, so the tool tip cannot be compensated"
                )));
            }
        }
        Ok(())
    }

    /// Output coordinates (program units) of canonical `p`, updating the machine position.
    fn target(&mut self, c: &Call, p: [f64; 3]) -> Result<[f64; 3], FlattenError> {
        let fold = self.fold(c)?;
        if fold.iter().any(|v| *v != 0.0) {
            self.report.offsets_folded = true;
        }
        let table = self.table_mm[self.work];
        if (0..3).any(|a| (self.work_offset_mm[a] - table[a]).abs() > 1e-9) {
            self.report.table_change_folded = true;
        }
        if self.css_max.is_some() && fold[0] != 0.0 {
            return Err(c.err("constant surface speed (G96) while an X offset is folded into the coordinates: the spindle speed would change"));
        }
        let s = self.scale();
        let mut out = [0.0; 3];
        for a in 0..3 {
            out[a] = p[a] + fold[a];
            let m = p[a] * s + self.work_offset_mm[a] + self.g92_mm[a] + self.tool_mm[a];
            if (m - self.machine_mm[a]).abs() > 1e-9 {
                self.live[a] = true;
            }
            self.machine_mm[a] = m;
        }
        self.machine_print_mm = 5e-5 * s;
        Ok(out)
    }

    fn axis_words(&self, out: &[f64; 3], s: &mut String) {
        for (a, l) in ["X", "Y", "Z"].iter().enumerate() {
            if self.live[a] {
                s.push(' ');
                s.push_str(l);
                num(out[a], s);
            }
        }
    }

    fn feed_words(&mut self, s: &mut String) {
        if self.out_feed != Some(self.feed) {
            s.push_str(" F");
            num(self.feed, s);
            self.out_feed = Some(self.feed);
        }
    }

    fn sync_feed_mode(&mut self) {
        if self.out_feed_per_rev != Some(self.feed_per_rev) {
            self.line(if self.feed_per_rev { "G95" } else { "G94" });
            self.out_feed_per_rev = Some(self.feed_per_rev);
            self.out_feed = None;
        }
    }

    fn straight(&mut self, c: &Call, rapid: bool) -> Result<(), FlattenError> {
        let v = c.numbers(6)?;
        let all = c.numbers(c.args.len())?;
        self.check_uvw(c, &all[6..])?;
        self.sync_modes(true);
        if !rapid {
            self.sync_feed_mode();
        }
        let held = self.next_held(c)?;
        let out = self.target(c, [v[0], v[1], v[2]])?;
        let probed = self.held.is_some();
        for (live, held) in self.live.iter_mut().zip(&held[..3]) {
            *live |= probed && !held;
        }
        let mut s = String::from(if rapid { "G0" } else { "G1" });
        self.axis_words(&out, &mut s);
        self.rotary_deg = [v[3], v[4], v[5]];
        for (k, l) in ["A", "B", "C"].iter().enumerate() {
            // with the start check: from the first move that commands an axis the program
            // names, also at 0 (`G0 A0` turns a table that stood elsewhere back to 0; leaving
            // the word out would leave it turned; a G28 of a program that never names A stays
            // three-axis); without it: once the program turns it
            self.rotary_live[k] |= if self.held.is_some() {
                self.rotary_named[k] && !held[3 + k]
            } else {
                self.rotary_turned[k] && self.rotary_deg[k] != 0.0
            };
            if self.rotary_live[k] {
                s.push(' ');
                s.push_str(l);
                num(self.rotary_deg[k], &mut s);
            }
        }
        if !rapid {
            self.feed_words(&mut s);
        }
        self.line(&s);
        self.report.straight_moves += 1;
        Ok(())
    }

    fn arc(&mut self, c: &Call) -> Result<(), FlattenError> {
        let v = c.numbers(9)?;
        let all = c.numbers(c.args.len())?;
        self.check_uvw(c, &all[9..])?;
        if let Some(k) = (0..3).find(|&k| (v[6 + k] - self.rotary_deg[k]).abs() > 5e-5) {
            return Err(c.err(format!(
                "an arc that turns the rotary axis {} (from {} to {}): its tool tip path is neither an arc nor a joint line the rewriter follows",
                ["A", "B", "C"][k],
                self.rotary_deg[k],
                v[6 + k]
            )));
        }
        let rot = v[4];
        if rot == 0.0 || rot.fract() != 0.0 || rot.abs() > 1e6 {
            return Err(c.err(format!(
                "arc rotation {rot} is not a non-zero whole number of turns"
            )));
        }
        // (first, second, normal) axis indices of the plane
        let (f, se, n) = match self.plane {
            0 => (0, 1, 2),
            1 => (2, 0, 1),
            _ => (1, 2, 0),
        };
        let mut end = [0.0; 3];
        end[f] = v[0];
        end[se] = v[1];
        end[n] = v[5];
        self.sync_modes(true);
        self.sync_feed_mode();
        let fold = self.fold(c)?;
        let s = self.scale();
        // start in output coordinates: the previous machine position in today's frame
        let start: [f64; 3] = std::array::from_fn(|a| {
            let mm =
                self.machine_mm[a] - (self.work_offset_mm[a] + self.g92_mm[a] + self.tool_mm[a]);
            mm / s + fold[a]
        });
        let mut centre = start;
        centre[f] = v[2] + fold[f];
        centre[se] = v[3] + fold[se];
        // the plane's axes take part in the arc: they are written from here on
        let held = self.next_held(c)?;
        self.live[f] = true;
        self.live[se] = true;
        self.live[n] |= self.held.is_some() && !held[n];
        let (from_mm, from_print_mm) = (self.machine_mm, self.machine_print_mm);
        let out = self.target(c, end)?;
        // an end within the printouts' rounding of the start but not on it: rs274's 4 decimals
        // cannot tell a full circle from an arc of a micrometre (LinuxCNC's motion decides by
        // digits below them); on it, the start is written as the end and the arc is whole
        let chord = (self.machine_mm[f] - from_mm[f]).hypot(self.machine_mm[se] - from_mm[se]);
        if chord > 1e-9
            && chord <= std::f64::consts::SQRT_2 * (from_print_mm + self.machine_print_mm) + 1e-9
        {
            return Err(c.err(format!(
                "an arc whose end lies {:.3} um from its start, within the rounding of rs274's printout (start and end printed in different units, or a micrometre arc): whether LinuxCNC runs a full circle cannot be told; give the full circle without axis words, or its end exactly at its start, in one unit system",
                chord * 1e3
            )));
        }
        let mut line = String::from(if rot < 0.0 { "G2" } else { "G3" });
        self.axis_words(&out, &mut line);
        for (a, l) in ["I", "J", "K"].iter().enumerate() {
            if a == f || a == se {
                line.push(' ');
                line.push_str(l);
                num(centre[a] - start[a], &mut line);
            }
        }
        if rot.abs() > 1.0 {
            line.push_str(" P");
            num(rot.abs(), &mut line);
        }
        self.feed_words(&mut line);
        self.line(&line);
        self.report.arcs += 1;
        Ok(())
    }

    fn call(&mut self, c: &Call) -> Result<(), FlattenError> {
        if let Some((mist, e)) = self.pending_off.take() {
            match (mist, c.name) {
                // M9
                (true, "FLOOD_OFF") => {
                    self.mist = false;
                    self.flood = false;
                    self.line("M9");
                    return Ok(());
                }
                // M30's reset prints the coolant off, then PALLET_SHUTTLE, then PROGRAM_END:
                // the off stays pending until the end (found 2026-11-28: `M8` … `M30` without
                // M9 was refused, the same program with M2 was not)
                (_, "PALLET_SHUTTLE") => {
                    self.pallet = true;
                    self.pending_off = Some((mist, e));
                    return Ok(());
                }
                // the program end's own reset switches off what is on: M2/M30 does it again
                (_, "PROGRAM_END") | (false, "MIST_OFF") => {
                    if mist {
                        self.mist = false;
                    } else {
                        self.flood = false;
                    }
                    if c.name == "MIST_OFF" {
                        self.pending_off = Some((true, c.err("a single coolant switched off: LinuxCNC has no code for that (M9 switches both off)")));
                        return Ok(());
                    }
                }
                _ => return Err(e),
            }
        }
        if self.ended {
            return match c.name {
                "ON_RESET" => Ok(()),
                _ => Err(c.err("a call after the program end")),
            };
        }
        if self.pallet && !matches!(c.name, "PROGRAM_END" | "PROGRAM_STOP") {
            return Err(c.err("a pallet shuttle not followed by a program end or stop"));
        }
        match c.name {
            "STRAIGHT_TRAVERSE" => self.straight(c, true)?,
            "STRAIGHT_FEED" => self.straight(c, false)?,
            "ARC_FEED" => self.arc(c)?,
            "USE_LENGTH_UNITS" => {
                self.inch = match c.args.first().copied() {
                    Some("CANON_UNITS_INCHES") => true,
                    Some("CANON_UNITS_MM") => false,
                    other => {
                        return Err(c.err(format!("length units {other:?} are not inch or mm")))
                    }
                }
            }
            "SET_G5X_OFFSET" => {
                let v = c.numbers(7)?;
                let idx = c.index(v[0], 9)?;
                let extra: Vec<f64> = c.numbers(c.args.len())?[4..].to_vec();
                self.check_rotary(c, &extra)?;
                let s = self.scale();
                self.work = idx;
                // the first SET_G5X_OFFSET is the interpreter's start state, not a selection
                if let Some(start) = self.unstated_start_system.take() {
                    if start != idx {
                        return Err(c.err(format!(
                            "rs274 started in {}, not in {}",
                            WORK_SYSTEMS[idx], WORK_SYSTEMS[start]
                        )));
                    }
                    self.out_work = Some(idx);
                }
                self.work_offset_mm = [v[1] * s, v[2] * s, v[3] * s];
                if !self.table_known[idx] {
                    self.table_mm[idx] = self.work_offset_mm;
                    self.table_known[idx] = true;
                }
            }
            "SET_G92_OFFSET" => {
                let v = c.numbers(6)?;
                self.check_rotary(c, &c.numbers(c.args.len())?[3..])?;
                let s = self.scale();
                self.g92_mm = [v[0] * s, v[1] * s, v[2] * s];
            }
            "USE_TOOL_LENGTH_OFFSET" => {
                let v = c.numbers(3)?;
                self.check_rotary(c, &c.numbers(c.args.len())?[3..])?;
                let s = self.scale();
                self.tool_mm = [v[0] * s, v[1] * s, v[2] * s];
            }
            "SET_XY_ROTATION" => {
                let v = c.numbers(1)?;
                if v[0].abs() > 5e-5 {
                    return Err(c.err(format!(
                        "the work system is rotated by {} degrees (G10 L2 R): flattening does not rotate coordinates",
                        v[0]
                    )));
                }
            }
            "SELECT_PLANE" => {
                self.plane = match c.args.first().copied() {
                    Some("CANON_PLANE_XY") => 0,
                    Some("CANON_PLANE_XZ") => 1,
                    Some("CANON_PLANE_YZ") => 2,
                    other => {
                        return Err(c.err(format!(
                            "plane {other:?}: only XY, XZ and YZ (G17, G18, G19) can be written"
                        )))
                    }
                }
            }
            "SET_FEED_RATE" => self.feed = c.numbers(1)?[0],
            "SET_FEED_MODE" => {
                let v = c.numbers(2)?;
                self.spindle(c, v[0])?;
                self.feed_per_rev = if v[1] == 0.0 {
                    false
                } else if v[1] == 1.0 {
                    true
                } else {
                    return Err(c.err(format!("feed mode {} is not 0 or 1", v[1])));
                };
            }
            "SET_MOTION_CONTROL_MODE" => {
                self.path = Some(match c.args.first().copied() {
                    Some("CANON_EXACT_STOP") => PathMode::ExactStop,
                    Some("CANON_EXACT_PATH") => PathMode::ExactPath,
                    Some("CANON_CONTINUOUS") => {
                        let p = match c.args.get(1).map(|a| a.parse::<f64>()) {
                            None => 0.0,
                            Some(Ok(p)) if p.is_finite() && p >= 0.0 => p,
                            Some(_) => return Err(c.err("path tolerance is not a number ≥ 0")),
                        };
                        PathMode::Continuous(p, p)
                    }
                    other => return Err(c.err(format!("path mode {other:?} is not known"))),
                })
            }
            "SET_NAIVECAM_TOLERANCE" => {
                let q = c.numbers(1)?[0];
                if let Some(PathMode::Continuous(p, _)) = self.path {
                    self.path = Some(PathMode::Continuous(p, q));
                }
            }
            "SET_SPINDLE_MODE" => {
                let v = c.numbers(2)?;
                self.spindle(c, v[0])?;
                self.css_max = if v[1] > 0.0 { Some(v[1]) } else { None };
            }
            "SET_SPINDLE_SPEED" => {
                let v = c.numbers(2)?;
                self.spindle(c, v[0])?;
                self.spindle_speed = v[1];
                self.sync_css(true);
            }
            "START_SPINDLE_CLOCKWISE" | "START_SPINDLE_COUNTERCLOCKWISE" | "STOP_SPINDLE_TURNING" => {
                if let Some(s) = c.args.first() {
                    let v: f64 = s.parse().map_err(|_| c.err("spindle number expected"))?;
                    self.spindle(c, v)?;
                }
                self.sync_css(false);
                self.sync_modes(false);
                self.line(match c.name {
                    "START_SPINDLE_CLOCKWISE" => "M3",
                    "START_SPINDLE_COUNTERCLOCKWISE" => "M4",
                    _ => "M5",
                });
            }
            // coolant is written as rs274 prints it: M7, M8, and M9 (MIST_OFF then FLOOD_OFF,
            // whatever was on), so that a program starting with M9 still turns it off
            "MIST_ON" | "FLOOD_ON" => {
                let mist = c.name == "MIST_ON";
                if mist {
                    self.mist = true;
                } else {
                    self.flood = true;
                }
                self.sync_modes(false);
                self.line(if mist { "M7" } else { "M8" });
            }
            "MIST_OFF" | "FLOOD_OFF" => {
                self.pending_off = Some((
                    c.name == "MIST_OFF",
                    c.err("a single coolant switched off: LinuxCNC has no code for that (M9 switches both off)"),
                ));
            }
            "DWELL" => {
                let t = c.numbers(1)?[0];
                self.sync_modes(false);
                let mut s = String::from("G4 P");
                num(t, &mut s);
                self.line(&s);
            }
            "SELECT_TOOL" => {
                let t = c.numbers(1)?[0];
                if t < 0.0 || t.fract() != 0.0 || t > 1e9 {
                    return Err(c.err(format!("tool {t} is not a tool number")));
                }
                self.selected_tool = Some(t as u64);
                self.sync_modes(false);
                self.line(&format!("T{}", t as u64));
            }
            "START_CHANGE" => {}
            "CHANGE_TOOL" => {
                if self.selected_tool.is_none() {
                    return Err(c.err("a tool change with no tool selected before"));
                }
                self.sync_modes(false);
                self.line("M6");
            }
            "CHANGE_TOOL_NUMBER" => {
                let t = c.numbers(1)?[0];
                if t < 0.0 || t.fract() != 0.0 || t > 1e9 {
                    return Err(c.err(format!("tool {t} is not a tool number")));
                }
                self.sync_modes(false);
                self.line(&format!("M61 Q{}", t as u64));
            }
            "COMMENT" => {
                let t = c.text();
                if !t.starts_with("interpreter: ") {
                    let s = format!("({})", comment_text(t));
                    self.line(&s);
                }
            }
            "MESSAGE" => {
                let s = format!("(MSG,{})", comment_text(c.text()));
                self.line(&s);
            }
            "OPTIONAL_PROGRAM_STOP" => {
                self.sync_modes(false);
                self.line("M1");
            }
            "PALLET_SHUTTLE" => self.pallet = true,
            "PROGRAM_STOP" => {
                self.sync_modes(false);
                self.line(if self.pallet { "M60" } else { "M0" });
                self.pallet = false;
            }
            "PROGRAM_END" | "FINISH" => {
                self.sync_css(false);
                if self.percent {
                    self.line("%");
                } else {
                    self.line(if self.pallet { "M30" } else { "M2" });
                }
                self.pallet = false;
                self.ended = true;
            }
            // M50/M51 (G76 switches feed override off around its passes)
            "ENABLE_FEED_OVERRIDE" | "DISABLE_FEED_OVERRIDE" | "ENABLE_SPEED_OVERRIDE"
            | "DISABLE_SPEED_OVERRIDE" => {
                self.sync_modes(false);
                let m = if c.name.contains("FEED") { "M50" } else { "M51" };
                let p = if c.name.starts_with("ENABLE") { 1 } else { 0 };
                self.line(&format!("{m} P{p}"));
            }
            // no effect on the motion or the machine's outputs
            "ON_RESET" | "SET_FEED_REFERENCE" | "TURN_PROBE_OFF" | "SET_TOOL_TABLE_ENTRY" => {}
            "STRAIGHT_PROBE" | "TURN_PROBE_ON" => {
                return Err(c.err(
                    "probing (G38.x): where the probe stops is only known at run time, so no plain program can follow it",
                ))
            }
            "START_SPEED_FEED_SYNCH" | "START_SPEED_FEED_SYNC" | "STOP_SPEED_FEED_SYNCH" => {
                return Err(c.err(
                    "spindle-synchronised motion (G33 and G76 threading, G33.1 rigid tapping): the moves follow the spindle and cannot be written as plain feed moves",
                ))
            }
            "RIGID_TAP" => {
                return Err(c.err("rigid tapping (G33.1) follows the spindle and cannot be written as plain moves"))
            }
            n if n.starts_with("NURBS") || n.starts_with("SPLINE") => {
                return Err(c.err("splines (G5, G5.1, G5.2): flattening writes straight moves and arcs only"))
            }
            other => {
                return Err(c.err(format!(
                    "{other} is a call flattening does not know how to write as a plain program"
                )))
            }
        }
        Ok(())
    }

    fn spindle(&self, c: &Call, v: f64) -> Result<(), FlattenError> {
        if v == 0.0 {
            Ok(())
        } else {
            Err(c.err(format!(
                "spindle {v}: only spindle 0 can be written (no $ words)"
            )))
        }
    }
}

/// Comment text that cannot close or nest the comment it is written in.
fn comment_text(t: &str) -> String {
    let s: String = t
        .chars()
        .map(|c| match c {
            '(' => '[',
            ')' => ']',
            c if c.is_control() => ' ',
            c => c,
        })
        .collect();
    if s.chars().count() > 240 {
        s.chars().take(240).collect()
    } else {
        s
    }
}

/// Flattens rs274's canonical output into a plain program (text ending in a newline).
pub fn flatten(canon: &str, opt: &FlattenOptions) -> Result<(String, FlattenReport), FlattenError> {
    let mut f = Flattener::new(opt);
    let turned = rotary_axes_turned(canon);
    f.rotary_live = std::array::from_fn(|k| turned[k] && opt.rotary_named[k]);
    f.rotary_turned = turned;
    // a program that ends at its closing % (rs274 prints FINISH and no PROGRAM_END): the same
    // end, without the reset that M2 would add (spindle stop, coolant off, modes); LinuxCNC
    // wants the opening % on the first line
    f.percent = canon.contains("FINISH(") && !canon.contains("PROGRAM_END(");
    if f.percent {
        f.line("%");
    }
    if let Some(h) = &opt.header {
        let h: String = h.replace(['\n', '\r'], " ").chars().take(254).collect();
        f.line(&h);
    }
    // G8: rs274 prints lathe X as a radius (G7 diameter mode is already undone)
    // a G92 offset rs274 read from the parameter file is folded into the coordinates: the
    // machine, which keeps it too, must drop it first
    let kept_g92 = canon
        .lines()
        .filter_map(|l| l.split_once("SET_G92_OFFSET("))
        .next()
        .is_some_and(|(_, a)| {
            a.trim_end_matches([')', ' '])
                .split(',')
                .any(|v| v.trim().parse::<f64>().is_ok_and(|x| x != 0.0))
        });
    match opt.g92_cancel_at_start.or(kept_g92.then_some("G92.1")) {
        Some(cancel) => f.line(&format!("G90 G91.1 G40 G49 G94 G80 G8 {cancel}")),
        None => f.line("G90 G91.1 G40 G49 G94 G80 G8"),
    }
    f.out_feed_per_rev = Some(false);
    for (i, raw) in canon.lines().enumerate() {
        f.report.canonical_lines += 1;
        let Some(c) = parse_line(raw, i + 1)? else {
            continue;
        };
        f.call(&c)?;
    }
    if let Some((_, e)) = f.pending_off.take() {
        return Err(e);
    }
    if let Some(h) = &f.held {
        if f.motion != h.len() {
            return Err(FlattenError {
                line: f.report.canonical_lines,
                call: String::new(),
                message: format!(
                    "{} moves, but the start-position check saw {} (the two rs274 runs differ)",
                    f.motion,
                    h.len()
                ),
            });
        }
    }
    if f.pallet {
        return Err(FlattenError {
            line: f.report.canonical_lines,
            call: String::new(),
            message: "the output ends after a pallet shuttle".into(),
        });
    }
    if !f.ended {
        f.sync_css(false);
        f.line(if f.percent { "%" } else { "M2" });
    }
    Ok((f.out, f.report))
}

/// Which of A, B, C some straight move or arc of rs274's output leaves at a non-zero angle.
fn rotary_axes_turned(canon: &str) -> [bool; 3] {
    let mut turned = [false; 3];
    for (i, raw) in canon.lines().enumerate() {
        let Ok(Some(c)) = parse_line(raw, i + 1) else {
            continue;
        };
        let first = match c.name {
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" => 3,
            "ARC_FEED" => 6,
            _ => continue,
        };
        if let Ok(v) = c.numbers(first + 3) {
            for k in 0..3 {
                turned[k] |= v[first + k].abs() > 5e-5;
            }
        }
    }
    turned
}

/// A LinuxCNC parameter (.var) file's text with its linear positions divided by 25.4: the
/// X Y Z U V W members of G28 (#5161…), G30 (#5181…), G92 (#5211…) and the nine work offsets
/// (#5221 + 20·k …); angles (A B C), rotations and every other parameter kept. Stand-alone
/// `rs274` reads a parameter file as inches whatever the machine's units.
pub fn var_file_to_inch(text: &str) -> String {
    // member index within a block of X Y Z A B C U V W: the linear ones
    let linear = |i: u32| matches!(i, 0 | 1 | 2 | 6 | 7 | 8);
    let is_length = |n: u32| match n {
        5161..=5169 => linear(n - 5161),
        5181..=5189 => linear(n - 5181),
        5211..=5219 => linear(n - 5211),
        5221..=5400 => (n - 5221) % 20 < 9 && linear((n - 5221) % 20),
        _ => false,
    };
    let mut out = String::with_capacity(text.len());
    for line in text.split_inclusive('\n') {
        let mut parts = line.split_whitespace();
        let converted = match (
            parts.next().and_then(|p| p.parse::<u32>().ok()),
            parts.next().and_then(|v| v.parse::<f64>().ok()),
        ) {
            (Some(n), Some(v)) if is_length(n) => Some(format!("{n}\t{:.9}\n", v / 25.4)),
            _ => None,
        };
        match converted {
            Some(c) => out.push_str(&c),
            None => out.push_str(line),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// rs274 output for `crates/mtec-cli/tests/data/flatten/offsets.ngc` (see the README there).
    const OFFSETS_CANON: &str = include_str!("../../tests/data/flatten/offsets.canon");
    const OFFSETS_FLAT: &str = include_str!("../../tests/data/flatten/offsets.flat.ngc");
    const PROBE_CANON: &str = include_str!("../../tests/data/flatten/probe.canon");

    fn zero_table() -> FlattenOptions {
        FlattenOptions {
            work_offsets_mm: Some([[0.0; 3]; 9]),
            ..FlattenOptions::default()
        }
    }

    #[test]
    fn an_unstated_start_system_is_never_written_and_a_changed_entry_is_reported() {
        let start = "    1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n    2 N..... SET_G5X_OFFSET(9, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n";
        let listing = |calls: &[&str]| {
            let mut t = start.to_string();
            for (i, c) in calls.iter().enumerate() {
                t.push_str(&format!("{:5} N..... {c}\n", i + 3));
            }
            t
        };
        let opt = FlattenOptions {
            unstated_start_system: Some(8),
            ..zero_table()
        };
        let (t, r) = flatten(
            &listing(&[
                "STRAIGHT_TRAVERSE(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
                "SET_G5X_OFFSET(2, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                "STRAIGHT_TRAVERSE(4.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
                "PROGRAM_END()",
            ]),
            &opt,
        )
        .unwrap();
        assert!(!t.contains("G59.3"), "{t}");
        let g55 = t.find("G55\n").unwrap();
        assert!(t.find("G0 X1.0").unwrap() < g55, "{t}");
        assert!(!r.table_change_folded);
        // G10 L2 P2 X100 (an entry changed while G55 is active) is folded and reported
        let (_, r) = flatten(
            &listing(&[
                "SET_G5X_OFFSET(2, 100.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                "STRAIGHT_TRAVERSE(4.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
            ]),
            &opt,
        )
        .unwrap();
        assert!(r.table_change_folded && r.offsets_folded);
        // rs274 started elsewhere than the system that stands for the machine's: an error
        let mut g54 = listing(&[]);
        g54 = g54.replace("SET_G5X_OFFSET(9", "SET_G5X_OFFSET(1");
        assert!(flatten(&g54, &opt).is_err());
    }

    fn flat(canon: &str) -> Result<String, FlattenError> {
        flatten(canon, &zero_table()).map(|(t, _)| t)
    }

    /// A canonical listing of the given calls, numbered as rs274 numbers them.
    fn canon(calls: &[&str]) -> String {
        let mut s = String::from(
            "    1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n    2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n",
        );
        for (i, c) in calls.iter().enumerate() {
            s.push_str(&format!("{:5} N..... {c}\n", i + 3));
        }
        s
    }

    #[test]
    fn recorded_rs274_output_flattens_to_the_recorded_program() {
        let (text, report) = flatten(OFFSETS_CANON, &zero_table()).unwrap();
        if std::env::var_os("MTEC_BLESS").is_some() {
            let p = concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/tests/data/flatten/offsets.flat.ngc"
            );
            std::fs::write(p, &text).unwrap();
        }
        assert_eq!(text, OFFSETS_FLAT);
        assert_eq!(report.canonical_lines, 60);
        assert_eq!((report.straight_moves, report.arcs), (9, 3));
        assert!(report.offsets_folded);
        assert!(text.lines().all(|l| l.len() <= 255));
    }

    #[test]
    fn offsets_are_folded_into_machine_positions() {
        // G54 (10, 20, 30), then G92 -15 in X, then a tool length of 5 on Z
        let t = flat(&canon(&[
            "SET_G5X_OFFSET(1, 10.0000, 20.0000, 30.0000, 0.0000, 0.0000, 0.0000)",
            "SET_G92_OFFSET(-15.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)",
            "USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 5.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)",
            "STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "USE_LENGTH_UNITS(CANON_UNITS_INCHES)",
            "STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "PROGRAM_END()",
        ]))
        .unwrap();
        let lines: Vec<&str> = t.lines().collect();
        assert!(lines.contains(&"G0 X-5.0 Y20.0 Z35.0"), "{t}");
        assert!(lines.contains(&"G0 X-4.0 Y20.0 Z35.0"), "{t}");
        // inch: (25.4 - 5 mm) / 25.4, (20 / 25.4), (35 / 25.4) with 6 decimals
        assert!(lines.contains(&"G0 X0.80315 Y0.787402 Z1.377953"), "{t}");
        assert_eq!(lines.last(), Some(&"M2"));
        // with the table G54 = (10, 20, 30) the work offset is not folded
        let opt = FlattenOptions {
            work_offsets_mm: Some([[10.0, 20.0, 30.0]; 9]),
            ..FlattenOptions::default()
        };
        let (t, _) = flatten(
            &canon(&[
                "SET_G5X_OFFSET(1, 10.0000, 20.0000, 30.0000, 0.0000, 0.0000, 0.0000)",
                "STRAIGHT_TRAVERSE(1.2345, -0.0001, 5.0000, 0.0000, 0.0000, 0.0000)",
            ]),
            &opt,
        )
        .unwrap();
        assert!(t.contains("\nG0 X1.2345 Y-0.0001 Z5.0\n"), "{t}");
        // without a table, the first value printed for a system is its table entry
        let (t, r) = flatten(
            &canon(&[
                "SET_G5X_OFFSET(2, 1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
                "STRAIGHT_TRAVERSE(1.0000, 1.0000, 1.0000, 0.0000, 0.0000, 0.0000)",
            ]),
            &FlattenOptions::default(),
        )
        .unwrap();
        assert!(
            t.contains("\nG55\n") && t.contains("\nG0 X1.0 Y1.0 Z1.0\n"),
            "{t}"
        );
        assert!(!r.offsets_folded);
    }

    #[test]
    fn arcs_in_three_planes_turns_and_helices() {
        // recorded from rs274 (LinuxCNC 2.9): G2 X11 Y2 I5 J0 from (1, 2, 3); G3 back with
        // Z-1 and P3; G18 G2 X3 Z-1 I1 K0; G19 G3 Y4 Z-1 J1 K0
        let t = flat(&canon(&[
            "STRAIGHT_FEED(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
            "ARC_FEED(11.0000, 2.0000, 6.0000, 2.0000, -1, 3.0000, 0.0000, 0.0000, 0.0000)",
            "ARC_FEED(1.0000, 2.0000, 6.0000, 2.0000, 3, -1.0000, 0.0000, 0.0000, 0.0000)",
            "SELECT_PLANE(CANON_PLANE_XZ)",
            "ARC_FEED(-1.0000, 3.0000, -1.0000, 2.0000, -1, 2.0000, 0.0000, 0.0000, 0.0000)",
            "SELECT_PLANE(CANON_PLANE_YZ)",
            "ARC_FEED(4.0000, -1.0000, 3.0000, -1.0000, 1, 3.0000, 0.0000, 0.0000, 0.0000)",
        ]))
        .unwrap();
        for want in [
            "G2 X11.0 Y2.0 Z3.0 I5.0 J0.0",
            "G3 X1.0 Y2.0 Z-1.0 I-5.0 J0.0 P3.0",
            "G18",
            "G2 X3.0 Y2.0 Z-1.0 I1.0 K0.0",
            "G19",
            "G3 X3.0 Y4.0 Z-1.0 J1.0 K0.0",
        ] {
            assert!(t.lines().any(|l| l == want), "{want} missing in\n{t}");
        }
        assert!(t.starts_with("G90 G91.1 "), "{t}");
    }

    #[test]
    fn a_circle_whose_end_lies_within_the_printouts_rounding_of_its_start_is_refused() {
        // a full circle after G20 -> G21 (generate.py seed 4): the start printed in inches
        // (Y -1.9528 in = -49.60112 mm), the end in mm 1.5 um away; rs274's digits cannot tell
        // LinuxCNC's full circle from a micrometre arc
        let e = flat(&canon(&[
            "USE_LENGTH_UNITS(CANON_UNITS_INCHES)",
            "SELECT_PLANE(CANON_PLANE_YZ)",
            "STRAIGHT_FEED(5.8071, -1.9528, 1.4637, 0.0000, 0.0000, 0.0000)",
            "USE_LENGTH_UNITS(CANON_UNITS_MM)",
            "ARC_FEED(-49.5999, 37.1788, -41.6078, 25.4381, -1, 138.2051, 0.0000, 0.0000, 0.0000)",
        ]))
        .unwrap_err();
        assert!(e.to_string().contains("1.4"), "{e}");
        assert!(e.to_string().contains("cannot be told"), "{e}");
        // printed on the start in the same units: a whole circle, its end written as its start
        let t = flat(&canon(&[
            "STRAIGHT_FEED(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
            "ARC_FEED(1.0000, 2.0000, 6.0000, 2.0000, -1, 3.0000, 0.0000, 0.0000, 0.0000)",
        ]))
        .unwrap();
        assert!(t.lines().any(|l| l == "G2 X1.0 Y2.0 Z3.0 I5.0 J0.0"), "{t}");
    }

    #[test]
    fn refusals_name_the_canonical_line_and_the_reason() {
        let cases: [(&str, &str); 12] = [
            (
                "STRAIGHT_PROBE(10.0000, 0.0000, -5.0000, 0.0000, 0.0000, 0.0000)",
                "probing",
            ),
            ("START_SPEED_FEED_SYNC(1.000000,0)", "spindle-synchronised"),
            ("RIGID_TAP(10.0000, 0.0000, -5.0000)", "rigid tapping"),
            ("NURBS_FEED(4, ...)", "splines"),
            (
                "STRAIGHT_FEED(5.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 10.0000)",
                "axis W",
            ),
            ("SET_XY_ROTATION(30.0000)", "rotated"),
            (
                "ARC_FEED(1.0000, 2.0000, 6.0000, 2.0000, 0, 3.0000, 0.0000, 0.0000, 0.0000)",
                "rotation",
            ),
            (
                "STRAIGHT_FEED(NaN, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                "finite",
            ),
            ("STRAIGHT_FEED(1.0, 2.0)", "needs 6 arguments"),
            ("SET_SPINDLE_SPEED(1, 100.0000)", "spindle 1"),
            ("ORIENT_SPINDLE(0, 0.0000, 0)", "does not know"),
            ("12 N..... this is not a call", "not a canonical call"),
        ];
        for (call, words) in cases {
            let e = flat(&canon(&[call])).unwrap_err();
            assert_eq!(e.line, 3, "{call}: {e}");
            assert!(e.message.contains(words), "{call}: {e}");
            assert!(e.to_string().contains("canonical line 3"), "{e}");
        }
        let e = flat(&canon(&[
            "PROGRAM_END()",
            "STRAIGHT_TRAVERSE(1, 0, 0, 0, 0, 0)",
        ]))
        .unwrap_err();
        assert_eq!(e.line, 4);
        let e = flat(&canon(&[
            "SET_G5X_OFFSET(3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)",
            "CHANGE_TOOL(1)",
        ]))
        .unwrap_err();
        assert!(e.message.contains("no tool selected"), "{e}");
        // CSS with a folded X offset would change the spindle speed
        let e = flat(&canon(&[
            "SET_G92_OFFSET(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "SET_SPINDLE_MODE(0 2000.0000)",
            "STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
        ]))
        .unwrap_err();
        assert!(e.message.contains("G96"), "{e}");
    }

    #[test]
    fn coolant_is_written_as_printed_and_the_end_as_the_original_ends() {
        // an M9 with nothing on still turns coolant off (the machine may have it on)
        let t = flat(&canon(&["MIST_OFF()", "FLOOD_OFF()", "PROGRAM_END()"])).unwrap();
        assert_eq!(t.lines().skip(1).collect::<Vec<_>>(), ["M9", "M2"], "{t}");
        // M2's own reset switches off the flood that is on: M2 does it again, nothing written
        let t = flat(&canon(&[
            "FLOOD_ON()",
            "STOP_SPINDLE_TURNING(0)",
            "SET_SPINDLE_MODE(0 0.0000)",
            "FLOOD_OFF()",
            "PROGRAM_END()",
        ]))
        .unwrap();
        assert_eq!(
            t.lines().skip(1).collect::<Vec<_>>(),
            ["G21", "G54", "G17", "M8", "M5", "M2"],
            "{t}"
        );
        // M30's reset: the off, then the pallet shuttle, then the end: M30 does it again
        let t = flat(&canon(&[
            "FLOOD_ON()",
            "STOP_SPINDLE_TURNING(0)",
            "SET_SPINDLE_MODE(0 0.0000)",
            "FLOOD_OFF()",
            "PALLET_SHUTTLE()",
            "PROGRAM_END()",
        ]))
        .unwrap();
        assert_eq!(
            t.lines().skip(1).collect::<Vec<_>>(),
            ["G21", "G54", "G17", "M8", "M5", "M30"],
            "{t}"
        );
        // but a lone off before an M60 (pallet shuttle and stop) has no code
        let e = flat(&canon(&[
            "FLOOD_ON()",
            "FLOOD_OFF()",
            "PALLET_SHUTTLE()",
            "PROGRAM_STOP()",
        ]))
        .unwrap_err();
        assert!(e.message.contains("single coolant"), "{e}");
        // a single coolant off anywhere else has no code
        let e = flat(&canon(&["FLOOD_ON()", "MIST_OFF()", "DWELL(1.0000)"])).unwrap_err();
        assert!(e.message.contains("single coolant"), "{e}");
        assert!(e.call.contains("MIST_OFF"), "{e}");
        // a program that ends at its % (FINISH, no PROGRAM_END) ends at a % again, without
        // the reset an M2 would add
        let t = flat(&canon(&[
            "STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "FINISH()",
            "ON_RESET()",
        ]))
        .unwrap();
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines.first(), Some(&"%"), "{t}");
        assert_eq!(lines.last(), Some(&"%"), "{t}");
        assert!(!t.contains("M2"), "{t}");
    }

    #[test]
    fn held_axes_are_not_written() {
        // G0 Z5 first (X, Y held), then G1 X1 Y2
        let opt = FlattenOptions {
            held: Some(vec![
                [true, true, false, true, true, true],
                [false, false, false, true, true, true],
            ]),
            ..zero_table()
        };
        let (t, _) = flatten(
            &canon(&[
                "STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)",
                "SET_FEED_RATE(100.0000)",
                "STRAIGHT_FEED(1.0000, 2.0000, 5.0000, 0.0000, 0.0000, 0.0000)",
                "PROGRAM_END()",
            ]),
            &opt,
        )
        .unwrap();
        let moves: Vec<&str> = t
            .lines()
            .filter(|l| l.starts_with('G') && l.contains(['X', 'Z']))
            .collect();
        assert_eq!(moves, ["G0 Z5.0", "G1 X1.0 Y2.0 Z5.0 F100.0"], "{t}");
        // an A the program commands is written also at 0 (a table standing elsewhere turns
        // back), one it never commands is not
        let opt = FlattenOptions {
            held: Some(vec![[false, false, false, false, true, true]]),
            ..zero_table()
        };
        let (t, _) = flatten(
            &canon(&[
                "STRAIGHT_TRAVERSE(1.0000, 2.0000, 5.0000, 0.0000, 0.0000, 0.0000)",
                "PROGRAM_END()",
            ]),
            &opt,
        )
        .unwrap();
        assert!(t.lines().any(|l| l == "G0 X1.0 Y2.0 Z5.0 A0.0"), "{t}");
        // a different number of moves than the check saw is refused
        let opt = FlattenOptions {
            held: Some(vec![[false; 6]]),
            ..zero_table()
        };
        let e = flatten(
            &canon(&[
                "STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)",
                "STRAIGHT_TRAVERSE(0.0000, 0.0000, 6.0000, 0.0000, 0.0000, 0.0000)",
            ]),
            &opt,
        )
        .unwrap_err();
        assert!(e.message.contains("start-position check"), "{e}");
    }

    #[test]
    fn non_motion_calls_become_their_codes() {
        let t = flat(&canon(&[
            "SET_SPINDLE_SPEED(0, 1000.0000)",
            "START_SPINDLE_CLOCKWISE(0)",
            "FLOOD_ON()",
            "MIST_ON()",
            "SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.010000)",
            "SET_NAIVECAM_TOLERANCE(0.0200)",
            "COMMENT(\"interpreter: cutter radius compensation on left\")",
            "COMMENT(\"keep (me)\")",
            "MESSAGE(\" hi\")",
            "SET_FEED_RATE(120.0000)",
            "STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "MIST_OFF()",
            "FLOOD_OFF()",
            "DWELL(1.5000)",
            "SELECT_TOOL(2)",
            "START_CHANGE()",
            "CHANGE_TOOL(2)",
            "SET_FEED_MODE(0, 1)",
            "SET_FEED_RATE(0.1000)",
            "STRAIGHT_FEED(2.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "STOP_SPINDLE_TURNING(0)",
            "PALLET_SHUTTLE()",
            "PROGRAM_END()",
            "ON_RESET()",
        ]))
        .unwrap();
        let body: Vec<&str> = t.lines().skip(1).collect();
        assert_eq!(
            body,
            [
                "G21",
                "G54",
                "G17",
                "S1000.0",
                "M3",
                "M8",
                "M7",
                "(keep [me])",
                "(MSG, hi)",
                "G64 P0.01 Q0.02",
                "G1 X1.0 Y0.0 Z0.0 F120.0",
                "M9",
                "G4 P1.5",
                "T2",
                "M6",
                "G95",
                "G1 X2.0 Y0.0 Z0.0 F0.1",
                "M5",
                "M30",
            ],
            "{t}"
        );
    }

    #[test]
    fn rotary_axes_the_program_turns_are_written_as_printed() {
        assert_eq!(
            rotary_axes_named(b"G0 X0 A0 (B1)\nG1 c-5 F10\no<abc> call\n"),
            [true, false, true]
        );
        let listing = canon(&[
            "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
            "SET_FEED_RATE(183.5756)",
            "STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, -12.3456)",
            "STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 30.0000, 0.0000, -12.3456)",
        ]);
        // A named and turned: from the first move; C not named: from where it leaves 0;
        // B never turned: never written
        let opt = FlattenOptions {
            rotary_named: [true, true, false],
            ..zero_table()
        };
        let (t, _) = flatten(&listing, &opt).unwrap();
        let moves: Vec<&str> = t
            .lines()
            .filter(|l| l.starts_with("G0 ") || l.starts_with("G1 "))
            .collect();
        assert_eq!(
            moves,
            [
                "G0 X0.0 Y0.0 Z0.0 A0.0",
                "G1 X1.0 Y0.0 Z0.0 A0.0 C-12.3456 F183.5756",
                "G1 X1.0 Y0.0 Z0.0 A30.0 C-12.3456"
            ],
            "{t}"
        );
        // an arc that turns A, a U move, a B offset: refused naming the line
        for (call, want) in [
            (
                "ARC_FEED(1.0000, 1.0000, 0.0000, 1.0000, 1, 0.0000, 10.0000, 0.0000, 0.0000)",
                "turns the rotary axis A",
            ),
            (
                "STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 5.0000, 0.0000, 0.0000)",
                "axis U at 5",
            ),
            (
                "SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 2.0000, 0.0000)",
                "offset of axis B",
            ),
        ] {
            let e = flatten(&canon(&[call]), &zero_table()).unwrap_err();
            assert!(e.message.contains(want), "{call}: {e}");
        }
    }

    #[test]
    fn axes_the_program_never_names_are_not_written() {
        let named =
            axes_named(b"G18 G0 X1 Z2 (Y is not here)\n; nor Y1 here\no<max> call\nG1 x-1 z#1\n");
        assert_eq!(named, [true, false, true]);
        let opt = FlattenOptions {
            work_offsets_mm: Some([[0.0; 3]; 9]),
            axes_named: named,
            rotary_named: [false; 3],
            header: Some("(flattened)".into()),
            held: None,
            unstated_start_system: None,
            g92_cancel_at_start: None,
        };
        let (t, _) = flatten(
            &canon(&[
                "STRAIGHT_TRAVERSE(1.0000, 0.0000, 2.0000, 0.0000, 0.0000, 0.0000)",
                "STRAIGHT_TRAVERSE(1.0000, 3.0000, 2.0000, 0.0000, 0.0000, 0.0000)",
            ]),
            &opt,
        )
        .unwrap();
        assert!(t.starts_with("(flattened)\n"));
        assert!(t.contains("\nG0 X1.0 Z2.0\n"), "{t}");
        // once Y moves it is written
        assert!(t.contains("\nG0 X1.0 Y3.0 Z2.0\n"), "{t}");
    }

    #[test]
    fn probe_output_gives_the_table_in_mm() {
        let t = work_offsets_from_probe(PROBE_CANON).unwrap();
        assert_eq!(t[0], [76.2, -50.8, -114.3]);
        assert_eq!(t[1], [31.75, 19.05, -25.4]);
        assert_eq!(t[8], [0.0; 3]);
        let e =
            work_offsets_from_probe("    1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n").unwrap_err();
        assert!(e.message.contains("G54"), "{e}");
    }

    #[test]
    fn arbitrary_and_damaged_input_never_panics() {
        // every prefix of every recorded line, and byte-level damage, through the flattener
        let mut seed = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for line in OFFSETS_CANON.lines() {
            for cut in 0..=line.len() {
                if line.is_char_boundary(cut) {
                    let _ = flat(&format!("{}\n", &line[..cut]));
                    let _ = flatten(&line[..cut], &FlattenOptions::default());
                }
            }
        }
        let bytes = OFFSETS_CANON.as_bytes();
        for _ in 0..300 {
            let mut b = bytes.to_vec();
            for _ in 0..(next() % 8 + 1) {
                let i = (next() % b.len() as u64) as usize;
                b[i] = b"(),.- 0123456789eEnNaAX\n\""[(next() % 25) as usize];
            }
            let _ = flat(&String::from_utf8_lossy(&b));
        }
        let _ = work_offsets_from_probe("1 N SET_G5X_OFFSET(99, 1, 2, 3, 4, 5, 6)\n");
        let _ = axes_named(b"X(((Y)))\n;Z\xff");
    }
}

#[cfg(test)]
mod units_tests {
    use super::*;

    #[test]
    fn var_file_lengths_become_inches_and_angles_stay() {
        let v = "5161\t25.4\n5164\t90\n5221\t254\n5223\t-50.8\n5224\t30\n5230\t45\n5241\t12.7\n5400\t3\n";
        let t = var_file_to_inch(v);
        let vals: Vec<(u32, f64)> = t
            .lines()
            .map(|l| {
                let mut p = l.split_whitespace();
                (
                    p.next().unwrap().parse().unwrap(),
                    p.next().unwrap().parse().unwrap(),
                )
            })
            .collect();
        let get = |n: u32| vals.iter().find(|(k, _)| *k == n).unwrap().1;
        assert!((get(5161) - 1.0).abs() < 1e-12);
        assert_eq!(get(5164), 90.0); // G28 A: an angle
        assert!((get(5221) - 10.0).abs() < 1e-12);
        assert!((get(5223) + 2.0).abs() < 1e-12);
        assert_eq!(get(5224), 30.0); // G54 A
        assert_eq!(get(5230), 45.0); // G54 R: rotation
        assert!((get(5241) - 0.5).abs() < 1e-12); // G55 X
        assert_eq!(get(5400), 3.0);
    }

    #[test]
    fn tool_table_lengths_become_inches() {
        let t = crate::gcode::tooltable::to_inch_text(
            "T1 P1 Z25.4 D6.35 ;end mill 6.35\nT2 P2 X-2.54 Z50.8 A10\n",
        );
        assert_eq!(t, "T1 P1 Z1 D0.25 ;end mill 6.35\nT2 P2 X-0.1 Z2 A10\n");
    }
}
