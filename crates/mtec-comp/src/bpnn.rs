//! The back-propagation network (BPNN) as plain data: one hidden layer, evaluated in pure Rust.
//!
//! y = D_out( W2 · σ( W1 · N_in(x) + b1 ) + b2 )            (the standard one-hidden-layer MLP)
//!
//! where N_in maps each input to [−1, 1] by its training min/max (MATLAB `mapminmax`, the
//! normalisation the BPNN literature uses) and D_out undoes the z-score of each output
//! (mean/std of the training targets). The flattened parameter vector θ used by the trainers is
//! `[W1 (hidden × in, row-major), b1, W2 (out × hidden, row-major), b2]`, so a 3-10-3 net has
//! 10·(3+1) + 3·(10+1) = 73 parameters.
//!
//! File format `mtec.bpnn/1` (JSON): `format`, `activation`, `input_names`, `output_names`,
//! `input_offset`, `input_scale` (x_n = (x − offset)/scale), `output_offset`, `output_scale`
//! (y = offset + scale·y_n), `w1` (rows = hidden units), `b1`, `w2` (rows = outputs), `b2`, and
//! free-form `provenance`. Loading checks every shape and that all numbers are finite.
//!
//! Where it lives: here in `mtec-comp`, beside the grid map, because a fitted network is a
//! compensable model like any other (`load_error_model`, the real-time library). Training is in
//! `mtec-nn`, which re-exports this module; evaluating needs no neural-network library.

use crate::model::ErrorModel;
use serde::{Deserialize, Serialize};

/// What is wrong with a network's input or file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BpnnError {
    /// The input does not fit the network (wrong length).
    #[error("invalid data: {0}")]
    Data(String),
    /// The document is not a valid `mtec.bpnn/1` network.
    #[error("invalid model file: {0}")]
    Model(String),
}

type Result<T> = std::result::Result<T, BpnnError>;

pub const FORMAT: &str = "mtec.bpnn/1";

/// Hidden-layer activation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    /// Logistic sigmoid 1/(1+e^−a) (the source's choice, default).
    #[default]
    Sigmoid,
    /// Hyperbolic tangent.
    Tanh,
    /// Rectified linear unit max(0, a).
    Relu,
}

impl Activation {
    #[inline]
    pub fn apply(self, a: f64) -> f64 {
        match self {
            Activation::Sigmoid => 1.0 / (1.0 + (-a).exp()),
            Activation::Tanh => a.tanh(),
            Activation::Relu => a.max(0.0),
        }
    }

    /// dσ/da expressed through the activation's value s = σ(a) (and a for ReLU).
    #[inline]
    pub fn derivative(self, a: f64, s: f64) -> f64 {
        match self {
            Activation::Sigmoid => s * (1.0 - s),
            Activation::Tanh => 1.0 - s * s,
            Activation::Relu => {
                if a > 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }

    pub fn parse(name: &str) -> Option<Activation> {
        match name.to_ascii_lowercase().as_str() {
            "sigmoid" | "logsig" => Some(Activation::Sigmoid),
            "tanh" | "tansig" => Some(Activation::Tanh),
            "relu" => Some(Activation::Relu),
            _ => None,
        }
    }
}

/// Per-column affine normalisation x_n = (x − offset) / scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Affine {
    pub offset: Vec<f64>,
    pub scale: Vec<f64>,
}

impl Affine {
    /// Maps each column's [min, max] to [−1, 1] (`mapminmax`); a constant column gets scale 1.
    pub fn min_max(rows: &[Vec<f64>], n: usize) -> Affine {
        let mut lo = vec![f64::INFINITY; n];
        let mut hi = vec![f64::NEG_INFINITY; n];
        for r in rows {
            for j in 0..n {
                lo[j] = lo[j].min(r[j]);
                hi[j] = hi[j].max(r[j]);
            }
        }
        let offset = (0..n).map(|j| 0.5 * (lo[j] + hi[j])).collect();
        let scale = (0..n)
            .map(|j| {
                let s = 0.5 * (hi[j] - lo[j]);
                if s > 0.0 && s.is_finite() {
                    s
                } else {
                    1.0
                }
            })
            .collect();
        Affine { offset, scale }
    }

    /// z-score of each column (mean 0, population std 1); a constant column gets scale 1.
    pub fn z_score(rows: &[Vec<f64>], n: usize) -> Affine {
        let m = rows.len().max(1) as f64;
        let offset: Vec<f64> = (0..n)
            .map(|j| rows.iter().map(|r| r[j]).sum::<f64>() / m)
            .collect();
        let scale = (0..n)
            .map(|j| {
                let v = rows.iter().map(|r| (r[j] - offset[j]).powi(2)).sum::<f64>() / m;
                let s = v.sqrt();
                if s > 0.0 && s.is_finite() {
                    s
                } else {
                    1.0
                }
            })
            .collect();
        Affine { offset, scale }
    }

