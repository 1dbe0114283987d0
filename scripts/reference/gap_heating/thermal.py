"""Viscous heating in the clearance gaps of the seed gear pump: how wrong is the
isothermal-gap assumption (gap oil at the rig's bulk temperature)?

Independent estimate (a second engineer, helper session 23; docs/model.md section 11). Pure Python 3 standard library.
Reuses, read-only, the reference helpers
  scripts/reference/meshing_zone/geom.py      (involute geometry, tip lands)
  scripts/reference/tip_chain_air/tipchain.py (Walther oil, tip-chain dynamics)
No project Rust code is read or run. See README.md for every assumption.

Usage:
  python3 scripts/reference/gap_heating/thermal.py            # all 14 conditions -> table (stdout)
  python3 scripts/reference/gap_heating/thermal.py --check    # film-solver checks (energy balance, Brinkman limit)
  python3 scripts/reference/gap_heating/thermal.py --quick    # only the 4 conditions of the brief
"""
import math
import sys
import pathlib

sys.dont_write_bytecode = True          # do not leave __pycache__ in the project tree
MAIN = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(MAIN / 'tip_chain_air'))
sys.path.insert(0, str(MAIN / 'meshing_zone'))
import geom          # noqa: E402
import tipchain as tc  # noqa: E402

MM = 1e-3
BAR = 1e5
# ------------------------------------------------------------------ oil
RHOC = 1.7e6            # rho c_p of a mineral oil, J/(m^3 K) (830 kg/m3 x 2050 J/(kg K))
ALPHA = 8e-8            # thermal diffusivity, m^2/s
KOIL = ALPHA * RHOC     # conductivity, 0.136 W/(m K)
_o = tc.D['oil']
_B = (math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) - math.log10(math.log10(_o['nu_100c_cst'] + 0.7))) \
    / (math.log10(373.15) - math.log10(313.15))
_A = math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) + _B * math.log10(313.15)


def nu_cst(T):
    return 10 ** (10 ** (_A - _B * math.log10(T + 273.15))) - 0.7


def rho(T):
    return _o['density_20c_kg_m3'] / (1 + _o['expansion_per_k'] * (T - 20))


def mu(T):
    return nu_cst(T) * 1e-6 * rho(T)


def slope(T):
    """-d ln(mu)/dT, 1/K"""
    return -(math.log(mu(T + 0.05)) - math.log(mu(T - 0.05))) / 0.1


# ------------------------------------------------------------------ geometry
b = geom.b * MM
Vm = tc.Vm
GEAR = tc.GEARS
SHAFT_R = {'drive': tc.D['bearings']['diameter_drive_mm'] / 2 * MM,
           'driven': tc.D['bearings']['diameter_driven_mm'] / 2 * MM}
LB = tc.D['bearings']['length_mm'] * MM
H_TIP = tc.D['clearance']['tip_um'] * 1e-6
H_LAT = tc.D['clearance']['lateral_um'] * 1e-6
C_BRG = tc.D['clearance']['bearing_um'] * 1e-6
RATIO = geom.z1 / geom.z2            # driven speed / driving speed


def n_tips_mean(g):
    """time-mean number of sealing tips of one gear"""
    pitch = 2 * math.pi / g['z']
    S = g['th_d'] - g['th_s'] - 2 * g['half_tip'] - pitch
    return S / pitch + 1.0, S


def tooth_fraction(g):
    """fraction of the annulus rf..ra covered by teeth (tooth faces shear on the plates)"""
    ann = math.pi * (g['ra']**2 - g['rf']**2) / g['z']
    return (ann - g['area']) / ann


