"""Raster geometry of the meshing-zone cavity of one transverse section.

Independent of the project's code: the involute geometry comes from
../meshing_zone/geom.py (pure Python, written without the model's code).

The cavity between two consecutive driving-flank contacts: newer contact at
l = L (delivery side), older at L + pbt. It is the union of
  * the gear-1 tooth space between tooth T_b (driving flank contact at L)
    and T_a (contact at L + pbt), on gear 1's side of the line of action
    (LOA) where it lies inside gear 2's tip circle, and
  * the gear-2 tooth space between S_b and S_a, on gear 2's side of the
    LOA where it lies inside gear 1's tip circle,
minus both gears' solid. This is the split by the LOA inside the lens that
docs/model.md section 3 describes (the pocket of a gear is the fluid of one
of its tooth spaces on its own side of the LOA inside the lens). When L < A
(or L + pbt > E) the contact is virtual and the section is open to the
neighbouring space through the gap past the end of the path of contact.

Units mm, rad. Frame of geom.py: O1 = (0,0), O2 = (a,0), y = common tangent
(delivery side -y, suction side +y).
"""
import math, os, sys
import numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'meshing_zone'))
from geom import *   # noqa  (z1, z2, rb1, ..., centres, A, E, pbt, DESIGN)

O2x = a
_c = DESIGN['casing']
def _edge(v):
    return pbt * math.cos(aw) / 2 if v == 'auto' else float(v)
eD = _edge(_c['delivery_groove_edge_mm'])
eS = _edge(_c['suction_groove_edge_mm'])
GW = float(os.environ.get('GROOVE_BAND_MM', _c['groove_width_mm']))   # planform band of the grooves (sensitivity: GROOVE_BAND_MM)
GD = _c['groove_depth_mm']
XG = rw1       # groove band along the line of centres: assumed centred on the pitch point
tn = (math.cos(aw), -math.sin(aw))   # unit normal of the LOA pointing to gear 2's side


def _half(rb, psib, r):
    c = np.clip(rb / np.maximum(r, 1e-9), -1, 1)
    al = np.arccos(c)
    return np.where(r > rb, psib - (np.tan(al) - al), psib)


def _in_gear(x, y, cx, rb, psib, ra, rf, c0, z):
    dx = x - cx
    r = np.hypot(dx, y)
    ph = np.arctan2(y, dx)
    p = 2 * np.pi / z
    d = (ph - c0 + p / 2) % p - p / 2
    return (r <= rf) | ((r <= ra) & (np.abs(d) <= _half(rb, psib, r))), r, ph


def _in_sector(ph, lo, hi):
    """angle ph within [lo, hi] (mod 2 pi), hi - lo < 2 pi"""
    return ((ph - lo) % (2 * np.pi)) <= ((hi - lo) % (2 * np.pi))


def masks(L, x, y):
    c1, c2 = centres(L)
    s1, r1_, ph1 = _in_gear(x, y, 0.0, rb1, psib1, ra1, rf1, c1, z1)
    s2, r2_, ph2 = _in_gear(x, y, O2x, rb2, psib2, ra2, rf2, c2, z2)
    fluid = ~(s1 | s2)
    side = (x - P[0]) * tn[0] + (y - P[1]) * tn[1]        # > 0: gear 2's side of the LOA
    sec1 = _in_sector(ph1, c1, c1 + 2 * np.pi / z1)
    sec2 = _in_sector(ph2, c2 - 2 * np.pi / z2, c2)
    g1 = fluid & sec1 & (r1_ < ra1) & ((side <= 0) | (r2_ >= ra2))
    g2 = fluid & sec2 & (r2_ < ra2) & ((side > 0) | (r1_ >= ra1))
    g2 &= ~g1
    return g1, g2


def _grid(x0, x1, y0, y1, h):
    xs = np.arange(x0 + h / 2, x1, h)
    ys = np.arange(y0 + h / 2, y1, h)
    X, Y = np.meshgrid(xs, ys, indexing='ij')
    return X, Y


def _perim(m, h):
    """wetted perimeter estimate of a raster region (edges x pi/4)."""
    e = np.count_nonzero(m[1:, :] != m[:-1, :]) + np.count_nonzero(m[:, 1:] != m[:, :-1])
    return e * h * math.pi / 4


XW = (13.0, 22.0)     # covers both root circles across the lens
YW = (-9.6, 9.6)


