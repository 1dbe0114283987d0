"""Tip corners that bound the gap past the ends of the path of contact.
Delivery end (virtual contact l < A): gear 2's tip corner on its contacting flank.
Suction end (l > E): gear 1's tip corner on its contacting flank.
Returns |X2 - O1| (delivery) or |X1 - O2| (suction), the radius the cavity's
cut reaches on the other gear (the flux formula uses the endpoint radii)."""
import math
from geom import *
O1, O2 = (0.0, 0.0), (a, 0.0)

def _flank_sign(gear):
    # which flank (+1: c + half, -1: c - half) carries the contact; test at l = 0
    l = 0.3
    q = Q(l)
    c1, c2 = centres(l)
    if gear == 1:
        rc = math.hypot(q[0], q[1]); ang = math.atan2(q[1], q[0])
        best = min((abs(((c1 + s * half_angle(rb1, psib1, rc) - ang + math.pi) % (2*math.pi)) - math.pi), s) for s in (1, -1))
    else:
        rc = math.hypot(q[0] - a, q[1]); ang = math.atan2(q[1], q[0] - a)
        best = min((abs(((c2 + s * half_angle(rb2, psib2, rc) - ang + math.pi) % (2*math.pi)) - math.pi), s) for s in (1, -1))
    assert best[0] < 1e-9, best
    return best[1]
S1, S2 = _flank_sign(1), _flank_sign(2)

def corner2(l):
    c1, c2 = centres(l)
    th = c2 + S2 * half_angle(rb2, psib2, ra2)
    return (a + ra2 * math.cos(th), ra2 * math.sin(th))

def corner1(l):
    c1, c2 = centres(l)
    th = c1 + S1 * half_angle(rb1, psib1, ra1)
    return (ra1 * math.cos(th), ra1 * math.sin(th))

def r1_cut_delivery(l):
    x = corner2(l); return math.hypot(x[0], x[1])

def r2_cut_suction(l):
    x = corner1(l); return math.hypot(x[0] - a, x[1])

if __name__ == '__main__':
    print('flank signs', S1, S2)
    rc1 = lambda l: math.sqrt(rb1**2 + (T1P + l)**2)
    rc2 = lambda l: math.sqrt(rb2**2 + (T2P - l)**2)
    print('at A: corner2 -> O1', r1_cut_delivery(A), 'rc1(A)', rc1(A), ' corner2 vs Q(A)', corner2(A), Q(A))
    print('at E: corner1 -> O2', r2_cut_suction(E), 'rc2(E)', rc2(E), ' corner1 vs Q(E)', corner1(E), Q(E))
    for D in (0.5, 1, 1.5, 2, 2.5):
        print(D, 'del: r1cut', round(r1_cut_delivery(A - D), 4), 'rc1(virtual)', round(rc1(A - D), 4),
              ' suc: r2cut', round(r2_cut_suction(E + D), 4), 'rc2(virtual)', round(rc2(E + D), 4))
