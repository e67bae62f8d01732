//! Environmental compensation of laser interferometer readings: the refractive index of air
//! (Ciddor 1996; the updated Edlén equations of Birch & Downs 1993/1994 and of Bönsch &
//! Potulski 1998) and the ISO 1 normalisation of a length to 20 °C.
//!
//! Both index equations are written as the NIST Engineering Metrology Toolbox states them
//! (J. A. Stone and J. H. Zimmerman, "Index of Refraction of Air", Appendix A,
//! emtoolbox.nist.gov/Wavelength/Documentation.asp):
//! - saturation vapour pressure: IAPWS (Wagner & Pruss) over water for t ≥ 0 °C, the IAPWS
//!   sublimation formula over ice below (A-I);
//! - Ciddor: P. E. Ciddor, Appl. Opt. 35, 1566–1573 (1996), with the BIPM-1981/91
//!   compressibility and the enhancement factor of Giacomo (A-III);
//! - Edlén: K. P. Birch and M. J. Downs, Metrologia 30, 155–162 (1993) and 31, 315–316 (1994),
//!   with the NIST water-vapour factor 292.75/T (A-IV), which equals Birch & Downs at 19.6 °C
//!   and departs from it by less than 1e-9 between 15 °C and 25 °C at 50 % RH.
//!
//! - Bönsch & Potulski: G. Bönsch and E. Potulski, Metrologia 35, 133–139 (1998), eqs. 6, 7, 8
//!   and 9a, as they give them (the water term without a temperature factor).
//!
//! A laser interferometer counts wavelengths in air: the length it reports is
//! `counts · λ_vac / n_laser`, where `n_laser` is the index its compensation assumed. With the
//! true index `n_actual` the true length is the reading times `n_laser / n_actual`.

/// State of the air in the beam path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Air {
    /// Air temperature t (°C).
    pub temperature_c: f64,
    /// Total pressure p (Pa).
    pub pressure_pa: f64,
    /// Relative humidity (%, 0..100).
    pub humidity_pct: f64,
    /// CO2 mole fraction x_c (µmol/mol); used by Ciddor and Bönsch & Potulski (Birch & Downs'
    /// Edlén assumes 450).
    pub co2_ppm: f64,
}

/// The reference air of ISO 1 and of most laser systems' "standard conditions": 20 °C,
/// 101 325 Pa, 50 % RH, 450 µmol/mol CO2.
pub const STANDARD_AIR: Air = Air {
    temperature_c: 20.0,
    pressure_pa: 101_325.0,
    humidity_pct: 50.0,
    co2_ppm: 450.0,
};

/// Vacuum wavelength of an iodine-unstabilised HeNe laser (nm), the usual interferometer source.
pub const HENE_WAVELENGTH_NM: f64 = 632.99;

/// Which equation gives the refractive index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AirFormula {
    /// Ciddor (1996): dispersion formula 230–1690 nm; built for air far from standard too.
    Ciddor,
    /// Birch & Downs (1993/1994) updated Edlén: 350–650 nm, near-standard shop-floor air.
    Edlen,
    /// Bönsch & Potulski (1998) updated Edlén: 350–650 nm, with the air's CO2 content.
    BonschPotulski,
}

impl AirFormula {
    /// Name as used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            AirFormula::Ciddor => "ciddor",
            AirFormula::Edlen => "edlen",
            AirFormula::BonschPotulski => "bonsch-potulski",
        }
    }

    /// Wavelength range (nm) mtec accepts (docs/methods.md §2.1).
    pub fn wavelength_range_nm(self) -> (f64, f64) {
        match self {
            AirFormula::Ciddor => (230.0, 1690.0),
            AirFormula::Edlen | AirFormula::BonschPotulski => (350.0, 650.0),
        }
    }
}

