//! The one CSV reading path: a streaming reader that yields the data rows of a file one at a
//! time, with their line numbers, and reports a bad line as soon as it is read.
//!
//! [`Table`](crate::Table) is this reader run to the end; a command that needs each row only once
//! (an ISO 230-2 run, the points of `map eval`) reads the file with [`CsvReader`] directly and
//! keeps only what it needs, so a 100 MB file costs its results, not 100 MB of strings.
//!
//! How: the file is read line by line (`BufRead::read_until`) by [`Lines`], which checks each
//! line is UTF-8, drops a byte-order mark, strips a CR before the LF, keeps `#` comment lines
//! (handing the CSV parser an empty line in their place, so line numbers stay those of the
//! file) and hands out at most one line per read. One `csv::Reader` per file splits the lines
//! into fields (RFC 4180 quotes); because it is fed one line at a time, after each record the
//! line counter of [`Lines`] is the record's line.

use crate::error::InputError;
use crate::fields::{check_header, decimal_comma, detect_dialect, Dialect, TableRow};
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// A record (one CSV row) may hold at most this many bytes of text: a `"` without its closing
/// quote would otherwise swallow the rest of the file into one field before anything is said.
pub const MAX_RECORD_BYTES: usize = 1 << 20;

/// The lines of a file, checked and cleaned, as a byte stream for the CSV parser.
struct Lines<R> {
    inner: R,
    path: PathBuf,
    /// Number (1-based) of the last line read from `inner`.
    line: usize,
    raw: Vec<u8>,
    /// Bytes for the parser not yet handed out: `pending[pos..]`.
    pending: Vec<u8>,
    pos: usize,
    eof: bool,
    comments: Vec<String>,
    /// The line (1-based) of each comment.
    comment_lines: Vec<usize>,
    /// Content bytes handed out since [`Lines::mark`] and the first content line after it.
    since_mark: usize,
    first_since_mark: Option<usize>,
}

impl<R: BufRead> Lines<R> {
    fn new(path: &Path, inner: R) -> Self {
        Lines {
            inner,
            path: path.to_path_buf(),
            line: 0,
            raw: Vec::new(),
            pending: Vec::new(),
            pos: 0,
            eof: false,
            comments: Vec::new(),
            comment_lines: Vec::new(),
            since_mark: 0,
            first_since_mark: None,
        }
    }

    /// Reads one line into `pending` (an empty line for a blank or comment line). Returns true
    /// for a line with content; at the end of the input `eof` is set.
    fn read_line(&mut self) -> Result<bool, InputError> {
        self.raw.clear();
        let n = self
            .inner
            .read_until(b'\n', &mut self.raw)
            .map_err(|e| InputError::file(&self.path, format!("cannot read: {e}")))?;
        if n == 0 {
            self.eof = true;
            return Ok(false);
        }
        self.line += 1;
        let mut bytes = self.raw.as_slice();
        bytes = bytes.strip_suffix(b"\n").unwrap_or(bytes);
        bytes = bytes.strip_suffix(b"\r").unwrap_or(bytes);
        let mut bom = 0;
        if self.line == 1 {
            if let Some(rest) = bytes.strip_prefix("\u{feff}".as_bytes()) {
                bom = bytes.len() - rest.len();
                bytes = rest;
            }
        }
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let valid = e.valid_up_to();
            InputError::at(
                &self.path,
                self.line,
                bom + valid + 1,
                format!("byte 0x{:02x} is not valid UTF-8 text", bytes[valid]),
            )
        })?;
        let trimmed = text.trim();
        if trimmed.is_empty() {
            self.pending.push(b'\n');
            return Ok(false);
        }
        if let Some(c) = trimmed.strip_prefix('#') {
            self.comments.push(c.trim().to_string());
            self.comment_lines.push(self.line);
            self.pending.push(b'\n');
            return Ok(false);
        }
        self.pending.extend_from_slice(bytes);
        self.pending.push(b'\n');
        self.since_mark += bytes.len() + 1;
        self.first_since_mark.get_or_insert(self.line);
        if self.since_mark > MAX_RECORD_BYTES {
            return Err(InputError::line(
                &self.path,
                self.first_since_mark.unwrap_or(self.line),
                format!(
                    "the row starting here runs on for more than {} MiB: a `\"` without its \
                     closing quote?",
                    MAX_RECORD_BYTES >> 20
                ),
            ));
        }
        Ok(true)
    }

    /// Reads up to the first line with content (the header), queued for the parser; `None` at
    /// the end of the input.
    fn first_content_line(&mut self) -> Result<Option<String>, InputError> {
        while !self.eof {
            let start = self.pending.len();
            if self.read_line()? {
                let line = &self.pending[start..self.pending.len() - 1];
                return Ok(Some(String::from_utf8_lossy(line).into_owned()));
            }
        }
        Ok(None)
    }

    /// A new record starts: its length is counted from here.
    fn mark(&mut self) {
        self.since_mark = 0;
        self.first_since_mark = None;
    }
}

