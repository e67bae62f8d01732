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
# Same work, same threads (issue 22 item 1), two comparisons per round:
# - one thread each: one call over all points on each side, thread CPU time (the machine may be
#   shared), best of 3 calls in one process;
# - each at its best: wall time, best of 3 calls, SciPy at its better of one call and the points
#   cut in THREADS runs evaluated by a Python thread pool (NumPy releases the GIL in its loops),
#   mtec at its better of one thread and `eval_batch_threads` on THREADS threads (default: the
#   core count). On a shared machine wall time includes waiting for a core: the load is printed.
# The sides run interleaved ROUNDS times (default 5); printed: each round with the load, the
# median ratios. The outputs (mtec one- and multi-threaded) must agree with SciPy to 1e-9 µm
# (|values| ≤ 4 µm), else the script fails.
# Last result: ARCHITECTURE.md "Measured costs" (issue 22 rows).
# The thread CPU clock of this VM has moved in steps of about 4 ms (4 ns per point at 1 M
# points) at times: the mtec CPU figures may be quantised to those steps.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${VENV:-/tmp/venv-mtec-interp}
ROUNDS=${ROUNDS:-5}
N=${N:-1000000}
THREADS=${THREADS:-$(nproc)}
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

# the SciPy side: the map file's grid and values; best of 3 calls, one thread (thread CPU and
# wall) and the points in THREADS runs on a thread pool (wall)
cat > "$W/scipy_side.py" <<'PY'
import json, sys, time
from concurrent.futures import ThreadPoolExecutor
import numpy as np, scipy
from scipy.interpolate import RegularGridInterpolator
w, threads = sys.argv[1], int(sys.argv[2])
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
wall_t = float("inf")
with ThreadPoolExecutor(threads) as pool:
    for _ in range(3):
        w0 = time.perf_counter()
        out_t = np.concatenate(list(pool.map(interp, np.array_split(pts, threads))))
        wall_t = min(wall_t, time.perf_counter() - w0)
assert np.array_equal(out, out_t), "the thread pool changed SciPy's values"
n = len(pts)
print(f"{cpu / n * 1e9:.3f} {wall / n * 1e9:.3f} {wall_t / n * 1e9:.3f} scipy-{scipy.__version__}")
PY

load() { awk '{print $1}' /proc/loadavg; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", a / b }'; }
min() { awk -v a="$1" -v b="$2" 'BEGIN { print (a < b) ? a : b }'; }
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
SAME=()
BEST=()
echo "grid 25x25x25, $N points; ns/point, best of 3 calls per side and round"
echo "one thread each: thread CPU / wall; at its best: wall, the better of 1 and $THREADS threads"
for r in $(seq 1 "$ROUNDS"); do
  L1=$(load)
  read -r S_CPU S_WALL S_WALLT S_VER <<<"$("$VENV/bin/python" "$W/scipy_side.py" "$W" "$THREADS")"
  read -r M_CPU M_WALL <<<"$("$MTEC" "$W/map.json" "$W/points.f64" "$W/mtec.f64")"
  read -r _ M_WALLT <<<"$("$MTEC" "$W/map.json" "$W/points.f64" "$W/mtec_threads.f64" 3 "$THREADS")"
  S_BEST=$(min "$S_WALL" "$S_WALLT")
  M_BEST=$(min "$M_WALL" "$M_WALLT")
  SAME+=("$(ratio "$S_CPU" "$M_CPU")")
  BEST+=("$(ratio "$S_BEST" "$M_BEST")")
  printf 'round %d (load %s): %s 1 thread %s / %s, %s threads %s; mtec 1 thread %s / %s, %s threads %s; ratio one thread (CPU) %s, at best (wall) %s\n' \
    "$r" "$L1" "$S_VER" "$S_CPU" "$S_WALL" "$THREADS" "$S_WALLT" "$M_CPU" "$M_WALL" "$THREADS" "$M_WALLT" "${SAME[-1]}" "${BEST[-1]}"
done

# the two sides must give the same values (mtec on one and on THREADS threads)
"$VENV/bin/python" - "$W" <<'PY'
import sys
import numpy as np
w = sys.argv[1]
a = np.fromfile(f"{w}/scipy.f64", dtype="<f8")
worst = 0.0
for name in ("mtec", "mtec_threads"):
    b = np.fromfile(f"{w}/{name}.f64", dtype="<f8")
    d = float(np.max(np.abs(a - b))) if len(a) == len(b) else float("inf")
    print(f"agreement: max |SciPy - {name}| = {d:.2e} um over {len(a) // 3} points (tolerance 1e-9 um)")
    worst = max(worst, d)
sys.exit(0 if worst <= 1e-9 else 1)
PY
echo "median ratio SciPy / mtec over $ROUNDS rounds: one thread each (thread CPU) $(median "${SAME[@]}"), each at its best (wall) $(median "${BEST[@]}"); load now $(load)"
