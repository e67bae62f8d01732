#!/usr/bin/env python3
"""Random plain G-code programs of the kind CAM post-processors write, for run_all.py.

    python3 tests/rs274/generate.py --out DIR --count 100 --seed 1
    python3 tests/rs274/run_all.py --mtec target/release/mtec --shared DIR --cases /nonexistent

Independent of mtec: it knows G-code (LinuxCNC's dialect), not the rewriter. Each program mixes,
at random: `%` wrappers, N numbers, upper/lower case and blanks inside words, number spellings
(`X1.`, `X.5`, `X-0.500`), comments in parentheses and after `;`, block-delete lines, G20/G21
(also switched mid-program), G17/G18/G19 arcs in centre (I J K) and radius (R, also negative)
form, helices, full circles and extra turns (P), modal motion (coordinates without a G word),
G90/G91 blocks, G90.1 absolute centres, work systems G54-G59 and G10 L2, G92 and G92.1, G53
moves, feed, spindle, coolant, dwell, tool change, G61/G64, parks at G28/G30 reference points
(G91 with zero words), `G0` beside the G80 of the preamble, and the end by M2, M30 or `%`.
Every arc is built valid: its end lies on its circle.
"""

import argparse
import math
import os
import random


class Gen:
    def __init__(self, rnd):
        self.r = rnd
        self.lines = []
        self.n = 0
        self.numbered = rnd.random() < 0.4
        self.lower = rnd.random() < 0.15
        self.inch = False
        self.plane = 0  # 0 XY, 1 XZ, 2 YZ
        self.incremental = False
        self.abs_centre = False
        self.pos = None  # current position in program units, None: unknown (start)
        self.motion = None

    # ---------------------------------------------------------------- formatting
    def digits(self):
        return 5 if self.inch else 4

    def q(self, v):
        """A value on the grid of the written digits (what the interpreter reads)."""
        return round(v, self.digits())

    def num(self, v):
        s = f"{v:.{self.digits()}f}"
        style = self.r.random()
        if style < 0.2:
            s = s.rstrip("0")  # "1." or "1.5"
        elif style < 0.3 and s.startswith(("0.", "-0.")):
            s = s.replace("0.", ".", 1)  # ".5", "-.5"
        return s

    def word(self, letter, v):
        sep = " " if self.r.random() < 0.1 else ""
        return f"{letter}{sep}{self.num(v)}"

    def emit(self, text, comment=None):
        if self.lower:
            text = text.lower()
        if self.numbered:
            self.n += 10
            text = f"N{self.n} {text}"
        if comment:
            text += f" ({comment})" if self.r.random() < 0.7 else f" ;{comment}"
        self.lines.append(text)

    def scale(self):
        return 1 / 25.4 if self.inch else 1.0

    # ---------------------------------------------------------------- geometry
    def point(self):
        s = self.scale()
        return [self.q(self.r.uniform(-150, 150) * s), self.q(self.r.uniform(-120, 120) * s),
                self.q(self.r.uniform(-40, 60) * s)]

    def move_words(self, target, axes=(0, 1, 2)):
        words = []
        for a in axes:
            v = target[a] - self.pos[a] if self.incremental else target[a]
            words.append(self.word("XYZ"[a], v))
        self.r.shuffle(words) if self.r.random() < 0.1 else None
        return words

    def line(self, rapid):
        target = self.point()
        axes = [a for a in range(3) if self.r.random() < 0.8] or [self.r.randrange(3)]
        for a in range(3):
            if a not in axes:
                target[a] = self.pos[a]
        code = "G0" if rapid else "G1"
        words = self.move_words(target, axes)
        if not rapid and self.r.random() < 0.3:
            words.append(self.word("F", self.r.uniform(50, 3000) * self.scale()))
        head = [] if self.motion == code and self.r.random() < 0.5 else [code]
        self.emit(" ".join(head + words))
        self.motion = code
        self.pos = target

    def arc(self):
        f, s, n = [(0, 1, 2), (2, 0, 1), (1, 2, 0)][self.plane]
        sc = self.scale()
        radius = self.r.uniform(2, 60) * sc
        start = self.pos
        phi0 = self.r.uniform(0, 2 * math.pi)
        centre = list(start)
        centre[f] = self.q(start[f] - radius * math.cos(phi0))
        centre[s] = self.q(start[s] - radius * math.sin(phi0))
        radius = math.hypot(start[f] - centre[f], start[s] - centre[s])
        cw = self.r.random() < 0.5
        full = self.r.random() < 0.1
        sweep = 2 * math.pi if full else self.r.uniform(0.05, 2 * math.pi - 0.05)
        phi1 = phi0 - sweep if cw else phi0 + sweep
        end = list(start)
        if full:
            end[f], end[s] = start[f], start[s]
        else:
            end[f] = self.q(centre[f] + radius * math.cos(phi1))
            end[s] = self.q(centre[s] + radius * math.sin(phi1))
        if self.r.random() < 0.3:
            end[n] = self.q(start[n] + self.r.uniform(-10, 10) * sc)  # helix
        code = "G2" if cw else "G3"
        use_r = not full and self.r.random() < 0.35
        words = []
        for a in (f, s):
            words.append(self.word("XYZ"[a], end[a] - start[a] if self.incremental else end[a]))
        if end[n] != start[n]:
            words.append(self.word("XYZ"[n], end[n] - start[n] if self.incremental else end[n]))
        elif full and self.r.random() < 0.5:
            words = []  # a full circle with no axis words
        if use_r:
            # R > 0: the shorter arc, R < 0: the longer; rounding of R must not break it
            r_val = radius if sweep <= math.pi else -radius
            if abs(sweep - math.pi) < 0.3:
                use_r = False
            else:
                words.append(self.word("R", r_val))
        if not use_r:
            for a in (f, s):
                off = centre[a] if self.abs_centre else centre[a] - start[a]
                words.append(self.word("IJK"[a], off))
            if self.r.random() < 0.05 and not full:
                words.append("P2")  # one extra turn
        if self.r.random() < 0.3:
            words.append(self.word("F", self.r.uniform(50, 2000) * sc))
        self.emit(" ".join([code] + words))
        self.motion = code
        self.pos = end

    # ---------------------------------------------------------------- program
    def program(self):
        r = self.r
        percent = r.random() < 0.3
        if percent:
            self.lines.append("%")
        self.lines.append("(generated by tests/rs274/generate.py)")
        self.inch = r.random() < 0.25
        pre = ["G17", "G90", "G94", "G40", "G49", "G80"]
        r.shuffle(pre)
        pre = pre[: r.randint(2, 6)] + ["G20" if self.inch else "G21"]
        if "G80" in pre and r.random() < 0.5:
            pre.append("G0")  # the safe-start line of many posts: LinuxCNC ignores the G80
        r.shuffle(pre)
        self.emit(" ".join(pre), "preamble")
        if r.random() < 0.5:
            self.emit(r.choice(["G54", "G55", "G56", "G59"]))
        if r.random() < 0.3:
            self.emit(r.choice(["G61", "G64 P0.01", "G64", "G61.1"]))
        # tools.tbl beside the programs (written by main): tools 1-9
        self.lines.insert(1 if percent else 0, "(mtec-options: --tool-table tools.tbl)")
        tool = r.randint(1, 9)
        self.emit(f"T{tool} M6", "tool change")
        if r.random() < 0.5:
            self.emit(f"G43 H{tool}")
        self.emit(f"S{r.randint(500, 18000)} M{r.choice([3, 4])}")
        if r.random() < 0.5:
            self.emit(r.choice(["M7", "M8", "M9"]))
        # the first move sets every axis: the start is unknown to a plain program's reader
        self.pos = [0.0, 0.0, 0.0]
        first = self.point()
        self.emit("G0 " + " ".join(self.move_words(first)))
        self.pos = first
        self.emit("G1 " + self.word("F", r.uniform(100, 2000) * self.scale()))
        self.motion = "G1"
        for _ in range(r.randint(15, 60)):
            k = r.random()
            if k < 0.3:
                self.line(rapid=r.random() < 0.25)
            elif k < 0.6:
                self.arc()
            elif k < 0.65:
                self.plane = r.randrange(3)
                self.emit(["G17", "G18", "G19"][self.plane])
            elif k < 0.7:
                self.incremental = not self.incremental
                self.emit("G91" if self.incremental else "G90")
            elif k < 0.72:
                self.abs_centre = not self.abs_centre
                self.emit("G90.1" if self.abs_centre else "G91.1")
            elif k < 0.75:
                # switch units: the position is the same, spelled in the other unit
                self.inch = not self.inch
                self.pos = [self.q(v * (1 / 25.4 if self.inch else 25.4)) for v in self.pos]
                self.emit("G20" if self.inch else "G21")
            elif k < 0.78:
                self.emit(r.choice(["M7", "M8", "M9", "M5", f"S{r.randint(500, 9000)} M3"]))
            elif k < 0.8:
                self.emit(f"G4 P{r.choice(['0.5', '1', '.2'])}", "dwell")
            elif k < 0.82:
                self.emit("(a comment line)")
            elif k < 0.84 and not self.incremental:
                # executed: rs274 and mtec run with the block delete switch off
                z = self.q(80 * self.scale())
                self.lines.append("/G0 Z" + self.num(z) + " (block delete)")
                self.pos = [self.pos[0], self.pos[1], z]
                self.motion = "G0"
            elif k < 0.86 and not self.incremental:
                # G92: the current point gets new coordinates
                new = self.point()
                self.emit("G92 " + " ".join(self.word("XYZ"[a], new[a]) for a in range(3)))
                self.pos = new
                self.g92 = True
            elif k < 0.87 and getattr(self, "g92", False):
                # G92.1 cancels: where the machine stands is unknown to the generator now
                self.emit("G92.1")
                self.g92 = False
                self.reposition()
            elif k < 0.89 and not self.incremental:
                m = [r.uniform(-100, 100) * self.scale() for _ in range(3)]
                self.emit("G53 G0 " + " ".join(self.word("XYZ"[a], m[a]) for a in range(3)))
                self.reposition()
            elif k < 0.9:
                w = r.choice([2, 3])
                off = [r.uniform(-50, 50) * self.scale() for _ in range(3)]
                self.emit(f"G10 L2 P{w} " + " ".join(self.word("XYZ"[a], off[a]) for a in range(3)))
                self.emit(f"G{53 + w}")
                self.reposition()
            elif k < 0.91:
                # a park at a reference point, as posts write it: G28/G30 with G91 and zero
                # words (the intermediate point is where the machine stands)
                was = self.incremental
                code = r.choice(["G28", "G30"])
                axes = r.choice(["Z0", "X0 Y0", "X0 Y0 Z0", "Z0."])
                self.emit(f"{code} G91 {axes}" if r.random() < 0.5 else f"G91 {code} {axes}")
                self.incremental = True
                if not was:
                    self.emit("G90")
                    self.incremental = False
                self.reposition()
            else:
                self.line(rapid=False)
        if self.incremental:
            self.emit("G90")
            self.incremental = False
        self.emit("G0 " + self.word("Z", 50 * self.scale()))
        self.emit("M5 M9")
        end = r.random()
        if percent and end < 0.5:
            self.lines.append("%")
        else:
            self.emit("M30" if end < 0.75 else "M2")
            if percent:
                self.lines.append("%")
        return "\n".join(self.lines) + "\n"

    def reposition(self):
        """An absolute move of every axis, in G90: the position is known again."""
        was = self.incremental
        if was:
            self.emit("G90")
            self.incremental = False
        p = self.point()
        self.emit("G0 " + " ".join(self.word("XYZ"[a], p[a]) for a in range(3)))
        self.pos = p
        self.motion = "G0"
        if was:
            self.emit("G91")
            self.incremental = True


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--count", type=int, default=50)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    # tool lengths in mm (run_all.py converts the table for rs274, mtec reads it in mm)
    with open(os.path.join(a.out, "tools.tbl"), "w") as f:
        for t in range(1, 10):
            f.write(f"T{t} P{t} Z{10.0 * t + 0.125 * t:.3f} D{2 * t:.1f} ;tool {t}\n")
    for i in range(a.count):
        text = Gen(random.Random(a.seed * 100003 + i)).program()
        with open(os.path.join(a.out, f"gen-{a.seed}-{i:04d}.ngc"), "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
