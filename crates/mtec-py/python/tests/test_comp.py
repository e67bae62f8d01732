"""Maps and G-code compensation: trilinear interpolation by hand, the CLI's files, and the
compensated program checked against the model it was compensated with."""

import re

import numpy as np
import pytest

import mtec
from conftest import EXAMPLES, read_csv_columns

GRID = EXAMPLES / "vmc" / "grid.csv"
PART = EXAMPLES / "vmc" / "part.ngc"


def trilinear(axes, values, p):
    """Trilinear interpolation inside a rectilinear grid, from its definition."""
    idx, w = [], []
    for a, x in zip(axes, p):
        i = min(max(np.searchsorted(a, x) - 1, 0), len(a) - 2)
        idx.append(i)
        w.append((x - a[i]) / (a[i + 1] - a[i]))
    out = 0.0
    for c in range(8):
        b = [(c >> k) & 1 for k in range(3)]
        weight = np.prod([w[k] if b[k] else 1 - w[k] for k in range(3)])
        out = out + weight * values[idx[0] + b[0], idx[1] + b[1], idx[2] + b[2]]
    return out


def test_map_is_trilinear_and_the_clis_file(cli, tmp_path):
    m = mtec.map_fit(GRID, out=tmp_path / "py.json")
    cli.run("map", "fit", "--grid", GRID, "-o", tmp_path / "cli.json")
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "cli.json").read_bytes()
    axes = [m["x_mm"], m["y_mm"], m["z_mm"]]
    rng = np.random.default_rng(3)
    lo, hi = [a[0] for a in axes], [a[-1] for a in axes]
    pts = rng.uniform(lo, hi, size=(200, 3))
    e = mtec.map_eval(tmp_path / "py.json", pts)
    want = np.array([[trilinear(axes, m[k], p) for k in ("ex_um", "ey_um", "ez_um")]
                     for p in pts])
    np.testing.assert_allclose(e, want, rtol=1e-12, atol=1e-12)
    # the nodes themselves are the measured values
    cols = read_csv_columns(GRID)
    nodes = np.column_stack([cols["x_mm"], cols["y_mm"], cols["z_mm"]])
    np.testing.assert_allclose(
        mtec.map_eval(tmp_path / "py.json", nodes),
        np.column_stack([cols["ex_um"], cols["ey_um"], cols["ez_um"]]), atol=1e-12)


def test_map_eval_is_the_clis(cli, tmp_path):
    mtec.map_fit(GRID, out=tmp_path / "m.json")
    pts = tmp_path / "pts.csv"
    pts.write_text("x_mm,y_mm,z_mm\n10,20,30\n555.5,1.25,299\n300,400,150\n")
    out = cli.run("map", "eval", "--map", tmp_path / "m.json", "--points", pts)
    ref = np.array([[float(v) for v in l.split(",")[3:]] for l in out.splitlines()[1:]])
    np.testing.assert_array_equal(mtec.map_eval(tmp_path / "m.json", pts), ref)


def test_map_grid_errors_are_located(tmp_path):
    cols = read_csv_columns(GRID)
    for k in cols:
        cols[k] = cols[k][:-1]  # a missing node
    with pytest.raises(mtec.InputError) as e:
        mtec.map_fit(cols)
    assert e.value.file == "<arrays>"
    m = tmp_path / "refuse.json"
    mtec.map_fit(GRID, out=m, outside="refuse")
    with pytest.raises(mtec.InputError) as e:
        mtec.map_eval(m, np.array([[10.0, 10.0, 10.0], [-5.0, 10.0, 10.0]]))
    assert (e.value.line, e.value.column) == (2, 1)
    with pytest.raises(ValueError, match="outside `nowhere`"):
        mtec.map_fit(GRID, outside="nowhere")


def test_gcode_is_the_clis_and_cuts_true(cli, tmp_path):
    model = tmp_path / "m.json"
    mtec.map_fit(GRID, out=model)
    program = PART.read_text()
    text, report = mtec.compensate_gcode(program, model, name=str(PART))
    cli.run("compensate", "gcode", "--model", model, PART, "-o", tmp_path / "cli.ngc")
    assert text == (tmp_path / "cli.ngc").read_text()
    assert report["moves_compensated"] > 0 and report["lines_read"] == len(program.splitlines())
    # every corrected end point p satisfies p + e(p) = t for the programmed t (to the rounding)
    pos = {}
    commanded = []
    for line in text.splitlines():
        if line.startswith("(") or not re.search(r"\bG[01]\b|^[XYZ]", line):
            continue
        for ax, v in re.findall(r"([XYZ])(-?[\d.]+)", line):
            pos[ax] = float(v)
        if len(pos) == 3:
            commanded.append([pos["X"], pos["Y"], pos["Z"]])
    p = np.array(commanded)
    reached = p + mtec.map_eval(model, p) / 1000.0
    targets_x = {50.0, 550.0, 300.0}
    assert any(abs(r[0] - t) < 1e-4 for r in reached for t in targets_x)
    # the final drilled point X300 Y400 Z180 is reached within the 4-decimal rounding
    drill = [r for r, q in zip(reached, p) if abs(q[2] - 180) < 0.1]
    assert drill and np.allclose(drill[0], [300.0, 400.0, 180.0], atol=6e-5)


