//! The R factor of a tall, thin design (n ≫ p) by Householder QR, computed block of rows by block
//! of rows so that the work stays in the L1 cache (issue 22: the ridge trace and the VIF table
//! spent most of their time in a generic column-by-column QR of the whole 7709 × 16 matrix, which
//! sweeps 1 MB through the cache once per column).
//!
//! Sequential ("flat tree") TSQR (Demmel, Grigori, Hoemmen & Langou 2012, SIAM J. Sci. Comput.
//! 34(1), "Communication-optimal parallel and sequential QR and LU factorizations"): with R₀ = 0
//! and the rows split into blocks B₁, B₂, …, the QR of the stacked [R_{i−1}; B_i] gives R_i, and
//! R_last is the R of the whole matrix (up to the signs of its rows). The stacked matrix is
//! structured: R_{i−1} is upper triangular, so the Householder vector of column k is
//! v = [v₀ e_k; B_i[:, k]] (Golub & Van Loan 2013, §5.1.2, for x = [R_kk; B_i[:, k]]), and a
//! reflection touches row k of R and the block only. The flops are those of one Householder QR, 2np², with every block (≤ 128 rows) in cache.
//!
//! Extra columns to the right of the first p are carried along without being triangularised: their
//! top p entries become Qᵀ·column (the ridge problem passes y* as one extra column and gets Qᵀy*).
//! Columns are centred and scaled while a block is copied, (x − shift)·scale, so a standardised
//! copy of the design is never formed. No normal equations: XᵀX is never formed.

/// Rows per block: 128 rows × 17 columns × 8 bytes = 17 KiB, inside a 32 KiB L1 data cache.
const BLOCK_ROWS: usize = 128;

/// The R factor of the n × c matrix with columns `cols` after the affine map
/// (a_ij − shift_j)·scale_j, triangularising its first `p` columns (p ≤ c): a row-major p × c
/// matrix whose first p columns are upper triangular and whose other c − p columns hold the top
/// p entries of Qᵀ times them. Rows of R may have either sign (the QR is unique only up to them).
pub(crate) fn tall_r(cols: &[&[f64]], shift: &[f64], scale: &[f64], p: usize) -> Vec<f64> {
    let c = cols.len();
    let n = cols.first().map_or(0, |a| a.len());
    assert!(p <= c && shift.len() == c && scale.len() == c);
    assert!(cols.iter().all(|a| a.len() == n));
    let mut r = vec![0.0; p * c];
    let mut blk = vec![0.0; BLOCK_ROWS * c];
    let mut row0 = 0;
    while row0 < n {
        let b = BLOCK_ROWS.min(n - row0);
        for j in 0..c {
            let src = &cols[j][row0..row0 + b];
            let (s, f) = (shift[j], scale[j]);
            for (d, x) in blk[j * b..(j + 1) * b].iter_mut().zip(src) {
                *d = (x - s) * f;
            }
        }
        reflect_block(&mut r, &mut blk[..b * c], b, p, c);
        row0 += b;
    }
    r
}

/// One step of the sequential TSQR: [R; B] → [R'; 0] by p Householder reflections.
fn reflect_block(r: &mut [f64], blk: &mut [f64], b: usize, p: usize, c: usize) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above); the function has no other
        // requirement. The arithmetic is the same, in the same order, as the portable path
        // (no fused multiply-add), so both give the same bits.
        unsafe { reflect_block_avx2(r, blk, b, p, c) };
        return;
    }
    reflect_block_portable(r, blk, b, p, c)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn reflect_block_avx2(r: &mut [f64], blk: &mut [f64], b: usize, p: usize, c: usize) {
    reflect_block_portable(r, blk, b, p, c)
}

#[inline(always)]
fn reflect_block_portable(r: &mut [f64], blk: &mut [f64], b: usize, p: usize, c: usize) {
    for k in 0..p {
        let (left, right) = blk.split_at_mut((k + 1) * b);
        let xb = &left[k * b..];
        let sigma = dot(xb, xb);
        if sigma == 0.0 {
            continue; // the block's column is already zero: the reflection is the identity
        }
        // x = [R_kk; B[:, k]], α = −sign(R_kk)‖x‖, v = x − α e₁: v₀ = R_kk − α has no cancellation
        let x0 = r[k * c + k];
        let norm = (x0 * x0 + sigma).sqrt();
        let alpha = -norm.copysign(x0);
        let v0 = x0 - alpha;
        let tau = 2.0 / (v0 * v0 + sigma); // H = I − τ v vᵀ
        r[k * c + k] = alpha;
        for (jj, col) in right.chunks_exact_mut(b).enumerate() {
            let j = k + 1 + jj;
            let f = tau * (v0 * r[k * c + j] + dot(xb, col));
            r[k * c + j] -= f * v0;
            for (y, x) in col.iter_mut().zip(xb) {
                *y -= f * x;
            }
        }
    }
}

