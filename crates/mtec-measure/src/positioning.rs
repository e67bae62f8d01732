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

use mtec_io::{CsvReader, InputError, Row, Table};
use std::collections::BTreeMap;
use std::io::BufRead;
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
pub const MAX_DEVIATION_UM: f64 = mtec_io::plausible::MAX_ERROR_UM;
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

    /// Reads and validates a run file, streaming: the rows are checked as they are read (a bad
    /// line stops the reading there) and only the deviations are kept, as numbers.
    pub fn read(path: &Path) -> Result<PositioningData, InputError> {
        Self::from_reader(CsvReader::open(path)?)
    }

    /// Reads and validates the rows of a streaming CSV reader (see the module docs for the
    /// rules).
    pub fn from_reader<R: BufRead>(mut r: CsvReader<R>) -> Result<PositioningData, InputError> {
        let mut c = Collector::new(|n| r.column(n))?;
        while let Some(row) = r.next_row()? {
            c.add(&row)?;
        }
        c.finish(r.path())
    }

    /// Validates a parsed table (see the module docs for the rules).
    pub fn from_table(table: &Table) -> Result<PositioningData, InputError> {
        let mut c = Collector::new(|n| table.column(n))?;
        for row in &table.rows {
            c.add(&table.view(row))?;
        }
        c.finish(&table.path)
    }
}

/// The deviations of one pass (a run in one direction), indexed by target number (the order in
/// which targets first appear in the file); NaN where the pass has no value yet.
struct Pass {
    dev_um: Vec<f64>,
    line: Vec<usize>,
    first_line: usize,
}

/// The run file's rows, checked one at a time and kept as numbers.
struct Collector {
    /// Columns target_mm, run, direction, deviation_um.
    cols: [usize; 4],
    /// Target key -> (target number, value in mm as first written).
    targets: BTreeMap<i64, (usize, f64)>,
    /// (direction, run) -> index into `passes`.
    pass_index: BTreeMap<(Approach, i64), usize>,
    passes: Vec<Pass>,
    /// The pass of the previous row (rows come pass by pass: the map is searched only when the
    /// pass changes).
    last: Option<((Approach, i64), usize)>,
}

impl Collector {
    fn new(column: impl Fn(&str) -> Result<usize, InputError>) -> Result<Collector, InputError> {
        let mut cols = [0; 4];
        for (c, name) in cols
            .iter_mut()
            .zip(["target_mm", "run", "direction", "deviation_um"])
        {
            *c = column(name)?;
        }
        Ok(Collector {
            cols,
            targets: BTreeMap::new(),
            pass_index: BTreeMap::new(),
            passes: Vec::new(),
            last: None,
        })
    }

    fn add(&mut self, row: &Row) -> Result<(), InputError> {
        let [ct, cr, cd, cx] = self.cols;
        let target = row.f64(ct)?;
        let run = row.i64(cr)?;
        let dir = match row.str(cd) {
            "+" => Approach::Up,
            "-" => Approach::Down,
            other => {
                return Err(row.error_at(
                    "direction",
                    format!("direction is `{other}`: expected `+` (approach in the positive direction) or `-`"),
                ))
            }
        };
        let dev = row.f64(cx)?;
        // A deviation of a metre or more is not a positioning error but a unit or export
        // mistake (e.g. nm or raw counts); the statistics would overflow to inf.
        if dev.abs() >= MAX_DEVIATION_UM {
            return Err(row.error_at(
                "deviation_um",
                format!(
                    "deviation {dev:e} um is implausible (|deviation| must be below 1e6 um = 1 m): check the unit"
                ),
            ));
        }
        let n_targets = self.targets.len();
        let (i, _) = *self
            .targets
            .entry(target_key(target))
            .or_insert((n_targets, target));
        let k = match self.last {
            Some((key, k)) if key == (dir, run) => k,
            _ => {
                let n = self.passes.len();
                let k = *self.pass_index.entry((dir, run)).or_insert(n);
                if k == n {
                    self.passes.push(Pass {
                        dev_um: Vec::new(),
                        line: Vec::new(),
                        first_line: row.line(),
                    });
                }
                self.last = Some(((dir, run), k));
                k
            }
        };
        let pass = &mut self.passes[k];
        if i >= pass.dev_um.len() {
            pass.dev_um.resize(i + 1, f64::NAN);
            pass.line.resize(i + 1, 0);
        }
        if !pass.dev_um[i].is_nan() {
            return Err(row.error_at(
                "target_mm",
                format!(
                    "target {target} mm appears twice in run {run} direction `{}` (first on line {})",
                    row.str(cd),
                    pass.line[i]
                ),
            ));
        }
        pass.dev_um[i] = dev;
        pass.line[i] = row.line();
        Ok(())
    }

