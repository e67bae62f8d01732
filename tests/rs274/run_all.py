#!/usr/bin/env python3
"""Runs `mtec compensate gcode` on every real and hand-written program with several non-zero
maps and checks every compensated program with check.py (LinuxCNC's rs274 as the reference).

    python3 tests/rs274/run_all.py --mtec target/debug/mtec --shared ../shared/data/gcode/linuxcnc

Maps (written here as mtec.map/1 JSON, never by mtec):
  tilt       an almost constant error (20, -15, 10 um plus 1-2 um per metre): arcs stay arcs
  smooth     20-40 um of smooth variation over +-1000 mm (100 mm cells, outside = extrapolate)
  bump-line  zero everywhere but one node: 30 um across the program's longest straight feed
  bump-arc   the same on the program's longest arc (programs with arcs only)
  clamp      a small 5x5x5 grid in the middle of the program (outside = clamp): most points
             are outside and take the value of the nearest point of the box

Per program options: a comment `(mtec-options: ...)` in the first lines is passed to mtec
(paths relative to the program's folder); `--offsets`, `--tool-table`, `--tolerance-um` and
`--chord-tolerance-um` are also given to the checker. Unless a program sets
`--start-position-mm`, mtec is told the machine starts at 0,0,0: where rs274 starts.

Outcomes: ok (written and checked), refused (mtec exit 2 with file:line:column; not a checker
failure), WRONG (written with exit 0 but the check fails), CRASH (mtec exit 1 or a checker
exception). The last line reads `N passed, M failed`; failures are WRONG and CRASH.
"""

import argparse
import concurrent.futures
import glob
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import check  # noqa: E402  (the checker next to this file)

HERE = os.path.dirname(os.path.abspath(__file__))
OPTIONS_RE = re.compile(r"\(\s*mtec-options:\s*([^)]*)\)")
CHECKER_OPTIONS = {"--offsets": "offsets", "--tool-table": "tool_table"}


# --------------------------------------------------------------------------------------------
# maps


def write_map(path, axes, values, outside):
    """values(x, y, z) -> (ex, ey, ez) um, written in C order: (i*ny + j)*nz + k."""
    ex, ey, ez = [], [], []
    for x in axes[0]:
        for y in axes[1]:
            for z in axes[2]:
                e = values(x, y, z)
                ex.append(round(e[0], 6))
                ey.append(round(e[1], 6))
                ez.append(round(e[2], 6))
    doc = {"format": "mtec.map/1", "model": "trilinear", "outside": outside,
           "source": "tests/rs274/run_all.py", "x_mm": axes[0], "y_mm": axes[1], "z_mm": axes[2],
           "ex_um": ex, "ey_um": ey, "ez_um": ez}
    with open(path, "w", encoding="utf-8") as f:
        json.dump(doc, f)


def smooth_error(x, y, z):
    # long waves: 20-40 um of variation over a few hundred mm
    t = 2 * math.pi
    return (12 * math.sin(t * x / 400) + 8 * math.cos(t * y / 300) + 0.01 * z,
            10 * math.sin(t * (x + y) / 500) - 7 * math.cos(t * z / 350),
            9 * math.cos(t * x / 450) * math.sin(t * y / 380) + 5)


def write_smooth_map(path):
    axis = [float(v) for v in range(-1000, 1001, 100)]
    write_map(path, [axis, axis, axis], smooth_error, "extrapolate")


def tilt_error(x, y, z):
    # nearly constant: the correction hardly varies along an arc, so a rewriter keeps arcs
    return (20 + 0.002 * x, -15 + 0.001 * y, 10 + 0.001 * z)


def write_tilt_map(path):
    # a linear function is reproduced exactly by trilinear interpolation on one cell
    axis = [-5000.0, 5000.0]
    write_map(path, [axis, axis, axis], tilt_error, "clamp")


def perpendicular(d):
    """A unit vector across direction d."""
    ref = (0.0, 0.0, 1.0) if abs(d[2]) < 0.9 * check.norm(d) else (1.0, 0.0, 0.0)
    c = check.cross(d, ref)
    return check.scale(c, 1.0 / check.norm(c))


def write_bump_map(path, node, direction, h=2.0, size_um=30.0):
    """Zero everywhere except one node (30 um along `direction`); cells of h mm around it."""
    axes = []
    for a in range(3):
        # the box reaches 1000 mm past the node: a program may run beyond +-5000 mm (LinuxCNC's
        # tests/interp/good/good-arc.big.imperial.* reaches 15 m)
        near = [node[a] + k * h for k in range(-3, 4)]
        axes.append([min(-5000.0, near[0] - 1000.0)] + near + [max(5000.0, near[-1] + 1000.0)])

    def values(x, y, z):
        if (x, y, z) == tuple(node):
            return check.scale(direction, size_um)
        return (0.0, 0.0, 0.0)

    write_map(path, axes, values, "clamp")


def bump_on_line(moves):
    feeds = [m for m in moves if m.kind == "feed" and m.geom.kind == "line"]
    if not feeds:
        return None
    m = max(feeds, key=lambda m: m.length)
    if m.length < 1.0:
        return None
    d = check.sub(m.end, m.start)
    across = perpendicular(d)
    node = check.add(m.geom.point(0.4 * m.length), check.scale(across, 0.3))
    return [round(v, 4) for v in node], across


