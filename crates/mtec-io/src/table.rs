//! A CSV table with a header row, `#` comment lines, and typed, located column access.

use crate::error::InputError;
use crate::fields::column_index;
pub use crate::fields::TableRow;
use crate::stream::{CsvReader, Row};
use std::path::{Path, PathBuf};

/// A CSV file read whole: header, data rows with their line numbers, and the comment lines.
///
/// Conventions: comma-separated, first non-comment line is the header, lines starting with `#`
/// are comments (kept in [`Table::comments`], e.g. a circular test's radius), a UTF-8
/// byte-order mark and CRLF line ends are accepted (spreadsheet exports), fields are trimmed.
///
/// Spreadsheet exports are read too, each with a note in [`Table::notes`] (the command prints
/// it): a header with semicolons (or tabs) and no comma makes the file semicolon- (tab-)
/// separated, the export of a German or French spreadsheet, and then a number written with a
/// decimal comma (`-1,25`, `3,5e-3`) is read with a decimal point; empty columns at the end of
/// every line (a spreadsheet's trailing separators) are dropped.
#[derive(Debug, Clone)]
pub struct Table {
    pub path: PathBuf,
    pub header: Vec<String>,
    pub header_line: usize,
    pub rows: Vec<TableRow>,
    pub comments: Vec<String>,
    /// The line (1-based) of each comment in [`Table::comments`].
    pub comment_lines: Vec<usize>,
    /// What the reader assumed about the file (a spreadsheet dialect), for the user.
    pub notes: Vec<String>,
}

impl Table {
    /// Reads and checks the file's shape: header present, no duplicated column, every row as wide
    /// as the header, at least one data row.
    pub fn read(path: &Path) -> Result<Table, InputError> {
        Table::collect(CsvReader::open(path)?)
    }

    /// Parses CSV text that was read from `path` (the path is used in messages only).
    pub fn parse(path: &Path, text: &str) -> Result<Table, InputError> {
        Table::collect(CsvReader::new(path, text.as_bytes())?)
    }

    /// Every row of a streaming reader: the one CSV reading path, run to the end.
    fn collect<R: std::io::BufRead>(mut r: CsvReader<R>) -> Result<Table, InputError> {
        let mut rows = Vec::new();
        while let Some(row) = r.next_row()? {
            rows.push(row.to_table_row());
        }
        Ok(Table {
            path: r.path().to_path_buf(),
            header: r.header().to_vec(),
            header_line: r.header_line(),
            rows,
            comments: r.comments().to_vec(),
            comment_lines: r.comment_lines().to_vec(),
            notes: r.notes().to_vec(),
        })
    }

    /// The typed, located view of one of this table's rows.
    pub fn view<'a>(&'a self, row: &'a TableRow) -> Row<'a> {
        Row {
            path: &self.path,
            header: &self.header,
            row,
        }
    }

    /// Index of a column, or an error that says what is there instead (including a column with
    /// the same name but another unit suffix, the most common mistake).
    pub fn column(&self, name: &str) -> Result<usize, InputError> {
        column_index(&self.path, &self.header, self.header_line, name)
    }

    /// True when the header has this exact column.
    pub fn has(&self, name: &str) -> bool {
        self.header.iter().any(|h| h == name)
    }

    /// Checks that all named columns are present (first missing one reported).
    pub fn require(&self, names: &[&str]) -> Result<(), InputError> {
        for n in names {
            self.column(n)?;
        }
        Ok(())
    }

    /// A column of finite numbers. Non-numeric cells, NaN and infinities are errors located at
    /// their line and column.
    pub fn f64_column(&self, name: &str) -> Result<Vec<f64>, InputError> {
        let c = self.column(name)?;
        self.rows.iter().map(|r| self.cell_f64(r, c)).collect()
    }

    /// The number in row `row`, column index `c`, or a located error.
    pub fn cell_f64(&self, row: &TableRow, c: usize) -> Result<f64, InputError> {
        self.view(row).f64(c)
    }

    /// The number in row `row`, column `c`, with |value| below `limit` (`crate::plausible`), or
    /// a located error naming the bound.
    pub fn cell_f64_within(
        &self,
        row: &TableRow,
        c: usize,
        limit: f64,
        unit: &str,
    ) -> Result<f64, InputError> {
        let v = self.cell_f64(row, c)?;
        crate::plausible::within(&self.header[c], v, limit, unit)
            .map_err(|m| InputError::at(&self.path, row.line, c + 1, m))
    }

    /// A column of text cells.
    pub fn str_column(&self, name: &str) -> Result<Vec<String>, InputError> {
        let c = self.column(name)?;
        Ok(self.rows.iter().map(|r| r.fields[c].clone()).collect())
    }

    /// A column of integers (e.g. run or experiment numbers).
    pub fn i64_column(&self, name: &str) -> Result<Vec<i64>, InputError> {
        let c = self.column(name)?;
        self.rows.iter().map(|r| self.view(r).i64(c)).collect()
    }

    /// Names of the columns that end with `suffix` (e.g. every `_c` temperature column).
    pub fn columns_with_suffix(&self, suffix: &str) -> Vec<String> {
        self.header
            .iter()
            .filter(|h| h.ends_with(suffix))
            .cloned()
            .collect()
    }

    /// A located error about row `row`, column named `name` (or the row alone if the column is absent).
    pub fn error_at(&self, row: &TableRow, name: &str, message: impl Into<String>) -> InputError {
        self.view(row).error_at(name, message)
    }

    /// The `key = value` or `key: value` pairs found in the comment lines (e.g. `# radius_mm = 100`).
    pub fn comment_value(&self, key: &str) -> Option<String> {
        self.comment_value_at(key).map(|(_, v)| v)
    }

