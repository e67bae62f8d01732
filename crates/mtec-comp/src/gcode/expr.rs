//! LinuxCNC's parameters and expressions, evaluated as LinuxCNC's interpreter evaluates them.
//!
//! **What it is for**: turning the value of a word (`X[#<r>*2]`, `Z-#3`, `Y[SIN[30]*#<_r>]`) and
//! the parameter assignments of a line (`#1=5`, `#<x>=[#1+2]`, `##2=4`) into numbers, so the
//! rewriter can correct a program that computes its points. **Not for**: O-word control flow or
//! subroutines (the path then depends on branches: see `--flatten-with rs274`), comments with
//! parameters (`(DEBUG,#1)`), and values that depend on the machine (see "Reading" below).
//!
//! It follows LinuxCNC's documentation, *G-code Overview* (docs/src/gcode/overview.adoc,
//! sections "Parameters", "Numbered Parameters", "Named Parameters", "Expressions", "Binary
//! Operators", "Equality and floating-point values", "Functions"), and where the documentation is
//! silent or differs, what LinuxCNC 2.9's `rs274` does (checked by running it: the golden values in
//! `tests/data/expr_golden.csv` and the cases named in the tests below).
//!
//! Rules, as LinuxCNC has them:
//! - Blanks are ignored everywhere in an expression, also inside numbers and names
//!   (`[1 0]` is 10, `#<a b>` is `#<ab>`); letters are case-insensitive.
//! - Numbers: `[+-]digits[.digits]` with at least one digit; no exponent (`1e3` is an error).
//! - Precedence, highest first: `**`; `* / MOD`; `+ -`; `EQ NE GT GE LT LE`; `AND OR XOR`.
//!   Every level is left-associative (`2**3**2` is 64). A leading `-` or `+` belongs to the
//!   value right after it (`[-2**2]` is 4, `[2*-3]` is -6, `[--2]` is 2).
//! - `EQ` and `NE` compare with a tolerance of 0.0001 (rs274 2.9; the documentation says 1e-6,
//!   but `[1 EQ 1.00009]` is 1 in rs274); `LT LE GT GE` compare exactly.
//!   `AND OR XOR` treat 0 as false and anything else as true and give 1 or 0.
//! - `MOD` is `fmod` made non-negative by adding `|b|` (`-7 MOD 3` is 2). `a ** b` with `a < 0`
//!   and a non-integer `b` is an error, as is `/` by zero. A *value* that is not finite (a
//!   bracket, a function result, a parameter, the word's value) is an error ("Calculation
//!   resulted in 'infinity'" / "'not a number'"), but the result of one operator inside an
//!   expression is not checked: `[5 MOD 0 LE 2]` is 0 in rs274 and here.
//! - Functions take `[arg]`; angles in degrees: `ABS ACOS ASIN COS EXP FIX (floor) FUP (ceil)
//!   ROUND (half away from zero) LN SIN SQRT TAN`, `ATAN[y]/[x]` (four-quadrant), and
//!   `EXISTS[#<name>]`. ACOS/ASIN outside [-1, 1], LN of a value ≤ 0 and SQRT of a negative
//!   value are errors. (rs274's ROUND converts through a C `int`; a value beyond ±2³¹ gives
//!   garbage there, so it is refused here.)
//! - `#n` reads numbered parameter `n`, 1…5601 (`#0` and `#5602` are "Parameter number out of
//!   range"); the index is a *value*, not an expression (`#1+2` is `[#1]+2`), it may be a
//!   parameter (`##2`), an expression (`#[1+2]`) or a number within 0.0001 of an integer.
//! - Assignments `#n=value`, `#<name>=value` (the right side is one value, not a bare
//!   expression: `#1=1+2` is an error) take effect at the **end of the line, in order**: every
//!   read on the line sees the values from before the line (`#1=5 G0 X#1` moves to the old #1),
//!   and of two settings of one parameter the last wins.
//! - Named parameters are case-insensitive with blanks removed; `#<_name>` is global, `#<name>`
//!   local to the (sub)program: without subroutines they behave alike. A named parameter comes
//!   into existence when an assignment to it is *read* on a line: it then reads 0 for the rest of
//!   that line (`#<b>=[#<b>+5]` on a fresh name gives 5, `#<d>=3 G0 X#<d>` moves to 0,
//!   `G0 X#<d> #<d>=3` is an error) and `EXISTS` is 1 from there on.
//!
//! Reading a parameter that was not set (a deliberate, documented choice):
//! - Numbered 1…5000: 0, as LinuxCNC gives for parameters not yet set after it starts. (In a
//!   running LinuxCNC they keep values from earlier programs; a program that relies on that is
//!   not reproducible by any tool.)
//! - Numbered 5001…5601 (offsets, G28/G30 homes, probe results, the current tool and position,
//!   …): **refused**, naming what the parameter holds, unless the program set it earlier or the
//!   caller seeded it ([`Params::set_numbered`], e.g. G54 from the offsets file). Their values
//!   live in the machine's `.var` file or its state, which mtec cannot see.
//! - Named: LinuxCNC's error `Named parameter #<x> not defined`; for LinuxCNC's predefined
//!   names (`#<_x>`, `#<_metric>`, `#<_ini[..]..>`, `#<_hal[..]>`, …) a refusal saying they
//!   depend on the machine. Assigning to a predefined name is LinuxCNC's error.
//!
//! Parameters above 5000 mirror state that G codes change (G92 rewrites #5211…, G10 L2 the
//! work offsets, a move the positions). This store does not see G codes: after each block the
//! caller forgets what the block rewrote ([`system_parameters_written_by`],
//! [`Params::forget_numbered`]) and re-seeds what it tracks exactly, so no stale value is read.
//!
//! Errors carry a 1-based byte `column` in the line, as [`super::lexer::LexError`] does. Words
//! reach this module through [`super::lexer`], which refuses a few spellings rs274 accepts
//! (blanks inside a number outside brackets `X1 0`, `#1.0`, `#-1`): refused, never misread.
//!
//! Checked against rs274 beyond the hand-picked golden values (`tests/data/expr_golden.csv`,
//! 103 rows): `expr_random_rs274.csv` (~800 random expressions) and
//! `expr_assign_random_rs274.csv` (700 random programs of assignments); the tests require
//! rs274's value (to 5e-5) or a refusal where rs274 refused, for every row.