# ------------------------------------------------------------------ the film solver
def film(h, L, G, U, W, T0, walls, Ny=48, Nx=3000, Tin=None):
    """Steady 2-D film, x along the through-flow (0..L), y across (0..h).
    Velocity (isoviscous at T0): u = U y/h + 6 ubar_p (y/h)(1-y/h), ubar_p = h^2 G/(12 mu0)
    (the wall y=0 at rest in the frame where the film geometry is steady, the wall y=h
    moving at U along x); a cross shear w = W y/h (moves no oil along x, dissipates).
    Energy: rho c u dT/dx = k d2T/dy2 + mu(T)[(du/dy)^2 + (dw/dy)^2]; no axial conduction.
    walls: 'iso' (both walls at T0) or 'adia' (no wall flux). Inlet at Tin (default T0).
    Backward Euler in x, conservative finite volumes in y.
    Returns exit mixing-cup rise, heat to walls / total dissipation, and the
    effective film rise dT_eff defined by the Poiseuille resistance with mu(T(x,y)):
    R/R0 = mu(T0 + dT_eff)/mu(T0)."""
    Tin = T0 if Tin is None else Tin
    mu0 = mu(T0)
    dy = h / Ny
    dx = L / Nx
    ubp = h * h * G / (12 * mu0)
    ys = [(i + 0.5) * dy for i in range(Ny)]
    u = [U * y / h + 6 * ubp * (y / h) * (1 - y / h) for y in ys]
    dudy2 = [(U / h + 6 * ubp / h * (1 - 2 * y / h))**2 + (W / h)**2 for y in ys]
    Q = sum(u) * dy                       # per unit width
    T = [Tin] * Ny
    diss_tot = 0.0
    wall = 0.0
    Rint = 0.0
    Rint0 = 0.0
    a = KOIL / dy**2
    q0 = sum((h - y) * (0.5 * h - y) for y in ys) * dy / mu0
    for n in range(Nx):
        # build tridiagonal: (rc u/dx + conduction) T_new = rc u/dx T_old + Phi
        lo = [0.0] * Ny
        di = [0.0] * Ny
        up = [0.0] * Ny
        rhs = [0.0] * Ny
        for i in range(Ny):
            c = RHOC * u[i] / dx
            phi = mu(T[i]) * dudy2[i]
            diss_tot += phi * dy * dx
            di[i] = c
            rhs[i] = c * T[i] + phi
            if i > 0:
                lo[i] = -a
                di[i] += a
            if i < Ny - 1:
                up[i] = -a
                di[i] += a
            if walls == 'iso' and (i == 0 or i == Ny - 1):
                di[i] += 2 * a        # wall at the cell face, half a cell away
                rhs[i] += 2 * a * T0
        # Thomas
        cp = [0.0] * Ny
        dp = [0.0] * Ny
        for i in range(Ny):
            den = di[i] - (lo[i] * cp[i - 1] if i else 0.0)
            cp[i] = up[i] / den
            dp[i] = (rhs[i] - (lo[i] * dp[i - 1] if i else 0.0)) / den
        for i in range(Ny - 2, -1, -1):
            dp[i] -= cp[i] * dp[i + 1]
        T = dp
        if walls == 'iso':
            wall += 2 * a * dy * ((T[0] - T0) + (T[-1] - T0)) * dx
        # Poiseuille conductance of this slice with mu(y)
        F = [1 / mu(t) for t in T]
        sF = sum(F)
        cc = sum(y * f for y, f in zip(ys, F)) / sF
        q = sum((h - y) * (cc - y) * f for y, f in zip(ys, F)) * dy
        Rint += dx / q
        Rint0 += dx / q0                  # same quadrature at uniform T0 (no discretisation bias)
    Tout = sum(ui * ti for ui, ti in zip(u, T)) * dy / Q
    ratio = Rint / Rint0
    dT_eff = -math.log(ratio) / slope(T0)
    return dict(dT_exit=Tout - Tin, wall_frac=wall / diss_tot if diss_tot else 0.0, dT_eff=dT_eff,
                ratio=ratio, Q=Q, diss=diss_tot, ubar=Q / h, Tmax=max(T) - T0)


# ------------------------------------------------------------------ tips
def pocket_mixing(g, omega, Qrel, dT_land, film_rise, Tdel_rise=0.0, npts=400):
    """Temperature of the oil in the sealed pockets of one gear (gear frame).
    Pocket = well-mixed volume V sealed at T0; the relative tip flow Qrel (m^3/s,
    the same through every land, quasi-steady) enters from the one-pitch-older
    pocket ahead, heated by dT_land in the land, and leaves to the younger one.
    dT/da = (Q/V)[T(a+tp) + dT_land - T(a)], T(0)=0, T(a+tp)=Tdel_rise past the
    opening. Returns the mean (over lands and pitch phase) rise of the oil entering
    a land, and the effective film rise of the chain (series resistances):
    mean over phase of the harmonic... (leak ~ 1/sum mu_k)."""
    pitch = 2 * math.pi / g['z']
    nt, S = n_tips_mean(g)
    tl = S / omega
    tp = pitch / omega
    V = g['V_space']
    k = Qrel / V
    da = tl / npts
    T = [0.0] * (npts + 1)

    def ahead(a, Tl):
        if a + tp > tl:
            return Tdel_rise
        x = (a + tp) / da
        i = min(int(x), npts - 1)
        w = x - i
        return Tl[i] * (1 - w) + Tl[i + 1] * w

    for sweep in range(200):
        new = [0.0] * (npts + 1)
        for i in range(npts):
            a = i * da
            # implicit midpoint-ish: exponential relaxation towards the target
            tgt = 0.5 * (ahead(a, T) + ahead(a + da, T)) + dT_land
            new[i + 1] = tgt + (new[i] - tgt) * math.exp(-k * da)
        if max(abs(x - y) for x, y in zip(new, T)) < 1e-9:
            T = new
            break
        T = new
    # lands at phase phi: land 0 fed by pocket age phi, ..., last land fed by delivery
    s0 = slope_T0[0]
    inv_m = 0.0
    mean_in = 0.0
    nph = 50
    for j in range(nph):
        phi = (j + 0.5) / nph * tp
        ages = []
        a = phi
        while a <= tl:
            ages.append(a)
            a += tp
        Tins = []
        for a in ages:
            x = a / da
            i = min(int(x), npts - 1)
            w = x - i
            Tins.append(T[i] * (1 - w) + T[i + 1] * w)
        Tins.append(Tdel_rise)
        m = sum(math.exp(-s0 * (t + film_rise)) for t in Tins) / len(Tins)
        inv_m += 1 / m / nph
        mean_in += sum(Tins) / len(Tins) / nph
    m_eff = 1 / inv_m
    return dict(m=m_eff, dT_film=-math.log(m_eff) / s0, mean_in=mean_in, Tmax=max(T),
                replaced=Qrel * tl / V)


