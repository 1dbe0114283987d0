"""The trapped cavity's pressure work with a piezoviscous oil over the seed
campaign's 14 working conditions, both plates' films at the design's 15 um:
the whole life's excess (and the closed phase's, and the peak) for Barus
coefficients alpha = 0 to 1.25e-7 1/Pa, with the viscosity rising with the
local pressure in the lateral films only (`lat_nm`), and in the lateral films
and the throats' laminar part (`all_nm`). Writes barus_relief.csv, from which
the hand calculation's plant of a piezoviscous oil (tests/hand_reference,
`trapped_barus`) takes what the oil does to the trapped volume's torque.
About 10 minutes on one core; `--part i/n` runs every n-th condition from the
i-th (for two cores) and `merge` joins the parts.
    python barus_relief.py [--part i/n] [out.csv]
    python barus_relief.py merge out.csv part1.csv part2.csv ...
"""
import csv, sys, time
import trapped as T
from lateral_relief import CONDITIONS, NS

H_UM = 15.0
ALPHAS = (0.0, 2.5e-8, 5e-8, 7.5e-8, 1e-7, 1.25e-7)


def one(rpm, bar, temp, lat_alpha, thr_alpha):
    r = T.run(rpm, bar, temp, NZ=1, NS=NS, h_lat_um=H_UM, margin=T.DEFAULT_MARGIN,
              lat_alpha=lat_alpha, thr_alpha=thr_alpha)
    assert abs(r['energy_residual_Nm']) < 1e-5, r['energy_residual_Nm']
    return r


def rows(conditions):
    for bar, rpm, temp in conditions:
        for alpha in ALPHAS:
            t = time.time()
            lat = one(rpm, bar, temp, alpha, 0.0)
            both = one(rpm, bar, temp, alpha, alpha) if alpha > 0 else lat
            print(f"{rpm} rpm / {bar} bar / {temp} degC, alpha {alpha:.3g}: whole life, lateral films "
                  f"{lat['excess_Nm']:.5f}, films and throats {both['excess_Nm']:.5f} N m; peak "
                  f"{lat['peak_bar_g']:.1f} / {both['peak_bar_g']:.1f} bar g [{time.time() - t:.1f} s]", flush=True)
            yield dict(rpm=rpm, bar=bar, temp_c=temp, h_um=H_UM, alpha_per_pa=alpha,
                       lat_nm=round(lat['excess_Nm'], 6), all_nm=round(both['excess_Nm'], 6),
                       lat_closed_nm=round(lat['exc_mid'], 6), all_closed_nm=round(both['exc_mid'], 6),
                       lat_peak_bar_g=round(lat['peak_bar_g'], 2), all_peak_bar_g=round(both['peak_bar_g'], 2))


def write(out, table):
    with open(out, 'w', newline='') as f:
        w = csv.DictWriter(f, fieldnames=list(table[0]))
        w.writeheader()
        w.writerows(table)
    print(f"wrote {out}: {len(table)} rows")


def key(row):
    return CONDITIONS.index((int(row['bar']), int(row['rpm']), int(row['temp_c']))), float(row['alpha_per_pa'])


if __name__ == '__main__':
    args = sys.argv[1:]
    if args and args[0] == 'merge':
        table = []
        for part in args[2:]:
            with open(part, newline='') as f:
                table += list(csv.DictReader(f))
        write(args[1], sorted(table, key=key))
        sys.exit(0)
    conditions = CONDITIONS
    if args and args[0] == '--part':
        i, n = (int(x) for x in args[1].split('/'))
        conditions = CONDITIONS[i - 1::n]
        args = args[2:]
    write(args[0] if args else 'barus_relief.csv', list(rows(conditions)))