impl<R: BufRead> Read for Lines<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.pos == self.pending.len() {
            self.pending.clear();
            self.pos = 0;
            if self.eof {
                return Ok(0);
            }
            self.read_line().map_err(io::Error::other)?;
            if self.pending.is_empty() {
                return Ok(0);
            }
        }
        let n = buf.len().min(self.pending.len() - self.pos);
        buf[..n].copy_from_slice(&self.pending[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// A CSV file read row by row: header checked when the reader is made, each data row checked
/// (width, quotes) when it is read, a bad line reported without reading further.
///
/// Same conventions, checks, messages and notes as [`Table`](crate::Table) (which is this
/// reader run to the end): `#` comment lines kept ([`CsvReader::comments`]), UTF-8 byte-order
/// mark and CRLF accepted, fields trimmed, spreadsheet exports (semicolons or tabs, decimal
/// commas, trailing empty columns) read with a note. A quoted field may not run past the end
/// of its line.
pub struct CsvReader<R> {
    rdr: csv::Reader<Lines<R>>,
    path: PathBuf,
    header: Vec<String>,
    header_line: usize,
    dialect: Dialect,
    notes: Vec<String>,
    decimal_commas: usize,
    record: csv::StringRecord,
    row: TableRow,
    rows: usize,
    done: bool,
    /// Split quote-free lines without the csv parser ([`CsvReader::read_plain_record`]); off
    /// only in the test that compares the two paths.
    plain_path: bool,
    /// The byte positions where the fields of a plain line end (reused).
    field_ends: Vec<usize>,
}

impl CsvReader<BufReader<File>> {
    /// Opens a file and reads its header.
    pub fn open(path: &Path) -> Result<Self, InputError> {
        let f =
            File::open(path).map_err(|e| InputError::file(path, format!("cannot read: {e}")))?;
        CsvReader::new(path, BufReader::with_capacity(1 << 16, f))
    }
}

impl<R: BufRead> CsvReader<R> {
    /// Reads the header of `input` (the text of `path`, which is used in messages only).
    pub fn new(path: &Path, input: R) -> Result<Self, InputError> {
        let mut lines = Lines::new(path, input);
        let Some(first) = lines.first_content_line()? else {
            return Err(InputError::file(
                path,
                "file is empty: expected a header row with column names",
            ));
        };
        let dialect = detect_dialect(&first);
        let delimiter = match dialect {
            Dialect::Comma => b',',
            Dialect::Spreadsheet(d) => d as u8,
        };
        let rdr = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .delimiter(delimiter)
            .terminator(csv::Terminator::Any(b'\n'))
            .from_reader(lines);
        let mut notes = Vec::new();
        if let Dialect::Spreadsheet(d) = dialect {
            notes.push(format!(
                "{}: read as a spreadsheet export: {} between fields, and numbers with a \
                 decimal comma read with a decimal point",
                path.display(),
                if d == ';' { "semicolons" } else { "tabs" }
            ));
        }
        let mut r = CsvReader {
            rdr,
            path: path.to_path_buf(),
            header: Vec::new(),
            header_line: 0,
            dialect,
            notes,
            decimal_commas: 0,
            record: csv::StringRecord::new(),
            row: TableRow {
                line: 0,
                fields: Vec::new(),
            },
            rows: 0,
            done: false,
            plain_path: true,
            field_ends: Vec::new(),
        };
        // `None` only if the csv crate dropped the whole line (a second byte-order mark)
        let Some(line_no) = r.read_record()? else {
            return Err(InputError::file(
                path,
                "file is empty: expected a header row with column names",
            ));
        };
        let mut fields = std::mem::take(&mut r.row.fields);
        let trailing = fields.iter().rev().take_while(|f| f.is_empty()).count();
        if trailing > 0 && trailing < fields.len() {
            fields.truncate(fields.len() - trailing);
            r.notes.push(format!(
                "{}:{line_no}: {trailing} empty column(s) at the end of the header ignored (a \
                 spreadsheet's trailing separators)",
                path.display()
            ));
        }
        check_header(path, line_no, &first, &fields)?;
        r.header = fields;
        r.header_line = line_no;
        Ok(r)
    }

    /// Reads the next record into `self.row.fields` (trimmed, decimal commas converted);
    /// returns its line, `None` at the end of the input.
    fn read_record(&mut self) -> Result<Option<usize>, InputError> {
        self.rdr.get_mut().mark();
        if self.rows > 0 && self.plain_path {
            if let Some(line) = self.read_plain_record()? {
                return Ok(line);
            }
        }
        match self.rdr.read_record(&mut self.record) {
            Ok(false) => return Ok(None),
            Ok(true) => {}
            Err(e) => return Err(self.csv_error(e)),
        }
        // fed one line per read, the parser has consumed exactly up to the record's last line
        let end = self.rdr.get_ref().line;
        if let Some(c) = self.record.iter().position(|f| f.contains('\n')) {
            let newlines: usize = self.record.iter().map(|f| f.matches('\n').count()).sum();
            return Err(InputError::at(
                &self.path,
                end - newlines,
                c + 1,
                "a quoted field runs past the end of the line (a `\"` without its closing \
                 quote?): a row must be on one line",
            ));
        }
        let n = self.record.len();
        let fields = &mut self.row.fields;
        fields.truncate(n);
        fields.resize_with(n, String::new);
        for (dst, f) in fields.iter_mut().zip(self.record.iter()) {
            let f = f.trim();
            put_field(self.dialect, &mut self.decimal_commas, dst, f);
        }
        self.row.line = end;
        Ok(Some(end))
    }

    /// The fast path of [`CsvReader::read_record`]: the next line with content, when it has no
    /// `"`, split at the delimiter here (what the csv parser makes of such a line, without its
    /// copies and checks). `Some(None)` at the end of the input; `None` when the line has a
    /// quote, left queued for the parser.
    ///
    /// Only between records: the parser has then consumed every byte handed to it (it is fed
    /// one line per read and a record ends with its line), so skipping it here loses nothing.
    fn read_plain_record(&mut self) -> Result<Option<Option<usize>>, InputError> {
        let lines = self.rdr.get_mut();
        if lines.pos != lines.pending.len() {
            return Ok(None);
        }
        lines.pending.clear();
        lines.pos = 0;
        loop {
            if lines.eof {
                return Ok(Some(None));
            }
            if lines.read_line()? {
                break;
            }
            // a blank or comment line: nothing for the parser
            lines.pending.clear();
        }
        let delimiter = match self.dialect {
            Dialect::Comma => b',',
            Dialect::Spreadsheet(d) => d as u8,
        };
        // where the fields end, in one pass that also looks for a quote
        let bytes = &lines.pending[..lines.pending.len() - 1];
        let ends = &mut self.field_ends;
        ends.clear();
        for (i, &b) in bytes.iter().enumerate() {
            if b == delimiter {
                ends.push(i);
            } else if b == b'"' {
                return Ok(None);
            }
        }
        ends.push(bytes.len());
        // the line is UTF-8 (checked by `read_line`) and the delimiter ASCII: every piece is
        // UTF-8 too, and the slicing below never splits a character
        let text = std::str::from_utf8(bytes).expect("checked by read_line");
        let fields = &mut self.row.fields;
        fields.truncate(ends.len());
        fields.resize_with(ends.len(), String::new);
        let mut start = 0;
        for (dst, &end) in fields.iter_mut().zip(ends.iter()) {
            let f = text[start..end].trim();
            start = end + 1;
            put_field(self.dialect, &mut self.decimal_commas, dst, f);
        }
        let end = lines.line;
        lines.pos = lines.pending.len();
        self.row.line = end;
        Ok(Some(Some(end)))
    }

    fn csv_error(&self, e: csv::Error) -> InputError {
        let line = self.rdr.get_ref().line;
        match e.into_kind() {
            csv::ErrorKind::Io(io) => match io.into_inner().map(|b| b.downcast::<InputError>()) {
                Some(Ok(e)) => *e,
                Some(Err(other)) => InputError::file(&self.path, format!("cannot read: {other}")),
                None => InputError::file(&self.path, "cannot read"),
            },
            other => InputError::line(
                &self.path,
                line,
                format!("cannot split the line into fields: {other:?}"),
            ),
        }
    }

    /// The next data row, `None` after the last one. Errors: a row whose width differs from
    /// the header's, a quote left open, a file with no data row at all.
    pub fn next_row(&mut self) -> Result<Option<Row<'_>>, InputError> {
        if self.done {
            return Ok(None);
        }
        let Some(line_no) = self.read_record()? else {
            self.done = true;
            if self.rows == 0 {
                return Err(InputError::line(
                    &self.path,
                    self.header_line,
                    "header only: the file has no data rows",
                ));
            }
            if self.decimal_commas == 0 {
                if let Some(n) = self.notes.iter_mut().find(|n| n.contains("decimal comma")) {
                    *n = n.replace(
                        ", and numbers with a decimal comma read with a decimal point",
                        "",
                    );
                }
            }
            crate::notes::record(&self.notes);
            return Ok(None);
        };
        let h = self.header.len();
        let fields = &mut self.row.fields;
        // the header's dropped trailing columns: empty in every row too
        while fields.len() > h && fields.last().is_some_and(|f| f.is_empty()) {
            fields.pop();
        }
        if fields.len() != h {
            let col = fields.len().min(h) + 1;
            return Err(InputError::at(
                &self.path,
                line_no,
                col,
                format!(
                    "row has {} fields but the header has {h} columns",
                    fields.len()
                ),
            ));
        }
        self.rows += 1;
        Ok(Some(Row {
            path: &self.path,
            header: &self.header,
            row: &self.row,
        }))
    }

    /// The file's path (as given).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The column names.
    pub fn header(&self) -> &[String] {
        &self.header
    }

    /// The line of the header.
    pub fn header_line(&self) -> usize {
        self.header_line
    }

    /// The comment lines read so far (the text after `#`, trimmed); all of them once
    /// [`CsvReader::next_row`] has returned `None`.
    pub fn comments(&self) -> &[String] {
        &self.rdr.get_ref().comments
    }

    /// The line (1-based) of each comment in [`CsvReader::comments`].
    pub fn comment_lines(&self) -> &[usize] {
        &self.rdr.get_ref().comment_lines
    }

    /// What the reader assumed about the file (a spreadsheet dialect); final once
    /// [`CsvReader::next_row`] has returned `None` (when they are also recorded for the
    /// command to print, see [`crate::notes`]).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Index of a column, or an error that says what is there instead (see
    /// [`Table::column`](crate::Table::column)).
    pub fn column(&self, name: &str) -> Result<usize, InputError> {
        crate::fields::column_index(&self.path, &self.header, self.header_line, name)
    }

    /// Checks that all named columns are present (first missing one reported).
    pub fn require(&self, names: &[&str]) -> Result<(), InputError> {
        for n in names {
            self.column(n)?;
        }
        Ok(())
    }

    /// True when the header has this exact column.
    pub fn has(&self, name: &str) -> bool {
        self.header.iter().any(|h| h == name)
    }
}

/// One data row of a file with typed, located access to its fields.
#[derive(Debug, Clone, Copy)]
pub struct Row<'a> {
    pub(crate) path: &'a Path,
    pub(crate) header: &'a [String],
    pub(crate) row: &'a TableRow,
}

