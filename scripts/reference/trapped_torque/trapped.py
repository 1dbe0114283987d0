"""Pressure history and pressure-work excess of the meshing-zone cavity of
the seed pump's helical pair (independent reference, no project code).

The cavity: the fluid between two consecutive driving-flank contact lines
(a gear-1 tooth space and a gear-2 tooth space, joined by the backlash,
taken as one node per transverse slice; tvgeom.py). Its section in the slice
at axial position z (0 .. b) has its newer contact at L(z) = Lm + (z - b/2)
tan(beta_b), Lm that of the mid-face section; L advances by rb1 per radian
of the driving gear. A slice is sealed in-plane while A <= L and L + pbt <= E;
past the ends of the path of contact it opens to the neighbouring space
(delivery side: L < A; suction side: L + pbt > E) through the throat between
a tip corner and the mating flank (gaptab.csv, from ../meshing_zone/gaps.py),
where the section is cut (sectab_cut.csv; the split by the line of action
alone, sectab.csv with cut='loa', is kept as a sensitivity):
per unit width dp = 12 mu Leff q / h^3 + rho q^2 / (2 Cd^2 h^2), Cd =
casing.mesh_discharge_coefficient. Relief grooves in both plates (offset by
the helix, as docs/model.md section 9 says, so that the mid-face section
counts): on each plate, the mid-face section's planform overlap with the
groove (y < -eD or y > eS, within the 6 mm band) in series with the groove's
section (width x depth), Cd = casing.groove_discharge_coefficient. The
neighbouring spaces are held at the line pressures (delivery p_d, suction
p_atm).

Models:
  lumped  (a): one node for the whole face width (every slice's openings on
               it, both plates' grooves on it): the model's axial_nodes = 1,
               i.e. the limit of free flow along the tooth space.
  sliced  (b): NZ slice nodes, joined along the space by the laminar channel
               (Poiseuille on the hydraulic diameter of each part, f Re = C),
               the z = 0 plate's grooves on slice 0 and the z = b plate's on
               slice NZ-1; optionally the axial flow's inertia (rho dz / A).

The cavity is followed from DEFAULT_MARGIN[0] mm of mid-face travel before
its delivery-end throat closes at the z = b face (starting at the delivery
pressure) to DEFAULT_MARGIN[1] mm after its suction-end throat opens at z = 0.

Output per condition: peak pressure, the mean over a mesh period of
sum (p - p_ideal)(-dV/dtheta) on the driving shaft (p_ideal: p_d while the
cavity's total volume shrinks, p_s while it grows), and an energy check.
"""
import math, os, sys
import numpy as np
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import tvgeom as g
import lateral as LAT
from oil import Oil, PATM

D = g.DESIGN
b = g.b
tb = math.tan(g.betab)
CD_MESH = D['casing']['mesh_discharge_coefficient']
CD_GROOVE = D['casing']['groove_discharge_coefficient']
AG = D['casing']['groove_width_mm'] * D['casing']['groove_depth_mm'] * 1e-6   # m^2
DP_REG = 0.01e5   # orifice regularisation (Pa)

# ---------------- tables ----------------
_gap = np.genfromtxt(os.path.join(HERE, 'gaptab.csv'), delimiter=',', names=True)


def _smooth(y, n=7):
    """local quadratic fit over n points (Savitzky-Golay), to differentiate the raster areas"""
    h = n // 2
    x = np.arange(-h, h + 1)
    M = np.vstack([np.ones_like(x), x, x * x]).T
    c = np.linalg.pinv(M)[0]
    yp = np.concatenate([np.full(h, y[0]), y, np.full(h, y[-1])])
    out = np.convolve(yp, c[::-1], mode='valid')
    out[:h] = y[:h]; out[-h:] = y[-h:]
    return out