slope_T0 = [0.03]


def tips(rpm, dp_bar, T0, base):
    """Temperature rises of the tip films of both gears, and the viscosity factor
    for the tip-chain run, in three limits."""
    w1 = rpm * 2 * math.pi / 60
    out = {}
    for nm, w in (('drive', w1), ('driven', w1 * RATIO)):
        g = GEAR[nm]
        nt, S = n_tips_mean(g)
        dpl = dp_bar * BAR / nt                      # mean pressure drop per land
        L = g['land']
        U = w * g['ra']
        Qrel = base['res'][nm]['leak_pct'] / 100 * Vm * rpm / 60   # relative flow through a land (gear frame)
        Gp = dpl / L
        m0 = mu(T0)
        Pc = m0 * U * U * b * L / H_TIP                 # Couette dissipation per land
        Qp = b * H_TIP**3 * dpl / (12 * m0 * L)
        Pp = Qp * dpl                                   # Poiseuille dissipation per land
        Qland = Qp + b * H_TIP * U / 2                  # isoviscous relative flow through a land
        dT_ad = (Pc + Pp) / (RHOC * Qland)              # (a) adiabatic rise through one land
        # film solver (tip frame: tip at rest, casing moving towards the suction at U)
        fa = film(H_TIP, L, Gp, U, 0.0, T0, 'adia', Ny=192, Nx=400)
        fb = film(H_TIP, L, Gp, U, 0.0, T0, 'iso', Ny=192, Nx=400)
        # pockets: (a) adiabatic lands, (b) conducting lands; mixing in the pockets
        mix_a = pocket_mixing(g, w, Qland, fa['dT_exit'], fa['dT_eff'])
        mix_b = pocket_mixing(g, w, Qland, fb['dT_exit'], fb['dT_eff'])
        # (a') no mixing in the pockets: the leak oil keeps all its heat from land to land
        cum = nt * dT_ad
        t_cond = H_TIP**2 / ALPHA
        t_res = L / (Qland / (b * H_TIP))
        out[nm] = dict(nt=nt, dpl=dpl, U=U, Qrel=Qrel, Qland=Qland, Pc=Pc, Pp=Pp, dT_ad=dT_ad, fa=fa, fb=fb,
                       mix_a=mix_a, mix_b=mix_b, cum=cum, t_cond=t_cond, t_res=t_res,
                       Gz=t_cond / t_res, Pe=Qland / b / ALPHA,
                       torque=nt * m0 * U * b * L / H_TIP * g['ra'] * (w / w1))   # Couette torque, to drive shaft
    return out


def run_chain(rpm, dp_bar, T0, mfac_drive=1.0, mfac_driven=1.0):
    """tip-chain leak (% of Vm n) with the viscosity of each gear's lands scaled"""
    tc.RHO0 = rho(T0)
    res = {}
    tot = {}
    for nm, mf in (('drive', mfac_drive), ('driven', mfac_driven)):
        tc.MU = mu(T0) * mf
        r = tc.pump(30, 0.0, rpm=rpm, dp_bar=dp_bar)
        res[nm] = r['res'][nm]
        tot[nm] = r
    tc.MU = mu(T0)
    # casing-frame net tip loss = leak (gear frame) + press - annulus; press and annulus do not depend on mu
    r = tot['drive']
    leak = res['drive']['leak_pct'] + res['driven']['leak_pct']
    return dict(res=res, leak=leak, net=leak + r['press'] - r['layer'], press=r['press'], layer=r['layer'])


# ------------------------------------------------------------------ lateral gaps
def pressure_integral(g):
    """int p_gauge dtheta / pd over the gear's periphery: delivery zone (mesh to the
    delivery edge) at pd, bore arc a linear ramp, suction zone at 0."""
    th_s = g['th_s']
    th_d = g['th_d'] - 2 * math.pi          # negative
    bore = g['th_d'] - g['th_s']
    return abs(th_d) + bore / 2


def radial_force(g, dp):
    """hydraulic radial force on the gear (N): -int p r_hat ra b dtheta"""
    th_s = g['th_s']
    th_d = g['th_d'] - 2 * math.pi
    bore = g['th_d'] - g['th_s']
    fx = fy = 0.0
    n = 2000
    for i in range(n):
        th = -math.pi + (i + 0.5) * 2 * math.pi / n
        if th_d <= th <= 0:
            p = dp
        elif 0 < th < th_s:
            p = 0.0
        else:
            a = (th - th_s) % (2 * math.pi)
            p = dp * a / bore
        fx -= p * math.cos(th) * 2 * math.pi / n
        fy -= p * math.sin(th) * 2 * math.pi / n
    return math.hypot(fx, fy) * g['ra'] * b


