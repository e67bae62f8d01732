//! Models written by hand, to check a rewriter or a controller path with a known answer:
//!
//! ```json
//! { "format": "mtec.zero-model/1" }
//! ```
//! a model with no error (a compensated program is then byte-identical to its input), and
//!
//! ```json
//! { "format": "mtec.poly-model/1",
//!   "description": "fitted on the 2026-03 laser run",
//!   "terms": [ { "powers": [0, 0, 0], "coef_um": [8.0, -4.0, 3.0] },
//!              { "powers": [1, 0, 0], "coef_um": [0.012, 0.0, 0.0] },
//!              { "powers": [0, 2, 0], "coef_um": [0.0, 0.0, 1.5e-5] } ] }
//! ```
//! a polynomial: E(x, y, z) = Σ coef_um · x^i · y^j · z^k with x, y, z the machine position in
//! mm and E = [Ex, Ey, Ez] in µm.

use crate::ErrorModel;
use mtec_io::InputError;
use serde::Deserialize;
use std::path::Path;

/// A model with no error (written by hand, to check the rewriter).
pub const ZERO_FORMAT: &str = "mtec.zero-model/1";
/// A polynomial model (written by hand).
pub const POLY_FORMAT: &str = "mtec.poly-model/1";

/// No error anywhere.
pub struct ZeroModel {
    source: String,
}

impl ZeroModel {
    /// A zero model described as loaded from `source`.
    pub fn new(source: impl Into<String>) -> Self {
        ZeroModel {
            source: source.into(),
        }
    }
}

impl ErrorModel for ZeroModel {
    fn error_um(&self, _p_mm: [f64; 3]) -> [f64; 3] {
        [0.0; 3]
    }
    fn describe(&self) -> String {
        format!("mtec.zero-model/1 from {}", self.source)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PolyFile {
    #[allow(dead_code)]
    format: String,
    #[serde(default)]
    description: Option<String>,
    terms: Vec<PolyTerm>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PolyTerm {
    powers: [u32; 3],
    coef_um: [f64; 3],
}

/// E(p) = Σ coef · x^i y^j z^k (µm, p in mm).
pub struct PolyModel {
    terms: Vec<PolyTerm>,
    describe: String,
}

impl PolyModel {
    pub(crate) fn new(file: PolyFile, path: &Path) -> Result<Self, InputError> {
        for (n, t) in file.terms.iter().enumerate() {
            if !t.coef_um.iter().all(|c| c.is_finite()) {
                return Err(InputError::file(
                    path,
                    format!("terms[{n}]: coef_um is not finite"),
                ));
            }
            if t.powers.iter().sum::<u32>() > 12 {
                return Err(InputError::file(
                    path,
                    format!("terms[{n}]: total degree above 12"),
                ));
            }
        }
        let describe = format!(
            "mtec.poly-model/1 from {} ({} terms){}",
            path.display(),
            file.terms.len(),
            file.description
                .map(|d| format!(": {d}"))
                .unwrap_or_default()
        );
        Ok(PolyModel {
            terms: file.terms,
            describe,
        })
    }
}

impl ErrorModel for PolyModel {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        let mut e = [0.0; 3];
        for t in &self.terms {
            let m = p[0].powi(t.powers[0] as i32)
                * p[1].powi(t.powers[1] as i32)
                * p[2].powi(t.powers[2] as i32);
            for (ei, ci) in e.iter_mut().zip(t.coef_um) {
                *ei += ci * m;
            }
        }
        e
    }
    fn describe(&self) -> String {
        self.describe.clone()
    }
}
