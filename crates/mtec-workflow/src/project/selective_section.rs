//! The report's "Selective compensation" section (issue 19, item 4): when a project compensates
//! with the identified kinematic model, which error elements EFAST ranks as key, and the
//! compensation rate per axis with all elements, with the key ones (and with the project's own
//! list, if `[compensation] elements` names one), and the loss. The numbers are those of
//! `compensate gcode|table --elements` ([`ops::selective`]), saved as `selective.json`.

use super::pipeline::Pipeline;
use crate::ops::{self, selective::Elements, selective::Selective};
use crate::Result;
use std::path::Path;

/// What `selective.json` holds: the key selection, the project's list (if any), and which
/// elements the project's programs and tables compensate (`all`, `key` or `list`).
#[derive(serde::Serialize)]
struct Saved<'a> {
    compensated: &'a str,
    key: &'a Selective,
    #[serde(skip_serializing_if = "Option::is_none")]
    list: Option<&'a Selective>,
}

/// Adds the section for the kinematic model file `model`; `chosen` is the project's
/// `[compensation] elements`.
pub(super) fn section(p: &mut Pipeline, model: &Path, chosen: &Elements) -> Result<()> {
    let Some(key) = ops::selective::load(model, &Elements::Key)?.1 else {
        return Ok(());
    };
    let list = match chosen {
        Elements::List(_) => ops::selective::load(model, chosen)?.1,
        _ => None,
    };
    let compensated = match chosen {
        Elements::All => "all",
        Elements::Key => "key",
        Elements::List(_) => "list",
    };
    let saved = Saved {
        compensated,
        key: &key,
        list: list.as_ref(),
    };
    let text = serde_json::to_string_pretty(&saved)?;
    p.json_result("selective.json", &text)?;

    let all = key.elements.len() + key.left_out.len();
    let pts = |v: [f64; 3]| format!("X {:.1}, Y {:.1}, Z {:.1}", v[0], v[1], v[2]);
    p.summary.fact(
        "Compensation",
        "key elements (EFAST)",
        format!(
            "{} of {all}: {}; loss of compensating only these {} percentage points",
            key.elements.len(),
            key.elements.join(", "),
            pts(key.loss_pct)
        ),
    );
    let sec = p.report.section("Selective compensation");
    sec.source(
        "EFAST first-order indices (Saltelli, Tarantola & Chan 1999) of the volumetric error; \
         compensation rate = 1 − RMS after / RMS before per axis; mtec docs/methods.md §6 \
         (selective compensation)",
    );
    let what = match (chosen, &list) {
        (Elements::Key, _) => format!("the {} key elements", key.elements.len()),
        (Elements::List(_), Some(l)) => format!("the listed elements {}", l.elements.join(", ")),
        _ => format!("all {all} elements"),
    };
    sec.text(format!(
        "Which error elements carry the volumetric error, and what compensating only those \
         costs. The key elements are, for each of Ex, Ey and Ez, the fewest with the largest \
         first-order index S1 (EFAST over a 4 × 4 × 4 grid of the travels, each element's \
         spread its RMS over its travel) that carry {:.0} % of the sum of its S1. The rates are \
         over the same grid against the identified model itself (the machine taken to have the \
         model's errors, commanded from the compensated elements only), so with all elements \
         the rate is 100 % by construction; on the machine both are lower by what the model \
         misses. The ranking is by S1 of the error's length |E|; an element small there can \
         still be key for one of Ex, Ey, Ez. The NC programs and tables of this project compensate {what} \
         ([compensation] elements).",
        100.0 * ops::selective::KEY_SHARE
    ));
    let rows: Vec<Vec<String>> = key
        .ranking
        .iter()
        .enumerate()
        .map(|(i, (name, s1))| {
            vec![
                format!("{}", i + 1),
                name.clone(),
                if *s1 >= 1e-3 || *s1 == 0.0 {
                    format!("{s1:.3}")
                } else {
                    format!("{s1:.1e}")
                },
                if key.elements.contains(name) {
                    "key".into()
                } else {
                    "–".into()
                },
            ]
        })
        .collect();
    sec.table(&["rank", "element", "S1 of |E|", "key"], rows);
    let pct = |v: f64| format!("{v:.1} %");
    let row = |label: &str, s: &Selective, rate: [f64; 3], loss: [f64; 3]| {
        let mut r = vec![label.to_string(), format!("{}", s.elements.len())];
        r.extend(rate.map(pct));
        r.extend(loss.map(|v| format!("{v:.1}")));
        r
    };
    let mut rates = vec![
        row("all elements", &key, key.rate_all_pct, [0.0; 3]),
        row("key elements", &key, key.rate_selected_pct, key.loss_pct),
    ];
    rates[0][1] = format!("{all}");
    if let Some(l) = &list {
        rates.push(row("listed elements", l, l.rate_selected_pct, l.loss_pct));
    }
    sec.table(
        &[
            "compensated",
            "elements",
            "rate X",
            "rate Y",
            "rate Z",
            "loss X (points)",
            "loss Y (points)",
            "loss Z (points)",
        ],
        rates,
    );
    sec.text(format!("Key elements: {}.", key.elements.join(", ")));
    Ok(())
}
