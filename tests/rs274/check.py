#!/usr/bin/env python3
"""Independent check of a compensated NC program against LinuxCNC's own interpreter.

Given the original program, the compensated program and the error model, this runs
`rs274 -g` (LinuxCNC's stand-alone RS274/NGC interpreter) on both, converts every canonical
move to machine millimetres and checks that the compensated program, moved by the model's
error, follows the original path:

  (a) rs274 accepts the compensated program to its end (or stops exactly where and how it stops
      on the original), and no line is over 255 characters;
  (b) every sampled point p of every compensated feed move, displaced to p + e(p), lies within
      the bound of the nominal path, walking the nominal moves in order;
  (c) every nominal feed, rapid and probe end point is reached by the end point of a
      compensated move (displaced by e);
  (d) the non-motion canonical calls (feeds, spindle, coolant, tools, offsets, dwell, end ...)
      come in the same order and between the same moves (COMMENT/MESSAGE ignored).

It shares no code with mtec: the trilinear map, the frames and the arc geometry are written
here from LinuxCNC's documented behaviour and from experiments with rs274 (see README.md).
Standard library only (Python >= 3.11 for tomllib).
"""

import argparse
import bisect
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib

MM_PER_INCH = 25.4
MAX_LINE_CHARS = 255  # the documented limit of LinuxCNC's interpreter (issue 15)
RS274_LINE_LIMIT = 252  # measured: rs274 says "Command too long" from 253 characters on
HALF_PRINT_UNIT = 0.5e-4  # rs274 -g prints 4 decimals in program units
SAMPLE_STEP_MM = 0.05
MIN_SAMPLES = 20
ZERO_LENGTH_MM = 1e-9
FULL_CIRCLE_MM = 1e-7  # start == end within this: an arc is a full turn
SQRT3 = math.sqrt(3.0)
WORK_SYSTEMS = ["G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"]
IGNORED_CALLS = {"COMMENT", "MESSAGE"}
MOTION_CALLS = {"STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED", "STRAIGHT_PROBE"}


class CheckFailure(Exception):
    """A violation of (a)-(d): the message names program, canonical line, point, deviation."""


# --------------------------------------------------------------------------------------------
# vectors


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def fmt_point(p):
    return "(" + ", ".join(f"{v:.5f}" for v in p) + ")"


# --------------------------------------------------------------------------------------------
# error models: e(p) in um at the machine position p in mm


class GridModel:
    """mtec.map/1: trilinear interpolation on a rectilinear grid, values flat in C order."""

    def __init__(self, doc):
        self.axes = [list(map(float, doc[k])) for k in ("x_mm", "y_mm", "z_mm")]
        self.outside = doc.get("outside", "clamp")
        n = [len(a) for a in self.axes]
        self.strides = (n[1] * n[2], n[2], 1)  # node (i, j, k) at (i*ny + j)*nz + k
        vals = [doc["ex_um"], doc["ey_um"], doc["ez_um"]]
        if any(len(v) != n[0] * n[1] * n[2] for v in vals):
            raise ValueError("map values do not match the grid size")
        self.values = list(zip(*vals))
        if self.outside not in ("clamp", "extrapolate", "refuse"):
            raise ValueError(f"unknown outside policy {self.outside!r}")

    def locate(self, axis, x):
        """Lower node index, step to the upper node (0 or 1) and fraction along `axis`."""
        ax = self.axes[axis]
        n = len(ax)
        if n == 1:
            return 0, 0, 0.0
        lo, hi = ax[0], ax[-1]
        if x < lo or x > hi:
            if lo - 1e-9 <= x <= hi + 1e-9 or self.outside == "clamp":
                x = min(max(x, lo), hi)  # clamp: nearest point of the grid box
            elif self.outside == "refuse":
                raise CheckFailure(f"point {x:.6f} on axis {'xyz'[axis]} is outside the "
                                   f"map's grid [{lo}, {hi}] (outside = refuse)")
        i = min(max(bisect.bisect_right(ax, x) - 1, 0), n - 2)
        return i, 1, (x - ax[i]) / (ax[i + 1] - ax[i])

    def error_um(self, p):
        # trilinear: e = sum over the 8 corners of prod(1 - t or t) * e_corner
        i, di, tx = self.locate(0, p[0])
        j, dj, ty = self.locate(1, p[1])
        k, dk, tz = self.locate(2, p[2])
        sx, sy, _ = self.strides
        v = self.values
        b = i * sx + j * sy + k
        dx, dy = di * sx, dj * sy
        ux, uy, uz = 1.0 - tx, 1.0 - ty, 1.0 - tz
        corners = ((b, ux * uy * uz), (b + dk, ux * uy * tz), (b + dy, ux * ty * uz),
                   (b + dy + dk, ux * ty * tz), (b + dx, tx * uy * uz), (b + dx + dk, tx * uy * tz),
                   (b + dx + dy, tx * ty * uz), (b + dx + dy + dk, tx * ty * tz))
        ex = ey = ez = 0.0
        for idx, w in corners:
            if w != 0.0:
                c = v[idx]
                ex += w * c[0]
                ey += w * c[1]
                ez += w * c[2]
        return [ex, ey, ez]

    def planes(self):
        """Grid values per axis: a trilinear map has kinks only on these planes."""
        return self.axes


class PolyModel:
    """mtec.poly-model/1: E = sum coef_um * x^i y^j z^k."""

    def __init__(self, doc):
        self.terms = [(t["powers"], t["coef_um"]) for t in doc["terms"]]

    def error_um(self, p):
        out = [0.0, 0.0, 0.0]
        for (i, j, k), c in self.terms:
            m = p[0] ** i * p[1] ** j * p[2] ** k
            out[0] += c[0] * m
            out[1] += c[1] * m
            out[2] += c[2] * m
        return out

    def planes(self):
        return [[], [], []]


class ZeroModel:
    def error_um(self, p):
        return [0.0, 0.0, 0.0]

    def planes(self):
        return [[], [], []]


def load_model(path):
    with open(path, encoding="utf-8") as f:
        doc = json.load(f)
    kind = doc.get("format")
    if kind == "mtec.map/1":
        return GridModel(doc)
    if kind == "mtec.poly-model/1":
        return PolyModel(doc)
    if kind == "mtec.zero-model/1":
        return ZeroModel()
    raise ValueError(f"{path}: model format {kind!r} is not supported by the checker")


def displaced(model, p):
    """Where the machine really goes when commanded to p: p + e(p) (e in um -> mm)."""
    e = model.error_um(p)
    return (p[0] + e[0] * 1e-3, p[1] + e[1] * 1e-3, p[2] + e[2] * 1e-3)


# --------------------------------------------------------------------------------------------
# rs274's inputs: offsets TOML (mtec.gcode-offsets/1) -> var file, tool table in inches


def read_offsets(path):
    with open(path, "rb") as f:
        doc = tomllib.load(f)
    work = {k.upper(): [float(v) for v in vals] for k, vals in doc.get("work_offsets_mm", {}).items()}
    tools = {int(k): float(v) for k, v in doc.get("tool_lengths_mm", {}).items()}
    return doc.get("active", "G54").upper(), work, tools


def write_var_file(path, active, work):
    # parameters 5221.. (G54) step 20 per system, 5220 = current system 1..9; the stand-alone
    # rs274 reads them in inches (its internal length unit; found by experiment)
    lines = [f"5220\t{WORK_SYSTEMS.index(active) + 1}"]
    for n, name in enumerate(WORK_SYSTEMS):
        xyz = work.get(name, [0.0, 0.0, 0.0])
        for a in range(3):
            lines.append(f"{5221 + 20 * n + a}\t{xyz[a] / MM_PER_INCH:.12f}")
    with open(path, "w", encoding="ascii") as f:
        f.write("\n".join(lines) + "\n")


