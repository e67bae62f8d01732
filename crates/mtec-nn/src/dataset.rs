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
    pub fn is_empty(&self) -> bool {
        self.features.is_empty()
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

    /// Train/test split by whole experiments; the two id sets must not overlap.
    pub fn split(&self, train: &[u32], test: &[u32]) -> Result<(ThermalDataset, ThermalDataset)> {
        if let Some(id) = train.iter().find(|id| test.contains(id)) {
            return Err(NnError::Config(format!(
                "experiment {id} is both in the training and the test set"
            )));
        }
        if train.is_empty() || test.is_empty() {
            return Err(NnError::Config(
                "both the training and the test set need an experiment".into(),
            ));
        }
        Ok((self.select(train)?, self.select(test)?))
    }

    /// The same data with the first `n` features (the temperatures) as rises over each
    /// sequence's first row. Thermal errors are defined against the state of the static
    /// (t = 0) measurement, so a rise is what they depend on; absolute temperatures also carry
    /// the room's level, which differs from one experiment to the next (an experiment that
    /// starts colder than every training one lies outside their range).
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

    /// Each scored row's first-row targets, in the order of [`ThermalDataset::rows`]: what
    /// turns predictions on [`ThermalDataset::target_changes`] back into targets.
    pub fn first_targets(&self) -> Vec<Vec<f64>> {
        let mut out = Vec::new();
        for seq in self.experiments.iter().flat_map(|e| &e.sequences) {
            for _ in seq.scored_rows() {
                out.push(seq.targets[0].clone());
            }
        }
        out
    }

    /// The same data with the first `n` features (the sensors) also `1..=lags` rows earlier:
    /// row t becomes [x₁…xₙ(t), x₁…xₙ(t − 1), …, x₁…xₙ(t − lags), the other features(t)],
    /// named `<sensor>_lag<l>`. Rows before a sequence's start take its first row, as the
    /// CNN-LSTM's windows do (the campaigns start after hours switched off). This is how a
    /// static network (the BPNN) sees history: the lagged linear model's φ(t) as inputs.
    pub fn lagged(&self, n: usize, lags: usize) -> ThermalDataset {
        let n = n.min(self.feature_names.len());
        let mut names: Vec<String> = self.feature_names[..n].to_vec();
        for l in 1..=lags {
            names.extend(
                self.feature_names[..n]
                    .iter()
                    .map(|s| format!("{s}_lag{l}")),
            );
        }
        names.extend_from_slice(&self.feature_names[n..]);
        let mut out = self.clone();
        out.feature_names = names;
        for seq in out.experiments.iter_mut().flat_map(|e| &mut e.sequences) {
            let x = std::mem::take(&mut seq.features);
            seq.features = (0..x.len())
                .map(|t| {
                    let mut row: Vec<f64> = Vec::with_capacity(x[t].len() + n * lags);
                    for l in 0..=lags {
                        row.extend_from_slice(&x[t.saturating_sub(l)][..n]);
                    }
                    row.extend_from_slice(&x[t][n..]);
                    row
                })
                .collect();
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
    fn split_by_experiment() {
        let d = ds();
        d.validate().unwrap();
        let (tr, te) = d.split(&[1, 2, 4], &[3]).unwrap();
        assert_eq!(
            tr.experiments.iter().map(|e| e.id).collect::<Vec<_>>(),
            vec![1, 2, 4]
        );
        assert_eq!(te.experiments[0].id, 3);
        assert_eq!(tr.scored_rows(), 6);
        assert_eq!(te.rows().0, vec![vec![3.0, 2.0], vec![3.0, 3.0]]);
        assert!(d.split(&[1, 3], &[3]).is_err());
        assert!(d.split(&[1, 9], &[3]).is_err());
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
    fn lagged_sensors_by_hand() {
        // one sequence: sensors (a, b), then an angle column
        let mut d = ds();
        d.feature_names = vec!["a".into(), "b".into(), "angle".into()];
        for seq in d.experiments.iter_mut().flat_map(|e| &mut e.sequences) {
            seq.features = vec![
                vec![1.0, 10.0, 0.5],
                vec![2.0, 20.0, 0.6],
                vec![4.0, 40.0, 0.7],
            ];
        }
        let l = d.lagged(2, 2);
        assert_eq!(
            l.feature_names,
            ["a", "b", "a_lag1", "b_lag1", "a_lag2", "b_lag2", "angle"]
        );
        // rows before the start repeat row 0; the angle stays the current row's
        assert_eq!(
            l.experiments[0].sequences[0].features,
            vec![
                vec![1.0, 10.0, 1.0, 10.0, 1.0, 10.0, 0.5],
                vec![2.0, 20.0, 1.0, 10.0, 1.0, 10.0, 0.6],
                vec![4.0, 40.0, 2.0, 20.0, 1.0, 10.0, 0.7],
            ]
        );
        assert_eq!(
            l.experiments[0].sequences[0].targets,
            d.experiments[0].sequences[0].targets
        );
        l.validate().unwrap();
        // lags 0 is the data itself; rises of every lagged sensor are over the first row
        assert_eq!(d.lagged(2, 0), d);
        let r = l.rises(6);
        assert_eq!(
            r.experiments[0].sequences[0].features[2],
            vec![3.0, 30.0, 1.0, 10.0, 0.0, 0.0, 0.7]
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
        // the first targets of the scored rows (1 and 2) undo it
        let first = d2.select(&[1]).unwrap().first_targets();
        assert_eq!(first, vec![vec![5.0], vec![5.0]]);
        let (_, y) = c.select(&[1]).unwrap().rows();
        let back: Vec<f64> = y.iter().zip(&first).map(|(a, b)| a[0] + b[0]).collect();
        assert_eq!(back, vec![7.0, 4.0]);
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
