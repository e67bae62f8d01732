//! Shared by the gcode_* integration tests: error models with known values, and a small
//! reference interpreter of the G-code subset the rewriter writes, independent of its
//! modal-state code, used to push programs through the "machine" p + e(p).
#![allow(dead_code)]

use mtec_comp::gcode::lexer::{lex_line, TokenKind, Value};
use mtec_comp::ErrorModel;
use mtec_comp::{GridMap, Outside};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// e = 0 everywhere.
pub struct ZeroModel;
impl ErrorModel for ZeroModel {
    fn error_um(&self, _p: [f64; 3]) -> [f64; 3] {
        [0.0; 3]
    }
    fn describe(&self) -> String {
        "zero model (test)".into()
    }
}

/// A smooth analytic model, linear + quadratic in x, y, z (µm, positions in mm): the kind of
/// error a real machine has (scale errors, squareness, straightness bows), large enough that
/// moves of a few mm need splitting at 0.5 µm.
pub struct PolyModel;
impl ErrorModel for PolyModel {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        let [x, y, z] = p;
        [
            8.0 + 0.30 * x - 0.10 * y + 2e-3 * x * y + 1e-3 * z * z,
            -4.0 + 0.20 * y + 1e-3 * x * x - 0.05 * z,
            3.0 + 0.10 * z + 5e-4 * (x * x + y * y),
        ]
    }
    fn describe(&self) -> String {
        "analytic linear+quadratic test model (test) (µm)".into()
    }
}

/// A constant error: every point needs the same correction.
pub struct ConstModel(pub [f64; 3]);
impl ErrorModel for ConstModel {
    fn error_um(&self, _p: [f64; 3]) -> [f64; 3] {
        self.0
    }
    fn describe(&self) -> String {
        "constant".into()
    }
}

/// The machine: commanded p goes to p + e(p)·1e-3.
pub fn machine(model: &dyn ErrorModel, p: [f64; 3]) -> [f64; 3] {
    let e = model.error_um(p);
    [p[0] + e[0] * 1e-3, p[1] + e[1] * 1e-3, p[2] + e[2] * 1e-3]
}

pub fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// A move of the reference interpreter, machine frame, mm.
#[derive(Debug, Clone)]
pub struct Move {
    pub line: usize,
    pub rapid: bool,
    pub start: [f64; 3],
    pub end: [f64; 3],
    /// Points along the move (for arcs: dense samples; for lines: start and end).
    pub path: Vec<[f64; 3]>,
    /// The exact geometry of an arc move.
    pub arc: Option<ArcGeom>,
}

/// An arc (or helix) of the reference interpreter: in-plane axes f, g about normal n.
#[derive(Debug, Clone, Copy)]
pub struct ArcGeom {
    pub f: usize,
    pub g: usize,
    pub n: usize,
    pub c: [f64; 2],
    pub r0: f64,
    pub r1: f64,
    pub a0: f64,
    pub sweep: f64,
    pub start: [f64; 3],
    pub end: [f64; 3],
}

impl ArcGeom {
    /// The point at fraction t of the sweep (radius and normal axis linear in t, as LinuxCNC).
    pub fn point(&self, t: f64) -> [f64; 3] {
        let th = self.a0 + self.sweep * t;
        let r = self.r0 + (self.r1 - self.r0) * t;
        let mut p = [0.0; 3];
        p[self.f] = self.c[0] + r * th.cos();
        p[self.g] = self.c[1] + r * th.sin();
        p[self.n] = self.start[self.n] + (self.end[self.n] - self.start[self.n]) * t;
        p
    }