# G28 and G30 reference points for the second rs274 run (machine mm; parameters 5161-5163 and
# 5181-5183): moves whose end changes with them go to or from a position that only the
# controller's parameters define
REFERENCE_PROBE_MM = {5161: -101.1, 5162: -102.2, 5163: -103.3,
                      5181: -201.1, 5182: -202.2, 5183: -203.3}
REFERENCE_RE = re.compile(r"[gG]\s*0*\s*(2\s*8|3\s*0)(?![\d.])")


def write_reference_var_file(path, var_file):
    """A var file with the parameters of `var_file` (or none) and moved reference points."""
    lines = []
    if var_file:
        with open(var_file, encoding="ascii") as f:
            lines = [ln.rstrip("\n") for ln in f if ln.split()[:1] and
                     int(float(ln.split()[0])) not in REFERENCE_PROBE_MM]
    lines += [f"{k}\t{v / MM_PER_INCH:.12f}" for k, v in sorted(REFERENCE_PROBE_MM.items())]
    # rs274 refuses a parameter file out of order ("Parameter file out of order"), which left
    # the reference moves unmarked whenever an offsets file came with a G28/G30
    lines.sort(key=lambda ln: float(ln.split()[0]))
    with open(path, "w", encoding="ascii") as f:
        f.write("\n".join(lines) + "\n")


def mark_reference(prog, moved):
    """Marks the moves of `prog` whose end differs in `moved` (the same program run with other
    reference points). Nothing is marked when the runs differ in their number of moves."""
    if len(prog.moves) != len(moved.moves):
        if not moved.moves and moved.error:
            raise CheckFailure(f"rs274 with moved reference points: {moved.error}")
        return
    for m, r in zip(prog.moves, moved.moves):
        m.reference = norm(sub(m.end, r.end)) > 1e-9


def write_tool_table(path, tools):
    with open(path, "w", encoding="ascii") as f:
        for t, length in sorted(tools.items()):
            f.write(f"T{t} P{t} Z{length / MM_PER_INCH:.12f} ;length {length} mm\n")


def convert_tool_table_to_inch(src, dst):
    """A LinuxCNC .tbl in mm -> the same table in inches (rs274 stand-alone reads inches)."""
    out = []
    with open(src, encoding="utf-8") as f:
        for line in f:
            body, sep, comment = line.rstrip("\n").partition(";")
            words = []
            for w in body.split():
                if w[0].upper() in "XYZUVWD" and len(w) > 1:
                    w = f"{w[0]}{float(w[1:]) / MM_PER_INCH:.12f}"
                words.append(w)
            out.append(" ".join(words) + (sep + comment if sep else ""))
    with open(dst, "w", encoding="ascii") as f:
        f.write("\n".join(out) + "\n")


# --------------------------------------------------------------------------------------------
# running rs274 and reading its canonical calls

# the block number field is `N.....`, `N0080`, and from six digits on has no blank before the
# call (`N100000STRAIGHT_FEED(`): with `\s+` required there, every move of a block numbered
# N100000 or above was dropped from both programs and went unchecked (found 2026-11-30)
CANON_RE = re.compile(r"^\s*(\d+)\s+N([0-9.]*)\s*([A-Z_][A-Z_0-9]*)\((.*)\)\s*$")


class Canon:
    __slots__ = ("seq", "nword", "name", "args")

    def __init__(self, seq, nword, name, args):
        self.seq, self.nword, self.name, self.args = seq, nword, name, args


def run_rs274(program, workdir, var_file=None, tool_table=None):
    """Runs `rs274 -g`; returns (canonical calls, error text or None)."""
    cmd = ["rs274", "-g"]
    if var_file:
        local = os.path.join(workdir, "rs274.var")  # rs274 rewrites its var file: use a copy
        shutil.copyfile(var_file, local)
        cmd += ["-v", local]
    if tool_table:
        cmd += ["-t", tool_table]
    cmd.append(os.path.abspath(program))
    # rs274 keeps its tool table in a file mapped from $HOME/.tool.mmap: concurrent runs with
    # one HOME crash with SIGBUS or read each other's tools, so every run gets its own HOME
    env = dict(os.environ, HOME=workdir)
    r = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True, timeout=120, env=env)
    calls = []
    for line in r.stdout.splitlines():
        m = CANON_RE.match(line)
        if m:
            calls.append(Canon(int(m.group(1)), m.group(2), m.group(3), m.group(4)))
    error = None
    if r.returncode != 0:
        text = [ln for ln in (r.stderr + r.stdout).splitlines()
                if ln.strip() and ln.strip() != "executing" and not CANON_RE.match(ln)]
        error = " | ".join(text) or f"rs274 exited with {r.returncode}"
    return calls, error


def numbers(args):
    return [float(x) for x in args.replace(",", " ").split()]


# --------------------------------------------------------------------------------------------
# frames: machine = rot_z(R) (canonical + G92) + G5x + tool offset (all in mm)
# (LinuxCNC emccanon from_prog order; verified with G53 moves under G10 L2 R, see README)


class Frame:
    def __init__(self):
        self.mm_per_unit = 1.0
        self.g5x = (0.0, 0.0, 0.0)
        self.g92 = (0.0, 0.0, 0.0)
        self.tool = (0.0, 0.0, 0.0)
        self.rot_deg = 0.0
        self.plane = "XY"
        # mm per unit in which each non-zero offset in force was printed (4 decimals): after a
        # G20 -> G21 switch an offset printed in inches carries up to 1.27 um per axis into
        # every machine position (found by tests/rs274/generate.py seed 3)
        self.offset_units = {}

    @property
    def offset_mm_per_unit(self):
        return max(self.offset_units.values(), default=0.0)

    @property
    def g92_mm_per_unit(self):
        """Units of a non-zero G92/G52 offset in force (0: none). The interpreter computes a G92
        from the current position, which differs between the two programs, so its print
        rounding differs too, also when printed in the move's own units (generator seed 10:
        an inch G92, 5.27 um at a 4.90 um bound)."""
        return self.offset_units.get("g92", 0.0)

    def note_offset(self, name, xyz):
        if any(abs(v) > 0.0 for v in xyz):
            self.offset_units[name] = self.mm_per_unit
        else:
            self.offset_units.pop(name, None)

    def update(self, call):
        """Applies a state-changing canonical call; offsets come in the current units."""
        u = self.mm_per_unit
        if call.name == "USE_LENGTH_UNITS":
            self.mm_per_unit = MM_PER_INCH if "INCH" in call.args else 1.0
        elif call.name == "SET_G5X_OFFSET":
            v = numbers(call.args)
            self.g5x = (v[1] * u, v[2] * u, v[3] * u)
            self.note_offset("g5x", self.g5x)
        elif call.name == "SET_G92_OFFSET":
            v = numbers(call.args)
            self.g92 = (v[0] * u, v[1] * u, v[2] * u)
            self.note_offset("g92", self.g92)
        elif call.name == "USE_TOOL_LENGTH_OFFSET":
            v = numbers(call.args)  # "x y z, a b c, u v w"
            self.tool = (v[0] * u, v[1] * u, v[2] * u)
            self.note_offset("tool", self.tool)
        elif call.name == "SET_XY_ROTATION":
            self.rot_deg = numbers(call.args)[0]
        elif call.name == "SELECT_PLANE":
            self.plane = call.args.replace("CANON_PLANE_", "")

    def rotate(self, p, sign):
        a = math.radians(self.rot_deg) * sign
        c, s = math.cos(a), math.sin(a)
        return (c * p[0] - s * p[1], s * p[0] + c * p[1], p[2])

    def to_machine(self, canon_xyz):
        u = self.mm_per_unit
        p = add(scale(canon_xyz, u), self.g92)
        return add(add(self.rotate(p, +1), self.g5x), self.tool)

    def to_canon(self, machine):
        p = self.rotate(sub(sub(machine, self.g5x), self.tool), -1)
        return scale(sub(p, self.g92), 1.0 / self.mm_per_unit)

    def direction_to_machine(self, v):
        return self.rotate(v, +1)


