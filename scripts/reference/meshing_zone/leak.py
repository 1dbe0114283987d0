"""Leak delivery -> suction through the channel between two consecutive contact
lines while neither line spans the face width. Pure Python.

Per unit face width, the passage past the end of a contact line (gap h_min,
laminar length Leff = h^3 int ds/h^3 from the measured profile) passes
    dp = 12 mu Leff q / h^3 + rho q^2 / (2 Cd^2 h^2)        ('combined', used)
or the limits 'orifice' (second term only) and 'laminar' (first only).
The delivery-side and suction-side openings are in series through the
trapped channel (its own conductance, ~1e-8 m^3/(s Pa) per the project's
measurement and >> the openings, taken as infinite); the channel pressure
p_t solves Q_d(pD - p_t) = Q_s(p_t - pS).
"""
import math, sys
from geom import *
from gaps import gap_at, profile_integral

import os
Cd = float(os.environ.get('CD', '0.6'))
# the design's oil at TEMP_C (default 60 degC): Walther (ASTM D341) through
# its two datasheet viscosities, density rho20 / (1 + alpha (T - 20))
_o = DESIGN['oil']
_T = float(os.environ.get('TEMP_C', '60'))
_B = (math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) - math.log10(math.log10(_o['nu_100c_cst'] + 0.7))) \
    / (math.log10(373.15) - math.log10(313.15))
_A = math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) + _B * math.log10(313.15)
_nu = 10 ** (10 ** (_A - _B * math.log10(_T + 273.15))) - 0.7   # cSt
rho = _o['density_20c_kg_m3'] / (1 + _o['expansion_per_k'] * (_T - 20))
mu = _nu * 1e-6 * rho
tb = math.tan(betab)

# ---- tables h(Delta), Leff(Delta) at both ends ----
def table(end, Dmax=None, N=43):
    if Dmax is None:
        Dmax = pbt + b * tb - galpha + 0.05
    rows = []
    for i in range(N):
        D = Dmax * (i / (N - 1)) ** 1.5
        l = A - D if end == 'd' else E + D
        d, p, a1, a2 = gap_at(l, R=1.5)
        if d > 2e-4:
            I3, _, _ = profile_integral(d, p, a1, a2)
            Leff = I3 * d**3
        else:
            Leff = 0.0
        rows.append((D, d, Leff))
    return rows

def interp(tab, D, k):
    if D <= tab[0][0]:
        return tab[0][k]
    for i in range(1, len(tab)):
        if D <= tab[i][0]:
            D0, D1 = tab[i-1][0], tab[i][0]
            w = (D - D0) / (D1 - D0)
            return tab[i-1][k] * (1 - w) + tab[i][k] * w
    raise ValueError(D)

def q_unit(h_mm, Leff_mm, dp, law):
    """flow per unit width, m^2/s, for gap h (mm), dp (Pa)."""
    if h_mm <= 2e-4 or dp <= 0 or (law != 'orifice' and Leff_mm <= 0):
        return 0.0
    h = h_mm * 1e-3; L = Leff_mm * 1e-3
    if law == 'orifice':
        return Cd * h * math.sqrt(2 * dp / rho)
    Rl = 12 * mu * L / h**3            # Pa s / m^2  (dp = Rl q)
    if law == 'laminar':
        return dp / Rl if Rl > 0 else float('inf')
    Ri = rho / (2 * Cd**2 * h**2)      # dp = Ri q^2
    # Ri q^2 + Rl q - dp = 0
    return (-Rl + math.sqrt(Rl * Rl + 4 * Ri * dp)) / (2 * Ri)

def Q_open(tab, Dmax, dp, law, n=200):
    """flow through one opening whose Delta runs linearly from Dmax (face) to 0
    over Dmax / tan(beta_b) of face width: integral over zeta (m^3/s)."""
    if Dmax <= 0:
        return 0.0
    tot = 0.0
    for i in range(n):
        D = Dmax * (i + 0.5) / n
        tot += q_unit(interp(tab, D, 1), interp(tab, D, 2), dp, law)
    dz = (Dmax / tb) / n * 1e-3
    return tot * dz

def leak(l0, dP, law, td, ts):
    """l0: position of the older contact line at zeta = 0 (its range l0 .. l0 + b tan bb).
    returns (Q m^3/s, Dd0, Ds_b, p_t/dP)."""
    w = b * tb
    if l0 + w <= E:          # older line spans the face: sealed
        return 0.0, 0.0, 0.0, None
    Dd = A - (l0 - pbt)      # newer line, at zeta=0, short of A by this
    Ds = l0 + w - E          # older line, at zeta=b, past E by this
    if Dd <= 0:
        return 0.0, Dd, Ds, None   # newer line spans the face (cannot happen here)
    lo, hi = 0.0, dP
    for _ in range(60):
        pt = 0.5 * (lo + hi)
        if Q_open(td, Dd, dP - pt, law) > Q_open(ts, Ds, pt, law):
            lo = pt
        else:
            hi = pt
    return Q_open(ts, Ds, pt, law), Dd, Ds, pt / dP

if __name__ == '__main__':
    td, ts = table('d'), table('s')
    with open('gap_table.csv', 'w') as f:
        f.write('Delta_mm,h_delivery_end_um,Leff_delivery_mm,h_suction_end_um,Leff_suction_mm\n')
        for (D, hd, Ld), (_, hs, Ls) in zip(td, ts):
            f.write(f'{D:.5f},{1000*hd:.4f},{Ld:.5f},{1000*hs:.4f},{Ls:.5f}\n')
    w = b * tb
    open_from = E - w
    print(f"open phase: older line's zeta=0 position l0 in ({open_from:.4f}, {A+pbt:.4f}) mm "
          f"= {(A+pbt-open_from)/pbt*100:.2f} % of the mesh period; "
          f"Dd(0)+Ds(b) = {pbt+w-galpha:.4f} mm")
    n_rpm = float(os.environ.get('RPM', '1000'))
    # displacement per driving revolution, m^3 (Manring & Kasaragadda's
    # closed form for unequal gears, from the geometry above, in mm)
    i_w = rw1 / rw2
    Vm = math.pi * b * (ra1**2 - rw1**2 + i_w * (ra2**2 - rw2**2)
                        - (1 + i_w) * pbt**2 / 12) * 1e-9
    Qth = Vm * n_rpm / 60
    print(f"Vm n = {Qth*6e4:.3f} l/min")
    N = 80
    for law in sys.argv[1].split(',') if len(sys.argv) > 1 else ('combined', 'orifice', 'laminar'):
        for dPbar in [int(x) for x in sys.argv[2].split(',')] if len(sys.argv) > 2 else (10, 30, 50, 100):
            dP = dPbar * 1e5
            s = 0.0; peak = (0, None)
            for i in range(N):
                l0 = open_from + (A + pbt - open_from) * (i + 0.5) / N
                q, Dd, Ds, r = leak(l0, dP, law, td, ts)
                s += q
                if q > peak[0]:
                    peak = (q, (l0, Dd, Ds, r))
            avg = s / N * (A + pbt - open_from) / pbt   # time average over the whole mesh period
            q, (l0, Dd, Ds, r) = peak
            print(f"{law:8s} {dPbar:4d} bar: mean {avg*6e4*1000:8.3f} ml/min "
                  f"= {100*avg/Qth:7.4f} % of Vm n; peak {q*6e4*1000:8.2f} ml/min "
                  f"at Dd(0)={Dd:.3f} Ds(b)={Ds:.3f} mm, p_t/dp={r:.2f}")
