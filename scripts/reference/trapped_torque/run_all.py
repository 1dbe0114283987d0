"""The table of the README: the meshing-zone cavity's pressure-work excess at
the four conditions, (a) lumped over the face width and (b) resolved into
slices joined by the laminar channel along the tooth space (with and without
the axial flow's inertia), next to the model's figures; plus the spur pair
of the same transverse section for context. About 2 minutes.
    python run_all.py
"""
import sys, time
import trapped as T

MARGIN = T.DEFAULT_MARGIN
MODEL = {  # meshing zone, outlet-opening, inlet-opening, total hydraulic excess, trapped peak (bar g)
    (1000, 30, 60): (0.0205, 0.0077, 0.0079, -0.017, 48.6),
    (2000, 30, 60): (0.0815, 0.0274, 0.0277, 0.083, None),
    (4000, 30, 60): (0.2848, 0.1076, 0.1003, 0.440, 150.0),
    (4000, 10, 120): (0.2602, 0.1033, 0.0966, 0.442, None),
}

if __name__ == '__main__':
    t0 = time.time()
    rows = []
    for c in T.CONDS:
        ra = T.run(*c, NZ=1, NS=128, margin=MARGIN)
        rb = T.run(*c, NZ=16, axial='laminar', margin=MARGIN)
        ri = T.run(*c, NZ=16, axial='laminar', inertia=True, margin=MARGIN)
        rs = T.run(*c, helix=False, margin=(MARGIN[0] + 1.3, MARGIN[1] + 1.3))   # the same start and end as the helical runs
        rows.append((c, ra, rb, ri, rs))
        for name, r in (('(a) lumped', ra), ('(b) 16 slices, laminar channel', rb),
                        ('(b) + inertia of the axial flow', ri), ('spur section (no helix)', rs)):
            print(f"{c} {name:34s} {T.line(r)}", flush=True)
    print()
    print('N m on the driving shaft, mean over a mesh period of sum (p - p_ideal)(-dV/dtheta); peak in bar gauge')
    print('| rpm / bar / degC | model: meshing zone | model: + outlet + inlet spaces | (a) lumped: total | (a) phases out / closed / in '
          '| (b) 16 slices: total, closed | (b) + inertia: total, closed | peak model | peak (a) | peak (b)+inertia | spur section: total, closed, peak |')
    print('|---|---|---|---|---|---|---|---|---|---|---|')
    for c, ra, rb, ri, rs in rows:
        m = MODEL[c]
        pk = f"{m[4]:.0f}" if m[4] else '-'
        print(f"| {c[0]} / {c[1]} / {c[2]} | {m[0]:.4f} | {m[0]+m[1]+m[2]:.4f} | {ra['excess_Nm']:.4f} | "
              f"{ra['exc_out']:.4f} / {ra['exc_mid']:.4f} / {ra['exc_in']:.4f} | {rb['excess_Nm']:.4f}, {rb['exc_mid']:.4f} | "
              f"{ri['excess_Nm']:.4f}, {ri['exc_mid']:.4f} | "
              f"{pk} | {ra['peak_bar_g']:.0f} | {ri['peak_bar_g']:.0f} | {rs['excess_Nm']:.3f}, {rs['exc_mid']:.3f}, {rs['peak_bar_g']:.0f} |")
    print(f"\n[{time.time()-t0:.0f} s]")
