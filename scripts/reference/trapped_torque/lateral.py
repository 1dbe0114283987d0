"""Lateral-gap leakage out of the meshing-zone cavity (added in helper
session 32 to the independent reference; written from docs/model.md section 4
and designs/seed_pump.toml only, no project code read).

Two plates, i.e. both faces of both gears, each with the same gap h. Laminar
film flow Q = w h^3 dp / (12 mu L) per path:

(a) over the tooth faces, from the cavity's space of each gear across the
    tooth that bounds it to the gear's neighbouring space: width w = the tooth
    height ra - rf, length L = the transverse tooth thickness (arc) at
    mid-height r_m = (ra + rf) / 2.
      gear 1: across T_b (newer contact, delivery side)  -> space behind, held at p_delivery
              across T_a (older contact, suction side)   -> space ahead,  held at p_suction
      gear 2: across S_b -> p_delivery,  across S_a -> p_suction
    (teeth cross the mesh from the delivery side (-y) to the suction side
    (+y): the space behind the newer contact is still on the delivery side of
    the mesh, the one ahead of the older contact is leaving it on the suction
    side; the same assignment the reference makes for its two throats.)

(b) radially from each of the cavity's two spaces to its gear's hub, an
    annular sector from the root radius rf to the journal radius R_j:
    G = dphi h^3 / (12 mu ln(rf / R_j)), hub at the suction pressure (by-pass
    grooves to the inlet). dphi = the space's angular width; SECTOR chooses
    at which radius: 'root' (default; the arc where the space meets the film
    under the root circle), 'mid' (at mid-height), 'pitch' (2 pi / z, the whole
    annulus shared among the pockets: an upper bound).

The conductances are fixed by the gears' geometry, so they are constant over
the cavity's life; returned as geometric factors (dimensionless w/L sums, per
face) and, given h and mu, conductances (m^3 / (s Pa)) for both faces.
"""
import math, os, sys
import numpy as np
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'meshing_zone'))
import geom as G

BR = G.DESIGN['bearings']
RJ1 = BR['diameter_drive_mm'] / 2
RJ2 = BR['diameter_driven_mm'] / 2


def gear_paths(rb, psib, ra, rf, z, Rj, sector):
    rm = 0.5 * (ra + rf)
    hm = G.half_angle(rb, psib, rm)            # half angular thickness at mid-height
    s_mid = 2 * rm * hm                         # arc thickness, mm
    height = ra - rf
    if sector == 'root':
        dphi = 2 * math.pi / z - 2 * G.half_angle(rb, psib, rf)
    elif sector == 'mid':
        dphi = 2 * math.pi / z - 2 * hm
    elif sector == 'pitch':
        dphi = 2 * math.pi / z
    else:
        raise ValueError(sector)
    lnr = math.log(rf / Rj)
    return dict(height=height, s_mid=s_mid, r_mid=rm, tooth=height / s_mid, dphi=dphi, lnr=lnr,
                hub=dphi / lnr)


def factors(sector=None):
    """per face: geometric factors (w/L) of the paths to the delivery-side
    neighbours (kd) and to suction (ks = suction-side neighbours + hubs)"""
    sector = sector or os.environ.get('LAT_SECTOR', 'root')
    g1 = gear_paths(G.rb1, G.psib1, G.ra1, G.rf1, G.z1, RJ1, sector)
    g2 = gear_paths(G.rb2, G.psib2, G.ra2, G.rf2, G.z2, RJ2, sector)
    kd = g1['tooth'] + g2['tooth']
    ks = g1['tooth'] + g2['tooth'] + g1['hub'] + g2['hub']
    return dict(g1=g1, g2=g2, kd=kd, ks=ks, sector=sector)


def conductances(h_um, mu, sector=None):
    """both faces together: (G to delivery, G to suction) in m^3/(s Pa)"""
    f = factors(sector)
    c = (h_um * 1e-6) ** 3 / (12 * mu)
    if os.environ.get('LAT_NEIGH', 'line') == 'suction':   # sensitivity: every path to suction
        return 0.0, 2 * (f['kd'] + f['ks']) * c
    return 2 * f['kd'] * c, 2 * f['ks'] * c


def barus_psi(alpha):
    """Barus's law in a film, mu(p) = mu exp(alpha p), p above the suction:
    in a film of uniform clearance the Reynolds equation is Laplace's in the
    reduced pressure psi(p) = (1 - exp(-alpha p)) / alpha, so a film's flow is
    its conductance at the oil's own viscosity times psi(p_a) - psi(p_b), its
    derivative exp(-alpha p). Returns (psi, dpsi/dp); alpha = 0: the clean oil
    (psi = p), to the last digit."""
    if alpha == 0.0:
        return (lambda p: p), (lambda p: 1.0)
    return (lambda p: -np.expm1(-alpha * p) / alpha), (lambda p: np.exp(-alpha * p))


def barus_film_factor(alpha):
    """The viscosity factor of a film by Barus's law between gauge pressures
    p_a and p_b (above the suction): the mean of exp(alpha p) along it with
    psi linear, (p_a - p_b) / (psi(p_a) - psi(p_b)) (exp(alpha p) where the
    two ends meet), so that G_own / factor (p_a - p_b) is its flow; 1 for
    alpha = 0."""
    if alpha == 0.0:
        return lambda pa, pb: np.ones_like(np.asarray(pa - pb, dtype=float))
    psi, _ = barus_psi(alpha)

    def factor(pa, pb):
        pa, pb = np.broadcast_arrays(np.asarray(pa, dtype=float), np.asarray(pb, dtype=float))
        d = psi(pa) - psi(pb)
        near = np.abs(pa - pb) < 1.0
        safe = np.where(near, 1.0, d)
        return np.where(near, np.exp(alpha * 0.5 * (pa + pb)), (pa - pb) / safe)
    return factor


if __name__ == '__main__':
    from oil import Oil
    for sec in ('root', 'mid', 'pitch'):
        f = factors(sec)
        print(f"sector={sec}")
        for k in ('g1', 'g2'):
            d = f[k]
            print(f"  {k}: tooth height {d['height']:.3f} mm, thickness at r_mid {d['r_mid']:.3f} mm: {d['s_mid']:.3f} mm,"
                  f" w/L {d['tooth']:.3f}; hub sector dphi {d['dphi']:.4f} rad ({math.degrees(d['dphi']):.2f} deg),"
                  f" ln(rf/Rj) {d['lnr']:.4f}, dphi/ln {d['hub']:.3f}")
        print(f"  per face: k_delivery {f['kd']:.3f}, k_suction {f['ks']:.3f}")
        mu = Oil(60).mu
        for h in (15, 24):
            gd, gs = conductances(h, mu, sec)
            print(f"  h {h} um, mu(60C) {mu*1e3:.3f} mPa s: G_d {gd:.3e}, G_s {gs:.3e} m^3/(s Pa) both faces;"
                  f" at 100 bar to suction {gs*1e7*6e4:.4f} l/min")
