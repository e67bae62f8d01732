//! ISO 230-2 positioning runs: the file `target_mm,run,direction,deviation_um` read into a
//! validated table of deviations x_ij↑ and x_ij↓ (target i, run j).
//!
//! Decisions where SPEC §4 is silent:
//! - `direction` is `+` (approach in the positive direction, ↑) or `-` (↓).
//! - A *pass* is one (run, direction) pair. Every pass must visit every target exactly once;
//!   the runs of the two directions need not carry the same numbers.
//! - Targets are matched to 1 nm (values that differ by less are the same target).
//! - At least 2 targets and 2 passes per direction are required (a standard deviation needs two
//!   values); ISO 230-2 asks for 5 runs per direction and 5 targets per metre (at least 5): fewer
//!   gives a warning, not an error.

use mtec_io::{InputError, Table};
use std::collections::BTreeMap;
use std::path::Path;

/// Approach direction of a target (ISO 230-2 ↑ and ↓).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Approach {
    /// `+`: the target is approached moving in the positive direction (↑).
    Up,
    /// `-`: approached moving in the negative direction (↓).
    Down,
}

/// Validated bidirectional positioning measurements of one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct PositioningData {
    /// Target positions P_i, ascending (mm).
    pub targets_mm: Vec<f64>,
    /// `up_um[i][j]`: deviation x_ij↑ at target i in the j-th positive pass (µm).
    pub up_um: Vec<Vec<f64>>,
    /// `down_um[i][j]`: deviation x_ij↓ at target i in the j-th negative pass (µm).
    pub down_um: Vec<Vec<f64>>,
    /// Run numbers of the positive and negative passes, in the order of the columns above.
    pub runs_up: Vec<i64>,
    pub runs_down: Vec<i64>,
    /// Things the standard asks for that this data set does not meet (too few runs or targets).
    pub warnings: Vec<String>,
}

const TARGET_RESOLUTION_MM: f64 = 1e-6;

fn target_key(t: f64) -> i64 {
    (t / TARGET_RESOLUTION_MM).round() as i64
}

/// Largest accepted |deviation| (1 m): anything larger is a unit or export mistake.
pub const MAX_DEVIATION_UM: f64 = 1e6;
impl PositioningData {
    /// The same runs with every measured position scaled by `factor` (an environmental length
    /// correction, see [`crate::air`]): the measured position P_i + x_ij becomes
    /// factor · (P_i + x_ij), so the deviation becomes factor · (P_i + x_ij) − P_i. Positions are
    /// those of the file, i.e. the interferometer is taken to read 0 at target 0 mm.
    pub fn with_scaled_positions(&self, factor: f64) -> PositioningData {
        let scale = |devs: &Vec<Vec<f64>>| -> Vec<Vec<f64>> {
            devs.iter()
                .zip(&self.targets_mm)
                .map(|(row, &p_mm)| {
                    let p_um = p_mm * 1000.0;
                    row.iter().map(|&x| factor * (p_um + x) - p_um).collect()
                })
                .collect()
        };
        PositioningData {
            up_um: scale(&self.up_um),
            down_um: scale(&self.down_um),
            ..self.clone()
        }
    }

    /// Reads and validates a run file.
    pub fn read(path: &Path) -> Result<PositioningData, InputError> {
        let table = Table::read(path)?;
        Self::from_table(&table)
    }

