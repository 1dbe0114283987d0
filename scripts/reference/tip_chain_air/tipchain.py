"""Lumped dynamic model of the tooth-tip chain of each gear of the seed pump,
with and without entrained (free) air. Pure Python 3 standard library.

Independent check (a second engineer, helper session 22; docs/references.md). Geometry basics (involute radii, base
half-angles, tip lands) are taken from the earlier reference script
scripts/reference/meshing_zone/geom.py (imported read-only); everything else
(space volume, oil, mixture law, chain dynamics) is computed here.
See README.md for every assumption.

Units inside: SI (m, Pa, s, kg). Gear angles in rad.

Usage:
  python3 tipchain.py                 # full table (1000 rpm, 30 bar, 60 degC)
  python3 tipchain.py --check         # geometry, oil, closed form, step convergence
  python3 tipchain.py --history       # pocket pressure histories at 30 um
  python3 tipchain.py --speeds        # 30 um at 500 / 1000 / 4000 rpm
  python3 tipchain.py --sens          # sensitivities (helix-shortened seal arc, drag sign, layer)
Environment: GEARPUMP_DESIGN (design file), DP_BAR (30), RPM (1000), TEMP_C (60).
"""
import math
import os
import sys
import pathlib

REF = pathlib.Path(__file__).resolve().parent.parent / 'meshing_zone'
sys.path.insert(0, str(REF))
import geom  # noqa: E402  (reference geometry helpers: rb, psib, half_angle, ra, rf, ...)

D = geom.DESIGN
MM = 1e-3
BAR = 1e5
P_ATM = 1.01325e5

# ------------------------------------------------------------------ geometry
b = geom.b * MM


def space_area(z, rb, psib, ra, rf, n=4000):
    """Transverse area of one tooth space between root and tip circle (m^2).
    Tooth half-angle psi(r) from the involute (radial flank below the base
    circle, no fillet, as geom.tooth_outline). Area of the tooth between rf
    and ra = int 2 psi(r) r dr (Simpson)."""
    h = (ra - rf) / n
    s = 0.0
    for i in range(n + 1):
        r = rf + i * h
        w = 1 if i in (0, n) else (4 if i % 2 else 2)
        s += w * 2 * geom.half_angle(rb, psib, r) * r
    tooth = s * h / 3
    return (math.pi * (ra**2 - rf**2) / z - tooth) * MM**2


GEARS = {}
for name, z, rb, psib, ra, rf, ks, kd in (
        ('drive', geom.z1, geom.rb1, geom.psib1, geom.ra1, geom.rf1, 'suction_port_edge_drive_deg',
         'delivery_port_edge_drive_deg'),
        ('driven', geom.z2, geom.rb2, geom.psib2, geom.ra2, geom.rf2, 'suction_port_edge_driven_deg',
         'delivery_port_edge_driven_deg')):
    A = space_area(z, rb, psib, ra, rf)
    half_tip = geom.half_angle(rb, psib, ra)            # half angular tip land (rad)
    GEARS[name] = dict(
        z=z, ra=ra * MM, rf=rf * MM, area=A, V_space=A * b,
        land=2 * half_tip * ra * MM,                      # tip land arc length (m), transverse
        half_tip=half_tip,
        th_s=math.radians(D['casing'][ks]),               # suction edge (seal starts beyond it)
        th_d=math.radians(D['casing'][kd]) + 2 * math.pi,  # delivery edge, round the back
    )

# displacement per driving revolution: closed form (Manring & Kasaragadda 2003),
# as in the reference scripts (leak.py / kin3d.py)
_k = geom.rw1 / geom.rw2
Vm = math.pi * geom.b * (geom.ra1**2 - geom.rw1**2 + _k * (geom.ra2**2 - geom.rw2**2)
                         - (1 + _k) * geom.pbt**2 / 12) * 1e-9

# ------------------------------------------------------------------ oil
_o = D['oil']
T_C = float(os.environ.get('TEMP_C', '60'))
_B = (math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) - math.log10(math.log10(_o['nu_100c_cst'] + 0.7))) \
    / (math.log10(373.15) - math.log10(313.15))
