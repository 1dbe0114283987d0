"""The second question: the spaces' openings through the bore.

 * Where the port edges are (casing.*_port_edge_*_deg, from the line of
   centres) against the lens of the two tip circles: whether a space still
   changes volume when its tip passes the port edge.
 * The compression (back-)flow through that opening: a volumetric effect,
   no shaft pressure work (the space's volume is constant there).
 * What the pressure work of the outlet / inlet-opening spaces then is: the
   discharge of the meshing spaces through their closing mouth (the cavity
   model's open phases, trapped.py), as a mean pressure over the displaced
   flow, next to the model's figures.
    python bore.py      (about 1 minute)
"""
import math
import trapped as T
from oil import Oil

g = T.g
D = g.DESIGN['casing']

if __name__ == '__main__':
    phi1, phi2 = math.degrees(T.PHI1), math.degrees(T.PHI2)
    p1, p2 = 360 / g.z1, 360 / g.z2
    print(f"lens of the tip circles: +-{phi1:.2f} deg on gear 1 (pitch {p1:.2f} deg), +-{phi2:.2f} deg on gear 2 (pitch {p2:.2f} deg)")
    for gear, edge, phi, p in ((1, D['delivery_port_edge_drive_deg'], phi1, p1), (2, D['delivery_port_edge_driven_deg'], phi2, p2)):
        # a space's leading tip passes the delivery edge; its trailing tip follows one pitch later
        gap = abs(edge) - phi
        print(f"gear {gear}: delivery edge {edge:+.1f} deg; the leading tip reaches the lens {gap:.1f} deg after it passes the edge, "
              f"the trailing tip passes the edge {p:.1f} deg after the leading one -> "
              + ("the space is open over its whole arc before the mating gear enters it" if p < gap else
                 f"the mating gear enters {p - gap:.1f} deg before the trailing tip clears the edge, "
                 f"while {gap:.1f} deg of arc ({math.radians(gap) * (g.ra1 if gear == 1 else g.ra2):.1f} mm x {g.b:.0f} mm) are open"))
    for gear, edge, phi in ((1, D['suction_port_edge_drive_deg'], phi1), (2, D['suction_port_edge_driven_deg'], phi2)):
        print(f"gear {gear}: suction edge {edge:+.1f} deg, {edge - phi:.1f} deg beyond the lens: a space leaving the mesh is wide open "
              f"to the inlet before it reaches the bore")
    As1, As2 = 22.951, 22.657     # tooth-space areas, checks.py
    oil = Oil(60)
    for dp in (10, 30):
        dv = (As1 * g.z1 + As2 * g.z2 * g.z1 / g.z2) * g.b * dp * 1e5 / oil.B   # mm^3 per driving revolution
        print(f"compression flow into the spaces as they open to the outlet (from suction pressure, at most): "
              f"{dv:.1f} mm^3/rev = {100 * dv / 14604.2:.3f} % of Vm at {dp} bar -- a volumetric effect; the spaces' volume "
              f"is constant there, so sum (p - p_ideal)(-dV) gets nothing from it")
    print()
    print('pressure work of the discharge through the closing mouth (cavity model, open phases), as the mean '
          'pressure over the displaced flow: excess / (Vm / 2 pi)')
    Vrad = 14.6042e-6 / (2 * math.pi)
    model = {(1000, 30, 60): (0.0077, 0.0079), (2000, 30, 60): (0.0274, 0.0277),
             (4000, 30, 60): (0.1076, 0.1003), (4000, 10, 120): (0.1033, 0.0966)}
    print('| rpm / bar / degC | model outlet spaces | this: outlet phase (window 0.3 / 1.5 / 2.7 mm) | model inlet spaces | this: inlet phase (window 1.5 / 2.7 mm) | mean overpressure of the outlet phase, bar |')
    print('|---|---|---|---|---|---|')
    for c in T.CONDS:
        ro = [T.run(*c, margin=(m, 2.7)) for m in (0.3, 1.5, 2.7)]
        ri = T.run(*c, margin=(1.5, 1.5))
        mo, mi = model[c]
        print(f"| {c[0]} / {c[1]} / {c[2]} | {mo:.4f} | {ro[0]['exc_out']:.4f} / {ro[1]['exc_out']:.4f} / {ro[2]['exc_out']:.4f} | "
              f"{mi:.4f} | {ri['exc_in']:.4f} / {ro[1]['exc_in']:.4f} | {ro[1]['exc_out'] / Vrad / 1e5:.2f} |", flush=True)
