//! The plain data a sequence model trains on: experiments × sequences × time × features, with
//! targets, and the split by experiment (`--train 1,2,4 --test 3`).
//!
//! A *sequence* is one time series of equally spaced rows: for the rotary ballbar case one
//! sequence per angle of one experiment (features = temperatures and the angle, constant along
//! the sequence; targets = the error motions at that angle over time), for a thermal log one
//! sequence per block. The first `warmup` rows of a sequence only serve as history for the
//! windows (their targets are neither trained on nor scored): this is how a held-out block of a
//! long record still sees the temperatures that preceded it.

use crate::error::{NnError, Result};
use mtec_thermal::ThermalData;
use nalgebra::DMatrix;

/// One time series: `features[t]` and `targets[t]` for t = 0..len.
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    pub features: Vec<Vec<f64>>,
    pub targets: Vec<Vec<f64>>,
    /// Leading rows used as history only.
    pub warmup: usize,
}

impl Sequence {
    pub fn len(&self) -> usize {
        self.features.len()
    }
    /// Rows whose targets count: `warmup..len`.
    pub fn scored_rows(&self) -> std::ops::Range<usize> {
        self.warmup.min(self.len())..self.len()
    }
}

/// One experiment (a measurement campaign under one duty cycle).
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    pub id: u32,
    pub sequences: Vec<Sequence>,
}

/// Named features and targets over a set of experiments.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalDataset {
    pub feature_names: Vec<String>,
    pub target_names: Vec<String>,
    pub experiments: Vec<Experiment>,
}

impl ThermalDataset {
    /// Checks widths, finiteness and that there is something to learn from.
    pub fn validate(&self) -> Result<()> {
        let (nf, nt) = (self.feature_names.len(), self.target_names.len());
        if nf == 0 || nt == 0 {
            return Err(NnError::Data(
                "a dataset needs at least one feature and one target".into(),
            ));
        }
        if self.experiments.is_empty() {
            return Err(NnError::Data("the dataset holds no experiment".into()));
        }
        for e in &self.experiments {
            for (s, seq) in e.sequences.iter().enumerate() {
                if seq.features.len() != seq.targets.len() {
                    return Err(NnError::Data(format!(
                        "experiment {} sequence {s}: {} feature rows but {} target rows",
                        e.id,
                        seq.features.len(),
                        seq.targets.len()
                    )));
                }
                for (t, (f, y)) in seq.features.iter().zip(&seq.targets).enumerate() {
                    if f.len() != nf || y.len() != nt {
                        return Err(NnError::Data(format!(
                            "experiment {} sequence {s} row {t}: expected {nf} features and {nt} targets",
                            e.id
                        )));
                    }
                    if f.iter().chain(y).any(|v| !v.is_finite()) {
                        return Err(NnError::Data(format!(
                            "experiment {} sequence {s} row {t}: non-finite value",
                            e.id
                        )));
                    }
                }
            }
        }
        if self.scored_rows() == 0 {
            return Err(NnError::Data("the dataset has no scored rows".into()));
        }
        Ok(())
    }

    /// Number of rows whose targets count.
    pub fn scored_rows(&self) -> usize {
        self.experiments
            .iter()
            .flat_map(|e| &e.sequences)
            .map(|s| s.scored_rows().len())
            .sum()
    }

    #[cfg(test)]
    /// The experiments with the given ids, in the order given; an unknown id is an error.
    pub fn select(&self, ids: &[u32]) -> Result<ThermalDataset> {
        let mut experiments = Vec::new();
        for id in ids {
            let e = self
                .experiments
                .iter()
                .find(|e| e.id == *id)
                .ok_or_else(|| {
                    let known: Vec<String> =
                        self.experiments.iter().map(|e| e.id.to_string()).collect();
                    NnError::Data(format!(
                        "no experiment {id} (the data holds {})",
                        known.join(", ")
                    ))
                })?;
            experiments.push(e.clone());
        }
        Ok(ThermalDataset {
            feature_names: self.feature_names.clone(),
            target_names: self.target_names.clone(),
            experiments,
        })
    }

