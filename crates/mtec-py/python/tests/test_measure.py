"""ISO 230-2: against the standard's formulas in numpy, and against the CLI's numbers."""

import numpy as np
import pytest

import mtec
from conftest import EXAMPLES, read_csv_columns

RUNS = EXAMPLES / "vmc" / "iso230-2.csv"


def iso_by_hand(cols):
    """ISO 230-2:2014 clause 3 from the definitions, in numpy (independent of mtec)."""
    t = cols["target_mm"]
    targets = np.unique(t)
    up = [cols["deviation_um"][(t == p) & (cols["direction"] == "+")] for p in targets]
    dn = [cols["deviation_um"][(t == p) & (cols["direction"] == "-")] for p in targets]
    mu = np.array([u.mean() for u in up])
    md = np.array([d.mean() for d in dn])
    su = np.array([u.std(ddof=1) for u in up])  # 3.3.5
    sd = np.array([d.std(ddof=1) for d in dn])
    b = mu - md  # 3.3.2
    ri = np.maximum.reduce([2 * su + 2 * sd + np.abs(b), 4 * su, 4 * sd])  # 3.3.7
    xbar = (mu + md) / 2
    return {
        "B_um": np.abs(b).max(),
        "mean_B_um": b.mean(),
        "R_up_um": (4 * su).max(),
        "R_down_um": (4 * sd).max(),
        "R_um": ri.max(),
        "E_up_um": mu.max() - mu.min(),
        "E_down_um": md.max() - md.min(),
        "E_um": max(mu.max(), md.max()) - min(mu.min(), md.min()),
        "M_um": xbar.max() - xbar.min(),
        "A_up_um": (mu + 2 * su).max() - (mu - 2 * su).min(),
        "A_down_um": (md + 2 * sd).max() - (md - 2 * sd).min(),
        "A_um": max((mu + 2 * su).max(), (md + 2 * sd).max())
        - min((mu - 2 * su).min(), (md - 2 * sd).min()),
        "targets": targets,
        "mean_up_um": mu,
        "s_down_um": sd,
    }


def test_axis_values_follow_the_standard():
    cols = read_csv_columns(RUNS)
    ref = iso_by_hand(cols)
    r = mtec.iso230_2(RUNS)
    for k in ["B_um", "mean_B_um", "R_up_um", "R_down_um", "R_um", "E_up_um", "E_down_um",
              "E_um", "M_um", "A_up_um", "A_down_um", "A_um"]:
        assert r[k] == pytest.approx(ref[k], rel=1e-12, abs=1e-12), k
    np.testing.assert_allclose(r["targets"]["target_mm"], ref["targets"], rtol=0, atol=0)
    np.testing.assert_allclose(r["targets"]["mean_up_um"], ref["mean_up_um"], rtol=1e-12)
    np.testing.assert_allclose(r["targets"]["s_down_um"], ref["s_down_um"], rtol=1e-12)
    assert r["runs_up"] == r["runs_down"] == 5


def test_same_numbers_as_the_cli(cli):
    ref = cli.json("iso230-2", RUNS, "--json")
    r = mtec.iso230_2(str(RUNS))
    for k, v in ref.items():
        if k in ("targets", "vdi3441", "corrections"):
            continue
        assert r[k] == v, k
    for k in ref["targets"][0]:
        assert r["targets"][k].tolist() == [t[k] for t in ref["targets"]], k
    for k in ("Ps_um", "U_um", "Pa_um", "P_um"):
        assert r["vdi3441"][k] == ref["vdi3441"][k]


def test_arrays_give_the_csv_numbers():
    cols = read_csv_columns(RUNS)
    from_arrays = mtec.iso230_2(cols)
    from_file = mtec.iso230_2(RUNS)
    assert from_arrays["A_um"] == from_file["A_um"]
    assert from_arrays["file"] == "<arrays>"
    np.testing.assert_array_equal(from_arrays["targets"]["r_um"], from_file["targets"]["r_um"])
    # integer directions are not accepted: +1/-1 is not the file's `+`/`-`
    cols["direction"] = np.where(cols["direction"] == "+", 1, -1)
    with pytest.raises(mtec.InputError) as e:
        mtec.iso230_2(cols)
    assert (e.value.file, e.value.line, e.value.column) == ("<arrays>", 1, 3)