/// Accepted input ranges: shop-floor air (the equations are valid wider, a value outside these
/// is far more likely a unit mistake than a real environment).
pub const AIR_TEMPERATURE_RANGE_C: (f64, f64) = (-40.0, 60.0);
pub const PRESSURE_RANGE_PA: (f64, f64) = (50_000.0, 120_000.0);
pub const HUMIDITY_RANGE_PCT: (f64, f64) = (0.0, 100.0);
pub const CO2_RANGE_PPM: (f64, f64) = (0.0, 2000.0);
pub const MATERIAL_TEMPERATURE_RANGE_C: (f64, f64) = (-40.0, 60.0);
pub const ALPHA_RANGE_UM_PER_M_K: (f64, f64) = (0.0, 50.0);

fn check(name: &str, unit: &str, v: f64, (lo, hi): (f64, f64)) -> Result<(), String> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "{name} is {v} {unit}: expected {lo} to {hi} {unit}"
        ))
    }
}

impl Air {
    /// Refuses values outside the accepted ranges, naming the quantity.
    pub fn validate(&self) -> Result<(), String> {
        check(
            "air temperature",
            "°C",
            self.temperature_c,
            AIR_TEMPERATURE_RANGE_C,
        )?;
        check("air pressure", "Pa", self.pressure_pa, PRESSURE_RANGE_PA)?;
        check(
            "relative humidity",
            "%",
            self.humidity_pct,
            HUMIDITY_RANGE_PCT,
        )?;
        check("CO2 mole fraction", "ppm", self.co2_ppm, CO2_RANGE_PPM)
    }
}

/// Refuses a wavelength outside the range of the chosen equation.
pub fn validate_wavelength(formula: AirFormula, wavelength_nm: f64) -> Result<(), String> {
    check(
        &format!("the vacuum wavelength for {}", formula.name()),
        "nm",
        wavelength_nm,
        formula.wavelength_range_nm(),
    )
}

/// Saturation vapour pressure p_sv (Pa) at t (°C): IAPWS over water for t ≥ 0, over ice below
/// (NIST toolbox A-I).
pub fn saturation_vapour_pressure_pa(t_c: f64) -> f64 {
    let t = t_c + 273.15;
    if t_c >= 0.0 {
        // A-I: Ω = T + K9/(T − K10); A, B, C quadratics in Ω; p_sv = 10^6 (2C / (−B + √(B² − 4AC)))^4
        const K: [f64; 10] = [
            1.167_052_145_28e3,
            -7.242_131_670_32e5,
            -1.707_384_694_01e1,
            1.202_082_470_25e4,
            -3.232_555_032_23e6,
            1.491_510_861_35e1,
            -4.823_265_736_16e3,
            4.051_134_054_21e5,
            -2.385_555_756_78e-1,
            6.501_753_484_48e2,
        ];
        let omega = t + K[8] / (t - K[9]);
        let a = omega * omega + K[0] * omega + K[1];
        let b = K[2] * omega * omega + K[3] * omega + K[4];
        let c = K[5] * omega * omega + K[6] * omega + K[7];
        let x = -b + (b * b - 4.0 * a * c).sqrt();
        1e6 * (2.0 * c / x).powi(4)
    } else {
        // A-I over ice: Θ = T/273.16; Y = A1(1 − Θ^−1.5) + A2(1 − Θ^−1.25); p_sv = 611.657 e^Y
        const A1: f64 = -13.928_169;
        const A2: f64 = 34.707_823_8;
        let theta = t / 273.16;
        let y = A1 * (1.0 - theta.powf(-1.5)) + A2 * (1.0 - theta.powf(-1.25));
        611.657 * y.exp()
    }
}

/// Refractive index by the chosen equation at vacuum wavelength `wavelength_nm`.
pub fn refractive_index(formula: AirFormula, air: &Air, wavelength_nm: f64) -> f64 {
    match formula {
        AirFormula::Ciddor => ciddor(air, wavelength_nm),
        AirFormula::Edlen => edlen(air, wavelength_nm),
        AirFormula::BonschPotulski => bonsch_potulski(air, wavelength_nm),
    }
}

