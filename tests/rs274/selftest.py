#!/usr/bin/env python3
"""Self-test of check.py without mtec: the checker accepts right programs and rejects wrong ones.

  1. a case checked against itself with a zero model passes;
  2. a constant error e is compensated exactly by moving every absolute X/Y/Z word by -e
     (centres I/J/K are relative, R is unchanged): those hand-made programs must pass, in every
     plane, for helices, full circles and inch programs;
  3. the same programs moved by -e + 3 um per axis (6 um in inch programs, whose printout is
     coarser), or with one word moved by 10 um, must fail;
  4. G28/G30 moves are matched without an end-point check, the moves after them are checked
     (a feed straight out of one at its end point);
  5. the G18 reading of ARC_FEED: G2 X50 Z0 I20 K0 from X10 Z0 passes through Z = -20.

    python3 tests/rs274/selftest.py     # prints "selftest: N passed" or the failures, exit 1
"""

import json
import os
import re
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import check  # noqa: E402

CASES = os.path.join(HERE, "cases")
# programs whose axis words are all absolute literal mm (or inch) values
TRANSLATABLE = ["arc-g17-cw-quarter", "arc-g18-cw", "arc-g18-ccw", "arc-g19-cw", "arc-g19-ccw",
                "helix-g17", "helix-g18-g19", "helix-turns", "full-circle-no-axis-words",
                "full-circle-p2", "r-semicircle", "r-negative-large", "mixed-planes",
                "g20-inch-arcs", "events-spindle-coolant", "back-and-forth", "g93-inverse-time",
                "bare-g1-first"]
E_UM = (20.0, -15.0, 10.0)
WORD = re.compile(r"([XYZxyz])(-?\d*\.?\d+)")


def constant_map(path, e_um):
    axis = [-5000.0, 5000.0]
    doc = {"format": "mtec.map/1", "model": "trilinear", "outside": "clamp",
           "x_mm": axis, "y_mm": axis, "z_mm": axis,
           "ex_um": [e_um[0]] * 8, "ey_um": [e_um[1]] * 8, "ez_um": [e_um[2]] * 8}
    with open(path, "w", encoding="utf-8") as f:
        json.dump(doc, f)


def translated(text, shift_um):
    """Every X/Y/Z word moved by shift (um), in the units of the line (G20 lines in inches)."""
    out, inch = [], False
    for line in text.splitlines():
        code = line.split("(")[0].upper()
        if "G20" in code:
            inch = True
        if "G21" in code:
            inch = False
        if line.lstrip().startswith("("):
            out.append(line)
            continue
        per_unit = 25.4 if inch else 1.0

        def move(m):
            a = "xyz".index(m.group(1).lower())
            v = float(m.group(2)) + shift_um[a] * 1e-3 / per_unit
            return f"{m.group(1)}{v:.6f}"

        out.append(WORD.sub(move, line))
    return "\n".join(out) + "\n"


def outcome(original, text, model, work, name):
    path = os.path.join(work, name)
    with open(path, "w", encoding="ascii") as f:
        f.write(text)
    return check.check(original, path, model).violations


def g18_direction(work):
    prog = os.path.join(work, "g18.ngc")
    with open(prog, "w", encoding="ascii") as f:
        f.write("G21 G90 G18\nG0 X10 Y0 Z0\nG2 X50 Z0 I20 K0 F100\nM2\n")
    calls, err = check.run_rs274(prog, work)
    arc = [m for m in check.interpret(prog, calls, err).moves if m.geom.kind == "arc"][0]
    mid = arc.geom.point(arc.length / 2)
    return abs(mid[0] - 30) < 1e-6 and abs(mid[2] + 20) < 1e-6, mid


