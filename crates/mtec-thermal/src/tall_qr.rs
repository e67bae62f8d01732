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
//! The reflections are applied two at a time to four columns at a time (one pass for the dot
//! products, one for the update) with fused multiply-adds: half the loads and stores per
//! multiply-add of one reflection at a time (issue 22).
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
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports AVX2 and FMA (checked just above); the function has no other
        // requirement. The arithmetic is the same, in the same order, as the portable path:
        // `mul_add` is one correctly rounded operation on both (an instruction here, a libm
        // call there), so both give the same bits.
        unsafe { reflect_block_fma(r, blk, b, p, c) };
        return;
    }
    reflect_block_portable(r, blk, b, p, c)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn reflect_block_fma(r: &mut [f64], blk: &mut [f64], b: usize, p: usize, c: usize) {
    reflect_block_generic::<true>(r, blk, b, p, c)
}

fn reflect_block_portable(r: &mut [f64], blk: &mut [f64], b: usize, p: usize, c: usize) {
    reflect_block_generic::<false>(r, blk, b, p, c)
}

/// One Householder reflector H = I − τ v vᵀ that maps x = [R_kk; B[:, k]] to [α; 0]:
/// α = −sign(R_kk)‖x‖, v = x − α e₁, so v₀ = R_kk − α (no cancellation) and v's block part is
/// B[:, k] itself (Golub & Van Loan 2013, Alg. 5.1.1). Returns (v₀, τ); τ = 0 is the identity.
#[inline(always)]
fn reflector(r_kk: &mut f64, sigma: f64) -> (f64, f64) {
    if sigma == 0.0 {
        return (0.0, 0.0); // the block's column is already zero
    }
    let x0 = *r_kk;
    let alpha = -x0.mul_add(x0, sigma).sqrt().copysign(x0);
    let v0 = x0 - alpha;
    *r_kk = alpha;
    (v0, 2.0 / v0.mul_add(v0, sigma))
}

/// The reflections two at a time (a compact-WY block of two, Schreiber & Van Loan 1989): with
/// u = [v₀ e_k; x] and w = [w₀ e_{k+1}; y] the vectors of H_k and H_{k+1}, a column [r; z] is
/// mapped by H_{k+1}H_k as f₁ = τ₁(v₀r_k + x·z), f₂ = τ₂(w₀r_{k+1} + y·z − f₁ y·x),
/// z ← z − f₁x − f₂y: one pass for the dot products and one for the update, four columns per pass
/// so that x and y are loaded once for four columns (issue 22: the single reflections were bound
/// by loads and stores, two per multiply-add).
/// `SIMD`: the four-column kernels in AVX2/FMA intrinsics (only from `reflect_block_fma`).
#[inline(always)]
fn reflect_block_generic<const SIMD: bool>(
    r: &mut [f64],
    blk: &mut [f64],
    b: usize,
    p: usize,
    c: usize,
) {
    let mut k = 0;
    while k < p {
        let (left, right) = blk.split_at_mut((k + 1) * b);
        let x = &left[k * b..];
        let (v0, tau1) = reflector(&mut r[k * c + k], dot(x, x));
        if k + 1 == p {
            // the last reflection alone, on the carried columns
            for (jj, z) in right.chunks_exact_mut(b).enumerate() {
                let j = k + 1 + jj;
                let f = tau1 * v0.mul_add(r[k * c + j], dot(x, z));
                r[k * c + j] = (-f).mul_add(v0, r[k * c + j]);
                axpy(z, -f, x);
            }
            break;
        }
        // H_k on column k + 1, then the reflector of column k + 1
        let (y, rest) = right.split_at_mut(b);
        let f = tau1 * v0.mul_add(r[k * c + k + 1], dot(x, y));
        r[k * c + k + 1] = (-f).mul_add(v0, r[k * c + k + 1]);
        axpy(y, -f, x);
        let k1 = k + 1;
        let (w0, tau2) = reflector(&mut r[k1 * c + k1], dot(y, y));
        let yx = dot(y, x);
        let y: &[f64] = y;
        let mut j = k + 2;
        for group in rest.chunks_mut(4 * b) {
            match group.len() / b {
                4 => pair_step::<4, SIMD>(r, group, x, y, k, j, c, [v0, tau1, w0, tau2, yx], b),
                3 => pair_step::<3, SIMD>(r, group, x, y, k, j, c, [v0, tau1, w0, tau2, yx], b),
                2 => pair_step::<2, SIMD>(r, group, x, y, k, j, c, [v0, tau1, w0, tau2, yx], b),
                _ => pair_step::<1, SIMD>(r, group, x, y, k, j, c, [v0, tau1, w0, tau2, yx], b),
            }
            j += group.len() / b;
        }
        k += 2;
    }
}

