"""Line and ballbar identification: the same files and numbers as the CLI."""

import json

import numpy as np
import pytest

import mtec
from conftest import EXAMPLES, read_csv_columns

MACHINE = EXAMPLES / "vmc" / "machine.toml"
LINES = EXAMPLES / "vmc" / "lines.csv"


def test_lines_files_are_the_clis(cli, tmp_path):
    r = mtec.identify_lines(
        MACHINE, LINES, errors_out=tmp_path / "e.json", kinematic_model_out=tmp_path / "km.json"
    )
    cli.run("identify", "lines", "--machine", MACHINE, "--data", LINES,
            "-o", tmp_path / "e-cli.json", "--kinematic-model", tmp_path / "km-cli.json")
    assert (tmp_path / "e.json").read_bytes() == (tmp_path / "e-cli.json").read_bytes()
    assert (tmp_path / "km.json").read_bytes() == (tmp_path / "km-cli.json").read_bytes()
    assert r["errors"] == json.loads((tmp_path / "e.json").read_text())


def test_lines_report_is_the_clis(cli):
    ref = cli.json("identify", "lines", "--machine", MACHINE, "--data", LINES, "--json")
    r = mtec.identify_lines(MACHINE, LINES)["report"]
    for k in ("rank", "parameters", "readings", "condition_number", "residual_rms_um",
              "sigma_um", "dof", "degree"):
        assert r[k] == ref[k], k
    assert r["singular_values"] == ref["singular_values"]
    assert r["elements"] == ref["elements"]
    assert r["unidentifiable"] == ref["unidentifiable"]


def test_lines_from_arrays_and_degree():
    cols = read_csv_columns(LINES)
    a = mtec.identify_lines(MACHINE, cols, degree=2)["report"]
    f = mtec.identify_lines(MACHINE, LINES, degree=2)["report"]
    assert a["elements"] == f["elements"] and a["degree"] == 2


def test_lines_bad_input_is_located(tmp_path):
    cols = read_csv_columns(LINES)
    cols["reading_um"][9] = np.inf
    with pytest.raises(mtec.InputError) as e:
        mtec.identify_lines(MACHINE, cols)
    assert (e.value.line, e.value.column) == (10, list(cols).index("reading_um") + 1)
    bad_machine = tmp_path / "m.toml"
    bad_machine.write_text(MACHINE.read_text().replace("[", "[[", 1))
    with pytest.raises(mtec.InputError) as e:
        mtec.identify_lines(bad_machine, LINES)
    assert e.value.file == str(bad_machine) and e.value.line is not None


def test_ballbar_is_the_clis(cli, sim):
    d = sim("dbb-rotary")
    ref = cli.json("identify", "ballbar", "--setup", d["setup.toml"], "--data", d["dbb.csv"],
                   "--json")
    r = mtec.identify_ballbar(d["setup.toml"], d["dbb.csv"])
    assert r["format"] == ref["format"]
    assert r["conditioning"] == ref["conditioning"]
    for k in ("experiment", "time_min", "angle_deg", "EXC_um", "EYC_um", "EZC_um",
              "EAC_urad", "EBC_urad"):
        assert r["motions"][k].tolist() == [m[k] for m in ref["motions"]], k


def test_ballbar_unknown_mode_is_located(sim):
    d = sim("dbb-rotary")
    cols = read_csv_columns(d["dbb.csv"])
    cols["mode"] = cols["mode"].astype(int)
    cols["mode"][4] = 99
    with pytest.raises(mtec.InputError) as e:
        mtec.identify_ballbar(d["setup.toml"], cols)
    assert (e.value.line, e.value.column) == (5, list(cols).index("mode") + 1)
    assert "mode 99 is not in the setup" in e.value.message
