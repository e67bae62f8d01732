"""`mtec.run_project` against `mtec run` on the same project, and the machine model's build and
replay against `mtec machine`: the same files, byte for byte."""

from pathlib import Path

import numpy as np
import pytest

import mtec
from conftest import EXAMPLES


def _files(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def test_project_from_python_writes_the_clis_files(cli, tmp_path, monkeypatch):
    # the report's date: the same for both runs, even across midnight
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1800000000")
    project = EXAMPLES / "vmc" / "project.toml"
    ours, theirs = tmp_path / "py", tmp_path / "cli"
    r = mtec.run_project(project, out=ours)
    cli.run("run", project, "--out", theirs, "--quiet")
    a, b = _files(ours), _files(theirs)
    assert sorted(a) == sorted(b)
    # model files, tables, corrected programs, every stage's JSON: byte-identical
    for name in a:
        if name != "report.html":
            assert a[name] == b[name], name
    # the report names its output folder; otherwise the same page with the same numbers
    assert a["report.html"].replace(b"/py/", b"/X/") == b["report.html"].replace(b"/cli/", b"/X/")
    assert r["format"] == "mtec.run/1" and Path(r["report"]) == ours / "report.html"
    assert {str(Path(o).relative_to(ours)) for o in r["outputs"]} <= set(a)
    assert "thermal-model-thermal-radial_um.json" in a and "map.json" in a


def test_a_failed_stage_raises_located_and_keeps_the_report(tmp_path):
    (tmp_path / "runs.csv").write_text(
        "target_mm,run,direction,deviation_um\n0,1,+,1.0\n100,1,+,nan\n"
    )
    (tmp_path / "p.toml").write_text('[[iso230_2]]\ndata = "runs.csv"\n')
    with pytest.raises(mtec.InputError) as e:
        mtec.run_project(tmp_path / "p.toml", out=tmp_path / "out")
    assert e.value.file.endswith("runs.csv") and (e.value.line, e.value.column) == (3, 4)
    html = (tmp_path / "out" / "report.html").read_text()
    assert "<h2>FAILED: ISO 230-2 statistics of" in html.rsplit("<section", 1)[1]


# ---- the machine error model with a state ----


def test_machine_build_and_replay_are_the_clis(cli, sim, tmp_path):
    """production-day: a heat-input model of dz on the training days, built into a machine
    file, replayed on the unseen day; the files and the summary are the CLI's."""
    d = sim("production-day")
    dz = tmp_path / "dz.json"
    mtec.thermal_fit(d["train.csv"], "dz_um", "heat-input", out=dz)
    m = mtec.machine_build(tmp_path / "py" / "machine.json", thermal=[f"z={dz}"],
                           data=d["train.csv"], guard=["air_c"])
    cli.run("machine", "build", "--thermal", f"z={dz}", "--data", d["train.csv"], "--guard",
            "air_c", "-o", tmp_path / "cli" / "machine.json")
    assert (tmp_path / "py" / "machine.json").read_bytes() == \
        (tmp_path / "cli" / "machine.json").read_bytes()
    assert m["thermal"][0]["axis"] == "z" and "air_c" in m["thermal"][0]["envelope"]

    machine = tmp_path / "cli" / "machine.json"
    r = mtec.machine_replay(machine, d["day-state.csv"], d["day-probes.csv"],
                            output=tmp_path / "py.csv")
    ref = cli.json("machine", "replay", "--model", machine, "--state", d["day-state.csv"],
                   "--probes", d["day-probes.csv"], "--json", "-o", tmp_path / "cli.csv")
    samples = r.pop("samples")
    assert r == ref
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    # the samples are the rows of the CSV, and the summary is their RMS
    n = ref["readings"]
    assert samples["after_um"].shape == (n, 3) and len(samples["probe"]) == n
    np.testing.assert_allclose(samples["after_um"],
                               samples["before_um"] + samples["correction_um"], atol=1e-9)
    assert np.sqrt(np.mean(samples["after_um"][:, 2] ** 2)) == \
        pytest.approx(ref["z"]["rms_after_um"], rel=1e-9)


def test_machine_refusals(tmp_path):
    with pytest.raises(ValueError, match="--thermal `q=dz.json`"):
        mtec.machine_build(tmp_path / "m.json", thermal=["q=dz.json"])
    with pytest.raises(ValueError, match="stdout"):
        mtec.machine_build("-", thermal=["z=dz.json"])
