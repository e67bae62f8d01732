//! The report checked as a person would see it (issue 23): `mtec demo`'s report and the
//! fl-thermal example's are opened in headless Chromium, which must find no script error, no
//! empty plot, no text over a plot's data, nothing wider than its box or the page; the demo's
//! report is printed to PDF (A4, several pages, real text). Screenshots of the summary and of
//! every section, and the PDF, are left in the test's output folder (the paths are printed).
//! The tables must show no raw field names and no unexpanded arrays (read from the HTML).
//!
//! Chromium and poppler-utils come from Debian's packages (.ci/run installs them); without them
//! the test is skipped on a developer machine and fails in CI.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

fn mtec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mtec"))
}

/// Chromium, or None (skip) on a developer machine without it; CI must have it.
fn browser() -> Option<PathBuf> {
    support::tool_on_path(
        &["chromium", "chromium-browser", "google-chrome"],
        "chromium",
        "the report's browser check skipped",
    )
}

/// Headless Chromium with `args`, bounded in time; returns stdout.
fn chromium(b: &Path, args: &[&str]) -> String {
    let out = Command::new("timeout")
        .arg("120")
        .arg(b)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--no-first-run",
            "--disable-dev-shm-usage",
        ])
        .args(args)
        .output()
        .expect("run chromium");
    assert!(
        out.status.success(),
        "chromium {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn url(f: &Path) -> String {
    format!("file://{}", f.display())
}

/// The report with `head` inserted first in its <head>.
fn with_head(html: &str, head: &str) -> String {
    html.replacen("<head>", &format!("<head>{head}"), 1)
}

/// Opens the report with the checks of report_check.js and returns (figures, problems).
fn browser_check(b: &Path, report: &Path, dir: &Path) -> (usize, Vec<String>) {
    let html = std::fs::read_to_string(report).unwrap();
    let js = include_str!("report_check.js");
    let checked = dir.join("checked.html");
    std::fs::write(
        &checked,
        with_head(&html, &format!("<script>{js}</script>")),
    )
    .unwrap();
    let dom = chromium(
        b,
        &[
            "--window-size=1200,1600",
            "--virtual-time-budget=10000",
            "--dump-dom",
            &url(&checked),
        ],
    );
    // the last one: the script's own text names the element too
    let start = dom
        .rfind("<pre id=\"mtec-check\">")
        .expect("the check script ran (no <pre id=mtec-check> in the page)");
    let rest = &dom[start + "<pre id=\"mtec-check\">".len()..];
    let text = &rest[..rest.find("</pre>").unwrap()];
    let text = text
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    let v: serde_json::Value = serde_json::from_str(&text).expect("check JSON");
    let mut problems: Vec<String> = v["problems"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap().to_string())
        .collect();
    for e in v["errors"].as_array().unwrap() {
        problems.push(format!("script error: {e}"));
    }
    (v["figures"].as_u64().unwrap() as usize, problems)
}

/// Screenshots of the summary (the top of the page) and of every section alone.
fn screenshots(b: &Path, report: &Path, dir: &Path) -> Vec<PathBuf> {
    let html = std::fs::read_to_string(report).unwrap();
    let sections = html.matches("<section id=\"s").count();
    let mut shots = Vec::new();
    let top = dir.join("summary.png");
    chromium(
        b,
        &[
            "--window-size=1200,1500",
            &format!("--screenshot={}", top.display()),
            &url(report),
        ],
    );
    shots.push(top);
    for k in 0..sections {
        let page = dir.join(format!("section-{k}.html"));
        let style = format!("<style>nav,section{{display:none}}#s{k}{{display:block}}</style>");
        std::fs::write(&page, with_head(&html, &style)).unwrap();
        let png = dir.join(format!("section-{k}.png"));
        chromium(
            b,
            &[
                "--window-size=1200,2400",
                &format!("--screenshot={}", png.display()),
                &url(&page),
            ],
        );
        shots.push(png);
    }
    for s in &shots {
        assert!(
            std::fs::metadata(s)
                .map(|m| m.len() > 5_000)
                .unwrap_or(false),
            "{} missing or blank",
            s.display()
        );
    }
    shots
}

