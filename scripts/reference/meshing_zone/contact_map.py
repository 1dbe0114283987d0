"""Contacts per transverse section over one mesh period. Time is the position u = l0 - A
of the reference contact line at zeta = 0 (contact travels at rb1*omega, so u is
uniform in time over one pbt). Lines at l = l0 + j pbt + zeta tan(beta_b)."""
import math
from geom import *
tb = math.tan(betab)
print(f"A={A:.3f} E={E:.3f} pbt={pbt:.4f} b*tan(bb)={b*tb:.4f}")
print("u/pbt | sections (zeta mm): number of contacts | lines spanning the full face | delivery->suction path")
for i in range(20):
    u = pbt * i / 20
    l0 = A + u
    segs = []
    full = []
    cnts = []
    for k in range(261):
        z = b * k / 260
        c = sum(1 for j in range(-2, 3) if A <= l0 + j * pbt + z * tb <= E)
        cnts.append(c)
    for j in range(-2, 3):
        lo, hi = l0 + j * pbt, l0 + j * pbt + b * tb
        if lo >= A and hi <= E:
            full.append(j)
    # compress counts
    runs = []; start = 0
    for k in range(1, 262):
        if k == 261 or cnts[k] != cnts[start]:
            runs.append(f"{b*start/260:4.1f}-{b*(k-1)/260:4.1f}:{cnts[start]}")
            start = k
    path = 'sealed' if full else 'OPEN'
    print(f"{u/pbt:5.2f} | {'  '.join(runs):40s} | {full} | {path}")
