//! Building a machine error model file (`mtec.machine-error/1`, [`crate::machine`]) from fitted
//! thermal models and the data they were fitted on (`mtec machine build`).
//!
//! Each thermal model's training envelope is the range [min, max] of each of its inputs over the
//! rows it was fitted on, which its file's `split` names: `train_until_min` (rows with
//! time_min ≤ it), `train_experiments` (the rows of those experiments), all rows otherwise. The
//! number of rows found must equal the file's `train_rows`, so a data file other than the one
//! the model was fitted on is refused rather than giving a wrong envelope. Guard columns
//! ([`PartRequest::guards`]) get their range from the same rows.
//!
//! Paths in the written file are relative to it, so the model files travel with it. The file is
//! loaded back through [`MachineErrorModel::new`] before it is returned: what `build` returns,
//! `load` accepts.

use crate::machine::{Fade, MachineErrorModel, MachineFile, ThermalPartSpec, MACHINE_FORMAT};
use mtec_io::{InputError, Table};
use mtec_thermal::ModelFile;
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

/// One thermal part to add: a model file, the axis its drift acts along and its sign.
#[derive(Debug, Clone, PartialEq)]
pub struct PartRequest {
    /// `x`, `y` or `z`.
    pub axis: String,
    pub model: PathBuf,
    /// +1 or −1 ([`crate::machine`]).
    pub sign: f64,
    /// Further columns whose training range the state must stay in (e.g. `air_c` for a model
    /// that does not read it): outside it the thermal part fades like for its own inputs.
    pub guards: Vec<String>,
}

/// Everything `build` needs.
#[derive(Debug, Clone)]
pub struct BuildRequest<'a> {
    /// Static geometric model file, if any.
    pub geometric: Option<&'a Path>,
    pub parts: &'a [PartRequest],
    /// The training data of the thermal models (the file `mtec thermal fit` read); needed when
    /// there are thermal parts.
    pub data: Option<&'a Table>,
    pub fade: Fade,
    /// Where the machine file will be written (paths in it are made relative to its folder).
    pub output: &'a Path,
}

/// The rows of `data` a model was fitted on (module docs), checked against `train_rows`.
pub fn training_rows(
    data: &Table,
    file: &ModelFile,
    model_path: &Path,
) -> Result<Vec<usize>, InputError> {
    let split = &file.split;
    let rows: Vec<usize> = if let Some(until) = split.train_until_min {
        let t = data.f64_column("time_min")?;
        (0..t.len()).filter(|&i| t[i] <= until).collect()
    } else if !split.train_experiments.is_empty() {
        // a file without an `experiment` column is one experiment, `1` (as `thermal fit` reads it)
        let exp = if data.has("experiment") {
            data.str_column("experiment")?
        } else {
            vec!["1".to_string(); data.rows.len()]
        };
        for e in &split.train_experiments {
            if !exp.contains(e) {
                return Err(InputError::line(
                    &data.path,
                    data.header_line,
                    format!(
                        "{} was fitted on experiment `{e}`, which this file does not hold: give \
                         the data the model was fitted on",
                        model_path.display()
                    ),
                ));
            }
        }
        (0..exp.len())
            .filter(|&i| split.train_experiments.contains(&exp[i]))
            .collect()
    } else {
        (0..data.rows.len()).collect()
    };
    if split.train_rows > 0 && rows.len() != split.train_rows {
        return Err(InputError::file(
            &data.path,
            format!(
                "{} training rows here, but {} was fitted on {}: give the data the model was \
                 fitted on (its envelope is computed from those rows)",
                rows.len(),
                model_path.display(),
                split.train_rows
            ),
        ));
    }
    if rows.is_empty() {
        return Err(InputError::file(
            &data.path,
            format!("no training rows of {} in this file", model_path.display()),
        ));
    }
    Ok(rows)
}

/// [min, max] of column `name` over `rows`.
fn column_range(data: &Table, name: &str, rows: &[usize]) -> Result<[f64; 2], InputError> {
    let c = data.column(name)?;
    let mut r = [f64::INFINITY, f64::NEG_INFINITY];
    for &i in rows {
        let v = data.cell_f64(&data.rows[i], c)?;
        r = [r[0].min(v), r[1].max(v)];
    }
    Ok(r)
}

