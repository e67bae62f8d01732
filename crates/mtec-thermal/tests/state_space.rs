//! The state-space family of issue 17 item 3 is the lag bank: a lumped thermal network
//! (C·dθ/dt = −G·θ + q·p, C diagonal, G a symmetric conductance matrix) has real negative
//! eigenvalues, so its response to the heat input p is exactly Σᵢ cᵢ·L_τᵢ[p] with τᵢ = −1/λᵢ,
//! the features `heat-input` and `dynamic` fit (docs/methods.md §7, "State-space form").
//!
//! Reference not written with the claim: the network is integrated by classical Runge–Kutta
//! (RK4) with 100 sub-steps per sample, not by its modes; the time constants and the modal gains
//! come from the closed-form eigenvalues of the 2 × 2 system matrix.

use mtec_thermal::features::Feature;
use mtec_thermal::linear::ols;
use mtec_thermal::ThermalData;
use nalgebra::DMatrix;

/// Node 1 (spindle housing, heated), node 2 (column), both losing heat to the room.
struct Network {
    c: [f64; 2],    // heat capacities, J/K (scaled: minutes as the time unit)
    g1a: f64,       // node 1 – room conductance
    g12: f64,       // node 1 – node 2
    g2a: f64,       // node 2 – room
    q: f64,         // heat into node 1 per unit of p
    k_um: [f64; 2], // displacement per kelvin of each node's rise
}

impl Network {
    /// A = C⁻¹·(−G), b = C⁻¹·[q, 0].
    fn system(&self) -> ([[f64; 2]; 2], [f64; 2]) {
        let [c1, c2] = self.c;
        (
            [
                [-(self.g1a + self.g12) / c1, self.g12 / c1],
                [self.g12 / c2, -(self.g2a + self.g12) / c2],
            ],
            [self.q / c1, 0.0],
        )
    }

