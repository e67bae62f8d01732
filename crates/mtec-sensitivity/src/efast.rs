//! EFAST, the extended Fourier amplitude sensitivity test (Saltelli, Tarantola & Chan 1999,
//! Technometrics 41(1):39–56): first-order and total indices from the Fourier spectrum of the
//! model output along search curves through the input space.
//!
//! Sampling: for each input i (and each of `resamples` repetitions) one search curve of N points
//! s_k = 2πk/N, k = 0..N−1, on which input i oscillates with the high frequency ω_i and every
//! other input with a low frequency from the complementary set {ω_~i} (eq. 19 of the paper):
//! x_j(s) = ½ + (1/π)·arcsin(sin(ω_j·s + φ_j)), mapped through x_j's quantile function.
//! Frequencies (as in SALib, so designs are comparable): ω_i = ⌊(N−1)/(2M)⌋, and the
//! complementary frequencies spread over 1..⌊ω_i/(2M)⌋, so that their first M harmonics stay
//! below ω_i/2 and do not interfere with ω_i's harmonics (M = interference factor, default 4;
//! N > 4M² is needed). Each curve gets independent random phase shifts φ_j ∈ [0, 2π) (the
//! paper's resampling scheme); repeating the curves `resamples` times with new phases and
//! averaging the indices reduces the estimator's variance, and the spread over repetitions gives
//! a confidence interval: the R replicate estimates are independent and identically distributed,
//! so the Student-t interval mean ± t_{R−1,(1+c)/2}·sd/√R holds at level c (see `interval`).
//! Cost model: N·D·R model evaluations and D·R FFTs of length N; with R = 10 (the default) the
//! interval costs 10× the evaluations of the single design (the model is usually the cost; the
//! FFTs of the analysis are measured in docs/methods.md).
//!
//! Analysis of one curve (eqs. 21–24): Λ_p = |F_p/N|² for p = 1..⌈N/2⌉−1 (F = DFT of the
//! output), V = 2 Σ_p Λ_p, V_i = 2 Σ_{q=1..M} Λ_{qω_i}, S1_i = V_i / V; the complementary set's
//! variance V_~i = 2 Σ_{p=1..⌊ω_i/2⌋} Λ_p and ST_i = 1 − V_~i / V. With one repetition this is
//! exactly SALib's `fast.analyze` (checked against a SALib fixture to 1e-9). SALib's bootstrap
//! of EFAST (half-size resamples of the curve's points, which destroys the periodic structure the
//! spectrum relies on) is deliberately not copied: intervals come from the repetitions instead.
//!
//! Known limitation, stated by the tests: with unbounded (normal) inputs the quantile function
//! turns the curve's triangle wave into a signal with heavy high harmonics, so with M = 4 a few
//! per cent of each input's variance lies above the M-th harmonic: S1 is biased low and an
//! input with no effect shows ST ≈ 0.01–0.02. A larger M (6–8, with N > 4M²) reduces this.

use crate::interval::{replicate_half_widths, replicate_mean};
use crate::problem::{check_outputs, Indices, Problem, Replicates, SampleMatrix};
use crate::SensitivityError;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use realfft::{num_complex::Complex, RealFftPlanner, RealToComplex};

/// Design settings of an EFAST analysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EfastSettings {
    /// Points per search curve (per input and repetition), N > 4M².
    pub n: usize,
    /// Interference factor M: harmonics of ω_i counted in S1 (default 4).
    pub m: usize,
    /// R, independent repetitions of every curve with new random phases (default 10; 1 is
    /// SALib's design, without intervals).
    pub resamples: usize,
    /// Confidence level of the intervals from the R repetitions (default 0.95).
    pub confidence: f64,
}

impl Default for EfastSettings {
    fn default() -> Self {
        EfastSettings {
            n: 1000,
            m: 4,
            resamples: 10,
            confidence: 0.95,
        }
    }
}

impl EfastSettings {
    fn check(&self) -> Result<(), SensitivityError> {
        if self.m == 0 {
            return Err(SensitivityError::Settings(
                "interference factor M must be at least 1".into(),
            ));
        }
        if self.n <= 4 * self.m * self.m {
            return Err(SensitivityError::Settings(format!(
                "EFAST needs N > 4M² = {} points per curve (got N = {}, M = {})",
                4 * self.m * self.m,
                self.n,
                self.m
            )));
        }
        if self.resamples == 0 {
            return Err(SensitivityError::Settings(
                "resamples must be at least 1".into(),
            ));
        }
        Ok(())
    }

    /// Total model evaluations: N · D · resamples.
    pub fn evaluations(&self, dim: usize) -> usize {
        self.n * dim * self.resamples
    }
}

