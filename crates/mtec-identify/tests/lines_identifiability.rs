//! The identifiability report names exactly what a design cannot determine.
//!
//! Worked expectations for the XYFZ machine (chain WXYFZT, tool on the Z axis at L = 100 mm):
//! - `ECZ` (roll of the tool-carrying Z) cannot move a tool tip that lies on the Z axis;
//! - `EBZ`, `EAZ` act only through the fixed tool offset: Ex ∋ EXZ(z) + L·EBZ(z) + z·EB0Z and
//!   Ey ∋ EYZ(z) − L·EAZ(z) − z·EA0Z, so they are confounded with `EXZ`/`EB0Z`, `EYZ`/`EA0Z`;
//! - `ECY` (yaw of Y, which carries X and the workpiece) reaches the tool as Ex ∋ y·ECY(y),
//!   as a function of y alone in x, like the straightness `EXY`.

use crate::support;

use mtec_identify::lines::{identify, ChannelKind, LineData};
use mtec_model::Machine;

fn nine_line_data() -> (Machine, LineData) {
    let (m, data, _) = support::vmc_9line(1);
    (m, data)
}

fn lost(m: &Machine, data: &LineData) -> Vec<(String, Vec<String>)> {
    let id = identify(m, data, 3).unwrap();
    // the error set never carries numbers for what the report calls unidentifiable
    for u in &id.report.unidentifiable {
        let e = mtec_model::ErrorElement::parse(&u.element).unwrap();
        assert!(
            id.errors.get(&e).is_none(),
            "{} must have no number",
            u.element
        );
        assert!(id.errors.unidentifiable.contains(&u.element));
    }
    id.report
        .unidentifiable
        .iter()
        .map(|u| (u.element.clone(), u.confounded_with.clone()))
        .collect()
}

fn names(v: &[(String, Vec<String>)]) -> Vec<&str> {
    let mut n: Vec<&str> = v.iter().map(|x| x.0.as_str()).collect();
    n.sort();
    n
}

fn partners<'a>(v: &'a [(String, Vec<String>)], e: &str) -> Vec<&'a str> {
    v.iter()
        .find(|x| x.0 == e)
        .map(|x| x.1.iter().map(|s| s.as_str()).collect())
        .unwrap_or_default()
}

#[test]
fn full_nine_line_design_loses_only_what_kinematics_hides() {
    let (m, data) = nine_line_data();
    let id = identify(&m, &data, 3).unwrap();
    let l = lost(&m, &data);
    assert_eq!(names(&l), ["EAZ", "EBZ", "ECY", "ECZ"], "{l:?}");
    assert_eq!(partners(&l, "ECZ"), Vec::<&str>::new());
    assert_eq!(partners(&l, "EBZ"), ["EXZ", "EB0Z"]);
    assert_eq!(partners(&l, "EAZ"), ["EYZ", "EA0Z"]);
    // y·ECY(y) reaches Ex like EXY does; its least-squares slope is a squareness (ISO 230-1
    // reference lines), so EC0Y shares it too
    assert_eq!(partners(&l, "ECY"), ["EXY", "EC0Y"]);
    let r = &id.report;
    // 21 elements at degree 3: 3 axes × (3 + 2 + 2 + 3·3) + 3 squareness = 51, plus one
    // alignment slope per straightness channel and run (6 axial lines × 2 + 3 diagonals × 2 = 18
    // channels, 3 runs)
    assert_eq!(r.parameters, 51 + 18 * mtec_sim::vmc_9line::RUNS);
    // deficiency: ECZ 3 + EBZ 3 + EAZ 3 + ECY 2 (its q⁴ part is outside EXY's span at degree 3)
    assert_eq!(r.rank_deficiency, 11);
    assert!(r.condition_number.is_finite() && r.condition_number < 1e4);
    assert!(r.singular_values.windows(2).all(|w| w[0] >= w[1]));
    assert!(r.text_has_every_lost_element());
    // repeat runs add readings, not information about other elements: one run loses the same
    let one_run = LineData {
        channels: data
            .channels
            .iter()
            .filter(|c| c.run == 1)
            .cloned()
            .collect(),
        ..data.clone()
    };
    let id1 = identify(&m, &one_run, 3).unwrap();
    assert_eq!(id1.report.parameters, 51 + 18);
    assert_eq!(id1.report.rank_deficiency, 11);
    assert_eq!(names(&lost(&m, &one_run)), names(&l));
}

trait TextCheck {
    fn text_has_every_lost_element(&self) -> bool;
}
impl TextCheck for mtec_identify::lines::LinesReport {
    fn text_has_every_lost_element(&self) -> bool {
        let t = self.to_text();
        self.unidentifiable.iter().all(|u| t.contains(&u.element)) && t.contains("tool offset")
    }
}

#[test]
fn removing_a_diagonal_loses_its_squareness() {
    let (m, data) = nine_line_data();
    let l = lost(&m, &data.without_lines(&["XY"]));
    assert_eq!(names(&l), ["EAZ", "EBZ", "EC0Y", "ECY", "ECZ"], "{l:?}");
    let l = lost(&m, &data.without_lines(&["XZ"]));
    assert_eq!(names(&l), ["EAZ", "EB0Z", "EBZ", "ECY", "ECZ"], "{l:?}");
    // without YZ nothing sees the y·z lever of the roll of Y any more, nor the Z-to-Y squareness
    let l = lost(&m, &data.without_lines(&["YZ"]));
    assert_eq!(
        names(&l),
        ["EA0Z", "EAZ", "EBY", "EBZ", "ECY", "ECZ"],
        "{l:?}"
    );
}

#[test]
fn removing_the_z_line_loses_the_z_to_x_squareness() {
    let (m, data) = nine_line_data();
    let l = lost(&m, &data.without_lines(&["Z1"]));
    assert!(names(&l).contains(&"EB0Z"), "{l:?}");
}

/// The literature's 9-line design reads the diagonals along the line only: the rolls' linear
/// parts (a guideway twist) then hide in the straightness alignment slopes and squareness.
#[test]
fn displacement_only_diagonals_lose_the_rolls() {
    let (m, mut data) = nine_line_data();
    data.channels.retain(|c| {
        !(["XY", "XZ", "YZ"].contains(&c.line.as_str()) && c.kind == ChannelKind::Straightness)
    });
    let l = lost(&m, &data);
    assert_eq!(
        names(&l),
        ["EAX", "EAZ", "EBY", "EBZ", "ECY", "ECZ"],
        "{l:?}"
    );
    assert_eq!(partners(&l, "EAX"), ["EB0Z", "EC0Y"]);
    // (removing X3 then does not lose the pitch EBX: the XZ diagonal's displacement still sees
    // it through the lever z + L that changes along the diagonal)
}
