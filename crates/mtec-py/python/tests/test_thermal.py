"""Thermal fit/predict: MLR against numpy least squares on real data, model files and
predictions against the CLI."""

import json

import numpy as np
import pytest

import mtec
from conftest import EXAMPLES, read_csv_columns

REAL = EXAMPLES / "fl-thermal" / "train_1min.csv"  # 32 h of a real machine, 1 min steps
SENSORS = ["t1_c", "t4_c", "t9_c", "t13_c"]


def test_mlr_is_least_squares_on_real_data():
    cols = read_csv_columns(REAL)
    m = mtec.thermal_fit(REAL, "ch1_um", "mlr", sensors=SENSORS)
    x = np.column_stack([np.ones(len(cols["ch1_um"]))] + [cols[s] for s in SENSORS])
    beta, *_ = np.linalg.lstsq(x, cols["ch1_um"], rcond=None)
    assert m["model"]["intercept_um"] == pytest.approx(beta[0], rel=1e-9)
    np.testing.assert_allclose(m["model"]["coefficients"], beta[1:], rtol=1e-9)
    resid = cols["ch1_um"] - x @ beta
    assert m["train_metrics"]["rmse_um"] == pytest.approx(np.sqrt(np.mean(resid**2)), rel=1e-9)


def test_ridge_with_fixed_k_is_the_augmented_least_squares():
    """Ridge on standardised regressors (docs/methods.md): minimise |y − Zb|² + k|b|²."""
    cols = read_csv_columns(REAL)
    k = 0.5
    m = mtec.thermal_fit(REAL, "ch1_um", "ridge", sensors=SENSORS, k=k)
    y = cols["ch1_um"]
    z = np.column_stack([cols[s] for s in SENSORS])
    n = len(y)
    # one accepted scaling convention: correlation form, columns (x - mean) / (sd·sqrt(n-1))
    zs = (z - z.mean(0)) / (z.std(0, ddof=1) * np.sqrt(n - 1))
    a = np.vstack([zs, np.sqrt(k) * np.eye(len(SENSORS))])
    b, *_ = np.linalg.lstsq(a, np.concatenate([y - y.mean(), np.zeros(len(SENSORS))]), rcond=None)
    beta = b / (z.std(0, ddof=1) * np.sqrt(n - 1))
    np.testing.assert_allclose(m["model"]["coefficients"], beta, rtol=1e-8)


@pytest.mark.parametrize(
    "args",
    [
        ("mlr", ["--sensors", ",".join(SENSORS)], {"sensors": SENSORS}),
        ("ridge", ["--sensors", ",".join(SENSORS), "--lag"], {"sensors": SENSORS, "lag": True}),
        ("heat-input", [], {}),
        # a registry kind the module has no code of its own for (issue 18)
        ("ridge-select", ["--sensors", ",".join(SENSORS)], {"sensors": SENSORS}),
        # a kind added as one file and one registry line (mtec-thermal/src/pls.rs)
        ("pls", ["--sensors", ",".join(SENSORS)], {"sensors": SENSORS}),
    ],
    ids=["mlr", "ridge-lag", "heat-input", "ridge-select", "pls"],
)
def test_model_file_and_predictions_are_the_clis(cli, tmp_path, args):
    model, cli_args, kwargs = args
    # every 4th minute of the real log: the lag and heat-input searches stay quick
    lines = REAL.read_text().splitlines()
    log = tmp_path / "log.csv"
    log.write_text("\n".join(lines[:1] + lines[1::4]) + "\n")
    ours, theirs = tmp_path / "py.json", tmp_path / "cli.json"
    m = mtec.thermal_fit(log, "ch1_um", model, train_until=1200.0, out=ours, **kwargs)
    cli.run("thermal", "fit", "--data", log, "--target", "ch1_um", "--model", model,
            "--train-until", "1200", *cli_args, "-o", theirs)
    assert ours.read_bytes() == theirs.read_bytes()
    assert m == json.loads(ours.read_text())
    assert m["validation"]["folds"], "the forward validation ran"
    ref = cli.json("thermal", "predict", "--model", theirs, "--data", log, "--json")
    p = mtec.thermal_predict(ours, log)
    assert p["predictions"].tolist() == ref["predictions"]
    for k in ("rmse_um", "mae_um", "uncertainty_um", "rows_outside_training_range"):
        assert p[k] == ref[k], k


