"""Mean delivered-flow deficit of the 3D helical pair (zero clearances,
incompressible, free flow along each tooth space, ideal relief per cavity)
against the per-section closed form (Vm n). Pure Python.

Units: mm, rad of the driving gear (omega1 = 1). Per unit face width, the
region on the delivery side of a boundary X is displaced at (1/2) Br(X),
Br = ra1^2 - r1^2 + k (ra2^2 - r2^2), r1, r2 the boundary's radii on gear 1
and gear 2 (k = rw1/rw2); at a contact at l, Br = C0 - (1+k) l^2 (Q(l) of
Manring & Kasaragadda / (b w1)). The cavity between boundaries Xn (newer,
delivery side) and Xo (older) changes at r = (Br(Xn) - Br(Xo))/2 per unit
width; between contacts r = (1+k)/2 (lo^2 - ln^2) (> 0: grows).
"""
import math, sys, os
from geom import *
from corners import r1_cut_delivery, r2_cut_suction

k = rw1 / rw2
C0 = ra1**2 - rw1**2 + k * (ra2**2 - rw2**2)
tb = math.tan(betab)
Vrad = 0.5 * b * (C0 - (1 + k) * pbt**2 / 12)     # mm^3 per rad = Vm / 2pi

def Br(l):
    return C0 - (1 + k) * l * l

# check: Br from contact radii
for l in (A, 0.0, E, 1.3):
    r1c2 = rb1**2 + (T1P + l)**2; r2c2 = rb2**2 + (T2P - l)**2
    assert abs((ra1**2 - r1c2 + k * (ra2**2 - r2c2)) - Br(l)) < 1e-9

# open-section cut models: Br at the delivery-end cut (virtual newer line at l<A)
# and at the suction-end cut (virtual older line at l>E)
def Br_cut_d(l, model):
    if model == 'virtual':
        return Br(l)
    if model == 'corner':
        return ra1**2 - r1_cut_delivery(l)**2          # r2 = ra2 (gear-2 tip corner)
    raise ValueError

def Br_cut_s(l, model):
    if model == 'virtual':
        return Br(l)
    if model == 'corner':
        return k * (ra2**2 - r2_cut_suction(l)**2)      # r1 = ra1 (gear-1 tip corner)
    raise ValueError

# ---- gap conductances (laminar, per unit width ~ 1/I3 = h^3/Leff), from leak.py tables
_G = None
def gap_tables():
    global _G
    if _G is None:
        from leak import table
        _G = (table('d', N=60), table('s', N=60))
    return _G

def cond_integral(tab, Dmax, n=200):
    """int_0^Dmax h^3/Leff dDelta (h, Leff mm) ~ tan(beta_b) * 12 mu * G."""
    from leak import interp
    if Dmax <= 0:
        return 0.0
    s = 0.0
    for i in range(n):
        D = Dmax * (i + 0.5) / n
        h = interp(tab, D, 1); L = interp(tab, D, 2)
        if h > 2e-4 and L > 0:
            s += h**3 / L
    return s * Dmax / n

def area_integral(tab, Dmax, n=200):
    from leak import interp
    if Dmax <= 0:
        return 0.0
    return sum(interp(tab, Dmax * (i + 0.5) / n, 1) for i in range(n)) * Dmax / n

def cavity(Lo, model, split, NZ):
    """One cavity: older line at l = Lo + zeta tb, newer at Lo - pbt + zeta tb.
    Returns (deficit rate, info). Deficit = per-section-rule delivery share -
    3D share (mm^3/rad)."""
    dz = b / NZ
    sumT = sumTpos = sumTneg = 0.0
    sumOD = sumOS = 0.0
    nT = nOD = nOS = 0
    for i in range(NZ):
        z = (i + 0.5) * dz
        lo = Lo + z * tb; ln = lo - pbt
        o_ok = A <= lo <= E; n_ok = A <= ln <= E
        if o_ok and n_ok:
            r = 0.5 * (1 + k) * (lo * lo - ln * ln)
            sumT += r * dz; sumTpos += max(r, 0) * dz; sumTneg += max(-r, 0) * dz; nT += 1
        elif o_ok and ln < A:
            if model != 'none':
                sumOD += 0.5 * (Br_cut_d(ln, model) - Br(lo)) * dz
            nOD += 1
        elif n_ok and lo > E:
            if model != 'none':
                sumOS += 0.5 * (Br(ln) - Br_cut_s(lo, model)) * dz
            nOS += 1
    if nT == 0:
        return 0.0, None
    R = sumT + sumOD + sumOS
    openD, openS = nOD > 0, nOS > 0
    assert openD or openS, 'sealed cavity: cannot happen for this pair'
    if openD and not openS:
        sd = 1.0
    elif openS and not openD:
        sd = 0.0
    else:
        Dd = A - (Lo - pbt)            # newer line short of A at zeta = 0
        Ds = Lo + b * tb - E           # older line past E at zeta = b
        if split == 'cond':            # laminar: int h^3/Leff over each opening
            td, ts = gap_tables()
            gd, gs = cond_integral(td, Dd), cond_integral(ts, Ds)
            sd = gd / (gd + gs)
        elif split == 'area':          # by open area int h (an orifice-like split)
            td, ts = gap_tables()
            gd, gs = area_integral(td, Dd), area_integral(ts, Ds)
            sd = gd / (gd + gs)
        elif split == 'best':          # the split that delivers most
            sd = 1.0 if R < 0 else 0.0
        elif split == 'worst':
            sd = 0.0 if R < 0 else 1.0
        else:
            sd = float(split)
    ps_share = sumTneg - sumOD            # per-section rule: shrinking trapped sections + OD regions
    share3d = -sd * R
    return ps_share - share3d, (openD, openS, sd, R, sumT, sumTpos, sumTneg, sumOD, sumOS, ps_share)

def mean_deficit(model='virtual', split='cond', NT=400, NZ=400, verbose=False):
    tot = 0.0; phase = {'D': 0.0, 'S': 0.0, 'DS': 0.0}
    per_phase = {'D': 0.0, 'S': 0.0, 'DS': 0.0}
    for it in range(NT):
        L0 = A + pbt * (it + 0.5) / NT
        d_t = 0.0
        for j in range(-3, 4):
            d, info = cavity(L0 + j * pbt, model, split, NZ)
            d_t += d
            if info:
                key = 'DS' if info[0] and info[1] else ('D' if info[0] else 'S')
                per_phase[key] += d / NT
        tot += d_t / NT
    return tot / Vrad, {kk: v / Vrad for kk, v in per_phase.items()}

if __name__ == '__main__':
    print(f"k = rw1/rw2 = {k:.6f}, (1+k)/2 = {(1+k)/2:.6f}; Vm = {2*math.pi*Vrad/1000:.4f} cm^3/rev")
    NT = int(os.environ.get('NT', '200')); NZ = int(os.environ.get('NZ', '400'))
    for model in ('none', 'virtual', 'corner'):
        for split in ('cond', 'area', '0', '1', 'best', 'worst'):
            d, ph = mean_deficit(model, split, NT, NZ)
            print(f"open-section volume: {model:8s} split {split:5s}: deficit {100*d:.4f} % of Vm n "
                  f"(one side open, delivery {100*ph['D']:.4f} + suction {100*ph['S']:.4f}; both open {100*ph['DS']:.4f})")