# --------------------------------------------------------------------------------------------
# moves in machine mm


class Line:
    kind = "line"

    def __init__(self, a, b):
        self.start, self.end = a, b
        self.length = norm(sub(b, a))

    def point(self, s):
        """Point at arc length s from the start."""
        if self.length <= ZERO_LENGTH_MM:
            return self.start
        return add(self.start, scale(sub(self.end, self.start), s / self.length))

    def nearest(self, q, _hint=None):
        """(distance, arc length of the nearest point): exact projection, clamped to the segment."""
        d = sub(self.end, self.start)
        if self.length <= ZERO_LENGTH_MM:
            return norm(sub(q, self.start)), 0.0
        t = min(max(dot(sub(q, self.start), d) / (self.length * self.length), 0.0), 1.0)
        return norm(sub(q, add(self.start, scale(d, t)))), t * self.length

    def breakpoints(self, planes):
        """Arc lengths where the segment crosses a grid plane (kinks of a trilinear map)."""
        out = []
        if self.length <= ZERO_LENGTH_MM:
            return out
        for a in range(3):
            x0, x1 = self.start[a], self.end[a]
            if x0 == x1:
                continue
            lo, hi = min(x0, x1), max(x0, x1)
            for v in planes[a][bisect.bisect_left(planes[a], lo):bisect.bisect_right(planes[a], hi)]:
                out.append((v - x0) / (x1 - x0) * self.length)
        return out


class Arc:
    """Circular/helical/spiral arc: P(phi) = C + r(phi)(cos phi U + sin phi V) + w(phi) W.

    phi runs from 0 to the sweep; r and w change linearly with phi (LinuxCNC moves a helix, and
    a spiral when start and end radius differ)."""

    kind = "arc"

    def __init__(self, centre, u, v, w, r0, r1, sweep, rise):
        self.centre, self.u, self.v, self.w = centre, u, v, w
        self.r0, self.r1, self.sweep, self.rise = r0, r1, sweep, rise
        self.start = self.at(0.0)
        self.end = self.at(sweep)
        # arc length of a helix-like curve, integrated numerically (64 panels per turn)
        n = max(8, int(64 * sweep / (2 * math.pi)) + 1)
        pts = [self.at(sweep * k / n) for k in range(n + 1)]
        self.cum = [0.0]
        for k in range(n):
            self.cum.append(self.cum[-1] + norm(sub(pts[k + 1], pts[k])))
        self.length = self.cum[-1]
        self.planar_circle = abs(r1 - r0) < 1e-12 and abs(rise) < 1e-12
        # the length itself, for the time of a G93 move: the polyline above is short of it by
        # ~(panel angle)^2/24, 4e-4 of a quarter circle, and two arcs of nearly the same sweep
        # can get different panel counts (found 2026-11-30: a kept G93 arc reported 5e-5 too
        # fast). |P'(phi)|^2 = r(phi)^2 + r'^2 + w'^2 (U, V, W orthonormal), integrated by
        # Simpson's rule on 256 panels per turn (exact for a circle or a helix)
        dr, dw = (r1 - r0) / sweep, rise / sweep
        m = 2 * max(8, int(128 * sweep / (2 * math.pi)) + 1)
        f = [math.sqrt(self.radius(sweep * k / m) ** 2 + dr * dr + dw * dw) for k in range(m + 1)]
        self.true_length = sweep / (3 * m) * (f[0] + f[-1] + 4 * sum(f[1:-1:2]) + 2 * sum(f[2:-1:2]))

    def radius(self, phi):
        return self.r0 + (self.r1 - self.r0) * phi / self.sweep

    def at(self, phi):
        r = self.radius(phi)
        c, s = math.cos(phi), math.sin(phi)
        off = add(scale(self.u, r * c), scale(self.v, r * s))
        return add(add(self.centre, off), scale(self.w, self.rise * phi / self.sweep))

    def phi_of_length(self, s):
        n = len(self.cum) - 1
        k = min(max(bisect.bisect_right(self.cum, s) - 1, 0), n - 1)
        seg = self.cum[k + 1] - self.cum[k]
        f = 0.0 if seg <= 0 else (s - self.cum[k]) / seg
        return self.sweep * (k + f) / n

    def length_of_phi(self, phi):
        n = len(self.cum) - 1
        x = phi / self.sweep * n
        k = min(int(x), n - 1)
        return self.cum[k] + (x - k) * (self.cum[k + 1] - self.cum[k])

    def point(self, s):
        return self.at(self.phi_of_length(s))

    def local(self, q):
        d = sub(q, self.centre)
        a, b, h = dot(d, self.u), dot(d, self.v), dot(d, self.w)
        return math.hypot(a, b), math.atan2(b, a) % (2 * math.pi), h

    def dist2(self, q_local, phi):
        # |q - P(phi)|^2 = rho^2 + r^2 - 2 rho r cos(phi - theta) + (h - w(phi))^2
        rho, theta, h = q_local
        r = self.radius(phi)
        dh = h - self.rise * phi / self.sweep
        return max(rho * rho + r * r - 2 * rho * r * math.cos(phi - theta) + dh * dh, 0.0)

    def nearest(self, q, hint=None):
        """(distance, arc length of a nearest point): the global minimum over the whole sweep;
        among (near-)equal minima, e.g. the turns of a multi-turn arc, the one nearest `hint`."""
        ql = self.local(q)
        cands = self.minima_circle(ql) if self.planar_circle else self.minima_helix(ql)
        best = min(v for v, _ in cands)
        phis = [p for v, p in cands if math.sqrt(v) <= math.sqrt(best) + 1e-4]
        along = [self.length_of_phi(p) for p in phis]
        if hint is None:
            return math.sqrt(best), along[0]
        if self.sweep > 2 * math.pi:
            # the turns of a spiral or helix lie one turn's spacing apart: a point within the
            # path bound of one turn may lie nearer the next when the spacing is small (an inch
            # arc whose printed end radius differs from its start radius by 3 um; found by
            # tests/rs274/generate.py). The path goes on continuously, so the nearest point
            # within half a turn of `hint` is the one followed, with its own distance.
            turn = self.length * 2 * math.pi / self.sweep
            window = [(v, self.length_of_phi(p)) for v, p in cands]
            window = [(v, s) for v, s in window if abs(s - hint) <= turn / 2]
            if window:
                v, s = min(window)
                return math.sqrt(v), s
        return math.sqrt(best), min(along, key=lambda s: abs(s - hint))

    def minima_circle(self, ql):
        # planar circle: the nearest point is at the angle of q (every turn) when that lies in
        # the sweep, else at an end point (exact)
        theta = ql[1]
        cands = [0.0, self.sweep]
        k = 0
        while theta + 2 * math.pi * k <= self.sweep:
            cands.append(theta + 2 * math.pi * k)
            k += 1
        return [(self.dist2(ql, p), p) for p in cands]

    def minima_helix(self, ql):
        """Local minima of the distance to a helix/spiral, exact and cheap.

        With any upper bound f_up of the minimum, a nearest point must satisfy
        2 rho r_min (1 - cos(phi - theta)) <= f_up, since |q - P|^2 = (rho - r)^2
        + 2 rho r (1 - cos(phi - theta)) + (h - w)^2: only small windows around theta + 2 pi j
        remain, where the distance is convex; golden section finds the minimum in each."""
        rho, theta, _ = ql
        turns = range(int(math.floor(-theta / (2 * math.pi))) - 1,
                      int(math.ceil((self.sweep - theta) / (2 * math.pi))) + 2)
        ends = [(self.dist2(ql, 0.0), 0.0), (self.dist2(ql, self.sweep), self.sweep)]
        inside = [theta + 2 * math.pi * j for j in turns if 0.0 <= theta + 2 * math.pi * j <= self.sweep]
        f_up = min([v for v, _ in ends] + [self.dist2(ql, p) for p in inside])
        c = 1.0 - f_up / (2.0 * rho * min(self.r0, self.r1)) if rho > 0 else -1.0
        if c <= 0.5:  # the windows would be wider than 60 degrees: scan instead
            return self.scan_helix(ql)
        half = math.acos(c) + 1e-12
        out = ends
        for j in turns:
            lo = max(0.0, theta + 2 * math.pi * j - half)
            hi = min(self.sweep, theta + 2 * math.pi * j + half)
            if lo < hi:
                phi, val = self.golden(ql, lo, hi)
                out.append((val, phi))
        return out

    def scan_helix(self, ql):
        # far from the path (near the axis): scan 96 points per turn, refine each local minimum
        n = max(16, int(96 * self.sweep / (2 * math.pi)) + 1)
        step = self.sweep / n
        f = [self.dist2(ql, k * step) for k in range(n + 1)]
        out = []
        for k in range(n + 1):
            if (k == 0 or f[k] <= f[k - 1]) and (k == n or f[k] <= f[k + 1]):
                phi, val = self.golden(ql, max(0.0, (k - 1) * step), min(self.sweep, (k + 1) * step))
                out.append((val, phi))
        return out

    def golden(self, ql, a, b):
        g = (math.sqrt(5) - 1) / 2
        c, d = b - g * (b - a), a + g * (b - a)
        fc, fd = self.dist2(ql, c), self.dist2(ql, d)
        for _ in range(60):
            if fc < fd:
                b, d, fd = d, c, fc
                c = b - g * (b - a)
                fc = self.dist2(ql, c)
            else:
                a, c, fc = c, d, fd
                d = a + g * (b - a)
                fd = self.dist2(ql, d)
        for phi in (a, b):  # end points of the bracket may be lower (sweep ends)
            val = self.dist2(ql, phi)
            if val < min(fc, fd):
                return phi, val
        return (c, fc) if fc < fd else (d, fd)

    def breakpoints(self, _planes):
        return []


