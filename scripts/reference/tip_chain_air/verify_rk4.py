"""Cross-check of tipchain.py's implicit integrator (TR-BDF2 + Newton) with a
separate, plain explicit RK4 on the pocket masses (small steps, well inside
the stability limit), driving gear only. Pure Python; slow (~1 min).
python3 scripts/reference/tip_chain_air/verify_rk4.py
"""
import math
import tipchain as T

def run(h, x0, rpm=1000.0, dp_bar=30.0, spd=60, pitches=None):
    g = T.GEARS['drive']
    fl = T.Fluid(x0)
    ps, pd = T.P_ATM, T.P_ATM + dp_bar * T.BAR
    w = rpm * 2 * math.pi / 60
    z = g['z']; pitch = 2 * math.pi / z; d = g['half_tip']
    S = (g['th_d'] - d - pitch / 2) - (g['th_s'] + d + pitch / 2)
    V = g['V_space'] + h * T.b * g['ra'] * (pitch - 2 * d)
    G = T.b * h**3 / (12 * T.MU * g['land'])
    Cu = T.b * h * w * g['ra'] / 2

    def p_of_m(m, pguess):
        # invert rho(p) V = m by Newton (mass is the state here, unlike tipchain.py)
        p = pguess
        for _ in range(50):
            f = fl.rho(p) * V - m
            p -= f / (fl.drho_dp(p) * V)
            if abs(f) < 1e-16:
                break
        return p

    def flow(pu, pn):
        fdn, fup = fl.Phi(pn), fl.Phi(pu)
        rb = (fdn - fup) / (pn - pu) if abs(pn - pu) > 1 else fl.rho(0.5 * (pn + pu))
        return G * (fdn - fup) + rb * Cu

    def deriv(ms, ps_guess):
        pr = [p_of_m(m, pg) for m, pg in zip(ms, ps_guess)]
        full = [ps] + pr + [pd]
        q = [flow(full[i], full[i + 1]) for i in range(len(full) - 1)]
        return [q[i + 1] - q[i] for i in range(len(ms))], q[0], q[-1], pr

    # pockets: list of (age, mass); time marching in gear angle
    dth = math.radians(1.0 / spd)
    dt = dth / w
    nsteps_pitch = int(round(pitch / dth))
    dth = pitch / nsteps_pitch; dt = dth / w
    ages = []; ms = []; pg = []
    J = int(S // pitch)
    npit = pitches or 4 * (J + 1) + 2
    Ms = Md = 0.0
    for k in range(npit):
        ages.insert(0, 0.0); ms.insert(0, fl.rho(ps) * V); pg.insert(0, ps)
        if k == npit - 1:
            Ms = Md = 0.0
        for st in range(nsteps_pitch):
            k1, a1, b1, pg = deriv(ms, pg)
            k2, a2, b2, _ = deriv([m + 0.5 * dt * x for m, x in zip(ms, k1)], pg)
            k3, a3, b3, _ = deriv([m + 0.5 * dt * x for m, x in zip(ms, k2)], pg)
            k4, a4, b4, _ = deriv([m + dt * x for m, x in zip(ms, k3)], pg)
            ms = [m + dt / 6 * (x1 + 2 * x2 + 2 * x3 + x4) for m, x1, x2, x3, x4 in zip(ms, k1, k2, k3, k4)]
            Ms += dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
            Md += dt / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
            ages = [a + dth for a in ages]
            if ages[-1] > S + 1e-12:       # opens to the delivery (event resolved to one step)
                ages.pop(); ms.pop(); pg.pop()
    f = z / T.Vm / fl.rho(pd) * 100
    return Ms * f, Md * f

if __name__ == '__main__':
    for h, x0, spd in ((10e-6, 0.0, 20), (10e-6, 0.02, 20), (30e-6, 0.0, 60), (30e-6, 0.02, 60)):
        ls, ld = run(h, x0, spd=spd)
        print(f"RK4 explicit, drive gear, h = {h*1e6:.0f} um, x0 = {x0}: leak to suction {ls:.4f} %, "
              f"in from delivery {ld:.4f} % of Vm n  ({spd} steps/deg)")
