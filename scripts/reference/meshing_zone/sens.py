"""Convergence and sensitivity of the deficit (corner cut model)."""
import kin3d
from kin3d import *
# 1. per-section closed form reproduces Vm n (mean of (1/2) Br(l*) over the period and face)
NT, NZ = 200, 200
s = 0.0
for it in range(NT):
    L0 = A + pbt * (it + 0.5) / NT
    for i in range(NZ):
        z = (i + 0.5) * b / NZ
        ls = [L0 + j * pbt + z * tb for j in range(-3, 4)]
        real = [l for l in ls if A <= l <= E]
        s += 0.5 * max(Br(l) for l in real) * (b / NZ) / NT
print(f"per-section closed form mean / Vrad = {s / Vrad:.6f}")
# 2. resolution
for NT, NZ in ((100, 200), (200, 400), (400, 800)):
    d, ph = mean_deficit('corner', 'cond', NT, NZ)
    print(f"corner/cond NT={NT} NZ={NZ}: {100*d:.4f} %")
# 3. laminar split with a constant laminar length (h^3 only)
from leak import interp
def cond_h3(tab, Dmax, n=200):
    if Dmax <= 0: return 0.0
    return sum(interp(tab, Dmax*(i+0.5)/n, 1)**3 for i in range(n)) * Dmax / n
kin3d.cond_integral = cond_h3
d, ph = mean_deficit('corner', 'cond', 200, 400)
print(f"corner, split by int h^3 (constant Leff): {100*d:.4f} %")
