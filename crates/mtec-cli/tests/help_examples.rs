//! Every leaf command's `--help` ends with examples that run (issue 24). The test walks the
//! command tree from `mtec --help`, checks that each leaf's long help ends with an example
//! block, and runs the block's commands as written, in order, with bash in a fresh empty folder:
//! an example that reads a file no earlier line of its block writes fails here. The help is read
//! at 80 columns, so an example line that clap would wrap on a narrow terminal (and that could no
//! longer be pasted) fails too. No help text may cite SPEC, a file users do not have.
//!
//! An example block (see `src/help.rs`): the heading line, then `  # ...` lines that say what
//! the next command does and `  $ ...` command lines; a command line ending in `\` continues on
//! the next line, indented by six spaces.

use mtec_comp::load::KNOWN_FORMATS;
use std::path::Path;
use std::process::{Command, Output};
use std::time::Instant;

const HEADING: &str = "Examples (they run as written, in order, in an empty folder):";

fn mtec(args: &[String]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mtec"))
        .args(args)
        .env("COLUMNS", "80")
        .env("LINES", "50")
        .output()
        .expect("mtec runs")
}

/// `mtec <path> <flag>` (`--help` or `-h`), which must succeed.
fn help(path: &[String], flag: &str) -> String {
    let mut args = path.to_vec();
    args.push(flag.to_string());
    let o = mtec(&args);
    assert!(o.status.success(), "mtec {args:?} failed");
    String::from_utf8(o.stdout).expect("help is UTF-8")
}

/// The subcommand names listed under `Commands:` (without clap's `help`).
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| *l != "Commands:")
        .skip(1)
        .take_while(|l| !l.is_empty())
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|name| *name != "help")
        .map(str::to_string)
        .collect()
}

/// Every command path under `path` whose help has no `Commands:`, with its long help. Every
/// help text on the way (long and short) is checked for SPEC.
fn leaves(path: Vec<String>, out: &mut Vec<(Vec<String>, String)>) {
    let long = help(&path, "--help");
    for text in [&long, &help(&path, "-h")] {
        assert!(
            !text.contains("SPEC"),
            "`mtec {}` help cites SPEC, which users do not have:\n{text}",
            path.join(" ")
        );
    }
    let subs = subcommands(&long);
    if subs.is_empty() {
        out.push((path, long));
        return;
    }
    for s in subs {
        let mut p = path.clone();
        p.push(s);
        leaves(p, out);
    }
}

/// The commands of the example block that ends `help`, continuation lines joined; panics with
/// the reason when the help has no such block or a line of it is neither comment, command nor
/// continuation (a line clap wrapped, for instance).
fn example_commands(name: &str, help: &str) -> Vec<String> {
    let lines: Vec<&str> = help.lines().collect();
    let at: Vec<usize> = (0..lines.len()).filter(|&i| lines[i] == HEADING).collect();
    assert_eq!(
        at.len(),
        1,
        "`{name} --help` has {} example headings",
        at.len()
    );
    let mut commands: Vec<String> = Vec::new();
    let mut continues = false;
    let mut comments = 0;
    for line in &lines[at[0] + 1..] {
        let part = if continues {
            line.strip_prefix("      ")
                .filter(|l| !l.starts_with(' '))
                .unwrap_or_else(|| {
                    panic!("`{name}`: a continuation must be indented by six spaces: {line:?}")
                })
        } else if let Some(cmd) = line.strip_prefix("  $ ") {
            commands.push(String::new());
            cmd
        } else if line.starts_with("  # ") {
            comments += 1;
            continue;
        } else {
            panic!("`{name}`: not a `  # ` comment or a `  $ ` command in its examples: {line:?}");
        };
        continues = part.ends_with('\\');
        let last = commands.last_mut().expect("a command line came first");
        if !last.is_empty() {
            last.push(' ');
        }
        last.push_str(part.trim_end_matches('\\').trim_end());
    }
    assert!(!continues, "`{name}`: the last example line ends in `\\`");
    assert!(!commands.is_empty(), "`{name}` has an empty example block");
    assert!(comments > 0, "`{name}`: no example says what it does");
    commands
}

/// Runs one example command with bash in `dir`, with the binary under test first on PATH.
fn run_example(dir: &Path, command: &str) -> Output {
    let bin = Path::new(env!("CARGO_BIN_EXE_mtec")).parent().unwrap();
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut dirs = vec![bin.to_path_buf()];
    dirs.extend(std::env::split_paths(&path));
    Command::new("bash")
        .arg("-c")
        .arg(format!("set -euo pipefail\n{command}"))
        .current_dir(dir)
        .env("PATH", std::env::join_paths(dirs).unwrap())
        .output()
        .expect("bash runs")
}

/// Runs the examples at the end of one leaf command's --help in a fresh folder.
fn run_examples_of(path: &[String], long: &str) {
    let name = format!("mtec {}", path.join(" "));
    let commands = example_commands(&name, long);
    assert!(
        commands
            .iter()
            .any(|c| c == &name || c.starts_with(&format!("{name} "))),
        "`{name}`: no example runs `{name}` itself: {commands:#?}"
    );
    let dir = tempfile::tempdir().unwrap();
    let t0 = Instant::now();
    for c in &commands {
        // the block stands alone: nothing from outside the fresh folder
        assert!(
            !c.contains("..") && !c.split_whitespace().any(|w| w.starts_with('/')),
            "`{name}`: an example reaches outside its folder: {c}"
        );
        let o = run_example(dir.path(), c);
        assert!(
            o.status.success(),
            "`{name}` example `{c}` failed ({:?}):\n{}\n{}",
            o.status.code(),
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    eprintln!(
        "{name}: {} commands, {:.2} s",
        commands.len(),
        t0.elapsed().as_secs_f64()
    );
}

#[test]
fn every_help_ends_with_examples_that_run_in_an_empty_folder() {
    let mut all = Vec::new();
    leaves(Vec::new(), &mut all);
    // the tree as the README presents it: 20 leaf commands when this test was written
    assert!(all.len() >= 20, "only {} leaf commands found", all.len());
    let start = Instant::now();
    // the leaves in parallel, each in its own folder (two workers: CI's 2 cores; the examples
    // ran 17 s one after the other)
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some((path, long)) = all.get(i) else {
                    break;
                };
                run_examples_of(path, long);
            });
        }
    });
    eprintln!(
        "{} leaf commands, examples ran in {:.1} s",
        all.len(),
        start.elapsed().as_secs_f64()
    );
}

/// `compensate gcode --help` names every model format the model loader reads, and (per the
/// loader's own list in mtec-comp) that list is the one the help was written against.
#[test]
fn compensate_gcode_help_names_every_model_format() {
    let h = help(&["compensate".into(), "gcode".into()], "--help");
    for f in KNOWN_FORMATS {
        assert!(h.contains(f), "compensate gcode --help does not name {f}");
    }
    // and says which command writes each of the formats mtec writes
    for writer in ["mtec map fit", "--model bpnn", "mtec run", "mtec machine"] {
        assert!(
            h.contains(writer),
            "compensate gcode --help lacks `{writer}`"
        );
    }
}