/// `path` relative to the folder `base` (both made absolute first; `..` where needed).
pub fn relative_to(path: &Path, base: &Path) -> PathBuf {
    let abs = |p: &Path| -> PathBuf {
        let p = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir().unwrap_or_default().join(p)
        };
        // resolve `.` and `..` lexically (the output folder may not exist yet)
        let mut out = PathBuf::new();
        for c in p.components() {
            match c {
                Component::CurDir => {}
                Component::ParentDir => {
                    out.pop();
                }
                other => out.push(other.as_os_str()),
            }
        }
        out
    };
    let (p, b) = (abs(path), abs(base));
    let pc: Vec<_> = p.components().collect();
    let bc: Vec<_> = b.components().collect();
    let common = pc.iter().zip(&bc).take_while(|(a, b)| a == b).count();
    let mut rel = PathBuf::new();
    for _ in common..bc.len() {
        rel.push("..");
    }
    for c in &pc[common..] {
        rel.push(c.as_os_str());
    }
    rel
}

/// Path as written into the file: relative, with `/` separators.
fn file_path(path: &Path, out_dir: &Path) -> String {
    relative_to(path, out_dir)
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

/// Builds the machine file (module docs) and checks that it loads.
pub fn build(req: &BuildRequest) -> Result<MachineFile, InputError> {
    let out_dir = req.output.parent().unwrap_or(Path::new("."));
    let out_dir = if out_dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        out_dir
    };
    let geometric = match req.geometric {
        Some(g) => {
            let m = crate::load::load_error_model(g)?;
            if !m.state_inputs().is_empty() {
                return Err(InputError::file(
                    g,
                    "the geometric part must be a static model (a map, a kinematic model, a \
                     BPNN), not a machine model",
                ));
            }
            Some(m)
        }
        None => None,
    };
    let mut specs = Vec::new();
    let mut streams = Vec::new();
    for part in req.parts {
        let Some(data) = req.data else {
            return Err(InputError::file(
                &part.model,
                "the training data of the thermal models is needed for their envelopes",
            ));
        };
        let file: ModelFile = mtec_io::read_json(&part.model)?;
        file.check_format()
            .map_err(|e| InputError::file(&part.model, e.to_string()))?;
        let stream = file
            .model
            .stream()
            .map_err(|e| InputError::file(&part.model, e.to_string()))?;
        let rows = training_rows(data, &file, &part.model)?;
        let mut envelope = BTreeMap::new();
        for name in stream.inputs().iter().chain(&part.guards) {
            envelope.insert(name.clone(), column_range(data, name, &rows)?);
        }
        specs.push(ThermalPartSpec {
            axis: part.axis.to_lowercase(),
            model: file_path(&part.model, out_dir),
            sign: part.sign,
            envelope,
        });
        streams.push(stream);
    }
    if specs.is_empty() && geometric.is_none() {
        return Err(InputError::file(
            req.output,
            "a machine model needs a geometric model, thermal models or both",
        ));
    }
    let file = MachineFile {
        format: MACHINE_FORMAT.into(),
        geometric: req.geometric.map(|g| file_path(g, out_dir)),
        thermal: specs,
        fade: req.fade,
    };
    // what is written must load: the same checks `MachineErrorModel::load` makes
    let parts = file.thermal.iter().zip(streams).collect();
    MachineErrorModel::new(geometric, parts, file.fade, String::new())
        .map_err(|m| InputError::file(req.output, m))?;
    Ok(file)
}

/// The file as JSON text.
pub fn to_json(file: &MachineFile) -> String {
    // a MachineFile holds strings, numbers and maps only: serialisation cannot fail
    serde_json::to_string_pretty(file).unwrap_or_default() + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths() {
        assert_eq!(
            relative_to(Path::new("/a/b/m.json"), Path::new("/a/c")),
            PathBuf::from("../b/m.json")
        );
        assert_eq!(
            relative_to(Path::new("/a/b/m.json"), Path::new("/a/b")),
            PathBuf::from("m.json")
        );
        assert_eq!(
            relative_to(Path::new("/a/b/./x/../m.json"), Path::new("/a/b/c/d")),
            PathBuf::from("../../m.json")
        );
    }
}