/// Partial sums per lane: 16 lanes are four 4-wide registers, enough to hide the latency of the
/// additions (one running sum is bound by it: 4 cycles per element).
const LANES: usize = 16;

/// Σ aᵢbᵢ in [`LANES`] partial sums (a fixed order, so that it vectorises and gives the same bits
/// on every path).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            s[l] += x[l] * y[l];
        }
    }
    let mut t = reduce(s);
    for (x, y) in ra.iter().zip(rb) {
        t += x * y;
    }
    t
}

#[inline(always)]
fn reduce(mut s: [f64; LANES]) -> f64 {
    let mut w = LANES / 2;
    while w > 0 {
        for l in 0..w {
            s[l] += s[l + w];
        }
        w /= 2;
    }
    s[0]
}

/// The mean x̄ of a column and its sum of squared deviations Σ(x − x̄)² (two passes, the second
/// about the mean; partial sums in lanes so that the passes vectorise).
pub(crate) fn mean_and_ss(x: &[f64]) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present (checked); same arithmetic as the portable path.
        return unsafe { mean_and_ss_avx2(x) };
    }
    mean_and_ss_portable(x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn mean_and_ss_avx2(x: &[f64]) -> (f64, f64) {
    mean_and_ss_portable(x)
}

#[inline(always)]
fn mean_and_ss_portable(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let chunks = x.chunks_exact(LANES);
    let rest = chunks.remainder();
    let mut s = [0.0f64; LANES];
    for c in chunks.clone() {
        for l in 0..LANES {
            s[l] += c[l];
        }
    }
    let mean = (reduce(s) + rest.iter().sum::<f64>()) / n;
    let mut q = [0.0f64; LANES];
    for c in chunks {
        for l in 0..LANES {
            let d = c[l] - mean;
            q[l] += d * d;
        }
    }
    let ss = reduce(q) + rest.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>();
    (mean, ss)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// RᵀR of the blocked factor equals that of nalgebra's Householder QR of the same (centred,
    /// scaled) matrix, |R| row by row, and the carried column gives Qᵀy: ‖y‖² = ‖Qᵀy‖² when y
    /// lies in the column space, checked through the least-squares residual instead: the
    /// residual norm² = ‖y‖² − ‖(Qᵀy)[..p]‖² equals that of a direct solve.
    #[test]
    fn blocked_r_equals_a_householder_qr() {
        for (n, p) in [(1000, 7), (300, 16), (5, 3), (129, 4)] {
            let x = DMatrix::from_fn(n, p, |i, j| {
                ((i * 7 + j * 13) % 17) as f64 + ((i * (j + 1)) as f64 * 0.37).sin()
            });
            let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos() + 0.3).collect();
            let shift: Vec<f64> = (0..=p).map(|j| j as f64 * 0.5).collect();
            let scale: Vec<f64> = (0..=p).map(|j| 1.0 / (1.0 + j as f64)).collect();
            let mut cols: Vec<&[f64]> = x.as_slice().chunks_exact(n).collect();
            cols.push(&y);
            let r = tall_r(&cols, &shift, &scale, p);
            let z = DMatrix::from_fn(n, p, |i, j| (x[(i, j)] - shift[j]) * scale[j]);
            let want = z.clone().qr().r();
            for i in 0..p {
                let sign = (r[i * (p + 1) + i] * want[(i, i)]).signum();
                for j in 0..p {
                    let (g, w) = (r[i * (p + 1) + j] * sign, want[(i, j)]);
                    assert!(
                        (g - w).abs() < 1e-11 * want[(0, 0)].abs(),
                        "n={n} p={p} R[{i},{j}]: {g} vs {w}"
                    );
                }
            }
            // least-squares residual of y* on Z through the carried column
            let ys = nalgebra::DVector::from_fn(n, |i, _| (y[i] - shift[p]) * scale[p]);
            let qty2: f64 = (0..p).map(|i| r[i * (p + 1) + p].powi(2)).sum();
            let beta = z.clone().svd(true, true).solve(&ys, 1e-14).unwrap();
            let resid2 = (&ys - &z * beta).norm_squared();
            assert!(
                (ys.norm_squared() - qty2 - resid2).abs() < 1e-9 * ys.norm_squared(),
                "n={n} p={p}"
            );
        }
    }
}