    /// Distance from q to the arc: the nearest point of the curve around each point at q's own
    /// angle (every turn), and the ends.
    pub fn distance(&self, q: [f64; 3]) -> f64 {
        let phi = (q[self.g] - self.c[1]).atan2(q[self.f] - self.c[0]);
        let two_pi = 2.0 * std::f64::consts::PI;
        let mut best = dist(q, self.point(0.0)).min(dist(q, self.point(1.0)));
        if self.sweep == 0.0 {
            return best;
        }
        // t = (phi − a0 + 2πm) / sweep in [0, 1]
        let base = phi - self.a0;
        let m_lo = ((-base).min(self.sweep - base) / two_pi).floor() as i64 - 1;
        let m_hi = ((-base).max(self.sweep - base) / two_pi).ceil() as i64 + 1;
        // a planar arc: the point at q's own angle is the nearest (to within the spiral of a
        // rounded end radius, which only makes the distance larger)
        let planar = (self.end[self.n] - self.start[self.n]).abs() < 1e-9;
        // on a helix the nearest point can be at another angle: golden-section search over
        // ±0.5 rad of sweep around each point at q's own angle
        let half = (0.5 / self.sweep.abs()).min(0.25);
        for m in m_lo..=m_hi {
            let t = (base + two_pi * m as f64) / self.sweep;
            if planar {
                if (0.0..=1.0).contains(&t) {
                    best = best.min(dist(q, self.point(t)));
                }
                continue;
            }
            if (-half..=1.0 + half).contains(&t) {
                let (mut a, mut b) = ((t - half).max(0.0), (t + half).min(1.0));
                let g = (5f64.sqrt() - 1.0) / 2.0;
                for _ in 0..60 {
                    let c = b - g * (b - a);
                    let d = a + g * (b - a);
                    if dist(q, self.point(c)) < dist(q, self.point(d)) {
                        b = d;
                    } else {
                        a = c;
                    }
                }
                best = best.min(dist(q, self.point(0.5 * (a + b))));
            }
        }
        best
    }
}

/// Distance from q to a move: exact for arcs, to the segment for straight moves.
pub fn dist_to_move(q: [f64; 3], m: &Move) -> f64 {
    match &m.arc {
        Some(a) => a.distance(q),
        None => dist_to_path(q, &m.path),
    }
}