    /// Like [`Table::comment_value`], with the comment's line (1-based; 0 when the table was
    /// not read from text).
    pub fn comment_value_at(&self, key: &str) -> Option<(usize, String)> {
        self.comments.iter().enumerate().find_map(|(i, c)| {
            let (k, v) = c.split_once('=').or_else(|| c.split_once(':'))?;
            (k.trim() == key).then(|| {
                (
                    self.comment_lines.get(i).copied().unwrap_or(0),
                    v.trim().to_string(),
                )
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Table, InputError> {
        Table::parse(Path::new("t.csv"), s)
    }

    #[test]
    fn reads_comments_header_rows_and_crlf() {
        let t = parse("# radius_mm = 100\r\nx_mm,y_um\r\n1,2\r\n\r\n3,4\r\n").unwrap();
        assert_eq!(t.header, vec!["x_mm", "y_um"]);
        assert_eq!(t.f64_column("y_um").unwrap(), vec![2.0, 4.0]);
        assert_eq!(t.rows[1].line, 5);
        assert_eq!(t.comment_value("radius_mm").as_deref(), Some("100"));
        let t = parse("# a\n\n# plane: ZX\nx_mm\n1\n").unwrap();
        assert_eq!(t.comment_value_at("plane"), Some((3, "ZX".to_string())));
        assert_eq!(t.comment_value_at("radius_mm"), None);
    }

    #[test]
    fn nan_and_text_are_located() {
        let t = parse("a_mm,b_um\n1,2\n3,NaN\n").unwrap();
        let e = t.f64_column("b_um").unwrap_err();
        assert_eq!((e.line, e.column), (Some(3), Some(2)));
        let t = parse("a_mm,b_um\n1,x\n").unwrap();
        assert!(t
            .f64_column("b_um")
            .unwrap_err()
            .to_string()
            .contains("t.csv:2:2"));
    }

    #[test]
    fn wrong_unit_suffix_is_named() {
        let t = parse("x_in,y_um\n1,2\n").unwrap();
        let e = t.column("x_mm").unwrap_err();
        assert!(e.message.contains("x_in"), "{e}");
        assert_eq!(e.column, Some(1));
    }

    /// Each line is split as the csv crate splits that line alone (RFC 4180 quotes), with
    /// the fields trimmed.
    #[test]
    fn lines_split_as_the_csv_crate_splits_them() {
        let lines = [
            "1,2,3",
            " a , b ,c ",
            ",,",
            "x,,",
            "1.5e3,-0, 7 ",
            "\"a,b\",c",
            "\"q\"\"x\",1",
        ];
        for line in lines {
            let mut rdr = csv::ReaderBuilder::new()
                .has_headers(false)
                .flexible(true)
                .from_reader(line.as_bytes());
            let mut rec = csv::StringRecord::new();
            rdr.read_record(&mut rec).unwrap();
            let want: Vec<String> = rec.iter().map(|f| f.trim().to_string()).collect();
            let header: Vec<String> = (0..want.len()).map(|i| format!("c{i}")).collect();
            let t = parse(&format!("{}\n{line}\n", header.join(","))).unwrap();
            assert_eq!(t.rows[0].fields, want, "{line}");
        }
    }

    /// A German spreadsheet export: semicolons, decimal commas, trailing separators, CRLF.
    #[test]
    fn spreadsheet_exports_are_read_with_a_note() {
        let t = parse("x_mm;y_um;name;;\r\n1,5;-2,25e-1;a,b;;\r\n3;4;c;;\r\n").unwrap();
        assert_eq!(t.header, vec!["x_mm", "y_um", "name"]);
        assert_eq!(t.f64_column("x_mm").unwrap(), vec![1.5, 3.0]);
        assert_eq!(t.f64_column("y_um").unwrap(), vec![-0.225, 4.0]);
        // text that is not a number keeps its comma
        assert_eq!(t.str_column("name").unwrap(), vec!["a,b", "c"]);
        assert_eq!(t.notes.len(), 2, "{:?}", t.notes);
        assert!(t.notes[0].contains("semicolons") && t.notes[0].contains("decimal comma"));
        assert!(t.notes[1].contains("2 empty column(s)"));
        // tabs, no decimal commas: the note does not claim any
        let t = parse("a_mm\tb_mm\n1.5\t2\n").unwrap();
        assert_eq!(t.f64_column("a_mm").unwrap(), vec![1.5]);
        assert!(t.notes[0].contains("tabs") && !t.notes[0].contains("decimal comma"));
        // a comma file with Excel's trailing commas
        let t = parse("a_mm,b_mm,,\n1,2,,\n").unwrap();
        assert_eq!((t.header.len(), t.rows[0].fields.len()), (2, 2));
        // a value under a dropped trailing column is still an error
        let e = parse("a_mm;b_mm;\n1;2;3\n").unwrap_err();
        assert_eq!(e.line, Some(2));
        // a plain comma file has no notes
        assert!(parse("a_mm,b_mm\n1,2\n").unwrap().notes.is_empty());
        // a decimal comma with a thousands point is not guessed at
        let t = parse("a_mm;b\n1.234,5;x\n").unwrap();
        assert!(t.f64_column("a_mm").is_err());
    }

    #[test]
    fn shape_errors() {
        assert!(parse("").unwrap_err().message.contains("empty"));
        assert!(parse("a_mm\n").unwrap_err().message.contains("header only"));
        assert_eq!(parse("a_mm,b_mm\n1\n").unwrap_err().line, Some(2));
        assert!(parse("a_mm|b_mm\n1|2\n")
            .unwrap_err()
            .message
            .contains("bars"));
        assert_eq!(parse("a_mm,a_mm\n1,2\n").unwrap_err().column, Some(2));
    }
}