def test_predict_from_arrays_equals_from_file(tmp_path):
    path = tmp_path / "m.json"
    mtec.thermal_fit(REAL, "ch1_um", "mlr", sensors=SENSORS, out=path)
    cols = read_csv_columns(REAL)
    no_target = {k: v for k, v in cols.items() if not k.endswith("_um")}
    a = mtec.thermal_predict(path, no_target)
    f = mtec.thermal_predict(path, REAL)
    np.testing.assert_array_equal(a["predictions"], f["predictions"])
    assert "rmse_um" not in a and "rmse_um" in f


def test_bad_thermal_input_is_located(tmp_path):
    cols = read_csv_columns(REAL)
    cols["t4_c"][41] = np.nan
    with pytest.raises(mtec.InputError) as e:
        mtec.thermal_fit(cols, "ch1_um", "mlr", sensors=SENSORS)
    assert (e.value.line, e.value.column) == (42, list(cols).index("t4_c") + 1)
    with pytest.raises(mtec.InputError) as e:
        mtec.thermal_fit(REAL, "ch1_um", "mlr", sensors=["nope_c"])
    assert e.value.file == str(REAL) and "nope_c" in e.value.message
    with pytest.raises(ValueError, match="no thermal model `cnn`; the models are auto, mlr"):
        mtec.thermal_fit(REAL, "ch1_um", "cnn")
    with pytest.raises(ValueError, match="goes with --model ridge"):
        mtec.thermal_fit(REAL, "ch1_um", "mlr", k=1.0)
    with pytest.raises(ValueError, match="would overwrite|input"):
        mtec.thermal_fit(REAL, "ch1_um", "mlr", sensors=SENSORS, out=REAL)
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "mtec.thermal-model/1",\n "target": 3}')
    with pytest.raises(mtec.InputError) as e:
        mtec.thermal_predict(bad, REAL)
    assert e.value.file == str(bad) and e.value.line == 2


# ---- sensor selection and forward validation ----


