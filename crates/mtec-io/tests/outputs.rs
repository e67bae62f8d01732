//! Issue 25: writing to a device, a FIFO or a symlink must not replace it. Every output goes
//! through `mtec_io::Destination`: files atomically, devices and FIFOs straight through, a link's
//! target beside that target, `-` to stdout; directories and block devices refused.

#![cfg(unix)]

use mtec_io::{write_output, Destination, OutputError, OutputGuard};
use std::ffi::CString;
use std::io::{Read, Write};
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::FileTypeExt;
use std::path::Path;

fn cpath(p: &Path) -> CString {
    CString::new(p.as_os_str().as_bytes()).unwrap()
}

fn mkfifo(p: &Path) {
    // SAFETY: a valid NUL-terminated path; mkfifo only creates a file system node.
    assert_eq!(
        unsafe { libc::mkfifo(cpath(p).as_ptr(), 0o600) },
        0,
        "mkfifo"
    );
}

/// Creates a device node (root only); `false` when not permitted.
fn mknod(p: &Path, kind: libc::mode_t, major: u32, minor: u32) -> bool {
    // SAFETY: a valid NUL-terminated path; mknod only creates a file system node.
    let r = unsafe { libc::mknod(cpath(p).as_ptr(), kind | 0o666, libc::makedev(major, minor)) };
    r == 0
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

/// The names in `dir` (to see that no temporary file is left behind).
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_fifo_is_written_through_and_stays_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    mkfifo(&fifo);
    assert_eq!(
        Destination::of(&fifo).unwrap(),
        Destination::Stream(fifo.clone())
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut s = String::new();
            std::fs::File::open(&fifo)
                .unwrap()
                .read_to_string(&mut s)
                .unwrap();
            s
        })
    };
    write_output(&fifo, b"through the pipe\n").unwrap();
    // checked before joining: a replaced FIFO would leave the reader waiting for ever
    let t = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(t.is_fifo(), "the FIFO was replaced: {t:?}");
    assert_eq!(reader.join().unwrap(), "through the pipe\n");
    assert_eq!(names(dir.path()), ["pipe"]);
}

#[test]
fn a_symlink_stays_a_link_and_its_target_gets_the_content() {
    let dir = tempfile::tempdir().unwrap();
    let real_dir = dir.path().join("real");
    std::fs::create_dir(&real_dir).unwrap();
    let target = real_dir.join("table.txt");
    std::fs::write(&target, "old").unwrap();
    let link = dir.path().join("link.txt");
    // a relative link, resolved against the link's folder
    std::os::unix::fs::symlink("real/table.txt", &link).unwrap();
    match Destination::of(&link).unwrap() {
        Destination::File(p) => assert_eq!(p, target.canonicalize().unwrap()),
        d => panic!("{d:?}"),
    }
    write_output(&link, b"new").unwrap();
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(
        std::fs::read_link(&link).unwrap(),
        Path::new("real/table.txt")
    );
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    // the temporary file went beside the target, and is gone
    assert_eq!(names(&real_dir), ["table.txt"]);
    assert_eq!(names(dir.path()), ["link.txt", "real"]);

    // a dangling link creates its target, and stays a link
    let dangling = dir.path().join("dangling.txt");
    std::os::unix::fs::symlink("real/created.txt", &dangling).unwrap();
    write_output(&dangling, b"created").unwrap();
    assert!(std::fs::symlink_metadata(&dangling)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(
        std::fs::read_to_string(real_dir.join("created.txt")).unwrap(),
        "created"
    );
}

#[test]
fn a_replaced_file_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("run.sh");
    std::fs::write(&f, "old").unwrap();
    std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o751)).unwrap();
    write_output(&f, b"new").unwrap();
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "new");
    assert_eq!(
        std::fs::metadata(&f).unwrap().permissions().mode() & 0o777,
        0o751
    );
}

#[test]
fn dash_is_stdout_and_an_empty_path_is_refused() {
    assert_eq!(
        Destination::of(Path::new("-")).unwrap(),
        Destination::Stdout
    );
    assert!(Destination::of(Path::new("-")).unwrap().is_stdout());
    assert!(matches!(
        Destination::of(Path::new("")),
        Err(OutputError::Refused(_))
    ));
    // `./-` is a file named `-`
    assert!(matches!(
        Destination::of(Path::new("./-")).unwrap(),
        Destination::File(_)
    ));
}

