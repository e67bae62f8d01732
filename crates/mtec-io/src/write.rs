//! Outputs: the one routine every command writes through (issue 25).
//!
//! What a path names decides how it is written ([`Destination::of`]):
//! - a regular file or a new path: atomically, a temporary file beside it is written, synced and
//!   renamed over it, so a reader (or a crash) never sees half a file; the parent folder is
//!   created if needed, and the permissions of a replaced file are kept;
//! - a character device (`/dev/null`, a terminal) or a FIFO (`-o /dev/stdout` in a pipe,
//!   `-o >(gzip > f.gz)`): written straight through, never replaced;
//! - `-`: standard output;
//! - a symbolic link: the file it resolves to, by the rules above (a regular target atomically
//!   beside that target); the link stays a link. A dangling link creates its target;
//! - a directory or a block device (or a socket): refused.
//!
//! [`OutputGuard`] also refuses an output that is one of the command's inputs, compared by
//! device and inode where both exist (hard links, symlinks, `./a/../a` spellings are the same
//! file) and by canonical path otherwise, and a file whose folder cannot take it.
//! [`OutputGuard::check`] does all of this without writing the output (it only creates and
//! removes an empty probe file in the folder), so a command calls it before any work.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Why an output cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output names something mtec will not write (an input, a directory, a block
    /// device): the user's mistake, exit code 2 in the CLI. The message names the path.
    #[error("{0}")]
    Refused(String),
    /// Writing failed (disk full, a closed pipe): not the user's input. (The OS error is
    /// part of the message, not a `source`, so a report of the chain does not print it twice.)
    #[error("cannot write {}: {error}", path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
}

impl OutputError {
    fn io(path: &Path, error: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            error,
        }
    }
}

impl From<OutputError> for std::io::Error {
    fn from(e: OutputError) -> Self {
        match e {
            OutputError::Refused(m) => std::io::Error::new(std::io::ErrorKind::AlreadyExists, m),
            OutputError::Io { path, error } => std::io::Error::new(
                error.kind(),
                format!("cannot write {}: {error}", path.display()),
            ),
        }
    }
}

/// Where an output goes, decided from what the path names (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Destination {
    /// `-`: standard output.
    Stdout,
    /// A character device or a FIFO (possibly reached through a link): written in place.
    Stream(PathBuf),
    /// A regular file or a new path (a link's resolved target): replaced atomically.
    File(PathBuf),
}

impl Destination {
    /// Classifies `path` without writing anything; refuses a directory, a block device or a
    /// socket with a message naming `path`.
    pub fn of(path: &Path) -> Result<Destination, OutputError> {
        if path.as_os_str() == "-" {
            return Ok(Destination::Stdout);
        }
        if path.as_os_str().is_empty() {
            return Err(OutputError::Refused(
                "the output path is empty: give a file name, or - for stdout".into(),
            ));
        }
        let meta = match std::fs::symlink_metadata(path) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Ok(Destination::File(path.to_path_buf()))
            }
            // a file where a folder should be, a folder that cannot be searched, a name too
            // long: the path itself is wrong, the user's to change
            Err(e) => {
                return Err(OutputError::Refused(format!(
                    "cannot write {}: {e}; choose another path",
                    path.display()
                )))
            }
        };
        if !meta.file_type().is_symlink() {
            return classify(path, path, &meta.file_type());
        }
        // a link: what it resolves to decides; the link itself is never replaced
        match std::fs::metadata(path) {
            // a device or FIFO is opened through the link (so /dev/stdout reaching a pipe
            // works, which no path could name); a regular file is replaced beside itself
            Ok(m) if m.file_type().is_file() => std::fs::canonicalize(path)
                .map(Destination::File)
                .map_err(|e| OutputError::io(path, e)),
            Ok(m) => classify(path, path, &m.file_type()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                resolve_dangling(path).map(Destination::File)
            }
            Err(e) => Err(OutputError::io(path, e)),
        }
    }

    /// Opens the output for writing; nothing is visible at a [`Destination::File`] until
    /// [`Output::commit`].
    pub fn open(&self) -> Result<Output, OutputError> {
        match self {
            Destination::Stdout => Ok(Output {
                inner: Inner::Stdout(std::io::stdout()),
                path: PathBuf::from("-"),
            }),
            Destination::Stream(p) => {
                let f = OpenOptions::new()
                    .write(true)
                    .open(p)
                    .map_err(|e| OutputError::io(p, e))?;
                Ok(Output {
                    inner: Inner::Stream(f),
                    path: p.clone(),
                })
            }
            Destination::File(p) => {
                let parent = match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                    _ => PathBuf::from("."),
                };
                std::fs::create_dir_all(&parent).map_err(|e| OutputError::io(p, e))?;
                let name = p
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "out".into());
                let tmp = parent.join(format!(".{name}.mtec-tmp-{}", std::process::id()));
                let f = File::create(&tmp).map_err(|e| OutputError::io(p, e))?;
                // a replaced file keeps its permissions (an executable script stays executable)
                if let Ok(m) = std::fs::metadata(p) {
                    let _ = f.set_permissions(m.permissions());
                }
                Ok(Output {
                    inner: Inner::File { file: Some(f), tmp },
                    path: p.clone(),
                })
            }
        }
    }

    /// Writes `bytes` whole: [`Destination::open`], `write_all`, [`Output::commit`].
    pub fn write(&self, bytes: &[u8]) -> Result<(), OutputError> {
        let mut out = self.open()?;
        out.write_all(bytes)
            .map_err(|e| OutputError::io(&out.path, e))?;
        out.commit()
    }

    /// Is this standard output? (A command then prints its summary to stderr instead.)
    pub fn is_stdout(&self) -> bool {
        matches!(self, Destination::Stdout)
    }
}

