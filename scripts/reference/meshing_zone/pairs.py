"""Which tooth pairs touch / nearly touch as a function of l (virtual contact of pair (0,0)).
Prints the min distance for gear-1 tooth k1 vs gear-2 tooth k2, k in -1..1, and the
gear-1 / gear-2 tip-to-mating-root-circle clearances."""
import math
from geom import *
from gaps import teeth, O1, O2
for l in [A-1.0, A-0.3, A, A+0.5*pbt*0.2, 0.0, E-0.5, E, E+0.3, E+1.0]:
    c1, c2, t1, t2 = teeth(l, k1=(-1,0,1), k2=(-1,0,1))
    row = []
    for k1_ in (-1,0,1):
        for k2_ in (-1,0,1):
            # quick reject
            p1 = [p for p in t1[k1_] if math.hypot(p[0]-a, p[1]) < ra2+0.5]
            p2 = [p for p in t2[k2_] if math.hypot(p[0], p[1]) < ra1+0.5]
            if not p1 or not p2:
                continue
            d = min_dist(p1[::3], p2[::3])[0]
            if d < 1.0:
                row.append(f"({k1_:+d},{k2_:+d}):{1000*d:7.1f}")
    print(f"l={l:7.3f}  ", "  ".join(row))
