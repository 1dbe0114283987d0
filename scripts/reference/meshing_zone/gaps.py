"""Gap between the two gears' outlines past the ends of the path of contact.

For a tooth pair whose (virtual) contact is at l, the gap at the would-be
contact is the minimum distance between the two teeth's outlines near Q(l).
Delta = distance past the end of the path along the line of action
(delivery end: Delta = A - l; suction end: Delta = l - E).
Also: the profile h(s) of the passage through the narrowest point, for the
laminar integral I3 = int ds / h^3, and the backlash-side gap.
Writes gaps.csv.
"""
import math, sys
from geom import *

O1, O2 = (0.0, 0.0), (a, 0.0)

def teeth(l, k1=(0,), k2=(0,)):
    c1, c2 = centres(l)
    t1 = {k: tooth_outline(rb1, psib1, ra1, rf1, c1 + 2 * math.pi * k / z1, O1) for k in k1}
    t2 = {k: tooth_outline(rb2, psib2, ra2, rf2, c2 + 2 * math.pi * k / z2, O2) for k in k2}
    return c1, c2, t1, t2

def near(pts, q, R):
    return [p for p in pts if math.hypot(p[0] - q[0], p[1] - q[1]) < R]

def dist_to_poly(p, poly):
    return min(seg_dist(p, poly[i], poly[i + 1]) for i in range(len(poly) - 1))

def gap_at(l, R=2.0):
    c1, c2, t1, t2 = teeth(l)
    q = Q(l)
    a1 = near(t1[0], q, R)
    a2 = near(t2[0], q, R)
    d, p, pq = min_dist(a1, a2)
    return d, p, a1, a2

def profile_integral(d0, p0, a1, a2, hmax_factor=20.0):
    """h(s) along whichever outline carries the closest point (the corner),
    from the corner outwards both ways; I3 = int ds/h^3 (mm^-2)."""
    # decide which polyline p0 belongs to
    own, other = (a1, a2) if p0 in a1 else (a2, a1)
    i0 = own.index(p0)
    I3 = 0.0
    prof = []
    for step in (+1, -1):
        i = i0
        hprev = dist_to_poly(own[i], other)
        while 0 <= i + step < len(own):
            j = i + step
            h = dist_to_poly(own[j], other)
            ds = math.hypot(own[j][0] - own[i][0], own[j][1] - own[i][1])
            hm = 0.5 * (h + hprev)
            I3 += ds / hm**3
            prof.append((step, own[j][2], h))
            if h > hmax_factor * d0:
                break
            hprev = h
            i = j
    return I3, prof, own[i0][2]

if __name__ == '__main__':
    out = open('gaps.csv', 'w')
    out.write('end,Delta_mm,l_mm,h_min_um,corner_tag,I3_per_mm2,Leff_mm\n')
    Ds = [0.0, 0.01, 0.02, 0.03, 0.05, 0.075, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2]
    for end in ('delivery', 'suction'):
        for D in Ds:
            l = A - D if end == 'delivery' else E + D
            d, p, a1, a2 = gap_at(l)
            if d > 1e-4:
                I3, prof, tag = profile_integral(d, p, a1, a2)
                Leff = I3 * d**3
            else:
                I3, tag, Leff = float('inf'), p[2], float('nan')
            which = 'gear1' if p in a1 else 'gear2'
            print(f"{end:8s} Delta={D:5.3f} l={l:8.4f} h_min={1000*d:9.3f} um  closest point on {which} {tag} r={p[3]:.4f}  Leff={Leff:.4f} mm")
            out.write(f"{end},{D},{l:.5f},{1000*d:.4f},{which}-{tag},{I3:.6g},{Leff:.6g}\n")
    out.close()
