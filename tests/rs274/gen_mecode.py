#!/usr/bin/env python3
"""Random G-code programs written by mecode (pip `mecode`, Lewis Lab, Harvard), an independent
generator, for run_all.py: its own G91/G90 handling, R and IJK arcs in all three planes,
helices, meanders, rectangles, triangular waves, G92 "set home", dwells and feed changes, in
mm or inch, and a bare `G1 F..` as its first block. mecode is not installed by CI; it runs by
hand:

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install mecode
    /tmp/venv/bin/python tests/rs274/gen_mecode.py --out DIR --count 300 --seed 100
    python3 tests/rs274/run_all.py --mtec $PWD/target/release/mtec --cases DIR --jobs 2

Some programs are invalid by construction (mecode's R arcs with a radius short of half the
chord, its G16 axis assignment, which LinuxCNC does not know): LinuxCNC stops on them and mtec
must refuse them. What it found (2026-11-29, 300 programs, seeds 100-399): the checker's
blind spot for a bare G1 first (check.py), an unchecked arc and a kept R after G92 (the
rewriter). Inch programs at scale 5 make paths of metres in 0.05 mm samples: the check takes
up to a minute each.
"""

import argparse
import math
import random

from mecode import G


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--seed", type=int, default=100)
    a = ap.parse_args()
    out, n0, n1 = a.out, a.seed, a.seed + a.count
    for seed in range(n0, n1):
        r = random.Random(seed)
        path = f"{out}/mecode_{seed:04d}.ngc"
        g = G(outfile=path, print_lines=False, output_digits=r.choice([3,4,6]), header=None, footer=None, setup=True)
        g.write(r.choice(["G21 G17 G94", "G21 G17 G94 G90", "G20 G17 G94"]))
        g.feed(r.choice([300, 1200]))
        s = r.choice([0.05, 1.0, 5.0])
        for k in range(r.randint(5, 25)):
            op = r.choice(["move", "abs_move", "arc", "arc_ijk", "meander", "rect", "tri", "home", "rapid", "set_home", "rel", "abs", "abs_arc", "dwell", "feed"])
            try:
                if op == "move": g.move(x=s*r.uniform(-30,30), y=s*r.uniform(-30,30), z=r.choice([None, s*r.uniform(-3,3)]))
                elif op == "abs_move": g.abs_move(x=s*r.uniform(-80,80), y=s*r.uniform(-80,80), z=s*r.uniform(-5,5))
                elif op == "rapid": g.rapid(x=s*r.uniform(-20,20), y=s*r.uniform(-20,20), z=r.choice([None, s*r.uniform(-3,3)]))
                elif op == "arc":
                    d = r.choice(["CW", "CCW"]); x, y = s*r.uniform(-20,20), s*r.uniform(-20,20)
                    rad = (x*x+y*y)**0.5/2 * r.choice([1.0, 1.3, -1.3, 3])
                    g.arc(x=x, y=y, direction=d, radius=rad, helix_dim=r.choice([None, 'z']), helix_len=s*r.uniform(-2,2))
                elif op == "abs_arc":
                    d = r.choice(["CW", "CCW"]); x, y = s*r.uniform(-50,50), s*r.uniform(-50,50)
                    g.abs_arc(x=x, y=y, direction=d, radius=s*r.uniform(30, 80))
                elif op == "arc_ijk":
                    # a centre that keeps the end on the circle: pick centre, radius from the start
                    ang = r.uniform(0, 6.283); rr = s*r.uniform(2, 20)
                    cx, cy = s*r.uniform(-10,10), s*r.uniform(-10,10)
                    # relative target so that |start - c| = |end - c| in the plane (start = origin of the move)
                    rad = math.hypot(cx, cy)
                    tx, ty = cx + rad*math.cos(ang), cy + rad*math.sin(ang)
                    g.arc_ijk(target=[tx, ty], center=[cx, cy], plane=r.choice(['xy','yz','xz']), direction=r.choice(['CW','CCW']), helix_len=r.choice([None, s*r.uniform(-2,2)]))
                elif op == "meander": g.meander(s*r.uniform(5,30), s*r.uniform(5,30), s*r.uniform(1,5), orientation=r.choice(['x','y']))
                elif op == "rect": g.rect(s*r.uniform(5,30), s*r.uniform(5,30), start=r.choice(['LL','UL','LR','UR']), direction=r.choice(['CW','CCW']))
                elif op == "tri": g.triangular_wave(s*r.uniform(1,5), s*r.uniform(1,5), r.randint(2,6), orientation=r.choice(['x','y']))
                elif op == "home": g.home()
                elif op == "set_home": g.set_home(x=s*r.uniform(-10,10), y=s*r.uniform(-10,10), z=r.choice([None, s*r.uniform(-2, 2)]))
                elif op == "rel": g.relative()
                elif op == "abs": g.absolute()
                elif op == "dwell": g.dwell(r.choice([0.5, 1]))
                elif op == "feed": g.feed(r.choice([50, 300, 2000]))
            except Exception as e:
                g.write(f"; skipped {op}: {type(e).__name__}")
        g.write("M2")
        g.teardown()


if __name__ == "__main__":
    main()
