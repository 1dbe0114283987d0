"""Tables of the gap past the ends of the path of contact (h_min and the
laminar length Leff = h^3 int ds/h^3), from ../meshing_zone/gaps.py, over
Delta = 0 .. 4.5 mm past each end (beyond about 2.5 mm the gap is a wide opening
and its laminar length is held); cached in gaptab.csv next to this script."""
import math, os, sys
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'meshing_zone'))
from geom import A, E
from gaps import gap_at, profile_integral

def build(N=52, Dmax=4.5):
    rows = []
    for i in range(N):
        D = Dmax * (i / (N - 1)) ** 1.5
        row = [D]
        for end in ('d', 's'):
            l = A - D if end == 'd' else E + D
            d, p, a1, a2 = gap_at(l, R=5.0)
            Leff = 0.0
            if d > 2e-4:
                try:
                    I3, _, _ = profile_integral(d, p, a1, a2)
                    Leff = I3 * d ** 3
                except ValueError:       # far past the end: keep the last laminar length
                    Leff = rows[-1][2 if end == 'd' else 4] if rows else 0.0
            row += [d, Leff]
        rows.append(row)
        print(' '.join(f'{v:.5f}' for v in row), flush=True)
    return rows

if __name__ == '__main__':
    rows = build()
    # beyond the search radius (no outline points near the virtual contact) the gap is wide:
    # extrapolate h ~ Delta^2 from the last good row
    for i, r in enumerate(rows):
        for k in (1, 3):
            if r[k] > 10.0:
                r[k] = rows[i - 1][k] * (r[0] / rows[i - 1][0]) ** 2
    with open(os.path.join(HERE, os.environ.get('GAPTAB', 'gaptab.csv')), 'w') as f:
        f.write('Delta_mm,h_d_mm,Leff_d_mm,h_s_mm,Leff_s_mm\n')
        for r in rows:
            f.write(','.join(f'{v:.6g}' for v in r) + '\n')