/// H_{k+1}H_k on the N columns j.. of `cols` and on rows k, k + 1 of R (see
/// `reflect_block_generic`); `h` = [v₀, τ₁, w₀, τ₂, y·x].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pair_step<const N: usize, const SIMD: bool>(
    r: &mut [f64],
    cols: &mut [f64],
    x: &[f64],
    y: &[f64],
    k: usize,
    j: usize,
    c: usize,
    h: [f64; 5],
    b: usize,
) {
    let [v0, tau1, w0, tau2, yx] = h;
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SIMD is true only inside `reflect_block_fma`, called when AVX2 and FMA are present
    let (d1, d2) = if SIMD {
        unsafe { simd::dots::<N>(x, y, cols, b) }
    } else {
        dots::<N>(x, y, cols, b)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (d1, d2) = dots::<N>(x, y, cols, b);
    let mut f1 = [0.0; N];
    let mut f2 = [0.0; N];
    for q in 0..N {
        let (rk, rk1) = (k * c + j + q, (k + 1) * c + j + q);
        f1[q] = tau1 * v0.mul_add(r[rk], d1[q]);
        f2[q] = tau2 * w0.mul_add(r[rk1], (-f1[q]).mul_add(yx, d2[q]));
        r[rk] = (-f1[q]).mul_add(v0, r[rk]);
        r[rk1] = (-f2[q]).mul_add(w0, r[rk1]);
    }
    #[cfg(target_arch = "x86_64")]
    if SIMD {
        // SAFETY: as for `dots` above
        unsafe { simd::update::<N>(cols, x, y, f1, f2, b) };
        return;
    }
    update::<N>(cols, x, y, f1, f2, b);
}

/// z ← z + a·x.
#[inline(always)]
fn axpy(z: &mut [f64], a: f64, x: &[f64]) {
    for (zi, xi) in z.iter_mut().zip(x) {
        *zi = a.mul_add(*xi, *zi);
    }
}

/// Width of the partial sums in the four-column kernels: 4 × 2 × 4 sums are eight 4-wide
/// registers, enough independent chains to hide the latency of the multiply-adds.
const W: usize = 4;

/// x·z_q and y·z_q for the N columns z_q of `cols` (column-major, b rows each), in one pass,
/// partial sums in 4 lanes.
#[inline(always)]
fn dots<const N: usize>(x: &[f64], y: &[f64], cols: &[f64], b: usize) -> ([f64; N], [f64; N]) {
    let whole = b / W * W;
    let mut a = [[0.0f64; W]; N];
    let mut c = [[0.0f64; W]; N];
    for i in (0..whole).step_by(W) {
        for q in 0..N {
            for l in 0..W {
                let v = cols[q * b + i + l];
                a[q][l] = x[i + l].mul_add(v, a[q][l]);
                c[q][l] = y[i + l].mul_add(v, c[q][l]);
            }
        }
    }
    let sum = |s: [f64; W]| (s[0] + s[2]) + (s[1] + s[3]);
    let mut dx = a.map(sum);
    let mut dy = c.map(sum);
    for q in 0..N {
        for t in whole..b {
            dx[q] = x[t].mul_add(cols[q * b + t], dx[q]);
            dy[q] = y[t].mul_add(cols[q * b + t], dy[q]);
        }
    }
    (dx, dy)
}

/// z_q ← z_q − f1_q·x − f2_q·y for the N columns of `cols`.
#[inline(always)]
fn update<const N: usize>(
    cols: &mut [f64],
    x: &[f64],
    y: &[f64],
    f1: [f64; N],
    f2: [f64; N],
    b: usize,
) {
    for (q, z) in cols.chunks_exact_mut(b).take(N).enumerate() {
        for ((zi, xi), yi) in z.iter_mut().zip(x).zip(y) {
            *zi = (-f2[q]).mul_add(*yi, (-f1[q]).mul_add(*xi, *zi));
        }
    }
}

/// `dots` and `update` in AVX2/FMA intrinsics: the same operations in the same order as the
/// portable versions (lane l of each register is partial sum l), so the same bits; written out
/// because the compiler vectorised the portable loops across the four columns instead of along
/// the rows (shuffles and broadcasts in the hot loop).
#[cfg(target_arch = "x86_64")]
mod simd {
    use super::W;
    use std::arch::x86_64::*;

    /// x·z_q and y·z_q for the N columns z_q of `cols` (column-major, b rows each), one pass.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn dots<const N: usize>(
        x: &[f64],
        y: &[f64],
        cols: &[f64],
        b: usize,
    ) -> ([f64; N], [f64; N]) {
        assert!(x.len() >= b && y.len() >= b && cols.len() >= N * b);
        let whole = b / W * W;
        let (xp, yp, zp) = (x.as_ptr(), y.as_ptr(), cols.as_ptr());
        let mut a = [_mm256_setzero_pd(); N];
        let mut c = [_mm256_setzero_pd(); N];
        let mut i = 0;
        while i < whole {
            // SAFETY: i + 4 ≤ b and every column has b entries (asserted above)
            unsafe {
                let xv = _mm256_loadu_pd(xp.add(i));
                let yv = _mm256_loadu_pd(yp.add(i));
                for q in 0..N {
                    let v = _mm256_loadu_pd(zp.add(q * b + i));
                    a[q] = _mm256_fmadd_pd(xv, v, a[q]);
                    c[q] = _mm256_fmadd_pd(yv, v, c[q]);
                }
            }
            i += W;
        }
        let sum = |v: __m256d| {
            let mut s = [0.0f64; W];
            // SAFETY: s holds 4 f64
            unsafe { _mm256_storeu_pd(s.as_mut_ptr(), v) };
            (s[0] + s[2]) + (s[1] + s[3])
        };
        let mut dx = a.map(sum);
        let mut dy = c.map(sum);
        for q in 0..N {
            for t in whole..b {
                dx[q] = x[t].mul_add(cols[q * b + t], dx[q]);
                dy[q] = y[t].mul_add(cols[q * b + t], dy[q]);
            }
        }
        (dx, dy)
    }

    /// z_q ← z_q − f1_q·x − f2_q·y for the N columns of `cols`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn update<const N: usize>(
        cols: &mut [f64],
        x: &[f64],
        y: &[f64],
        f1: [f64; N],
        f2: [f64; N],
        b: usize,
    ) {
        assert!(x.len() >= b && y.len() >= b && cols.len() >= N * b);
        let whole = b / W * W;
        let (xp, yp, zp) = (x.as_ptr(), y.as_ptr(), cols.as_mut_ptr());
        let a1 = f1.map(|f| _mm256_set1_pd(-f));
        let a2 = f2.map(|f| _mm256_set1_pd(-f));
        let mut i = 0;
        while i < whole {
            // SAFETY: i + 4 ≤ b and every column has b entries (asserted above)
            unsafe {
                let xv = _mm256_loadu_pd(xp.add(i));
                let yv = _mm256_loadu_pd(yp.add(i));
                for q in 0..N {
                    let zq = zp.add(q * b + i);
                    let z = _mm256_fmadd_pd(a1[q], xv, _mm256_loadu_pd(zq));
                    _mm256_storeu_pd(zq, _mm256_fmadd_pd(a2[q], yv, z));
                }
            }
            i += W;
        }
        for q in 0..N {
            for t in whole..b {
                let z = &mut cols[q * b + t];
                *z = (-f2[q]).mul_add(y[t], (-f1[q]).mul_add(x[t], *z));
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
            s[l] = x[l].mul_add(y[l], s[l]);
        }
    }
    let mut t = reduce(s);
    for (x, y) in ra.iter().zip(rb) {
        t = x.mul_add(*y, t);
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

/// The mean x̄ of a column (partial sums in lanes, so that the pass vectorises).
pub(crate) fn mean(x: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present (checked); same arithmetic as the portable path.
        return unsafe { mean_avx2(x) };
    }
    mean_portable(x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn mean_avx2(x: &[f64]) -> f64 {
    mean_portable(x)
}

#[inline(always)]
fn mean_portable(x: &[f64]) -> f64 {
    let chunks = x.chunks_exact(LANES);
    let rest = chunks.remainder();
    let mut s = [0.0f64; LANES];
    for c in chunks {
        for l in 0..LANES {
            s[l] += c[l];
        }
    }
    (reduce(s) + rest.iter().sum::<f64>()) / x.len() as f64
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
    let mean = mean_portable(x);
    let chunks = x.chunks_exact(LANES);
    let rest = chunks.remainder();
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

    /// The AVX2/FMA kernels and the portable ones give the same bits (same operations, same
    /// order; `mul_add` is correctly rounded on both), for every column-group width 1–4.
    #[test]
    fn simd_and_portable_reflections_agree_bitwise() {
        for (b, p, c) in [(128, 16, 17), (29, 7, 8), (5, 4, 5), (130, 5, 5)] {
            let blk0: Vec<f64> = (0..b * c)
                .map(|i| ((i * 31 % 97) as f64 * 0.37).sin() + (i % 7) as f64)
                .collect();
            let r0: Vec<f64> = (0..p * c).map(|i| (i as f64 * 0.5).cos()).collect();
            let (mut r1, mut b1) = (r0.clone(), blk0.clone());
            let (mut r2, mut b2) = (r0.clone(), blk0.clone());
            reflect_block(&mut r1, &mut b1, b, p, c);
            reflect_block_portable(&mut r2, &mut b2, b, p, c);
            assert!(r1.iter().zip(&r2).all(|(a, b)| a.to_bits() == b.to_bits()));
            assert!(b1.iter().zip(&b2).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }
}
