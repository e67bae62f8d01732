#!/usr/bin/env bash
# G-code rewriting throughput (issue 22): `mtec_comp::gcode::rewrite` on a program held in
# memory (crates/mtec-comp/examples/gcode_rewrite.rs; no file reading or writing timed), with
# the zero model (every line passes through unchanged) and with a 25 × 25 × 3 trilinear map
# (every line compensated, the exact path bound included). Reference: `cat` of the same file
# (wall time).
# Not run in CI. Standard-library Python only (no venv).
#
# Program: the criterion bench's (crates/mtec-comp/benches/gcode.rs): N lines
# `N<k> G01 X<50 cos a> Y<50 sin a>` with a = 0.001·k (0.05 mm moves on a 50 mm circle), after
# three setup lines. Map: the criterion bench's 25 × 25 × 3 grid (5 mm cells, −60…60 mm in x and
# y, −5…5 mm in z; ex = 8 + 0.03x − 0.01y + 2e-4·xy, ey = −4 + 0.02y + 1e-4·x², ez = 3 + 0.01z).
# Each round runs the three sides one after the other (interleaved), each rewrite the best of
# REPEATS (default 3) in one process, thread CPU time (the machine may be shared) and wall time.
# Checks: the zero-model output is byte-identical to the input; the map output is the same in
# every round. Printed: each round with the load, the median M lines/s (CPU) of each side.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${ROUNDS:-5}
N=${N:-1000000}
REPEATS=${REPEATS:-3}
cargo build --quiet --release -p mtec-comp --example gcode_rewrite
TARGET=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')
REWRITE="$TARGET/release/examples/gcode_rewrite"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT

python3 - "$W" "$N" <<'PY'
import json, math, sys
w, n = sys.argv[1], int(sys.argv[2])
xs = [-60.0 + 5.0 * i for i in range(25)]
zs = [-5.0, 0.0, 5.0]
ex, ey, ez = [], [], []
for x in xs:
    for y in xs:
        for z in zs:
            ex.append(8.0 + 0.03 * x - 0.01 * y + 2e-4 * x * y)
            ey.append(-4.0 + 0.02 * y + 1e-4 * x * x)
            ez.append(3.0 + 0.01 * z)
json.dump({"format": "mtec.map/1", "model": "trilinear", "outside": "clamp", "source": "bench",
           "x_mm": xs, "y_mm": xs, "z_mm": zs, "ex_um": ex, "ey_um": ey, "ez_um": ez},
          open(f"{w}/map.json", "w"))
with open(f"{w}/prog.ngc", "w") as f:
    f.write("G21 G90 G17\nG0 X50 Y0 Z1\nG1 Z-1 F1000\n")
    for i in range(n):
        a = i * 0.001
        f.write(f"N{i + 10} G01 X{50 * math.cos(a):.4f} Y{50 * math.sin(a):.4f}\n")
PY
LINES=$(wc -l <"$W/prog.ngc")

load() { awk '{print $1}' /proc/loadavg; }
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
cat_rate() {
  # M lines/s of `cat FILE > /dev/null`, best of REPEATS, wall time (cat's CPU time is below the
  # 10 ms resolution of its rusage on this machine)
  local best=0
  for _ in $(seq 1 "$REPEATS"); do
    local t0 t1
    t0=$(date +%s.%N)
    cat "$W/prog.ngc" >/dev/null
    t1=$(date +%s.%N)
    best=$(awk -v l="$LINES" -v a="$t0" -v b="$t1" -v m="$best" 'BEGIN { r = l / (b - a) / 1e6; print (r > m) ? r : m }')
  done
  echo "$best"
}
ZERO=()
MAP=()
CAT=()
echo "program: $LINES lines, $(wc -c <"$W/prog.ngc") bytes; M lines/s, thread CPU (wall), best of $REPEATS per round"
for r in $(seq 1 "$ROUNDS"); do
  L1=$(load)
  read -r _ _ _ Z_CPU Z_WALL <<<"$("$REWRITE" zero "$W/prog.ngc" "$W/zero.ngc" "$REPEATS")"
  cmp -s "$W/zero.ngc" "$W/prog.ngc" || { echo "the zero model changed the program" >&2; exit 1; }
  read -r _ _ _ M_CPU M_WALL <<<"$("$REWRITE" "$W/map.json" "$W/prog.ngc" "$W/map.ngc" "$REPEATS")"
  if [ "$r" -eq 1 ]; then cp "$W/map.ngc" "$W/map_first.ngc"; fi
  cmp -s "$W/map.ngc" "$W/map_first.ngc" || { echo "the map output differs between rounds" >&2; exit 1; }
  C=$(cat_rate)
  ZERO+=("$Z_CPU")
  MAP+=("$M_CPU")
  CAT+=("$C")
  printf 'round %d (load %s): pass-through (zero model) %s (%s), trilinear map %s (%s), cat %s\n' \
    "$r" "$L1" "$Z_CPU" "$Z_WALL" "$M_CPU" "$M_WALL" "$C"
done
echo "median M lines/s over $ROUNDS rounds: pass-through $(median "${ZERO[@]}"), trilinear map $(median "${MAP[@]}"), cat $(median "${CAT[@]}"); load now $(load)"
