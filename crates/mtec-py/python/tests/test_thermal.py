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