impl<'a> Row<'a> {
    /// The line of the file (1-based).
    pub fn line(&self) -> usize {
        self.row.line
    }

    /// The fields (trimmed, as many as the header has columns).
    pub fn fields(&self) -> &'a [String] {
        &self.row.fields
    }

    /// The text in column `c`.
    pub fn str(&self, c: usize) -> &'a str {
        &self.row.fields[c]
    }

    /// The row as owned data.
    pub fn to_table_row(&self) -> TableRow {
        self.row.clone()
    }

    /// The finite number in column `c`, or an error located at this line and column.
    pub fn f64(&self, c: usize) -> Result<f64, InputError> {
        let s = self.str(c);
        let name = &self.header[c];
        let at = |m: String| InputError::at(self.path, self.row.line, c + 1, m);
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(at(format!("`{name}` is `{s}`: not a finite number"))),
            Err(_) if s.is_empty() => Err(at(format!("`{name}` is empty"))),
            Err(_) => Err(at(format!("`{name}` is `{s}`: not a number"))),
        }
    }

    /// The whole number in column `c` (a run or experiment number), or a located error.
    pub fn i64(&self, c: usize) -> Result<i64, InputError> {
        let s = self.str(c);
        s.parse::<i64>().map_err(|_| {
            InputError::at(
                self.path,
                self.row.line,
                c + 1,
                format!("`{}` is `{s}`: not a whole number", self.header[c]),
            )
        })
    }

    /// A located error about this row, column named `name` (or the row alone if the column is
    /// absent).
    pub fn error_at(&self, name: &str, message: impl Into<String>) -> InputError {
        match self.header.iter().position(|h| h == name) {
            Some(c) => InputError::at(self.path, self.row.line, c + 1, message),
            None => InputError::line(self.path, self.row.line, message),
        }
    }
}