def lateral(rpm, dp_bar, T0):
    """lateral gaps, both faces of both gears.
    Leak (my estimate): radial pocket -> hub (hub drained to suction) across the
    annular land rf..r_shaft, with the periphery's pressure; plus one path per face
    across a tooth face in the mesh (delivery -> suction: length = tooth thickness at
    mid height, width = tooth height)."""
    w1 = rpm * 2 * math.pi / 60
    dp = dp_bar * BAR
    m0 = mu(T0)
    out = {}
    Qtot = 0.0
    torque = 0.0
    P_ann_tot = 0.0
    for nm, w in (('drive', w1), ('driven', w1 * RATIO)):
        g = GEAR[nm]
        rs = SHAFT_R[nm]
        rf, ra = g['rf'], g['ra']
        lnr = math.log(rf / rs)
        Qrad = H_LAT**3 / (12 * m0 * lnr) * dp * pressure_integral(g)        # per face
        # mesh path: tooth thickness at mid height
        rm = 0.5 * (rf + ra)
        rb = geom.rb1 * MM if nm == 'drive' else geom.rb2 * MM
        psib = geom.psib1 if nm == 'drive' else geom.psib2
        s_mid = 2 * geom.half_angle(rb / MM, psib, rm / MM) * rm
        Qmesh = H_LAT**3 * (ra - rf) * dp / (12 * m0 * s_mid)               # per face
        ft = tooth_fraction(g)
        P_ann = m0 * w * w * math.pi * (rf**4 - rs**4) / (2 * H_LAT)         # per face, annulus
        P_teeth = ft * m0 * w * w * math.pi * (ra**4 - rf**4) / (2 * H_LAT)  # per face, tooth faces
        tq = 2 * (P_ann + P_teeth) / w * (w / w1)                           # 2 faces, to drive shaft
        torque += tq
        Qtot += 2 * (Qrad + Qmesh)
        P_ann_tot += 2 * P_ann
        # film along the radial path (plane approximation), cross shear at the land's mean radius
        Lr = rf - rs
        Gr = dp / lnr / (0.5 * (rf + rs))            # mean radial gradient in the delivery sector
        fb = film(H_LAT, Lr, Gr, 0.0, w * 0.5 * (rf + rs), T0, 'iso', Nx=800)
        # (a) adiabatic: all the annulus shear heat leaves with the radial leak (+ its own throttling)
        dT_ad_exit = (P_ann + Qrad * dp) / (RHOC * Qrad)
        # developed Couette rise (walls at T0) at the tip radius, over the tooth faces
        dT_dev_ra = m0 * (w * ra)**2 / (12 * KOIL)
        out[nm] = dict(Qrad=Qrad, Qmesh=Qmesh, P_ann=P_ann, P_teeth=P_teeth, fb=fb, dT_ad_exit=dT_ad_exit,
                       dT_dev_ra=dT_dev_ra, t_cond=H_LAT**2 / ALPHA,
                       t_res=Lr / fb['ubar'], t_circ=(pressure_integral(g)) / (w / 2), torque=tq, lnr=lnr)
    out['Q'] = Qtot
    out['torque'] = torque
    out['pct'] = Qtot / (Vm * rpm / 60) * 100
    return out


# ------------------------------------------------------------------ bearings
def bearings(rpm, dp_bar, T0, mesh_force_drive):
    """Two journal bearings per gear. Petroff torque; Ocvirk short bearing for the
    eccentricity, side flow and loaded friction (sensitivity)."""
    w1 = rpm * 2 * math.pi / 60
    m0 = mu(T0)
    out = {}
    tq_p = tq_o = 0.0
    for nm, w in (('drive', w1), ('driven', w1 * RATIO)):
        g = GEAR[nm]
        R = SHAFT_R[nm]
        U = w * R
        Tp = 2 * math.pi * m0 * w * R**3 * LB / C_BRG                # one bearing, Petroff
        Fh = radial_force(g, dp_bar * BAR)
        W = 0.5 * math.hypot(Fh, mesh_force_drive)                  # per bearing (mesh force at random angle)
        # Ocvirk: W = mu U L^3 e/(4 c^2 (1-e^2)^2) sqrt(pi^2 (1-e^2) + 16 e^2)
        def Wof(e):
            return m0 * U * LB**3 * e / (4 * C_BRG**2 * (1 - e * e)**2) * math.sqrt(math.pi**2 * (1 - e * e) + 16 * e * e)
        lo, hi = 0.0, 0.99999
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if Wof(mid) < W:
                lo = mid
            else:
                hi = mid
        e = lo
        phi = math.atan2(math.pi * math.sqrt(1 - e * e), 4 * e)
        To = Tp / math.sqrt(1 - e * e) + 0.5 * W * C_BRG * e * math.sin(phi)
        Qs = e * U * C_BRG * LB
        # conduction limit: developed Couette film, walls at T0 (mean rise mu U^2/(12 k));
        # at the minimum film the shear is 1/(1-e) larger but the developed rise is the same
        dT_dev = m0 * U * U / (12 * KOIL)
        dT_ad = Tp * w / (RHOC * Qs) if Qs > 0 else float('inf')    # all Petroff heat into the side flow
        dT_ad_o = To * w / (RHOC * Qs) if Qs > 0 else float('inf')
        tq_p += 2 * Tp * (w / w1)
        tq_o += 2 * To * (w / w1)
        out[nm] = dict(Tp=Tp, To=To, W=W, Fh=Fh, e=e, hmin=C_BRG * (1 - e), Qs=Qs, dT_dev=dT_dev, dT_ad=dT_ad,
                       dT_ad_o=dT_ad_o, t_cond=C_BRG**2 / ALPHA, t_lap=2 * math.pi * R / (U / 2),
                       S=(R / C_BRG)**2 * m0 * (w / 2 / math.pi) / (W / (2 * R * LB)))
    out['torque_p'] = tq_p
    out['torque_o'] = tq_o
    return out