    pub fn forward(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.offset.iter().zip(&self.scale))
            .map(|(v, (o, s))| (v - o) / s)
            .collect()
    }

    pub fn inverse(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.offset.iter().zip(&self.scale))
            .map(|(v, (o, s))| o + s * v)
            .collect()
    }
}

/// A trained one-hidden-layer network with its normalisation; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Bpnn {
    pub format: String,
    pub activation: Activation,
    pub input_names: Vec<String>,
    pub output_names: Vec<String>,
    pub input_offset: Vec<f64>,
    pub input_scale: Vec<f64>,
    pub output_offset: Vec<f64>,
    pub output_scale: Vec<f64>,
    /// Hidden-layer weights, one row per hidden unit.
    pub w1: Vec<Vec<f64>>,
    pub b1: Vec<f64>,
    /// Output-layer weights, one row per output.
    pub w2: Vec<Vec<f64>>,
    pub b2: Vec<f64>,
    #[serde(default)]
    pub provenance: serde_json::Value,
}

impl Bpnn {
    /// A network with the given shape and normalisation from a flattened parameter vector θ.
    pub fn from_params(
        n_in: usize,
        n_hidden: usize,
        n_out: usize,
        activation: Activation,
        input_norm: &Affine,
        output_norm: &Affine,
        theta: &[f64],
    ) -> Bpnn {
        let mut net = Bpnn {
            format: FORMAT.to_string(),
            activation,
            input_names: (0..n_in).map(|i| format!("x{i}")).collect(),
            output_names: (0..n_out).map(|i| format!("y{i}")).collect(),
            input_offset: input_norm.offset.clone(),
            input_scale: input_norm.scale.clone(),
            output_offset: output_norm.offset.clone(),
            output_scale: output_norm.scale.clone(),
            w1: vec![vec![0.0; n_in]; n_hidden],
            b1: vec![0.0; n_hidden],
            w2: vec![vec![0.0; n_hidden]; n_out],
            b2: vec![0.0; n_out],
            provenance: serde_json::Value::Null,
        };
        net.set_params(theta);
        net
    }

    pub fn n_in(&self) -> usize {
        self.input_offset.len()
    }
    pub fn n_hidden(&self) -> usize {
        self.b1.len()
    }
    pub fn n_out(&self) -> usize {
        self.b2.len()
    }

    /// Number of trainable parameters: hidden·(in+1) + out·(hidden+1).
    pub fn param_count(&self) -> usize {
        param_count(self.n_in(), self.n_hidden(), self.n_out())
    }

    /// The flattened parameter vector θ (layout in the module docs).
    pub fn params(&self) -> Vec<f64> {
        let mut t = Vec::with_capacity(self.param_count());
        for r in &self.w1 {
            t.extend_from_slice(r);
        }
        t.extend_from_slice(&self.b1);
        for r in &self.w2 {
            t.extend_from_slice(r);
        }
        t.extend_from_slice(&self.b2);
        t
    }

    /// Sets the weights from θ (length must be `param_count()`).
    pub fn set_params(&mut self, theta: &[f64]) {
        let (n_in, n_h, n_out) = (self.n_in(), self.n_hidden(), self.n_out());
        let mut k = 0;
        for h in 0..n_h {
            self.w1[h].copy_from_slice(&theta[k..k + n_in]);
            k += n_in;
        }
        self.b1.copy_from_slice(&theta[k..k + n_h]);
        k += n_h;
        for o in 0..n_out {
            self.w2[o].copy_from_slice(&theta[k..k + n_h]);
            k += n_h;
        }
        self.b2.copy_from_slice(&theta[k..k + n_out]);
    }

    /// Network output in normalised units for a normalised input (used by the trainers).
    pub fn forward_normalised(&self, xn: &[f64], hidden: &mut [f64], yn: &mut [f64]) {
        for (h, (row, b)) in self.w1.iter().zip(&self.b1).enumerate() {
            let a = b + row.iter().zip(xn).map(|(w, x)| w * x).sum::<f64>();
            hidden[h] = self.activation.apply(a);
        }
        for (o, (row, b)) in self.w2.iter().zip(&self.b2).enumerate() {
            yn[o] = b + row
                .iter()
                .zip(hidden.iter())
                .map(|(w, s)| w * s)
                .sum::<f64>();
        }
    }