/// Interprets the subset: G0 G1 G2 G3 (I J K or R, P turns), G17/18/19, G20/21, G90/91,
/// G90.1/91.1, G54–G59.3 with `work` (G59.1–G59.3 start at zero), G43 H/G49 with `tools`,
/// comments, N/F/S/T/M words; and the offset codes as LinuxCNC's `rs274` runs them (checked
/// against its recorded output in tests/gcode_offsets_state.rs): G92 and G10 L20 make the
/// current position read as the given values, G52 and G10 L2 set the offset, G92.1/G92.2 zero
/// the G92 offset (G92.1 also its parameters, which G92.3 restores), G10 L1 sets a tool length (used at the next G43), all in the block's units
/// and absolute in G91; G53 ignores work and G92 offsets; M2/M30 select G54 and keep G92.
/// Moves before X, Y and Z are all known are not returned (nor compensated by the rewriter).
pub fn interpret(
    text: &str,
    work: &[[f64; 3]; 6],
    tools: &BTreeMap<u32, f64>,
    start: Option<[f64; 3]>,
) -> Vec<Move> {
    let mut pos: [Option<f64>; 3] = start.map(|p| p.map(Some)).unwrap_or([None; 3]);
    let mut scale = 1.0;
    let mut absolute = true;
    let mut arc_abs = false;
    let mut plane = (0usize, 1usize, 2usize);
    let mut mode = -1i32;
    let mut wcs = 0usize;
    let mut tool = 0.0;
    let mut work9 = [[0.0; 3]; 9];
    work9[..6].copy_from_slice(work);
    let work = &mut work9;
    let mut tools = tools.clone();
    let mut g92 = [0.0f64; 3];
    // parameters 5211-5213: G92/G52 set them, G92.1 zeroes them, G92.3 restores the offset
    let mut g92_saved: Option<[f64; 3]> = None;
    let mut moves = Vec::new();
    let mut toks = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let line = line.trim_start_matches('\u{feff}');
        lex_line(line.as_bytes(), 0, &mut toks).expect("reference interpreter: lexable line");
        let mut w: BTreeMap<u8, f64> = BTreeMap::new();
        let mut gs = Vec::new();
        for t in &toks {
            if let TokenKind::Word {
                letter,
                value: Value::Number(v),
            } = t.kind
            {
                if letter == b'G' {
                    gs.push((v * 10.0).round() as i32);
                } else {
                    w.insert(letter, v);
                }
            }
        }
        for &g in &gs {
            match g {
                170 => plane = (0, 1, 2),
                180 => plane = (2, 0, 1),
                190 => plane = (1, 2, 0),
                200 => scale = 25.4,
                210 => scale = 1.0,
                900 => absolute = true,
                910 => absolute = false,
                901 => arc_abs = true,
                911 => arc_abs = false,
                540 | 550 | 560 | 570 | 580 | 590 => wcs = ((g - 540) / 10) as usize,
                591..=593 => wcs = (g - 591) as usize + 6,
                921 => {
                    g92 = [0.0; 3];
                    g92_saved = Some([0.0; 3]);
                }
                922 => g92 = [0.0; 3],
                923 => g92 = g92_saved.expect("reference interpreter: G92.3 before G92/G52/G92.1"),
                430 => tool = tools[&(w[&b'H'] as u32)],
                490 => tool = 0.0,
                0 | 10 | 20 | 30 => mode = g / 10,
                _ => {}
            }
        }
        let letters = [b'X', b'Y', b'Z'];
        let stop = toks.iter().any(|t| {
            matches!(t.kind, TokenKind::Word { letter: b'M', value: Value::Number(v) } if v == 2.0 || v == 30.0)
        });
        if stop {
            wcs = 0;
        }
        // G10 / G92 / G52 take the axis words (LinuxCNC's order: after units, G43, G54…)
        let tool_of = |a: usize, tool: f64| if a == 2 { tool } else { 0.0 };
        if gs.contains(&920) || gs.contains(&520) {
            for a in 0..3 {
                if let Some(v) = w.get(&letters[a]) {
                    g92[a] = if gs.contains(&520) {
                        v * scale
                    } else {
                        pos[a].expect("G92 at a known position")
                            - work[wcs][a]
                            - tool_of(a, tool)
                            - v * scale
                    };
                }
            }
            g92_saved = Some(g92);
            continue;
        }
        if gs.contains(&100) {
            let l = w[&b'L'] as i32;
            let p = w[&b'P'] as usize;
            match l {
                1 => {
                    if let Some(z) = w.get(&b'Z') {
                        tools.insert(p as u32, z * scale);
                    }
                }
                2 | 20 => {
                    let n = if p == 0 { wcs } else { p - 1 };
                    for a in 0..3 {
                        if let Some(v) = w.get(&letters[a]) {
                            work[n][a] = if l == 2 {
                                v * scale
                            } else {
                                pos[a].expect("G10 L20 at a known position")
                                    - g92[a]
                                    - tool_of(a, tool)
                                    - v * scale
                            };
                        }
                    }
                }
                _ => panic!("reference interpreter: G10 L{l}"),
            }
            continue;
        }
        // a G2/G3 block with centre words only is a full circle (LinuxCNC runs `G3 I-5`)
        let full_circle =
            (mode == 2 || mode == 3) && [b'I', b'J', b'K'].iter().any(|l| w.contains_key(l));
        if !letters.iter().any(|l| w.contains_key(l)) && !full_circle {
            continue;
        }
        // G53: this block only, machine coordinates
        let off = if gs.contains(&530) {
            [0.0; 3]
        } else {
            [
                work[wcs][0] + g92[0],
                work[wcs][1] + g92[1],
                work[wcs][2] + g92[2] + tool,
            ]
        };
        let mut end = pos;
        for a in 0..3 {
            if let Some(v) = w.get(&letters[a]) {
                end[a] = if absolute {
                    Some(v * scale + off[a])
                } else {
                    pos[a].map(|p| p + v * scale)
                };
            }
        }
        let known = pos.iter().all(|p| p.is_some()) && end.iter().all(|p| p.is_some());
        let s = pos.map(|p| p.unwrap_or(0.0));
        let e = end.map(|p| p.unwrap_or(0.0));
        pos = end;
        if !known {
            continue;
        }
        let mut arc = None;
        let path = if mode == 2 || mode == 3 {
            let (f, g2, n) = plane;
            let c = if let Some(r) = w.get(&b'R') {
                let r = r * scale;
                let (dx, dy) = (e[f] - s[f], e[g2] - s[g2]);
                let d = (dx * dx + dy * dy).sqrt();
                let h = (r * r - d * d / 4.0).max(0.0).sqrt();
                let side = if mode == 2 { -1.0 } else { 1.0 } * r.signum();
                [
                    (s[f] + e[f]) / 2.0 - side * h * dy / d,
                    (s[g2] + e[g2]) / 2.0 + side * h * dx / d,
                ]
            } else {
                let ijk = [b'I', b'J', b'K'];
                let get = |a: usize, base: f64| match w.get(&ijk[a]) {
                    Some(v) if arc_abs => v * scale + off[a],
                    Some(v) => base + v * scale,
                    None => base,
                };
                [get(f, s[f]), get(g2, s[g2])]
            };
            let a0 = (s[g2] - c[1]).atan2(s[f] - c[0]);
            let a1 = (e[g2] - c[1]).atan2(e[f] - c[0]);
            let mut sweep = a1 - a0;
            let full = (e[f] - s[f]).hypot(e[g2] - s[g2]) < 1e-9;
            if mode == 3 {
                if full {
                    sweep = 2.0 * std::f64::consts::PI;
                }
                while sweep <= 0.0 {
                    sweep += 2.0 * std::f64::consts::PI;
                }
            } else {
                if full {
                    sweep = -2.0 * std::f64::consts::PI;
                }
                while sweep >= 0.0 {
                    sweep -= 2.0 * std::f64::consts::PI;
                }
            }
            let turns = w.get(&b'P').copied().unwrap_or(1.0);
            sweep += sweep.signum() * 2.0 * std::f64::consts::PI * (turns - 1.0);
            let r0 = (s[f] - c[0]).hypot(s[g2] - c[1]);
            let r1 = (e[f] - c[0]).hypot(e[g2] - c[1]);
            arc = Some(ArcGeom {
                f,
                g: g2,
                n,
                c,
                r0,
                r1,
                a0,
                sweep,
                start: s,
                end: e,
            });
            let k = 400;
            (0..=k)
                .map(|i| {
                    let t = i as f64 / k as f64;
                    let th = a0 + sweep * t;
                    let r = r0 + (r1 - r0) * t;
                    let mut p = [0.0; 3];
                    p[f] = c[0] + r * th.cos();
                    p[g2] = c[1] + r * th.sin();
                    p[n] = s[n] + (e[n] - s[n]) * t;
                    p
                })
                .collect()
        } else {
            vec![s, e]
        };
        moves.push(Move {
            line: ln + 1,
            rapid: mode == 0,
            start: s,
            end: e,
            path,
            arc,
        });
    }
    moves
}