def section(L, h=0.01, hf=0.002, band=0.6):
    """Section quantities at newer-contact position L (mm along the LOA):
    areas of the gear-1 and gear-2 parts (mm^2), wetted perimeters (mm),
    planform overlap with the delivery groove (y < -eD) and suction groove
    (y > eS) inside the groove band |x - XG| < GW/2; the overlaps within
    `band` of the edge are resolved at hf."""
    X, Y = _grid(XW[0], XW[1], YW[0], YW[1], h)
    g1, g2 = masks(L, X, Y)
    cav = g1 | g2
    inb = np.abs(X - XG) < GW / 2
    out = dict(L=L, A1=g1.sum() * h * h, A2=g2.sum() * h * h,
               P1=_perim(g1, h), P2=_perim(g2, h),
               ymin=Y[cav].min() if cav.any() else 0, ymax=Y[cav].max() if cav.any() else 0)
    # coarse overlaps beyond the band
    oD = (cav & inb & (Y < -eD - band)).sum() * h * h
    oS = (cav & inb & (Y > eS + band)).sum() * h * h
    # fine overlaps within the band (exact band limits)
    xb0, xb1 = max(XW[0], XG - GW / 2), min(XW[1], XG + GW / 2)
    Xf, Yf = _grid(xb0, xb1, -eD - band, -eD, hf)
    f1, f2 = masks(L, Xf, Yf)
    oD += (f1 | f2).sum() * hf * hf
    Xf, Yf = _grid(xb0, xb1, eS, eS + band, hf)
    f1, f2 = masks(L, Xf, Yf)
    oS += (f1 | f2).sum() * hf * hf
    out['oD'] = oD
    out['oS'] = oS
    return out


def rate_formula(L):
    """d(area)/d(theta1) of the sealed section, mm^2/rad (kin3d.py): per unit
    width and per radian of gear 1, (1+k)/2 (lo^2 - ln^2), k = rw1/rw2."""
    k = rw1 / rw2
    lo = L + pbt
    return 0.5 * (1 + k) * (lo * lo - L * L)


if __name__ == '__main__':
    import time
    for L in (A, -4.0, -pbt / 2 - 0.3, -pbt / 2, -pbt / 2 + 0.3, E - pbt):
        t = time.time()
        s = section(L)
        print({k_: round(v, 4) for k_, v in s.items()}, f'{time.time()-t:.2f}s')


# ---------------------------------------------------------------------------
# The cavity cut at the throats (physical boundary in open sections)
# ---------------------------------------------------------------------------
# Past the ends of the path of contact the cavity is bounded not by the LOA
# but by the throat between a tip corner and the mating flank (delivery end:
# gear 2's tip corner X2 and tooth T_b's driving flank; suction end: gear 1's
# tip corner X1 and tooth S_a's flank): the narrowest passage, whose gap is
# the opening of gaptab.csv. The region beyond the throat belongs to the
# neighbouring space. The cut cavity is the connected fluid region holding
# the backlash, with the contacts and throats blocked (a breadth-first fill).
from collections import deque
import corners as _cn


def _flank_pts(gear, c, n=400):
    if gear == 1:
        rs = np.linspace(max(rb1, rf1), ra1, n)
        th = c + _cn.S1 * _half(rb1, psib1, rs)
        return np.stack([rs * np.cos(th), rs * np.sin(th)], 1)
    rs = np.linspace(max(rb2, rf2), ra2, n)
    th = c + _cn.S2 * _half(rb2, psib2, rs)
    return np.stack([O2x + rs * np.cos(th), rs * np.sin(th)], 1)


def throat_d(L):
    """delivery-end throat of the cavity whose newer contact is virtual at L < A:
    (X2, F), X2 gear 2's tip corner, F the closest point of T_b's driving flank"""
    X2 = np.array(_cn.corner2(L))
    c1, _ = centres(L)
    pts = _flank_pts(1, c1)
    F = pts[np.argmin(np.hypot(*(pts - X2).T))]
    return X2, F


def throat_s(lo):
    """suction-end throat when the older contact is virtual at lo > E:
    (X1, F), X1 gear 1's tip corner (tooth T_a), F the closest point of S_a's flank"""
    X1 = np.array(_cn.corner1(lo))
    _, c2 = centres(lo)
    pts = _flank_pts(2, c2)
    F = pts[np.argmin(np.hypot(*(pts - X1).T))]
    return X1, F


def _seg_dist(X, Y, P0, P1):
    d = P1 - P0
    L2 = float(d @ d)
    t = np.clip(((X - P0[0]) * d[0] + (Y - P0[1]) * d[1]) / max(L2, 1e-18), 0, 1)
    return np.hypot(X - (P0[0] + t * d[0]), Y - (P0[1] + t * d[1]))