# ------------------------------------------------------------------ one condition
ETA_HM = 0.9
# metal-offset scenario (order of magnitude; see README)
PLATE_F = tc.D['losses']['thrust_plate_friction']       # 0.05
PLATE_UNB = tc.D['losses']['thrust_plate_unbalance']    # 0.15 (one pressure-compensated face per gear)
MESH_LOSS = 0.017       # mesh friction loss / ideal hydraulic power: f pi (1/z1 + 1/z2) x 0.5, f = 0.06
UA = 20.0               # metal-to-oil conductance at 1000 rpm, W/K: ~0.015 m^2 wetted x ~1300 W/(m^2 K) (range 12..36), x sqrt(n/1000)


def condition(rpm, dp_bar, T0, verbose=True):
    slope_T0[0] = slope(T0)
    s = slope(T0)
    w1 = rpm * 2 * math.pi / 60
    Vn = Vm * rpm / 60
    base = run_chain(rpm, dp_bar, T0)
    tp = tips(rpm, dp_bar, T0, tc.pump(30, 0.0, rpm=rpm, dp_bar=dp_bar))
    lat = lateral(rpm, dp_bar, T0)
    torque_ideal = Vm * dp_bar * BAR / (2 * math.pi)
    F_mesh = torque_ideal / (geom.rb1 * MM)
    brg = bearings(rpm, dp_bar, T0, F_mesh)
    eta_v = 1 - base['net'] / 100 - lat['pct'] / 100
    # global balance
    tq = torque_ideal / ETA_HM
    Qdel = eta_v * Vn
    Ploss = tq * w1 - Qdel * dp_bar * BAR
    dT_glob = Ploss / (RHOC * Qdel)
    # tips: chain with the film viscosity of each limit
    runs = {}
    for lab, key in (('a', 'mix_a'), ('b', 'mix_b')):
        runs[lab] = run_chain(rpm, dp_bar, T0, tp['drive'][key]['m'], tp['driven'][key]['m'])
    # no-mixing bound: the oil keeps its heat from land to land (land k from the delivery is fed
    # at (k-1) dT_exit(a)), plus the adiabatic film rise of the land itself
    mcum = {}
    for nm in ('drive', 'driven'):
        t = tp[nm]
        N = int(round(t['nt']))
        mcum[nm] = sum(math.exp(-s * (k * t['fa']['dT_exit'] + t['fa']['dT_eff'])) for k in range(N)) / N
        t['nomix_film'] = -math.log(mcum[nm]) / s
    runs['cum'] = run_chain(rpm, dp_bar, T0, mcum['drive'], mcum['driven'])
    # global shift: all gaps at T0 + dT_glob (bound)
    mg = math.exp(-s * dT_glob)
    runs['glob'] = run_chain(rpm, dp_bar, T0, mg, mg)
    # metal offset (lumped, order of magnitude): heat into the metal / (h A)
    P_plate = 0.0
    for nm, w in (('drive', w1), ('driven', w1 * RATIO)):
        ra = GEAR[nm]['ra']
        P_plate += PLATE_F * PLATE_UNB * math.pi * ra**2 * dp_bar * BAR * (2 / 3) * ra * w
    P_mesh = MESH_LOSS * Vn * dp_bar * BAR
    P_brg = brg['torque_o'] * w1
    P_lat = lat['torque'] * w1
    P_tipwall = sum(tp[nm]['fb']['wall_frac'] * (tp[nm]['Pc'] + tp[nm]['Pp']) * tp[nm]['nt'] for nm in ('drive', 'driven'))
    P_metal = P_plate + P_mesh + P_brg + P_lat + P_tipwall
    UAn = UA * math.sqrt(rpm / 1000)    # transient conduction into pocket oil: h ~ (alpha t)^-1/2, t ~ 1/n
    dT_metal = P_metal / UAn
    mm_ = math.exp(-s * dT_metal)
    runs['metal'] = run_chain(rpm, dp_bar, T0, mm_, mm_)
    d_tip = {k: -(r['leak'] - base['leak']) for k, r in runs.items()}   # + = eta_v gain? no: leak up -> eta_v down
    # d eta_v (points) = -(leak change)
    deta_tip = {k: -(r['leak'] - base['leak']) for k, r in runs.items()}
    # lateral: leak ~ 1/mu, film rise (b) from the solver (walls at T0), (a) half the adiabatic exit rise
    def lat_deta(dT):
        return -lat['pct'] * (math.exp(s * dT) - 1)
    lat_b = max(lat[nm]['fb']['dT_eff'] for nm in ('drive', 'driven'))
    lat_b_w = sum(lat[nm]['fb']['dT_eff'] * (lat[nm]['Qrad'] + lat[nm]['Qmesh']) for nm in ('drive', 'driven')) \
        / sum(lat[nm]['Qrad'] + lat[nm]['Qmesh'] for nm in ('drive', 'driven'))
    lat_a = sum(0.5 * lat[nm]['dT_ad_exit'] * lat[nm]['Qrad'] for nm in ('drive', 'driven')) \
        / sum(lat[nm]['Qrad'] for nm in ('drive', 'driven'))
    # torque changes (viscous parts scale with mu)
    def fac(dT):
        return math.exp(-s * dT) - 1
    tip_tq = tp['drive']['torque'] + tp['driven']['torque']
    tip_dTa = -math.log(0.5 * (tp['drive']['mix_a']['m'] + tp['driven']['mix_a']['m'])) / s
    tip_dTb = -math.log(0.5 * (tp['drive']['mix_b']['m'] + tp['driven']['mix_b']['m'])) / s
    # lateral torque: film rise over the shear area, conduction limit = developed Couette mean (area-weighted ~ r^4 weight -> use ra value x 0.6)
    lat_dT_tq_b = 0.6 * max(lat['drive']['dT_dev_ra'], lat['driven']['dT_dev_ra'])
    lat_dT_tq_a = lat_a
    brg_dT_b = max(brg['drive']['dT_dev'], brg['driven']['dT_dev'])
    brg_dT_a = min(brg['drive']['dT_ad'], brg['driven']['dT_ad'])
    R = dict(rpm=rpm, dp=dp_bar, T0=T0, mu=mu(T0), nu=nu_cst(T0), s=s, base=base, tp=tp, lat=lat, brg=brg,
             eta_v=eta_v, Ploss=Ploss, dT_glob=dT_glob, runs=runs, deta_tip=deta_tip,
             lat_a=lat_a, lat_b=lat_b_w, deta_lat_a=lat_deta(lat_a), deta_lat_b=lat_deta(lat_b_w),
             deta_lat_glob=lat_deta(dT_glob),
             tip_tq=tip_tq, lat_tq=lat['torque'], brg_tq=brg['torque_p'], brg_tq_o=brg['torque_o'],
             tip_dTa=tip_dTa, tip_dTb=tip_dTb, lat_dT_tq_a=lat_dT_tq_a, lat_dT_tq_b=lat_dT_tq_b,
             brg_dT_a=brg_dT_a, brg_dT_b=brg_dT_b, fac=fac)
    R['dtq_a'] = tip_tq * fac(tip_dTa) + lat['torque'] * fac(lat_dT_tq_a) + brg['torque_p'] * fac(brg_dT_a)
    R['dtq_b'] = tip_tq * fac(tip_dTb) + lat['torque'] * fac(lat_dT_tq_b) + brg['torque_p'] * fac(brg_dT_b)
    R['dtq_glob'] = (tip_tq + lat['torque'] + brg['torque_o']) * fac(dT_glob)
    R['dtq_metal'] = (tip_tq + lat['torque'] + brg['torque_o']) * fac(dT_metal)
    R.update(P_plate=P_plate, P_mesh=P_mesh, P_brg=P_brg, P_lat=P_lat, P_tipwall=P_tipwall, P_metal=P_metal,
             dT_metal=dT_metal, deta_lat_metal=lat_deta(dT_metal))
    if verbose:
        report(R)
    return R