/// The frequencies of one curve: ω_max for the input of interest, then the complementary set
/// for the other D−1 inputs (SALib's choice, see the module docs).
pub fn frequencies(n: usize, m: usize, dim: usize) -> (usize, Vec<usize>) {
    let omega_max = (n - 1) / (2 * m);
    let m_c = omega_max / (2 * m);
    let others = if dim <= 1 {
        Vec::new()
    } else if m_c >= dim - 1 {
        // floor(linspace(1, m_c, D−1))
        (0..dim - 1)
            .map(|k| {
                if dim == 2 {
                    1
                } else if k == dim - 2 {
                    m_c
                } else {
                    // numpy's linspace: start + k·step, the last point set to stop exactly.
                    let step = (m_c as f64 - 1.0) / (dim - 2) as f64;
                    (k as f64 * step + 1.0).floor() as usize
                }
            })
            .collect()
    } else {
        (0..dim - 1).map(|k| k % m_c + 1).collect()
    };
    (omega_max, others)
}

/// Draws the EFAST design: `resamples × D` curves of N rows each, in that order (repetition,
/// then input of interest, then the point along the curve).
pub fn sample(
    problem: &Problem,
    settings: &EfastSettings,
    seed: u64,
) -> Result<SampleMatrix, SensitivityError> {
    settings.check()?;
    let d = problem.dim();
    let n = settings.n;
    crate::problem::check_design_size(
        n.checked_mul(d)
            .and_then(|r| r.checked_mul(settings.resamples)),
        d,
        &format!("EFAST N = {n} × resamples {}", settings.resamples),
    )?;
    let (omega_max, others) = frequencies(n, settings.m, d);
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let curves = settings.resamples * d;
    // Phases drawn in curve order from one seeded generator, so the design does not depend on
    // the number of threads that fill it.
    let phases: Vec<Vec<f64>> = (0..curves)
        .map(|_| {
            (0..d)
                .map(|_| rng.random::<f64>() * std::f64::consts::TAU)
                .collect()
        })
        .collect();
    let mut data = vec![0.0; settings.evaluations(d) * d];
    let curve_len = n * d;
    data.par_chunks_exact_mut(curve_len)
        .enumerate()
        .for_each(|(c, curve)| {
            let i = c % d;
            // ω_j on this curve: ω_max for input i, the complementary set in order for the others.
            let mut omega = vec![0usize; d];
            let mut rest = others.iter();
            for (j, w) in omega.iter_mut().enumerate() {
                *w = if j == i {
                    omega_max
                } else {
                    *rest.next().unwrap_or(&1)
                };
            }
            // Search curve, Saltelli et al. 1999 eq. 19, at θ = ω_j·2πk/N + φ_j in the form
            // |2·frac((θ − π/2)/2π) − 1| (see `search_curve`), with the whole turns ω_j·k/N taken
            // in integers: (ω_j·k mod N)/N + (φ_j − π/2)/2π. No sine, arcsine or fmod per point.
            let offset: Vec<f64> = phases[c]
                .iter()
                .map(|p| (p - std::f64::consts::FRAC_PI_2) / std::f64::consts::TAU)
                .collect();
            // one input at a time down the curve, so that the quantile function's choice is made
            // once per input and the loop has no inner loop (issue 22)
            for (j, dist) in problem.distributions.iter().enumerate() {
                match *dist {
                    // the same arithmetic as `Distribution::quantile`, inlined into the loop
                    crate::Distribution::Uniform { low, high } => {
                        search_curve_column(curve, d, j, n, omega[j], offset[j], |u| {
                            low + u * (high - low)
                        })
                    }
                    _ => search_curve_column(curve, d, j, n, omega[j], offset[j], |u| {
                        dist.quantile(u)
                    }),
                }
            }
        });
    SampleMatrix::from_rows(d, data)
}

