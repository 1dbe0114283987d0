"""Join section tables (sorted by L, later files win on equal L):
    python merge.py out.csv in1.csv in2.csv ..."""
import sys
import numpy as np
rows = {}
hdr = None
for f in sys.argv[2:]:
    with open(f) as fh:
        hdr = fh.readline().strip()
    for r in np.atleast_2d(np.genfromtxt(f, delimiter=',', skip_header=1)):
        rows[round(float(r[0]), 6)] = r
arr = np.array([rows[k] for k in sorted(rows)])
np.savetxt(sys.argv[1], arr, delimiter=',', header=hdr, comments='')
print(len(arr), 'rows ->', sys.argv[1])