def report(R):
    p = print
    p(f"\n=== {R['rpm']:.0f} rpm, {R['dp']:.0f} bar, {R['T0']:.0f} degC: nu {R['nu']:.2f} cSt, mu {R['mu']*1e3:.2f} mPa s, "
      f"-dln(mu)/dT = {R['s']:.4f} /K")
    b0 = R['base']
    p(f"  isothermal: tip leak (gear frame) drive {b0['res']['drive']['leak_pct']:.3f} driven {b0['res']['driven']['leak_pct']:.3f} %; "
      f"tip net (casing frame, incl. compressibility) {b0['net']:.3f} %; lateral leak {R['lat']['pct']:.3f} %; eta_v ~ {R['eta_v']*100:.2f} %")
    for nm in ('drive', 'driven'):
        t = R['tp'][nm]
        p(f"  tips {nm:6s}: {t['nt']:.2f} tips, dp/land {t['dpl']/BAR:.2f} bar, U {t['U']:.2f} m/s, Q/land {t['Qland']*1e6:.3f} cm3/s "
          f"(ubar {t['fa']['ubar']:.2f} m/s), Couette {t['Pc']*1e3:.2f} mW + Poiseuille {t['Pp']*1e3:.1f} mW per land")
        p(f"      t_cond h^2/alpha {t['t_cond']*1e3:.2f} ms vs residence {t['t_res']*1e6:.1f} us: Gz {t['Gz']:.0f}, Pe {t['Pe']:.0f}; "
          f"(a) adiabatic land rise {t['dT_ad']:.3f} K (solver {t['fa']['dT_exit']:.3f}), film eff {t['fa']['dT_eff']:.3f} K; "
          f"(b) walls at T0: exit {t['fb']['dT_exit']:.3f} K, film eff {t['fb']['dT_eff']:.3f} K, wall share {t['fb']['wall_frac']*100:.0f} %")
        for lab in ('mix_a', 'mix_b'):
            m = t[lab]
            p(f"      pockets {lab}: replaced {m['replaced']:.2f} x V over the life, oldest pocket +{m['Tmax']:.3f} K, "
              f"mean inlet +{m['mean_in']:.3f} K, chain film rise {m['dT_film']:.3f} K (mu x {m['m']:.4f})")
        p(f"      no-mixing bound: cumulative {t['cum']:.3f} K through the chain; chain film rise {t['nomix_film']:.3f} K")
    for nm in ('drive', 'driven'):
        l = R['lat'][nm]
        p(f"  lateral {nm:6s}: Q radial {l['Qrad']*1e6*2:.3f} + mesh {l['Qmesh']*1e6*2:.3f} cm3/s (2 faces); shear annulus {l['P_ann']*2:.3f} W, teeth {l['P_teeth']*2:.3f} W; "
          f"t_cond {l['t_cond']*1e3:.2f} ms, radial res. {l['t_res']*1e3:.2f} ms, circ. {l['t_circ']*1e3:.1f} ms")
        p(f"      (a) adiabatic exit {l['dT_ad_exit']:.3f} K; (b) walls at T0: film eff {l['fb']['dT_eff']:.4f} K, exit {l['fb']['dT_exit']:.4f} K; "
          f"developed Couette at ra {l['dT_dev_ra']:.4f} K")
    for nm in ('drive', 'driven'):
        g = R['brg'][nm]
        p(f"  bearing {nm:6s}: Petroff {g['Tp']*1e3:.2f} mN m, load {g['W']:.0f} N, S {g['S']:.4f}, Ocvirk e {g['e']:.3f} (h_min {g['hmin']*1e6:.2f} um), "
          f"loaded torque {g['To']*1e3:.2f} mN m, side flow {g['Qs']*1e6:.4f} cm3/s; t_cond {g['t_cond']*1e3:.2f} ms, lap {g['t_lap']*1e3:.0f} ms; "
          f"(a) adiabatic {g['dT_ad']:.1f} K (loaded {g['dT_ad_o']:.1f}); (b) developed {g['dT_dev']:.4f} K")
    p(f"  viscous torque (isothermal, to drive shaft): tips {R['tip_tq']:.4f}, lateral {R['lat_tq']:.4f}, bearings Petroff {R['brg_tq']:.4f} "
      f"(loaded {R['brg_tq_o']:.4f}) N m")
    p(f"  global: shaft {Vm*R['dp']*BAR/(2*math.pi)/ETA_HM:.2f} N m, P_loss {R['Ploss']:.1f} W, delivery rise {R['dT_glob']:.3f} K")
    p(f"  d eta_v (points): tips (a) {R['deta_tip']['a']:+.4f}, (b) {R['deta_tip']['b']:+.4f}, no-mixing {R['deta_tip']['cum']:+.4f}, "
      f"global {R['deta_tip']['glob']:+.4f}; lateral (a) {R['deta_lat_a']:+.4f}, (b) {R['deta_lat_b']:+.4f}, global {R['deta_lat_glob']:+.4f}")
    p(f"  d torque (N m): (a) {R['dtq_a']:+.5f}, (b) {R['dtq_b']:+.5f}, global {R['dtq_glob']:+.5f}")
    p(f"  metal offset: heat into metal {R['P_metal']:.1f} W (plate friction {R['P_plate']:.1f}, mesh {R['P_mesh']:.1f}, "
      f"bearings {R['P_brg']:.1f}, lateral shear {R['P_lat']:.1f}, tip walls {R['P_tipwall']:.1f}) / UA {UA*math.sqrt(R['rpm']/1000):.1f} W/K "
      f"= {R['dT_metal']:.2f} K: d eta_v tips {R['deta_tip']['metal']:+.4f}, lateral {R['deta_lat_metal']:+.4f}; "
      f"d torque {R['dtq_metal']:+.5f} N m")