_A = math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) + _B * math.log10(313.15)
NU_CST = 10 ** (10 ** (_A - _B * math.log10(T_C + 273.15))) - 0.7
RHO0 = _o['density_20c_kg_m3'] / (1 + _o['expansion_per_k'] * (T_C - 20))   # at p_atm
MU = NU_CST * 1e-6 * RHO0
K = _o['bulk_modulus_gpa'] * 1e9


class Fluid:
    """Oil + free air: v(p) = (1-x0) exp(-(p-pa)/K) + x0 pa/p (volume of the
    mixture relative to its volume at pa; isothermal ideal gas, air mass
    neglected, no dissolution). rho(p) = RHO0 (1-x0) / v(p)."""

    def __init__(self, x0):
        self.x0 = x0
        self.r0 = RHO0 * (1 - x0)
        # table of Phi(p) = int_{pa}^{p} rho dp for the compressible Poiseuille flux
        self.p_lo, self.p_hi, self.dp = 0.05 * BAR, 120 * BAR, 0.002 * BAR
        n = int((self.p_hi - self.p_lo) / self.dp) + 1
        self.n = n
        phi = [0.0] * n
        prev = self.rho(self.p_lo)
        for i in range(1, n):
            p = self.p_lo + i * self.dp
            pm = p - 0.5 * self.dp
            cur = self.rho(p)
            phi[i] = phi[i - 1] + self.dp * (prev + 4 * self.rho(pm) + cur) / 6
            prev = cur
        off = self._interp(phi, P_ATM)
        self.phi = [v - off for v in phi]

    def v(self, p):
        return (1 - self.x0) * math.exp(-(p - P_ATM) / K) + self.x0 * P_ATM / p

    def rho(self, p):
        return self.r0 / self.v(p)

    def drho_dp(self, p):
        vv = self.v(p)
        dv = -(1 - self.x0) / K * math.exp(-(p - P_ATM) / K) - self.x0 * P_ATM / p**2
        return -self.r0 * dv / vv**2

    def _interp(self, tab, p):
        u = (p - self.p_lo) / self.dp
        i = int(u)
        if i < 0 or i >= self.n - 1:
            raise ValueError(f'pressure {p/BAR:.4f} bar outside table')
        w = u - i
        return tab[i] * (1 - w) + tab[i + 1] * w

    def Phi(self, p):
        return self._interp(self.phi, p)