use super::code::GCode;
use super::lexer::{Token, TokenKind};
use std::collections::HashMap;
use std::ops::Range;

/// The highest numbered parameter LinuxCNC has (RS274NGC_MAX_PARAMETERS − 1 in 2.9).
pub const MAX_PARAMETER: u32 = 5601;

/// LinuxCNC's tolerance for `EQ` and `NE` (TOLERANCE_EQUAL): 0.0001 in rs274 2.9, although the
/// documentation says 1e-6 (`[1 EQ 1.00009]` is 1 there).
const TOLERANCE_EQUAL: f64 = 0.0001;

/// How deep `[` may nest before the input is refused (LinuxCNC's lines are ≤ 256 characters,
/// so real programs never come near; this only guards against stack exhaustion).
const MAX_DEPTH: usize = 64;

/// An expression or parameter that cannot be evaluated; `column` is 1-based (bytes in the line).
#[derive(Debug, Clone, PartialEq)]
pub struct ExprError {
    pub column: usize,
    pub message: String,
}

impl std::fmt::Display for ExprError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "column {}: {}", self.column, self.message)
    }
}

impl std::error::Error for ExprError {}

fn err(pos: usize, message: impl Into<String>) -> ExprError {
    ExprError {
        column: pos + 1,
        message: message.into(),
    }
}

/// A parameter: numbered (1…5601) or named (lower case, blanks removed, without `<>`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum ParamRef {
    Numbered(u32),
    Named(String),
}

impl ParamRef {
    /// True for numbered parameters above 5000: they hold offsets, homes and machine state, so
    /// a program that assigns one changes how its coordinates reach the machine (the rewriter
    /// must track or refuse such an assignment).
    pub fn is_system(&self) -> bool {
        matches!(self, ParamRef::Numbered(n) if *n > 5000)
    }
}

impl std::fmt::Display for ParamRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamRef::Numbered(n) => write!(f, "#{n}"),
            ParamRef::Named(s) => write!(f, "#<{s}>"),
        }
    }
}

/// What a system parameter holds (for the refusal message), or None for 1…5000.
pub fn system_parameter_meaning(n: u32) -> Option<&'static str> {
    Some(match n {
        0..=5000 => return None,
        5021..=5029 => "the current machine (G53) position",
        5061..=5069 => "a G38 probe result",
        5070 => "the G38 probe success flag",
        5081..=5089 => "the tool length offset in effect",
        5161..=5169 => "the G28 home position",
        5181..=5189 => "the G30 home position",
        5210 => "the G52/G92 offset flag",
        5211..=5219 => "the G52/G92 offset",
        5220 => "the active coordinate system number",
        5221..=5390 => "a G54-G59.3 work offset or rotation",
        5399 => "the M66 input result",
        5400 => "the current tool number",
        5401..=5409 => "the loaded tool's offsets",
        5410..=5413 => "the loaded tool's diameter, angles or orientation",
        5420..=5428 => "the current position",
        _ => "a value of the machine's state or parameter file",
    })
}

/// Numbered parameters LinuxCNC refuses to assign ("Parameter is readonly"): the current tool,
/// its offsets and geometry, and the current position (checked with rs274 for each number
/// 5400-5429: 5414-5419 and 5429 are writable).
fn numbered_read_only(n: u32) -> bool {
    matches!(n, 5400..=5413 | 5420..=5428)
}

/// The system parameters the interpreter itself rewrites when a block has these G codes, M
/// codes, or moves the machine: G10 (tool table and work offsets), G28.1/G30.1
/// (homes), G52/G92/G92.x (#5210-#5219), G54-G59.3 (#5220), G43/G49 (#5081-#5089), G38.x
/// (probe results), M6/M61 (tool), M66 (#5399), any motion (positions #5021-#5029, #5420-#5428).
/// Checked with rs274: `#5211=3` then `G92 X10` leaves 10 in #5211.
pub fn system_parameters_written_by(
    g_codes: &[(GCode, usize)],
    m_codes: &[(u32, usize)],
    moves: bool,
) -> Vec<std::ops::RangeInclusive<u32>> {
    let mut out = Vec::new();
    for_each_system_parameter_range(g_codes, m_codes, moves, |r| out.push(r));
    out
}

/// [`system_parameters_written_by`] without the vector: `f` gets each range (the rewriter
/// calls it for every block, so it allocates nothing).
pub fn for_each_system_parameter_range(
    g_codes: &[(GCode, usize)],
    m_codes: &[(u32, usize)],
    moves: bool,
    mut f: impl FnMut(std::ops::RangeInclusive<u32>),
) {
    use GCode::*;
    for &(g, _) in g_codes {
        match g {
            G10 => {
                f(5221..=5390);
                f(5400..=5413);
            }
            G28_1 => f(5161..=5169),
            G30_1 => f(5181..=5189),
            G52 | G92 | G92_1 | G92_2 | G92_3 => f(5210..=5219),
            G54 | G55 | G56 | G57 | G58 | G59 | G59_1 | G59_2 | G59_3 => f(5220..=5220),
            G43 | G43_1 | G43_2 | G49 => f(5081..=5089),
            G38_2 | G38_3 | G38_4 | G38_5 => f(5061..=5070),
            _ => {}
        }
    }
    for &(m, _) in m_codes {
        match m {
            6 | 61 => f(5400..=5413),
            66 => f(5399..=5399),
            _ => {}
        }
    }
    if moves {
        f(5021..=5029);
        f(5420..=5428);
    }
}

/// LinuxCNC 2.9's predefined (read-only) named parameters, without the leading `_`.
const PREDEFINED: &[&str] = &[
    "vmajor",
    "vminor",
    "line",
    "motion_mode",
    "plane",
    "ccomp",
    "metric",
    "imperial",
    "absolute",
    "incremental",
    "inverse_time",
    "units_per_minute",
    "units_per_rev",
    "coord_system",
    "tool_offset",
    "retract_r_plane",
    "retract_old_z",
    "spindle_rpm_mode",
    "spindle_css_mode",
    "ijk_absolute_mode",
    "lathe_diameter_mode",
    "lathe_radius_mode",
    "spindle_on",
    "spindle_cw",
    "mist",
    "flood",
    "speed_override",
    "feed_override",
    "adaptive_feed",
    "feed_hold",
    "feed",
    "rpm",
    "x",
    "y",
    "z",
    "a",
    "b",
    "c",
    "u",
    "v",
    "w",
    "abs_x",
    "abs_y",
    "abs_z",
    "abs_a",
    "abs_b",
    "abs_c",
    "abs_u",
    "abs_v",
    "abs_w",
    "current_tool",
    "current_pocket",
    "selected_tool",
    "selected_pocket",
    "value",
    "value_returned",
    "task",
    "call_level",
    "remap_level",
];

