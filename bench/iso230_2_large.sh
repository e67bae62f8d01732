#!/usr/bin/env bash
# Streaming reader cost (issue 20): a 100 MB ISO 230-2 run file through the release
# `mtec iso230-2`, and a file with a bad value on line 102 followed by 100 MB. Not run in CI.
#
# The run file: 2001 targets (0 to 1000 mm every 0.5 mm), RUNS runs in each direction (default
# 1350, about 105 MB), deviation 5 sin(P/100 mm) + 0.002 P + noise µm, +2 µm reversal on the
# way down, written by awk with a fixed seed. Goals (issue 20): under 10 s and under 200 MB
# peak RSS for the large file, under 1 s for the early bad line.
# Prints wall time and peak RSS (/usr/bin/time -v) of each, and the machine load (uptime),
# since the machine may be shared with other jobs.
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${RUNS:-1350}
TARGET_DIR=${CARGO_TARGET_DIR:-target}
cargo build --release -p mtec-cli --quiet
BIN=$TARGET_DIR/release/mtec
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT

awk -v runs="$RUNS" 'BEGIN {
  srand(1)
  print "target_mm,run,direction,deviation_um"
  for (r = 1; r <= runs; r++) {
    for (i = 0; i <= 2000; i++) {
      t = i * 0.5
      printf "%.1f,%d,+,%.4f\n", t, r, 5 * sin(t / 100) + 0.002 * t + rand() - 0.5
    }
    for (i = 2000; i >= 0; i--) {
      t = i * 0.5
      printf "%.1f,%d,-,%.4f\n", t, r, 5 * sin(t / 100) + 0.002 * t + 2 + rand() - 0.5
    }
  }
}' > "$DIR/large.csv"
# the same file with a deviation that is not a number on line 102
awk 'NR == 102 { print "50.0,1,+,1.2.3"; next } { print }' "$DIR/large.csv" > "$DIR/bad.csv"

measure() { # label, expected exit code, file
  local label=$1 want=$2 file=$3 rc=0
  /usr/bin/time -v "$BIN" iso230-2 "$file" --out "$DIR/out" \
    > "$DIR/stdout" 2> "$DIR/time" || rc=$?
  if [ "$rc" != "$want" ]; then
    echo "$label: exit code $rc, expected $want" >&2
    cat "$DIR/time" >&2
    exit 1
  fi
  local wall rss user sys
  wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$DIR/time")
  rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$DIR/time")
  user=$(sed -n 's/.*User time (seconds): //p' "$DIR/time")
  sys=$(sed -n 's/.*System time (seconds): //p' "$DIR/time")
  printf '%-32s wall %s  CPU %s s user + %s s sys  peak RSS %d MB\n' \
    "$label" "$wall" "$user" "$sys" $((rss * 1024 / 1000000))
}

echo "file: $(($(stat -c %s "$DIR/large.csv") / 1000000)) MB, $(wc -l < "$DIR/large.csv") lines"
echo "load before: $(uptime)"
measure "iso230-2, whole file" 0 "$DIR/large.csv"
grep -m1 'A  accuracy' "$DIR/stdout"
measure "iso230-2, bad value on line 102" 2 "$DIR/bad.csv"
grep -m1 'bad.csv:102:4' "$DIR/time" || { echo "error not at line 102" >&2; exit 1; }
echo "load after:  $(uptime)"