/// Compressibility Z of moist air (BIPM-1981/91 as in Ciddor 1996, eq. 12).
fn compressibility(t_k: f64, p: f64, xw: f64) -> f64 {
    const A0: f64 = 1.581_23e-6;
    const A1: f64 = -2.9331e-8;
    const A2: f64 = 1.1043e-10;
    const B0: f64 = 5.707e-6;
    const B1: f64 = -2.051e-8;
    const C0: f64 = 1.9898e-4;
    const C1: f64 = -2.376e-6;
    const D: f64 = 1.83e-11;
    const E: f64 = -0.765e-8;
    let t = t_k - 273.15;
    let pt = p / t_k;
    // Z = 1 − (p/T)[a0 + a1 t + a2 t² + (b0 + b1 t) x_w + (c0 + c1 t) x_w²] + (p/T)²(d + e x_w²)
    1.0 - pt * (A0 + A1 * t + A2 * t * t + (B0 + B1 * t) * xw + (C0 + C1 * t) * xw * xw)
        + pt * pt * (D + E * xw * xw)
}

/// Ciddor (1996) phase index of moist air (NIST toolbox A-III).
pub fn ciddor(air: &Air, wavelength_nm: f64) -> f64 {
    const R: f64 = 8.314_472; // J/(mol K); cancels in the density ratios below
    const MV: f64 = 0.018_015; // kg/mol, water
    let t = air.temperature_c;
    let tk = t + 273.15;
    let p = air.pressure_pa;
    let s = (1000.0 / wavelength_nm).powi(2); // σ² in µm⁻²
                                              // mole fraction of water vapour: x_v = h f(p, t) p_sv / p, f = α + βp + γt² (Giacomo)
    let f = 1.000_62 + 3.14e-8 * p + 5.6e-7 * t * t;
    let xv = air.humidity_pct / 100.0 * f * saturation_vapour_pressure_pa(t) / p;
    // Ciddor eq. 1: (n_as − 1)·10⁸ = k1/(k0 − σ²) + k3/(k2 − σ²)
    let r_as = 1e-8 * (5_792_105.0 / (238.0185 - s) + 167_917.0 / (57.362 - s));
    // Ciddor eq. 3: (n_ws − 1)·10⁸ = 1.022 (w0 + w1σ² + w2σ⁴ + w3σ⁶)
    let r_vs = 1.022e-8 * (295.235 + 2.6422 * s - 0.032_380 * s * s + 0.004_028 * s * s * s);
    // Ciddor eq. 4: molar mass of dry air with x_c ppm CO2
    let ma = 0.028_963_5 + 1.2011e-8 * (air.co2_ppm - 400.0);
    // Ciddor eq. 2: (n_axs − 1) = (n_as − 1)[1 + 0.534·10⁻⁶ (x_c − 450)]
    let r_axs = r_as * (1.0 + 5.34e-7 * (air.co2_ppm - 450.0));
    // Ciddor eq. 4: ρ = p M_a / (Z R T) [1 − x_w (1 − M_w/M_a)], split into dry and vapour parts
    let z_a = compressibility(288.15, 101_325.0, 0.0);
    let z_v = compressibility(293.15, 1333.0, 1.0);
    let z_m = compressibility(tk, p, xv);
    let rho_axs = 101_325.0 * ma / (z_a * R * 288.15);
    let rho_vs = 1333.0 * MV / (z_v * R * 293.15);
    let rho_a = p * ma * (1.0 - xv) / (z_m * R * tk);
    let rho_v = p * MV * xv / (z_m * R * tk);
    // Ciddor eq. 5: n − 1 = (ρ_a/ρ_axs)(n_axs − 1) + (ρ_v/ρ_vs)(n_ws − 1)
    1.0 + rho_a / rho_axs * r_axs + rho_v / rho_vs * r_vs
}

