//! Reading any compensable model file: dispatch on the JSON `"format"` field.
//!
//! Known formats: `mtec.map/1` (a [`GridMap`]), `mtec.kinematic-model/1` (identified error
//! functions on a machine) and `mtec.bpnn/1` (a network fitted to a volumetric grid by
//! `mtec map fit --model bpnn`, 3 inputs and 3 outputs) and `mtec.machine-error/1` (a geometric
//! model plus thermal models with a state, [`crate::machine`]).

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
];

/// Loads an error model file, whatever its kind, as an [`ErrorModel`].
pub fn load_error_model(path: &Path) -> Result<Box<dyn ErrorModel>, InputError> {
    let text = mtec_io::read_text(path)?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| InputError::at(path, e.line(), e.column(), e.to_string()))?;
    let format = model_format(path, &text, &value)?;
    match format.as_str() {
        MAP_FORMAT => Ok(Box::new(load_map_text(path, &text)?)),
        crate::kinematic::KINEMATIC_FORMAT => {
            let f: crate::kinematic::KinematicFile = serde_json::from_str(&text)
                .map_err(|e| InputError::at(path, e.line(), e.column(), e.to_string()))?;
            let m = crate::kinematic::KinematicModel::from_file(f, path.display().to_string())
                .map_err(|e| InputError::file(path, e))?;
            Ok(Box::new(m))
        }
        crate::bpnn::FORMAT => {
            let net = crate::bpnn::Bpnn::load_volumetric(&text)
                .map_err(|e| InputError::file(path, e.to_string()))?;
            Ok(Box::new(net))
        }
        crate::machine::MACHINE_FORMAT => {
            Ok(Box::new(crate::machine::MachineErrorModel::load(path)?))
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
    let file: MapFile = serde_json::from_str(text)
        .map_err(|e| InputError::at(path, e.line(), e.column(), e.to_string()))?;
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
}
