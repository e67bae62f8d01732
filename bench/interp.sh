#!/usr/bin/env bash
# Trilinear interpolation speed: mtec's batch call (ErrorModel::eval_batch, through
# crates/mtec-comp/examples/map_batch.rs) vs SciPy's RegularGridInterpolator, one vectorised call
# each, on the same grid and the same 1 M points. Not run in CI; SciPy and NumPy are installed
# here into a venv ($VENV), never by CI.
#
# Grid: 25 × 25 × 25 nodes over 600 × 400 × 300 mm (a controller-size grid), values (sin(x/90),
# cos(y/70), 1e-5·x·y + 1e-3·z), written once as an mtec.map/1 file that both sides read; points:
# 1 M drawn uniformly inside the box by NumPy (seed 22), handed to both sides as the same f64
# bytes.
# Same work, same threads: one call over all points, one thread on each side (neither has a
# multi-threaded mode, so "each at its best" is the same run). Each side reports the best of 3
# calls in one process, thread CPU time (the machine may be shared) and wall time. The sides
# run interleaved ROUNDS times (default 5); printed: each round with the load, the median
# ratio. The outputs must agree to 1e-9 µm (|values| ≤ 4 µm), else the script fails.
# Last result (2026-11-27, load 6.2–6.35, after the block kernel of issue 22): mtec 15.8–23.9
# ns, SciPy 1.17.1 359–390 ns per point, median ratio 22.6× (ARCHITECTURE.md "Measured costs").
# The thread CPU clock of this VM moves in steps of about 4 ms (4 ns per point at 1 M points):
# the mtec figures are quantised to those steps.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${VENV:-/tmp/venv-mtec-interp}
ROUNDS=${ROUNDS:-5}
N=${N:-1000000}
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet scipy numpy
fi
cargo build --quiet --release -p mtec-comp --example map_batch
TARGET=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')
MTEC="$TARGET/release/examples/map_batch"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT

# the grid (as a map file) and the points, once
"$VENV/bin/python" - "$W" "$N" <<'PY'
import json, sys
import numpy as np
w, n = sys.argv[1], int(sys.argv[2])
axis = lambda length: [length * i / 24.0 for i in range(25)]
x, y, z = axis(600.0), axis(400.0), axis(300.0)
X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
v = [np.sin(X / 90.0), np.cos(Y / 70.0), 1e-5 * X * Y + Z * 1e-3]
json.dump({"format": "mtec.map/1", "model": "trilinear", "outside": "clamp", "source": "bench",
           "x_mm": x, "y_mm": y, "z_mm": z,
           "ex_um": v[0].ravel().tolist(), "ey_um": v[1].ravel().tolist(),
           "ez_um": v[2].ravel().tolist()}, open(f"{w}/map.json", "w"))
rng = np.random.default_rng(22)
pts = rng.random((n, 3)) * np.array([600.0, 400.0, 300.0])
pts.astype("<f8").tofile(f"{w}/points.f64")
PY

# the SciPy side: the map file's grid and values, one vectorised call, best of 3
cat > "$W/scipy_side.py" <<'PY'
import json, sys, time
import numpy as np, scipy
from scipy.interpolate import RegularGridInterpolator
w = sys.argv[1]
m = json.load(open(f"{w}/map.json"))
axes = (np.array(m["x_mm"]), np.array(m["y_mm"]), np.array(m["z_mm"]))
shape = tuple(len(a) for a in axes)
values = np.stack([np.array(m[k]).reshape(shape) for k in ("ex_um", "ey_um", "ez_um")], axis=-1)
interp = RegularGridInterpolator(axes, values, method="linear")
pts = np.fromfile(f"{w}/points.f64", dtype="<f8").reshape(-1, 3)
cpu, wall = float("inf"), float("inf")
for _ in range(3):
    c0, w0 = time.thread_time(), time.perf_counter()
    out = interp(pts)
    cpu, wall = min(cpu, time.thread_time() - c0), min(wall, time.perf_counter() - w0)
out.astype("<f8").tofile(f"{w}/scipy.f64")
n = len(pts)
print(f"{cpu / n * 1e9:.3f} {wall / n * 1e9:.3f} scipy-{scipy.__version__}")
PY

load() { awk '{print $1}' /proc/loadavg; }
RATIOS=()
echo "grid 25x25x25, $N points, one call per side, one thread each; ns/point (thread CPU / wall), best of 3 calls"
for r in $(seq 1 "$ROUNDS"); do
  L1=$(load)
  read -r S_CPU S_WALL S_VER <<<"$("$VENV/bin/python" "$W/scipy_side.py" "$W")"
  read -r M_CPU M_WALL <<<"$("$MTEC" "$W/map.json" "$W/points.f64" "$W/mtec.f64")"
  RATIO=$(awk -v a="$S_CPU" -v b="$M_CPU" 'BEGIN { printf "%.1f", a / b }')
  RATIOS+=("$RATIO")
  printf 'round %d (load %s): SciPy %s %s / %s, mtec eval_batch %s / %s, ratio (CPU) %s\n' \
    "$r" "$L1" "$S_VER" "$S_CPU" "$S_WALL" "$M_CPU" "$M_WALL" "$RATIO"
done

# the two sides must give the same values
"$VENV/bin/python" - "$W" <<'PY'
import sys
import numpy as np
w = sys.argv[1]
a, b = np.fromfile(f"{w}/scipy.f64", dtype="<f8"), np.fromfile(f"{w}/mtec.f64", dtype="<f8")
d = float(np.max(np.abs(a - b))) if len(a) == len(b) else float("inf")
print(f"agreement: max |SciPy - mtec| = {d:.2e} um over {len(a) // 3} points (tolerance 1e-9 um)")
sys.exit(0 if d <= 1e-9 else 1)
PY
MEDIAN=$(printf '%s\n' "${RATIOS[@]}" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')
echo "median ratio SciPy / mtec (thread CPU): $MEDIAN over $ROUNDS rounds; load now $(load)"
