#!/usr/bin/env bash
# CNN-LSTM: mtec (candle, CPU) against PyTorch on the same architecture, data, split and
# hyper-parameters. Prints the time-per-epoch ratio and both test RMSEs.
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
# Not run by CI. Needs network access to PyPI for torch (the PyPI wheel; it runs on the CPU).
set -euo pipefail
cd "$(dirname "$0")/.."
EPOCHS="${EPOCHS:-40}"
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
echo "load before training: $(uptime)"
./target/release/examples/"$EXAMPLE" --epochs "$EPOCHS" --fixed --export "$WORK" "${EXTRA[@]}" | tee "$WORK/mtec.txt"
"$VENV/bin/python" bench/cnn_lstm_torch.py "$WORK/rotary.csv" "$EPOCHS" "$LR_FINAL" | tee "$WORK/torch.txt"
echo "load after training: $(uptime)"

mtec_spe=$(grep '^MTEC_SECONDS_PER_EPOCH=' "$WORK/mtec.txt" | cut -d= -f2)
mtec_rmse=$(grep '^MTEC_TEST_RMSE=' "$WORK/mtec.txt" | cut -d= -f2)
torch_spe=$(grep '^TORCH_SECONDS_PER_EPOCH=' "$WORK/torch.txt" | cut -d= -f2)
torch_rmse=$(grep '^TORCH_TEST_RMSE=' "$WORK/torch.txt" | cut -d= -f2)
python3 - "$mtec_spe" "$torch_spe" "$mtec_rmse" "$torch_rmse" <<'PY'
import sys
m, t, mr, tr = map(float, sys.argv[1:])
print(f"time per epoch: mtec {m:.4f} s, PyTorch {t:.4f} s, ratio mtec/PyTorch = {m/t:.2f}")
print(f"test RMSE (exp 3, all channels): mtec {mr:.4f}, PyTorch {tr:.4f}")
PY
