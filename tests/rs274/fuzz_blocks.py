"""Random single blocks inserted into a valid program (tests/rs274, 2026-11-28).

Each program sets up G21 G90 G17 G94, F, S and M3, then has one or two random blocks: random
G and M codes with random D E F H I J K L P Q R S T X Y Z words, some followed by a straight
move. rs274 stops at most of them; the point is that mtec refuses (at file:line:column) every
block LinuxCNC stops at, and never reports success on one. Run the result through run_all.py.

usage: python3 fuzz_blocks.py SEED COUNT OUT_DIR
"""
import random, sys, os
seed=int(sys.argv[1]); n=int(sys.argv[2]); out=sys.argv[3]
rnd=random.Random(seed)
os.makedirs(out, exist_ok=True)
G=['G0','G1','G2','G3','G4','G17','G18','G19','G20','G21','G40','G49','G53','G54','G55','G61','G61.1','G64','G80','G90','G91','G90.1','G91.1','G93','G94','G95','G96','G97','G98','G99','G43','G52','G92','G92.1','G10 L2 P1','G10 L20 P2','G28','G30','G7','G8','G43.1']
M=['M0','M1','M3','M4','M5','M7','M8','M9','M6','M48','M49','M50','M51','M52','M53','M60','M19','M62','M66','M100']
L='XYZIJKRPQFSTHDEL'
def num(l):
    if l in 'XYZ': return f"{rnd.uniform(-20,20):.3f}"
    if l in 'IJK': return f"{rnd.uniform(-5,5):.3f}"
    if l=='R': return f"{rnd.uniform(-8,8):.3f}"
    if l in 'PQ': return rnd.choice(['0','1','0.01','-1','2','0.5'])
    if l=='F': return rnd.choice(['0','100','250','-3','0.1'])
    if l=='S': return rnd.choice(['0','1000','-5','300'])
    if l in 'THD': return rnd.choice(['0','1','2','-1'])
    if l in 'EL': return rnd.choice(['0','1','2'])
    return f"{rnd.uniform(-30,30):.2f}"
for i in range(n):
    lines=['G21 G90 G17 G94','G0 X0 Y0 Z0','F200 S1000 M3','G1 X1 Y1']
    for k in range(rnd.randint(1,2)):
        parts=[]
        for _ in range(rnd.choice([0,1,1,2])): parts.append(rnd.choice(G))
        if rnd.random()<0.3: parts.append(rnd.choice(M))
        for l in rnd.sample(L, rnd.choice([0,1,2,2,3])):
            parts.append(l+num(l))
        rnd.shuffle(parts)
        if parts: lines.append(' '.join(parts))
        if rnd.random()<0.5: lines.append(f"G1 X{rnd.uniform(-20,20):.3f} Y{rnd.uniform(-20,20):.3f}")
    lines.append('M2')
    open(f"{out}/b{seed}_{i:03d}.ngc",'w').write('\n'.join(lines)+'\n')