def bump_on_arc(moves):
    arcs = [m for m in moves if m.kind == "feed" and m.geom.kind == "arc"]
    if not arcs:
        return None
    m = max(arcs, key=lambda m: m.length)
    g = m.geom
    phi = g.phi_of_length(0.4 * g.length)
    on = g.at(phi)
    radial = check.sub(on, check.add(g.centre, check.scale(g.w, g.rise * phi / g.sweep)))
    radial = check.scale(radial, 1.0 / check.norm(radial))
    node = check.add(on, check.scale(radial, 0.3))
    return [round(v, 4) for v in node], radial


def write_clamp_map(path, moves):
    """A 5x5x5 grid over the middle half of the program's box; everything else is clamped."""
    pts = [m.end for m in moves] or [(0.0, 0.0, 0.0)]
    axes = []
    for a in range(3):
        lo, hi = min(p[a] for p in pts), max(p[a] for p in pts)
        mid, half = (lo + hi) / 2, max((hi - lo) / 4, 1.0)
        axes.append([round(mid - half + k * half / 2, 4) for k in range(5)])

    def values(x, y, z):
        return (0.2 * (x - axes[0][0]) / 1.0 + 5, -0.15 * (y - axes[1][0]) + 8, 10 + 3 * math.sin(z))

    write_map(path, axes, lambda x, y, z: [max(-40, min(40, v)) for v in values(x, y, z)], "clamp")


def maps_for(program, nominal_moves, workdir, shared_maps):
    out = list(shared_maps)
    stem = os.path.splitext(os.path.basename(program))[0]
    for name, finder in (("bump-line", bump_on_line), ("bump-arc", bump_on_arc)):
        found = finder(nominal_moves)
        if found:
            path = os.path.join(workdir, f"{stem}.{name}.json")
            write_bump_map(path, found[0], found[1])
            out.append((name, path))
    path = os.path.join(workdir, f"{stem}.clamp.json")
    write_clamp_map(path, nominal_moves)
    out.append(("clamp", path))
    return out


# --------------------------------------------------------------------------------------------
# one program


def program_options(path):
    """The `(mtec-options: ...)` words of a program, paths made absolute."""
    with open(path, encoding="utf-8", errors="replace") as f:
        head = "".join(f.readline() for _ in range(5))
    m = OPTIONS_RE.search(head)
    words = shlex.split(m.group(1)) if m else []
    base = os.path.dirname(os.path.abspath(path))
    for k, w in enumerate(words[:-1]):
        if w in ("--offsets", "--tool-table"):
            words[k + 1] = os.path.join(base, words[k + 1])
    return words


def checker_args(words):
    kw = {}
    limits = check.Limits()
    for k, w in enumerate(words[:-1]):
        if w in CHECKER_OPTIONS:
            kw[CHECKER_OPTIONS[w]] = words[k + 1]
        elif w == "--tolerance-um":
            limits.tolerance_um = float(words[k + 1])
        elif w == "--chord-tolerance-um":
            limits.chord_tolerance_um = float(words[k + 1])
    kw["limits"] = limits
    return kw


def nominal_moves(program, kw):
    with tempfile.TemporaryDirectory(prefix="mtec-rs274-") as work:
        var_file, tbl = check.prepare_rs274_inputs(work, kw.get("offsets"), kw.get("tool_table"))
        calls, err = check.run_rs274(program, work, var_file, tbl)
    return check.interpret(program, calls, err).moves


def run_one(mtec, program, map_name, map_path, words, out_dir, always_flatten=False):
    """Returns (outcome, max deviation um, bound um, note). `always_flatten`: through
    `--flatten-with rs274` even when the rewriter would take the program itself."""
    stem = os.path.splitext(os.path.basename(program))[0]
    out = os.path.join(out_dir, f"{stem}.{map_name}.ngc")
    # mtec runs in the map's folder with a relative model path: the provenance comment names
    # the model, and its length must not depend on where the test happens to run
    cmd = [mtec, "compensate", "gcode", "--model", os.path.basename(map_path), program, "-o", out] + words
    if "--start-position-mm" not in words:
        cmd += ["--start-position-mm", "0,0,0"]
    flattened = always_flatten and "--flatten-with" not in words
    if flattened:
        cmd += ["--flatten-with", "rs274"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=os.path.dirname(map_path))
    if r.returncode == 2 and "--flatten-with" not in words:
        # refused directly: the LinuxCNC route flattens the program with rs274 first; its
        # output is checked against the ORIGINAL program like any other
        r2 = subprocess.run(cmd + ["--flatten-with", "rs274"], capture_output=True, text=True,
                            timeout=300, cwd=os.path.dirname(map_path))
        if r2.returncode == 0:
            r, flattened = r2, True
    if r.returncode == 2:
        lines = r.stderr.strip().splitlines() or ["(no message)"]
        msg = next((ln for ln in lines if ln.startswith("error:")), lines[0])
        located = re.search(r":\d+:\d+", msg) is not None
        return ("refused" if located else "CRASH"), None, None, msg
    if r.returncode != 0:
        return "CRASH", None, None, f"mtec exit {r.returncode}: {r.stderr.strip()[:300]}"
    kw = checker_args(words)
    try:
        res = check.check(program, out, map_path, flattened=flattened, **kw)
    except check.CheckFailure as e:
        return "WRONG", None, None, str(e)
    except Exception:  # a checker crash is a failure too
        return "CRASH", None, None, "checker: " + traceback.format_exc().strip().splitlines()[-1]
    if res.violations:
        more = f" [+{len(res.violations) - 1} more checks failed]" if len(res.violations) > 1 else ""
        return "WRONG", res.max_dev_um, res.bound_um, res.violations[0] + more
    note = f"both stop at: {res.stopped}" if res.stopped else ""
    if flattened:
        note = ("flattened by rs274; " + note).strip("; ")
    return "ok", res.max_dev_um, res.bound_um, note