fn classify(shown: &Path, path: &Path, t: &std::fs::FileType) -> Result<Destination, OutputError> {
    if t.is_file() {
        return Ok(Destination::File(path.to_path_buf()));
    }
    if t.is_dir() {
        return Err(OutputError::Refused(format!(
            "{} is a directory: give a file name to write",
            shown.display()
        )));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() || t.is_fifo() {
            return Ok(Destination::Stream(path.to_path_buf()));
        }
        if t.is_block_device() {
            return Err(OutputError::Refused(format!(
                "{} is a block device: mtec does not write to disks",
                shown.display()
            )));
        }
    }
    Err(OutputError::Refused(format!(
        "{} is neither a file, a character device nor a FIFO: mtec does not write to it",
        shown.display()
    )))
}

/// The path a dangling link chain ends at (the file to create), at most 40 links deep.
fn resolve_dangling(path: &Path) -> Result<PathBuf, OutputError> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::read_link(&p) {
            Ok(target) => {
                p = match p.parent() {
                    Some(d) if target.is_relative() => d.join(target),
                    _ => target,
                };
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(p),
            // not a link (EINVAL): the end of the chain
            Err(_) if std::fs::symlink_metadata(&p).is_ok() => return Ok(p),
            Err(e) => return Err(OutputError::io(path, e)),
        }
    }
    Err(OutputError::Refused(format!(
        "{}: too many levels of symbolic links",
        path.display()
    )))
}

/// An open output; write to it, then [`Output::commit`]. Dropped uncommitted, a file output
/// leaves nothing behind (the target is untouched).
pub struct Output {
    inner: Inner,
    path: PathBuf,
}

enum Inner {
    Stdout(std::io::Stdout),
    Stream(File),
    File { file: Option<File>, tmp: PathBuf },
}

impl Output {
    /// The path written (`-` for standard output; a link's target for a link).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Finishes the output: flushes; a file is synced and renamed over its target.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let path = self.path.clone();
        let io = |e| OutputError::io(&path, e);
        match &mut self.inner {
            Inner::Stdout(s) => s.flush().map_err(io),
            Inner::Stream(f) => f.flush().map_err(io),
            Inner::File { file, tmp } => {
                let f = file.take().expect("an output is committed once");
                f.sync_all().map_err(io)?;
                drop(f);
                std::fs::rename(&*tmp, &path).map_err(io)
            }
        }
    }
}

impl Write for Output {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.inner {
            Inner::Stdout(s) => s.write(buf),
            Inner::Stream(f) => f.write(buf),
            Inner::File { file: Some(f), .. } => f.write(buf),
            Inner::File { file: None, .. } => {
                Err(std::io::Error::other("output already committed"))
            }
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.inner {
            Inner::Stdout(s) => s.flush(),
            Inner::Stream(f) => f.flush(),
            Inner::File { file: Some(f), .. } => f.flush(),
            Inner::File { file: None, .. } => Ok(()),
        }
    }
}

