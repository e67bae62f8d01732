//! Reading any compensable model file: dispatch on the JSON `"format"` field.
//!
//! Known formats: `mtec.map/1` (a [`GridMap`]), `mtec.kinematic-model/1` (identified error
//! functions on a machine) and `mtec.bpnn/1` (a network fitted to a volumetric grid by
//! `mtec map fit --model bpnn`, 3 inputs and 3 outputs), `mtec.machine-error/1` (a geometric
//! model plus thermal models with a state, [`crate::machine`]), and the hand-written
//! `mtec.zero-model/1` and `mtec.poly-model/1` ([`crate::hand`]). This is the one registry of
//! error models: the CLI, the workflow library and the real-time library all load through it.

use crate::map::{GridMap, MapFile, MAP_FORMAT};
use crate::ErrorModel;
use mtec_io::InputError;
use std::path::Path;

/// The model formats this build can load, for messages.
pub const KNOWN_FORMATS: &[&str] = &[
    MAP_FORMAT,
    crate::kinematic::KINEMATIC_FORMAT,
    crate::bpnn::FORMAT,
    crate::machine::MACHINE_FORMAT,
    crate::hand::ZERO_FORMAT,
    crate::hand::POLY_FORMAT,
];

/// Loads an error model file, whatever its kind, as an [`ErrorModel`].
pub fn load_error_model(path: &Path) -> Result<Box<dyn ErrorModel>, InputError> {
    let text = mtec_io::read_text(path)?;
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
    let format = model_format(path, &text, &value)?;
    match format.as_str() {
        MAP_FORMAT => Ok(Box::new(load_map_text(path, &text)?)),
        crate::kinematic::KINEMATIC_FORMAT => {
            let f: crate::kinematic::KinematicFile =
                serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
            let m = crate::kinematic::KinematicModel::from_file(f, path.display().to_string())
                .map_err(|e| InputError::file(path, e))?;
            Ok(Box::new(m))
        }
        crate::bpnn::FORMAT => {
            let net = crate::bpnn::Bpnn::load_volumetric(&text)
                .map_err(|e| InputError::file(path, e.to_string()))?;
            Ok(Box::new(net))
        }
        crate::machine::MACHINE_FORMAT => Ok(Box::new(crate::machine::MachineErrorModel::load(
            path,
            &load_error_model,
        )?)),
        crate::hand::ZERO_FORMAT => Ok(Box::new(crate::hand::ZeroModel::new(
            path.display().to_string(),
        ))),
        crate::hand::POLY_FORMAT => {
            let f: crate::hand::PolyFile =
                serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
            Ok(Box::new(crate::hand::PolyModel::new(f, path)?))
        }
        other => Err(located_format_error(
            path,
            &text,
            format!(
                "unknown model format `{other}`; this mtec reads: {}",
                KNOWN_FORMATS.join(", ")
            ),
        )),
    }
}

/// Loads a grid map file (`mtec.map/1`) as the concrete type (for table writers that need the
/// grid itself).
pub fn load_map(path: &Path) -> Result<GridMap, InputError> {
    let text = mtec_io::read_text(path)?;
    load_map_text(path, &text)
}

fn load_map_text(path: &Path, text: &str) -> Result<GridMap, InputError> {
    let file: MapFile = serde_json::from_str(text).map_err(|e| mtec_io::json_error(path, &e))?;
    let map = GridMap::from_file(file).map_err(|e| InputError::file(path, e.to_string()))?;
    // a map without provenance is described by the file it was loaded from
    Ok(if map.source().is_empty() {
        map.with_source(path.display().to_string())
    } else {
        map
    })
}

/// The `"format"` string of a model document, or a located error.
pub fn model_format(
    path: &Path,
    text: &str,
    value: &serde_json::Value,
) -> Result<String, InputError> {
    let Some(obj) = value.as_object() else {
        return Err(InputError::line(
            path,
            1,
            "a model file must be a JSON object with a \"format\" field",
        ));
    };
    match obj.get("format") {
        Some(serde_json::Value::String(s)) => Ok(s.clone()),
        Some(_) => Err(located_format_error(
            path,
            text,
            "\"format\" must be a string such as \"mtec.map/1\"".to_string(),
        )),
        None => Err(InputError::file(
            path,
            format!(
                "no \"format\" field: mtec model files say what they are (one of: {})",
                KNOWN_FORMATS.join(", ")
            ),
        )),
    }
}