/// The columns named in the headers of the CSV files under `dir` (data names the report may show
/// as they are).
fn data_columns(dir: &Path, names: &mut Vec<String>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let f = e.unwrap().path();
        if f.is_dir() {
            data_columns(&f, names);
        } else if f.extension().is_some_and(|x| x == "csv") {
            let text = std::fs::read_to_string(&f).unwrap_or_default();
            if let Some(h) = text.lines().find(|l| !l.starts_with('#')) {
                names.extend(h.split(',').map(|c| c.trim().to_string()));
            }
        }
    }
}

/// Cells of every table (text between <td>/<th> and the closing tag), as (is header, text).
fn cells(html: &str) -> Vec<(bool, String)> {
    let mut out = Vec::new();
    for (tag, header) in [("<td", false), ("<th", true)] {
        let mut rest = html;
        while let Some(i) = rest.find(tag) {
            rest = &rest[i..];
            let open = rest.find('>').unwrap();
            let close = rest.find(if header { "</th>" } else { "</td>" }).unwrap();
            out.push((header, rest[open + 1..close].to_string()));
            rest = &rest[close..];
        }
    }
    out
}

/// No raw field names (snake_case words that are not the data's own column names) and no
/// unexpanded arrays or objects in any table.
fn tables_read_as_text(html: &str, columns: &[String]) {
    for (header, c) in cells(html) {
        assert!(
            !(c.contains("{…}") || c.starts_with('[') && c.ends_with(" values]")),
            "unexpanded value in a table: {c}"
        );
        let raw = c.contains('_')
            && c
                .chars()
                .all(|ch| ch.is_ascii_alphanumeric() || ch == '_' || ch == '.')
            && !columns.iter().any(|n| n == &c)
            // a file's name is the user's, not a field's
            && ![".csv", ".toml", ".ngc", ".json", ".txt"]
                .iter()
                .any(|x| c.ends_with(x));
        assert!(
            !raw,
            "raw field name in a table {}: {c}",
            if header { "header" } else { "cell" }
        );
    }
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("report-check")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn the_demo_report_reads_and_prints_as_a_customer_would_see_it() {
    let Some(b) = browser() else { return };
    let work = tempfile::tempdir().unwrap();
    let st = mtec()
        .arg("demo")
        .current_dir(work.path())
        .env("SOURCE_DATE_EPOCH", "1800000000")
        .status()
        .unwrap();
    assert!(st.success());
    let folder = work.path().join("mtec-demo");
    let report = folder.join("report.html");
    let html = std::fs::read_to_string(&report).unwrap();
    // the summary is the first section, with its verdict and key figures
    let first = html.find("<section id=\"s0\"><h2>").unwrap();
    assert!(html[first..].starts_with("<section id=\"s0\"><h2>Summary</h2><p class=\"verdict"));
    assert!(
        html.contains("2027-01-15"),
        "report date from SOURCE_DATE_EPOCH"
    );
    for q in [
        "bidirectional accuracy A",
        "bidirectional circular deviation G(b)",
        "volumetric error RMS after",
        "SHA-256",
    ] {
        assert!(html.contains(q), "summary lacks {q}");
    }
    // every analysis section names its method and source in a footnote
    for title in [
        "Positioning (ISO 230-2)",
        "Identified geometric errors",
        "Global sensitivity",
        "Circular test (ISO 230-4)",
        "Rotary axis",
        "Thermal model",
        "Volumetric error map",
        "Compensation outputs",
        "Compensation rate",
    ] {
        let at = html.find(&format!("<h2>{title}")).expect(title);
        let end = at + html[at..].find("</section>").unwrap();
        assert!(
            html[at..end].contains("<p class=\"source\">Method and source: "),
            "{title} has no method footnote"
        );
    }
    let mut columns = Vec::new();
    data_columns(&folder.join("data"), &mut columns);
    tables_read_as_text(&html, &columns);

    let dir = out_dir("demo");
    let (figures, problems) = browser_check(&b, &report, &dir);
    assert!(figures >= 15, "{figures} figures");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    let shots = screenshots(&b, &report, &dir);

    // print: A4 pages with the report's text in them (vector text, not pictures of it)
    let pdf = dir.join("report.pdf");
    chromium(
        &b,
        &[
            "--no-pdf-header-footer",
            &format!("--print-to-pdf={}", pdf.display()),
            &url(&report),
        ],
    );
    let info = Command::new("pdfinfo").arg(&pdf).output().expect("pdfinfo");
    let info = String::from_utf8_lossy(&info.stdout);
    let pages: usize = info
        .lines()
        .find_map(|l| l.strip_prefix("Pages:"))
        .map(|p| p.trim().parse().unwrap())
        .expect("pdfinfo pages");
    assert!(pages >= 8, "{pages} pages: one section a page at least");
    assert!(info.contains("(A4)"), "{info}");
    let text = Command::new("pdftotext")
        .args(["-f", "1", "-l", "2"])
        .arg(&pdf)
        .arg("-")
        .output()
        .expect("pdftotext");
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("Summary") && text.contains("bidirectional accuracy A"),
        "the PDF's first pages hold the summary as text"
    );
    assert!(
        !text.contains("Print / PDF"),
        "the print button is not printed"
    );
    eprintln!(
        "report check: {figures} figures, {pages} PDF pages; screenshots and PDF in {}",
        dir.display()
    );
    for s in shots {
        eprintln!("  {}", s.display());
    }
}

