//! Atomic output: a file appears whole or not at all, and never replaces an input.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Remembers the input files of a command so that no output can overwrite one of them.
#[derive(Debug, Default, Clone)]
pub struct OutputGuard {
    inputs: Vec<PathBuf>,
}

impl OutputGuard {
    /// A guard over these input paths.
    pub fn new<P: AsRef<Path>>(inputs: &[P]) -> Self {
        OutputGuard {
            inputs: inputs.iter().map(|p| canonical(p.as_ref())).collect(),
        }
    }

    /// Adds one more input path.
    pub fn add_input(&mut self, p: &Path) {
        self.inputs.push(canonical(p));
    }

    /// Writes `bytes` to `path` atomically, unless `path` is one of the inputs.
    pub fn write(&self, path: &Path, bytes: &[u8]) -> std::io::Result<()> {
        let target = canonical(path);
        if self.inputs.contains(&target) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                format!("refusing to overwrite the input file {}", path.display()),
            ));
        }
        write_atomic(path, bytes)
    }
}

fn canonical(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    // Not there yet: canonicalise the parent and keep the name.
    match (p.parent(), p.file_name()) {
        (Some(parent), Some(name)) => {
            let parent = if parent.as_os_str().is_empty() {
                Path::new(".")
            } else {
                parent
            };
            parent
                .canonicalize()
                .map(|c| c.join(name))
                .unwrap_or_else(|_| p.to_path_buf())
        }
        _ => p.to_path_buf(),
    }
}

/// Writes `bytes` into a temporary file beside `path`, syncs it and renames it over `path`, so a
/// reader (or a crash) never sees a half-written file. Creates the parent folder if needed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = parent.join(format!(".{name}.mtec-tmp-{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guard_refuses_inputs_and_writes_others() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.csv");
        std::fs::write(&input, "a").unwrap();
        let g = OutputGuard::new(&[&input]);
        assert!(g.write(&input, b"b").is_err());
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "a");
        let out = dir.path().join("sub/out.csv");
        g.write(&out, b"c").unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "c");
        // no temporary file left behind
        assert_eq!(
            std::fs::read_dir(dir.path().join("sub")).unwrap().count(),
            1
        );
    }
}
