//! The self-contained HTML report: sections of text, key–value tables, tables and inline SVG
//! figures. One file, no scripts, no network.

use std::fmt::Write;

/// Escapes text for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[derive(Debug, Clone)]
enum Block {
    Paragraph(String),
    Table {
        header: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    Figure {
        svg: String,
        caption: String,
    },
    Note(String),
    /// The overall verdict, as a banner.
    Verdict {
        verdict: Verdict,
        text: String,
    },
    /// Key figures against their tolerances.
    KeyFigures(Vec<KeyFigure>),
    /// Name–text rows, left-aligned.
    Facts(Vec<[String; 2]>),
}

/// A result judged against a tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Pass,
    Fail,
    /// No tolerance was given, so nothing is judged.
    NotJudged,
}

impl Verdict {
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "FAIL",
            Verdict::NotJudged => "not judged",
        }
    }
    fn class(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::NotJudged => "none",
        }
    }
}

/// One row of the summary: what was measured, its value and its tolerance, already formatted
/// with their units.
#[derive(Debug, Clone)]
pub struct KeyFigure {
    pub stage: String,
    pub quantity: String,
    pub value: String,
    pub tolerance: Option<String>,
    pub verdict: Verdict,
}

/// One section of the report.
#[derive(Debug, Clone)]
pub struct Section {
    pub title: String,
    blocks: Vec<Block>,
    /// The method and its source, printed as the section's footnote.
    source: Option<String>,
}

impl Section {
    pub fn new(title: impl Into<String>) -> Self {
        Section {
            title: title.into(),
            blocks: vec![],
            source: None,
        }
    }
    /// The method and its source (standard, paper, mtec's docs), the section's footnote.
    pub fn source(&mut self, t: impl Into<String>) -> &mut Self {
        self.source = Some(t.into());
        self
    }
    /// A paragraph of plain text.
    pub fn text(&mut self, t: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(t.into()));
        self
    }
    /// A highlighted note (warnings, what could not be identified).
    pub fn note(&mut self, t: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Note(t.into()));
        self
    }
    /// A table.
    pub fn table(&mut self, header: &[&str], rows: Vec<Vec<String>>) -> &mut Self {
        self.blocks.push(Block::Table {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows,
        });
        self
    }
    /// A figure (SVG text from [`crate::plot`]).
    pub fn figure(&mut self, svg: String, caption: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Figure {
            svg,
            caption: caption.into(),
        });
        self
    }
    /// The overall verdict as a banner.
    pub fn verdict(&mut self, verdict: Verdict, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Verdict {
            verdict,
            text: text.into(),
        });
        self
    }
    /// A table of (name, text) rows, left-aligned, without a header.
    pub fn facts(&mut self, rows: Vec<[String; 2]>) -> &mut Self {
        self.blocks.push(Block::Facts(rows));
        self
    }
    /// The key-figures table (stage, quantity, value, tolerance, verdict).
    pub fn key_figures(&mut self, rows: Vec<KeyFigure>) -> &mut Self {
        self.blocks.push(Block::KeyFigures(rows));
        self
    }
    /// Number of figures (the browser check counts them).
    pub fn figures(&self) -> usize {
        self.blocks
            .iter()
            .filter(|b| matches!(b, Block::Figure { .. }))
            .count()
    }
}

/// The whole report.
#[derive(Debug, Clone)]
pub struct Report {
    pub title: String,
    pub subtitle: String,
    pub sections: Vec<Section>,
}

const STYLE: &str = "body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}\
h1{margin-bottom:0}h2{border-bottom:2px solid #1f77b4;padding-bottom:.2em;margin-top:2em}.sub{color:#666}\
table{border-collapse:collapse;margin:1em 0;font-size:.92em}td,th{border:1px solid #ccc;padding:.25em .6em;text-align:right}\
th{background:#f0f4f8}td:first-child,th:first-child{text-align:left}figure{margin:1em 0}figcaption{color:#555;font-size:.9em}\
.note{background:#fff6e0;border-left:4px solid #f0a000;padding:.5em 1em}nav a{margin-right:1em}svg{max-width:100%;height:auto}\
td.pass{color:#1a7f37;font-weight:600}td.fail{color:#b42318;font-weight:700}td.none{color:#666}\
.verdict{font-size:1.25em;font-weight:700;padding:.6em 1em;border-radius:4px;margin:1em 0}.verdict.pass{background:#e6f4ea;color:#1a7f37}\
.verdict.fail{background:#fde8e7;color:#b42318}.verdict.none{background:#eef1f4;color:#333}\
td.hash{font-family:monospace;font-size:.85em;word-break:break-all;text-align:left}table{max-width:100%}td{overflow-wrap:break-word}\
table.key td{text-align:left}table.key td:nth-child(3){text-align:right}table.key td:nth-child(4){text-align:right;white-space:nowrap}\
table.wide{font-size:.8em}table.wide td,table.wide th{padding:.2em .35em}\
table.facts td{text-align:left}\
.source{color:#555;font-size:.85em;border-top:1px solid #ddd;padding-top:.4em;margin-top:1.5em}\
.print{float:right;font-size:.9em;padding:.3em .8em;cursor:pointer}\
@page{size:A4;margin:14mm}\
@media print{body{max-width:none;margin:0;padding:0;font-size:10.5pt}nav,.print{display:none}section{break-before:page}\
section:first-of-type{break-before:auto}figure,table,tr{break-inside:avoid}h2{break-after:avoid}a{color:inherit;text-decoration:none}}";

