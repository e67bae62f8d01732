//! The basis functions of the error functions: Legendre polynomials on the travel mapped to
//! [−1, 1], and a sine/cosine pair for a ball screw's pitch error of known period.
//!
//! With x = (2q − q_min − q_max)/L the axis position mapped to [−1, 1]:
//! - φ_p(x) = P_p(x) − P_p(−1) = P_p(x) − (−1)^p, p ≥ 1: zero at the origin (the travel's lower
//!   end). P_p is orthogonal to 1 and x on [−1, 1] for p ≥ 2, so φ_p (p ≥ 2) has a zero
//!   least-squares slope over the travel: it is a straightness from its ISO 230-1 reference line
//!   as it stands, with no correction term;
//! - the pitch pair ψ_s(q) = sin(2π(q − q_min)/P), ψ_c(q) = cos(2π(q − q_min)/P) − 1: zero at
//!   the origin, P = `period_mm` of the axis (the screw lead).
//!
//! Why Legendre and not powers of s ∈ [0, 1]: the columns s, s², …, s¹² are nearly parallel
//! (the Gram matrix of the monomials on [0, 1] is the Hilbert matrix, condition ~10¹⁶ at degree
//! 12); the P_p are orthogonal on the travel, so the column-scaled design stays well conditioned
//! at the degrees a real machine needs.

/// P_0(x) .. P_n(x) by Bonnet's recursion (n + 1)P_{n+1} = (2n + 1)x P_n − n P_{n−1}.
pub fn legendre_all(n: usize, x: f64) -> Vec<f64> {
    let mut p = Vec::with_capacity(n + 1);
    p.push(1.0);
    if n >= 1 {
        p.push(x);
    }
    for k in 1..n {
        let kf = k as f64;
        p.push(((2.0 * kf + 1.0) * x * p[k] - kf * p[k - 1]) / (kf + 1.0));
    }
    p
}

/// P_p(−1) = (−1)^p.
pub fn at_minus_one(p: usize) -> f64 {
    if p.is_multiple_of(2) {
        1.0
    } else {
        -1.0
    }
}

/// φ_p(x) = P_p(x) − (−1)^p (zero at x = −1).
pub fn legendre_from_origin(p: usize, x: f64) -> f64 {
    legendre_all(p, x)[p] - at_minus_one(p)
}

/// Monomial coefficients (in x, ascending) of P_0 .. P_n, from the same recursion.
pub fn legendre_monomials(n: usize) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = vec![vec![1.0]];
    if n >= 1 {
        out.push(vec![0.0, 1.0]);
    }
    for k in 1..n {
        let kf = k as f64;
        let mut next = vec![0.0; k + 2];
        for (i, c) in out[k].iter().enumerate() {
            next[i + 1] += (2.0 * kf + 1.0) * c / (kf + 1.0);
        }
        for (i, c) in out[k - 1].iter().enumerate() {
            next[i] -= kf * c / (kf + 1.0);
        }
        out.push(next);
    }
    out
}

/// Σ_p c_p φ_p(x) as (power of s, coefficient) terms, s = (x + 1)/2 ∈ [0, 1]: the Legendre
/// series expanded to monomials in x, then x = 2s − 1 substituted (binomial expansion).
pub fn legendre_to_power_terms(orders: &[i32], coeffs: &[f64]) -> Vec<(i32, f64)> {
    let n = orders.iter().copied().max().unwrap_or(0).max(0) as usize;
    let mono = legendre_monomials(n);
    // in x
    let mut in_x = vec![0.0; n + 1];
    for (&p, &c) in orders.iter().zip(coeffs) {
        let p = p as usize;
        for (i, m) in mono[p].iter().enumerate() {
            in_x[i] += c * m;
        }
        in_x[0] -= c * at_minus_one(p);
    }
    // x^i = (2s − 1)^i = Σ_k C(i,k) 2^k s^k (−1)^(i−k)
    let mut in_s = vec![0.0; n + 1];
    for (i, &a) in in_x.iter().enumerate() {
        let mut binom = 1.0;
        for (k, o) in in_s.iter_mut().enumerate().take(i + 1) {
            *o += a * binom * 2f64.powi(k as i32) * at_minus_one(i - k);
            binom = binom * (i - k) as f64 / (k + 1) as f64;
        }
    }
    in_s.into_iter()
        .enumerate()
        .map(|(k, c)| (k as i32, c))
        .collect()
}

/// The pitch pair (ψ_s, ψ_c) at distance d = q − q_min from the origin, period P (mm).
pub fn pitch_pair(d_mm: f64, period_mm: f64) -> [f64; 2] {
    let w = std::f64::consts::TAU * d_mm / period_mm;
    [w.sin(), w.cos() - 1.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monomial_expansion_matches_the_recursion() {
        let orders: Vec<i32> = (1..=12).collect();
        let coeffs: Vec<f64> = (0..12).map(|i| 0.3 * i as f64 - 1.1).collect();
        let terms = legendre_to_power_terms(&orders, &coeffs);
        for k in 0..=20 {
            let s = k as f64 / 20.0;
            let x = 2.0 * s - 1.0;
            let direct: f64 = orders
                .iter()
                .zip(&coeffs)
                .map(|(&p, c)| c * legendre_from_origin(p as usize, x))
                .sum();
            let expanded: f64 = terms.iter().map(|(p, c)| c * s.powi(*p)).sum();
            // the expansion in powers cancels: ~1e-10 relative at degree 12 (f64 storage)
            assert!((direct - expanded).abs() < 1e-7, "{s}: {direct} {expanded}");
        }
    }

    #[test]
    fn straightness_functions_have_no_least_squares_slope() {
        // ∫ x φ_p(x) dx = 0 for p ≥ 2 (midpoint rule, 2000 points)
        for p in 2..=12 {
            let n = 2000;
            let s: f64 = (0..n)
                .map(|i| {
                    let x = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                    x * legendre_from_origin(p, x)
                })
                .sum::<f64>()
                / n as f64;
            assert!(s.abs() < 1e-5, "p {p}: {s}");
        }
    }
}
