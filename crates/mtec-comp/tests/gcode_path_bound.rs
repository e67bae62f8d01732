//! The path bound on random programs and random maps (issue 15): every sample of every output
//! move, pushed through the machine p + e(p), lies within the documented bound of the original
//! path (`--tolerance-um` + `--chord-tolerance-um`), for programs with straight moves (absolute
//! and G91), arcs in G17/G18/G19 (I/J/K and R format, near-semicircles, full circles without
//! axis words, P turns, helices) over trilinear maps with smooth errors and single-node bumps.
//!
//! 1000 cases in CI (about a second per hundred); `MTEC_PATH_BOUND_CASES=10000` runs more.

mod gcode_support;
use gcode_support::*;
use mtec_comp::gcode::{rewrite, RewriteOptions};
use mtec_comp::{GridMap, Outside};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

/// SplitMix64: a small deterministic generator seeded by proptest.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn pick(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A grid over [0, 120]² × [−10, 10] mm: a smooth error plus up to three single-node bumps.
fn random_map(r: &mut Rng) -> GridMap {
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
fn random_program(r: &mut Rng) -> String {
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

fn cases() -> u32 {
    std::env::var("MTEC_PATH_BOUND_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000)
}

#[test]
fn every_output_sample_lies_within_the_bound_of_the_original_path() {
    let mut runner = TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    });
    let opts = RewriteOptions::default();
    let bound = (opts.tolerance_um + opts.chord_tolerance_um) * 1e-3;
    runner
        .run(&any::<u64>(), |seed| {
            let mut r = Rng(seed);
            let map = random_map(&mut r);
            let program = random_program(&mut r);
            let mut out = Vec::new();
            let res = rewrite(program.as_bytes(), &mut out, &map, &opts);
            prop_assert!(res.is_ok(), "seed {seed}: refused {res:?}\n{program}");
            let out = String::from_utf8(out).unwrap();
            let worst = std::panic::catch_unwind(|| {
                check_path_dense(&program, &out, &map, &[[0.0; 3]; 6], None, 0.05, bound)
            });
            prop_assert!(
                worst.is_ok(),
                "seed {seed}: bound violated\n{program}\n---\n{out}"
            );
            Ok(())
        })
        .unwrap();
}
