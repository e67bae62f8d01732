#!/usr/bin/env bash
# CNN-LSTM: mtec (its own forward/backward kernel, mtec_nn::cnn_lstm_kernel, one thread) against
# PyTorch on the same architecture, data, split and hyper-parameters. Prints the time per epoch
# of every run, the median ratios and both test RMSEs.
#
# Data (DATA=dbb-rotary, the default): the virtual machine's `dbb-rotary` campaign (seed 2),
# error motions identified by the ballbar method, one sequence per experiment and angle (72 angles
# x 13 measurement times x 4 experiments; T1..T9 + the angle's harmonics cos/sin(kC), k = 1..3
# (HARMONICS=0: angle_deg) -> EXC, EYC, EZC, EAC, EBC),
# exported by the `dbb_rotary_cnn_lstm` example. DATA=synthetic uses the analytic model of
# mtec_nn::synthetic instead (24 angles x 49 steps; `rotary_cnn_lstm` example). Train on
# experiments 1, 2, 4, test on 3. Both sides train a fixed number of epochs (no early stopping)
# and keep the weights of the best validation epoch.
#
# Issue 22, build item 1: ROUNDS interleaved rounds (default 3), each running mtec (one thread:
# the kernel is single-threaded, which is also its best), PyTorch with one thread and PyTorch
# with 2 threads (this machine's cores); the load is printed before every round. Reported: the
# median over rounds of mtec / PyTorch-1-thread ("one thread each") and of mtec / the better of
# PyTorch's two runs in that round ("each at its best"). Times are wall clock per epoch as each
# side measures its training loop (validation pass included on both sides).
#
# Not run by CI. Needs network access to PyPI for torch (the PyPI wheel; it runs on the CPU).
set -euo pipefail
cd "$(dirname "$0")/.."
EPOCHS="${EPOCHS:-40}"
ROUNDS="${ROUNDS:-3}"
DATA="${DATA:-dbb-rotary}"
HARMONICS="${HARMONICS:-3}"
EXTRA=()
LR_FINAL=1
case "$DATA" in
  # the dbb-rotary example decays the step size to 5 % (cosine); the synthetic one keeps it
  dbb-rotary) EXAMPLE=dbb_rotary_cnn_lstm; LR_FINAL=0.05
    [ "$HARMONICS" -gt 0 ] && EXTRA=(--harmonics "$HARMONICS") ;;
  synthetic) EXAMPLE=rotary_cnn_lstm ;;
  *) echo "DATA must be dbb-rotary or synthetic" >&2; exit 2 ;;
esac
VENV="${VENV:-/tmp/venv-mtec-bench-torch}"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet torch numpy
fi

cargo build --release -p mtec-nn --example "$EXAMPLE"
BIN="${CARGO_TARGET_DIR:-target}/release/examples/$EXAMPLE"
val() { grep "^$1=" "$2" | cut -d= -f2; }
: > "$WORK/rows"
for r in $(seq 1 "$ROUNDS"); do
  echo "round $r, load: $(uptime)"
  "$BIN" --epochs "$EPOCHS" --fixed --export "$WORK" "${EXTRA[@]}" > "$WORK/mtec.txt"
  grep '^CNN-LSTM:' "$WORK/mtec.txt" || true
  "$VENV/bin/python" bench/cnn_lstm_torch.py "$WORK/rotary.csv" "$EPOCHS" "$LR_FINAL" 1 > "$WORK/t1.txt"
  "$VENV/bin/python" bench/cnn_lstm_torch.py "$WORK/rotary.csv" "$EPOCHS" "$LR_FINAL" 2 > "$WORK/t2.txt"
  head -n 1 "$WORK/t1.txt"; head -n 1 "$WORK/t2.txt"
  echo "$(val MTEC_SECONDS_PER_EPOCH "$WORK/mtec.txt") $(val TORCH_SECONDS_PER_EPOCH "$WORK/t1.txt") $(val TORCH_SECONDS_PER_EPOCH "$WORK/t2.txt") $(val MTEC_TEST_RMSE "$WORK/mtec.txt") $(val TORCH_TEST_RMSE "$WORK/t1.txt") $(val TORCH_TEST_RMSE "$WORK/t2.txt")" >> "$WORK/rows"
done
echo "load after: $(uptime)"
python3 - "$WORK/rows" <<'PY'
import sys, statistics as st
rows = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
for i, (m, t1, t2, *_ ) in enumerate(rows, 1):
    print(f"round {i}: s/epoch mtec {m:.4f}, PyTorch 1 thread {t1:.4f}, 2 threads {t2:.4f}")
one = st.median(m / t1 for m, t1, t2, *_ in rows)
best = st.median(m / min(t1, t2) for m, t1, t2, *_ in rows)
med = lambda k: st.median(r[k] for r in rows)
print(f"time per epoch, medians: mtec {med(0):.4f} s, PyTorch 1 thread {med(1):.4f} s, 2 threads {med(2):.4f} s")
print(f"ratio mtec/PyTorch, median over rounds: one thread each {one:.2f}, each at its best {best:.2f} (goal <= 0.5)")
print(f"test RMSE (exp 3, all channels), medians: mtec {med(3):.4f}, PyTorch 1 thread {med(4):.4f}, 2 threads {med(5):.4f}")
PY
