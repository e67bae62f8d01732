//! `mtec compensate table --elements key|all|LIST` (issue 19, item 4) on a kinematic model that
//! `identify lines` wrote from the simulated 9-line measurements. `all` is the model as it is,
//! byte for byte; a list (and the key set) gives the same table as a model file with the other
//! elements deleted from its JSON here, in the test (an independent route: no mtec code selects
//! them); a name the model lacks and a model that is not kinematic are usage errors (exit 2).

mod support;

use std::path::Path;
use support::{mtec, stderr, text};

fn p(d: &Path, n: &str) -> String {
    d.join(n).to_string_lossy().into_owned()
}

/// `compensate table --model MODEL --format FORMAT -o OUT` with the extra `args`.
fn table(model: &str, format: &str, out: &str, args: &[&str]) -> std::process::Output {
    let mut a = vec![
        "compensate",
        "table",
        "--model",
        model,
        "--format",
        format,
        "-o",
        out,
    ];
    match format {
        "beckhoff" => a.extend([
            "--x-range",
            "0:600:150",
            "--y-range",
            "0:800:200",
            "--z-range",
            "0:300:100",
        ]),
        _ => a.extend(["--axis", "X", "--range", "0:600:50", "--at", "300,400,150"]),
    }
    a.extend(args);
    mtec(&a)
}

/// The table file without its comment lines (a beckhoff table names its model file there).
fn values(path: &str) -> String {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// `km` with only the elements `keep` in its error set, written to `out` (edited as JSON).
fn only(km: &str, keep: &[&str], out: &str) {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(km).unwrap()).unwrap();
    let elements = v["errors"]["elements"].as_object_mut().unwrap();
    let before = elements.len();
    elements.retain(|name, _| keep.contains(&name.as_str()));
    assert_eq!(
        elements.len(),
        keep.len(),
        "every kept element is in the model"
    );
    assert!(before > keep.len());
    std::fs::write(out, serde_json::to_string(&v).unwrap()).unwrap();
}

#[test]
fn table_elements_all_key_and_list() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    support::write_scenario("vmc-9line", 1, d);
    let o = mtec(&[
        "identify",
        "lines",
        "--machine",
        &p(d, "machine.toml"),
        "--data",
        &p(d, "lines.csv"),
        "-o",
        &p(d, "errors.json"),
        "--kinematic-model",
        &p(d, "km.json"),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let km = p(d, "km.json");

    for format in ["linuxcnc", "beckhoff"] {
        // --elements all: the same bytes and the same report as without the option
        let plain = table(&km, format, &p(d, &format!("{format}.txt")), &[]);
        assert!(plain.status.success(), "{}", text(&plain));
        let all = table(
            &km,
            format,
            &p(d, &format!("{format}-all.txt")),
            &["--elements", "all"],
        );
        assert!(all.status.success(), "{}", text(&all));
        assert_eq!(
            std::fs::read(d.join(format!("{format}.txt"))).unwrap(),
            std::fs::read(d.join(format!("{format}-all.txt"))).unwrap(),
            "{format}"
        );
        assert_eq!(stderr(&plain), stderr(&all));

        // a list: the table of the model with the other elements deleted
        let list = ["EXX", "EC0Y", "EBX", "EZZ"];
        let o = table(
            &km,
            format,
            &p(d, &format!("{format}-list.txt")),
            &["--elements", "EXX, EC0Y,EBX,EZZ,EXX"],
        );
        assert!(o.status.success(), "{}", text(&o));
        let said = stderr(&o);
        assert!(
            said.contains("selective compensation (list): 4 of ")
                && said.contains("EXX, EC0Y, EBX, EZZ")
                && said.contains("loss"),
            "{said}"
        );
        only(&km, &list, &p(d, "km-list.json"));
        let o = table(&p(d, "km-list.json"), format, &p(d, "indep.txt"), &[]);
        assert!(o.status.success(), "{}", text(&o));
        let selected = values(&p(d, &format!("{format}-list.txt")));
        assert_eq!(selected, values(&p(d, "indep.txt")), "{format}");
        assert_ne!(
            selected,
            values(&p(d, &format!("{format}.txt"))),
            "{format}"
        );
    }

    // key: the elements the report names, and their table is the table of those alone
    let o = table(&km, "linuxcnc", &p(d, "key.txt"), &["--elements", "key"]);
    assert!(o.status.success(), "{}", text(&o));
    let said = stderr(&o);
    let line = said
        .lines()
        .find(|l| l.starts_with("selective compensation (key): "))
        .unwrap_or_else(|| panic!("{said}"));
    let key: Vec<&str> = line.rsplit(": ").next().unwrap().split(", ").collect();
    assert!(key.len() >= 3, "{line}");
    assert!(said.contains("all elements X 100.0 %"), "{said}");
    only(&km, &key, &p(d, "km-key.json"));
    let o = table(
        &p(d, "km-key.json"),
        "linuxcnc",
        &p(d, "key-indep.txt"),
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        std::fs::read(d.join("key.txt")).unwrap(),
        std::fs::read(d.join("key-indep.txt")).unwrap()
    );

    // a name the model lacks: exit 2, named, no table written
    let o = table(
        &km,
        "linuxcnc",
        &p(d, "bad.txt"),
        &["--elements", "EXX,EQQ"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(stderr(&o).contains("no element `EQQ`"), "{}", stderr(&o));
    assert!(!d.join("bad.txt").exists());

    // a model that is not kinematic (a grid map): exit 2, saying what it needs
    support::write_scenario("volumetric-grid", 1, d);
    let o = mtec(&[
        "map",
        "fit",
        "--grid",
        &p(d, "grid.csv"),
        "-o",
        &p(d, "map.json"),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = table(
        &p(d, "map.json"),
        "linuxcnc",
        &p(d, "map.txt"),
        &["--elements", "key"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        stderr(&o).contains("needs a kinematic model"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("map.txt").exists());
}