PLANE_AXES = {  # ARC_FEED(first_end, second_end, first_centre, second_centre, rotation, axis_end)
    "XY": (0, 1, 2),
    "XZ": (2, 0, 1),  # G18: first = Z, second = X, axis = Y
    "YZ": (1, 2, 0),  # G19: first = Y, second = Z, axis = X
}

UNIT = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def arc_from_canon(frame, start_machine, v, start_mm_per_unit=None, start_offset_mm_per_unit=0.0):
    """ARC_FEED in canonical units -> Arc in machine mm (start = previous position).

    `start_mm_per_unit`: the units the start was printed in. After a G20/G21 switch the start
    (printed in the old units) and the end (in the new) carry different roundings, so a full
    circle (G91 with no axis words, end = start inside LinuxCNC) can print with its end a
    micrometre from its start: start and end within both printouts' rounding are one point
    then (found by tests/rs274/generate.py).

    `start_offset_mm_per_unit`: the units of a G92 offset that was in force when the start was
    printed and has changed since (the first arc after G92.1 or a new G92): the start carries
    that offset's print rounding, the end does not, so a full circle can again print with its
    end apart from its start (pygcode study, tests/rs274/README.md)."""
    i1, i2, i3 = PLANE_AXES[frame.plane]
    start_c = frame.to_canon(start_machine)
    end_c = [0.0, 0.0, 0.0]
    end_c[i1], end_c[i2], end_c[i3] = v[0], v[1], v[5]
    centre_c = [0.0, 0.0, 0.0]
    centre_c[i1], centre_c[i2], centre_c[i3] = v[2], v[3], start_c[i3]
    turns = int(round(v[4]))  # +n: counter-clockwise in (first, second), n-1 extra full turns
    end_m = frame.to_machine(tuple(end_c))
    centre_m = frame.to_machine(tuple(centre_c))
    e1 = frame.direction_to_machine(UNIT[i1])
    e2 = frame.direction_to_machine(UNIT[i2])
    normal = cross(e1, e2)
    if turns < 0:
        normal = scale(normal, -1.0)  # clockwise: the same arc seen along -normal
    r_start = sub(start_machine, centre_m)
    r_start_plane = sub(r_start, scale(normal, dot(r_start, normal)))
    r0 = norm(r_start_plane)
    r_end = sub(end_m, centre_m)
    r_end_plane = sub(r_end, scale(normal, dot(r_end, normal)))
    r1 = norm(r_end_plane)
    if r0 <= ZERO_LENGTH_MM and r1 <= ZERO_LENGTH_MM:
        # start, centre and end on one axial line (a subroutine run with zero arguments):
        # LinuxCNC moves along the axis only, a straight line
        return Line(start_machine, end_m)
    if r0 <= ZERO_LENGTH_MM or r1 <= ZERO_LENGTH_MM:
        raise CheckFailure("arc with zero radius at one end only")
    u = scale(r_start_plane, 1.0 / r0)
    vv = cross(normal, u)
    ang = math.atan2(dot(r_end_plane, vv), dot(r_end_plane, u)) % (2 * math.pi)
    same = FULL_CIRCLE_MM
    if start_mm_per_unit is not None and start_mm_per_unit != frame.mm_per_unit:
        same = SQRT3 * HALF_PRINT_UNIT * (start_mm_per_unit + frame.mm_per_unit)
    if start_offset_mm_per_unit > 0.0:
        printed = start_mm_per_unit or frame.mm_per_unit
        same = max(same, SQRT3 * HALF_PRINT_UNIT
                   * (printed + start_offset_mm_per_unit + frame.mm_per_unit))
    if ang < 1e-12 or norm(sub(r_end_plane, scale(u, r1))) < same:
        ang = 2 * math.pi  # start == end: a full circle
    sweep = ang + 2 * math.pi * (abs(turns) - 1)
    centre_start = add(centre_m, scale(normal, dot(r_start, normal)))
    rise = dot(sub(end_m, start_machine), normal)
    return Arc(centre_start, u, vv, normal, r0, r1, sweep, rise)


