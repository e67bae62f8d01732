#!/usr/bin/env bash
# Ridge trace (100 values of k) and VIF table: mtec-thermal against scikit-learn / statsmodels on
# the real fl-thermal training record. Creates its own venv (not run by CI). Prints both times and
# the ratio (Python time / mtec time; > 1 means mtec is faster).
#
# Usage: bench/thermal.sh [FILE.csv [TARGET]]
# Default file: ../shared/data/fl-thermal/train.csv (15 s sampling, 7709 rows) when present,
# else examples/fl-thermal/train_1min.csv (the 1-min copy in this repository).
set -euo pipefail
cd "$(dirname "$0")/.."
FILE="${1:-}"
if [ -z "$FILE" ]; then
  if [ -f ../shared/data/fl-thermal/train.csv ]; then FILE=../shared/data/fl-thermal/train.csv
  elif [ -f /work/shared/data/fl-thermal/train.csv ]; then FILE=/work/shared/data/fl-thermal/train.csv
  else FILE=examples/fl-thermal/train_1min.csv; fi
fi
TARGET="${2:-ch1_um}"
VENV="${MTEC_BENCH_VENV:-/tmp/mtec-bench-thermal}"
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q numpy pandas scikit-learn statsmodels
fi

cargo build -q --release -p mtec-thermal --example bench_thermal
RUST_OUT="$(cargo run -q --release -p mtec-thermal --example bench_thermal -- "$FILE" "$TARGET")"
echo "mtec-thermal: $RUST_OUT" | tr '\n' ' '; echo

# single-threaded BLAS, like mtec (and no thread oversubscription on a shared machine)
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
PY_OUT="$("$VENV/bin/python" - "$FILE" "$TARGET" <<'PY'
import sys, time
import numpy as np, pandas as pd
import sklearn, statsmodels
from sklearn.linear_model import Ridge
from sklearn.preprocessing import StandardScaler
import statsmodels.api as sm
from statsmodels.stats.outliers_influence import variance_inflation_factor

d = pd.read_csv(sys.argv[1], comment="#")
cols = [c for c in d.columns if c.endswith("_c") and c != "ambient_c"]
X = d[cols].to_numpy(float); y = d[sys.argv[2]].to_numpy(float); n = len(y)
ks = np.concatenate([[0.0], np.logspace(-4, 0, 99)])

def best_of(f):
    best = float("inf"); start = time.perf_counter(); reps = 0
    while reps < 3 or (time.perf_counter() - start < 2.0 and reps < 1000):
        t = time.perf_counter(); f(); best = min(best, time.perf_counter() - t); reps += 1
    return best

def trace():
    # the same work as mtec: standardise, then the standardised coefficients at every k
    Z = StandardScaler().fit_transform(X)
    return [Ridge(alpha=n * k, solver="svd").fit(Z, y).coef_ for k in ks]

def vif():
    Xc = sm.add_constant(X)
    return [variance_inflation_factor(Xc, i) for i in range(1, Xc.shape[1])]

print(f"sklearn={sklearn.__version__} statsmodels={statsmodels.__version__}")
print(f"ridge_trace_s={best_of(trace):.6e}")
print(f"vif_s={best_of(vif):.6e}")
PY
)"
echo "python:       $PY_OUT" | tr '\n' ' '; echo
get() { echo "$1" | sed -n "s/^$2=//p"; }
python3 - "$(get "$RUST_OUT" ridge_trace_s)" "$(get "$PY_OUT" ridge_trace_s)" "$(get "$RUST_OUT" vif_s)" "$(get "$PY_OUT" vif_s)" <<'PY'
import sys
rt, pt, rv, pv = map(float, sys.argv[1:])
print(f"ridge trace (100 k): mtec {rt*1e3:.3f} ms, scikit-learn {pt*1e3:.3f} ms, ratio {pt/rt:.1f}x")
print(f"VIF table:           mtec {rv*1e3:.3f} ms, statsmodels  {pv*1e3:.3f} ms, ratio {pv/rv:.1f}x")
PY