    /// Prediction in physical units for one input vector (length `n_in`, else an error).
    pub fn predict(&self, x: &[f64]) -> Result<Vec<f64>> {
        if x.len() != self.n_in() {
            return Err(BpnnError::Data(format!(
                "the network takes {} inputs, got {}",
                self.n_in(),
                x.len()
            )));
        }
        let mut out = vec![0.0; self.n_out()];
        self.predict_into(x, &mut out);
        Ok(out)
    }

    /// Prediction without allocation for nets of up to 8 inputs and 64 hidden units (otherwise
    /// one allocation); `x.len()` must be `n_in` and `out.len()` `n_out`.
    pub fn predict_into(&self, x: &[f64], out: &mut [f64]) {
        let n_h = self.n_hidden();
        let mut stack = [0.0f64; 64];
        let mut heap = Vec::new();
        let hidden: &mut [f64] = if n_h <= 64 {
            &mut stack[..n_h]
        } else {
            heap.resize(n_h, 0.0);
            &mut heap
        };
        // normalise the inputs once (n_in divisions), then the dot products
        let mut xn_stack = [0.0f64; 8];
        let mut xn_heap = Vec::new();
        let xn: &mut [f64] = if x.len() <= 8 {
            &mut xn_stack[..x.len()]
        } else {
            xn_heap.resize(x.len(), 0.0);
            &mut xn_heap
        };
        for (v, (xi, (o, s))) in xn.iter_mut().zip(
            x.iter()
                .zip(self.input_offset.iter().zip(&self.input_scale)),
        ) {
            *v = (xi - o) / s;
        }
        for (h, (row, b)) in self.w1.iter().zip(&self.b1).enumerate() {
            let a = b + row.iter().zip(xn.iter()).map(|(w, v)| w * v).sum::<f64>();
            hidden[h] = self.activation.apply(a);
        }
        for (o, (row, b)) in self.w2.iter().zip(&self.b2).enumerate() {
            let yn = b + row
                .iter()
                .zip(hidden.iter())
                .map(|(w, s)| w * s)
                .sum::<f64>();
            out[o] = self.output_offset[o] + self.output_scale[o] * yn;
        }
    }

    /// True for a volumetric map: inputs (x, y, z) in mm, outputs (ex, ey, ez) in µm.
    pub fn is_volumetric(&self) -> bool {
        self.n_in() == 3 && self.n_out() == 3
    }

    /// Volumetric error [ex, ey, ez] µm at `p_mm`, for a 3-input/3-output net (what
    /// `mtec map fit --model bpnn` writes). No allocation. A net of another shape is refused
    /// when loaded as a map ([`Bpnn::load_volumetric`]); called on one anyway, missing inputs
    /// are taken as 0 and missing outputs returned as 0, never a panic.
    #[inline]
    pub fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        if self.is_volumetric() {
            self.predict_into(&p_mm, &mut out);
        } else {
            let mut x = vec![0.0; self.n_in()];
            for (xi, p) in x.iter_mut().zip(p_mm) {
                *xi = p;
            }
            let mut y = vec![0.0; self.n_out()];
            self.predict_into(&x, &mut y);
            for (o, v) in out.iter_mut().zip(y) {
                *o = v;
            }
        }
        out
    }

    /// One line of provenance for compensation outputs.
    pub fn describe(&self) -> String {
        format!(
            "BPNN {}-{}-{} ({:?}, {} parameters, {})",
            self.n_in(),
            self.n_hidden(),
            self.n_out(),
            self.activation,
            self.param_count(),
            FORMAT
        )
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a Bpnn always serialises")
    }

    /// Parses and validates an `mtec.bpnn/1` document.
    pub fn from_json(text: &str) -> Result<Bpnn> {
        let net: Bpnn = serde_json::from_str(text).map_err(|e| {
            BpnnError::Model(format!("line {}, column {}: {e}", e.line(), e.column()))
        })?;
        net.validate()?;
        Ok(net)
    }

    /// Parses an `mtec.bpnn/1` document and requires a 3-input/3-output volumetric map.
    pub fn load_volumetric(text: &str) -> Result<Bpnn> {
        let net = Bpnn::from_json(text)?;
        if !net.is_volumetric() {
            return Err(BpnnError::Model(format!(
                "a volumetric map needs 3 inputs (x, y, z) and 3 outputs (ex, ey, ez); this network is {}-{}-{}",
                net.n_in(),
                net.n_hidden(),
                net.n_out()
            )));
        }
        Ok(net)
    }

    fn validate(&self) -> Result<()> {
        if self.format != FORMAT {
            return Err(BpnnError::Model(format!(
                "format is \"{}\", expected \"{FORMAT}\"",
                self.format
            )));
        }
        let (n_in, n_h, n_out) = (self.n_in(), self.n_hidden(), self.n_out());
        let bad = |what: &str| Err(BpnnError::Model(format!("{what} has the wrong shape")));
        if n_in == 0 || n_h == 0 || n_out == 0 {
            return Err(BpnnError::Model("empty layer".into()));
        }
        if self.input_scale.len() != n_in || self.input_names.len() != n_in {
            return bad("input_scale/input_names");
        }
        if self.output_offset.len() != n_out
            || self.output_scale.len() != n_out
            || self.output_names.len() != n_out
        {
            return bad("output_offset/output_scale/output_names");
        }
        if self.w1.len() != n_h || self.w1.iter().any(|r| r.len() != n_in) {
            return bad("w1");
        }
        if self.w2.len() != n_out || self.w2.iter().any(|r| r.len() != n_h) {
            return bad("w2");
        }
        let all_finite = self.params().iter().all(|v| v.is_finite())
            && self.input_offset.iter().all(|v| v.is_finite())
            && self.output_offset.iter().all(|v| v.is_finite())
            && self.input_scale.iter().all(|v| v.is_finite() && *v != 0.0)
            && self.output_scale.iter().all(|v| v.is_finite() && *v != 0.0);
        if !all_finite {
            return Err(BpnnError::Model(
                "a weight or normalisation value is not finite (or a scale is 0)".into(),
            ));
        }
        Ok(())
    }
}

