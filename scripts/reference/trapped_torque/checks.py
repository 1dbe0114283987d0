"""Sanity checks of the geometry (the reference's own checks):
 * tooth-space areas against the closed-form displacement: per section the
   delivery receives a gear-1 and a gear-2 space per mesh period and gets back
   the cavity between two contacts at the hand-over (its smallest volume,
   contacts symmetric about the pitch point), so Vm = z1 b (A_s1 + A_s2 - A_min);
 * the cavity's area change between the ends of double contact against the
   closed form (1+k)/2 (lo^2 - ln^2) integrated;
 * raster resolution (10 um against 5 um).
    python checks.py
"""
import math, os, sys
import numpy as np
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import tvgeom as g


def space_area(gear, h=0.005):
    """fluid of one tooth space inside the tip circle (the gear alone)"""
    if gear == 1:
        rb, psib, ra, rf, z, cx = g.rb1, g.psib1, g.ra1, g.rf1, g.z1, 0.0
    else:
        rb, psib, ra, rf, z, cx = g.rb2, g.psib2, g.ra2, g.rf2, g.z2, 0.0
    X, Y = g._grid(-ra, ra, -ra, ra, h)
    s, r, ph = g._in_gear(X, Y, cx, rb, psib, ra, rf, 0.0, z)
    fl = (~s) & (r < ra)
    return fl.sum() * h * h / z


if __name__ == '__main__':
    k = g.rw1 / g.rw2
    Vm = math.pi * g.b * (g.ra1**2 - g.rw1**2 + k * (g.ra2**2 - g.rw2**2) - (1 + k) * g.pbt**2 / 12)
    As1, As2 = space_area(1), space_area(2)
    Lsw = -g.pbt / 2
    Amin10 = g.section(Lsw, h=0.01); Amin5 = g.section(Lsw, h=0.005)
    Amin = Amin5['A1'] + Amin5['A2']
    print(f"closed form Vm = {Vm/1000:.4f} cm^3/rev (Manring & Kasaragadda)")
    print(f"tooth-space areas: gear 1 {As1:.4f} mm^2, gear 2 {As2:.4f} mm^2 (5 um raster)")
    print(f"cavity at the hand-over (contacts at +-pbt/2): {Amin10['A1']+Amin10['A2']:.4f} mm^2 (10 um), {Amin:.4f} (5 um)")
    Vr = g.z1 * g.b * (As1 + As2 - Amin)
    print(f"z1 b (A_s1 + A_s2 - A_min) = {Vr/1000:.4f} cm^3/rev, {100*(Vr/Vm-1):+.3f} % of the closed form")
    # cavity area change over double contact
    a0 = g.section(g.A, h=0.005); a1 = g.section(g.E - g.pbt, h=0.005)
    dA = (a1['A1'] + a1['A2']) - (a0['A1'] + a0['A2'])
    Ls = np.linspace(g.A, g.E - g.pbt, 2001)
    dAf = np.trapezoid(g.rate_formula(Ls), Ls) / g.rb1
    Am = g.section(-g.pbt / 2 - 0.6, h=0.005)
    dA2 = (Am['A1'] + Am['A2']) - Amin
    Ls2 = np.linspace(-g.pbt / 2, -g.pbt / 2 - 0.6, 2001)
    dAf2 = np.trapezoid(g.rate_formula(Ls2), Ls2) / g.rb1
    print(f"cavity area change A..E-pbt: raster {dA:+.4f} mm^2, closed form {dAf:+.4f} mm^2")
    print(f"cavity area change from the hand-over to 0.6 mm before: raster {dA2:+.4f}, closed form {dAf2:+.4f} mm^2")
    for L in (-4.0, -3.6):
        s10 = g.section(L, h=0.01); s5 = g.section(L, h=0.005, hf=0.001)
        print(f"L = {L}: overlap with the delivery groove {s10['oD']:.4f} mm^2 (10/2 um) vs {s5['oD']:.4f} (5/1 um)")