    /// The same data with the first `n` features (the temperatures) as rises over each
    /// sequence's first row. Thermal errors are defined against the state of the static
    /// (t = 0) measurement, so a rise is what they depend on; absolute temperatures also carry
    /// the room's level, which differs from one experiment to the next (an experiment that
    /// starts colder than every training one lies outside their range).
    #[cfg(test)]
    pub fn rises(&self, n: usize) -> ThermalDataset {
        let mut out = self.clone();
        for seq in out.experiments.iter_mut().flat_map(|e| &mut e.sequences) {
            let Some(first) = seq.features.first().cloned() else {
                continue;
            };
            for row in &mut seq.features {
                for (v, v0) in row.iter_mut().zip(&first).take(n) {
                    *v -= v0;
                }
            }
        }
        out
    }

    /// The same data with every target as its change since the sequence's first row (the
    /// static measurement that starts an experiment): a model trained on it predicts the
    /// thermal change, and the motion is that first measurement plus the prediction.
    #[cfg(test)]
    pub fn target_changes(&self) -> ThermalDataset {
        let mut out = self.clone();
        for seq in out.experiments.iter_mut().flat_map(|e| &mut e.sequences) {
            let Some(first) = seq.targets.first().cloned() else {
                continue;
            };
            for row in &mut seq.targets {
                for (v, v0) in row.iter_mut().zip(&first) {
                    *v -= v0;
                }
            }
        }
        out
    }

    /// Where early stopping's hold-out starts in the scored rows of `seq` of experiment
    /// `experiment` (rows from it on are validation rows): with a validation experiment, all of
    /// that experiment's rows and none of the others'; without, the last `fraction` of every
    /// sequence (a block at the end of each series, never random rows).
    pub fn validation_start(
        experiment: u32,
        seq: &Sequence,
        fraction: f64,
        validation_experiment: Option<u32>,
    ) -> usize {
        let rows = seq.scored_rows();
        match validation_experiment {
            Some(v) if v == experiment => rows.start,
            Some(_) => rows.end,
            None => rows.end - ((rows.len() as f64) * fraction).round() as usize,
        }
    }

    /// Every row as mtec-thermal's `ThermalData`, in experiment, sequence, row order: the
    /// features as its columns (`sensor_names`), the targets as `target` and `more_targets`,
    /// the experiment id as its label, and `at(experiment, sequence, row)` giving each row's
    /// time (min) and its value of the sequence column `sequence` (e.g. the angle).
    pub(crate) fn to_thermal_data(
        &self,
        sequence: &str,
        at: &dyn Fn(u32, usize, usize) -> (f64, f64),
    ) -> ThermalData {
        let (mut experiment, mut time_min, mut seq_value) = (Vec::new(), Vec::new(), Vec::new());
        let (mut x, mut y): (Vec<&[f64]>, Vec<&[f64]>) = (Vec::new(), Vec::new());
        for e in &self.experiments {
            for (k, seq) in e.sequences.iter().enumerate() {
                for t in 0..seq.len() {
                    let (time, value) = at(e.id, k, t);
                    experiment.push(e.id.to_string());
                    time_min.push(time);
                    seq_value.push(value);
                    x.push(&seq.features[t]);
                    y.push(&seq.targets[t]);
                }
            }
        }
        let n = x.len();
        let mut targets = (self.target_names.iter().enumerate())
            .map(|(c, name)| (name.clone(), y.iter().map(|r| r[c]).collect::<Vec<_>>()));
        ThermalData {
            experiment,
            time_min,
            sensor_names: self.feature_names.clone(),
            temps_c: DMatrix::from_fn(n, self.feature_names.len(), |i, j| x[i][j]),
            ambient_c: None,
            position_mm: None,
            target: targets.next(),
            more_targets: targets.collect(),
            sequence: Some((sequence.to_string(), seq_value)),
            source: None,
            lines: (2..n + 2).collect(),
        }
    }