class Move:
    """One canonical motion in machine mm."""

    def __init__(self, kind, geom, call, mm_per_unit, abc, start_mm_per_unit=None,
                 offset_mm_per_unit=0.0, g92_mm_per_unit=0.0):
        self.kind = kind  # "rapid", "feed", "probe"
        self.geom = geom
        self.call = call
        # the start was printed with the previous move, maybe in other units (G20 -> G21):
        # the coarser of the two print resolutions applies to the whole move
        self.mm_per_unit = max(mm_per_unit, start_mm_per_unit or mm_per_unit)
        # offsets printed in coarser units than the move shift the whole move by their rounding
        self.offset_mm_per_unit = max(
            offset_mm_per_unit if offset_mm_per_unit > self.mm_per_unit else 0.0, g92_mm_per_unit)
        self.abc = abc
        self.start, self.end, self.length = geom.start, geom.end, geom.length
        self.reference = False  # its end depends on the G28/G30 reference points (mark_reference)
        self.inverse_time_feed_mm = None  # under G93: the feed rs274 derived from F, in mm/min
        self.feed_mm = None  # under G94: the feed in effect, mm/min

    def rounding_um(self):
        # printed to 4 decimals: each coordinate off by half a unit; an arc's printed centre
        # too, which moves the arc by up to 2*|centre error| + |end point error|
        h = HALF_PRINT_UNIT * self.mm_per_unit * 1e3
        shift = SQRT3 * HALF_PRINT_UNIT * self.offset_mm_per_unit * 1e3
        if self.geom.kind == "arc":
            return (2 * math.sqrt(2) + SQRT3) * h + shift
        return SQRT3 * h + shift

    def where(self):
        n = f" N{self.call.nword}" if self.call.nword.strip(".") else ""
        return f"canonical line {self.call.seq}{n} {self.call.name}"


class Program:
    def __init__(self, path, calls, error):
        self.path, self.calls, self.error = path, calls, error
        self.moves = []
        self.events = []  # (name, args, index of the preceding move)


def interpret(path, calls, error):
    """Canonical calls -> moves in machine mm and the sequence of non-motion events."""
    prog = Program(path, calls, error)
    frame = Frame()
    pos = (0.0, 0.0, 0.0)  # rs274 stand-alone starts at machine zero (found by experiment)
    pos_units = None  # units in which the current position was printed
    # the G92 offset in force when the current position was printed, and its print units
    pos_g92, pos_g92_units = frame.g92, 0.0
    inverse_time, per_rev, feed = False, False, None  # G93, G95, the last SET_FEED_RATE
    for c in calls:
        if c.name == "COMMENT" and "feed mode set to" in c.args:
            inverse_time = "inverse time" in c.args
            per_rev = "per revolution" in c.args
        if c.name == "SET_FEED_RATE":
            feed = numbers(c.args)[0]
            if inverse_time:
                continue  # compared as each move's time by check_inverse_time
        if c.name in MOTION_CALLS:
            v = numbers(c.args)
            # a G92 changed since the start was printed: the start keeps the old one's rounding
            old_g92_units = pos_g92_units if frame.g92 != pos_g92 else 0.0
            if c.name == "ARC_FEED":
                geom = arc_from_canon(frame, pos, v, pos_units, old_g92_units)
                abc = tuple(v[6:9])
                kind = "feed"
            else:
                geom = Line(pos, frame.to_machine((v[0], v[1], v[2])))
                abc = tuple(v[3:6])
                kind = {"STRAIGHT_TRAVERSE": "rapid", "STRAIGHT_FEED": "feed"}.get(c.name, "probe")
            move = Move(kind, geom, c, frame.mm_per_unit, abc, pos_units, frame.offset_mm_per_unit,
                        max(frame.g92_mm_per_unit, old_g92_units))
            if kind == "feed" and inverse_time and feed:
                move.inverse_time_feed_mm = feed * frame.mm_per_unit  # mm/min rs274 computed
            elif kind == "feed" and not per_rev and feed:
                move.feed_mm = feed * frame.mm_per_unit  # G94: mm/min
            prog.moves.append(move)
            pos, pos_units = geom.end, frame.mm_per_unit
            pos_g92, pos_g92_units = frame.g92, frame.g92_mm_per_unit
            continue
        frame.update(c)
        if c.name not in IGNORED_CALLS:
            prog.events.append((c.name, c.args, len(prog.moves) - 1, c))
    return prog


# --------------------------------------------------------------------------------------------
# the walk: compensated moves along the nominal ones


class Limits:
    def __init__(self, tolerance_um=0.5, chord_tolerance_um=0.5):
        self.tolerance_um = tolerance_um
        self.chord_tolerance_um = chord_tolerance_um

    def path_bound_um(self, nominal, comp):
        b = self.tolerance_um + nominal.rounding_um() + comp.rounding_um()
        if nominal.geom.kind == "arc" and comp.geom.kind == "line":
            b += self.chord_tolerance_um  # the arc was linearised into chords
        return b

    def point_bound_um(self, nominal, comp):
        h = HALF_PRINT_UNIT * 1e3 * SQRT3
        return (self.tolerance_um + h * (nominal.mm_per_unit + nominal.offset_mm_per_unit)
                + h * (comp.mm_per_unit + comp.offset_mm_per_unit))


def sample_lengths(geom, planes):
    """Arc lengths to check: every 0.05 mm, >= 20 per move, both ends, grid-plane crossings."""
    n = max(MIN_SAMPLES, int(math.ceil(geom.length / SAMPLE_STEP_MM)))
    s = [geom.length * k / n for k in range(n + 1)]
    s.extend(geom.breakpoints(planes))
    return sorted(s)


