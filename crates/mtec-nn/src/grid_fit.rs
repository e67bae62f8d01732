//! Fitting a BPNN to a volumetric error grid (inputs x, y, z in mm; outputs ex, ey, ez in µm)
//! and reporting how well it fits: per-axis statistics of the fit error over every grid point
//! and the parameter count next to the number of values a grid table stores (3 per point: the
//! source's 73 parameters against 3993 values for 11³ points).

use crate::bpnn::Activation;
use crate::bpnn::Bpnn;
use crate::bpnn_train::{train_bpnn_monitored, BpnnTrainConfig, Optimizer, TrainReport};
use crate::error::{NnError, Result};
use crate::progress::{Monitor, Quiet};
use serde::Serialize;

/// How to fit the map.
#[derive(Debug, Clone)]
pub struct GridFitConfig {
    pub hidden: usize,
    pub activation: Activation,
    pub optimizer: Optimizer,
    pub max_epochs: usize,
    pub seed: u64,
}

impl Default for GridFitConfig {
    fn default() -> Self {
        GridFitConfig {
            hidden: 10,
            activation: Activation::Sigmoid,
            optimizer: Optimizer::LevenbergMarquardt,
            max_epochs: 500,
            seed: 42,
        }
    }
}

/// min, max, mean and (population) standard deviation of one axis's fit error, µm.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct AxisStats {
    pub min_um: f64,
    pub max_um: f64,
    pub mean_um: f64,
    pub std_um: f64,
    pub rms_um: f64,
}

impl AxisStats {
    pub fn of(values: &[f64]) -> AxisStats {
        let n = values.len().max(1) as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        AxisStats {
            min_um: values.iter().copied().fold(f64::INFINITY, f64::min),
            max_um: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            mean_um: mean,
            std_um: var.sqrt(),
            rms_um: (values.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
        }
    }
}

/// The fit's quality: fit error = model − grid value at every grid point, per axis.
#[derive(Debug, Clone, Serialize)]
pub struct GridFitReport {
    pub points: usize,
    /// Values a grid table stores: 3 per point.
    pub grid_values: usize,
    pub parameters: usize,
    pub fit_error_x: AxisStats,
    pub fit_error_y: AxisStats,
    pub fit_error_z: AxisStats,
    pub training: TrainReport,
}

/// Trains a 3-`hidden`-3 BPNN on the grid points (`p_mm` → `e_um`).
pub fn fit_grid(
    p_mm: &[[f64; 3]],
    e_um: &[[f64; 3]],
    config: &GridFitConfig,
) -> Result<(Bpnn, GridFitReport)> {
    fit_grid_monitored(p_mm, e_um, config, &mut Quiet)
}

/// [`fit_grid`] reporting every epoch to `monitor`, which may stop it.
pub fn fit_grid_monitored(
    p_mm: &[[f64; 3]],
    e_um: &[[f64; 3]],
    config: &GridFitConfig,
    monitor: &mut dyn Monitor,
) -> Result<(Bpnn, GridFitReport)> {
    if p_mm.len() != e_um.len() {
        return Err(NnError::Data(format!(
            "{} points but {} error rows",
            p_mm.len(),
            e_um.len()
        )));
    }
    if p_mm.len() < 8 {
        return Err(NnError::Data(format!(
            "a grid needs at least 8 points, got {}",
            p_mm.len()
        )));
    }
    let x: Vec<Vec<f64>> = p_mm.iter().map(|p| p.to_vec()).collect();
    let y: Vec<Vec<f64>> = e_um.iter().map(|e| e.to_vec()).collect();
    let train_config = BpnnTrainConfig {
        hidden: config.hidden,
        activation: config.activation,
        optimizer: config.optimizer,
        max_epochs: config.max_epochs,
        seed: config.seed,
        ..BpnnTrainConfig::default()
    };
    let (mut net, training) = train_bpnn_monitored(&x, &y, &train_config, monitor)?;
    net.input_names = ["x_mm", "y_mm", "z_mm"].map(String::from).to_vec();
    net.output_names = ["ex_um", "ey_um", "ez_um"].map(String::from).to_vec();
    let mut err = [Vec::new(), Vec::new(), Vec::new()];
    for (p, e) in p_mm.iter().zip(e_um) {
        let m = net.error_um(*p);
        for a in 0..3 {
            err[a].push(m[a] - e[a]);
        }
    }
    let report = GridFitReport {
        points: p_mm.len(),
        grid_values: 3 * p_mm.len(),
        parameters: net.param_count(),
        fit_error_x: AxisStats::of(&err[0]),
        fit_error_y: AxisStats::of(&err[1]),
        fit_error_z: AxisStats::of(&err[2]),
        training,
    };
    Ok((net, report))
}
