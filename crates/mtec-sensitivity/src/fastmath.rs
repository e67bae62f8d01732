//! The sine as a branch-free polynomial, so that a loop of them vectorises (issue 22: libm's `sin`
//! is one call per value and was 44 % of an EFAST run on the Ishigami function).
//!
//! Cody–Waite reduction x = q·π/2 + r with q the nearest integer to 2x/π and π/2 split into three
//! parts (fdlibm's `__ieee754_rem_pio2`, medium case: pio2_1, pio2_2, pio2_2t; q·pio2_1 and
//! q·pio2_2 are exact for |q| < 2²⁰), then fdlibm's minimax kernels `__kernel_sin` and
//! `__kernel_cos` on |r| ≤ π/4 (errors below one unit in the last place there), and the quadrant
//! q mod 4 picks ±sin r or ±cos r. Valid for |x| ≤ [`POLY_LIMIT`]; beyond it, and for non-finite
//! x, `std`'s sine is used. The tests bound the difference from `std`'s sine.

// the coefficients as fdlibm prints them (17+ digits), so that they can be checked against it
#![allow(clippy::excessive_precision)]

/// |x| up to which the reduction above is accurate (|q| < 2¹⁷).
pub const POLY_LIMIT: f64 = 1.0e5;

const FRAC_2_PI: f64 = std::f64::consts::FRAC_2_PI;
// π/2 = PIO2_1 + PIO2_2 + PIO2_2T (fdlibm e_rem_pio2.c): 33 + 33 bits and the tail
const PIO2_1: f64 = 1.570_796_326_734_125_614_17e0;
const PIO2_2: f64 = 6.077_100_506_303_965_976_60e-11;
const PIO2_2T: f64 = 2.022_266_248_795_950_631_54e-21;
// fdlibm k_sin.c
const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;
// fdlibm k_cos.c
const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;
/// 1.5·2⁵²: adding and subtracting it rounds a double of magnitude < 2⁵¹ to the nearest integer.
const ROUND: f64 = 6_755_399_441_055_744.0;

/// sin x: the polynomial for |x| ≤ [`POLY_LIMIT`], `std` beyond.
#[inline]
pub fn sin(x: f64) -> f64 {
    if x.abs() <= POLY_LIMIT {
        sin_poly(x)
    } else {
        x.sin()
    }
}

/// `out[i] = sin(x[i])` ([`sin`] for every element; the loop vectorises).
pub fn sin_slice(x: &[f64], out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present (checked). The arithmetic is the same as the portable loop's
        // (no fused multiply-add), so both give the same bits.
        return unsafe { sin_slice_avx2(x, out) };
    }
    sin_slice_portable(x, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sin_slice_avx2(x: &[f64], out: &mut [f64]) {
    sin_slice_portable(x, out)
}

#[inline(always)]
fn sin_slice_portable(x: &[f64], out: &mut [f64]) {
    for (o, &v) in out.iter_mut().zip(x) {
        *o = sin_poly(v);
    }
    for (o, &v) in out.iter_mut().zip(x) {
        if v.abs() > POLY_LIMIT || v.is_nan() {
            *o = v.sin();
        }
    }
}

/// The reduction and the kernels, valid for |x| ≤ [`POLY_LIMIT`].
#[inline(always)]
fn sin_poly(x: f64) -> f64 {
    let shifted = x * FRAC_2_PI + ROUND; // 2⁵¹·1.5 + q: q in the low bits of the mantissa
    let q = shifted - ROUND; // the nearest integer to 2x/π (ties to even)
    let r = ((x - q * PIO2_1) - q * PIO2_2) - q * PIO2_2T;
    let z = r * r;
    // __kernel_sin(r, 0, 0)
    let s = r + z * r * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    // __kernel_cos(r, 0)
    let w2 = z * z;
    let c_r = z * (C1 + z * (C2 + z * C3)) + w2 * w2 * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let c = w + (((1.0 - w) - hz) + z * c_r);
    // q mod 4 from the mantissa bits (2⁵¹ ≡ 0 mod 4): odd q takes cos r, q mod 4 ≥ 2 flips
    // the sign; done with masks so that the loop has no branch and no integer conversion
    let bits = shifted.to_bits();
    let take_cos = 0u64.wrapping_sub(bits & 1);
    let v = (s.to_bits() & !take_cos) | (c.to_bits() & take_cos);
    f64::from_bits(v ^ ((bits & 2) << 62))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within one unit in the last place of `std`'s sine (two for the values that the reduction
    /// makes tiny, near multiples of π, where the bound is absolute: 2·10⁻²⁰·|x|), on [−π, π]
    /// densely, on [−10⁴, 10⁴], at the quadrant boundaries and beyond the polynomial's range.
    #[test]
    fn sin_is_within_an_ulp_of_std() {
        let mut xs: Vec<f64> = (0..400_001)
            .map(|i| -std::f64::consts::PI + i as f64 * std::f64::consts::TAU / 400_000.0)
            .collect();
        xs.extend((0..200_001).map(|i| -1.0e4 + i as f64 * 0.1 + 1e-3 * (i as f64).sin()));
        xs.extend((-64..=64).map(|k| k as f64 * std::f64::consts::FRAC_PI_4));
        xs.extend([0.0, -0.0, 1e-300, 3e5, -7.5e8, 1e300]);
        let mut out = vec![0.0; xs.len()];
        sin_slice(&xs, &mut out);
        for (&x, &got) in xs.iter().zip(&out) {
            let want = x.sin();
            let err = (got - want).abs();
            let ulp = f64::EPSILON * want.abs().max(f64::MIN_POSITIVE);
            assert!(
                err <= ulp.max(2e-20 * x.abs()) * 2.0,
                "sin({x:e}) = {got:e}, std {want:e}"
            );
            assert_eq!(
                got.to_bits(),
                sin(x).to_bits(),
                "slice and scalar differ at {x}"
            );
        }
    }

    #[test]
    fn non_finite_inputs_give_nan() {
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(sin(x).is_nan());
        }
    }
}