class SecTable:
    """section quantities against L (tvgeom via sectab.py): 'throat' = the
    cavity cut at the throats past the ends of the path of contact (default),
    'loa' = split by the line of action only (then the spaces' arcs outside
    the lens are openings too)."""
    _cache = {}

    def __init__(self, cut='throat', name=None):
        name = name or os.environ.get('SECTAB') or ('sectab_cut.csv' if cut == 'throat' else 'sectab.csv')
        d = np.genfromtxt(os.path.join(HERE, name), delimiter=',', names=True)
        self.cut = cut
        self.L = d['L']; self.d = d
        self.A1s = _smooth(d['A1']); self.A2s = _smooth(d['A2'])

    @classmethod
    def get(cls, cut, name=None):
        if (cut, name) not in cls._cache:
            cls._cache[(cut, name)] = cls(cut, name)
        return cls._cache[(cut, name)]

    def area(self, L):         # mm^2
        return np.interp(L, self.L, self.A1s) + np.interp(L, self.L, self.A2s)

    def parts(self, L):        # areas and wetted perimeters of the two parts, mm^2, mm
        d = self.d
        return (np.interp(L, self.L, d['A1']), np.interp(L, self.L, d['P1']),
                np.interp(L, self.L, d['A2']), np.interp(L, self.L, d['P2']))

    def overlap(self, L):      # planform overlaps with the delivery / suction groove, mm^2
        return np.interp(L, self.L, self.d['oD']), np.interp(L, self.L, self.d['oS'])


_GAPS = {None: _gap}


def _gaptab(name):
    if name not in _GAPS:
        _GAPS[name] = np.genfromtxt(os.path.join(HERE, name), delimiter=',', names=True)
    return _GAPS[name]


def gap_d(Dl, name=None):   # h, Leff (mm) at Delta past the delivery end
    t = _gaptab(name)
    return np.interp(Dl, t['Delta_mm'], t['h_d_mm']), np.interp(Dl, t['Delta_mm'], t['Leff_d_mm'])


def gap_s(Dl, name=None):
    t = _gaptab(name)
    return np.interp(Dl, t['Delta_mm'], t['h_s_mm']), np.interp(Dl, t['Delta_mm'], t['Leff_s_mm'])


# the tooth spaces' openings on the tip circles outside the lens (the
# overlap of the two tip circles): there a space faces the outlet chamber
# (y < 0) or the inlet chamber (y > 0) directly, not through the mesh
_XI = (g.a ** 2 + g.ra1 ** 2 - g.ra2 ** 2) / (2 * g.a)
PHI1 = math.acos(_XI / g.ra1)
PHI2 = math.acos((g.a - _XI) / g.ra2)
_H1 = g.half_angle(g.rb1, g.psib1, g.ra1)
_H2 = g.half_angle(g.rb2, g.psib2, g.ra2)


def _wrap(x):
    return (x + np.pi) % (2 * np.pi) - np.pi


def arcs(L, parts=False):
    """arc lengths (mm) of the cavity's two spaces outside the lens: to the
    delivery side and to the suction side (parts=True: d1, d2, s1, s2)"""
    c1 = -g.aw + (g.T1P + L) / g.rb1 - g.psib1
    c2 = (np.pi - g.aw) + (g.T2P - L) / g.rb2 - g.psib2
    lo1 = _wrap(c1 + _H1); hi1 = _wrap(c1 + 2 * np.pi / g.z1 - _H1)
    d1 = g.ra1 * np.maximum(0, np.minimum(hi1, -PHI1) - lo1)
    s1 = g.ra1 * np.maximum(0, hi1 - np.maximum(lo1, PHI1))
    lo2 = _wrap(c2 - 2 * np.pi / g.z2 + _H2 - np.pi); hi2 = _wrap(c2 - _H2 - np.pi)
    d2 = g.ra2 * np.maximum(0, hi2 - np.maximum(lo2, PHI2))
    s2 = g.ra2 * np.maximum(0, np.minimum(hi2, -PHI2) - lo2)
    if parts:
        return d1, d2, s1, s2
    return d1 + d2, s1 + s2


# ---------------- flow laws (SI) ----------------
def orifice(CdA, dp, rho):
    """Q (m^3/s) from a to b for dp = pa - pb, and dQ/d(dp)"""
    s = np.sqrt(np.sqrt(dp * dp + DP_REG * DP_REG))
    k = CdA * math.sqrt(2 / rho)
    Q = k * dp / s
    dQ = k * (1 / s - 0.5 * dp * dp / s ** 5)
    return Q, dQ