class Walker:
    """Walks the compensated moves along the nominal ones (checks (b) and (c)).

    State: nominal move i being followed and the arc length reached along it. A compensated
    feed continues move i, or starts the next nominal move once i's end point has been reached
    by the previous compensated end point. A violation is recorded and the walk goes on with the
    nearest explanation, so that the largest deviation of the whole program is known."""

    def __init__(self, nominal, comp, model, limits):
        self.nom, self.comp, self.model, self.limits = nominal, comp, model, limits
        self.planes = model.planes()
        self.i = -1  # nominal move being followed (-1: the initial position)
        self.progress = 0.0  # arc length reached along nominal move i
        self.match = []  # nominal index of each compensated move
        self.max_dev_um = 0.0
        self.max_dev_at = ""
        self.max_bound_um = 0.0
        self.samples = 0
        self.end_only = 0  # moves from the initial position: checked at their end point only
        self.at_start = set()  # zero-length rapids at the initial position (a bare `G0` block)
        self.reference_moves = 0  # rapids whose end is a G28/G30 reference point (not checked)
        self.violations = []

    def violation(self, comp, msg):
        where = comp.where() if comp is not None else "end of program"
        self.violations.append(f"{self.comp.path}: {where}: {msg}")

    def note(self, dev_um, bound_um, comp):
        self.max_bound_um = max(self.max_bound_um, bound_um)
        if dev_um > self.max_dev_um:
            self.max_dev_um = dev_um
            self.max_dev_at = comp.where()

    def end_gap_um(self, i, point):
        return norm(sub(point, self.nom.moves[i].end)) * 1e3

    def at_end(self, i, point):
        """Nominal move i is finished: its end reached by `point` (a displaced end point)."""
        if i < 0 or i in self.at_start:
            return True  # the initial position: not commanded by either program
        if self.nom.moves[i].reference:
            return True  # a G28/G30 reference point: the controller's, in both programs
        n = self.nom.moves[i]
        bound = self.limits.point_bound_um(n, n)
        if n.kind == "feed" and (n.length - self.progress) * 1e3 > bound + self.limits.tolerance_um:
            return False
        return self.end_gap_um(i, point) <= bound

    def run(self):
        for c in self.comp.moves:
            start = displaced(self.model, c.start)
            if c.kind == "feed":
                self.feed(c, start)
            else:
                self.rapid(c, start)
            self.match.append(self.i)
        self.finish()

    def next_indices(self, start):
        """Candidates for the next nominal move: i+1, and past it while the candidate is a
        zero-length move whose end `start` already sits on (it may have been dropped)."""
        out = []
        j = self.i + 1
        while j < len(self.nom.moves):
            out.append(j)
            n = self.nom.moves[j]
            if n.length > ZERO_LENGTH_MM or norm(sub(start, n.end)) * 1e3 > self.limits.point_bound_um(n, n):
                break
            j += 1
        return out

    def check_end_reached(self, c, start):
        """(c): before a new nominal move starts, the current one's end must have been reached."""
        if self.at_end(self.i, start):
            return True
        self.violation(c, self.unreached(start))
        self.note(self.end_gap_um(self.i, start), self.limits.point_bound_um(self.nom.moves[self.i], c), c)
        return False

    def rapid(self, c, start):
        """A compensated rapid (or probe) is one nominal rapid, checked at its end point."""
        self.check_end_reached(c, start)
        end = displaced(self.model, c.end)
        same = [j for j in self.next_indices(start) if self.nom.moves[j].kind == c.kind]
        if not same:
            self.violation(c, f"a {c.kind} move where the original has "
                              f"{self.describe_nominal(self.i + 1)}")
            return
        j = same[0]
        n = self.nom.moves[j]
        if self.stands_at_start(c, j):
            return
        if n.reference and c.reference:
            # a move to (or on from) a G28/G30 reference point: where it ends is the
            # controller's parameter, the same in both programs; not a compensated position
            self.reference_moves += 1
            self.check_abc(c, n)
            self.i, self.progress = j, n.length
            return
        dev = norm(sub(end, n.end)) * 1e3
        bound = self.limits.point_bound_um(n, c)
        self.note(dev, bound, c)
        if dev > bound:
            self.violation(c, f"end point {fmt_point(c.end)} displaced to {fmt_point(end)} misses "
                              f"the nominal end {fmt_point(n.end)} ({n.where()}) by {dev:.3f} um "
                              f"> bound {bound:.3f} um")
        self.check_abc(c, n)
        self.i, self.progress = j, n.length

    def stands_at_start(self, c, j):
        """A block such as a bare `G0` or `G1 F100` before any move: LinuxCNC issues a move of
        zero length where the machine stands, which neither program commands. Matched without a
        check when nominal move j is such a move, every move before it was one too, and the
        compensated move c is one as well."""
        n = self.nom.moves[j]
        # zero within the print rounding: from the start (machine 0) to a point printed in
        # inches, e.g. -5.9055 in after a G54 X of 150 mm, is 0.3 um
        if (j == self.i + 1 and (self.i < 0 or self.i in self.at_start)
                and n.kind == c.kind and n.length * 1e3 <= n.rounding_um()
                and c.length * 1e3 <= c.rounding_um()
                and norm(sub(c.end, n.end)) <= ZERO_LENGTH_MM):
            self.at_start.add(j)
            self.i, self.progress = j, n.length
            return True
        return False

    def feed(self, c, start):
        """A compensated feed continues nominal move i, or starts the next one once i is done."""
        if self.i + 1 < len(self.nom.moves) and self.stands_at_start(c, self.i + 1):
            return
        i = self.i
        # a zero-length move where the machine stood at the start (a bare `G1 F300`) is not
        # continued: the next move starts the program's first real move (found on mecode's output)
        stay = [i] if i >= 0 and i not in self.at_start and self.nom.moves[i].kind == "feed" else []
        advance = self.next_indices(start)
        if self.at_end(i, start):
            candidates = advance + stay  # prefer advancing once i is finished
        elif stay:
            candidates = stay + advance  # advancing now would leave i's end unreached
        else:
            candidates = advance
        tries = []
        for j in candidates:
            n = self.nom.moves[j]
            if n.kind != "feed":
                continue
            worst, bound, progress, msg = self.fit(c, j, self.progress if j == i else 0.0)
            if msg is None and (j == i or self.at_end(i, start)):
                self.accept(c, j, progress, worst, bound)
                return
            tries.append((worst, j, progress, msg, bound))
        if not tries:
            self.violation(c, f"a feed move where the original has {self.describe_nominal(i + 1)}")
            return
        worst, j, progress, msg, bound = min(tries, key=lambda t: t[0])  # nearest explanation
        if msg is None:
            self.check_end_reached(c, start)
        else:
            self.violation(c, msg)
        self.accept(c, j, progress, worst, bound)

    def accept(self, c, j, progress, worst, bound):
        if j != self.i and self.i >= 0 and self.match:
            self.check_abc(self.comp.moves[len(self.match) - 1], self.nom.moves[self.i])
        self.note(worst, bound, c)
        self.i, self.progress = j, progress

    def fit(self, c, j, progress):
        """Every sample of compensated feed c against nominal move j.

        Returns (largest deviation um, bound um, new progress, first violation or None)."""
        n = self.nom.moves[j]
        bound = self.limits.path_bound_um(n, c)
        if self.first_real_move(j) or self.from_reference(j):
            # the first move starts wherever the machine happens to be, and a move out of a
            # G28/G30 reference point starts at the controller's point, uncorrected in both
            # programs (mtec: "feed moves from an unknown start corrected at their end point
            # only"): end point only
            _, s = n.geom.nearest(displaced(self.model, c.end), n.length)
            self.end_only += 1
            return 0.0, bound, s, None
        worst, first, prev = 0.0, None, None
        for s in sample_lengths(c.geom, self.planes):
            p = c.geom.point(s)
            q = displaced(self.model, p)
            dev_mm, along = n.geom.nearest(q, progress)
            dev = dev_mm * 1e3
            self.samples += 1
            worst = max(worst, dev)
            if dev > bound and first is None:
                first = (f"point {fmt_point(p)} (at {s:.4f} of {c.length:.4f} mm) displaced to "
                         f"{fmt_point(q)} is {dev:.3f} um from the nominal path of {n.where()} "
                         f"> bound {bound:.3f} um")
            # progress moves on continuously: by at most the step between samples plus the bound
            step = 0.0 if prev is None else norm(sub(q, prev))
            if progress < along <= progress + step + 2 * bound * 1e-3 + 1e-9:
                progress = along
            elif (along < progress and n.geom.kind == "arc"
                  and norm(sub(n.end, n.start)) <= ZERO_LENGTH_MM
                  and n.length <= progress + step + 2 * bound * 1e-3 + 1e-9
                  and norm(sub(q, n.end)) * 1e3 <= bound):
                # a closed circle's end is its start: a point just past it (displaced, or the
                # printout's rounding) projects to the beginning, but the path has reached the end
                # (found by tests/rs274/generate.py seed 3)
                progress = n.length
            prev = q
        if first is not None:
            first += f" (largest on this move {worst:.3f} um)"
        return worst, bound, progress, first

    def first_real_move(self, j):
        """Nominal move j is the first the machine makes: every move before it stood where the
        machine was at the start (`stands_at_start`)."""
        return all(k in self.at_start for k in range(j))

    def from_reference(self, j):
        """Nominal move j and the compensated move being matched both start where a move to a
        G28/G30 reference point ended (found by a G1 straight after G28)."""
        if not self.match:
            return False
        return self.nom.moves[j - 1].reference and self.comp.moves[len(self.match) - 1].reference

    def check_abc(self, c, n):
        if any(abs(a - b) > 1e-4 for a, b in zip(c.abc, n.abc)):
            self.violation(c, f"rotary axes {c.abc} differ from the original's {n.abc} ({n.where()})")

    def describe_nominal(self, j):
        if j >= len(self.nom.moves):
            return "no more moves"
        n = self.nom.moves[j]
        return f"a {n.kind} move ({n.where()})"

    def unreached(self, start):
        n = self.nom.moves[self.i]
        d = norm(sub(start, n.end)) * 1e3
        return (f"starts before the nominal end point {fmt_point(n.end)} of {n.where()} was reached "
                f"(previous end displaced to {fmt_point(start)}, {d:.3f} um away; "
                f"{n.length - self.progress:.4f} mm of the nominal move left)")

    def finish(self):
        last = len(self.nom.moves) - 1
        while last > self.i and self.nom.moves[last].length <= ZERO_LENGTH_MM:
            last -= 1
        end = displaced(self.model, self.comp.moves[-1].end) if self.comp.moves else (0.0, 0.0, 0.0)
        if self.i < last:
            n = self.nom.moves[self.i + 1]
            self.violation(None, f"the compensated program ends before {n.where()} of the "
                                 f"original (and {last - self.i - 1} more moves) was executed")
        elif self.i >= 0 and not self.at_end(self.i, end):
            self.violation(None, f"the last compensated move ends {self.end_gap_um(self.i, end):.3f} um "
                                 f"from the nominal end of {self.nom.moves[self.i].where()}")


