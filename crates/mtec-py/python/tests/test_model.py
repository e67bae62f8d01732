"""Volumetric error: the CLI's numbers, and a hand calculation for single elements."""

import json

import numpy as np
import pytest

import mtec
from conftest import EXAMPLES

MACHINE = EXAMPLES / "vmc" / "machine.toml"


def test_same_numbers_as_the_cli(cli, sim, tmp_path):
    d = sim("vmc-9line")
    rng = np.random.default_rng(7)
    pts = rng.uniform([0, 0, 0], [600, 800, 300], size=(20, 3))
    csv = tmp_path / "pts.csv"
    csv.write_text("x_mm,y_mm,z_mm\n" + "".join(f"{float(x)!r},{float(y)!r},{float(z)!r}\n" for x, y, z in pts))
    for form in ("htm-exact", "poe-first"):
        ref = cli.json("volumetric", "--machine", d["machine.toml"], "--errors",
                       d["truth.json"], "--points", csv, "--form", form, "--json")
        e = mtec.volumetric(d["machine.toml"], d["truth.json"], pts, form=form)
        want = np.array([[p["ex_um"], p["ey_um"], p["ez_um"]] for p in ref["points"]])
        np.testing.assert_array_equal(e, want)
        np.testing.assert_array_equal(mtec.volumetric(d["machine.toml"], d["truth.json"], csv,
                                                      form=form), want)


def test_single_elements_by_hand(tmp_path):
    """EXX = 0.01·x µm alone moves the tool along X only, by 0.01·x; a squareness EC0Y of
    50 µrad alone gives an X error of 50e-6·y mm = 0.05·y µm (first order) and nothing else."""
    errs = tmp_path / "e.json"
    errs.write_text(json.dumps({"format": "mtec.errors/1", "elements": {
        "EXX": {"type": "polynomial", "coeffs": [0.0, 0.01]}}}))
    pts = np.array([[100.0, 200.0, 50.0], [500.0, 700.0, 250.0]])
    e = mtec.volumetric(MACHINE, errs, pts)
    np.testing.assert_allclose(np.abs(e[:, 0]), 0.01 * pts[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(e[:, 1:], 0.0, atol=1e-9)
    errs.write_text(json.dumps({"format": "mtec.errors/1", "elements": {
        "EC0Y": {"type": "constant", "value": 50.0}}}))
    e = mtec.volumetric(MACHINE, errs, pts, form="htm-first")
    np.testing.assert_allclose(np.abs(e[:, 0]), 0.05 * pts[:, 1], rtol=1e-9)
    np.testing.assert_allclose(e[:, 1:], 0.0, atol=1e-9)
    pos, rot = mtec.volumetric(MACHINE, errs, pts, orientation=True)
    assert pos.shape == rot.shape == (2, 3)


def test_pose_outside_the_travel_is_located(sim):
    d = sim("vmc-9line")
    pts = np.array([[100.0, 200.0, 50.0], [100.0, 900.0, 50.0]])
    with pytest.raises(mtec.InputError) as e:
        mtec.volumetric(d["machine.toml"], d["truth.json"], pts)
    assert (e.value.file, e.value.line, e.value.column) == ("<arrays>", 2, 2)
    assert "outside the travel [0, 800] of axis Y" in e.value.message
    with pytest.raises(ValueError, match="3 axes"):
        mtec.volumetric(d["machine.toml"], d["truth.json"], np.zeros((2, 2)))
    with pytest.raises(ValueError, match="form `htm`"):
        mtec.volumetric(d["machine.toml"], d["truth.json"], pts[:1], form="htm")