    /// Validates a parsed table (see the module docs for the rules).
    pub fn from_table(table: &Table) -> Result<PositioningData, InputError> {
        table.require(&["target_mm", "run", "direction", "deviation_um"])?;
        let targets = table.f64_column("target_mm")?;
        let runs = table.i64_column("run")?;
        let dirs = table.str_column("direction")?;
        let devs = table.f64_column("deviation_um")?;

        // (direction, run) -> target key -> (deviation, line); first line of each pass kept.
        type Pass = BTreeMap<i64, (f64, usize)>;
        let mut passes: BTreeMap<(Approach, i64), Pass> = BTreeMap::new();
        let mut first_line: BTreeMap<(Approach, i64), usize> = BTreeMap::new();
        let mut target_values: BTreeMap<i64, f64> = BTreeMap::new();
        for (k, row) in table.rows.iter().enumerate() {
            let dir = match dirs[k].as_str() {
                "+" => Approach::Up,
                "-" => Approach::Down,
                other => {
                    return Err(table.error_at(
                        row,
                        "direction",
                        format!("direction is `{other}`: expected `+` (approach in the positive direction) or `-`"),
                    ))
                }
            };
            // A deviation of a metre or more is not a positioning error but a unit or export
            // mistake (e.g. nm or raw counts); the statistics would overflow to inf.
            if devs[k].abs() >= MAX_DEVIATION_UM {
                return Err(table.error_at(
                    row,
                    "deviation_um",
                    format!(
                        "deviation {:e} um is implausible (|deviation| must be below 1e6 um = 1 m): check the unit",
                        devs[k]
                    ),
                ));
            }
            let key = target_key(targets[k]);
            target_values.entry(key).or_insert(targets[k]);
            first_line.entry((dir, runs[k])).or_insert(row.line);
            let pass = passes.entry((dir, runs[k])).or_default();
            if let Some((_, prev)) = pass.get(&key) {
                return Err(table.error_at(
                    row,
                    "target_mm",
                    format!(
                        "target {} mm appears twice in run {} direction `{}` (first on line {prev})",
                        targets[k],
                        runs[k],
                        dirs[k]
                    ),
                ));
            }
            pass.insert(key, (devs[k], row.line));
        }

        let keys: Vec<i64> = target_values.keys().copied().collect();
        if keys.len() < 2 {
            return Err(InputError::file(
                &table.path,
                format!(
                    "only {} target position(s): ISO 230-2 statistics need at least 2 (the standard asks for 5 or more)",
                    keys.len()
                ),
            ));
        }
        // Every pass must visit every target.
        for ((dir, run), pass) in &passes {
            if let Some(missing) = keys.iter().find(|k| !pass.contains_key(k)) {
                return Err(InputError::line(
                    &table.path,
                    first_line[&(*dir, *run)],
                    format!(
                        "run {run} direction `{}` has no deviation for target {} mm: every run must visit every target",
                        if *dir == Approach::Up { "+" } else { "-" },
                        target_values[missing]
                    ),
                ));
            }
        }
        let runs_of = |d: Approach| -> Vec<i64> {
            passes
                .keys()
                .filter(|(dd, _)| *dd == d)
                .map(|(_, r)| *r)
                .collect()
        };
        let runs_up = runs_of(Approach::Up);
        let runs_down = runs_of(Approach::Down);
        for (runs, sign) in [(&runs_up, "+"), (&runs_down, "-")] {
            if runs.len() < 2 {
                return Err(InputError::file(
                    &table.path,
                    format!(
                        "{} run(s) in direction `{sign}`: each direction needs at least 2 runs for a standard deviation (ISO 230-2 asks for 5)",
                        runs.len()
                    ),
                ));
            }
        }
        let mut warnings = Vec::new();
        for (runs, sign) in [(&runs_up, "+"), (&runs_down, "-")] {
            if runs.len() < 5 {
                warnings.push(format!(
                    "only {} runs in direction `{sign}`: ISO 230-2 asks for 5",
                    runs.len()
                ));
            }
        }
        if keys.len() < 5 {
            warnings.push(format!(
                "only {} targets: ISO 230-2 asks for at least 5 (and 5 per metre of travel)",
                keys.len()
            ));
        }
        let matrix = |d: Approach, runs: &[i64]| -> Vec<Vec<f64>> {
            keys.iter()
                .map(|k| runs.iter().map(|r| passes[&(d, *r)][k].0).collect())
                .collect()
        };
        Ok(PositioningData {
            targets_mm: keys.iter().map(|k| target_values[k]).collect(),
            up_um: matrix(Approach::Up, &runs_up),
            down_um: matrix(Approach::Down, &runs_down),
            runs_up,
            runs_down,
            warnings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<PositioningData, InputError> {
        PositioningData::from_table(&Table::parse(Path::new("run.csv"), s)?)
    }

    const OK: &str = "target_mm,run,direction,deviation_um\n\
        0,1,+,1\n10,1,+,2\n10,1,-,3\n0,1,-,4\n\
        0,2,+,5\n10,2,+,6\n10,2,-,7\n0,2,-,8\n";

    #[test]
    fn reads_matrix_in_target_and_run_order() {
        let d = parse(OK).unwrap();
        assert_eq!(d.targets_mm, vec![0.0, 10.0]);
        assert_eq!(d.up_um, vec![vec![1.0, 5.0], vec![2.0, 6.0]]);
        assert_eq!(d.down_um, vec![vec![4.0, 8.0], vec![3.0, 7.0]]);
        assert_eq!(d.warnings.len(), 3, "{:?}", d.warnings);
    }

    #[test]
    fn scaled_positions_move_each_deviation_by_the_scaled_position() {
        // k = 1 + 10 ppm: at 10 mm (10 000 µm) a deviation x becomes k (10 000 + x) − 10 000,
        // i.e. x + 0.1 µm + 10 ppm of x; at 0 mm only the 10 ppm of x remains.
        let d = parse(OK).unwrap().with_scaled_positions(1.0 + 1e-5);
        assert!((d.up_um[1][0] - (2.0 + 0.1 + 2e-5)).abs() < 1e-9);
        assert!((d.down_um[1][1] - (7.0 + 0.1 + 7e-5)).abs() < 1e-9);
        assert!((d.up_um[0][1] - (5.0 + 5e-5)).abs() < 1e-12);
        assert_eq!(d.targets_mm, vec![0.0, 10.0]);
    }

    #[test]
    fn located_errors() {
        let bad_dir = OK.replace("10,2,-,7", "10,2,down,7");
        let e = parse(&bad_dir).unwrap_err();
        assert_eq!((e.line, e.column), (Some(8), Some(3)), "{e}");

        let dup = OK.replace("0,2,-,8", "10,2,-,8");
        let e = parse(&dup).unwrap_err();
        assert_eq!((e.line, e.column), (Some(9), Some(1)), "{e}");
        assert!(e.message.contains("line 8"), "{e}");

        let missing = "target_mm,run,direction,deviation_um\n0,1,+,1\n10,1,+,2\n0,1,-,4\n10,1,-,1\n0,2,+,1\n10,2,+,1\n0,2,-,1\n";
        let e = parse(missing).unwrap_err();
        assert_eq!(e.line, Some(8), "{e}");
        assert!(e.message.contains("target 10 mm"), "{e}");

        let one_run =
            "target_mm,run,direction,deviation_um\n0,1,+,1\n10,1,+,2\n0,1,-,4\n10,1,-,1\n";
        assert!(parse(one_run)
            .unwrap_err()
            .message
            .contains("at least 2 runs"));

        let nan = OK.replace("0,2,+,5", "0,2,+,NaN");
        let e = parse(&nan).unwrap_err();
        assert_eq!((e.line, e.column), (Some(6), Some(4)));

        // 1e300 um passed every check and came out as `inf` statistics
        let absurd = OK.replace("10,2,+,6", "10,2,+,1e300");
        let e = parse(&absurd).unwrap_err();
        assert_eq!((e.line, e.column), (Some(7), Some(4)), "{e}");
        assert!(e.message.contains("1e300 um is implausible"), "{e}");
        assert!(parse(&OK.replace("10,2,+,6", "10,2,+,-999999")).is_ok());
    }
}