# offsets set from the current position (G92, G10 L20) differ by the correction there in a
# compensated program, by design: the rewritten program stands at the corrected point. Their
# values are not compared here; (b) and (c) check every position they lead to in machine mm.
OFFSET_CALLS = {"SET_G92_OFFSET": 0, "SET_G5X_OFFSET": 1}


def event_key(name, args):
    """What (d) compares of a call: everything, but only the system index of an offset."""
    if name in OFFSET_CALLS:
        return (name, tuple(a.strip() for a in args.split(",")[:OFFSET_CALLS[name]]))
    return (name, args)


def check_events(nominal, comp, match):
    """(d): the same non-motion calls, in the same order, between the same nominal moves.

    Returns the first violation or None."""
    ne, ce = nominal.events, comp.events
    for k in range(max(len(ne), len(ce))):
        if k >= len(ne) or k >= len(ce):
            extra = ce[k] if k < len(ce) else ne[k]
            side = "compensated" if k < len(ce) else "original"
            return (f"{comp.path}: canonical line {extra[3].seq}: {extra[0]}({extra[1]}) "
                    f"appears only in the {side} program")
        (n_name, n_args, n_idx, n_call), (c_name, c_args, c_idx, c_call) = ne[k], ce[k]
        if event_key(n_name, n_args) != event_key(c_name, c_args):
            return (f"{comp.path}: canonical line {c_call.seq}: {c_name}({c_args}) where the "
                    f"original has {n_name}({n_args}) (canonical line {n_call.seq})")
        at = match[c_idx] if 0 <= c_idx < len(match) else -1
        between = nominal.moves[at + 1:n_idx + 1]
        if at > n_idx or any(m.length > ZERO_LENGTH_MM for m in between):
            return (f"{comp.path}: canonical line {c_call.seq}: {c_name}({c_args}) comes after "
                    f"nominal move {at + 1} but the original has it after move {n_idx + 1} "
                    f"(canonical line {n_call.seq})")
        split = c_idx + 1 < len(match) and match[c_idx + 1] == at and at >= 0
        if split and nominal.moves[at].length > ZERO_LENGTH_MM:
            return (f"{comp.path}: canonical line {c_call.seq}: {c_name}({c_args}) falls between "
                    f"two pieces of one nominal move ({nominal.moves[at].where()})")
    return None


def check_inverse_time(nominal, comp, match):
    """(d) for G93: rs274 turns each inverse-time F into a feed in mm/min (length x F), so a
    compensated move's feed differs from the original's by the length change, and a split move
    has a feed per piece. What must hold is the time: the pieces of a nominal move together take
    as long as it does (T = L / f). Bound: the print rounding of each end point (length) and of
    each printed feed, on both sides. Returns the first violation or None."""
    times = {}
    for c, j in zip(comp.moves, match):
        if c.kind == "feed" and 0 <= j < len(nominal.moves):
            times.setdefault(j, []).append(c)
    for j, n in enumerate(nominal.moves):
        if n.inverse_time_feed_mm is None:
            continue
        pieces = times.get(j, [])
        for c in pieces:
            if c.inverse_time_feed_mm is not None:
                continue
            # a flattened program states the feed rs274 derived, in G94: the same number
            f_n, f_c = n.inverse_time_feed_mm, c.feed_mm
            tol = HALF_PRINT_UNIT * (n.mm_per_unit + c.mm_per_unit) + 1e-9
            if f_c is None or abs(f_c - f_n) > tol:
                return (f"{comp.path}: {n.where()} is an inverse-time (G93) move at {f_n:.4f} "
                        f"mm/min; a compensated piece of it runs at "
                        f"{'no feed per minute' if f_c is None else f'{f_c:.4f} mm/min'}")
        pieces = [c for c in pieces if c.inverse_time_feed_mm is not None]
        if not pieces or n.length <= ZERO_LENGTH_MM:
            continue

        def time_and_bound(m):
            f = m.inverse_time_feed_mm
            dl = 2 * SQRT3 * HALF_PRINT_UNIT * m.mm_per_unit  # both end points' rounding
            df = HALF_PRINT_UNIT * m.mm_per_unit  # the printed feed's rounding
            length = getattr(m.geom, "true_length", m.length)
            return length / f, dl / f + length * df / f ** 2
        t_n, b_n = time_and_bound(n)
        tb = [time_and_bound(c) for c in pieces]
        t_c, b_c = sum(t for t, _ in tb), sum(b for _, b in tb)
        if abs(t_c - t_n) > b_n + b_c + 1e-12:
            return (f"{comp.path}: {n.where()} is an inverse-time (G93) move of {t_n * 60:.6f} s; "
                    f"its {len(pieces)} compensated piece(s) take {t_c * 60:.6f} s "
                    f"(bound {(b_n + b_c) * 60:.2e} s)")
    return None


def long_lines(path, limit=MAX_LINE_CHARS):
    """(line number, length) of every line longer than `limit` characters."""
    out = []
    with open(path, "rb") as f:
        for no, line in enumerate(f, 1):
            n = len(line.rstrip(b"\r\n"))
            if n > limit:
                out.append((no, n))
    return out


def without_long_comments(path, workdir):
    """A copy without over-long comment-only lines, so (b)-(d) can still be checked."""
    out = os.path.join(workdir, "without-long-comments.ngc")
    with open(path, "rb") as f, open(out, "wb") as g:
        for line in f:
            body = line.rstrip(b"\r\n").strip()
            if len(body) > RS274_LINE_LIMIT and body.startswith(b"(") and body.endswith(b")"):
                continue
            g.write(line)
    return out


class Result:
    def __init__(self, nominal, comp, walker, violations):
        self.nominal_moves = len(nominal.moves)
        self.comp_moves = len(comp.moves)
        self.max_dev_um = walker.max_dev_um if walker else None
        self.max_dev_at = walker.max_dev_at if walker else ""
        self.bound_um = walker.max_bound_um if walker else None
        self.samples = walker.samples if walker else 0
        self.end_only = walker.end_only if walker else 0
        self.reference_moves = walker.reference_moves if walker else 0
        self.stopped = nominal.error
        self.violations = violations

    def summary(self, path):
        stop = f"; both stop at: {self.stopped}" if self.stopped else ""
        first = f"; {self.end_only} first moves checked at the end point only" if self.end_only else ""
        if self.reference_moves:
            first += f"; {self.reference_moves} moves to or from a G28/G30 reference point not checked"
        dev = "-" if self.max_dev_um is None else f"{self.max_dev_um:.3f}"
        bound = "-" if self.bound_um is None else f"{self.bound_um:.3f}"
        return (f"{path}: {self.nominal_moves} nominal moves, {self.comp_moves} compensated, "
                f"{self.samples} samples; max deviation {dev} um ({self.max_dev_at or '-'}), "
                f"largest bound {bound} um{first}{stop}")


