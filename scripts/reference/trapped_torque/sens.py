"""Sensitivities and convergence of the cavity model (lumped unless stated),
at 1000 and 4000 rpm / 30 bar / 60 degC. About 3 minutes.
    python sens.py [quick]
"""
import sys, time
import trapped as T

CASES = [
    ('base (a) lumped', {}),
    ('steps x2', dict(steps=2 * int(4000 * (1 + 2.1 / 2)))),
    ('(a) with 16 sub-slices for the openings instead of 128 (the model: 16 slices)', dict(NS=16)),
    ('(b) 8 slices', dict(NZ=8, axial='laminar')),
    ('(b) 32 slices', dict(NZ=32, axial='laminar')),
    ('(b) 16 slices, f Re = 96 (slit)', dict(NZ=16, axial='laminar', C=96.0)),
    ('(b) 16 slices, channel 10x less conductive (f Re = 640)', dict(NZ=16, axial='laminar', C=640.0)),
    ('throats: orifice only (no laminar term)', dict(throat_law='orifice')),
    ('Cd of the throats 1.0 (design 0.6)', dict(cd_mesh=1.0)),
    ('Cd of the grooves 1.0 (design 0.6)', dict(cd_groove=1.0)),
    ('groove band unbounded along the line of centres (design 6 mm)', dict(table='sectab_cut_wideband.csv')),
    ('tips broken by 0.05 mm (path of contact shortened)', dict(dra=0.05, gaptab='gaptab_dra05.csv')),
    ('grooves NOT offset by the helix (each plate at the nominal edges)', dict(groove='nominal')),
    ('no grooves', dict(grooves=False)),
    ('window: delivery side 0.3 mm (base 1.5)', dict(margin=(0.3, 2.7))),
    ('window: delivery side 2.7 mm (base 1.5)', dict(margin=(2.7, 2.7))),
    ('window: suction side 1.5 mm (base 2.7)', dict(margin=(1.5, 1.5))),
    ('inlet at 0.8 bar abs', dict(p_in_bar_abs=0.8)),
]

if __name__ == '__main__':
    t0 = time.time()
    for c in [(1000, 30, 60), (4000, 30, 60)]:
        for name, kw in CASES:
            r = T.run(*c, **kw)
            leak = -(r['port'] - r['ideal']) / (c[1] * 1e5) * 2 * 3.141592653589793 * 1e6   # cm^3/rev short-circuited
            print(f"{c} {name:66s} {r['excess_Nm']:+.4f} N m (closed phase {r['exc_mid']:+.4f}), "
                  f"peak {r['peak_bar_g']:6.1f} bar g; delivery->suction through the cavity ~{leak:+.3f} cm^3/rev", flush=True)
    print(f'[{time.time()-t0:.0f} s]')