/// Distance from `p` to the polyline `path`.
pub fn dist_to_path(p: [f64; 3], path: &[[f64; 3]]) -> f64 {
    let mut best = f64::INFINITY;
    for w in path.windows(2) {
        let (a, b) = (w[0], w[1]);
        let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
        let t = if l2 == 0.0 {
            0.0
        } else {
            (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1] + (p[2] - a[2]) * ab[2]) / l2)
                .clamp(0.0, 1.0)
        };
        best = best.min(dist(
            p,
            [a[0] + ab[0] * t, a[1] + ab[1] * t, a[2] + ab[2] * t],
        ));
    }
    if path.len() == 1 {
        best = dist(p, path[0]);
    }
    best
}

/// The shared data folder: `../shared` beside the repository root, or `$MTEC_SHARED_DIR`.
pub fn shared_dir() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let candidates = [
        std::env::var_os("MTEC_SHARED_DIR").map(PathBuf::from),
        Some(root.join("../shared")),
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|p| p.join("data/gcode").is_dir())
}

/// Pushes the rewritten program through the machine and checks it against the original:
/// the machine's end point of every original move lies within `end_tol_mm` of its target, and
/// every output vertex and piece midpoint lies within `path_tol_mm` of the original path (the
/// moves are matched in order). Returns the largest end and path deviations (mm).
#[allow(clippy::too_many_arguments)]
pub fn check_lands_on_target(
    input: &str,
    output: &str,
    model: &dyn ErrorModel,
    work: &[[f64; 3]; 6],
    tools: &BTreeMap<u32, f64>,
    start: Option<[f64; 3]>,
    end_tol_mm: f64,
    path_tol_mm: f64,
) -> (f64, f64) {
    let want = interpret(input, work, tools, start);
    let got = interpret(output, work, tools, start);
    assert!(!want.is_empty(), "no moves in the input");
    let mut j = 0usize; // current original move
    let mut worst_end: f64 = 0.0;
    let mut worst_path: f64 = 0.0;
    let mut ends_hit = vec![false; want.len()];
    for g in &got {
        let reached = machine(model, g.end);
        let mid = machine(model, [0, 1, 2].map(|i| 0.5 * (g.start[i] + g.end[i])));
        // advance to the original move this output move belongs to
        let mut k = j;
        loop {
            let d = dist_to_path(reached, &want[k].path);
            if d <= path_tol_mm {
                break;
            }
            k += 1;
            assert!(
                k < want.len(),
                "output move of line {} reaches {:?}, not on any remaining original move (from line {})",
                g.line,
                reached,
                want[j].line
            );
        }
        j = k;
        let d_end = dist(reached, want[j].end);
        if d_end <= end_tol_mm {
            ends_hit[j] = true;
            worst_end = worst_end.max(d_end);
        }
        worst_path = worst_path.max(dist_to_path(reached, &want[j].path));
        if !g.rapid && g.path.len() == 2 {
            let dm = dist_to_path(mid, &want[j].path);
            assert!(
                dm <= path_tol_mm,
                "midpoint of the output move of line {} is {:.3} um off the original path of line {}",
                g.line,
                dm * 1e3,
                want[j].line
            );
            worst_path = worst_path.max(dm);
        }
    }
    for (k, hit) in ends_hit.iter().enumerate() {
        // a zero-length original move shares its end with the move before it
        let hit = *hit
            || got
                .iter()
                .any(|g| dist(machine(model, g.end), want[k].end) <= end_tol_mm);
        assert!(
            hit,
            "the end point of original line {} ({:?}) is not reached within {} um",
            want[k].line,
            want[k].end,
            end_tol_mm * 1e3
        );
    }
    (worst_end, worst_path)
}