impl ErrorModel for Bpnn {
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        Bpnn::error_um(self, p_mm)
    }
    fn describe(&self) -> String {
        Bpnn::describe(self)
    }
}

/// hidden·(in+1) + out·(hidden+1).
pub fn param_count(n_in: usize, n_hidden: usize, n_out: usize) -> usize {
    n_hidden * (n_in + 1) + n_out * (n_hidden + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> Bpnn {
        // 2-2-1 net worked by hand below.
        let inorm = Affine {
            offset: vec![1.0, 0.0],
            scale: vec![2.0, 1.0],
        };
        let onorm = Affine {
            offset: vec![10.0],
            scale: vec![3.0],
        };
        // w1 = [[1, -1], [0.5, 2]], b1 = [0, -1], w2 = [[2, -3]], b2 = [0.5]
        let theta = [1.0, -1.0, 0.5, 2.0, 0.0, -1.0, 2.0, -3.0, 0.5];
        Bpnn::from_params(2, 2, 1, Activation::Sigmoid, &inorm, &onorm, &theta)
    }

    #[test]
    fn forward_pass_matches_hand_computation() {
        let net = tiny();
        // x = (3, 0.5): xn = ((3-1)/2, 0.5) = (1, 0.5)
        // a1 = 1 - 0.5 = 0.5, a2 = 0.5 + 1 - 1 = 0.5; s = 1/(1+e^-0.5) = 0.622459331
        let s = 1.0 / (1.0 + (-0.5f64).exp());
        let yn = 0.5 + 2.0 * s - 3.0 * s;
        let y = net.predict(&[3.0, 0.5]).unwrap();
        assert!((y[0] - (10.0 + 3.0 * yn)).abs() < 1e-12);
        assert!((s - 0.622_459_331_201_854_6).abs() < 1e-12);
        assert_eq!(net.param_count(), 9);
        assert_eq!(param_count(3, 10, 3), 73);
    }

    #[test]
    fn params_round_trip_and_json_round_trip() {
        let net = tiny();
        let theta = net.params();
        assert_eq!(theta, vec![1.0, -1.0, 0.5, 2.0, 0.0, -1.0, 2.0, -3.0, 0.5]);
        let back = Bpnn::from_json(&net.to_json()).unwrap();
        assert_eq!(back, net);
    }

    #[test]
    fn bad_model_files_are_refused() {
        let net = tiny();
        let mut v: serde_json::Value = serde_json::from_str(&net.to_json()).unwrap();
        v["format"] = "mtec.bpnn/2".into();
        assert!(Bpnn::from_json(&v.to_string()).is_err());
        let mut v: serde_json::Value = serde_json::from_str(&net.to_json()).unwrap();
        v["w1"][0] = serde_json::json!([1.0]);
        assert!(Bpnn::from_json(&v.to_string()).is_err());
        assert!(Bpnn::from_json("{").is_err());
        assert!(Bpnn::load_volumetric(&net.to_json()).is_err());
        assert!(net.predict(&[1.0]).is_err());
    }
}
