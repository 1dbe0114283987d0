"""Table of the cavity's section quantities against the newer contact's
position L along the line of action, cached as CSV next to this script.
    python sectab.py          # the cavity cut at the throats (default, sectab_cut.csv, ~10 min)
    CUT=loa python sectab.py  # split by the LOA only (sectab.csv, ~3 min; sensitivity)
L = -7.2 .. 0.2 mm, step 0.02 mm (SECTAB_L0, SECTAB_L1, SECTAB_DL; SECTAB_Y a wider
window half-height, mm; merge.py joins the pieces); RASTER_MM (0.01) the cell; GROOVE_BAND_MM the
planform band of the grooves along the line of centres (design: 6 mm).
"""
import os, sys, time
import numpy as np
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import tvgeom as g

def build(L0=-7.2, L1=0.2, dL=0.02, h=0.01, cut=True):
    Ls = np.arange(L0, L1 + 1e-9, dL)
    keys = ['L', 'A1', 'A2', 'P1', 'P2', 'oD', 'oS', 'ymin', 'ymax']
    rows = []
    for L in Ls:
        s = g.section_cut(float(L), h=h) if cut else g.section(float(L), h=h)
        rows.append([s[k] for k in keys])
    return keys, np.array(rows)

if __name__ == '__main__':
    h = float(os.environ.get('RASTER_MM', '0.01'))
    cut = os.environ.get('CUT', 'throat') != 'loa'
    L0 = float(os.environ.get('SECTAB_L0', '-7.2')); L1 = float(os.environ.get('SECTAB_L1', '0.2'))
    dL = float(os.environ.get('SECTAB_DL', '0.02'))
    if 'SECTAB_X0' in os.environ:
        g.XW = (float(os.environ['SECTAB_X0']), float(os.environ.get('SECTAB_X1', g.XW[1])))
    if 'SECTAB_Y' in os.environ:        # wider window for sections far from the pitch point
        g.YW = (-float(os.environ['SECTAB_Y']), float(os.environ['SECTAB_Y']))
    t = time.time()
    keys, arr = build(L0=L0, L1=L1, dL=dL, h=h, cut=cut)
    out = os.path.join(HERE, os.environ.get('SECTAB', 'sectab_cut.csv' if cut else 'sectab.csv'))
    np.savetxt(out, arr, delimiter=',', header=','.join(keys), comments='')
    print(f'{len(arr)} sections in {time.time()-t:.0f} s -> {out}')
