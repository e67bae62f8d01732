//! Writing CSV: the one path every CSV output of mtec is built on (issue 18).
//!
//! The fields arrive already formatted (each output keeps its own number formatting, e.g.
//! `{:.4}` for µm); the `csv` crate joins them, quoting only a field that needs it: one that
//! holds a comma, a quote, a line break or a `#` (which mtec's readers would otherwise take for
//! a comment at the start of a line). Lines end in `\n`. The text is returned whole, for the
//! caller to write through [`crate::write_output`] or an [`crate::Output`] (atomically).

/// A CSV text built row by row: optional `#` comment lines, a header, data rows.
///
/// ```
/// let mut w = mtec_io::CsvWriter::new(["x_mm", "note"]);
/// w.row([format!("{:.1}", 2.0), "a, b".to_string()]);
/// assert_eq!(w.finish(), "x_mm,note\n2.0,\"a, b\"\n");
/// ```
pub struct CsvWriter {
    w: csv::Writer<Vec<u8>>,
    columns: usize,
}

impl CsvWriter {
    /// A CSV text whose first line is `header`.
    pub fn new<I, S>(header: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: AsRef<str>,
    {
        Self::commented(std::iter::empty::<&str>(), header)
    }

    /// A CSV text that starts with the `comments` as `# ` lines (a line break in a comment
    /// becomes a space), then `header`.
    pub fn commented<C, T, I, S>(comments: C, header: I) -> Self
    where
        C: IntoIterator<Item = T>,
        T: AsRef<str>,
        I: IntoIterator<Item = S>,
        S: AsRef<str>,
    {
        let mut text = Vec::new();
        for c in comments {
            text.extend_from_slice(format!("# {}\n", c.as_ref().replace('\n', " ")).as_bytes());
        }
        let w = csv::WriterBuilder::new()
            .comment(Some(b'#'))
            // the field count is checked below (in debug builds): a row cannot fail to be written
            .flexible(true)
            .from_writer(text);
        let mut out = CsvWriter { w, columns: 0 };
        let header: Vec<S> = header.into_iter().collect();
        out.columns = header.len();
        out.record(&header);
        out
    }

    /// Appends one data row of formatted fields (as many as the header has).
    pub fn row<I, S>(&mut self, fields: I)
    where
        I: IntoIterator<Item = S>,
        S: AsRef<str>,
    {
        let fields: Vec<S> = fields.into_iter().collect();
        debug_assert_eq!(fields.len(), self.columns, "a CSV row of another width");
        self.record(&fields);
    }

    fn record<S: AsRef<str>>(&mut self, fields: &[S]) {
        // writing into memory with flexible rows cannot fail
        self.w
            .write_record(fields.iter().map(|f| f.as_ref().as_bytes()))
            .expect("CSV into memory");
    }

    /// The CSV text.
    pub fn finish(self) -> String {
        let bytes = self.w.into_inner().expect("CSV into memory");
        String::from_utf8(bytes).expect("CSV of UTF-8 fields is UTF-8")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_fields_are_joined_as_they_come() {
        let mut w = CsvWriter::new(["a", "b_um"]);
        w.row(["1", "-0.1250"]);
        w.row(["", "+"]);
        assert_eq!(w.finish(), "a,b_um\n1,-0.1250\n,+\n");
    }

    #[test]
    fn comments_come_first_on_one_line_each() {
        let w = CsvWriter::commented(["made by\na test", "radius_mm = 50"], ["x"]);
        assert_eq!(w.finish(), "# made by a test\n# radius_mm = 50\nx\n");
    }

    #[test]
    fn only_fields_that_need_it_are_quoted() {
        let mut w = CsvWriter::new(["name", "v"]);
        w.row(["T1,spindle", "say \"hi\""]);
        w.row(["#3", "a;b"]);
        assert_eq!(
            w.finish(),
            "name,v\n\"T1,spindle\",\"say \"\"hi\"\"\"\n\"#3\",a;b\n"
        );
    }

    #[test]
    fn what_it_writes_reads_back() {
        let mut w = CsvWriter::commented(["note"], ["name", "x_mm"]);
        w.row(["a, \"b\"", "1.5"]);
        let text = w.finish();
        let t = crate::Table::parse(std::path::Path::new("t.csv"), &text).unwrap();
        assert_eq!(t.comments, vec!["note".to_string()]);
        assert_eq!(t.rows[0].fields[0], "a, \"b\"");
    }
}