def gapflow(h, Le, w, dp, rho, mu, Cd):
    """combined laminar + orifice passage of width w (m), gap h (m), length Le (m)"""
    Rl = 12 * mu * np.maximum(Le, 1e-6) / np.maximum(h, 1e-9) ** 3
    Ri = rho / (2 * Cd * Cd * np.maximum(h, 1e-9) ** 2)
    adp = np.abs(dp)
    q = (-Rl + np.sqrt(Rl * Rl + 4 * Ri * adp)) / (2 * Ri)
    dq = 1 / (Rl + 2 * Ri * q)
    ok = h > 2e-7
    return np.where(ok, np.sign(dp) * q * w, 0.0), np.where(ok, dq * w, 0.0)


def series_area(a1, a2):
    a1 = np.maximum(a1, 1e-18)
    return 1 / np.sqrt(1 / a1 ** 2 + 1 / a2 ** 2)


# ---------------- geometry of the cavity over its life ----------------
class Geometry:
    """per step: slice volumes, openings. NZ nodes (1 = lumped), NS
    sub-slices per node for the openings."""

    def __init__(self, NZ, NS=8, margin=0.3, cut='throat', groove='offset', helix=True, table=None,
                 gaptab=None, dra=0.0):
        self.T = SecTable.get(cut, table)
        self.gaptab = gaptab
        # ends of the path of contact; dra > 0: both tip radii reduced (edge-break stand-in, with
        # the matching gap table from gaptab.py run with DRA_MM); the volumes are left as they are
        self.A = g.T2P - math.sqrt((g.ra2 - dra) ** 2 - g.rb2 ** 2)
        self.E = math.sqrt((g.ra1 - dra) ** 2 - g.rb1 ** 2) - g.T1P
        tb = math.tan(g.betab) if helix else 0.0     # helix=False: the spur pair of the same transverse section
        self.groove = groove
        self.NZ = NZ
        md, ms = margin if isinstance(margin, (tuple, list)) else (margin, margin)
        self.L0 = g.A - b * tb / 2 - md              # mid-face Lm at the start (open to delivery)
        self.L1 = (g.E - g.pbt) + b * tb / 2 + ms    # and at the end (open to suction)
        zf = (np.arange(NZ * NS) + 0.5) / (NZ * NS) * b     # sub-slice centres (mm)
        self.zoff = ((zf - b / 2) * tb).reshape(NZ, NS)    # L(z) - Lm
        self.wsub = b / (NZ * NS) * 1e-3                   # m
        zc = (np.arange(NZ) + 0.5) / NZ * b
        self.zoffc = (zc - b / 2) * tb
        self.NS = NS

    def at(self, Lm):
        L = Lm + self.zoff                                  # (NZ, NS)
        V = self.T.area(L).sum(axis=1) * self.wsub * 1e-6   # m^3 per node
        Dd = self.A - L                                     # > 0: open to delivery
        Ds = L + g.pbt - self.E                             # > 0: open to suction
        hd, Ld = gap_d(np.maximum(Dd, 0), self.gaptab); hs, Ls = gap_s(np.maximum(Ds, 0), self.gaptab)
        hd = np.where(Dd > 0, hd, 0.0); hs = np.where(Ds > 0, hs, 0.0)
        if self.groove == 'offset':      # both plates: the mid-face section at the nominal edges
            oD, oS = self.T.overlap(Lm)
            oD = np.array([oD, oD]); oS = np.array([oS, oS])
        else:                            # 'nominal': each plate sees its own face section
            oD, oS = self.T.overlap(np.array([Lm - b * tb / 2, Lm + b * tb / 2]))
        if self.T.cut == 'loa':
            ad, as_ = arcs(L)
        else:   # gear 1's delivery arc and gear 2's suction arc lie beyond the throats; the other two
            _, ad, as_, _ = arcs(L, parts=True)      # (far from the mesh) open the cut cavity itself
        return dict(V=V, arcd=ad.sum(axis=1) * self.wsub * 1e-3, arcs=as_.sum(axis=1) * self.wsub * 1e-3,
                    hd=hd * 1e-3, Ld=Ld * 1e-3, hs=hs * 1e-3, Ls=Ls * 1e-3,
                    aD=series_area(oD * 1e-6, AG), aS=series_area(oS * 1e-6, AG), oD=oD, oS=oS)

    def axial(self, Lm, mu, C=64.0):
        """conductances (m^3/(s Pa)) and inertances (kg/m^4) between consecutive nodes"""
        if self.NZ == 1:
            return np.zeros(0), np.zeros(0)
        dz = b / self.NZ * 1e-3
        L = Lm + self.zoffc
        A1, P1, A2, P2 = self.T.parts(L)
        def cond(Aa, Pp):
            Aa = np.maximum(Aa, 1e-4) * 1e-6; Pp = np.maximum(Pp, 1e-3) * 1e-3
            Dh = 4 * Aa / Pp
            return 2 * Aa * Dh * Dh / (C * mu)   # x length
        gi = cond(A1, P1) + cond(A2, P2)        # per unit length: Q = gi dp/dx
        G = 1 / (0.5 * dz / gi[:-1] + 0.5 * dz / gi[1:])
        Atot = (A1 + A2) * 1e-6
        I = 0.5 * dz / Atot[:-1] + 0.5 * dz / Atot[1:]   # x rho
        return G, I