def test_bad_rows_are_located(tmp_path):
    cols = read_csv_columns(RUNS)
    cols["deviation_um"] = cols["deviation_um"].copy()
    cols["deviation_um"][6] = np.nan
    with pytest.raises(mtec.InputError) as e:
        mtec.iso230_2(cols)
    assert (e.value.file, e.value.line, e.value.column) == ("<arrays>", 7, 4)
    assert "not a finite number" in e.value.message
    assert isinstance(e.value, ValueError)

    text = RUNS.read_text().splitlines()
    header = next(i for i, l in enumerate(text) if l.startswith("target_mm"))
    row = text[header + 3].split(",")
    row[2] = "up"
    text[header + 3] = ",".join(row)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(text) + "\n")
    with pytest.raises(mtec.InputError) as e:
        mtec.iso230_2(bad)
    assert (e.value.file, e.value.line, e.value.column) == (str(bad), header + 4, 3)
    assert str(e.value).startswith(f"{bad}:{header + 4}:3: direction is `up`")


def test_missing_column_and_ragged_columns():
    cols = read_csv_columns(RUNS)
    del cols["run"]
    with pytest.raises(mtec.InputError) as e:
        mtec.iso230_2(cols)
    assert e.value.line is None and "missing column `run`" in e.value.message
    cols = read_csv_columns(RUNS)
    cols["run"] = cols["run"][:-1]
    with pytest.raises(ValueError, match="every column needs one value per row"):
        mtec.iso230_2(cols)
    with pytest.raises(ValueError, match="CSV path or a mapping"):
        mtec.iso230_2(42)


# ---- circular test (ISO 230-4) ----