#[test]
fn a_directory_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let err = write_output(dir.path(), b"x").unwrap_err();
    assert!(matches!(err, OutputError::Refused(_)), "{err}");
    let msg = err.to_string();
    assert!(msg.contains(&dir.path().display().to_string()), "{msg}");
    assert!(msg.contains("is a directory"), "{msg}");
    assert!(dir.path().is_dir());
    // through a link too
    let link = dir.path().join("to-dir");
    std::os::unix::fs::symlink(dir.path(), &link).unwrap();
    assert!(matches!(
        write_output(&link, b"x"),
        Err(OutputError::Refused(_))
    ));
    assert_eq!(names(dir.path()), ["to-dir"]);
}

/// A character device made with mknod in a temporary folder (a twin of /dev/null, major 1
/// minor 3): written through, never replaced. Needs root; the FIFO test covers the logic
/// otherwise.
#[test]
fn a_character_device_is_written_through_and_stays_a_device() {
    if !is_root() {
        eprintln!("note: not root, mknod is not permitted: character-device case skipped");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let null = dir.path().join("null");
    assert!(mknod(&null, libc::S_IFCHR, 1, 3), "mknod as root");
    assert_eq!(
        Destination::of(&null).unwrap(),
        Destination::Stream(null.clone())
    );
    write_output(&null, &vec![b'x'; 600_000]).unwrap();
    let t = std::fs::symlink_metadata(&null).unwrap().file_type();
    assert!(t.is_char_device(), "the device was replaced: {t:?}");
    assert_eq!(names(dir.path()), ["null"]);
    // and through a symlink to it (/dev/stdout style)
    let link = dir.path().join("out");
    std::os::unix::fs::symlink(&null, &link).unwrap();
    write_output(&link, b"x").unwrap();
    assert!(std::fs::symlink_metadata(&null)
        .unwrap()
        .file_type()
        .is_char_device());
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
}

/// A block device (a loop-device node made in a temporary folder) is refused; nothing is
/// ever opened. Needs root.
#[test]
fn a_block_device_is_refused() {
    if !is_root() {
        eprintln!("note: not root, mknod is not permitted: block-device case skipped");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let disk = dir.path().join("disk");
    assert!(mknod(&disk, libc::S_IFBLK, 7, 200), "mknod as root");
    let err = write_output(&disk, b"x").unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, OutputError::Refused(_)), "{msg}");
    assert!(
        msg.contains("block device") && msg.contains("disk"),
        "{msg}"
    );
    assert!(std::fs::symlink_metadata(&disk)
        .unwrap()
        .file_type()
        .is_block_device());
}

/// An input is never overwritten, however the output names it: the same spelling, another
/// spelling, a symlink to it, a hard link to it. Checked without writing anything.
#[test]
fn the_input_is_refused_through_links_and_spellings() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    let input = sub.join("grid.csv");
    std::fs::write(&input, "a").unwrap();
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink(&input, &link).unwrap();
    let hard = dir.path().join("hard.csv");
    std::fs::hard_link(&input, &hard).unwrap();
    let g = OutputGuard::new(&[&input]);
    for out in [
        input.clone(),
        sub.join("../sub/./grid.csv"),
        link.clone(),
        hard.clone(),
    ] {
        let err = g.check(&out).unwrap_err();
        assert!(matches!(err, OutputError::Refused(_)), "{}", out.display());
        assert!(
            err.to_string().contains(&format!(
                "refusing to overwrite the input file {}",
                out.display()
            )),
            "{err}"
        );
        assert!(g.write(&out, b"b").is_err());
    }
    assert_eq!(std::fs::read_to_string(&input).unwrap(), "a");
    // the input given through the link is the same file
    let g2 = OutputGuard::new(&[&link]);
    assert!(g2.check(&input).is_err());
    // a device or FIFO that is also read is not replaced, so it is not refused
    let fifo = dir.path().join("fifo");
    mkfifo(&fifo);
    assert!(OutputGuard::new(&[&fifo]).check(&fifo).is_ok());
    // another file is fine
    g.write(&dir.path().join("out.csv"), b"c").unwrap();
}

/// An output dropped before `commit` (the command failed half-way) leaves the old file and no
/// temporary file.
#[test]
fn an_uncommitted_output_leaves_the_target_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("prog.ngc");
    std::fs::write(&f, "old").unwrap();
    {
        let mut out = Destination::of(&f).unwrap().open().unwrap();
        out.write_all(b"half a program").unwrap();
    }
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "old");
    assert_eq!(names(dir.path()), ["prog.ngc"]);
    let mut out = Destination::of(&f).unwrap().open().unwrap();
    out.write_all(b"whole").unwrap();
    out.commit().unwrap();
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "whole");
}