impl Drop for Output {
    fn drop(&mut self) {
        if let Inner::File {
            file: Some(_), tmp, ..
        } = &self.inner
        {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Writes `bytes` to `path` (a file, a device, a FIFO, a link, or `-`) by the rules of the
/// module docs. Commands with inputs use [`OutputGuard::write`] instead.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    Destination::of(path)?.write(bytes)
}

/// What identifies an input: its canonical path, and its device and inode where it exists.
#[derive(Debug, Clone, PartialEq)]
struct Identity {
    path: PathBuf,
    inode: Option<(u64, u64)>,
}

impl Identity {
    fn of(p: &Path) -> Identity {
        Identity {
            path: canonical(p),
            inode: inode(p),
        }
    }
    fn same(&self, other: &Identity) -> bool {
        match (self.inode, other.inode) {
            (Some(a), Some(b)) => a == b,
            _ => self.path == other.path,
        }
    }
}

#[cfg(unix)]
fn inode(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn inode(_p: &Path) -> Option<(u64, u64)> {
    None
}

/// Remembers the input files of a command so that no output can overwrite one of them.
#[derive(Debug, Default, Clone)]
pub struct OutputGuard {
    inputs: Vec<Identity>,
}

impl OutputGuard {
    /// A guard over these input paths.
    pub fn new<P: AsRef<Path>>(inputs: &[P]) -> Self {
        OutputGuard {
            inputs: inputs.iter().map(|p| Identity::of(p.as_ref())).collect(),
        }
    }

    /// Adds one more input path.
    pub fn add_input(&mut self, p: &Path) {
        self.inputs.push(Identity::of(p));
    }

    /// Where `path` would be written, refusing an input (only files can be replaced, so only a
    /// file destination is compared), a directory, a block device, or a file whose folder
    /// cannot take it ([`check_folder`]). Leaves nothing behind: call it before any work, so
    /// that an unwritable `-o` is said at once, not after a long fit.
    pub fn check(&self, path: &Path) -> Result<Destination, OutputError> {
        let dest = Destination::of(path)?;
        if let Destination::File(target) = &dest {
            let out = Identity::of(target);
            if self.inputs.iter().any(|i| i.same(&out)) {
                return Err(OutputError::Refused(format!(
                    "refusing to overwrite the input file {}",
                    path.display()
                )));
            }
            check_folder(path, target)?;
        }
        Ok(dest)
    }

    /// Writes `bytes` to `path` ([`OutputGuard::check`], then [`Destination::write`]).
    pub fn write(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        self.check(path)?.write(bytes)
    }
}

/// Can a file be created at `target` (shown as `shown`)? The nearest existing folder above it
/// must be a folder and must take a new file: probed by creating and removing an empty file
/// there (permission bits do not tell: root, read-only mounts, `/proc`). A folder that does not
/// exist yet is created only when the output is written.
fn check_folder(shown: &Path, target: &Path) -> Result<(), OutputError> {
    let mut folder = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    while std::fs::symlink_metadata(&folder).is_err() {
        match folder.parent() {
            Some(d) if !d.as_os_str().is_empty() => folder = d.to_path_buf(),
            _ => {
                folder = PathBuf::from(".");
                break;
            }
        }
    }
    if !folder.is_dir() {
        return Err(OutputError::Refused(format!(
            "cannot write {}: {} is not a folder",
            shown.display(),
            folder.display()
        )));
    }
    let probe = folder.join(format!(".mtec-probe-{}", std::process::id()));
    match OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(f) => {
            drop(f);
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        // a probe left by a crashed run of the same pid: the folder takes files
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(OutputError::Refused(format!(
            "cannot write {}: the folder {} does not take new files ({e}); choose a path \
             in a folder you can write",
            shown.display(),
            folder.display()
        ))),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guard_refuses_inputs_and_writes_others() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.csv");
        std::fs::write(&input, "a").unwrap();
        let g = OutputGuard::new(&[&input]);
        assert!(matches!(
            g.write(&input, b"b"),
            Err(OutputError::Refused(_))
        ));
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

    #[test]
    fn check_refuses_a_folder_that_cannot_take_the_file_and_creates_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f.csv");
        std::fs::write(&file, "a").unwrap();
        let g = OutputGuard::new(&[&file]);
        let e = g.check(&file.join("out.csv")).unwrap_err();
        assert!(matches!(e, OutputError::Refused(_)), "{e}");
        // a missing folder is fine and is not created by the check
        let deep = dir.path().join("a/b/out.csv");
        assert!(g.check(&deep).is_ok());
        assert!(!dir.path().join("a").exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // the probe's error is said once: the OS error is not also the source
        let io = OutputError::io(&file, std::io::Error::other("disk full"));
        assert!(std::error::Error::source(&io).is_none());
        assert_eq!(
            io.to_string(),
            format!("cannot write {}: disk full", file.display())
        );
    }
}