# ------------------------------------------------------------------ one chain
def chain(gear, fl, h, omega, ps, pd, steps_per_deg=4, drag=+1, layer=True,
          arc_cut=0.0, record=False):
    """Periodic state of the tip chain of one gear.

    gear: entry of GEARS; fl: Fluid; h: tip clearance (m); omega: the gear's
    angular speed (rad/s); ps, pd: absolute port pressures (Pa).
    drag: +1 = Couette flow relative to the tooth (gear frame: the stationary
    casing drags oil from the delivery-side pocket back into the suction-side
    pocket, b h U / 2); -1 = the opposite sign (casing-frame convention);
    0 = no drag term.
    layer: the pocket includes the clearance layer above its space.
    arc_cut: angle (rad) removed from the sealed arc at each end (helix
    sensitivity).
    Returns a dict of per-pitch quantities (kg) and, with record, the pressure
    history of one pocket.
    """
    z = gear['z']
    pitch = 2 * math.pi / z
    dlt = gear['half_tip']
    th_a = gear['th_s'] + dlt + pitch / 2 + arc_cut   # space centre angle at sealing
    th_b = gear['th_d'] - dlt - pitch / 2 - arc_cut   # space centre angle at opening
    S = th_b - th_a
    J = int(S // pitch)
    psi_b = S - J * pitch
    V = gear['V_space']
    if layer:
        V += h * b * gear['ra'] * (pitch - 2 * dlt)
    U = omega * gear['ra']
    G = b * h**3 / (12 * MU * gear['land'])            # m^3/(s Pa) per kg/m^3 ... (mass: G*dPhi)
    Cu = drag * b * h * U / 2                          # m^3/s, + = towards suction

    def tipflow(p_up, p_dn):
        """mass flow (kg/s) from the delivery-side pocket (p_dn) into the
        suction-side pocket (p_up) through one tip gap."""
        fdn, fup = fl.Phi(p_dn), fl.Phi(p_up)
        if abs(p_dn - p_up) > 1.0:
            rbar = (fdn - fup) / (p_dn - p_up)
        else:
            rbar = fl.rho(0.5 * (p_dn + p_up))
        return G * (fdn - fup) + rbar * Cu

    def flows(p):
        """mass flows through the n+1 sealing tips (index 0: first tip, into the
        suction; index n: last tip, from the delivery) and their derivatives."""
        n = len(p)
        full = [ps] + p + [pd]
        m = [tipflow(full[i], full[i + 1]) for i in range(n + 1)]
        # d m_i / d p_up, d m_i / d p_dn (Poiseuille part exact; the drag term's
        # density derivative, < 1e-3 of it, is left out: Newton still converges)
        dup = [-G * fl.rho(full[i]) for i in range(n + 1)]
        ddn = [G * fl.rho(full[i + 1]) for i in range(n + 1)]
        return m, dup, ddn

    def net(m):
        return [m[i + 1] - m[i] for i in range(len(m) - 1)]

    def solve(p0, c, adt):
        """Newton for V rho(p_i) - c_i - adt * (m_{i+1} - m_i)(p) = 0 (tridiagonal)."""
        p = list(p0)
        n = len(p)
        for it in range(60):
            m, dup, ddn = flows(p)
            R = [V * fl.rho(p[i]) - c[i] - adt * (m[i + 1] - m[i]) for i in range(n)]
            # Jacobian: F_i = m_{i+1}(p_i, p_{i+1}) - m_i(p_{i-1}, p_i)
            diag = [V * fl.drho_dp(p[i]) - adt * (dup[i + 1] - ddn[i]) for i in range(n)]
            low = [-adt * (-dup[i]) for i in range(n)]        # d/dp_{i-1}: -(-d m_i/d p_up)
            up = [-adt * ddn[i + 1] for i in range(n)]         # d/dp_{i+1}: d m_{i+1}/d p_dn
            # Thomas
            cp = [0.0] * n
            dp_ = [0.0] * n
            for i in range(n):
                den = diag[i] - (low[i] * cp[i - 1] if i else 0.0)
                cp[i] = up[i] / den
                dp_[i] = (-R[i] - (low[i] * dp_[i - 1] if i else 0.0)) / den
            for i in range(n - 2, -1, -1):
                dp_[i] -= cp[i] * dp_[i + 1]
            mx = 0.0
            for i in range(n):
                q = min(max(p[i] + dp_[i], 0.06 * BAR), 119 * BAR)
                mx = max(mx, abs(q - p[i]))
                p[i] = q
            if mx < 1e-5:
                return p
        raise RuntimeError('Newton did not converge')

    gam = 2 - math.sqrt(2)
    w_a = 1 / (2 * (2 - gam))           # weights of F_n, F_g, F_{n+1} in the step's mass change
    w_c = (1 - gam) / (2 - gam)

    def step(p, dt):
        """TR-BDF2 (L-stable, 2nd order); returns new p and the step's mass
        through the first tip (to suction) and the last tip (from delivery)."""
        n = len(p)
        mn = [V * fl.rho(x) for x in p]
        m0, _, _ = flows(p)
        F0 = net(m0)
        c = [mn[i] + 0.5 * gam * dt * F0[i] for i in range(n)]
        pg = solve(p, c, 0.5 * gam * dt)
        mg = [V * fl.rho(x) for x in pg]
        m1, _, _ = flows(pg)
        c2 = [(mg[i] - (1 - gam)**2 * mn[i]) / (gam * (2 - gam)) for i in range(n)]
        pn = solve(pg, c2, w_c * dt)
        m2, _, _ = flows(pn)
        ms = dt * (w_a * (m0[0] + m1[0]) + w_c * m2[0])
        md = dt * (w_a * (m0[-1] + m1[-1]) + w_c * m2[-1])
        return pn, ms, md

    # state: pressures of the sealed pockets, index 0 = youngest (next to the suction)
    p = [ps] * J            # at psi = 0- (just before a new pocket seals)
    n_pitches = 4 * (J + 1) + 2   # the initial state is flushed; the last pitch is recorded
    hist = []
    Ms = Md = 0.0
    m_open = 0.0
    segs = ((0.0, psi_b), (psi_b, pitch))
    for k in range(n_pitches):
        last = k == n_pitches - 1
        p = [ps] + p        # a new pocket seals at the suction pressure
        if last:
            Ms = Md = 0.0
            m_seal = fl.rho(ps) * V
            p_start = list(p)
        for si, (a0, a1) in enumerate(segs):
            nst = max(2, int(math.ceil(math.degrees(a1 - a0) * steps_per_deg)))
            dt = (a1 - a0) / omega / nst
            for st in range(nst):
                if last and record:
                    hist.append((a0 + st * (a1 - a0) / nst, list(p)))
                p, ms, md = step(p, dt)
                if last:
                    Ms += ms
                    Md += md
            if si == 0:
                # the oldest pocket opens to the delivery
                if last:
                    m_open = fl.rho(p[-1]) * V
                    p_open = p[-1]
                p = p[:-1]
        if last and record:
            hist.append((pitch, list(p)))
    per = max(abs(a_ - b_) for a_, b_ in zip([ps] + p, p_start)) / (pd - ps)   # periodicity
    out = dict(per=per, J=J, S=S, psi_b=psi_b, V=V, Ms=Ms, Md=Md, m_open=m_open, m_seal=m_seal,
               p_open=p_open, balance=m_seal + Md - Ms - m_open, pitch=pitch)
    if record:
        # one pocket's history: age = (pocket index) * pitch + psi
        H = []
        for psi, pl in hist:
            for j, pj in enumerate(pl):
                age = j * pitch + psi
                if age <= S + 1e-12:
                    H.append((age, pj))
        H.sort()
        out['history'] = H
    return out


def pump(h_um, x0, rpm=None, dp_bar=None, **kw):
    rpm = rpm if rpm is not None else float(os.environ.get('RPM', '1000'))
    dp_bar = dp_bar if dp_bar is not None else float(os.environ.get('DP_BAR', '30'))
    ps = P_ATM
    pd = P_ATM + dp_bar * BAR
    fl = Fluid(x0)
    w1 = rpm * 2 * math.pi / 60
    w2 = w1 * geom.z1 / geom.z2
    rho_d = fl.rho(pd)
    res = {}
    for name, w in (('drive', w1), ('driven', w2)):
        r = chain(GEARS[name], fl, h_um * 1e-6, w, ps, pd, **kw)
        # per driving revolution: z1 pitches of each gear pass
        f = geom.z1 / Vm / rho_d * 100      # kg per pitch -> % of Vm n (delivery volume)
        r['leak_pct'] = r['Ms'] * f
        r['in_pct'] = r['Md'] * f
        r['fill_pct'] = (fl.rho(pd) * r['V'] - r['m_open']) * f    # backflow at opening
        r['bal_pct'] = r['balance'] * f
        res[name] = r
    Vsum = GEARS['drive']['V_space'] + GEARS['driven']['V_space']
    press = geom.z1 * Vsum / Vm * (1 - fl.v(pd) / fl.v(ps)) * 100
    # clearance annulus (ra .. ra + h, over spaces AND lands) carried round the
    # bore by the gear: a gain against Vm (gear-frame accounting; with the
    # relative drag in the leak this is the casing-frame "Poiseuille - U h b/2")
    ann = 0.0
    for nm, w in (('drive', w1), ('driven', w2)):
        g = GEARS[nm]
        ann += h_um * 1e-6 * b * 2 * math.pi * g['ra'] * (w / w1)   # per driving revolution
    lay = ann / Vm * 100 * fl.v(pd) / fl.v(ps)
    leak = res['drive']['leak_pct'] + res['driven']['leak_pct']
    return dict(res=res, leak=leak, press=press, total=leak + press, layer=lay, fl=fl, pd=pd)


def closed_form(x0, dp_bar=30.0):
    pd = P_ATM + dp_bar * BAR
    vx = lambda p: (1 - x0) * math.exp(-(p - P_ATM) / K) + x0 * P_ATM / p
    v0 = lambda p: math.exp(-(p - P_ATM) / K)
    Vsum = GEARS['drive']['V_space'] + GEARS['driven']['V_space']
    return geom.z1 * Vsum / Vm * ((1 - vx(pd) / vx(P_ATM)) - (1 - v0(pd) / v0(P_ATM))) * 100


# ------------------------------------------------------------------ reports
def check():
    print(f"oil at {T_C:.0f} degC: nu = {NU_CST:.3f} cSt, rho = {RHO0:.2f} kg/m3, mu = {MU*1e3:.3f} mPa s, K = {K/1e9:.2f} GPa")
    print(f"Vm (closed form) = {Vm*1e6:.4f} cm3/rev")
    for nm, g in GEARS.items():
        pitch = 360 / g['z']
        dlt = math.degrees(g['half_tip'])
        S = (math.degrees(g['th_d'] - g['th_s']) - 2 * dlt - pitch)
        print(f"{nm:6s}: z={g['z']}, ra={g['ra']*1e3:.3f} mm, rf={g['rf']*1e3:.3f} mm, "
              f"space area {g['area']*1e6:.4f} mm2, V_space = {g['V_space']*1e9:.2f} mm3, "
              f"tip land {g['land']*1e3:.4f} mm ({2*dlt:.3f} deg), bore arc "
              f"{math.degrees(g['th_d']-g['th_s']):.1f} deg, sealed arc of a space centre {S:.2f} deg "
              f"= {S/pitch:.3f} pitches")
    Vs = GEARS['drive']['V_space'] + GEARS['driven']['V_space']
    print(f"z1 (V1+V2) / Vm = {geom.z1*Vs/Vm:.4f}")
    # independent check of the space area: z (A_space + A_tooth) = pi (ra^2 - rf^2)
    # and the displacement against the 'annulus' estimate
    for x0 in (0.0, 0.02, 0.048):
        print(f"closed-form extra loss from air, x0={x0}: {closed_form(x0):.4f} % of Vm n")
    f0 = Fluid(0.0)
    pd = P_ATM + 30 * BAR
    print(f"Phi check (x0=0): table {f0.Phi(pd):.6e} analytic {RHO0*K*(math.exp((pd-P_ATM)/K)-1):.6e}")
    print("step convergence, 30 um, x0 = 0 and 0.02 (steps per degree of gear angle):")
    for x0 in (0.0, 0.02):
        for spd in (0.5, 1, 4, 16):
            r = pump(30, x0, steps_per_deg=spd)
            print(f"  x0={x0:5.3f} spd={spd:5.1f}: leak drive {r['res']['drive']['leak_pct']:.6f} "
                  f"driven {r['res']['driven']['leak_pct']:.6f} %, total {r['total']:.6f} %, "
                  f"mass-balance residual {r['res']['drive']['bal_pct']:.2e} / {r['res']['driven']['bal_pct']:.2e} %, "
                  f"periodicity {r['res']['drive']['per']:.1e} / {r['res']['driven']['per']:.1e}")


def table(hs=(1, 5, 10, 20, 30), xs=(0.0, 0.02), extra=((30, 0.048),), **kw):
    print(f"{'tip um':>6s} {'x0':>6s} | {'leak->suction %':>28s} | {'in from deliv %':>20s} | "
          f"{'press %':>7s} {'total %':>8s} {'d(air) %':>8s} {'d leak %':>8s} | {'annul %':>7s} {'net tot':>8s} {'d(air)':>7s} | p_open drive/driven bar")
    print(f"{'':6s} {'':6s} | {'drive':>8s} {'driven':>8s} {'sum':>9s} | {'drive':>9s} {'driven':>9s} |")
    rows = []
    base = {}
    cases = [(hh, x) for hh in hs for x in xs] + list(extra)
    for hh, x in cases:
        r = pump(hh, x, **kw)
        if x == 0.0:
            base[hh] = r
        b0 = base[hh]
        d_air = r['total'] - b0['total']
        d_leak = r['leak'] - b0['leak']
        rd, rv = r['res']['drive'], r['res']['driven']
        print(f"{hh:6.0f} {x:6.3f} | {rd['leak_pct']:8.4f} {rv['leak_pct']:8.4f} {r['leak']:9.4f} | "
              f"{rd['in_pct']:9.4f} {rv['in_pct']:9.4f} | {r['press']:7.4f} {r['total']:8.4f} "
              f"{d_air:8.4f} {d_leak:8.4f} | {r['layer']:7.4f} {r['total']-r['layer']:8.4f} "
              f"{r['total']-r['layer']-(b0['total']-b0['layer']):7.4f} | "
              f"{(rd['p_open']-P_ATM)/BAR:6.2f} / {(rv['p_open']-P_ATM)/BAR:6.2f} (gauge)")
        rows.append((hh, x, r))
    print("leak: through the first sealing tip into the suction (gear frame: Poiseuille + drag of the casing"
          " relative to the tip, b h U/2, towards the suction); press: z1 (V1+V2)(1 - v(pd)/v(ps))/Vm;"
          " total = leak + press; annul: the clearance annulus carried round (a gain); net tot = total - annul"
          " (= the casing-frame convention, drag b h U/2 towards the delivery). All % of Vm n.")
    return rows


def history(h_um=30, xs=(0.0, 0.02, 0.048), every_deg=10.0):
    for nm in ('drive', 'driven'):
        print(f"pocket pressure (bar gauge) vs gear angle since sealing, {nm} gear, tip {h_um} um:")
        Hs = {}
        for x in xs:
            fl = Fluid(x)
            rpm = float(os.environ.get('RPM', '1000'))
            w = rpm * 2 * math.pi / 60 * (1 if nm == 'drive' else geom.z1 / geom.z2)
            r = chain(GEARS[nm], fl, h_um * 1e-6, w, P_ATM, P_ATM + 30 * BAR, record=True)
            Hs[x] = (r['history'], r['S'])
        S = Hs[xs[0]][1]
        print(f"{'angle deg':>9s} " + ' '.join(f"{'x0='+str(x):>9s}" for x in xs))
        n = int(math.degrees(S) // every_deg)
        angles = [i * every_deg for i in range(n + 1)] + [math.degrees(S)]
        for ang in angles:
            vals = []
            for x in xs:
                H = Hs[x][0]
                a = math.radians(ang)
                best = min(H, key=lambda t: abs(t[0] - a))
                vals.append((best[1] - P_ATM) / BAR)
            print(f"{ang:9.1f} " + ' '.join(f"{v:9.3f}" for v in vals))


if __name__ == '__main__':
    args = sys.argv[1:]
    if '--check' in args:
        check()
    elif '--history' in args:
        history()
        print()
        history(h_um=10, xs=(0.0, 0.02))
    elif '--speeds' in args:
        for rpm in (500, 1000, 4000):
            print(f"--- {rpm} rpm, 30 bar, 30 um")
            table(hs=(30,), xs=(0.0, 0.02), extra=((30, 0.048),), rpm=rpm)
    elif '--sens' in args:
        print('--- sealed arc shortened at each end by half the helix spread b tan(beta)/ra (both ends)')
        for nm, g in GEARS.items():
            print(f"  {nm}: spread {math.degrees(b*math.tan(geom.beta)/g['ra']):.2f} deg")
        # arc_cut is per gear: run the gears separately
        for x in (0.0, 0.02):
            tot = 0.0
            fl = Fluid(x)
            w1 = 1000 * 2 * math.pi / 60
            for nm, w in (('drive', w1), ('driven', w1 * geom.z1 / geom.z2)):
                g = GEARS[nm]
                cut = 0.5 * b * math.tan(geom.beta) / g['ra']
                r = chain(g, fl, 30e-6, w, P_ATM, P_ATM + 30 * BAR, arc_cut=cut)
                lp = r['Ms'] * geom.z1 / Vm / fl.rho(P_ATM + 30 * BAR) * 100
                tot += lp
                print(f"  x0={x}: {nm} J={r['J']} leak {lp:.4f} %")
            print(f"  x0={x}: leak sum {tot:.4f} %")
        for drag, lab in ((0, 'no drag term'), (-1, 'drag towards the delivery (casing-frame sign)')):
            print(f'--- {lab}')
            table(hs=(10, 30), xs=(0.0, 0.02), extra=(), drag=drag)
        print('--- pocket without the clearance layer')
        table(hs=(30,), xs=(0.0, 0.02), extra=(), layer=False)
        print('--- delivery 10 bar and 60 bar at 30 um')
        for dpb in (10, 60):
            print(f'  {dpb} bar; closed form d(air) x0=0.02: {closed_form(0.02, dpb):.4f} %')
            table(hs=(30,), xs=(0.0, 0.02), extra=(), dp_bar=dpb)
    else:
        table()