def check():
    T0 = 60.0
    slope_T0[0] = slope(T0)
    print(f"oil: nu(60) {nu_cst(60):.3f} cSt, nu(120) {nu_cst(120):.3f} cSt, mu(60) {mu(60)*1e3:.3f}, mu(120) {mu(120)*1e3:.3f} mPa s; "
          f"-dln mu/dT: 60 degC {slope(60):.4f}, 120 degC {slope(120):.4f} /K; k = {KOIL:.3f} W/(m K)")
    g = GEAR['drive']
    # energy check, adiabatic: exit rise = dissipation / (rho c Q)
    U, L, h = 2.06, g['land'], 30e-6
    Gp = 3.5e5 / L
    fa = film(h, L, Gp, U, 0.0, T0, 'adia', Nx=600)
    print(f"adiabatic tip film: exit {fa['dT_exit']:.5f} K, diss/(rho c Q) {fa['diss']/(RHOC*fa['Q']):.5f} K")
    for nx in (150, 600, 2400):
        fb = film(h, L, Gp, U, 0.0, T0, 'iso', Nx=nx)
        print(f"  iso walls Nx={nx}: exit {fb['dT_exit']:.5f}, film eff {fb['dT_eff']:.5f}, wall share {fb['wall_frac']:.4f}")
    for ny in (24, 96):
        fb = film(h, L, Gp, U, 0.0, T0, 'iso', Ny=ny, Nx=600)
        print(f"  iso walls Ny={ny}: exit {fb['dT_exit']:.5f}, film eff {fb['dT_eff']:.5f}")
    # Brinkman limit: pure Couette shear (cross), long channel, iso walls: mean -> mu W^2/(12 k)
    hh = 15e-6
    W = 5.0
    f = film(hh, 0.05, 1e9 * 0 + 2e7, 0.0, W, T0, 'iso', Nx=3000)
    print(f"long lateral-type film (W = 5 m/s): Tmax {f['Tmax']:.4f} K (developed Couette max mu W^2/(8k) = {mu(T0)*W*W/(8*KOIL):.4f}), "
          f"film eff {f['dT_eff']:.4f}")