def strip_comments(path):
    """The program's text without (comments) and ; comments."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read()
    return re.sub(r"\([^)\n]*\)|;[^\n]*", "", text)


def prepare_rs274_inputs(workdir, offsets=None, tool_table=None):
    """The var file and tool table rs274 needs to see the same offsets as mtec."""
    var_file = tbl = None
    tools = {}
    if offsets:
        active, work, tools = read_offsets(offsets)
        var_file = os.path.join(workdir, "offsets.var")
        write_var_file(var_file, active, work)
    if not tool_table:
        # the machine's table has the tools the program changes to; without a table from the
        # user their lengths are 0 (mtec refuses a G43 that would use one; since 2026-11-28
        # it flattens `T4 M6` alone, which rs274's built-in table of three tools stopped at)
        tools = {**{t: 0.0 for t in range(1, 1000)}, **(tools or {})}
        tbl = os.path.join(workdir, "tools.tbl")
        write_tool_table(tbl, tools)
    if tool_table:
        tbl = os.path.join(workdir, "tools-inch.tbl")
        convert_tool_table_to_inch(tool_table, tbl)
    return var_file, tbl


# what a flattened program (mtec --flatten-with rs274) must still do in the same order: the
# machine's actions. Its modes and offsets are restated or folded into the coordinates by
# design, and (b)/(c) already compare every position in machine coordinates.
# SET_FEED_RATE is left out: a flattened program states F just before the feed move that
# uses it (and M2 resets it differently); the feed in effect at every move is compared by
# crates/mtec-cli/tests/flatten_rs274.rs.
ACTION_CALLS = {
    "START_SPINDLE_CLOCKWISE", "START_SPINDLE_COUNTERCLOCKWISE",
    "STOP_SPINDLE_TURNING", "SET_SPINDLE_SPEED", "FLOOD_ON", "FLOOD_OFF", "MIST_ON", "MIST_OFF",
    "SELECT_TOOL", "CHANGE_TOOL", "DWELL", "PROGRAM_END", "PROGRAM_STOP", "OPTIONAL_PROGRAM_STOP",
    "PALLET_SHUTTLE",
}


def actions_only(prog):
    """The events of a program reduced to its actions, a repeated state (the same call with the
    same arguments as the last of its kind) dropped."""
    last, kept = {}, []
    for ev in prog.events:
        name, args = ev[0], ev[1]
        if name in ACTION_CALLS and last.get(name) != args:
            kept.append(ev)
            last[name] = args
    prog.events = kept


END_OF_FILE_WITHOUT_END = "File ended with no percent sign or program end"
ECHO_COORDINATE_RE = re.compile(r"[XYZIJKR]\s*[-+]?[\d.]+", re.IGNORECASE)


def same_stop(c_err, n_err):
    """Whether rs274 stops both programs the same way: the same message, and the same echoed
    line once its coordinates (X Y Z I J K R words) are taken out. The compensation changes
    the coordinates of the line rs274 stops at, e.g. at a move that carries a user M code the
    machine has and stand-alone rs274 does not ("Unknown m code used"). At the end of a file
    without M2/M30/% ("File ended with no percent sign or program end") the echo is the last
    line whatever it is: the same message is enough. The moves run before the stop are then
    checked as for a whole program."""
    if c_err == n_err:
        return True
    if not (c_err and n_err):
        return False
    (c_msg, _, c_line), (n_msg, _, n_line) = c_err.partition(" | "), n_err.partition(" | ")
    if c_msg == n_msg == END_OF_FILE_WITHOUT_END:
        # the echo is only the file's last line, which the compensation may rewrite in more
        # than its coordinates (an arc flattened to G1, a parameter or an F expression written
        # out, the motion mode made explicit); what ran before it is checked move by move
        return True
    squeeze = lambda t: ECHO_COORDINATE_RE.sub("", t).replace(" ", "").upper()  # noqa: E731
    return c_msg == n_msg and squeeze(c_line) == squeeze(n_line)


def check(original, compensated, model_path, offsets=None, tool_table=None, limits=None,
          flattened=False):
    """Runs (a)-(d); returns a Result whose `violations` lists the first violation of each
    check (empty: the compensated program is right). `flattened`: the compensated program was
    flattened by rs274, so (d) compares the machine's actions only."""
    limits = limits or Limits()
    model = load_model(model_path)
    violations = [f"{compensated}:{no}: line of {n} characters; LinuxCNC's limit is "
                  f"{MAX_LINE_CHARS}" for no, n in long_lines(compensated)[:1]]
    with tempfile.TemporaryDirectory(prefix="mtec-rs274-") as work:
        var_file, tbl = prepare_rs274_inputs(work, offsets, tool_table)
        n_calls, n_err = run_rs274(original, work, var_file, tbl)
        c_calls, c_err = run_rs274(compensated, work, var_file, tbl)
        if not same_stop(c_err, n_err):
            violations.append(f"{compensated}: rs274 does not read the compensated program as it "
                              f"reads the original: {c_err or 'no error'} (original: {n_err or 'no error'})")
            if long_lines(compensated, RS274_LINE_LIMIT):
                # go on without the over-long comments to report the path as well
                c_calls, c_err = run_rs274(without_long_comments(compensated, work), work, var_file, tbl)
        refs = None
        if same_stop(c_err, n_err) and any(REFERENCE_RE.search(strip_comments(p)) for p in (original, compensated)):
            ref_var = os.path.join(work, "reference.var")
            write_reference_var_file(ref_var, var_file)
            refs = [interpret(p, *run_rs274(p, work, ref_var, tbl)) for p in (original, compensated)]
    nominal = interpret(original, n_calls, n_err)
    comp = interpret(compensated, c_calls, c_err)
    if refs:
        mark_reference(nominal, refs[0])
        mark_reference(comp, refs[1])
    if flattened:
        actions_only(nominal)
        actions_only(comp)
    if not same_stop(c_err, n_err):
        return Result(nominal, comp, None, violations)
    walker = Walker(nominal, comp, model, limits)
    walker.run()
    violations += walker.violations[:1]
    if len(walker.violations) > 1:
        violations.append(f"... and {len(walker.violations) - 1} more path/end-point violations")
    event = check_events(nominal, comp, walker.match) or check_inverse_time(nominal, comp, walker.match)
    if event:
        violations.append(event)
    return Result(nominal, comp, walker, violations)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("original")
    ap.add_argument("compensated")
    ap.add_argument("--model", required=True, help="mtec.map/1 (or poly/zero) model JSON")
    ap.add_argument("--offsets", help="mtec.gcode-offsets/1 TOML given to mtec")
    ap.add_argument("--tool-table", help="LinuxCNC .tbl in mm given to mtec")
    ap.add_argument("--tolerance-um", type=float, default=0.5)
    ap.add_argument("--chord-tolerance-um", type=float, default=0.5)
    a = ap.parse_args(argv)
    try:
        res = check(a.original, a.compensated, a.model, a.offsets, a.tool_table,
                    Limits(a.tolerance_um, a.chord_tolerance_um))
    except CheckFailure as e:
        print(f"WRONG: {e}")
        return 1
    print(res.summary(a.compensated))
    for v in res.violations:
        print(f"WRONG: {v}")
    return 1 if res.violations else 0


if __name__ == "__main__":
    sys.exit(main())