def test_circular_is_the_clis(cli, sim, tmp_path):
    """The simulated trace: the document and both files of `mtec circular --json --out`."""
    trace = sim("circular-test")["circular.csv"]
    ref = cli.json("circular", trace, "--json", "--out", tmp_path / "cli")
    r = mtec.circular(trace, out=tmp_path / "py")
    assert r["iso230_4"] == ref["iso230_4"]
    assert r["diagnostics"]["faults"] == ref["diagnostics"]["faults"]
    assert (r["radius_mm"], r["plane"], r["samples"]) == (ref["radius_mm"], ref["plane"], ref["samples"])
    for f in ("circular.json", "polar.svg"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f


def test_circular_from_arrays_equals_from_file(sim):
    trace = sim("circular-test")["circular.csv"]
    cols = read_csv_columns(trace)
    a = mtec.circular(trace, threshold_um=0.5)
    b = mtec.circular(cols, radius_mm=a["radius_mm"], plane=a["plane"],
                      feed_mm_min=a["feed_mm_min"], threshold_um=0.5)
    assert a["iso230_4"] == b["iso230_4"]
    assert a["diagnostics"] == b["diagnostics"]
    assert b["file"] == "<arrays>"


def test_circular_deviation_by_hand():
    """G of a trace is max − min of its radial deviation about the least-squares circle (ISO
    230-4 §3.2): a centred ellipse plus a third harmonic, whose least-squares circle is the
    nominal one (the harmonics are orthogonal to 1, cos θ, sin θ), computed here in numpy."""
    a = np.arange(0.0, 360.0, 0.5)
    th = np.radians(a)
    ccw = 2.0 * np.cos(2 * th) + 0.7 * np.sin(3 * th)
    cw = ccw + 0.4  # the other direction 0.4 µm larger all round: its own circle
    r = mtec.circular({"angle_deg": np.concatenate([a, a]),
                       "direction": ["ccw"] * a.size + ["cw"] * a.size,
                       "dl_um": np.concatenate([ccw, cw])}, radius_mm=100.0)
    iso = r["iso230_4"]
    assert iso["G_ccw_um"] == pytest.approx(ccw.max() - ccw.min(), abs=1e-9)
    assert iso["G_cw_um"] == pytest.approx(cw.max() - cw.min(), abs=1e-9)
    assert iso["circle_cw"]["radius_deviation_um"] == pytest.approx(0.4, abs=1e-9)


def test_circular_needs_a_radius_and_checks_options():
    cols = {"angle_deg": [0.0, 90.0], "direction": ["ccw", "ccw"], "dl_um": [0.0, 0.0]}
    with pytest.raises(mtec.InputError) as e:
        mtec.circular(cols)
    assert "radius" in e.value.message and e.value.file == "<arrays>"
    with pytest.raises(ValueError, match="plane"):
        mtec.circular(cols, radius_mm=100.0, plane="XZ")
    with pytest.raises(ValueError, match="arc"):
        mtec.circular(cols, radius_mm=100.0, arc_start_deg=0.0)


# ---- environmental corrections and the standards side by side ----


@pytest.mark.parametrize("py_kwargs,cli_args", [
    ({"air_temp_c": 23.5, "pressure_pa": 98000.0, "humidity_pct": 40.0},
     ["--air-temp-c", "23.5", "--pressure-pa", "98000", "--humidity-pct", "40"]),
    ({"air_temp_c": 18.0, "pressure_pa": 101000.0, "humidity_pct": 60.0, "air_formula": "edlen",
      "laser_n": 1.00027, "material_temp_c": 21.5, "alpha_um_per_m_k": 11.7, "standard": "all"},
     ["--air-temp-c", "18", "--pressure-pa", "101000", "--humidity-pct", "60", "--air-formula",
      "edlen", "--laser-n", "1.00027", "--material-temp-c", "21.5", "--alpha-um-per-m-k", "11.7",
      "--standard", "all"]),
], ids=["air", "air-material-all"])
def test_corrections_are_the_clis(cli, tmp_path, py_kwargs, cli_args):
    ref = cli.json("iso230-2", RUNS, *cli_args, "--json", "--out", tmp_path / "cli")
    r = mtec.iso230_2(RUNS, out=tmp_path / "py", **py_kwargs)
    assert r["corrections"] == ref["corrections"]
    assert r.get("standards") == ref.get("standards")
    for k in ("A_um", "B_um", "E_um", "M_um", "R_um"):
        assert r[k] == ref[k], k
    f = "iso230-2.json"
    assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes()


def test_material_normalisation_scales_the_positions():
    """ISO 1: a reading taken on a scale at T is normalised to 20 °C by k = 1 / (1 + α(T − 20))
    applied to the measured position P + x (the interferometer reads 0 at target 0), so a
    deviation x becomes k·(P + x) − P: worked here by hand."""
    cols = read_csv_columns(RUNS)
    plain = mtec.iso230_2(cols)
    warm = mtec.iso230_2(cols, material_temp_c=22.0, alpha_um_per_m_k=11.5)
    k = 1 / (1 + 11.5e-6 * 2.0)
    assert warm["corrections"]["scale_factor"] == pytest.approx(k, rel=1e-12)
    p_um = plain["targets"]["target_mm"] * 1000
    for key in ("mean_up_um", "mean_down_um"):
        np.testing.assert_allclose(warm["targets"][key],
                                   k * (p_um + plain["targets"][key]) - p_um, rtol=0, atol=1e-9)


def test_correction_options_are_checked():
    with pytest.raises(ValueError, match="all of --air-temp-c"):
        mtec.iso230_2(RUNS, air_temp_c=20.0)
    with pytest.raises(ValueError, match="air_formula `owens`"):
        mtec.iso230_2(RUNS, air_temp_c=20.0, pressure_pa=1e5, humidity_pct=50.0,
                      air_formula="owens")
    with pytest.raises(ValueError, match="both --material-temp-c"):
        mtec.iso230_2(RUNS, alpha_um_per_m_k=11.5)