#[test]
fn the_fl_thermal_report_opens_with_its_summary_and_clean_plots() {
    let Some(b) = browser() else { return };
    let project =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fl-thermal/project.toml");
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("fl");
    let st = mtec()
        .arg("run")
        .arg(&project)
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let report = out.join("report.html");
    let html = std::fs::read_to_string(&report).unwrap();
    assert!(html.contains("<section id=\"s0\"><h2>Summary</h2><p class=\"verdict"));
    assert!(
        html.contains("Thermal ch1_um"),
        "key figures of the thermal stages"
    );
    let mut columns = Vec::new();
    data_columns(project.parent().unwrap(), &mut columns);
    tables_read_as_text(&html, &columns);
    let dir = out_dir("fl-thermal");
    let (figures, problems) = browser_check(&b, &report, &dir);
    assert!(figures >= 3, "{figures} figures");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    screenshots(&b, &report, &dir);
}

/// The checks can fail: a label over a line, an empty plot, a short caption, a rotated axis
/// title over tick labels and a table wider than the page are each reported.
#[test]
fn the_browser_check_finds_what_a_reader_would_object_to() {
    let Some(b) = browser() else { return };
    let dir = out_dir("planted");
    let line = "<polyline fill=\"none\" stroke=\"#000\" points=\"10,100 200,100 390,100\"/>";
    let html = format!(
        "<!DOCTYPE html><html><head><style>body{{max-width:600px}}</style></head><body>\
         <figure class=\"plot\"><svg xmlns=\"http://www.w3.org/2000/svg\" width=\"400\" height=\"200\">\
         {line}<text x=\"150\" y=\"104\" font-size=\"14\">over the data</text>\
         <text x=\"5\" y=\"190\">a</text><text x=\"300\" y=\"190\">b</text></svg>\
         <figcaption>A line with a label on top of it, which a reader cannot read.</figcaption></figure>\
         <figure class=\"plot\"><svg xmlns=\"http://www.w3.org/2000/svg\" width=\"400\" height=\"200\">\
         <rect x=\"0\" y=\"0\" width=\"400\" height=\"200\" fill=\"#fff\"/><text x=\"5\" y=\"20\">t</text>\
         <text x=\"5\" y=\"40\">u</text><text x=\"5\" y=\"60\">v</text></svg><figcaption>x</figcaption></figure>\
         <figure class=\"plot\"><svg xmlns=\"http://www.w3.org/2000/svg\" width=\"400\" height=\"200\">{line}\
         <text x=\"30\" y=\"60\" text-anchor=\"middle\" transform=\"rotate(270, 30, 60)\">a long axis title</text>\
         <text x=\"24\" y=\"66\">12.5</text><text x=\"300\" y=\"190\">c</text></svg>\
         <figcaption>Tick label under a rotated axis title, which overlap on the page.</figcaption></figure>\
         <table><tr><td>{}</td></tr></table></body></html>",
        "x".repeat(300)
    );
    let f = dir.join("planted.html");
    std::fs::write(&f, html).unwrap();
    let (figures, problems) = browser_check(&b, &f, &dir);
    let all = problems.join("\n");
    assert_eq!(figures, 3);
    for want in [
        "text \"over the data\" covers",
        "figure 2 (x): empty plot",
        "figure 2 (x): caption too short",
        "labels \"a long axis title\" and \"12.5\" overlap",
        "wider than the page",
    ] {
        assert!(all.contains(want), "not found: {want}\nin:\n{all}");
    }
}
