"""Random modal programs (tests/rs274, 2026-11-28): G20/G21 switches (with F re-set), G90/G91,
G17/G18/G19, G52, G92/G92.1/G92.2, G10 L2/L20, path-control modes, parameters used in
expressions, G53 moves, G28/G30, G93 and G95 moves, and arcs written in G91 (R format with a
reachable radius, or centre words giving a half circle, with a helical rise and P turns),
plus cosmetic variation (lower case, N numbers, comments, no spaces). Run the result through
run_all.py (also with --flatten always).

usage: python3 fuzz_modal.py SEED COUNT OUT_DIR [words]

With `words` (added 2026-11-28, after a stop on a split move was found), a fifth of the moves
and arcs also carry words LinuxCNC runs before the motion (M3/M5, M7/M8/M9, S, G4 P) or after
it (M0, M1, M60), and some programs end with M30 on their last move; without it the programs of
a seed are as before.
"""
import random, sys, os
seed=int(sys.argv[1]); n=int(sys.argv[2]); out=sys.argv[3]
words=len(sys.argv) > 4 and sys.argv[4] == "words"
rnd=random.Random(seed); os.makedirs(out, exist_ok=True)
wrnd=random.Random(seed + 1000003)  # its own stream: the programs' moves stay those of the seed
def extra():
    if not words or wrnd.random() >= 0.2: return ""
    return " " + wrnd.choice(["M0", "M1", "M60", "M5", "M3 S800", "M8", "M9", "M7", "G4 P0.1", "M5 M0", "M9 M1"])
def f(v): return f"{v:.4f}".rstrip('0').rstrip('.') if rnd.random()<0.7 else f"{v:.3f}"
for i in range(n):
    L=['G21 G90 G17 G94 G40 G49 G80','G0 X0 Y0 Z0','S1000 M3','F300']
    st=dict(inch=False, inc=False, plane=17, mode='G94', par=0)
    for k in range(rnd.randint(8,25)):
        s=1/25.4 if st['inch'] else 1.0
        c=rnd.random()
        if c<0.06:
            st['inch']=not st['inch']; L.append(('G20' if st['inch'] else 'G21')+f" F{300/25.4 if st['inch'] else 300:.3f}")
        elif c<0.12:
            st['inc']=not st['inc']; L.append('G91' if st['inc'] else 'G90')
        elif c<0.17:
            st['plane']=rnd.choice([17,18,19]); L.append(f"G{st['plane']}")
        elif c<0.21:
            L.append(rnd.choice([f"G52 X{f(rnd.uniform(-20,20)*s)} Y{f(rnd.uniform(-20,20)*s)}", "G52 X0 Y0 Z0", f"G52 Z{f(rnd.uniform(-5,5)*s)}"]))
        elif c<0.25:
            L.append(rnd.choice([f"G92 X{f(rnd.uniform(-20,20)*s)} Y{f(rnd.uniform(-20,20)*s)}", "G92.1", "G92.2", f"G92 Z{f(rnd.uniform(-5,5)*s)}"]))
        elif c<0.29:
            l=rnd.choice([2,20]); L.append(f"G10 L{l} P{rnd.choice([0,1])} X{f(rnd.uniform(-30,30)*s)} Z{f(rnd.uniform(-5,5)*s)}")
        elif c<0.32:
            L.append(rnd.choice(['G64 P0.005 Q0','G61','G61.1','G64']))
        elif c<0.35:
            st['par']+=1; v=rnd.uniform(-10,10)*s
            L.append(f"#{100+st['par']} = {f(v)}"); L.append(f"G1 X[#{100+st['par']} + {f(rnd.uniform(0,3)*s)}] Y{f(rnd.uniform(-10,10)*s)}")
        elif c<0.38 and not st['inc']:
            L.append(f"G53 G0 Z{f(rnd.uniform(-10,0)*s)}")
        elif c<0.395:
            L.append(rnd.choice(["G28", "G30", "G28 Z0" if not st['inc'] else "G28"]) ); L.append("G0 X1 Y1 Z1" if not st['inc'] else "G0 X1")
        elif c<0.42:
            L.append(f"G93 G1 X{f(rnd.uniform(-10,10)*s)} Y{f(rnd.uniform(-10,10)*s)} F{rnd.choice([5,10,20])}"); L.append(f"G94 F{300*s:.3f}")
        elif c<0.45:
            L.append(f"G95 F{0.1*s:.4f}"); L.append(f"G1 X{f(rnd.uniform(-10,10)*s)}") if not st['inc'] else L.append(f"G1 X{f(rnd.uniform(-3,3)*s)}"); L.append(f"G94 F{300*s:.3f}")
        elif c<0.70:
            # arc, incremental end with R, or centre words
            p=st['plane']; a,b={17:('X','Y'),18:('Z','X'),19:('Y','Z')}[p]; ci={17:('I','J'),18:('K','I'),19:('J','K')}[p]
            da,db=rnd.uniform(-8,8)*s, rnd.uniform(-8,8)*s
            g=rnd.choice(['G2','G3'])
            if rnd.random()<0.5:
                d=(da*da+db*db)**0.5; r=d/2*rnd.uniform(1.05,3); r=-r if rnd.random()<0.3 else r
                L.append(f"G91 {g} {a}{f(da)} {b}{f(db)} R{f(r)}" + extra() + ("" if st['inc'] else "\nG90"))
            else:
                # centre words (incremental IJK default), end = start + 2*centre -> half circle
                third={17:'Z',18:'Y',19:'X'}[p]
                hel=f" {third}{f(rnd.uniform(-2,2)*s)}" if rnd.random()<0.4 else ""
                turns=f" P{rnd.choice([1,2])}" if rnd.random()<0.2 else ""
                L.append(f"G91 {g} {a}{f(2*da)} {b}{f(2*db)}{hel} {ci[0]}{f(da)} {ci[1]}{f(db)}{turns}" + extra() + ("" if st['inc'] else "\nG90"))
        else:
            g=rnd.choice(['G0','G1','G1','G1'])
            if st['inc']:
                L.append(f"{g} X{f(rnd.uniform(-10,10)*s)} Y{f(rnd.uniform(-10,10)*s)}" + (f" Z{f(rnd.uniform(-2,2)*s)}" if rnd.random()<0.3 else "") + extra())
            else:
                L.append(f"{g} X{f(rnd.uniform(-30,30)*s)} Y{f(rnd.uniform(-30,30)*s)}" + (f" Z{f(rnd.uniform(-5,5)*s)}" if rnd.random()<0.3 else "") + extra())
    if words and wrnd.random() < 0.3:
        L.append("G90 G1 X40 Y-35 M30")
    else:
        L.append('M2')
    def cosm(line):
        if rnd.random()<0.15: line=line.lower()
        if rnd.random()<0.1: line=f"N{rnd.randint(1,99999)} "+line
        if rnd.random()<0.1: line=line+" (c "+str(rnd.randint(0,9))+")"
        if rnd.random()<0.05: line=line+" ; tail"
        if rnd.random()<0.05: line=line.replace(" ","")
        return line
    L=[cosm(x) if not x.startswith('#') and '\n' not in x else x for x in L]
    open(f"{out}/m{seed}_{i:03d}.ngc",'w').write('\n'.join(L)+'\n')