impl Report {
    pub fn new(title: impl Into<String>, subtitle: impl Into<String>) -> Self {
        Report {
            title: title.into(),
            subtitle: subtitle.into(),
            sections: vec![],
        }
    }

    /// Puts `section` before every other section (the summary, written last, is read first).
    pub fn insert_first(&mut self, section: Section) {
        self.sections.insert(0, section);
    }

    /// Adds a section and returns it for filling.
    pub fn section(&mut self, title: impl Into<String>) -> &mut Section {
        self.sections.push(Section::new(title));
        self.sections.last_mut().expect("just pushed")
    }

    /// The HTML text.
    pub fn to_html(&self) -> String {
        let mut h = String::new();
        let _ = write!(h, "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body>", escape(&self.title));
        let _ = write!(
            h,
            "<button class=\"print\" onclick=\"window.print()\" title=\"Print, or save as a paginated PDF\">Print / PDF</button><h1>{}</h1><p class=\"sub\">{}</p><nav>",
            escape(&self.title),
            escape(&self.subtitle)
        );
        for (i, s) in self.sections.iter().enumerate() {
            let _ = write!(h, "<a href=\"#s{i}\">{}</a>", escape(&s.title));
        }
        h.push_str("</nav>");
        for (i, s) in self.sections.iter().enumerate() {
            let _ = write!(h, "<section id=\"s{i}\"><h2>{}</h2>", escape(&s.title));
            for b in &s.blocks {
                match b {
                    Block::Paragraph(t) => {
                        let _ = write!(h, "<p>{}</p>", escape(t));
                    }
                    Block::Note(t) => {
                        let _ = write!(h, "<p class=\"note\">{}</p>", escape(t));
                    }
                    Block::Table { header, rows } => {
                        // many columns: a smaller font keeps the table within the page
                        h.push_str(if header.len() > 7 {
                            "<table class=\"wide\">"
                        } else {
                            "<table>"
                        });
                        // a table of key–value rows has no header worth a line
                        if header.iter().any(|c| !c.is_empty()) {
                            h.push_str("<tr>");
                            for c in header {
                                let _ = write!(h, "<th>{}</th>", escape(c));
                            }
                            h.push_str("</tr>");
                        }
                        for r in rows {
                            h.push_str("<tr>");
                            for c in r {
                                let _ = write!(h, "<td>{}</td>", escape(c));
                            }
                            h.push_str("</tr>");
                        }
                        h.push_str("</table>");
                    }
                    Block::Verdict { verdict, text } => {
                        let _ = write!(
                            h,
                            "<p class=\"verdict {}\">{}</p>",
                            verdict.class(),
                            escape(text)
                        );
                    }
                    Block::Facts(rows) => {
                        h.push_str("<table class=\"facts\">");
                        for [k, v] in rows {
                            let _ =
                                write!(h, "<tr><td>{}</td><td>{}</td></tr>", escape(k), escape(v));
                        }
                        h.push_str("</table>");
                    }
                    Block::KeyFigures(rows) => {
                        h.push_str("<table class=\"key\"><tr><th>stage</th><th>quantity</th><th>value</th><th>tolerance</th><th>verdict</th></tr>");
                        for r in rows {
                            let _ = write!(
                                h,
                                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"{}\">{}</td></tr>",
                                escape(&r.stage),
                                escape(&r.quantity),
                                escape(&r.value),
                                escape(r.tolerance.as_deref().unwrap_or("—")),
                                r.verdict.class(),
                                r.verdict.label()
                            );
                        }
                        h.push_str("</table>");
                    }
                    Block::Figure { svg, caption } => {
                        let _ = write!(
                            h,
                            "<figure class=\"plot\">{svg}<figcaption>{}</figcaption></figure>",
                            escape(caption)
                        );
                    }
                }
            }
            if let Some(src) = &s.source {
                let _ = write!(
                    h,
                    "<p class=\"source\">Method and source: {}</p>",
                    escape(src)
                );
            }
            h.push_str("</section>");
        }
        h.push_str("</body></html>\n");
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_is_self_contained_and_escaped() {
        let mut r = Report::new("mtec <report>", "test");
        r.section("A")
            .text("x < y")
            .table(&["k", "v"], vec![vec!["a".into(), "1".into()]])
            .figure("<svg></svg>".into(), "fig");
        let h = r.to_html();
        assert!(
            h.contains("mtec &lt;report&gt;")
                && h.contains("x &lt; y")
                && h.contains("<svg></svg>")
        );
        assert!(!h.contains("http://") && !h.contains("https://") && !h.contains("<script"));
    }
}