/// Updated Edlén equation (Birch & Downs 1993, corrected 1994) with the NIST water term
/// (NIST toolbox A-IV).
pub fn edlen(air: &Air, wavelength_nm: f64) -> f64 {
    let t = air.temperature_c;
    let p = air.pressure_pa;
    let s = (1000.0 / wavelength_nm).powi(2); // σ² in µm⁻²
                                              // Birch & Downs (1994) eq. 2: (n − 1)_s·10⁸ = 8342.54 + 2406147/(130 − σ²) + 15998/(38.9 − σ²)
    let r_s = 1e-8 * (8342.54 + 2_406_147.0 / (130.0 - s) + 15_998.0 / (38.9 - s));
    // Birch & Downs (1993) eq. 3: (n − 1)_tp = p (n − 1)_s [1 + 10⁻⁸(0.601 − 0.00972 t) p] / (96095.43 (1 + 0.003661 t))
    let r_tp =
        p * r_s * (1.0 + 1e-8 * (0.601 - 0.009_72 * t) * p) / (96_095.43 * (1.0 + 0.003_661 * t));
    // Birch & Downs (1993) eq. 4 with NIST's 292.75/T: n_tpf − n_tp = −(292.75/T) f (3.7345 − 0.0401 σ²)·10⁻¹⁰
    let pv = air.humidity_pct / 100.0 * saturation_vapour_pressure_pa(t);
    1.0 + r_tp - 292.75 / (t + 273.15) * pv * (3.7345 - 0.0401 * s) * 1e-10
}

/// Updated Edlén equation of Bönsch & Potulski (1998), with the air's CO2 content.
pub fn bonsch_potulski(air: &Air, wavelength_nm: f64) -> f64 {
    let t = air.temperature_c;
    let p = air.pressure_pa;
    let x = air.co2_ppm * 1e-6;
    // σ² in µm⁻²
    let s = (1000.0 / wavelength_nm).powi(2);
    // B&P eq. 6: (n − 1)_N·10⁸ = 8091.37 + 2333983/(130 − σ²) + 15518/(38.9 − σ²)
    let r_n = 1e-8 * (8091.37 + 2_333_983.0 / (130.0 - s) + 15_518.0 / (38.9 - s));
    // B&P eq. 7: (n − 1)_x = (n − 1)_N [1 + 0.5327 (x − 0.0004)]
    let r_x = r_n * (1.0 + 0.5327 * (x - 0.0004));
    // B&P eq. 8: (n − 1)_tp = p (n − 1)_x [1 + 10⁻⁸(0.5953 − 0.009876 t) p] / (93214.60 (1 + 0.0036610 t))
    let r_tp = p * r_x * (1.0 + 1e-8 * (0.5953 - 0.009_876 * t) * p)
        / (93_214.60 * (1.0 + 0.003_661_0 * t));
    // B&P eq. 9a: n_tpf − n_tp = −f (3.8020 − 0.0384 σ²)·10⁻¹⁰
    let f = air.humidity_pct / 100.0 * saturation_vapour_pressure_pa(t);
    1.0 + r_tp - f * (3.8020 - 0.0384 * s) * 1e-10
}

/// Factor that turns a length read by a laser that assumed index `n_laser` into the true length
/// in air of index `n_actual`: L_true = L_read · n_laser / n_actual.
pub fn index_correction_factor(n_laser: f64, n_actual: f64) -> f64 {
    n_laser / n_actual
}

/// ISO 1 normalisation: a length L measured on material at temperature `t_c` with linear
/// expansion coefficient `alpha_um_per_m_k` is, at 20 °C, L20 = L / (1 + α (t − 20)) (exact
/// linear-expansion form; the first-order L (1 − α (t − 20)) differs by α²Δt² L, 0.13 µm/m at
/// 11.5 µm/m/K and 30 K).
pub fn normalise_to_20c(length: f64, t_c: f64, alpha_um_per_m_k: f64) -> f64 {
    length * normalisation_factor(t_c, alpha_um_per_m_k)
}

/// The factor 1 / (1 + α (t − 20)) of [`normalise_to_20c`].
pub fn normalisation_factor(t_c: f64, alpha_um_per_m_k: f64) -> f64 {
    1.0 / (1.0 + alpha_um_per_m_k * 1e-6 * (t_c - 20.0))
}