/// True for LinuxCNC's predefined named parameters (`_x`, `_ini[...]...`, `_hal[...]`, …).
pub fn is_predefined_name(name: &str) -> bool {
    match name.strip_prefix('_') {
        Some(rest) => {
            rest.starts_with("ini[") || rest.starts_with("hal[") || PREDEFINED.contains(&rest)
        }
        None => false,
    }
}

/// The parameter store: numbered and named parameters set so far.
#[derive(Debug, Clone)]
pub struct Params {
    numbered: Vec<Option<f64>>,
    named: HashMap<String, f64>,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            numbered: vec![None; MAX_PARAMETER as usize + 1],
            named: HashMap::new(),
        }
    }
}

/// One assignment of a line, evaluated with the values from before the line.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    pub target: ParamRef,
    pub value: f64,
    /// Index of the assignment's token in the line.
    pub token: usize,
}

/// The values of one line: every word's value (by token index) and the assignments to apply at
/// the end of the line. Reuse one across lines: its buffers are kept.
#[derive(Debug, Clone, Default)]
pub struct LineValues {
    values: Vec<Option<f64>>,
    pub assignments: Vec<Assignment>,
}

impl LineValues {
    /// The value of the word at `token` (None for tokens that are not words).
    pub fn word(&self, token: usize) -> Option<f64> {
        self.values.get(token).copied().flatten()
    }
}

impl Params {
    pub fn new() -> Self {
        Self::default()
    }

    /// The stored value, if the parameter was set (no defaults, no refusals).
    pub fn get(&self, p: &ParamRef) -> Option<f64> {
        match p {
            ParamRef::Numbered(n) => self.numbered.get(*n as usize).copied().flatten(),
            ParamRef::Named(s) => self.named.get(s).copied(),
        }
    }

    /// Seeds a numbered parameter the caller knows (e.g. #5221–#5223 from the offsets file).
    /// LinuxCNC keeps the offsets in these parameters in **machine units** (rs274, whose
    /// stand-alone machine is in inches: `G21 #5221=10` makes a G54 X offset of 254 mm), so
    /// convert before seeding. (An assignment to #5221 while G54 is active does not move the
    /// current offset in rs274: `#5221=10 G0 X0` and a later `G0 X1` still use the old one.)
    pub fn set_numbered(&mut self, n: u32, value: f64) -> Result<(), String> {
        if n == 0 || n > MAX_PARAMETER {
            return Err(format!("parameter #{n} is not 1..{MAX_PARAMETER}"));
        }
        if !value.is_finite() {
            return Err(format!("parameter #{n}: value is not finite"));
        }
        self.numbered[n as usize] = Some(value);
        Ok(())
    }

    /// Forgets numbered parameters (reading one above 5000 is then refused until it is set
    /// again). Call it with [`system_parameters_written_by`] after each block, so a value the
    /// interpreter rewrote (a G92, a G10, a move) is never read stale; re-seed with
    /// [`Params::set_numbered`] what the caller tracks exactly.
    pub fn forget_numbered(&mut self, range: std::ops::RangeInclusive<u32>) {
        let start = *range.start() as usize;
        let end = (*range.end() as usize)
            .saturating_add(1)
            .min(self.numbered.len());
        if start < end {
            self.numbered[start..end].fill(None);
        }
    }

    /// Sets a named parameter (the name is normalised: lower case, blanks removed, no `<>`).
    pub fn set_named(&mut self, name: &str, value: f64) {
        self.named.insert(normalize_name(name.as_bytes()), value);
    }

