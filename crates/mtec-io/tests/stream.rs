//! The streaming CSV reader: same rows, lines, comments and notes as `Table` (worked by hand
//! here, not only compared), and a bad line reported before the rest of the file is read.

use mtec_io::{CsvReader, InputError, Table, MAX_RECORD_BYTES};
use std::io::{BufReader, Read};
use std::path::Path;

/// An input that fails the test if it is read past `limit` bytes: what comes after is not
/// supposed to be looked at.
struct Tripwire {
    data: Vec<u8>,
    pos: usize,
    limit: usize,
}

impl Read for Tripwire {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        assert!(
            self.pos < self.limit,
            "read past byte {} of {}",
            self.limit,
            self.data.len()
        );
        let n = buf.len().min(self.data.len() - self.pos);
        buf[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// Header, two good rows, a bad line 3 ... then `garbage` bytes; read through a 1 KiB buffer
/// that may not go past 16 KiB.
fn tripwire(head: &[u8], garbage: usize) -> BufReader<Tripwire> {
    let mut data = head.to_vec();
    data.extend(b"x,y\n".repeat(garbage / 4));
    BufReader::with_capacity(
        1024,
        Tripwire {
            data,
            pos: 0,
            limit: 16 << 10,
        },
    )
}

fn first_error<R: std::io::BufRead>(mut r: CsvReader<R>) -> InputError {
    loop {
        match r.next_row() {
            Ok(Some(row)) => {
                for c in 0..row.fields().len() {
                    if let Err(e) = row.f64(c) {
                        return e;
                    }
                }
            }
            Ok(None) => panic!("no error"),
            Err(e) => return e,
        }
    }
}

#[test]
fn a_bad_line_3_is_reported_before_the_rest_is_read() {
    // a value that is not a number on line 3, then 10 MB of garbage
    let input = tripwire(b"a_mm,b_um\n1,2\nthree,4\n", 10 << 20);
    let e = first_error(CsvReader::new(Path::new("t.csv"), input).unwrap());
    assert_eq!((e.line, e.column), (Some(3), Some(1)), "{e}");
    assert!(e.message.contains("`a_mm` is `three`: not a number"), "{e}");
    // a row too short on line 3
    let input = tripwire(b"a_mm,b_um\n1,2\n3\n", 10 << 20);
    let e = first_error(CsvReader::new(Path::new("t.csv"), input).unwrap());
    assert_eq!((e.line, e.column), (Some(3), Some(2)), "{e}");
    assert!(e.message.contains("row has 1 fields"), "{e}");
    // an invalid UTF-8 byte on line 3, column 3
    let input = tripwire(b"a_mm,b_um\n1,2\n3,\xff\n", 10 << 20);
    let e = first_error(CsvReader::new(Path::new("t.csv"), input).unwrap());
    assert_eq!((e.line, e.column), (Some(3), Some(3)), "{e}");
    assert!(e.message.contains("0xff is not valid UTF-8"), "{e}");
}

/// A German spreadsheet export with everything at once: BOM, CRLF, comments before, between
/// and after the rows, a blank line, semicolons, decimal commas, trailing separators.
const EXPORT: &str = "\u{feff}# radius_mm = 100\r\n# plane: xy\r\nx_mm;y_um;name;;\r\n\
    1,5;-2,25e-1;a,b;;\r\n\r\n# between\r\n3;4;c;;\r\n  # indented comment\r\n";

#[test]
fn streaming_gives_the_rows_table_gives_worked_by_hand() {
    let path = Path::new("export.csv");
    let mut r = CsvReader::new(path, EXPORT.as_bytes()).unwrap();
    assert_eq!(r.header(), ["x_mm", "y_um", "name"]);
    assert_eq!(r.header_line(), 3);
    let mut rows = Vec::new();
    while let Some(row) = r.next_row().unwrap() {
        rows.push((
            row.line(),
            row.f64(0).unwrap(),
            row.f64(1).unwrap(),
            row.str(2).to_string(),
        ));
    }
    // lines as in the file (two comment lines, then the header, a blank line and a comment)
    assert_eq!(
        rows,
        vec![
            (4, 1.5, -0.225, "a,b".to_string()),
            (7, 3.0, 4.0, "c".to_string())
        ]
    );
    assert_eq!(
        r.comments(),
        [
            "radius_mm = 100",
            "plane: xy",
            "between",
            "indented comment"
        ]
    );
    assert_eq!(r.notes().len(), 2, "{:?}", r.notes());
    assert!(r.notes()[0].contains("semicolons") && r.notes()[0].contains("decimal comma"));
    assert!(r.notes()[1].contains("export.csv:3: 2 empty column(s)"));

    // Table (text and file) holds the same
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("export.csv");
    std::fs::write(&file, EXPORT).unwrap();
    for t in [
        Table::parse(path, EXPORT).unwrap(),
        Table::read(&file).unwrap(),
    ] {
        assert_eq!(t.header, r.header());
        assert_eq!(t.header_line, 3);
        assert_eq!(t.comments, r.comments());
        assert_eq!(t.notes.len(), 2);
        let lines: Vec<usize> = t.rows.iter().map(|r| r.line).collect();
        assert_eq!(lines, [4, 7]);
        assert_eq!(t.f64_column("y_um").unwrap(), [-0.225, 4.0]);
        assert_eq!(t.str_column("name").unwrap(), ["a,b", "c"]);
    }
}

#[test]
fn quotes_that_do_not_close_on_their_line_are_located() {
    // a quoted field over two lines: reported at the line it starts on
    let e = Table::parse(Path::new("t.csv"), "a,b\n1,\"2\n3\"\n4,5\n").unwrap_err();
    assert_eq!((e.line, e.column), (Some(2), Some(2)), "{e}");
    assert!(e.message.contains("closing quote"), "{e}");
    // a quote left open on line 3 of a file with more than MAX_RECORD_BYTES after it: stopped
    // at the limit, not at the end of the file
    let mut text = String::from("a,b\n1,2\n\"3,4\n");
    let line = "5,6\n";
    let lines = 3 * MAX_RECORD_BYTES / line.len();
    text.push_str(&line.repeat(lines));
    let input = BufReader::new(Tripwire {
        data: text.into_bytes(),
        pos: 0,
        limit: 2 * MAX_RECORD_BYTES,
    });
    let mut r = CsvReader::new(Path::new("t.csv"), input).unwrap();
    assert!(r.next_row().unwrap().is_some());
    let e = r.next_row().unwrap_err();
    assert_eq!(e.line, Some(3), "{e}");
    assert!(e.message.contains("closing quote"), "{e}");
}

#[test]
fn quoted_fields_hold_separators_in_both_dialects() {
    let t = Table::parse(Path::new("t.csv"), "name;x_mm\n\"a;b\";1,5\n").unwrap();
    assert_eq!(t.rows[0].fields, ["a;b", "1.5"]);
    let t = Table::parse(Path::new("t.csv"), "name,x_mm\n\"a,\"\"b\"\"\",1.5\n").unwrap();
    assert_eq!(t.rows[0].fields, ["a,\"b\"", "1.5"]);
}
