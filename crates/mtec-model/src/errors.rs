//! A set of error functions, one per element: what identification produces and the volumetric
//! model consumes. JSON: `{"format": "mtec.errors/1", "elements": {"EXX": {...}, ...}}`.

use crate::element::ErrorElement;
use crate::function::{ErrorFunction, Temperatures};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The format tag of an error-set JSON file.
pub const ERRORS_FORMAT: &str = "mtec.errors/1";

/// Error functions by element. Elements that are absent are zero.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct ErrorSet {
    pub format: String,
    /// Free text: where the values come from (simulation truth, identification run, ...).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub source: String,
    pub elements: BTreeMap<ErrorElement, ErrorFunction>,
    /// Elements a measurement could not determine (reported by identification, never given numbers).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unidentifiable: Vec<String>,
}

/// Why an error set is unusable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ErrorSetError {
    #[error("format is `{0}`, expected `{ERRORS_FORMAT}`")]
    Format(String),
    #[error("element {0}: {1}")]
    Function(String, crate::function::FunctionError),
}

impl ErrorSet {
    /// An empty (all-zero) set.
    pub fn new(source: impl Into<String>) -> Self {
        ErrorSet {
            format: ERRORS_FORMAT.into(),
            source: source.into(),
            elements: BTreeMap::new(),
            unidentifiable: vec![],
        }
    }

    /// Sets one element's function.
    pub fn insert(&mut self, e: ErrorElement, f: ErrorFunction) {
        self.elements.insert(e, f);
    }

    /// The function of an element, if present.
    pub fn get(&self, e: &ErrorElement) -> Option<&ErrorFunction> {
        self.elements.get(e)
    }

    /// Value of an element at axis position q (0 when absent), in µm or µrad.
    pub fn value(&self, e: &ErrorElement, q: f64) -> f64 {
        self.elements.get(e).map_or(0.0, |f| f.value(q))
    }

    /// Value with temperatures.
    pub fn value_at(&self, e: &ErrorElement, q: f64, temps: &Temperatures) -> f64 {
        self.elements.get(e).map_or(0.0, |f| f.value_at(q, temps))
    }

    /// Checks the format tag and every function.
    pub fn validate(&self) -> Result<(), ErrorSetError> {
        if self.format != ERRORS_FORMAT {
            return Err(ErrorSetError::Format(self.format.clone()));
        }
        for (e, f) in &self.elements {
            f.validate()
                .map_err(|err| ErrorSetError::Function(e.name(), err))?;
        }
        Ok(())
    }

    /// The same set with every value multiplied by `s` (used to test the first-order model's
    /// quadratic convergence and to build zero models).
    pub fn scaled(&self, s: f64) -> ErrorSet {
        use crate::function::Shape;
        let mut out = self.clone();
        for f in out.elements.values_mut() {
            match &mut f.shape {
                Shape::Constant { value } => *value *= s,
                Shape::Polynomial { coeffs } => coeffs.iter_mut().for_each(|c| *c *= s),
                Shape::Fourier { a0, cos, sin } => {
                    *a0 *= s;
                    cos.iter_mut().chain(sin.iter_mut()).for_each(|c| *c *= s);
                }
                Shape::Table { values, .. } => values.iter_mut().for_each(|v| *v *= s),
            }
            if let Some(t) = &mut f.thermal {
                t.per_k *= s;
                t.per_k_per_mm *= s;
            }
        }
        out
    }
}
