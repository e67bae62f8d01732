#!/usr/bin/env bash
# Ridge trace (100 values of k) and VIF table (16 sensors): mtec-thermal against its Python peers
# on the real fl-thermal training record (issue #22), the same work on both sides:
#   ridge trace: the standardised coefficients at the 100 k of mtec's grid, from standardised
#     sensors; peers (a) ONE vectorised scikit-learn call, Ridge(alpha = n·k, solver="svd") on
#     100 copies of the target (one alpha per target), (b) numpy, one SVD of the standardised
#     design and the 100 shrinkages vectorised;
#   VIF: peer numpy diag(inv(corrcoef)) (and statsmodels' auxiliary regressions, for reference).
# One thread on both sides (OPENBLAS/OMP/MKL_NUM_THREADS=1; mtec-thermal is single-threaded).
# Each side's time is its best of repeated calls in one process (2 s budget); the sides run
# interleaved for ROUNDS rounds and the median of the per-round ratios is reported. Outputs are
# compared: trace coefficients within 1e-6 (relative to the largest), VIF within 1e-6 relative.
# Prints the load (uptime) before and after. Creates its own venv (not run by CI).
#
# Usage: bench/thermal.sh [ROUNDS [FILE.csv [TARGET]]]
# Default file: ../shared/data/fl-thermal/train.csv (15 s sampling, 7709 rows) when present,
# else examples/fl-thermal/train_1min.csv (the 1-min copy in this repository).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-5}"
FILE="${2:-}"
if [ -z "$FILE" ]; then
  if [ -f ../shared/data/fl-thermal/train.csv ]; then FILE=../shared/data/fl-thermal/train.csv
  elif [ -f /work/shared/data/fl-thermal/train.csv ]; then FILE=/work/shared/data/fl-thermal/train.csv
  else FILE=examples/fl-thermal/train_1min.csv; fi
fi
TARGET="${3:-ch1_um}"
VENV="${MTEC_BENCH_VENV:-/tmp/mtec-bench-thermal}"
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q numpy pandas scikit-learn statsmodels
fi
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
cargo build -q --release -p mtec-thermal --example bench_thermal
TARGET_DIR="$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')"
echo "load before: $(uptime)"
rc=0
"$VENV/bin/python" - "$FILE" "$TARGET" "$ROUNDS" "$TARGET_DIR/release/examples/bench_thermal" <<'PY' || rc=$?
import json, subprocess, sys, time
import numpy as np, pandas as pd
import sklearn, statsmodels
from sklearn.linear_model import Ridge
from sklearn.preprocessing import StandardScaler
import statsmodels.api as sm
from statsmodels.stats.outliers_influence import variance_inflation_factor

path, target, rounds, exe = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
d = pd.read_csv(path, comment="#")
cols = [c for c in d.columns if c.endswith("_c") and c != "ambient_c"]
X = d[cols].to_numpy(float); y = d[target].to_numpy(float); n = len(y)
print(f"{path}: {n} rows, {len(cols)} sensors; numpy {np.__version__}, scikit-learn "
      f"{sklearn.__version__}, statsmodels {statsmodels.__version__}")

def best_of(f):
    best = float("inf"); start = time.perf_counter(); reps = 0
    while reps < 3 or (time.perf_counter() - start < 2.0 and reps < 1000):
        t = time.perf_counter(); f(); best = min(best, time.perf_counter() - t); reps += 1
    return best

def mtec():
    out = subprocess.run([exe, path, target], check=True, capture_output=True, text=True).stdout
    kv = dict(l.split("=", 1) for l in out.splitlines() if "=" in l)
    return float(kv["ridge_trace_s"]), float(kv["vif_s"]), json.loads(kv["outputs"])

ks = np.array(mtec()[2]["k"])

def trace_sklearn():
    # one call: 100 targets (copies of y), one alpha each; coef_ / std(y) = standardised
    Z = StandardScaler().fit_transform(X)
    return Ridge(alpha=n * ks, solver="svd").fit(Z, np.repeat(y[:, None], len(ks), 1)).coef_ / y.std()

def trace_numpy():
    # one SVD of the standardised design; β*(k) = V diag(s/(s² + n·k)) Uᵀ(y − ȳ)/std(y)
    Z = (X - X.mean(0)) / X.std(0)
    u, s, vt = np.linalg.svd(Z, full_matrices=False)
    uty = u.T @ ((y - y.mean()) / y.std())
    return (s / (s**2 + n * ks[:, None]) * uty) @ vt

def vif_numpy():
    return np.diag(np.linalg.inv(np.corrcoef(X, rowvar=False)))

def vif_statsmodels():
    Xc = sm.add_constant(X)
    return [variance_inflation_factor(Xc, i) for i in range(1, Xc.shape[1])]

ok = True
def check(what, a, b, tol):
    global ok
    a, b = np.asarray(a), np.asarray(b)
    err = float(np.max(np.abs(a - b)) / np.max(np.abs(b)))
    ok &= err <= tol
    print(f"  {what:<40} max rel diff {err:.1e} (tolerance {tol:g}) {'ok' if err <= tol else 'DISAGREE'}")

_, _, out = mtec()
print("outputs:")
check("trace mtec vs scikit-learn (one call)", out["trace"], trace_sklearn(), 1e-6)
check("trace mtec vs numpy (one SVD)", out["trace"], trace_numpy(), 1e-6)
check("VIF mtec vs numpy diag(inv(corr))", out["vif"], vif_numpy(), 1e-6)
check("VIF mtec vs statsmodels", out["vif"], vif_statsmodels(), 1e-6)

rows = {"trace/sklearn": [], "trace/numpy": [], "vif/numpy": [], "vif/statsmodels": []}
times = {k: [] for k in ["mtec trace", "mtec vif", "sklearn", "numpy svd", "numpy vif", "statsmodels"]}
for _ in range(rounds):
    mt, mv, _ = mtec()
    ts, tn, tv, tsm = best_of(trace_sklearn), best_of(trace_numpy), best_of(vif_numpy), best_of(vif_statsmodels)
    for k, v in zip(times, [mt, mv, ts, tn, tv, tsm]):
        times[k].append(v)
    rows["trace/sklearn"].append(ts / mt); rows["trace/numpy"].append(tn / mt)
    rows["vif/numpy"].append(tv / mv); rows["vif/statsmodels"].append(tsm / mv)
med = {k: float(np.median(v)) * 1e3 for k, v in times.items()}
print(f"times (median of {rounds} rounds' best, ms): " + ", ".join(f"{k} {v:.3f}" for k, v in med.items()))
goals = {"trace/sklearn": 10, "trace/numpy": 2, "vif/numpy": 2, "vif/statsmodels": None}
for k, v in rows.items():
    g = goals[k]
    r = float(np.median(v))
    print(f"RATIO {k:<16} {r:6.1f}x  (per round {[round(x, 1) for x in v]})"
          + (f"  goal >= {g}x: {'met' if r >= g else 'NOT met'}" if g else ""))
sys.exit(0 if ok else 1)
PY
echo "load after: $(uptime)"
exit $rc