def main():
    failures, passed = [], 0
    with tempfile.TemporaryDirectory(prefix="mtec-rs274-self-") as work:
        zero = os.path.join(work, "zero.json")
        constant = os.path.join(work, "constant.json")
        constant_map(zero, (0.0, 0.0, 0.0))
        constant_map(constant, E_UM)
        for stem in TRANSLATABLE:
            prog = os.path.join(CASES, stem + ".ngc")
            v = check.check(prog, prog, zero).violations
            (failures.append(f"{stem} against itself: {v[0]}") if v else None)
            passed += not v
            text = open(prog, encoding="utf-8").read()
            right = translated(text, tuple(-e for e in E_UM))
            v = outcome(prog, right, constant, work, stem + ".right.ngc")
            (failures.append(f"{stem} compensated exactly: {v[0]}") if v else None)
            passed += not v
            # 3 um per axis is 5.2 um: beyond the 0.67 um end-point bound of a mm program but
            # within the 4.9 um of an inch one (rs274 prints 4 decimals of an inch); 6 um per
            # axis (10.4 um) for inch programs
            miss = 6.0 if "G20" in text else 3.0
            off = translated(text, tuple(-e + miss for e in E_UM))
            v = outcome(prog, off, constant, work, stem + ".off.ngc")
            (failures.append(f"{stem} off by 3 um per axis was accepted") if not v else None)
            passed += bool(v)
        # G28/G30 moves end at the controller's reference points, not compensated; a move
        # after them that names every axis absolutely is checked like any other
        prog = os.path.join(CASES, "g28-reference-park.ngc")
        text = open(prog, encoding="utf-8").read()
        keep_ref = lambda t, sh: "\n".join(  # noqa: E731
            ln if re.search(r"G28|G30", ln.split("(")[0]) else translated(ln, sh).rstrip("\n")
            for ln in t.splitlines()) + "\n"
        v = outcome(prog, keep_ref(text, tuple(-e for e in E_UM)), constant, work, "g28.right.ngc")
        (failures.append(f"g28-reference-park compensated exactly: {v[0]}") if v else None)
        passed += not v
        wrong = keep_ref(text, tuple(-e for e in E_UM)).replace("G0 X29.98", "G0 X30.0")
        v = outcome(prog, wrong, constant, work, "g28.wrong.ngc")
        (failures.append("g28-reference-park: a move after G28 left uncompensated was accepted")
         if not v else None)
        passed += bool(v)
        # a feed straight out of a reference point is checked at its end point: left
        # uncompensated there, it must fail
        prog = os.path.join(CASES, "g28-then-feed.ngc")
        text = open(prog, encoding="utf-8").read()
        right = keep_ref(text, tuple(-e for e in E_UM))
        v = outcome(prog, right, constant, work, "g28feed.right.ngc")
        (failures.append(f"g28-then-feed compensated exactly: {v[0]}") if v else None)
        passed += not v
        wrong = right.replace("G1 X19.98", "G1 X20.0")
        v = outcome(prog, wrong, constant, work, "g28feed.wrong.ngc")
        (failures.append("g28-then-feed: a feed out of G28 left uncompensated was accepted")
         if not v or "G1 X19.98" not in right else None)
        passed += bool(v)
        # G93: a move split in two pieces that each keep the move's F takes twice as long
        prog = os.path.join(CASES, "g93-inverse-time.ngc")
        right = translated(open(prog, encoding="utf-8").read(), tuple(-e for e in E_UM))
        first = next(ln for ln in right.splitlines() if ln.startswith("G93 G1"))
        words = dict(re.findall(r"([XYF])(-?[\d.]+)", first))
        mid = [(float(words[a]) - E_UM[i] * 1e-3) / 2 for i, a in enumerate("XY")]  # from X0 Y0
        half = f"G93 G1 X{mid[0]:.6f} Y{mid[1]:.6f} F{words['F']}"
        slow = right.replace(first, half + "\n" + first.replace("G93 ", ""))
        v = outcome(prog, slow, constant, work, "g93.slow.ngc")
        ok = len(v) == 1 and "inverse-time (G93) move of 10.000000 s" in v[0]
        (failures.append(f"g93-inverse-time: a split move that doubles its duration: {v}")
         if not ok else None)
        passed += ok
        # a program without M2/M30/%: rs274 stops both at the end of the file, each echoing its
        # own last line, which the compensation may rewrite in more than its coordinates; the
        # moves decide, so a compensated program that lost its last move must still fail
        prog = os.path.join(CASES, "no-program-end.ngc")
        lines = translated(open(prog, encoding="utf-8").read(),
                           tuple(-e for e in E_UM)).splitlines()
        right = "\n".join(lines[:-1] + ["G90 " + lines[-1]]) + "\n"
        v = outcome(prog, right, constant, work, "noend.right.ngc")
        (failures.append(f"no-program-end with its last line rewritten: {v[0]}") if v else None)
        passed += not v
        v = outcome(prog, "\n".join(lines[:-1]) + "\n", constant, work, "noend.short.ngc")
        (failures.append("no-program-end: a compensated program without the last move was "
                         "accepted") if not v else None)
        passed += bool(v)
        ok, mid = g18_direction(work)
        (failures.append(f"G18 G2 midpoint {mid}, expected (30, 0, -20)") if not ok else None)
        passed += ok
    for f in failures:
        print(f"FAIL: {f}")
    print(f"selftest: {passed} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
