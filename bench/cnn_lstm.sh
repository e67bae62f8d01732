#!/usr/bin/env bash
# CNN-LSTM: mtec (candle, CPU) against PyTorch on the same architecture, data, split and
# hyper-parameters. Prints the time-per-epoch ratio and both test RMSEs.
#
# Data: the synthetic rotary-axis thermal model of mtec_nn::synthetic (24 angles × 49 steps ×
# 4 experiments; T1..T9, cos/sin of the angle → EXC, EYC, EZC, EAC, EBC), exported by the
# `rotary_cnn_lstm` example. Train on experiments 1, 2, 4, test on 3. Both sides train a fixed
# number of epochs (no early stopping) and keep the weights of the best validation epoch.
#
# Not run by CI. Needs network access to PyPI for torch (the PyPI wheel; it runs on the CPU).
set -euo pipefail
cd "$(dirname "$0")/.."
EPOCHS="${EPOCHS:-40}"
VENV="${VENV:-/tmp/venv-mtec-bench-torch}"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet torch numpy
fi

cargo build --release -p mtec-nn --example rotary_cnn_lstm
./target/release/examples/rotary_cnn_lstm --epochs "$EPOCHS" --fixed --export "$WORK" | tee "$WORK/mtec.txt"
"$VENV/bin/python" bench/cnn_lstm_torch.py "$WORK/rotary.csv" "$EPOCHS" | tee "$WORK/torch.txt"

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