def test_gcode_tolerance_sets_the_digits_as_the_cli_does(cli, tmp_path):
    # 0.2 um: 5 inch digits round by 0.22 um, more than half the tolerance; the module refused
    # every program with it until 2026-11-29 (only the CLI chose 6 digits)
    model = tmp_path / "m.json"
    mtec.map_fit(GRID, out=model)
    program = "G20 G90\nG0 X0 Y0 Z0\nG1 X2 Y3 F10\nM2\n"
    (tmp_path / "in.ngc").write_text(program)
    text, _ = mtec.compensate_gcode(program, model, tolerance_um=0.2, name="in.ngc")
    cli.run("compensate", "gcode", "--model", model, tmp_path / "in.ngc", "--tolerance-um", "0.2",
            "-o", tmp_path / "cli.ngc")
    assert text == (tmp_path / "cli.ngc").read_text()
    assert re.search(r"X2\.\d{6}\b|X1\.\d{6}\b", text), text
    with pytest.raises(ValueError, match="start-position-mm"):
        mtec.compensate_gcode(program, model, start_position_mm=[1e300, 0.0, 0.0])


def test_gcode_refusal_is_located(tmp_path):
    model = tmp_path / "m.json"
    mtec.map_fit(GRID, out=model)
    with pytest.raises(mtec.InputError) as e:
        mtec.compensate_gcode("G21 G90\nG0 X0 Y0 Z0\nG81 X10 Y10 Z-5 R1 F100\n", model,
                              name="drill.ngc")
    assert e.value.file == "drill.ngc" and e.value.line == 3 and e.value.column is not None
    with pytest.raises(ValueError, match="on_unsupported"):
        mtec.compensate_gcode("G0 X1\n", model, on_unsupported="ignore")
    with pytest.raises(mtec.InputError) as e:
        mtec.compensate_gcode("G0 X1\n", EXAMPLES / "vmc" / "machine.toml")
    assert e.value.file.endswith("machine.toml") and e.value.line == 1


# ---- controller tables ----

RUN = EXAMPLES / "vmc" / "iso230-2.csv"


@pytest.mark.parametrize("fmt,py_kwargs,cli_args", [
    ("linuxcnc", {"axis": "X"}, ["--axis", "X"]),
    ("linuxcnc", {"axis": "Y", "range": (0.0, 400.0, 20.0), "at": (100.0, 0.0, -50.0),
                  "comp_type": 0},
     ["--axis", "Y", "--range", "0:400:20", "--at", "100,0,-50", "--comp-type", "0"]),
    ("sinumerik-cec", {"axis": "X", "output_axis": "Z", "table_index": 2},
     ["--axis", "X", "--output-axis", "Z", "--table-index", "2"]),
    ("fanuc", {"axis": "Z", "magnification": 2}, ["--axis", "Z", "--magnification", "2"]),
    ("beckhoff", {}, []),
], ids=["linuxcnc", "linuxcnc-range", "sinumerik-cec", "fanuc", "beckhoff"])
def test_table_from_a_map_is_the_clis(cli, tmp_path, fmt, py_kwargs, cli_args):
    mtec.map_fit(GRID, out=tmp_path / "map.json")
    ours, theirs = tmp_path / "py.txt", tmp_path / "cli.txt"
    r = mtec.compensate_table(fmt, ours, model=tmp_path / "map.json", **py_kwargs)
    cli.run("compensate", "table", "--model", tmp_path / "map.json", "--format", fmt,
            *cli_args, "-o", theirs)
    assert ours.read_bytes() == theirs.read_bytes()
    assert r["format"] == fmt and r["points"] > 1 and r["out"] == str(ours)


def test_linuxcnc_table_is_minus_the_map_along_the_axis(tmp_path):
    """Type 1 trims are c = −e (mm) at each nominal position, e the map interpolated there by
    hand (trilinear, from the grid file) at the other axes' `at`."""
    m = mtec.map_fit(GRID, out=tmp_path / "map.json")
    axes = [m["x_mm"], m["y_mm"], m["z_mm"]]
    at = (0.5 * (axes[0][0] + axes[0][-1]), 123.0, axes[2][1])
    mtec.compensate_table("linuxcnc", tmp_path / "x.comp", model=tmp_path / "map.json",
                          axis="X", at=at)
    rows = [list(map(float, l.split())) for l in (tmp_path / "x.comp").read_text().splitlines()]
    assert [r[0] for r in rows] == pytest.approx(list(axes[0]))
    for x, fwd, rev in rows:
        e = trilinear(axes, m["ex_um"], (x, at[1], at[2]))
        assert fwd == rev == pytest.approx(-e * 1e-3, abs=5e-7)  # 6 decimals of mm