/// Column `j` of one curve's rows: the quantile of the search curve at θ = ω·2πk/N + φ, in the
/// form (turns mod 1) with the whole turns ω·k/N counted exactly (see `sample`); `offset` is
/// (φ − π/2)/2π.
fn search_curve_column(
    curve: &mut [f64],
    d: usize,
    j: usize,
    n: usize,
    omega: usize,
    offset: f64,
    quantile: impl Fn(f64) -> f64,
) {
    let inv_n = 1.0 / n as f64;
    let point = |turn: f64| {
        // t ∈ [−¼, 7/4): ⌊t⌋ ∈ {−1, 0, 1}, chosen without a call to floor
        let t = turn * inv_n + offset;
        let whole = if t < 0.0 {
            -1.0
        } else if t >= 1.0 {
            1.0
        } else {
            0.0
        };
        quantile((2.0 * (t - whole) - 1.0).abs())
    };
    // ω·k mod N for LANES rows at a time, each lane advanced by LANES·ω mod N: independent
    // chains, so the loop is not bound by the latency of one running sum. Whole numbers below
    // 2⁵³ are exact in a double, and so is `%` (fmod): the same values as one chain.
    const LANES: usize = 4;
    let (w, nf) = (omega as f64, n as f64);
    let step = (LANES as f64 * w) % nf;
    let mut turn: [f64; LANES] = std::array::from_fn(|l| (l as f64 * w) % nf);
    let mut groups = curve.chunks_exact_mut(d * LANES);
    for group in &mut groups {
        for (l, row) in group.chunks_exact_mut(d).enumerate() {
            row[j] = point(turn[l]);
            turn[l] += step;
            if turn[l] >= nf {
                turn[l] -= nf;
            }
        }
    }
    for (l, row) in groups.into_remainder().chunks_exact_mut(d).enumerate() {
        row[j] = point(turn[l]);
    }
}

/// The search curve ½ + arcsin(sin θ)/π (Saltelli et al. 1999 eq. 19), evaluated through the
/// identity arcsin(sin θ) = |((θ − π/2) mod 2π) − π| − π/2 (a triangle wave): one remainder
/// instead of a sine and an arcsine.
pub fn search_curve(theta: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI, TAU};
    ((theta - FRAC_PI_2).rem_euclid(TAU) - PI).abs() / PI
}

/// S1 and ST of the input of interest from the outputs along one curve (eqs. 21–24; SALib's
/// `compute_orders`), and the curve's variance V.
pub fn curve_indices(y: &[f64], m: usize, omega_max: usize) -> (f64, f64, f64) {
    let plan = fft_plan(y.len());
    let mut bufs = FftBuffers::default();
    curve_indices_with(&*plan, &mut bufs, y, m, omega_max)
}

/// The forward real-input FFT plan of length `n` from one process-wide planner, which keeps the
/// plans it made: planning a length of 10 000 takes about as long as one transform, and an
/// analysis over many outputs or poses needs the same length every time. The output is real, so
/// a real-to-complex transform gives F_0..F_{N/2} for half the work of a complex FFT (issue 22).
fn fft_plan(n: usize) -> std::sync::Arc<dyn RealToComplex<f64>> {
    static PLANNER: std::sync::OnceLock<std::sync::Mutex<RealFftPlanner<f64>>> =
        std::sync::OnceLock::new();
    let planner = PLANNER.get_or_init(|| std::sync::Mutex::new(RealFftPlanner::new()));
    // a poisoned lock only means another thread panicked while planning: the cache is intact
    let mut p = planner.lock().unwrap_or_else(|e| e.into_inner());
    p.plan_fft_forward(n)
}