def test_select_is_the_clis(cli, tmp_path):
    """VIF, ridge trace and selection on the real log: the document of `thermal select --json`
    and the three files of `--out`, byte for byte."""
    sensors = ["t1_c", "t4_c", "t6_c", "t9_c", "t13_c"]
    ref = cli.json("thermal", "select", "--data", REAL, "--target", "ch2_um",
                   "--sensors", ",".join(sensors), "--json", "--out", tmp_path / "cli")
    r = mtec.thermal_select(REAL, "ch2_um", sensors=sensors, out=tmp_path / "py")
    assert r["selected"] == ref["selected"] and r["k"] == ref["k"]
    assert r["vif"] == ref["vif"]
    assert r["coefficients"] == ref["coefficients"]
    for f in ("ridge_trace.csv", "ridge_trace.svg", "selection.json"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f


def test_select_vif_is_numpys():
    """VIF_j = 1 / (1 − R²_j), R²_j of sensor j regressed on the others (numpy lstsq)."""
    sensors = ["t1_c", "t4_c", "t6_c", "t9_c", "t13_c"]
    cols = read_csv_columns(REAL)
    x = np.column_stack([cols[s] for s in sensors])
    r = mtec.thermal_select(REAL, "ch1_um", sensors=sensors)
    for j, v in enumerate(r["vif"]):
        others = np.column_stack([np.ones(len(x))] + [x[:, i] for i in range(x.shape[1]) if i != j])
        beta, *_ = np.linalg.lstsq(others, x[:, j], rcond=None)
        res = x[:, j] - others @ beta
        r2 = 1 - res @ res / np.sum((x[:, j] - x[:, j].mean()) ** 2)
        assert v["sensor"] == sensors[j]
        assert v["vif"] == pytest.approx(1 / (1 - r2), rel=1e-8)


@pytest.mark.parametrize("model,args,kwargs", [
    ("mlr", ["--sensors", ",".join(SENSORS)], {"sensors": SENSORS}),
    ("ridge", ["--sensors", ",".join(SENSORS), "--k", "0.1", "--loo", "--block-min", "240"],
     {"sensors": SENSORS, "k": 0.1, "loo": True, "block_min": 240.0}),
], ids=["mlr-forward", "ridge-loo"])
def test_cv_is_the_clis(cli, model, args, kwargs):
    ref = cli.json("thermal", "cv", "--data", REAL, "--target", "ch1_um", "--model", model,
                   *args, "--json")
    r = mtec.thermal_cv(REAL, "ch1_um", model, **kwargs)
    if "per_block" in ref:
        # flat numeric records come back as a dict of arrays (docs/python.md, conventions)
        blocks, ref_blocks = r.pop("per_block"), ref.pop("per_block")
        assert len(ref_blocks) >= 4 and set(blocks) == set(ref_blocks[0])
        for k, col in blocks.items():
            want = [np.nan if b[k] is None else b[k] for b in ref_blocks]
            np.testing.assert_array_equal(col, want, err_msg=k)
    assert r == ref


def test_cv_folds_only_train_on_the_past():
    """Forward folds on arrays: each fold's training rows end before its scored rows begin, and
    the pooled RMSE is that of the scored residuals (an MLR refitted by numpy on each fold)."""
    cols = read_csv_columns(REAL)
    r = mtec.thermal_cv(cols, "ch1_um", "mlr", sensors=SENSORS)
    assert r["protocol"] == "forward" and len(r["folds"]) >= 2
    t, y = cols["time_min"], cols["ch1_um"]
    x = np.column_stack([np.ones(len(t))] + [cols[s] for s in SENSORS])
    sq = []
    for f in r["folds"]:
        assert f["train_to_min"] < f["test_from_min"]
        tr = (t >= f["train_from_min"]) & (t <= f["train_to_min"])
        te = (t >= f["test_from_min"]) & (t <= f["test_to_min"])
        beta, *_ = np.linalg.lstsq(x[tr], y[tr], rcond=None)
        res = y[te] - x[te] @ beta
        assert f["metrics"]["rmse_um"] == pytest.approx(np.sqrt(np.mean(res**2)), rel=1e-8)
        sq.append(res**2)
    assert r["pooled_rmse_um"] == pytest.approx(np.sqrt(np.mean(np.concatenate(sq))), rel=1e-8)


def test_select_and_cv_locate_bad_input(tmp_path):
    with pytest.raises(mtec.InputError) as e:
        mtec.thermal_select({"time_min": [0.0, 1.0, 2.0], "s1_c": [20.0, 20.5, 21.0]}, "dz_um")
    assert "dz_um" in e.value.message
    with pytest.raises(ValueError, match="no thermal model"):
        mtec.thermal_cv(REAL, "ch1_um", "lstm")


# ---- the thermal model at the machine: work-offset updates ----

from conftest import REPO  # noqa: E402

OFFSET_DATA = REPO / "crates" / "mtec-cli" / "tests" / "data" / "thermal_offset"


@pytest.mark.parametrize("fmt,kwargs,golden", [
    ("g10", {"base_mm": -312.4501}, "linuxcnc.ngc"),
    ("fanuc", {"base_mm": -312.4501}, "fanuc.nc"),
    ("fanuc-macro", {"base_mm": -312.4501}, "fanuc_macro.nc"),
    ("sinumerik", {}, "sinumerik_frame.spf"),
], ids=["g10", "fanuc", "fanuc-macro", "sinumerik"])
def test_offset_update_is_the_controllers_golden_text(tmp_path, fmt, kwargs, golden):
    """The goldens were worked from each controller's documentation (their README): the linear
    model e = 12·t1 − 228 µm at t1 = 20 °C now, +12 µm along Z."""
    r = mtec.compensate_thermal_offset(OFFSET_DATA / "machine.json", OFFSET_DATA / "now.csv",
                                       fmt, out=tmp_path / "u.txt", **kwargs)
    want = (OFFSET_DATA / "golden" / golden).read_text()
    assert r["text"] == want
    assert (tmp_path / "u.txt").read_text() == want
    assert r["update"]["drift_um"] == pytest.approx(12.0, abs=1e-9)
    assert r["update"]["correction_um"] == pytest.approx(-12.0, abs=1e-9)


def test_sinumerik_temperature_compensation_is_the_golden():
    r = mtec.compensate_thermal_offset(
        OFFSET_DATA / "exp_machine.json", OFFSET_DATA / "exp_now.csv", "sinumerik-sd",
        starts_at_rest=True, position_origin_mm=-500.0, travel_mm=(-500.0, 0.0))
    assert r["text"] == (OFFSET_DATA / "golden" / "sinumerik_sd.spf").read_text()
    assert r["update"] is None and r["setting"]["position_dependent"]


def test_offset_from_arrays_is_the_clis(cli, tmp_path):
    """A bare thermal model with its training log (README tour, step 4), the temperatures
    now as arrays: the CLI's lines on the same rows written as a file."""
    sim_dir = tmp_path / "t"
    files = mtec.simulate("spindle-sensors", sim_dir, seed=1)
    log = files["thermal.csv"]
    mtec.thermal_fit(log, "radial_um", "mlr", sensors=["s1_c", "s4_c"], out=tmp_path / "m.json")
    cols = read_csv_columns(log)
    last = {k: v[-3:] for k, v in cols.items() if k in ("time_min", "s1_c", "s4_c")}
    now = tmp_path / "now.csv"
    now.write_text("time_min,s1_c,s4_c\n" + "".join(
        f"{float(t)!r},{float(a)!r},{float(b)!r}\n"
        for t, a, b in zip(last["time_min"], last["s1_c"], last["s4_c"])))
    ref = cli.run("compensate", "thermal-offset", "--model", tmp_path / "m.json", "--training",
                  log, "--temps", now, "--axis", "X", "--format", "g10", "--base-mm", "-312.45")
    r = mtec.compensate_thermal_offset(tmp_path / "m.json", last, "g10", axis="X",
                                       training=log, base_mm=-312.45)
    # the second comment names the log and its lines: `<arrays>` rows here, the file's there
    ours, theirs = r["text"].splitlines(), ref.splitlines()
    assert len(ours) == len(theirs) == 4
    assert ours[0] == theirs[0] and ours[2:] == theirs[2:]
    now_min = f"{last['time_min'][-1]:g} min"
    assert f"<arrays> line 3 at {now_min}" in ours[1] and f"now.csv line 4 at {now_min}" in theirs[1]
    assert r["temps"] == "<arrays>" and r["now_line"] == 3


def test_offset_envelope_rule_and_refusals(tmp_path):
    model = OFFSET_DATA / "machine.json"
    # t1 = 27 °C, 1 °C above the training range [18, 26]: refused at its row (the second:
    # line 2 of the arrays) and column, or faded to half (fade width 2 °C): c = −0.5·96 µm
    hot = {"time_min": [0.0, 60.0], "t1_c": [19.0, 27.0]}
    with pytest.raises(mtec.InputError) as e:
        mtec.compensate_thermal_offset(model, hot, base_mm=0.0)
    assert (e.value.file, e.value.line, e.value.column) == ("<arrays>", 2, 2)
    r = mtec.compensate_thermal_offset(model, hot, base_mm=0.0, outside="fade")
    assert r["update"]["weight"] == pytest.approx(0.5)
    assert r["text"].endswith("G10 L2 P1 Z-0.048\n")
    with pytest.raises(ValueError, match="--base-mm is required"):
        mtec.compensate_thermal_offset(model, OFFSET_DATA / "now.csv", "fanuc")
    with pytest.raises(ValueError, match="--base-mm"):
        mtec.compensate_thermal_offset(model, OFFSET_DATA / "now.csv", "sinumerik", base_mm=1.0)
    with pytest.raises(ValueError, match="format `heidenhain`"):
        mtec.compensate_thermal_offset(model, OFFSET_DATA / "now.csv", "heidenhain")
    with pytest.raises(ValueError, match="outside `clamp`"):
        mtec.compensate_thermal_offset(model, OFFSET_DATA / "now.csv", base_mm=0.0,
                                       outside="clamp")
    # never over an input
    before = (OFFSET_DATA / "now.csv").read_bytes()
    with pytest.raises(Exception):
        mtec.compensate_thermal_offset(model, OFFSET_DATA / "now.csv", base_mm=0.0,
                                       out=OFFSET_DATA / "now.csv")
    assert (OFFSET_DATA / "now.csv").read_bytes() == before