fn located_format_error(path: &Path, text: &str, msg: String) -> InputError {
    match text.find("\"format\"") {
        Some(off) => {
            let (l, c) = mtec_io::line_col(text, off);
            InputError::at(path, l, c, msg)
        }
        None => InputError::file(path, msg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("model.json");
        std::fs::write(&p, text).unwrap();
        (dir, p)
    }

    #[test]
    fn map_dispatch_and_provenance() {
        let (_d, p) = write(
            r#"{"format":"mtec.map/1","model":"trilinear","x_mm":[0,1],"y_mm":[0],"z_mm":[0],
                "ex_um":[1,3],"ey_um":[0,0],"ez_um":[0,0]}"#,
        );
        let m = load_error_model(&p).unwrap();
        assert_eq!(m.error_um([0.5, 7.0, 7.0]), [2.0, 0.0, 0.0]);
        assert!(m.describe().contains("model.json"), "{}", m.describe());
    }

    #[test]
    fn unknown_format_is_located() {
        let (_d, p) = write("{\n  \"format\": \"mtec.bogus/1\"\n}\n");
        let e = load_error_model(&p).err().unwrap();
        assert_eq!((e.line, e.column), (Some(2), Some(3)), "{e}");
        assert!(e.message.contains("mtec.map/1"), "{e}");
    }

    #[test]
    fn missing_format_and_bad_fields() {
        let (_d, p) = write("{\"x_mm\": []}");
        assert!(load_error_model(&p)
            .err()
            .unwrap()
            .message
            .contains("no \"format\""));
        let (_d2, p2) = write(
            "{\"format\":\"mtec.map/1\",\"model\":\"trilinear\",\"x_mm\":[1,0],\"y_mm\":[0],\"z_mm\":[0],\"ex_um\":[0,0],\"ey_um\":[0,0],\"ez_um\":[0,0]}",
        );
        let e = load_error_model(&p2).err().unwrap();
        assert!(e.message.contains("strictly increasing"), "{e}");
    }

    /// A refused model file names every format the registry reads.
    #[test]
    fn refusals_name_every_readable_format() {
        for (text, located) in [
            ("{\"terms\": []}", false),
            ("{\n  \"format\": \"mtec.bogus/1\"\n}\n", true),
        ] {
            let (_d, p) = write(text);
            let Err(e) = load_error_model(&p) else {
                panic!("{text} was accepted")
            };
            for f in KNOWN_FORMATS {
                assert!(e.message.contains(f), "{text}: {e} lacks {f}");
            }
            assert!(e.message.contains("mtec.poly-model/1"), "{e}");
            assert_eq!(e.line.is_some(), located, "{e}");
        }
    }

    /// The hand-written models: zero everywhere; a polynomial evaluated term by term
    /// (8 + 0.012·x, -4, 3 + 1.5e-5·y² at (100, 200, 0): 9.2, -4, 3.6 µm); unknown fields located.
    #[test]
    fn hand_written_models() {
        let (_d, p) = write("{\"format\": \"mtec.zero-model/1\"}");
        assert_eq!(
            load_error_model(&p).unwrap().error_um([1.0, 2.0, 3.0]),
            [0.0; 3]
        );
        let (_d2, p2) = write(
            r#"{"format": "mtec.poly-model/1", "terms": [
                {"powers": [0, 0, 0], "coef_um": [8.0, -4.0, 3.0]},
                {"powers": [1, 0, 0], "coef_um": [0.012, 0.0, 0.0]},
                {"powers": [0, 2, 0], "coef_um": [0.0, 0.0, 1.5e-5]}]}"#,
        );
        let e = load_error_model(&p2).unwrap().error_um([100.0, 200.0, 0.0]);
        for (a, b) in e.iter().zip([9.2, -4.0, 3.6]) {
            assert!((a - b).abs() < 1e-12, "{e:?}");
        }
        let (_d3, p3) = write("{\"format\": \"mtec.poly-model/1\",\n \"terms\": [], \"x\": 1}");
        let e = load_error_model(&p3).err().unwrap();
        assert_eq!(e.line, Some(2), "{e}");
    }
}
