"""The CNN-LSTM of mtec_nn::cnn_lstm rebuilt in PyTorch (same layer names, shapes, gate order,
initialisation bounds, windowing, normalisation, validation split and optimiser), for
bench/cnn_lstm.sh. Usage: python cnn_lstm_torch.py rotary.csv EPOCHS [LR_FINAL_FRACTION [THREADS]]
(THREADS: torch.set_num_threads; default PyTorch's own choice)"""
import sys, time, csv
import numpy as np
import torch
from torch import nn

WINDOW, C, K, H = 16, 16, 3, 32
BATCH, LR, VAL_FRACTION = 64, 3e-3, 0.15
# cosine decay of the step size over the epochs to LR x this fraction (1: constant), as mtec's
# CnnLstmConfig::final_learning_rate_fraction; third argument, default 1
TRAIN, TEST = [1, 2, 4], [3]

path, epochs = sys.argv[1], int(sys.argv[2])
LR_FINAL_FRACTION = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
if len(sys.argv) > 4:
    torch.set_num_threads(int(sys.argv[4]))
torch.manual_seed(42)
rows = list(csv.reader(open(path)))
header, body = rows[0], np.array(rows[1:], dtype=float)
nf = sum(1 for h in header[3:] if h.endswith("_c") or "angle" in h)
no = len(header) - 3 - nf
seqs = {}
for r in body:
    seqs.setdefault((int(r[0]), int(r[1])), []).append(r[3:])
seqs = {k: np.array(v) for k, v in seqs.items()}

train_rows = np.concatenate([v for (e, _), v in seqs.items() if e in TRAIN])
f_mu, f_sd = train_rows[:, :nf].mean(0), train_rows[:, :nf].std(0)
t_mu, t_sd = train_rows[:, nf:].mean(0), train_rows[:, nf:].std(0)
f_sd[f_sd == 0] = 1.0
t_sd[t_sd == 0] = 1.0

def windows(exps, split):
    xs, ys, xv, yv = [], [], [], []
    for (e, _), v in sorted(seqs.items()):
        if e not in exps:
            continue
        f = (v[:, :nf] - f_mu) / f_sd
        t = (v[:, nf:] - t_mu) / t_sd
        n = len(v)
        cut = n - int(round(n * VAL_FRACTION)) if split else n
        for i in range(n):
            idx = [max(i + k + 1 - WINDOW, 0) for k in range(WINDOW)]
            (xs if i < cut else xv).append(f[idx])
            (ys if i < cut else yv).append(t[i])
    as_t = lambda a: torch.tensor(np.array(a), dtype=torch.float32)
    return as_t(xs), as_t(ys), (as_t(xv) if xv else None), (as_t(yv) if yv else None)

class CnnLstm(nn.Module):
    def __init__(self):
        super().__init__()
        self.conv = nn.Conv1d(1, C, K, padding=K // 2)
        self.pool = nn.MaxPool1d(2)
        self.lstm = nn.LSTM(C * (nf // 2), H, batch_first=True)
        self.fc = nn.Linear(H, no)
        for name, p in self.named_parameters():  # mtec's bounds: 1/sqrt(k) conv, 1/sqrt(H) others
            b = 1 / np.sqrt(K) if name.startswith("conv") else 1 / np.sqrt(H)
            nn.init.uniform_(p, -b, b)
    def forward(self, x):
        b, w, f = x.shape
        z = self.pool(torch.relu(self.conv(x.reshape(b * w, 1, f))))
        out, _ = self.lstm(z.reshape(b, w, -1))
        return self.fc(out[:, -1])

xt, yt, xv, yv = windows(TRAIN, True)
xs, ys, _, _ = windows(TEST, False)
model = CnnLstm()
opt = torch.optim.Adam(model.parameters(), lr=LR)
best, best_state = float("inf"), None
t0 = time.perf_counter()
for epoch in range(epochs):
    frac = LR_FINAL_FRACTION + (1 - LR_FINAL_FRACTION) * 0.5 * (1 + np.cos(np.pi * epoch / epochs))
    for g in opt.param_groups:
        g["lr"] = LR * frac
    perm = torch.randperm(len(xt))
    model.train()
    for i in range(0, len(xt), BATCH):
        ids = perm[i:i + BATCH]
        loss = ((model(xt[ids]) - yt[ids]) ** 2).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    with torch.no_grad():
        v = ((model(xv) - yv) ** 2).mean().item()
    if v < best:
        best, best_state = v, {k: t.clone() for k, t in model.state_dict().items()}
elapsed = time.perf_counter() - t0
model.load_state_dict(best_state)
with torch.no_grad():
    pred = model(xs).numpy() * t_sd + t_mu
meas = ys.numpy() * t_sd + t_mu
rmse = float(np.sqrt(((pred - meas) ** 2).mean()))
print(f"PyTorch {torch.__version__}, {torch.get_num_threads()} threads: {epochs} epochs in {elapsed:.2f} s")
print(f"TORCH_SECONDS_PER_EPOCH={elapsed / epochs:.6f}")
print(f"TORCH_TEST_RMSE={rmse:.6f}")