@pytest.mark.parametrize("fmt", ["linuxcnc", "beckhoff"])
def test_table_from_an_iso230_2_run_is_the_clis(cli, tmp_path, fmt):
    ours, theirs = tmp_path / "py.txt", tmp_path / "cli.txt"
    r = mtec.compensate_table(fmt, ours, from_iso230_2=RUN, axis="X")
    cli.run("compensate", "table", "--from-iso230-2", RUN, "--format", fmt, "--axis", "X",
            "-o", theirs)
    assert ours.read_bytes() == theirs.read_bytes()
    assert r["reversal_max_um"] > 0


def test_equally_spaced_formats_refuse_the_standards_unequal_targets(tmp_path):
    """ISO 230-2 spaces targets unequally on purpose; FANUC and Siemens tables hold equal
    steps only: refused at the run's line, nothing written."""
    for fmt in ("fanuc", "sinumerik-cec"):
        with pytest.raises(mtec.InputError) as e:
            mtec.compensate_table(fmt, tmp_path / "t", from_iso230_2=RUN, axis="X")
        assert e.value.file == str(RUN) and e.value.line is not None
        assert "equally spaced" in e.value.message
    assert not (tmp_path / "t").exists()


def test_heidenhain_writes_the_com_and_its_cma(cli, tmp_path):
    mtec.map_fit(GRID, out=tmp_path / "map.json")
    (tmp_path / "py").mkdir()
    (tmp_path / "cli").mkdir()
    r = mtec.compensate_table("heidenhain", tmp_path / "py" / "X.COM",
                              model=tmp_path / "map.json", axis="X", output_axis="Y")
    cli.run("compensate", "table", "--model", tmp_path / "map.json", "--format", "heidenhain",
            "--axis", "X", "--output-axis", "Y", "-o", tmp_path / "cli" / "X.COM")
    for f in ("X.COM", "config.cma"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    assert r["cma"] == str(tmp_path / "py" / "config.cma")


def test_table_refusals(tmp_path):
    mtec.map_fit(GRID, out=tmp_path / "map.json")
    model = tmp_path / "map.json"
    with pytest.raises(ValueError, match="exactly one"):
        mtec.compensate_table("linuxcnc", tmp_path / "t", model=model, from_iso230_2=RUN)
    with pytest.raises(ValueError, match="exactly one"):
        mtec.compensate_table("linuxcnc", tmp_path / "t")
    with pytest.raises(ValueError, match="format `haas`"):
        mtec.compensate_table("haas", tmp_path / "t", model=model)
    with pytest.raises(ValueError, match="stdout"):
        mtec.compensate_table("linuxcnc", "-", model=model)
    # an option the format does not read is refused, not ignored
    with pytest.raises(ValueError, match="magnification"):
        mtec.compensate_table("linuxcnc", tmp_path / "t", model=model, magnification=10)
    # a run's table has the run's targets: a range would be silently ignored
    with pytest.raises(ValueError, match="--range"):
        mtec.compensate_table("linuxcnc", tmp_path / "t", from_iso230_2=RUN,
                              range=(0.0, 100.0, 10.0))
    with pytest.raises(ValueError, match="range"):
        mtec.compensate_table("linuxcnc", tmp_path / "t", model=model, range=(0.0, 100.0, -1.0))
    # never over an input, and a correction beyond the bound writes nothing
    with pytest.raises(Exception):
        mtec.compensate_table("linuxcnc", model, model=model)
    assert model.read_text().startswith("{")
    with pytest.raises(mtec.InputError):
        mtec.compensate_table("linuxcnc", tmp_path / "t", model=model, max_correction_um=1e-3)
    assert not (tmp_path / "t").exists()


# ---- a program file, as the command compensates it ----


def _rs274_or_skip():
    import os
    import shutil

    if shutil.which("rs274"):
        return
    if os.environ.get("CI"):
        pytest.fail("rs274 (LinuxCNC) is installed by .ci/run before the tests: not found")
    pytest.skip("rs274 (LinuxCNC) not installed")


@pytest.mark.parametrize("py_kwargs,cli_args", [
    ({}, []),
    ({"tolerance_um": 0.2, "max_segment_mm": 5.0, "decimals_mm": 5},
     ["--tolerance-um", "0.2", "--max-segment-mm", "5", "--decimals-mm", "5"]),
], ids=["defaults", "options"])
def test_gcode_file_is_the_clis(cli, tmp_path, py_kwargs, cli_args):
    mtec.map_fit(GRID, out=tmp_path / "map.json")
    r = mtec.compensate_gcode_file(PART, tmp_path / "map.json", tmp_path / "py.ngc", **py_kwargs)
    cli.run("compensate", "gcode", "--model", tmp_path / "map.json", PART, "-o",
            tmp_path / "cli.ngc", *cli_args)
    assert (tmp_path / "py.ngc").read_bytes() == (tmp_path / "cli.ngc").read_bytes()
    assert r["report"]["moves_compensated"] > 0 and r["output"] == str(tmp_path / "py.ngc")
    if not py_kwargs:
        # the text form of the same call gives the same program
        text, _ = mtec.compensate_gcode(PART.read_text(), tmp_path / "map.json")
        assert text == (tmp_path / "py.ngc").read_text()


def test_gcode_file_block_delete(cli, tmp_path):
    mtec.map_fit(GRID, out=tmp_path / "map.json")
    prog = tmp_path / "p.ngc"
    prog.write_text("G21 G90 G17\nG0 X10 Y10 Z5\n/G1 X200 F500\nG1 X100 F500\nM2\n")
    with pytest.raises(mtec.InputError) as e:
        mtec.compensate_gcode_file(prog, tmp_path / "map.json", tmp_path / "o.ngc")
    assert (e.value.file, e.value.line) == (str(prog), 3)
    for on, flag in ((True, "on"), (False, "off")):
        mtec.compensate_gcode_file(prog, tmp_path / "map.json", tmp_path / f"py-{flag}.ngc",
                                   block_delete=on)
        cli.run("compensate", "gcode", "--model", tmp_path / "map.json", prog, "-o",
                tmp_path / f"cli-{flag}.ngc", "--block-delete", flag)
        assert (tmp_path / f"py-{flag}.ngc").read_bytes() == \
            (tmp_path / f"cli-{flag}.ngc").read_bytes()


def test_gcode_file_key_elements_are_the_clis(cli, sim, tmp_path):
    d = sim("vmc-9line")
    mtec.identify_lines(d["machine.toml"], d["lines.csv"], kinematic_model_out=tmp_path / "km.json")
    r = mtec.compensate_gcode_file(PART, tmp_path / "km.json", tmp_path / "py.ngc",
                                   elements="key")
    cli.run("compensate", "gcode", "--model", tmp_path / "km.json", PART, "-o",
            tmp_path / "cli.ngc", "--elements", "key")
    assert (tmp_path / "py.ngc").read_bytes() == (tmp_path / "cli.ngc").read_bytes()
    assert r["selective"]["selection"] == "key" and r["selective"]["elements"]


def test_gcode_file_flattened_by_rs274_is_the_clis(cli, tmp_path):
    _rs274_or_skip()
    mtec.map_fit(GRID, out=tmp_path / "map.json")
    prog = tmp_path / "loop.ngc"
    prog.write_text("G21 G90 G17\nG0 X10 Y10 Z5\n#1 = 0\no100 while [#1 LT 3]\n"
                    "G1 X[20 + 30 * #1] Y40 F600\n#1 = [#1 + 1]\no100 endwhile\nM2\n")
    r = mtec.compensate_gcode_file(prog, tmp_path / "map.json", tmp_path / "py.ngc",
                                   flatten_with="rs274")
    cli.run("compensate", "gcode", "--model", tmp_path / "map.json", prog, "-o",
            tmp_path / "cli.ngc", "--flatten-with", "rs274")
    assert (tmp_path / "py.ngc").read_bytes() == (tmp_path / "cli.ngc").read_bytes()
    assert r["flattened"] is not None
    assert "while" not in (tmp_path / "py.ngc").read_text()


def test_gcode_file_refusals(tmp_path):
    mtec.map_fit(GRID, out=tmp_path / "map.json")
    m = tmp_path / "map.json"
    with pytest.raises(ValueError, match="stdout"):
        mtec.compensate_gcode_file(PART, m, "-")
    with pytest.raises(ValueError, match="flatten_with"):
        mtec.compensate_gcode_file(PART, m, tmp_path / "o.ngc", rs274="/usr/bin/rs274")
    with pytest.raises(ValueError, match="flatten_with `camotics`"):
        mtec.compensate_gcode_file(PART, m, tmp_path / "o.ngc", flatten_with="camotics")
    with pytest.raises(ValueError, match="machine_units `cm`"):
        mtec.compensate_gcode_file(PART, m, tmp_path / "o.ngc", machine_units="cm")
    before = PART.read_bytes()
    with pytest.raises(Exception):
        mtec.compensate_gcode_file(PART, m, PART)
    assert PART.read_bytes() == before
