"""Trace of the cavity with both ends open (older line at l = Lo + zeta tb)."""
import sys
from kin3d import *
model = sys.argv[1] if len(sys.argv) > 1 else 'corner'
print(f"both-open phase: Lo in ({E - b*tb:.4f}, {A + pbt:.4f}); Vrad = {Vrad:.2f} mm^3/rad")
print(" Lo      Dd(0)  Ds(b)   s_d(cond)  R/Vrad%   sumT    sumOD    sumOS   PSshare  deficit(cond)  [all /Vrad %]")
N = 20
for i in range(N):
    Lo = (E - b*tb) + (A + pbt - (E - b*tb)) * (i + 0.5) / N
    d, info = cavity(Lo, model, 'cond', 400)
    openD, openS, sd, R, sT, sTp, sTn, sOD, sOS, ps = info
    f = 100 / Vrad
    print(f"{Lo:7.4f} {A-(Lo-pbt):6.3f} {Lo+b*tb-E:6.3f}  {sd:8.5f}  {R*f:8.3f} {sT*f:8.3f} {sOD*f:8.3f} {sOS*f:8.3f} {ps*f:8.3f}  {d*f:8.3f}")
