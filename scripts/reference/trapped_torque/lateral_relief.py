"""The trapped cavity's relief by the lateral gaps over the seed campaign's
14 working conditions: the whole life's pressure-work excess (and the closed
phase's, and the peak) with both plates' films at a lateral clearance h, for
h = 10 to 35 um. Writes lateral_relief.csv, the table from which the hand
calculation's plant (tests/hand_reference, `trapped_relief`) takes what a
wider or narrower lateral gap does to the trapped volume's torque. About
7 minutes on one core.
    python lateral_relief.py [out.csv]
"""
import csv, sys, time
import trapped as T

# (delivery bar gauge, rpm, degC): the seed's Table 2 (crates/campaign/src/conditions.rs)
CONDITIONS = [(10, 1000, 60), (20, 1000, 60), (30, 1000, 60), (40, 1000, 60), (30, 500, 60),
              (30, 2000, 60), (30, 4000, 60), (10, 1000, 120), (20, 1000, 120), (30, 1000, 120),
              (40, 1000, 120), (30, 500, 120), (30, 2000, 120), (30, 4000, 120)]
HS = (10.0, 15.0, 20.0, 25.0, 30.0, 35.0)
NS = 16   # sub-slices of the helix; the relief moves by < 1e-3 N m against 128 (README)


def rows():
    for bar, rpm, temp in CONDITIONS:
        for h in HS:
            t = time.time()
            r = T.run(rpm, bar, temp, NZ=1, NS=NS, h_lat_um=h, margin=T.DEFAULT_MARGIN)
            assert abs(r['energy_residual_Nm']) < 1e-5, r['energy_residual_Nm']
            print(f"{rpm} rpm / {bar} bar / {temp} degC, h {h:.0f} um: whole life {r['excess_Nm']:.5f}, "
                  f"closed {r['exc_mid']:.5f} N m, peak {r['peak_bar_g']:.1f} bar g, leak share at the peak "
                  f"{100 * r['lat_share_peak']:.1f} % [{time.time() - t:.1f} s]", flush=True)
            yield dict(rpm=rpm, bar=bar, temp_c=temp, h_um=h, total_nm=round(r['excess_Nm'], 6),
                       closed_nm=round(r['exc_mid'], 6), peak_bar_g=round(r['peak_bar_g'], 2),
                       leak_share_at_peak=round(r['lat_share_peak'], 4))


if __name__ == '__main__':
    out = sys.argv[1] if len(sys.argv) > 1 else 'lateral_relief.csv'
    table = list(rows())
    with open(out, 'w', newline='') as f:
        w = csv.DictWriter(f, fieldnames=list(table[0]))
        w.writeheader()
        w.writerows(table)
    print(f"wrote {out}: {len(table)} rows")
