#!/usr/bin/env bash
# Peer benchmark of `mtec sensitivity` against SALib (the established Python library), same
# method, same N, same model:
#   1. EFAST on the Ishigami function, N = 10000 points per curve, M = 4;
#   2. EFAST on the 18-element first-order error model of an XYFZ machine at one pose,
#      N = 1200 points per curve (the source's sample size), outputs Ex, Ey, Ez, |E|.
# Checks that both agree with each other (and with the analytic Ishigami indices) and prints
# the time ratio SALib / mtec. mtec is timed as a whole process (start-up, sampling, parallel
# evaluation, analysis, JSON output); SALib in-process (sample + numpy evaluation + analyze),
# i.e. without the Python start-up and imports, which favours SALib.
# Creates its own venv (not used by CI). Usage: bash bench/sensitivity.sh
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
VENV="${VENV:-/tmp/venv-mtec-bench-sensitivity}"
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
fi
# SALib 1.5.1 does not work with pandas 3.
"$VENV/bin/pip" install -q "SALib==1.5.1" "pandas<3"
(cd "$ROOT" && cargo build --release -q -p mtec-cli)
MTEC="$ROOT/target/release/mtec"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

cat > "$WORK/machine.toml" <<'EOF'
name = "XYFZ vertical machining centre (bench)"
chain = "WXYFZT"
tool_offset_mm = [0.0, 0.0, 150.0]
[axes.X]
travel = [0.0, 600.0]
[axes.Y]
travel = [0.0, 800.0]
[axes.Z]
travel = [0.0, 300.0]
EOF
# Typical measured statistics (µm, µrad): 18 error motions + 3 squareness errors (fixed).
cat > "$WORK/stats.csv" <<'EOF'
element,mean,std,unit
EXX,6.1,4.2,um
EYX,0.8,1.6,um
EZX,-1.1,1.9,um
EAX,2.0,3.1,urad
EBX,-3.5,5.8,urad
ECX,4.2,6.9,urad
EXY,-0.9,1.4,um
EYY,7.8,5.1,um
EZY,1.3,2.2,um
EAY,-2.7,4.6,urad
EBY,1.9,3.3,urad
ECY,3.1,7.4,urad
EXZ,0.6,1.2,um
EYZ,-1.4,1.7,um
EZZ,5.2,3.6,um
EAZ,1.1,2.9,urad
EBZ,-0.7,2.4,urad
ECZ,2.4,3.8,urad
EC0Y,18.0,0,urad
EB0Z,-25.0,0,urad
EA0Z,12.0,0,urad
EOF

"$VENV/bin/python" - "$MTEC" "$WORK" <<'EOF'
import json, math, subprocess, sys, time
import numpy as np
from SALib.analyze import fast
from SALib.sample import fast_sampler
from SALib.test_functions import Ishigami

mtec, work = sys.argv[1], sys.argv[2]
REPEAT = 5

def best_time(fn):
    best, out = math.inf, None
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out

def run_mtec(args):
    return json.loads(subprocess.run([mtec, "sensitivity", *args, "--json"], check=True,
                                     capture_output=True, text=True).stdout)

ok = True
def check(what, a, b, tol):
    global ok
    d = float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
    flag = "ok" if d <= tol else "DISAGREE"
    ok &= d <= tol
    print(f"  {what:<34} max |diff| = {d:.4f} (tolerance {tol})  {flag}")

# 1. Ishigami, EFAST N = 10000, M = 4
N, M = 10000, 4
t_mtec, r = best_time(lambda: run_mtec(["--function", "ishigami", "--method", "efast",
                                        "--samples", str(N), "--interference", str(M)]))
problem = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-math.pi, math.pi]] * 3}
def salib_ishigami():
    x = fast_sampler.sample(problem, N, M=M, seed=1)
    y = Ishigami.evaluate(x)
    return fast.analyze(problem, y, M=M, seed=1)  # SALib's defaults (100 bootstrap resamples)
t_salib, s = best_time(salib_ishigami)
print(f"Ishigami EFAST N={N} M={M} ({3 * N} evaluations)")
print(f"  mtec S1 {np.round(r['S1'], 4)} ST {np.round(r['ST'], 4)}")
print(f"  SALib S1 {np.round(s['S1'], 4)} ST {np.round(s['ST'], 4)}")
check("S1 mtec vs SALib", r["S1"], s["S1"], 0.02)
check("ST mtec vs SALib", r["ST"], s["ST"], 0.02)
check("S1 mtec vs analytic", r["S1"], r["analytic"]["S1"], 0.02)
check("ST mtec vs analytic", r["ST"], r["analytic"]["ST"], 0.05)
print(f"  time: mtec {t_mtec * 1e3:.1f} ms, SALib {t_salib * 1e3:.1f} ms, ratio SALib/mtec = {t_salib / t_mtec:.1f}x")
ratio_ishigami = t_salib / t_mtec

# 2. The 18-element error model at one pose, EFAST N = 1200, M = 4
N = 1200
args = ["--machine", f"{work}/machine.toml", "--stats", f"{work}/stats.csv", "--method", "efast",
        "--samples", str(N), "--at", "300,400,150"]
t_mtec, r = best_time(lambda: run_mtec(args))
names = r["inputs"]
J = np.array([r["coefficients_um_per_unit"][n] for n in names])  # (18, 3)
stats = {}
for line in open(f"{work}/stats.csv").read().splitlines()[1:]:
    e, mean, std, unit = line.split(",")
    stats[e] = (float(mean), float(std))
fixed = [e for e in stats if stats[e][1] == 0.0]
problem = {"num_vars": len(names), "names": names,
           "bounds": [[stats[n][0], stats[n][1]] for n in names], "dists": ["norm"] * len(names)}
# The fixed squareness errors only shift Ex, Ey, Ez (their indices do not depend on it), so the
# SALib side evaluates J·e of the 18 random elements; it computes |E| too (the same work as mtec)
# but only the linear outputs are compared.
def salib_model():
    x = fast_sampler.sample(problem, N, M=4, seed=1)
    e = x @ J                                   # (rows, 3): Ex, Ey, Ez
    y = np.column_stack([e, np.linalg.norm(e, axis=1)])
    return [fast.analyze(problem, y[:, k].copy(), M=4, seed=1) for k in range(4)]
t_salib, s = best_time(salib_model)
print(f"error model: {len(names)} elements, EFAST N={N} M=4 ({len(names) * N} evaluations, 4 outputs)")
for k, o in enumerate(["Ex", "Ey", "Ez"]):
    mine = r["outputs"][k]
    check(f"{o} S1 mtec vs SALib", mine["S1"], s[k]["S1"], 0.03)
    check(f"{o} ST mtec vs SALib", mine["ST"], s[k]["ST"], 0.03)
top = [k["element"] for k in r["key_errors"][:5]]
print(f"  mtec key errors (S1 of |E|): {top}")
print(f"  time: mtec {t_mtec * 1e3:.1f} ms, SALib {t_salib * 1e3:.1f} ms, ratio SALib/mtec = {t_salib / t_mtec:.1f}x")
ratio_model = t_salib / t_mtec
print()
print(f"RATIO ishigami {ratio_ishigami:.1f}x  error-model {ratio_model:.1f}x  (goal >= 20x)  indices {'agree' if ok else 'DISAGREE'}")
sys.exit(0 if ok else 1)
EOF