    /// Evaluates every word and assignment of a lexed line, as LinuxCNC reads the line from left
    /// to right, with the parameter values from before the line. Nothing is changed: call
    /// [`Params::commit`] (or use [`Params::apply_line`]) when the line is accepted.
    pub fn eval_line(
        &self,
        line: &[u8],
        tokens: &[Token],
        out: &mut LineValues,
    ) -> Result<(), ExprError> {
        out.values.clear();
        out.values.resize(tokens.len(), None);
        out.assignments.clear();
        for (i, t) in tokens.iter().enumerate() {
            match t.kind {
                TokenKind::Word { value, .. } => {
                    out.values[i] = Some(match value {
                        super::lexer::Value::Number(v) => v,
                        super::lexer::Value::Computed => {
                            eval_in(line, t.value_span.clone(), self, &out.assignments)?
                        }
                    });
                }
                TokenKind::Assignment { .. } => {
                    let mut c = Cursor::new(line, t.span.start, t.value_span.start);
                    let ctx = Ctx {
                        params: self,
                        pending: &out.assignments,
                    };
                    let target = c.param_target(&ctx)?;
                    if let ParamRef::Numbered(n) = target {
                        if numbered_read_only(n) {
                            return Err(err(t.span.start, "Parameter is readonly"));
                        }
                    }
                    if let ParamRef::Named(name) = &target {
                        if is_predefined_name(name) {
                            return Err(err(
                                t.span.start,
                                format!("Cannot assign to read-only parameter #<{name}>"),
                            ));
                        }
                    }
                    // the target exists (reads 0 if new) from here on, also for its own value
                    out.assignments.push(Assignment {
                        target,
                        value: 0.0,
                        token: i,
                    });
                    let v = eval_in(line, t.value_span.clone(), self, &out.assignments)?;
                    if let Some(a) = out.assignments.last_mut() {
                        a.value = v;
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Applies a line's assignments in order (the last setting of a parameter wins).
    pub fn commit(&mut self, values: &LineValues) {
        for a in &values.assignments {
            match &a.target {
                ParamRef::Numbered(n) => {
                    if let Some(slot) = self.numbered.get_mut(*n as usize) {
                        *slot = Some(a.value);
                    }
                }
                ParamRef::Named(s) => {
                    if let Some(v) = self.named.get_mut(s) {
                        *v = a.value;
                    } else {
                        self.named.insert(s.clone(), a.value);
                    }
                }
            }
        }
    }

    /// [`Params::eval_line`] then [`Params::commit`]: the line's word values are in `out`.
    pub fn apply_line(
        &mut self,
        line: &[u8],
        tokens: &[Token],
        out: &mut LineValues,
    ) -> Result<(), ExprError> {
        self.eval_line(line, tokens, out)?;
        self.commit(out);
        Ok(())
    }

    fn read_numbered(&self, n: u32, pos: usize) -> Result<f64, ExprError> {
        if let Some(v) = self.numbered.get(n as usize).copied().flatten() {
            return Ok(v);
        }
        match system_parameter_meaning(n) {
            None => Ok(0.0),
            Some(what) => Err(err(
                pos,
                format!(
                    "#{n} holds {what}, which depends on the machine's state or parameter file \
                     and is not known to mtec; write the value itself"
                ),
            )),
        }
    }
}

/// The value of one word or assignment: `span` is the value's text in `line` (a number, `#…`,
/// `[…]`, a function, with an optional sign), read with the parameter values in `params`.
/// The whole span must be one value.
pub fn eval_value(line: &[u8], span: Range<usize>, params: &Params) -> Result<f64, ExprError> {
    eval_in(line, span, params, &[])
}

/// The assignments of a lexed line, evaluated with the values from before the line (what
/// [`Params::eval_line`] gives in [`LineValues::assignments`]).
pub fn assignments(
    line: &[u8],
    tokens: &[Token],
    params: &Params,
) -> Result<Vec<Assignment>, ExprError> {
    let mut lv = LineValues::default();
    params.eval_line(line, tokens, &mut lv)?;
    Ok(lv.assignments)
}

fn eval_in(
    line: &[u8],
    span: Range<usize>,
    params: &Params,
    pending: &[Assignment],
) -> Result<f64, ExprError> {
    let end = span.end.min(line.len());
    let start = span.start.min(end);
    let mut c = Cursor::new(line, start, end);
    let ctx = Ctx { params, pending };
    let v = c.value(&ctx, 0)?;
    c.skip();
    if c.pos < c.end {
        return Err(err(c.pos, "unexpected text after the value"));
    }
    Ok(v)
}

/// Lower case, blanks removed, as LinuxCNC stores names.
fn normalize_name(name: &[u8]) -> String {
    let name = name.strip_prefix(b"<").unwrap_or(name);
    let name = name.strip_suffix(b">").unwrap_or(name);
    name.iter()
        .filter(|b| !is_blank(**b))
        .map(|b| b.to_ascii_lowercase() as char)
        .collect()
}

fn is_blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | 0x0b | 0x0c)
}

struct Ctx<'a> {
    params: &'a Params,
    pending: &'a [Assignment],
}

impl Ctx<'_> {
    fn named(&self, name: &str, pos: usize) -> Result<f64, ExprError> {
        if let Some(v) = self.params.named.get(name) {
            return Ok(*v);
        }
        if self
            .pending
            .iter()
            .any(|a| matches!(&a.target, ParamRef::Named(s) if s == name))
        {
            return Ok(0.0);
        }
        if is_predefined_name(name) {
            return Err(err(
                pos,
                format!(
                    "#<{name}> is one of LinuxCNC's predefined parameters: its value depends on \
                     the machine or interpreter state, which mtec does not know"
                ),
            ));
        }
        Err(err(pos, format!("Named parameter #<{name}> not defined")))
    }

    fn exists(&self, name: &str, pos: usize) -> Result<f64, ExprError> {
        if self.params.named.contains_key(name)
            || self
                .pending
                .iter()
                .any(|a| matches!(&a.target, ParamRef::Named(s) if s == name))
        {
            Ok(1.0)
        } else if is_predefined_name(name) {
            Err(err(
                pos,
                format!(
                    "EXISTS[#<{name}>]: a predefined parameter, whether it exists depends on \
                     the LinuxCNC version and configuration"
                ),
            ))
        } else {
            Ok(0.0)
        }
    }
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Op {
    Pow,
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

impl Op {
    fn precedence(self) -> u8 {
        match self {
            Op::Pow => 5,
            Op::Mul | Op::Div | Op::Mod => 4,
            Op::Add | Op::Sub => 3,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 2,
            Op::And | Op::Or | Op::Xor => 1,
        }
    }

    fn apply(self, a: f64, b: f64, pos: usize) -> Result<f64, ExprError> {
        let t = |c: bool| if c { 1.0 } else { 0.0 };
        let r = match self {
            Op::Pow => {
                if a < 0.0 && b.floor() != b {
                    return Err(err(pos, "Attempt to raise negative to non integer power"));
                }
                a.powf(b)
            }
            Op::Mul => a * b,
            Op::Div => {
                if b == 0.0 {
                    return Err(err(pos, "Attempt to divide by zero"));
                }
                a / b
            }
            Op::Mod => {
                let r = a % b;
                if r < 0.0 {
                    r + b.abs()
                } else {
                    r
                }
            }
            Op::Add => a + b,
            Op::Sub => a - b,
            Op::Eq => t((a - b).abs() < TOLERANCE_EQUAL),
            Op::Ne => t((a - b).abs() >= TOLERANCE_EQUAL),
            Op::Gt => t(a > b),
            Op::Ge => t(a >= b),
            Op::Lt => t(a < b),
            Op::Le => t(a <= b),
            Op::And => t(a != 0.0 && b != 0.0),
            Op::Or => t(a != 0.0 || b != 0.0),
            Op::Xor => t((a != 0.0) != (b != 0.0)),
        };
        // not checked for NaN or infinity here: rs274 lets them flow through the operators of
        // an expression (`[5 MOD 0 LE 2]` is 0) and only refuses a value that is not finite
        Ok(r)
    }
}

fn finite(r: f64, pos: usize) -> Result<f64, ExprError> {
    if r.is_nan() {
        Err(err(pos, "Calculation resulted in 'not a number'"))
    } else if r.is_infinite() {
        Err(err(pos, "Calculation resulted in 'infinity'"))
    } else {
        Ok(r)
    }
}

/// A position in the line that skips blanks, as LinuxCNC removes them before reading.
struct Cursor<'a> {
    line: &'a [u8],
    pos: usize,
    end: usize,
}

impl<'a> Cursor<'a> {
    fn new(line: &'a [u8], pos: usize, end: usize) -> Self {
        Cursor { line, pos, end }
    }

    fn skip(&mut self) {
        while self.pos < self.end && is_blank(self.line[self.pos]) {
            self.pos += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip();
        (self.pos < self.end).then(|| self.line[self.pos])
    }

    fn bump(&mut self) {
        self.pos += 1;
    }

    fn expect(&mut self, c: u8, what: &str) -> Result<(), ExprError> {
        if self.peek() == Some(c) {
            self.bump();
            Ok(())
        } else {
            Err(err(self.pos.min(self.end), what.to_string()))
        }
    }

    /// One value: number, parameter, `[expression]`, function, or a signed value. As in
    /// rs274, a value (not an intermediate result of an operator) must be finite.
    fn value(&mut self, ctx: &Ctx, depth: usize) -> Result<f64, ExprError> {
        if depth > MAX_DEPTH {
            return Err(err(self.pos, "expression nested too deeply"));
        }
        self.skip();
        let at = self.pos;
        let v = self.value_inner(ctx, depth)?;
        finite(v, at)
    }

    fn value_inner(&mut self, ctx: &Ctx, depth: usize) -> Result<f64, ExprError> {
        match self.peek() {
            None | Some(b']') => Err(err(self.pos.min(self.end), "a value is missing here")),
            Some(b'[') => {
                self.bump();
                self.expression(ctx, depth + 1)
            }
            Some(b'#') => {
                let p = self.pos;
                match self.param_ref(ctx, depth)? {
                    ParamRef::Numbered(n) => ctx.params.read_numbered(n, p),
                    ParamRef::Named(name) => ctx.named(&name, p),
                }
            }
            Some(b'-') => {
                self.bump();
                Ok(-self.value(ctx, depth + 1)?)
            }
            Some(b'+') => {
                self.bump();
                self.value(ctx, depth + 1)
            }
            Some(c) if c.is_ascii_alphabetic() => self.function(ctx, depth),
            Some(c) if c.is_ascii_digit() || c == b'.' => self.number(),
            Some(c) => Err(err(
                self.pos,
                format!("Bad character '{}' used", (c as char).escape_default()),
            )),
        }
    }

    /// `[` already consumed: operators and values up to the matching `]`.
    fn expression(&mut self, ctx: &Ctx, depth: usize) -> Result<f64, ExprError> {
        let v = self.value(ctx, depth)?;
        let v = self.climb(ctx, depth, v, 0)?;
        match self.peek() {
            Some(b']') => {
                self.bump();
                Ok(v)
            }
            _ => Err(err(
                self.pos.min(self.end),
                "expression not closed: ']' expected",
            )),
        }
    }

    /// Precedence climbing; all operators left-associative.
    fn climb(&mut self, ctx: &Ctx, depth: usize, mut lhs: f64, min: u8) -> Result<f64, ExprError> {
        loop {
            let save = self.pos;
            let Some((op, op_pos)) = self.operator()? else {
                return Ok(lhs);
            };
            if op.precedence() < min.max(1) {
                self.pos = save;
                return Ok(lhs);
            }
            let mut rhs = self.value(ctx, depth)?;
            loop {
                let save2 = self.pos;
                match self.operator()? {
                    Some((next, _)) if next.precedence() > op.precedence() => {
                        self.pos = save2;
                        rhs = self.climb(ctx, depth, rhs, next.precedence())?;
                    }
                    _ => {
                        self.pos = save2;
                        break;
                    }
                }
            }
            lhs = op.apply(lhs, rhs, op_pos)?;
        }
    }

    /// Reads a binary operator, or None at `]` / the end.
    fn operator(&mut self) -> Result<Option<(Op, usize)>, ExprError> {
        let Some(c) = self.peek() else {
            return Ok(None);
        };
        let at = self.pos;
        let op = match c {
            b']' => return Ok(None),
            b'*' => {
                self.bump();
                if self.peek() == Some(b'*') {
                    self.bump();
                    Op::Pow
                } else {
                    Op::Mul
                }
            }
            b'/' => {
                self.bump();
                Op::Div
            }
            b'+' => {
                self.bump();
                Op::Add
            }
            b'-' => {
                self.bump();
                Op::Sub
            }
            c if c.is_ascii_alphabetic() => {
                let mut name = [0u8; 3];
                let mut k = 0;
                while k < 3 {
                    match self.peek() {
                        Some(c) if c.is_ascii_alphabetic() => {
                            name[k] = c.to_ascii_lowercase();
                            k += 1;
                            self.bump();
                            if let Some(op) = named_op(&name[..k]) {
                                return Ok(Some((op, at)));
                            }
                        }
                        _ => break,
                    }
                }
                return Err(err(
                    at,
                    format!(
                        "Unknown operation name starting with {}",
                        (c.to_ascii_lowercase()) as char
                    ),
                ));
            }
            c => {
                return Err(err(
                    at,
                    format!(
                        "Unknown operation '{}': an operator or ']' is expected",
                        (c as char).escape_default()
                    ),
                ));
            }
        };
        Ok(Some((op, at)))
    }

    fn number(&mut self) -> Result<f64, ExprError> {
        let start = self.pos;
        let mut buf = [0u8; 64];
        let mut k = 0;
        let mut digits = 0;
        let mut point = false;
        while let Some(c) = self.peek() {
            if c.is_ascii_digit() {
                digits += 1;
            } else if c == b'.' && !point {
                point = true;
            } else if c == b'.' {
                return Err(err(self.pos, "bad number format: a second decimal point"));
            } else {
                break;
            }
            if k < buf.len() {
                buf[k] = c;
                k += 1;
            } else if c == b'.' || !point {
                return Err(err(start, "number too long"));
            } // digits far after the point do not change an f64
            self.bump();
        }
        if digits == 0 {
            return Err(err(start, "bad number format: no digits"));
        }
        std::str::from_utf8(&buf[..k])
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| err(start, "number cannot be read"))
    }

    /// `#…` at the cursor: the parameter it names (indices evaluated).
    fn param_ref(&mut self, ctx: &Ctx, depth: usize) -> Result<ParamRef, ExprError> {
        self.expect(b'#', "'#' expected")?;
        if depth > MAX_DEPTH {
            return Err(err(self.pos, "expression nested too deeply"));
        }
        let pos = self.pos;
        if self.peek() == Some(b'<') {
            let open = self.pos;
            let close = self.line[open..self.end]
                .iter()
                .position(|&c| c == b'>')
                .map(|p| p + open)
                .ok_or_else(|| err(open, "parameter name not closed: '<' without '>'"))?;
            let name = normalize_name(&self.line[open + 1..close]);
            if name.is_empty() {
                return Err(err(open, "parameter name is empty"));
            }
            if !name.bytes().all(|b| b.is_ascii_graphic()) {
                return Err(err(
                    open,
                    "parameter name has a character that is not printable ASCII",
                ));
            }
            self.pos = close + 1;
            return Ok(ParamRef::Named(name));
        }
        let v = self.value(ctx, depth + 1)?;
        let r = v.round();
        if (v - r).abs() > 0.0001 {
            return Err(err(pos, "Non integer value for integer"));
        }
        if r < 1.0 || r > MAX_PARAMETER as f64 {
            return Err(err(pos, "Parameter number out of range"));
        }
        Ok(ParamRef::Numbered(r as u32))
    }

    /// The target of an assignment token `#…=`: the cursor ends after the `=`.
    fn param_target(&mut self, ctx: &Ctx) -> Result<ParamRef, ExprError> {
        // the index of `#<v>=` or `#n=` is a value: stop it at '='
        let eq = self.line[self.pos..self.end]
            .iter()
            .rposition(|&c| c == b'=')
            .map(|p| p + self.pos);
        let Some(eq) = eq else {
            return Err(err(self.pos, "assignment without '='"));
        };
        let end = self.end;
        self.end = eq;
        let r = self.param_ref(ctx, 0)?;
        self.skip();
        if self.pos != eq {
            return Err(err(self.pos, "unexpected text before '='"));
        }
        self.end = end;
        self.pos = eq + 1;
        Ok(r)
    }

    fn function(&mut self, ctx: &Ctx, depth: usize) -> Result<f64, ExprError> {
        let at = self.pos;
        let mut name = [0u8; 6];
        let mut k = 0;
        while let Some(c) = self.peek() {
            if !c.is_ascii_alphabetic() {
                break;
            }
            if k == name.len() {
                return Err(err(
                    at,
                    "Unknown word starting with a letter: not a function",
                ));
            }
            name[k] = c.to_ascii_lowercase();
            k += 1;
            self.bump();
        }
        let name = &name[..k];
        let known = matches!(
            name,
            b"abs"
                | b"acos"
                | b"asin"
                | b"atan"
                | b"cos"
                | b"exists"
                | b"exp"
                | b"fix"
                | b"fup"
                | b"ln"
                | b"round"
                | b"sin"
                | b"sqrt"
                | b"tan"
        );
        if !known {
            return Err(err(
                at,
                format!(
                    "Unknown function '{}'",
                    String::from_utf8_lossy(name).to_uppercase()
                ),
            ));
        }
        if self.peek() != Some(b'[') {
            return Err(err(
                self.pos.min(self.end),
                "Left bracket missing after unary operation name",
            ));
        }
        self.bump();
        if name == b"exists" {
            let p = self.pos;
            if self.peek() != Some(b'#') {
                return Err(err(p, "EXISTS takes one named parameter: EXISTS[#<name>]"));
            }
            let r = self.param_ref(ctx, depth + 1)?;
            let ParamRef::Named(n) = r else {
                return Err(err(p, "EXISTS takes a named parameter, not a numbered one"));
            };
            self.expect(b']', "']' expected after EXISTS[#<name>")?;
            return ctx.exists(&n, p);
        }
        let a = self.expression(ctx, depth + 1)?;
        let deg = std::f64::consts::PI / 180.0;
        let r = match name {
            b"abs" => a.abs(),
            b"acos" => {
                if !(-1.0..=1.0).contains(&a) {
                    return Err(err(at, "Argument to acos out of range"));
                }
                a.acos() / deg
            }
            b"asin" => {
                if !(-1.0..=1.0).contains(&a) {
                    return Err(err(at, "Argument to asin out of range"));
                }
                a.asin() / deg
            }
            b"atan" => {
                if self.peek() != Some(b'/') {
                    return Err(err(
                        self.pos.min(self.end),
                        "Slash missing after first atan argument",
                    ));
                }
                self.bump();
                if self.peek() != Some(b'[') {
                    return Err(err(
                        self.pos.min(self.end),
                        "Left bracket missing after slash with atan",
                    ));
                }
                self.bump();
                let b = self.expression(ctx, depth + 1)?;
                a.atan2(b) / deg
            }
            b"cos" => (a * deg).cos(),
            b"exp" => a.exp(),
            b"fix" => a.floor(),
            b"fup" => a.ceil(),
            b"ln" => {
                if a <= 0.0 {
                    return Err(err(at, "Zero or negative argument to ln"));
                }
                a.ln()
            }
            b"round" => {
                let r = (a + if a < 0.0 { -0.5 } else { 0.5 }).trunc();
                if !(r > -2_147_483_649.0 && r < 2_147_483_648.0) {
                    return Err(err(
                        at,
                        "ROUND of a value beyond ±2147483647: LinuxCNC converts it through a \
                         C int and gives no defined result",
                    ));
                }
                r
            }
            b"sin" => (a * deg).sin(),
            b"sqrt" => {
                if a < 0.0 {
                    return Err(err(at, "Negative argument to sqrt"));
                }
                a.sqrt()
            }
            _ => (a * deg).tan(), // "tan"
        };
        finite(r, at)
    }
}

fn named_op(name: &[u8]) -> Option<Op> {
    Some(match name {
        b"mod" => Op::Mod,
        b"eq" => Op::Eq,
        b"ne" => Op::Ne,
        b"gt" => Op::Gt,
        b"ge" => Op::Ge,
        b"lt" => Op::Lt,
        b"le" => Op::Le,
        b"and" => Op::And,
        b"or" => Op::Or,
        b"xor" => Op::Xor,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::super::lexer::lex_line;
    use super::*;

    /// Runs `lines` through lexer and parameters; returns the X word value of the last line.
    fn run(params: &mut Params, lines: &[&str]) -> Result<Option<f64>, ExprError> {
        let mut toks = Vec::new();
        let mut lv = LineValues::default();
        let mut x = None;
        for l in lines {
            lex_line(l.as_bytes(), 0, &mut toks).map_err(|e| ExprError {
                column: e.column,
                message: e.message,
            })?;
            params.apply_line(l.as_bytes(), &toks, &mut lv)?;
            x = toks.iter().enumerate().find_map(|(i, t)| match t.kind {
                TokenKind::Word { letter: b'X', .. } => lv.word(i),
                _ => None,
            });
        }
        Ok(x)
    }

    fn x(expr: &str) -> Result<f64, ExprError> {
        let line = format!("G0 X{expr}");
        Ok(run(&mut Params::new(), &[&line])?.unwrap())
    }

    #[test]
    fn golden_values_from_rs274() {
        let text = include_str!("../../tests/data/expr_golden.csv");
        let mut n = 0;
        for row in text.lines().filter(|l| !l.starts_with("%%")).skip(1) {
            let mut f = row.split(',');
            let (setup, line, want) = (f.next().unwrap(), f.next().unwrap(), f.next().unwrap());
            let want: f64 = want.parse().unwrap();
            let mut lines: Vec<&str> = setup
                .split('|')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .collect();
            lines.push(line);
            let got = run(&mut Params::new(), &lines)
                .unwrap_or_else(|e| panic!("{row}: {e}"))
                .unwrap_or_else(|| panic!("{row}: no X"));
            assert!(
                (got - want).abs() <= 5e-5,
                "{row}: mtec {got}, rs274 {want}"
            );
            n += 1;
        }
        assert!(n >= 60, "only {n} golden rows");
    }

    #[test]
    fn random_expressions_agree_with_rs274() {
        agree_with_rs274(
            include_str!("../../tests/data/expr_random_rs274.csv"),
            500,
            100,
        );
    }

    #[test]
    fn random_assignment_programs_agree_with_rs274() {
        agree_with_rs274(
            include_str!("../../tests/data/expr_assign_random_rs274.csv"),
            400,
            200,
        );
    }

    /// Every row: rs274's value (to 5e-5) or, where rs274 refused the program, a refusal.
    fn agree_with_rs274(text: &str, min_values: usize, min_errors: usize) {
        let (mut values, mut errors) = (0, 0);
        for row in text.lines().filter(|l| !l.starts_with("%%")).skip(1) {
            let mut f = row.splitn(3, ',');
            let (setup, line, want) = (f.next().unwrap(), f.next().unwrap(), f.next().unwrap());
            let mut lines: Vec<&str> = setup.split(" | ").collect();
            lines.push(line);
            let got = run(&mut Params::new(), &lines);
            match (want.strip_prefix("ERR "), got) {
                // rs274 refused it: so must we (lexer or evaluator; messages may differ)
                (Some(_), Err(_)) => errors += 1,
                (None, Ok(Some(v))) => {
                    let w: f64 = want.parse().unwrap();
                    assert!(
                        (v - w).abs() <= 5e-5 + 1e-12 * w.abs(),
                        "{line}: mtec {v}, rs274 {w}"
                    );
                    values += 1;
                }
                (_, got) => panic!("{line}: rs274 {want}, mtec {got:?}"),
            }
        }
        assert!(
            values >= min_values && errors >= min_errors,
            "{values} values, {errors} errors"
        );
    }

    #[test]
    fn not_finite_intermediate_results_flow_as_in_rs274() {
        // rs274 checks values, not the results of single operators
        assert_eq!(x("[5 MOD 0 LE 2]").unwrap(), 0.0);
        assert_eq!(x("[0 ** -1 NE 3]").unwrap(), 1.0);
        assert!(x("[[0 ** -1] NE 3]").is_err()); // a bracket is a value
        assert!(x("[EXP[1000]]").is_err());
        assert!(x("[[5 MOD 0]]").is_err());
    }

    #[test]
    fn errors_are_linuxcnc_s_and_located() {
        // (expression, message fragment as rs274 prints it, 1-based column in "G0 X…")
        for (e, msg, col) in [
            ("[1/0]", "Attempt to divide by zero", 7),
            ("[sqrt[-1]]", "Negative argument to sqrt", 6),
            ("[acos[2]]", "Argument to acos out of range", 6),
            ("[asin[-2]]", "Argument to asin out of range", 6),
            ("[ln[0]]", "Zero or negative argument to ln", 6),
            (
                "[[-8]**[1/3]]",
                "Attempt to raise negative to non integer power",
                10,
            ),
            ("[5 MOD 0]", "not a number", 5),
            ("[0**-1]", "infinity", 5),
            ("[atan[1]]", "Slash missing after first atan argument", 13),
            ("[1e3]", "Unknown operation name starting with e", 7),
            ("[1.2.3]", "second decimal point", 9),
            ("[1+]", "a value is missing", 8),
            ("[]", "a value is missing", 6),
            ("[#0]", "Parameter number out of range", 7),
            ("[#5602]", "Parameter number out of range", 7),
            ("#[1.001]", "Non integer value for integer", 6),
            ("[#<foo>]", "Named parameter #<foo> not defined", 6),
            ("[#5420]", "current position", 6),
            ("[#5400]", "current tool", 6),
            ("[#5061]", "probe", 6),
            ("[#5221]", "work offset", 6),
            ("[#<_x>]", "predefined", 6),
            ("[#<_ini[setup]xpos>]", "predefined", 6),
            ("[exists[#<_x>]]", "predefined", 13),
            ("[exists[#1]]", "named parameter", 13),
            ("[round[3000000000.4]]", "C int", 6),
            ("[foo[1]]", "Unknown function 'FOO'", 6),
            ("[sin 30]", "Left bracket missing", 10),
        ] {
            let r = x(e);
            let Err(err) = r else {
                panic!("{e}: accepted as {r:?}");
            };
            assert!(err.message.contains(msg), "{e}: {err:?}");
            assert_eq!(err.column, col, "{e}: {err:?}");
        }
    }

    #[test]
    fn assignments_take_effect_at_the_end_of_the_line() {
        let mut p = Params::new();
        assert_eq!(run(&mut p, &["#1=3", "#1=5 G0 X#1"]).unwrap(), Some(3.0));
        assert_eq!(p.get(&ParamRef::Numbered(1)), Some(5.0));
        // a named parameter read before its first assignment on the line is an error,
        // after it it reads 0 (rs274: "Named parameter #<d> not defined" / X0)
        let mut p = Params::new();
        let e = run(&mut p, &["G0 X#<d> #<d>=3"]).unwrap_err();
        assert!(e.message.contains("not defined"), "{e:?}");
        assert_eq!(e.column, 5);
        assert_eq!(run(&mut p, &["#<d>=3 G0 X#<d>"]).unwrap(), Some(0.0));
        assert_eq!(p.get(&ParamRef::Named("d".into())), Some(3.0));
        // an error leaves the parameters untouched
        let mut p = Params::new();
        assert!(run(&mut p, &["#1=5 G0 X[1/0]"]).is_err());
        assert_eq!(p.get(&ParamRef::Numbered(1)), None);
        // read-only targets (rs274: "Parameter is readonly", "Cannot assign to read-only …")
        for (l, m) in [
            ("#5420=1", "readonly"),
            ("#5400=1", "readonly"),
            ("#<_x>=1", "read-only"),
            ("#0=1", "out of range"),
        ] {
            let e = run(&mut Params::new(), &[l]).unwrap_err();
            assert!(e.message.contains(m), "{l}: {e:?}");
        }
        // indirect and named targets
        let mut p = Params::new();
        run(&mut p, &["#1=2 #<A b>=7", "##1=4 #[#1+1]=6"]).unwrap();
        assert_eq!(p.get(&ParamRef::Numbered(2)), Some(4.0));
        assert_eq!(p.get(&ParamRef::Numbered(3)), Some(6.0));
        assert_eq!(p.get(&ParamRef::Named("ab".into())), Some(7.0));
        let a = assignments(b"#1=[#1+1] #<q>=2", &lexed("#1=[#1+1] #<q>=2"), &p).unwrap();
        assert_eq!(a.len(), 2);
        assert_eq!(
            (a[0].target.clone(), a[0].value),
            (ParamRef::Numbered(1), 3.0)
        );
        assert!(ParamRef::Numbered(5221).is_system() && !ParamRef::Numbered(5000).is_system());
        // rs274: "#5414=1" and "#5429=1" are accepted, "#5413=1" and "#5428=1" are not
        assert!(run(&mut Params::new(), &["#5414=1 #5429=1 #5021=1"]).is_ok());
        assert!(run(&mut Params::new(), &["#5413=1"]).is_err());
        assert!(run(&mut Params::new(), &["#5428=1"]).is_err());
    }

    #[test]
    fn state_rewritten_by_a_block_is_forgotten() {
        let mut p = Params::new();
        run(&mut p, &["#5211=3 #5221=4 #5161=5 #5021=6 #100=7"]).unwrap();
        assert_eq!(run(&mut p, &["G0 X#5211"]).unwrap(), Some(3.0));
        // after "G92 X10" rs274 holds 10 in #5211: the store must not answer 3
        for r in system_parameters_written_by(&[(GCode::G92, 0)], &[], false) {
            p.forget_numbered(r);
        }
        let e = run(&mut p, &["G0 X#5211"]).unwrap_err();
        assert!(e.message.contains("G52/G92 offset"), "{e:?}");
        assert_eq!(run(&mut p, &["G0 X#5221"]).unwrap(), Some(4.0)); // G92 leaves G54 alone
        let w =
            system_parameters_written_by(&[(GCode::G10, 0), (GCode::G28_1, 1)], &[(6, 2)], true);
        for (n, hit) in [
            (5221, true),
            (5390, true),
            (5161, true),
            (5181, false),
            (5021, true),
        ] {
            assert_eq!(w.iter().any(|r| r.contains(&n)), hit, "#{n}");
        }
        for r in w {
            p.forget_numbered(r);
        }
        assert!(run(&mut p, &["G0 X#5221"]).is_err());
        assert!(run(&mut p, &["G0 X#5021"]).is_err());
        assert_eq!(run(&mut p, &["G0 X#100"]).unwrap(), Some(7.0)); // user parameters stay
        assert!(
            system_parameters_written_by(&[(GCode::G1, 0), (GCode::G90, 1)], &[(3, 2)], false)
                .is_empty()
        );
    }

    fn lexed(l: &str) -> Vec<Token> {
        let mut t = Vec::new();
        lex_line(l.as_bytes(), 0, &mut t).unwrap();
        t
    }

    #[test]
    fn seeded_system_parameters_and_values_of_spans() {
        let mut p = Params::new();
        p.set_numbered(5221, 250.0).unwrap();
        assert!(p.set_numbered(5602, 1.0).is_err());
        assert!(p.set_numbered(1, f64::NAN).is_err());
        p.set_named("<Tool Len>", 85.25);
        let line = b"G0 X[#5221 + #<toollen>] (c)";
        assert_eq!(eval_value(line, 4..24, &p), Ok(335.25));
        assert!(eval_value(line, 4..26, &p).is_err()); // trailing text
        assert!(eval_value(line, 4..8, &p).is_err()); // cut off
                                                      // signed functions lex as one value (rs274: G0 X-sin[30] goes to)
        assert!((x("-sin[30]").unwrap() + 0.5).abs() < 1e-12);
        assert_eq!(x("+COS[0]").unwrap(), 1.0);
        let e = eval_value(b"[1 + 2", 0..6, &p).unwrap_err();
        assert_eq!(
            (e.column, e.message.contains("']' expected")),
            (7, true),
            "{e:?}"
        );
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..200)) {
            let mut p = Params::new();
            p.set_named("a", 1.0);
            let _ = eval_value(&bytes, 0..bytes.len(), &p);
            let _ = eval_value(&bytes, 3..bytes.len() + 5, &p);
            let mut toks = Vec::new();
            if lex_line(&bytes, 0, &mut toks).is_ok() {
                let mut lv = LineValues::default();
                let _ = p.apply_line(&bytes, &toks, &mut lv);
            }
        }

        #[test]
        fn never_panics_on_expression_like_text(s in "[-+*/#<>\\[\\]0-9.a-zA-Z =]{0,80}") {
            let p = Params::new();
            let b = s.as_bytes();
            let _ = eval_value(b, 0..b.len(), &p);
        }
    }

    #[test]
    fn deep_nesting_is_refused_not_a_stack_overflow() {
        let deep = format!("{}1{}", "[".repeat(5000), "]".repeat(5000));
        assert!(eval_value(deep.as_bytes(), 0..deep.len(), &Params::new()).is_err());
        let minus = format!("[{}1]", "-".repeat(5000));
        assert!(eval_value(minus.as_bytes(), 0..minus.len(), &Params::new()).is_err());
        let hashes = format!("{}1", "#".repeat(5000));
        assert!(eval_value(hashes.as_bytes(), 0..hashes.len(), &Params::new()).is_err());
    }
}
