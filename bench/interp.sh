#!/usr/bin/env bash
# Trilinear interpolation speed: mtec's GridMap vs SciPy's RegularGridInterpolator on the same
# grid and the same points. Not run in CI.
#
# Grid: 25 × 25 × 25 nodes over 600 × 400 × 300 mm, values (sin(x/90), cos(y/70), 1e-5·x·y +
# 1e-3·z); points: 100 000 drawn by the same xorshift64 generator as
# crates/mtec-comp/benches/map.rs (so both sides evaluate identical points).
# Prints ns per point (thread CPU time on both sides) and the ratio SciPy / mtec.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${VENV:-/tmp/venv-mtec-interp}
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet scipy numpy
fi

SCIPY_OUT=$("$VENV/bin/python" - <<'PY'
import time
import numpy as np, scipy
from scipy.interpolate import RegularGridInterpolator

def axis(length):
    return np.array([length * i / 24.0 for i in range(25)])
x, y, z = axis(600.0), axis(400.0), axis(300.0)
X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
values = np.stack([np.sin(X / 90.0), np.cos(Y / 70.0), 1e-5 * X * Y + Z * 1e-3], axis=-1)
interp = RegularGridInterpolator((x, y, z), values, method="linear")

# xorshift64 exactly as benches/map.rs
M = (1 << 64) - 1
s = 0x9E3779B97F4A7C15
def u():
    global s
    s ^= (s << 13) & M
    s ^= s >> 7
    s ^= (s << 17) & M
    return (s >> 11) / float(1 << 53)
pts = np.array([[600.0 * u(), 400.0 * u(), 300.0 * u()] for _ in range(100_000)])

# thread CPU time, like the mtec side (the machine may be shared with other jobs)
best = float("inf")
for _ in range(7):
    t0 = time.thread_time(); interp(pts); best = min(best, time.thread_time() - t0)
batch_ns = best / len(pts) * 1e9
# one call per point, as a controller loop would call it
n1 = 2000
t0 = time.thread_time()
for p in pts[:n1]:
    interp(p)
single_ns = (time.thread_time() - t0) / n1 * 1e9
print(f"{batch_ns:.3f} {single_ns:.1f} scipy-{scipy.__version__}")
PY
)
read -r SCIPY_BATCH_NS SCIPY_SINGLE_NS SCIPY_VERSION <<<"$SCIPY_OUT"

# the thread-CPU-time group of benches/map.rs (wall time is distorted on a shared machine)
BENCH_LOG=$(cargo bench -p mtec-comp --bench map -- "trilinear_cpu/grid25_eval_100k_points" 2>&1)
# criterion: "time:   [a unit b unit c unit]" for 100 000 points; take the middle estimate
MTEC_NS=$(echo "$BENCH_LOG" | grep -m1 "time:" | sed -E 's/.*\[[^ ]+ [^ ]+ ([0-9.]+) ([a-zµ]+) .*/\1 \2/' | awk '
  { v=$1; u=$2; f=1; if (u=="ps") f=1e-3; else if (u=="ns") f=1; else if (u=="µs"||u=="us") f=1e3; else if (u=="ms") f=1e6; else if (u=="s") f=1e9;
    printf "%.3f", v*f/100000 }')

echo "grid 25x25x25, 100000 points"
echo "mtec GridMap::error_um          : ${MTEC_NS} ns/point (criterion, thread CPU time, one call per point)"
echo "SciPy RegularGridInterpolator   : ${SCIPY_BATCH_NS} ns/point (one vectorised call, thread CPU time, ${SCIPY_VERSION})"
echo "SciPy, one call per point       : ${SCIPY_SINGLE_NS} ns/point"
awk -v a="$SCIPY_BATCH_NS" -v b="$MTEC_NS" -v c="$SCIPY_SINGLE_NS" 'BEGIN {
  printf "ratio SciPy(vectorised)/mtec    : %.1f\n", a/b;
  printf "ratio SciPy(per point)/mtec     : %.0f\n", c/b }'