def _fill(fluid, seed):
    nx, ny = fluid.shape
    flat = fluid.ravel()
    seen = np.zeros(nx * ny, bool)
    s = seed[0] * ny + seed[1]
    if not flat[s]:
        raise ValueError('seed not in fluid')
    seen[s] = True
    dq = deque([s])
    fl = flat.tolist()
    sn = seen.tolist()
    while dq:
        i = dq.popleft()
        x, y = divmod(i, ny)
        for j, ok in ((i - ny, x > 0), (i + ny, x < nx - 1), (i - 1, y > 0), (i + 1, y < ny - 1)):
            if ok and fl[j] and not sn[j]:
                sn[j] = True
                dq.append(j)
    return np.array(sn, bool).reshape(nx, ny)


def cut_region(L, X, Y, h):
    """boolean mask of the cut cavity on grid X, Y (cell h), and the two
    LOA-split parts within it"""
    c1, c2 = centres(L)
    s1, r1_, _ = _in_gear(X, Y, 0.0, rb1, psib1, ra1, rf1, c1, z1)
    s2, r2_, _ = _in_gear(X, Y, O2x, rb2, psib2, ra2, rf2, c2, z2)
    fluid = ~(s1 | s2) & ((r1_ < ra1) | (r2_ < ra2))
    lo = L + pbt
    blk = 1.6 * h
    for l, end in ((L, 'd'), (lo, 's')):
        if A <= l <= E:
            q = Q(l)
            fluid &= np.hypot(X - q[0], Y - q[1]) > max(0.02, 2 * h)
        elif (l < A and end == 'd') or (l > E and end == 's'):
            P0, P1 = throat_d(l) if end == 'd' else throat_s(l)
            # extend the segment a little into both solids so that no cell leaks past it
            d = P1 - P0; n_ = d / max(np.hypot(*d), 1e-12)
            fluid &= _seg_dist(X, Y, P0 - 3 * h * n_, P1 + 3 * h * n_) > blk
    g1, g2 = masks(L, X, Y)
    lsplit = g1 | g2
    # seed: a fluid cell of the LOA-split cavity on the LOA between the contacts
    seed = None
    for f in np.linspace(0.3, 0.7, 41):
        q = Q(L + f * pbt)
        i = int((q[0] - X[0, 0]) / h + 0.5); j = int((q[1] - Y[0, 0]) / h + 0.5)
        if 0 <= i < X.shape[0] and 0 <= j < X.shape[1] and fluid[i, j] and lsplit[i, j]:
            seed = (i, j)
            break
    cav = _fill(fluid, seed)
    return cav, g1 & cav, g2 & cav


def section_cut(L, h=0.01, hf=0.002, band=0.6):
    X, Y = _grid(XW[0], XW[1], YW[0], YW[1], h)
    cav, g1, g2 = cut_region(L, X, Y, h)
    inb = np.abs(X - XG) < GW / 2
    out = dict(L=L, A1=g1.sum() * h * h, A2=g2.sum() * h * h, Acut=cav.sum() * h * h,
               P1=_perim(g1, h), P2=_perim(g2, h),
               ymin=Y[cav].min(), ymax=Y[cav].max())
    oD = (cav & inb & (Y < -eD - band)).sum() * h * h
    oS = (cav & inb & (Y > eS + band)).sum() * h * h
    # fine band: fine cells of the LOA-split mask inside the (dilated) coarse cut region
    dil = cav.copy()
    dil[1:] |= cav[:-1]; dil[:-1] |= cav[1:]; dil[:, 1:] |= cav[:, :-1]; dil[:, :-1] |= cav[:, 1:]
    xb0, xb1 = max(XW[0], XG - GW / 2), min(XW[1], XG + GW / 2)
    for sgn in (-1, 1):
        y0, y1 = (-eD - band, -eD) if sgn < 0 else (eS, eS + band)
        Xf, Yf = _grid(xb0, xb1, y0, y1, hf)
        f1, f2 = masks(L, Xf, Yf)
        ci = np.clip(((Xf - XW[0]) / h).astype(int), 0, X.shape[0] - 1)
        cj = np.clip(((Yf - YW[0]) / h).astype(int), 0, X.shape[1] - 1)
        val = ((f1 | f2) & dil[ci, cj]).sum() * hf * hf
        if sgn < 0:
            oD += val
        else:
            oS += val
    out['oD'] = oD
    out['oS'] = oS
    return out
