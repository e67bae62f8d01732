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
}

/// One section of the report.
#[derive(Debug, Clone)]
pub struct Section {
    pub title: String,
    blocks: Vec<Block>,
}

impl Section {
    pub fn new(title: impl Into<String>) -> Self {
        Section {
            title: title.into(),
            blocks: vec![],
        }
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
.note{background:#fff6e0;border-left:4px solid #f0a000;padding:.5em 1em}nav a{margin-right:1em}svg{max-width:100%;height:auto}";

impl Report {
    pub fn new(title: impl Into<String>, subtitle: impl Into<String>) -> Self {
        Report {
            title: title.into(),
            subtitle: subtitle.into(),
            sections: vec![],
        }
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
            "<h1>{}</h1><p class=\"sub\">{}</p><nav>",
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
                        h.push_str("<table><tr>");
                        for c in header {
                            let _ = write!(h, "<th>{}</th>", escape(c));
                        }
                        h.push_str("</tr>");
                        for r in rows {
                            h.push_str("<tr>");
                            for c in r {
                                let _ = write!(h, "<td>{}</td>", escape(c));
                            }
                            h.push_str("</tr>");
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