    fn finish(self, path: &Path) -> Result<PositioningData, InputError> {
        let Collector {
            targets,
            pass_index,
            passes,
            ..
        } = self;
        if targets.len() < 2 {
            return Err(InputError::file(
                path,
                format!(
                    "only {} target position(s): ISO 230-2 statistics need at least 2 (the standard asks for 5 or more)",
                    targets.len()
                ),
            ));
        }
        // Every pass must visit every target (checked in ascending target order).
        for ((dir, run), &k) in &pass_index {
            let pass = &passes[k];
            if let Some((_, &(_, t))) = targets
                .iter()
                .find(|(_, (i, _))| pass.dev_um.get(*i).is_none_or(|x| x.is_nan()))
            {
                return Err(InputError::line(
                    path,
                    pass.first_line,
                    format!(
                        "run {run} direction `{}` has no deviation for target {t} mm: every run must visit every target",
                        if *dir == Approach::Up { "+" } else { "-" },
                    ),
                ));
            }
        }
        let runs_of = |d: Approach| -> Vec<i64> {
            pass_index
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
                    path,
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
        if targets.len() < 5 {
            warnings.push(format!(
                "only {} targets: ISO 230-2 asks for at least 5 (and 5 per metre of travel)",
                targets.len()
            ));
        }
        // the lines were for messages; free them before the matrices are built
        let mut passes = passes;
        for p in &mut passes {
            p.line = Vec::new();
        }
        let matrix = |d: Approach, runs: &[i64]| -> Vec<Vec<f64>> {
            targets
                .values()
                .map(|&(i, _)| {
                    runs.iter()
                        .map(|r| passes[pass_index[&(d, *r)]].dev_um[i])
                        .collect()
                })
                .collect()
        };
        Ok(PositioningData {
            targets_mm: targets.values().map(|&(_, t)| t).collect(),
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

    /// Streaming and whole-table reading give the same data; a spreadsheet export with
    /// comments, BOM and CRLF too.
    #[test]
    fn streaming_reads_what_the_table_reads() {
        let want = parse(OK).unwrap();
        let stream = |text: &str| {
            PositioningData::from_reader(CsvReader::new(Path::new("run.csv"), text.as_bytes())?)
        };
        assert_eq!(stream(OK).unwrap(), want);
        let export = format!(
            "\u{feff}# laser run\r\n{}",
            OK.replace(',', ";").replace('\n', "\r\n# note\r\n")
        );
        assert_eq!(stream(&export).unwrap(), want);
        assert_eq!(parse(&export).unwrap(), want);
    }

    /// An input that fails the test if read past `limit` bytes.
    struct Tripwire(std::io::Cursor<Vec<u8>>, u64);
    impl std::io::Read for Tripwire {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            assert!(self.0.position() < self.1, "read past byte {}", self.1);
            self.0.read(buf)
        }
    }

    /// A bad direction on line 3 of a 20 MB file is reported having read at most 16 KiB.
    #[test]
    fn a_bad_line_3_stops_the_reading() {
        let mut text = "target_mm,run,direction,deviation_um\n0,1,+,1\n10,1,up,2\n".to_string();
        text.push_str(&"20,1,+,3.25\n".repeat(20 << 20 >> 4));
        let input = std::io::BufReader::with_capacity(
            1024,
            Tripwire(std::io::Cursor::new(text.into_bytes()), 16 << 10),
        );
        let e = PositioningData::from_reader(CsvReader::new(Path::new("run.csv"), input).unwrap())
            .unwrap_err();
        assert_eq!((e.line, e.column), (Some(3), Some(3)), "{e}");
        assert!(e.message.contains("direction is `up`"), "{e}");
    }
}