# phases of the cavity's life by its mid-face position, for comparison with
# the model's classes of spaces: while some slice of its gear-1 space still
# has an arc outside the lens on the delivery side (a bore opening to the
# outlet, in the model's terms), none, and once some slice of its gear-2 space
# has an arc outside the lens on the suction side
def _phase_limits():
    L = np.linspace(-9, 3, 120001)
    d, s_ = arcs(L)
    return L[d > 0].max() + b * tb / 2, L[s_ > 0].min() - b * tb / 2
LM_OUT, LM_IN = _phase_limits()


# ---------------- the solver ----------------
def run(rpm, dp_bar, T_c, NZ=1, NS=None, steps=None, axial='laminar', inertia=False,
        C=64.0, cut='throat', groove='offset', throat_law='combined', cd_mesh=None,
        cd_groove=None, throats=True, grooves=True, p_in_bar_abs=None, margin=None, keep=False, helix=True, table=None, gaptab=None, dra=0.0,
        h_lat_um=None, lat_sector=None, lat_alpha=0.0, thr_alpha=0.0):
    """One cavity over its life (mid-face newer contact from A - b tan(bb)/2 -
    margin to E - pbt + b tan(bb)/2 + margin), starting at the delivery
    pressure. axial: 'laminar' (channel between slice nodes) or 'free' (the
    lumped node). Returns a dict; N m figures are per driving-gear radian,
    averaged over one mesh period (2 pi / z1)."""
    if margin is None:
        margin = DEFAULT_MARGIN
    if steps is None:
        mm = sum(margin) / 2 if isinstance(margin, (tuple, list)) else margin
        steps = int(4000 * (1 + mm / 2))
    oil = Oil(T_c)
    rho, mu = oil.rho, oil.mu
    # lateral-gap leakage on both plates (lateral.py); h_lat_um = 0: none (the original reference)
    if h_lat_um is None:
        h_lat_um = float(os.environ.get('LAT_UM', '0'))
    GLd, GLs = LAT.conductances(h_lat_um, mu, lat_sector) if h_lat_um > 0 else (0.0, 0.0)
    # lat_alpha > 0: the lateral films' viscosity rises with their own pressure by Barus's law
    # (lateral.py, barus_psi): each film carries G (psi(p_a) - psi(p_b)), G of the oil's own viscosity
    psi, dpsi = LAT.barus_psi(lat_alpha)
    # thr_alpha > 0: so does the throats' laminar part, at the mean of exp(alpha p) along a film
    # whose psi runs linearly between its ends (exact for a pure laminar film); the inertial part,
    # which does not depend on the viscosity, is left as it is
    thr_factor = LAT.barus_film_factor(thr_alpha)
    cdm = CD_MESH if cd_mesh is None else cd_mesh
    cdg = CD_GROOVE if cd_groove is None else cd_groove
    omega = rpm * 2 * math.pi / 60
    pd = PATM + dp_bar * 1e5
    ps = PATM if p_in_bar_abs is None else p_in_bar_abs * 1e5
    if axial == 'free' or NZ == 1:
        n = 1; NS_ = NS or 128
    else:
        n = NZ; NS_ = NS or max(1, 128 // NZ)
    G = Geometry(n, NS=NS_, margin=margin, cut=cut, groove=groove, helix=helix, table=table, gaptab=gaptab, dra=dra)
    Lms = np.linspace(G.L0, G.L1, steps + 1)
    dth = (Lms[1] - Lms[0]) / g.rb1
    dt = dth / omega
    p = np.full(n, pd)
    Qax = np.zeros(max(n - 1, 0))
    Vold = G.at(Lms[0])['V']
    plate_node = (0, n - 1)
    # each plate's half of the lateral conductances on the node at its face
    gLd = np.zeros(n); gLs = np.zeros(n)
    for pl in (0, 1):
        gLd[plate_node[pl]] += GLd / 2; gLs[plate_node[pl]] += GLs / 2
    W = dict(thr_lat=0.0, vol_lat=0.0, vol_sq=0.0, exc_out=0.0, exc_mid=0.0, exc_in=0.0, exc=0.0, thr=0.0, comp=0.0, port=0.0, ideal=0.0, press=0.0, thr_ax=0.0,
             thr_throat=0.0, thr_groove=0.0)
    peak = -1e30; low = 1e30; peakL = None
    hist = []
    lam = throat_law != 'orifice'
    for it in range(steps):
        Lm = Lms[it + 1]
        Lmid = 0.5 * (Lms[it] + Lms[it + 1])
        geo = G.at(Lmid)
        Vn = G.at(Lm)['V']
        dV = Vn - Vold
        if n > 1:
            Gax, Iax = G.axial(Lmid, mu, C)
        hd = geo['hd'] if throats else 0 * geo['hd']
        hs = geo['hs'] if throats else 0 * geo['hs']
        Ld = geo['Ld'] if lam else 0 * geo['Ld'] + 1e-12
        Ls = geo['Ls'] if lam else 0 * geo['Ls'] + 1e-12
        aD = geo['aD'] * cdg * grooves; aS = geo['aS'] * cdg * grooves
        lnr_old = oil.lnrho(p)
        pn = p.copy()
        for k in range(80):
            if thr_alpha:
                fd = thr_factor(pn - ps, pd - ps)[:, None]; fs = thr_factor(pn - ps, 0.0)[:, None]
            else:
                fd = fs = 1.0
            qd, dqd = gapflow(hd, Ld, G.wsub, pn[:, None] - pd, rho, mu * fd, cdm)
            qs, dqs = gapflow(hs, Ls, G.wsub, pn[:, None] - ps, rho, mu * fs, cdm)
            q1, d1 = orifice(cdm * geo['arcd'], pn - pd, rho)
            q2, d2 = orifice(cdm * geo['arcs'], pn - ps, rho)
            Qd = qd.sum(1) + q1; Qs = qs.sum(1) + q2
            diag = dqd.sum(1) + dqs.sum(1) + d1 + d2
            gD = np.zeros(n); gS = np.zeros(n)
            for pl in (0, 1):
                j = plate_node[pl]
                a1, e1 = orifice(aD[pl], pn[j] - pd, rho)
                a2, e2 = orifice(aS[pl], pn[j] - ps, rho)
                gD[j] += a1; gS[j] += a2; diag[j] += e1 + e2
            Ld_ = gLd * (psi(pn - ps) - psi(pd - ps)); Ls_ = gLs * psi(pn - ps)
            diag = diag + (gLd + gLs) * dpsi(pn - ps)
            Qout = Qd + Qs + gD + gS + Ld_ + Ls_
            J = np.diag(diag)
            if n > 1:
                if inertia and axial == 'laminar':
                    den = rho * Iax / dt + 1 / Gax
                    Qa = (Qax * rho * Iax / dt + (pn[:-1] - pn[1:])) / den
                    dQa = 1 / den
                elif axial == 'laminar':
                    Qa = Gax * (pn[:-1] - pn[1:]); dQa = Gax
                Qout[:-1] += Qa; Qout[1:] -= Qa
                idx = np.arange(n - 1)
                J[idx, idx] += dQa; J[idx + 1, idx + 1] += dQa
                J[idx, idx + 1] -= dQa; J[idx + 1, idx] -= dQa
            lnr = oil.lnrho(pn)
            F = Vn * (lnr - lnr_old) + dV + dt * Qout
            Jt = np.diag(Vn * oil.dlnrho(pn)) + dt * J
            step = np.linalg.solve(Jt, -F)
            mx = np.max(np.abs(step))
            if mx > 50e5:
                step *= 50e5 / mx
            pn = np.maximum(pn + step, 0.1 * oil.pfloor)
            if mx < 1e-3 * max(dp_bar, 1.0):
                break
        else:
            raise RuntimeError(f'Newton failed at Lm = {Lm}')
        pm = pn
        dVtot = dV.sum()
        pid = pd if dVtot < 0 else ps
        W['press'] += float(np.sum(pm * (-dV)))
        W['ideal'] += pid * (-dVtot)
        e_ = float(np.sum((pm - pid) * (-dV)))
        W['exc'] += e_
        W['exc_out' if Lmid < LM_OUT else ('exc_in' if Lmid > LM_IN else 'exc_mid')] += e_
        t_thr = float(np.sum(Qd * (pm - pd)) + np.sum(Qs * (pm - ps)))
        t_gr = float(np.sum(gD * (pm - pd)) + np.sum(gS * (pm - ps)))
        t_ax = float(np.sum(Qa * (pm[:-1] - pm[1:]))) if n > 1 else 0.0
        Ld_ = gLd * (psi(pm - ps) - psi(pd - ps)); Ls_ = gLs * psi(pm - ps)
        t_lat = float(np.sum(Ld_ * (pm - pd)) + np.sum(Ls_ * (pm - ps)))
        W['thr_lat'] += t_lat * dt
        W['thr'] += t_lat * dt
        W['port'] += float(pd * Ld_.sum() + ps * Ls_.sum()) * dt
        W['vol_lat'] += float(Ld_.sum() + Ls_.sum()) * dt
        W['vol_sq'] += max(0.0, -dVtot)
        W['thr_throat'] += t_thr * dt; W['thr_groove'] += t_gr * dt; W['thr_ax'] += t_ax * dt
        W['thr'] += (t_thr + t_gr + t_ax) * dt
        W['port'] += (pd * (Qd.sum() + gD.sum()) + ps * (Qs.sum() + gS.sum())) * dt
        W['comp'] += float(np.sum(pm * Vn * (oil.lnrho(pm) - lnr_old)))
        if n > 1 and inertia:
            Qax = Qa
        if pm.max() > peak:
            peak = pm.max(); peakL = Lm
            sq_peak = -dVtot / dt                       # squeeze flow at the peak (m^3/s)
            lat_peak = float(Ld_.sum() + Ls_.sum())     # lateral leakage out at the peak
            out_peak = float(Qd.sum() + Qs.sum() + gD.sum() + gS.sum())
        low = min(low, pm.min())
        if keep:
            hist.append(dict(Lm=Lm, p=pm.copy(), V=float(Vn.sum()), dV=float(dVtot), oD=geo['oD'], oS=geo['oS'],
                             Qd=float(Qd.sum()), Qs=float(Qs.sum()), gD=float(gD.sum()), gS=float(gS.sum()),
                             exc=float(np.sum((pm - pid) * (-dV)))))
        p = pn; Vold = Vn
    per = 2 * math.pi / g.z1
    vol_lat, vol_sq = W.pop('vol_lat'), W.pop('vol_sq')
    res = {k: v / per for k, v in W.items()}
    res.update(h_lat_um=h_lat_um, lat_alpha=lat_alpha, thr_alpha=thr_alpha, G_lat_d=GLd, G_lat_s=GLs, lat_vol_mm3=vol_lat * 1e9, squeeze_vol_mm3=vol_sq * 1e9,
               sq_peak=sq_peak, lat_peak=lat_peak, out_peak=out_peak,
               lat_share_peak=lat_peak / sq_peak if sq_peak != 0 else float('nan'))
    res.update(rpm=rpm, dp_bar=dp_bar, T=T_c, NZ=NZ, axial=axial, excess_Nm=res['exc'],
               peak_bar_g=(peak - PATM) / 1e5, peak_Lm=peakL, low_bar_abs=low / 1e5, hist=hist,
               end_bar_g=(float(p.mean()) - PATM) / 1e5)
    # energy identity: sum p (-dV) = throttling + p_j Q_j to the chambers + compression
    res['energy_residual_Nm'] = res['press'] - (res['thr'] + res['port'] + res['comp'])
    return res


def line(r):
    return (f"excess {r['excess_Nm']:+.4f} N m  peak {r['peak_bar_g']:6.1f} bar g (Lm {r['peak_Lm']:+.3f})  "
            f"low {r['low_bar_abs']:.3f} bar abs | phases: outlet-arc {r['exc_out']:+.4f}, closed {r['exc_mid']:+.4f}, "
            f"inlet-arc {r['exc_in']:+.4f} | throttling {r['thr']:.4f} (throats {r['thr_throat']:.4f}, "
            f"grooves {r['thr_groove']:.4f}, channel {r['thr_ax']:.4f}), ports-ideal {r['port']-r['ideal']:+.4f}, "
            f"compression {r['comp']:+.4f}, lateral {r.get('thr_lat', 0):.4f}, energy residual {r['energy_residual_Nm']:+.1e}")


# mm of mid-face travel before the delivery-end throat closes at the z = b face / after the
# suction-end throat opens at the z = 0 face: the window of the cavity's life that is simulated
# (it starts at the delivery pressure); 2.7 mm is as far as the section tables reach
DEFAULT_MARGIN = (1.5, 2.7)

CONDS = [(1000, 30, 60), (2000, 30, 60), (4000, 30, 60), (4000, 10, 120)]
MODEL = {(1000, 30, 60): (0.0205, 48.6), (2000, 30, 60): (0.0815, None),
         (4000, 30, 60): (0.2848, 150.0), (4000, 10, 120): (0.2602, None)}

if __name__ == '__main__':
    import time
    which = sys.argv[1] if len(sys.argv) > 1 else 'a'
    if which == 'hist':    # python trapped.py hist RPM BAR DEGC [NZ]: pressure history to ./history_*.csv
        c = tuple(int(v) for v in sys.argv[2:5]); nz = int(sys.argv[5]) if len(sys.argv) > 5 else 1
        r = run(*c, NZ=nz, keep=True)
        name = f"history_{c[0]}_{c[1]}_{c[2]}_nz{nz}.csv"
        with open(name, 'w') as f:
            f.write('Lm_mm,theta_deg,' + ','.join(f'p{i}_bar_g' for i in range(len(r['hist'][0]['p'])))
                    + ',V_mm3,dV_mm3,overlapD_mm2,overlapS_mm2,Q_to_delivery_lpm,Q_to_suction_lpm,excess_J\n')
            for h in r['hist']:
                f.write(f"{h['Lm']:.5f},{math.degrees((h['Lm'] - r['hist'][0]['Lm']) / g.rb1):.4f},"
                        + ','.join(f'{(x - PATM) / 1e5:.4f}' for x in h['p'])
                        + f",{h['V']*1e9:.4f},{h['dV']*1e9:.6f},{h['oD'][0]:.5f},{h['oS'][0]:.5f},"
                        f"{(h['Qd'] + h['gD'])*6e4:.5f},{(h['Qs'] + h['gS'])*6e4:.5f},{h['exc']:.4e}\n")
        print(line(r)); print('->', name)
        sys.exit(0)
    for c in CONDS:
        t = time.time()
        if which == 'a':
            r = run(*c, NZ=1, NS=128)
        else:
            r = run(*c, NZ=int(which))
        print(f"{c}: {line(r)}  [{time.time()-t:.1f}s]", flush=True)