/// A trimmed field into `dst`, a decimal comma made a point in a spreadsheet dialect (counted
/// in `decimal_commas`): the one rule of both the csv-parser and the quote-free paths.
fn put_field(dialect: Dialect, decimal_commas: &mut usize, dst: &mut String, f: &str) {
    dst.clear();
    match dialect {
        Dialect::Spreadsheet(_) => match decimal_comma(f) {
            Some(v) => {
                *decimal_commas += 1;
                dst.push_str(&v);
            }
            None => dst.push_str(f),
        },
        Dialect::Comma => dst.push_str(f),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Everything a reader makes of a text: each row (line and fields) or the error, then the
    /// notes.
    fn transcript(text: &str, plain_path: bool) -> Vec<String> {
        let path = Path::new("t.csv");
        let mut out = Vec::new();
        let mut r = match CsvReader::new(path, text.as_bytes()) {
            Ok(r) => r,
            Err(e) => return vec![e.to_string()],
        };
        r.plain_path = plain_path;
        loop {
            match r.next_row() {
                Ok(Some(row)) => out.push(format!("{}: {:?}", row.line(), row.fields())),
                Ok(None) => break,
                Err(e) => {
                    out.push(e.to_string());
                    break;
                }
            }
        }
        out.extend(r.notes().iter().cloned());
        out.extend(r.comments().iter().cloned());
        out
    }

    /// The fast path for lines without quotes gives exactly what the csv parser gives: rows,
    /// line numbers, errors and notes, on random texts of numbers, separators of both dialects,
    /// quotes (also open ones), blank and comment lines, CRLF and spaces.
    #[test]
    fn plain_lines_split_as_the_csv_parser_splits_them() {
        let pieces = [
            "x_mm", "y_mm", "1.5", "-2", "3,25", " 4 ", "", ",", ",", ",", ";", "\t", "\"",
            "\"a,b\"", "\n", "\n", "\r\n", "# note\n", "\n\n", "1e3", "NaN", " ",
        ];
        let mut x = 0x9E3779B97F4A7C15u64;
        let mut next = |m: usize| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % m as u64) as usize
        };
        for _ in 0..3000 {
            let header = [
                "x_mm,y_mm,z_mm\n",
                "x_mm;y_mm;z_mm\n",
                "x_mm\ty_mm\n",
                "a,b,\n",
            ];
            let mut text = header[next(header.len())].to_string();
            for _ in 0..next(60) {
                text.push_str(pieces[next(pieces.len())]);
            }
            assert_eq!(
                transcript(&text, true),
                transcript(&text, false),
                "{text:?}"
            );
        }
    }
}