/// Refuses a material temperature or expansion coefficient outside the accepted ranges.
pub fn validate_material(t_c: f64, alpha_um_per_m_k: f64) -> Result<(), String> {
    check(
        "material temperature",
        "°C",
        t_c,
        MATERIAL_TEMPERATURE_RANGE_C,
    )?;
    check(
        "expansion coefficient",
        "µm/m/K",
        alpha_um_per_m_k,
        ALPHA_RANGE_UM_PER_M_K,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn air(t: f64, p: f64, rh: f64) -> Air {
        Air {
            temperature_c: t,
            pressure_pa: p,
            humidity_pct: rh,
            co2_ppm: 450.0,
        }
    }

    // Published values: the `ref_index` package (P. Nair, pypi.org/project/ref-index), an
    // implementation of the NIST toolbox equations, documents these results in its README at
    // λ_vac = 633.0 nm, 101 325 Pa, 450 ppm CO2.
    #[allow(clippy::excessive_precision)] // the digits as published
    const REF_INDEX: [(f64, f64, f64, f64); 3] = [
        // (t °C, RH %, Ciddor, Edlén)
        (20.0, 20.0, 1.000_271_628_534_057_8, 1.000_271_629_169_164_9),
        (20.0, 80.0, 1.000_271_118_347_262_6, 1.000_271_119_763_522_6),
        (60.0, 80.0, 1.000_234_024_175_405_5, 1.000_233_974_854_282_3),
    ];

    #[test]
    fn ciddor_matches_published_values_within_1e_8() {
        for (t, rh, n_ciddor, _) in REF_INDEX {
            let n = ciddor(&air(t, 101_325.0, rh), 633.0);
            assert!(
                (n - n_ciddor).abs() < 1e-8,
                "t {t} RH {rh}: {n} vs {n_ciddor}"
            );
        }
    }

    #[test]
    fn edlen_matches_published_values_within_1e_8() {
        for (t, rh, _, n_edlen) in REF_INDEX {
            let n = edlen(&air(t, 101_325.0, rh), 633.0);
            assert!(
                (n - n_edlen).abs() < 1e-8,
                "t {t} RH {rh}: {n} vs {n_edlen}"
            );
        }
    }

    // An independent implementation: the `AstroAtmosphere` package 1.6 (PyPI),
    // `refractivityModels.BonschPotulski(l=0.633, T, p=101325, RH, CO2)`, which writes B&P eqs.
    // 6–9a from the paper with the CIPM (Davis 1992) saturation vapour pressure; run for these
    // values. (t °C, RH %, CO2 ppm, n)
    #[allow(clippy::excessive_precision)] // the digits as printed
    const ASTRO_ATMOSPHERE_BP: [(f64, f64, f64, f64); 4] = [
        (20.0, 20.0, 450.0, 1.000_271_617_016_67),
        (20.0, 80.0, 450.0, 1.000_271_096_857_165_8),
        (15.0, 0.0, 400.0, 1.000_276_513_004_164_4),
        (25.0, 50.0, 450.0, 1.000_266_631_699_270_5),
    ];

    #[test]
    fn bonsch_potulski_matches_an_independent_implementation_within_1e_8() {
        for (t, rh, co2, n_ref) in ASTRO_ATMOSPHERE_BP {
            let a = Air {
                co2_ppm: co2,
                ..air(t, 101_325.0, rh)
            };
            let n = bonsch_potulski(&a, 633.0);
            assert!((n - n_ref).abs() < 1e-8, "t {t} RH {rh}: {n} vs {n_ref}");
        }
        // and CO2 moves it as B&P eq. 7 says: +0.5327·(n − 1) per unit mole fraction
        let lo = bonsch_potulski(&air(20.0, 101_325.0, 0.0), 633.0);
        let hi = bonsch_potulski(
            &Air {
                co2_ppm: 550.0,
                ..air(20.0, 101_325.0, 0.0)
            },
            633.0,
        );
        let expected = (lo - 1.0) * 0.5327 * 100e-6 / (1.0 + 0.5327 * (450e-6 - 0.0004));
        assert!(((hi - lo) - expected).abs() < 1e-15);
    }

    #[test]
    fn the_three_equations_agree_near_standard_air() {
        // B&P and Birch & Downs are fits to the same measurements: within 3e-8 of Ciddor at
        // shop-floor conditions (Bönsch & Potulski 1998, §5)
        for (t, rh) in [(18.0, 30.0), (20.0, 50.0), (23.0, 60.0)] {
            let a = air(t, 100_000.0, rh);
            let c = ciddor(&a, 633.0);
            for n in [edlen(&a, 633.0), bonsch_potulski(&a, 633.0)] {
                assert!((n - c).abs() < 3e-8, "t {t} RH {rh}: {n} vs Ciddor {c}");
            }
        }
    }

    #[test]
    fn ciddor_standard_dry_air_is_the_dispersion_formula() {
        // Ciddor eq. 1 defines standard air (15 °C, 101 325 Pa, dry, 450 ppm): at these
        // conditions the density ratio is exactly 1, so n − 1 must equal (n_as − 1) itself.
        // (This checks the density bookkeeping, not the constants: those are checked above.)
        let s: f64 = (1000.0f64 / 633.0).powi(2);
        let by_hand = 1e-8 * (5_792_105.0 / (238.0185 - s) + 167_917.0 / (57.362 - s));
        let n = ciddor(&air(15.0, 101_325.0, 0.0), 633.0);
        assert!((n - 1.0 - by_hand).abs() < 1e-12, "{n}");
    }

    #[test]
    fn humidity_lowers_the_index_and_temperature_lowers_it_by_about_1_ppm_per_kelvin() {
        for f in [
            AirFormula::Ciddor,
            AirFormula::Edlen,
            AirFormula::BonschPotulski,
        ] {
            let n20 = refractive_index(f, &STANDARD_AIR, HENE_WAVELENGTH_NM);
            let n21 = refractive_index(f, &air(21.0, 101_325.0, 50.0), HENE_WAVELENGTH_NM);
            let dn_ppm = (n20 - n21) * 1e6;
            assert!((0.90..1.0).contains(&dn_ppm), "{f:?}: {dn_ppm} ppm/K");
            let dry = refractive_index(f, &air(20.0, 101_325.0, 0.0), HENE_WAVELENGTH_NM);
            assert!(dry > n20);
        }
    }

    #[test]
    fn saturation_vapour_pressure_matches_the_iapws_fixed_points() {
        // IAPWS: 611.657 Pa at the triple point (0.01 °C, over water); over ice at 0 °C
        // 611.15 Pa (below the 611.21 Pa of supercooled water: the switch at 0 °C is a real step)
        assert!((saturation_vapour_pressure_pa(0.01) - 611.657).abs() < 0.01);
        assert!((saturation_vapour_pressure_pa(-1e-9) - 611.15).abs() < 0.01);
        assert!((saturation_vapour_pressure_pa(0.0) - 611.21).abs() < 0.01);
        // steam tables (IAPWS-IF97) at 20 °C: 2.3393 kPa
        assert!((saturation_vapour_pressure_pa(20.0) - 2339.3).abs() < 0.3);
    }

    #[test]
    fn normalisation_to_20c() {
        // steel 11.5 µm/m/K, 1000 mm at 25 °C → 1000 / (1 + 57.5e-6) = 999.942503... mm
        let l20 = normalise_to_20c(1000.0, 25.0, 11.5);
        assert!((l20 - 1000.0 / 1.0000575).abs() < 1e-12);
        assert!((l20 - (1000.0 - 0.0575)).abs() < 4e-6); // first order within α²Δt² L
        assert_eq!(normalise_to_20c(1000.0, 20.0, 11.5), 1000.0);
    }

    #[test]
    fn ranges_are_enforced() {
        assert!(STANDARD_AIR.validate().is_ok());
        assert!(air(61.0, 101_325.0, 50.0).validate().is_err());
        assert!(air(20.0, 49_999.0, 50.0).validate().is_err());
        assert!(air(20.0, 101_325.0, 100.5).validate().is_err());
        assert!(air(f64::NAN, 101_325.0, 50.0).validate().is_err());
        assert!(validate_material(20.0, 51.0).is_err());
        assert!(validate_material(20.0, -0.1).is_err());
        assert!(validate_material(20.0, 11.5).is_ok());
        assert!(validate_wavelength(AirFormula::Edlen, 1064.0).is_err());
        assert!(validate_wavelength(AirFormula::Ciddor, 1064.0).is_ok());
    }
}