/// The densest check of a rewritten program: every output move is sampled every `step_mm`
/// (arcs at their 400 path points), each sample pushed through the machine p + e(p), and its
/// distance to the original path measured (moves matched in order, rapids only at their ends).
/// Returns the largest distance (mm); panics naming the output line when it exceeds `tol_mm`.
pub fn check_path_dense(
    input: &str,
    output: &str,
    model: &dyn ErrorModel,
    work: &[[f64; 3]; 6],
    start: Option<[f64; 3]>,
    step_mm: f64,
    tol_mm: f64,
) -> f64 {
    let tools = BTreeMap::new();
    let want = interpret(input, work, &tools, start);
    let got = interpret(output, work, &tools, start);
    assert!(!want.is_empty(), "no moves in the input");
    let mut j = 0usize;
    let mut worst: f64 = 0.0;
    for g in &got {
        // samples of the commanded path
        let mut pts: Vec<[f64; 3]> = Vec::new();
        match &g.arc {
            Some(a) => {
                let len = (a.sweep.abs() * a.r0.max(a.r1)).hypot(a.end[a.n] - a.start[a.n]);
                let n = ((len / step_mm).ceil() as usize).clamp(16, 200_000);
                pts.extend((0..=n).map(|i| a.point(i as f64 / n as f64)));
            }
            None => {
                let n = ((dist(g.start, g.end) / step_mm).ceil() as usize).clamp(1, 200_000);
                for i in 0..=n {
                    let t = i as f64 / n as f64;
                    pts.push([0, 1, 2].map(|a| g.start[a] + (g.end[a] - g.start[a]) * t));
                }
            }
        }
        let reached = machine(model, g.end);
        let mut k = j;
        while dist_to_move(reached, &want[k]) > tol_mm {
            k += 1;
            assert!(
                k < want.len(),
                "output line {}: its end {:?} reaches no remaining original move",
                g.line,
                reached
            );
        }
        j = k;
        if g.rapid {
            continue;
        }
        // the samples lie on the original move k or a neighbour (an end point can match a
        // crossing move first: the window looks two moves either way)
        let window = k.saturating_sub(2)..=(k + 2).min(want.len() - 1);
        for p in &pts {
            let q = machine(model, *p);
            let d = window
                .clone()
                .map(|m| dist_to_move(q, &want[m]))
                .fold(f64::INFINITY, f64::min);
            assert!(
                d <= tol_mm,
                "output line {}: the tool reaches {:?}, {:.3} um off the original path (bound {:.3} um)",
                g.line,
                q,
                d * 1e3,
                tol_mm * 1e3
            );
            worst = worst.max(d);
        }
    }
    worst
}