    /// θ at every sample: RK4 over each interval (t[i−1], t[i]] with p[i] held, 100 sub-steps.
    fn rises(&self, time: &[f64], p: &[f64]) -> Vec<[f64; 2]> {
        let (a, b) = self.system();
        let f = |th: [f64; 2], u: f64| {
            [
                a[0][0] * th[0] + a[0][1] * th[1] + b[0] * u,
                a[1][0] * th[0] + a[1][1] * th[1] + b[1] * u,
            ]
        };
        let mut th = [0.0, 0.0];
        let mut out = vec![th];
        for i in 1..time.len() {
            let h = (time[i] - time[i - 1]) / 100.0;
            for _ in 0..100 {
                let add = |x: [f64; 2], k: [f64; 2], s: f64| [x[0] + s * k[0], x[1] + s * k[1]];
                let k1 = f(th, p[i]);
                let k2 = f(add(th, k1, h / 2.0), p[i]);
                let k3 = f(add(th, k2, h / 2.0), p[i]);
                let k4 = f(add(th, k3, h), p[i]);
                for j in 0..2 {
                    th[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
                }
            }
            out.push(th);
        }
        out
    }

    /// Time constants −1/λ and the modal gains cᵢ of y = Σ cᵢ·L_τᵢ[p] (gain of L is 1 at
    /// steady state): y_ss = kᵀ·(−A)⁻¹·b·p splits over the modes as kᵀ·vᵢ·(wᵢᵀ·b)/(−λᵢ), with
    /// vᵢ the right and wᵢ the left eigenvectors (wᵢᵀvᵢ = 1) of the closed-form eigenvalues.
    fn modes(&self) -> [(f64, f64); 2] {
        let (a, b) = self.system();
        let tr = a[0][0] + a[1][1];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let disc = (tr * tr - 4.0 * det).sqrt();
        [(tr + disc) / 2.0, (tr - disc) / 2.0].map(|l| {
            let v = [a[0][1], l - a[0][0]]; // (A − λI)v = 0, first row
            let w = [a[1][0], l - a[0][0]]; // wᵀ(A − λI) = 0, first column
            let s = w[0] * v[0] + w[1] * v[1];
            let gain =
                (self.k_um[0] * v[0] + self.k_um[1] * v[1]) * (w[0] * b[0] + w[1] * b[1]) / s / -l;
            (-1.0 / l, gain)
        })
    }
}

fn record(net: &Network) -> (ThermalData, Vec<f64>) {
    // 15-s samples; the spindle steps every 100 min through speeds no model saw in order
    let speeds = [0.0, 2000.0, 4000.0, 0.0, 3000.0, 1000.0, 0.0, 4500.0, 0.0];
    let n = speeds.len() * 400;
    let time: Vec<f64> = (0..n).map(|i| i as f64 * 0.25).collect();
    let rpm: Vec<f64> = time.iter().map(|t| speeds[(t / 100.0) as usize]).collect();
    let p: Vec<f64> = rpm.iter().map(|v| (v / 1000.0).powf(1.5)).collect();
    let th = net.rises(&time, &p);
    let y: Vec<f64> = th
        .iter()
        .map(|t| net.k_um[0] * t[0] + net.k_um[1] * t[1])
        .collect();
    let d = ThermalData {
        experiment: vec!["1".into(); n],
        time_min: time,
        sensor_names: vec!["spindle_rpm".into()],
        temps_c: DMatrix::from_fn(n, 1, |i, _| rpm[i]),
        ambient_c: None,
        position_mm: None,
        target: Some(("drift_um".into(), y.clone())),
        more_targets: Vec::new(),
        sequence: None,
        source: None,
        lines: (2..n + 2).collect(),
    };
    (d, y)
}

fn heat(tau: f64) -> Feature {
    Feature::HeatLag {
        input: "spindle_rpm".into(),
        alpha: 1.5,
        tau_min: tau,
        rest_tau_min: tau,
    }
}

/// Largest |residual| (µm) and the coefficients of the OLS fit of y on the heat lags at `taus`.
fn fit(d: &ThermalData, y: &[f64], taus: &[f64]) -> (f64, Vec<f64>, f64) {
    let feats: Vec<Feature> = taus.iter().map(|&t| heat(t)).collect();
    let cols: Vec<Vec<f64>> = feats.iter().map(|f| f.values(d).unwrap()).collect();
    let x = DMatrix::from_fn(y.len(), cols.len(), |i, j| cols[j][i]);
    let names: Vec<String> = feats.iter().map(|f| f.name()).collect();
    let r = ols(&x, y, &names).unwrap();
    let worst = (0..y.len())
        .map(|i| {
            let pred = r.intercept
                + (0..cols.len())
                    .map(|j| r.coefficients[j] * cols[j][i])
                    .sum::<f64>();
            (y[i] - pred).abs()
        })
        .fold(0.0, f64::max);
    (worst, r.coefficients.clone(), r.intercept)
}

fn network() -> Network {
    Network {
        c: [40.0, 400.0],
        g1a: 0.8,
        g12: 1.2,
        g2a: 1.5,
        q: 10.0,
        k_um: [0.3, 0.5],
    }
}

#[test]
fn a_two_node_network_is_exactly_two_heat_lags_at_its_modal_time_constants() {
    let net = network();
    let modes = net.modes();
    let (tau_fast, tau_slow) = (modes[0].0.min(modes[1].0), modes[0].0.max(modes[1].0));
    // a real network: distinct, real time constants of minutes to hours
    assert!(
        tau_fast > 5.0 && tau_slow > 3.0 * tau_fast && tau_slow < 1000.0,
        "{modes:?}"
    );
    let (d, y) = record(&net);
    let span = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(span > 15.0, "drift {span} um");
    let taus = [modes[0].0, modes[1].0];
    let (worst, coef, intercept) = fit(&d, &y, &taus);
    // exact up to RK4's truncation and rounding: the model is the network, not an approximation
    assert!(worst < 1e-6, "largest residual {worst} um of {span} um");
    assert!(intercept.abs() < 1e-6, "intercept {intercept}");
    for (c, (_, gain)) in coef.iter().zip(modes) {
        assert!(
            (c - gain).abs() < 1e-6 * gain.abs(),
            "coefficient {c}, modal gain {gain}"
        );
    }
}

#[test]
fn wrong_time_constants_or_one_mode_do_not_fit_the_network() {
    let net = network();
    let modes = net.modes();
    let (d, y) = record(&net);
    // 20 % off in both time constants: a visible model error
    let (off, _, _) = fit(&d, &y, &[modes[0].0 * 1.2, modes[1].0 * 1.2]);
    assert!(off > 0.05, "largest residual {off} um");
    // one first-order lag cannot be a two-node network, whatever its time constant
    let best_one = [10.0, 20.0, 40.0, 80.0, 160.0, 320.0, 640.0]
        .iter()
        .map(|&t| fit(&d, &y, &[t]).0)
        .fold(f64::INFINITY, f64::min);
    assert!(best_one > 0.5, "largest residual {best_one} um");
}