/// Reusable buffers of one thread's transforms: the input (the transform overwrites it), the
/// spectrum F_0..F_{N/2} and the plan's scratch.
#[derive(Default)]
struct FftBuffers {
    input: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

/// [`curve_indices`] with a prepared FFT plan of length `y.len()` and reusable buffers (the
/// analysis plans once for all D·R curves).
fn curve_indices_with(
    plan: &dyn RealToComplex<f64>,
    bufs: &mut FftBuffers,
    y: &[f64],
    m: usize,
    omega_max: usize,
) -> (f64, f64, f64) {
    let n = y.len();
    bufs.input.clear();
    bufs.input.extend_from_slice(y);
    bufs.spectrum
        .resize(plan.complex_len(), Complex::new(0.0, 0.0));
    bufs.scratch
        .resize(plan.get_scratch_len(), Complex::new(0.0, 0.0));
    plan.process_with_scratch(&mut bufs.input, &mut bufs.spectrum, &mut bufs.scratch)
        .expect("buffer lengths from the plan");
    let buf = &bufs.spectrum;
    // Λ_p = |F_p / N|², p = 1 .. ceil(N/2) − 1 (all ≤ N/2: within the real transform's output)
    let spectrum = |p: usize| (buf[p] / n as f64).norm_sqr();
    let top = n.div_ceil(2);
    let v: f64 = 2.0 * (1..top).map(spectrum).sum::<f64>();
    let v_i: f64 = 2.0 * (1..=m).map(|q| spectrum(q * omega_max)).sum::<f64>();
    let v_not_i: f64 = 2.0 * (1..=omega_max / 2).map(spectrum).sum::<f64>();
    (v_i / v, 1.0 - v_not_i / v, v)
}

/// EFAST indices from the outputs `y` of a design drawn by [`sample`] (or by SALib's
/// `fast_sampler` when `resamples` is 1): S1 and ST per input, averaged over the R repetitions;
/// with R ≥ 2 the half widths t_{R−1,(1+c)/2}·sd/√R of the intervals at confidence level c.
pub fn analyze(
    names: &[String],
    y: &[f64],
    m: usize,
    resamples: usize,
    confidence: f64,
) -> Result<Indices, SensitivityError> {
    crate::interval::check_confidence(confidence)?;
    let d = names.len();
    if d == 0 || resamples == 0 {
        return Err(SensitivityError::Settings(
            "need at least one input and one repetition".into(),
        ));
    }
    if y.len() % (d * resamples) != 0 {
        return Err(SensitivityError::Outputs(format!(
            "{} outputs are not a multiple of D·resamples = {}",
            y.len(),
            d * resamples
        )));
    }
    let n = y.len() / (d * resamples);
    let settings = EfastSettings {
        n,
        m,
        resamples,
        confidence,
    };
    settings.check()?;
    check_outputs(y, settings.evaluations(d))?;
    let (omega_max, _) = frequencies(n, m, d);
    let plan = fft_plan(n);
    let per_curve: Vec<(f64, f64, f64)> = y
        .par_chunks_exact(n)
        .map_init(FftBuffers::default, |bufs, c| {
            curve_indices_with(&*plan, bufs, c, m, omega_max)
        })
        .collect();
    if let Some(c) = per_curve.iter().position(|r| r.2.is_nan() || r.2 <= 0.0) {
        return Err(SensitivityError::Outputs(format!(
            "the output does not vary along curve {c} (input `{}`): indices are undefined",
            names[c % d]
        )));
    }
    // Replicate k's indices of input i come from curve k·D + i.
    let reps = Replicates {
        s1: per_curve
            .chunks_exact(d)
            .map(|c| c.iter().map(|t| t.0).collect())
            .collect(),
        st: per_curve
            .chunks_exact(d)
            .map(|c| c.iter().map(|t| t.1).collect())
            .collect(),
    };
    let variance = per_curve.iter().map(|t| t.2).sum::<f64>() / per_curve.len() as f64;
    let (s1_conf, st_conf) = if resamples >= 2 {
        // t_{R−1}·sd/√R over the independent random-phase replicates (`interval` module)
        (
            Some(replicate_half_widths(&reps.s1, confidence)),
            Some(replicate_half_widths(&reps.st, confidence)),
        )
    } else {
        (None, None)
    };
    Ok(Indices {
        inputs: names.to_vec(),
        s1: replicate_mean(&reps.s1),
        st: replicate_mean(&reps.st),
        s1_conf,
        st_conf,
        replicates: (resamples >= 2).then_some(reps),
        variance,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_sampler_draws_the_search_curve() {
        // every design value equals search_curve(ω_j·2πk/N + φ_j) with SALib's frequencies
        use crate::{Distribution, Problem};
        let d = 4;
        let p = Problem::new(
            (1..=d).map(|i| format!("x{i}")).collect(),
            vec![
                Distribution::Uniform {
                    low: 0.0,
                    high: 1.0
                };
                d
            ],
        )
        .unwrap();
        let s = super::EfastSettings {
            n: 257,
            m: 4,
            resamples: 2,
            confidence: 0.95,
        };
        let x = super::sample(&p, &s, 7).unwrap();
        let (w_max, others) = super::frequencies(s.n, s.m, d);
        // the phases as the sampler draws them
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for c in 0..s.resamples * d {
            let phi: Vec<f64> = (0..d)
                .map(|_| rng.random::<f64>() * std::f64::consts::TAU)
                .collect();
            let mut omega = others.clone();
            omega.insert(c % d, w_max);
            for k in 0..s.n {
                let sk = std::f64::consts::TAU * k as f64 / s.n as f64;
                for j in 0..d {
                    let want = super::search_curve(omega[j] as f64 * sk + phi[j]);
                    let got = x.row(c * s.n + k)[j];
                    assert!((got - want).abs() < 1e-12, "curve {c} k {k} input {j}");
                }
            }
        }
    }

    #[test]
    fn search_curve_is_the_arcsine_of_the_sine() {
        for k in -2000..2000 {
            let theta = k as f64 * 0.0173;
            let direct = 0.5 + theta.sin().asin() / std::f64::consts::PI;
            assert!(
                (super::search_curve(theta) - direct).abs() < 1e-12,
                "θ = {theta}"
            );
        }
    }
}