    /// Every row as CSV `experiment,sequence,step,<features>,<targets>` (sequence and step
    /// counted from 0): the exchange format of `bench/cnn_lstm.sh` with its PyTorch peer.
    pub fn to_csv(&self) -> String {
        let header = ["experiment", "sequence", "step"]
            .iter()
            .map(|s| s.to_string())
            .chain(self.feature_names.iter().cloned())
            .chain(self.target_names.iter().cloned());
        let mut w = mtec_io::CsvWriter::new(header);
        for e in &self.experiments {
            for (k, seq) in e.sequences.iter().enumerate() {
                for t in 0..seq.len() {
                    let ids = [e.id.to_string(), k.to_string(), t.to_string()];
                    let values = seq.features[t].iter().chain(&seq.targets[t]);
                    w.row(ids.into_iter().chain(values.map(|v| v.to_string())));
                }
            }
        }
        w.finish()
    }

    /// Scored rows flattened (features at time t → targets at t): the BPNN baseline's data.
    pub fn rows(&self) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let mut x = Vec::new();
        let mut y = Vec::new();
        for seq in self.experiments.iter().flat_map(|e| &e.sequences) {
            for t in seq.scored_rows() {
                x.push(seq.features[t].clone());
                y.push(seq.targets[t].clone());
            }
        }
        (x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ds() -> ThermalDataset {
        let seq = |v: f64| Sequence {
            features: vec![vec![v, 1.0], vec![v, 2.0], vec![v, 3.0]],
            targets: vec![vec![0.0], vec![1.0], vec![2.0]],
            warmup: 1,
        };
        ThermalDataset {
            feature_names: vec!["t1_c".into(), "angle_deg".into()],
            target_names: vec!["exc_um".into()],
            experiments: (1..=4)
                .map(|id| Experiment {
                    id,
                    sequences: vec![seq(id as f64)],
                })
                .collect(),
        }
    }

    #[test]
    fn rises_over_each_sequence_start() {
        let mut d = ds();
        d.experiments[0].sequences[0].features = vec![vec![20.5, 1.0], vec![21.0, 2.0]];
        d.experiments[0].sequences[0].targets = vec![vec![0.0], vec![1.0]];
        let r = d.rises(1);
        // the first feature minus its value at the sequence's first row; the second untouched
        assert_eq!(
            r.experiments[0].sequences[0].features,
            vec![vec![0.0, 1.0], vec![0.5, 2.0]]
        );
        assert_eq!(
            r.experiments[1].sequences[0].features,
            vec![vec![0.0, 1.0], vec![0.0, 2.0], vec![0.0, 3.0]]
        );
        assert_eq!(
            r.experiments[1].sequences[0].targets,
            d.experiments[1].sequences[0].targets
        );
    }

    #[test]
    fn target_changes_by_hand() {
        let d = ds(); // targets 0, 1, 2 in every sequence, warmup 1
        let mut d2 = d.clone();
        d2.experiments[0].sequences[0].targets = vec![vec![5.0], vec![7.0], vec![4.0]];
        let c = d2.target_changes();
        assert_eq!(
            c.experiments[0].sequences[0].targets,
            vec![vec![0.0], vec![2.0], vec![-1.0]]
        );
        assert_eq!(
            c.experiments[0].sequences[0].features,
            d2.experiments[0].sequences[0].features
        );
    }

    #[test]
    fn validation_rows_tail_or_whole_experiment() {
        let d = ds(); // 3 rows, warmup 1: scored rows 1..3
        let seq = &d.experiments[0].sequences[0];
        assert_eq!(ThermalDataset::validation_start(1, seq, 0.5, None), 2);
        assert_eq!(ThermalDataset::validation_start(1, seq, 0.0, None), 3);
        assert_eq!(ThermalDataset::validation_start(1, seq, 0.5, Some(1)), 1);
        assert_eq!(ThermalDataset::validation_start(1, seq, 0.5, Some(2)), 3);
    }

    #[test]
    fn csv_export_by_hand() {
        let mut d = ds();
        d.experiments.truncate(1);
        assert_eq!(
            d.to_csv(),
            "experiment,sequence,step,t1_c,angle_deg,exc_um\n1,0,0,1,1,0\n1,0,1,1,2,1\n1,0,2,1,3,2\n"
        );
    }

    #[test]
    fn inconsistent_data_is_refused() {
        let mut d = ds();
        d.experiments[1].sequences[0].features[2] = vec![1.0];
        assert!(d.validate().is_err());
        let mut d = ds();
        d.experiments[0].sequences[0].targets[0][0] = f64::NAN;
        assert!(d.validate().is_err());
    }
}