# the real programs' setups: tool 1 of cds.ngc and g76.ngc from a tool table, in the machine's
# units (mm: mtec's default --machine-units; the checker hands rs274 an inch copy, as mtec does)
REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SHARED_OPTIONS = {
    name: ["--tool-table", os.path.join(REPO, "crates/mtec-cli/tests/data/flatten/mill.tbl")]
    for name in ("cds.ngc", "g76.ngc")
}


def run_program(mtec, program, out_dir, shared_maps, only_maps, always_flatten=False):
    words = program_options(program) or list(SHARED_OPTIONS.get(os.path.basename(program), []))
    kw = checker_args(words)
    try:
        moves = nominal_moves(program, kw)
        maps = maps_for(program, moves, out_dir, shared_maps)
    except Exception:
        return [(program, "-", "CRASH", None, None,
                 "checker: " + traceback.format_exc().strip().splitlines()[-1])]
    rows = []
    for name, path in maps:
        if only_maps and name not in only_maps:
            continue
        outcome, dev, bound, note = run_one(mtec, program, name, path, words, out_dir,
                                            always_flatten)
        rows.append((program, name, outcome, dev, bound, note))
    return rows


# --------------------------------------------------------------------------------------------
# driver


def print_table(rows, label):
    print(f"{'program':<34} {'map':<10} {'outcome':<8} {'max dev um':>10} {'bound um':>9}  note")
    for program, name, outcome, dev, bound, note in rows:
        d = f"{dev:.3f}" if dev is not None else "-"
        b = f"{bound:.3f}" if bound is not None else "-"
        print(f"{label(program):<34} {name:<10} {outcome:<8} {d:>10} {b:>9}  {note}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mtec", required=True, help="the mtec binary to test")
    ap.add_argument("--shared", help="folder of real programs (../shared/data/gcode/linuxcnc)")
    ap.add_argument("--cases", default=os.path.join(HERE, "cases"))
    ap.add_argument("--work", help="keep maps and compensated programs here")
    ap.add_argument("--maps", help="comma-separated subset of tilt,smooth,bump-line,bump-arc,clamp")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", help="regular expression on program file names")
    ap.add_argument("--flatten", choices=["refused", "always"], default="refused",
                    help="flatten with rs274 the programs the rewriter refuses (default), or all")
    a = ap.parse_args(argv)

    real = sorted(glob.glob(os.path.join(a.shared, "*.ngc"))) if a.shared else []
    cases = sorted(glob.glob(os.path.join(a.cases, "*.ngc")))
    programs = [p for p in real + cases if not a.only or re.search(a.only, os.path.basename(p))]
    only_maps = set(a.maps.split(",")) if a.maps else None
    mtec = os.path.abspath(a.mtec)

    work = a.work or tempfile.mkdtemp(prefix="mtec-rs274-run-")
    os.makedirs(work, exist_ok=True)
    shared_maps = [("tilt", os.path.join(work, "tilt.json")), ("smooth", os.path.join(work, "smooth.json"))]
    write_tilt_map(shared_maps[0][1])
    write_smooth_map(shared_maps[1][1])
    with concurrent.futures.ProcessPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        futures = [pool.submit(run_program, mtec, p, work, shared_maps, only_maps,
                               a.flatten == "always") for p in programs]
        rows = [row for f in futures for row in f.result()]

    def label(p):
        return ("cases/" if p in cases else "shared/") + os.path.basename(p)

    print_table(rows, label)
    failed = sum(1 for r in rows if r[2] in ("WRONG", "CRASH"))
    passed = len(rows) - failed
    counts = {k: sum(1 for r in rows if r[2] == k) for k in ("ok", "refused", "WRONG", "CRASH")}
    n_cases = len({r[0] for r in rows if r[0] in cases})
    n_real = len({r[0] for r in rows if r[0] in real})
    print(f"programs: {n_cases} cases, {n_real} real; runs: {counts['ok']} ok, "
          f"{counts['refused']} refused, {counts['WRONG']} wrong, {counts['CRASH']} crash")
    if not a.work:
        shutil.rmtree(work, ignore_errors=True)  # --work keeps them for inspection
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