if __name__ == '__main__':
    if '--check' in sys.argv:
        check()
        sys.exit()
    conds = [(1000, 10), (1000, 20), (1000, 30), (1000, 40), (500, 30), (2000, 30), (4000, 30)]
    if '--quick' in sys.argv:
        todo = [(1000, 30, 60), (4000, 30, 60), (500, 30, 120), (1000, 40, 120)]
    else:
        todo = [(r, d, T) for T in (60, 120) for r, d in conds]
    rows = [condition(r, d, T) for r, d, T in todo]
    print("\nSUMMARY (film rises in K; d eta_v in points of Vm n, + = better; d torque in N m)")
    print(f"{'rpm':>5s} {'bar':>4s} {'degC':>4s} | {'tip a':>6s} {'tip b':>6s} {'nomix':>6s} | {'lat a':>6s} {'lat b':>7s} | "
          f"{'brg a':>6s} {'brg b':>7s} | {'glob':>5s} | {'eta_v':>6s} {'dEv a':>7s} {'dEv b':>7s} {'dEv nm':>7s} {'dEv gl':>7s} | "
          f"{'Tq visc':>7s} {'dTq a':>8s} {'dTq b':>8s} {'dTq gl':>8s} | {'dTmet':>5s} {'dEv mt':>7s} {'dTq mt':>8s}")
    for R in rows:
        print(f"{R['rpm']:5.0f} {R['dp']:4.0f} {R['T0']:4.0f} | {R['tip_dTa']:6.3f} {R['tip_dTb']:6.3f} "
              f"{max(R['tp']['drive']['nomix_film'], R['tp']['driven']['nomix_film']):6.3f} | {R['lat_a']:6.2f} {R['lat_b']:7.4f} | "
              f"{R['brg_dT_a']:6.1f} {R['brg_dT_b']:7.4f} | {R['dT_glob']:5.2f} | {R['eta_v']*100:6.2f} "
              f"{R['deta_tip']['a']+R['deta_lat_a']:+7.3f} {R['deta_tip']['b']+R['deta_lat_b']:+7.3f} "
              f"{R['deta_tip']['cum']+R['deta_lat_a']:+7.3f} {R['deta_tip']['glob']+R['deta_lat_glob']:+7.3f} | "
              f"{R['tip_tq']+R['lat_tq']+R['brg_tq']:7.4f} {R['dtq_a']:+8.4f} {R['dtq_b']:+8.4f} {R['dtq_glob']:+8.4f} | "
              f"{R['dT_metal']:5.2f} {R['deta_tip']['metal']+R['deta_lat_metal']:+7.3f} {R['dtq_metal']:+8.4f}")