// --- random programs and maps: the property test and the fuzz target draw from these -------

/// SplitMix64: a small deterministic generator seeded by proptest.
pub struct Rng(pub u64);
impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    pub fn pick(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A grid over [0, 120]² × [−10, 10] mm: a smooth error plus up to three single-node bumps.
pub fn random_map(r: &mut Rng) -> GridMap {
    let h = [5.0, 7.5, 10.0, 20.0][r.pick(4)];
    let n = (120.0 / h) as usize + 1;
    let xs: Vec<f64> = (0..n).map(|i| i as f64 * h).collect();
    let zs = vec![-10.0, 0.0, 10.0];
    let k: [f64; 6] = std::array::from_fn(|_| r.range(-0.15, 0.15));
    let mut values = Vec::with_capacity(n * n * 3);
    for &x in &xs {
        for &y in &xs {
            for &z in &zs {
                values.push([
                    k[0] * x + k[1] * y * 0.5 + 1e-3 * k[2] * x * y,
                    k[3] * y + k[4] * z + 1e-3 * k[5] * x * x,
                    k[2] * z + k[0] * 0.1 * y,
                ]);
            }
        }
    }
    for _ in 0..r.pick(4) {
        let i = r.pick(values.len());
        let c = r.pick(3);
        values[i][c] += r.range(5.0, 30.0) * if r.unit() < 0.5 { -1.0 } else { 1.0 };
    }
    GridMap::new([xs.clone(), xs, zs], values, Outside::Clamp, "random").unwrap()
}

fn f4(v: f64) -> String {
    format!("{v:.4}")
}

/// A program of straight moves and arcs inside [15, 105]² × [−5, 5] mm.
pub fn random_program(r: &mut Rng) -> String {
    let mut p = [
        r.range(20.0, 100.0),
        r.range(20.0, 100.0),
        r.range(-4.0, 4.0),
    ];
    let mut s = format!(
        "G21 G90 G17\nG0 X{} Y{} Z{}\nG1 X{} F200\n",
        f4(p[0]),
        f4(p[1]),
        f4(p[2]),
        f4(p[0])
    );
    // printed positions are what the program means: keep p as written
    let read = |v: f64| f4(v).parse::<f64>().unwrap();
    p = p.map(read);
    for _ in 0..(4 + r.pick(9)) {
        match r.pick(7) {
            0 | 1 => {
                let q = [
                    r.range(15.0, 105.0),
                    r.range(15.0, 105.0),
                    r.range(-5.0, 5.0),
                ];
                s += &format!("G1 X{} Y{} Z{}\n", f4(q[0]), f4(q[1]), f4(q[2]));
                p = q.map(read);
            }
            2 => {
                // incremental steps, then back to absolute
                let d = [r.range(-8.0, 8.0), r.range(-8.0, 8.0)];
                let q = [
                    (p[0] + d[0]).clamp(15.0, 105.0),
                    (p[1] + d[1]).clamp(15.0, 105.0),
                ];
                let d = [read(q[0] - p[0]), read(q[1] - p[1])];
                s += &format!("G91 G1 X{} Y{}\nG90\n", f4(d[0]), f4(d[1]));
                p[0] += d[0];
                p[1] += d[1];
            }
            3 => {
                // I/J arc in G17 (maybe a helix) to a point on its circle
                let rad = r.range(2.0, 25.0);
                let a0 = r.range(0.0, std::f64::consts::TAU);
                let c = [p[0] - rad * a0.cos(), p[1] - rad * a0.sin()];
                if c[0] - rad < 15.0
                    || c[0] + rad > 105.0
                    || c[1] - rad < 15.0
                    || c[1] + rad > 105.0
                {
                    continue;
                }
                let a1 = r.range(0.0, std::f64::consts::TAU);
                let e = [c[0] + rad * a1.cos(), c[1] + rad * a1.sin()];
                let z = if r.unit() < 0.3 {
                    r.range(-5.0, 5.0)
                } else {
                    p[2]
                };
                let g = if r.unit() < 0.5 { "G2" } else { "G3" };
                s += &format!(
                    "{g} X{} Y{} Z{} I{} J{}\n",
                    f4(e[0]),
                    f4(e[1]),
                    f4(z),
                    f4(c[0] - p[0]),
                    f4(c[1] - p[1])
                );
                p = [read(e[0]), read(e[1]), read(z)];
            }
            4 => {
                // R arc, often exactly a semicircle
                let q = [r.range(20.0, 100.0), r.range(20.0, 100.0)];
                let q = q.map(read);
                let half = (q[0] - p[0]).hypot(q[1] - p[1]) / 2.0;
                if !(1.0..=40.0).contains(&half) {
                    continue;
                }
                let rad = if r.unit() < 0.5 {
                    half + 0.001
                } else {
                    half * r.range(1.0, 1.5)
                };
                let sign = if r.unit() < 0.8 { 1.0 } else { -1.0 };
                let g = if r.unit() < 0.5 { "G2" } else { "G3" };
                // the arc must stay inside the map: its centre within [15+R, 105−R] is enough
                let m = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
                if m[0] - 2.0 * rad < 15.0
                    || m[0] + 2.0 * rad > 105.0
                    || m[1] - 2.0 * rad < 15.0
                    || m[1] + 2.0 * rad > 105.0
                {
                    continue;
                }
                s += &format!("{g} X{} Y{} R{}\n", f4(q[0]), f4(q[1]), f4(sign * rad));
                p[0] = q[0];
                p[1] = q[1];
            }
            5 => {
                // a full circle without axis words, maybe modal, maybe with P turns
                let rad = r.range(2.0, 15.0);
                let a0 = r.range(0.0, std::f64::consts::TAU);
                let off = [read(rad * a0.cos()), read(rad * a0.sin())];
                let c = [p[0] + off[0], p[1] + off[1]];
                if c[0] - rad < 15.0
                    || c[0] + rad > 105.0
                    || c[1] - rad < 15.0
                    || c[1] + rad > 105.0
                {
                    continue;
                }
                let turns = if r.unit() < 0.3 { " P2" } else { "" };
                s += &format!(
                    "G3 I{} J{}{turns}\nI{} J{}\n",
                    f4(off[0]),
                    f4(off[1]),
                    f4(off[0]),
                    f4(off[1])
                );
            }
            _ => {
                // a quarter arc in G18 or G19 about the current point's neighbour
                let (plane, f, g) = if r.unit() < 0.5 {
                    ("G18", 2, 0)
                } else {
                    ("G19", 1, 2)
                };
                let rad = r.range(1.0, 4.0);
                let mut c = p;
                c[f] -= rad; // centre "before" the point along the plane's first axis
                let mut e = c;
                e[g] += rad;
                if e.iter().take(2).any(|v| !(15.0..=105.0).contains(v))
                    || !(-9.0..=9.0).contains(&e[2])
                {
                    continue;
                }
                let ijk = ["I", "J", "K"];
                let mut words = String::new();
                for a in 0..3 {
                    if e[a] != p[a] {
                        words += &format!(" {}{}", ["X", "Y", "Z"][a], f4(e[a]));
                    }
                }
                s += &format!("{plane} G2{words} {}{}\nG17\n", ijk[f], f4(c[f] - p[f]));
                p = e.map(read);
            }
        }
    }
    s
}
