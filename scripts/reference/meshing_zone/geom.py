"""Independent transverse involute geometry of the seed pump (pure Python; numpy
is not installed on this machine). Units: mm, rad.

Frame: O1 = (0,0), O2 = (a,0). Gear 1 (driving) turns CCW, gear 2 CW; the
teeth cross the mesh moving +y, so the delivery (meshing-in) side is -y and
the suction side +y. Line of action through the pitch point P with unit
direction n = (sin aw, cos aw); contact travels along +n from A (delivery,
gear-2 tip circle) to E (suction, gear-1 tip circle). l = signed distance of
a (real or virtual) contact from P along n.
"""
import math

# ---- design: the bundled designs/seed_pump.toml (or GEARPUMP_DESIGN) ----
import os
import pathlib
import tomllib

_path = os.environ.get('GEARPUMP_DESIGN') or str(
    pathlib.Path(__file__).resolve().parents[3] / 'designs' / 'seed_pump.toml')
DESIGN = tomllib.loads(pathlib.Path(_path).read_text())
_g = DESIGN['gears']
z1, z2 = _g['z_drive'], _g['z_driven']
mn = _g['normal_module_mm']
beta = math.radians(_g['helix_angle_deg'])
an = math.radians(_g['normal_pressure_angle_deg'])
b = _g['face_width_mm']
x1, x2 = _g['profile_shift_drive'], _g['profile_shift_driven']
ra1, ra2 = _g['tip_radius_drive_mm'], _g['tip_radius_driven_mm']
_dra = float(os.environ.get('DRA_MM', '0'))  # sensitivity: tip radii reduced by this (edge break proxy)
ra1, ra2 = ra1 - _dra, ra2 - _dra
rf1, rf2 = _g['root_radius_drive_mm'], _g['root_radius_driven_mm']
jn = _g['backlash_normal_mm']  # normal backlash, made by thinning gear 1
assert _g['centre_distance_mm'] == 'auto', 'the scripts take the zero-backlash centre distance'

def inv(a):
    return math.tan(a) - a

def inv_solve(v):
    a = (3 * v) ** (1 / 3)
    for _ in range(60):
        a -= (inv(a) - v) / math.tan(a) ** 2
    return a

at = math.atan(math.tan(an) / math.cos(beta))
mt = mn / math.cos(beta)
r1, r2 = z1 * mt / 2, z2 * mt / 2
rb1, rb2 = r1 * math.cos(at), r2 * math.cos(at)
pbt = 2 * math.pi * rb1 / z1
betab = math.atan(math.tan(beta) * math.cos(at))
aw = inv_solve(inv(at) + 2 * math.tan(an) * (x1 + x2) / (z1 + z2))
a = (r1 + r2) * math.cos(at) / math.cos(aw)
rw1, rw2 = rb1 / math.cos(aw), rb2 / math.cos(aw)

# transverse tooth thickness at the reference circle, base half-angles
st1 = mt * (math.pi / 2 + 2 * x1 * math.tan(an))
st2 = mt * (math.pi / 2 + 2 * x2 * math.tan(an))
psib1_0 = st1 / (2 * r1) + inv(at)   # half angular thickness on the base circle
psib2 = st2 / (2 * r2) + inv(at)
jbt = jn / math.cos(betab)           # normal backlash -> transverse, along the line of action
psib1 = psib1_0 - jbt / (2 * rb1)    # thinned driving gear (base-arc thickness reduced by jbt)

n = (math.sin(aw), math.cos(aw))
P = (rw1, 0.0)
T1P = rb1 * math.tan(aw)       # distance T1..P
T2P = rb2 * math.tan(aw)
rho1a = math.sqrt(ra1**2 - rb1**2)
rho2a = math.sqrt(ra2**2 - rb2**2)
A = T2P - rho2a   # wait: sign fixed below
# contact at l: rho1 = T1P + l, rho2 = T2P - l
A = -(rho2a - T2P)   # rho2 = rho2a  -> l = T2P - rho2a
E = rho1a - T1P      # rho1 = rho1a
galpha = E - A
eps_a = galpha / pbt
eps_b = b * math.tan(betab) / pbt

def Q(l):
    return (P[0] + l * n[0], P[1] + l * n[1])

def centres(l):
    """Tooth-centre angles c1, c2 (each in its own gear frame) of the pair whose
    driving-flank contact is at l (virtual if l outside [A,E])."""
    rho1 = T1P + l
    rho2 = T2P - l
    th01 = -aw + rho1 / rb1
    th02 = (math.pi - aw) + rho2 / rb2
    return th01 - psib1, th02 - psib2

def half_angle(rb, psib, r):
    if r <= rb:
        return psib
    return psib - inv(math.acos(rb / r))

def tooth_outline(rb, psib, ra, rf, c, centre, npts=400, root=True):
    """Polyline of one tooth: CW flank (rf..ra), tip arc, CCW flank (ra..rf).
    Below the base circle the flank is taken radial (no fillet). Returns list of
    (x,y,tag) with tag in {'cwflank','tip','ccwflank'}."""
    rs = [max(rf, 0.0) + (ra - max(rf, 0.0)) * (i / npts) ** 0.5 for i in range(npts + 1)]
    # denser near ra: use sqrt spacing reversed
    rs = [ra - (ra - rf) * (1 - i / npts) ** 2 for i in range(npts + 1)]
    pts = []
    for r in rs:
        th = c - half_angle(rb, psib, r)
        pts.append((centre[0] + r * math.cos(th), centre[1] + r * math.sin(th), 'cwflank', r))
    h = half_angle(rb, psib, ra)
    m = 60
    for i in range(1, m):
        th = c - h + 2 * h * i / m
        pts.append((centre[0] + ra * math.cos(th), centre[1] + ra * math.sin(th), 'tip', ra))
    for r in reversed(rs):
        th = c + half_angle(rb, psib, r)
        pts.append((centre[0] + r * math.cos(th), centre[1] + r * math.sin(th), 'ccwflank', r))
    return pts

def seg_dist(p, a_, b_):
    ax, ay = a_[0], a_[1]
    bx, by = b_[0], b_[1]
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    t = 0.0 if L2 == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / L2))
    qx, qy = ax + t * dx, ay + t * dy
    return math.hypot(p[0] - qx, p[1] - qy)

def min_dist(pa, pb):
    """min distance between polylines pa and pb (points of each to segments of the other)."""
    best = (1e9, None, None)
    for src, dst in ((pa, pb), (pb, pa)):
        for p in src:
            for i in range(len(dst) - 1):
                d = seg_dist(p, dst[i], dst[i + 1])
                if d < best[0]:
                    best = (d, p, dst[i])
    return best

def inside_tooth(pt, rb, psib, ra, c, centre):
    x, y = pt[0] - centre[0], pt[1] - centre[1]
    r = math.hypot(x, y)
    if r > ra:
        return False
    th = math.atan2(y, x) - c
    th = (th + math.pi) % (2 * math.pi) - math.pi
    return abs(th) <= half_angle(rb, psib, r)

if __name__ == '__main__':
    print(f"alpha_t = {math.degrees(at):.4f} deg, m_t = {mt:.5f} mm, r1 = {r1:.4f}, r2 = {r2:.4f}")
    print(f"rb1 = {rb1:.4f}, rb2 = {rb2:.4f}, pbt = {pbt:.4f} mm, beta_b = {math.degrees(betab):.4f} deg")
    print(f"alpha_w = {math.degrees(aw):.4f} deg, a = {a:.4f} mm, rw1 = {rw1:.4f}, rw2 = {rw2:.4f}")
    print(f"transverse tooth thickness at r: s1 = {st1:.4f} (before thinning), s2 = {st2:.4f}; jbt = {jbt:.4f}")
    print(f"T1T2 = {T1P+T2P:.4f}, rho1a = {rho1a:.4f}, rho2a = {rho2a:.4f}")
    print(f"path: A = {A:.4f} (delivery end), E = {E:.4f} (suction end), g_alpha = {galpha:.4f} mm")
    print(f"  rho1 at A = {T1P+A:.4f}, rho2 at E = {T2P-E:.4f} (must be > 0: no interference)")
    print(f"eps_alpha = {eps_a:.4f}, eps_beta = {eps_b:.4f}, total {eps_a+eps_b:.4f}")
    print(f"b tan(beta_b) = {b*math.tan(betab):.4f} mm of line of action across the face")
    # zero-backlash check: gear-1 unthinned opposite flank vs gear 2 along the other line of action
    # sum of base pitches: psib1_0*rb1*2 + psib2*rb2*2 ... check via working circle thickness
    sw1 = 2 * rw1 * (psib1_0 - inv(aw)); sw2 = 2 * rw2 * (psib2 - inv(aw))
    pw = 2 * math.pi * rw1 / z1
    print(f"zero-backlash check: sw1+sw2 = {sw1+sw2:.6f}, pw = {pw:.6f}")
    ha1 = half_angle(rb1, psib1, ra1); ha2 = half_angle(rb2, psib2, ra2)
    print(f"tip lands: gear1 {2*ha1*ra1:.4f} mm (thinned), gear2 {2*ha2*ra2:.4f} mm")
    print(f"root clearance: a - ra1 - rf2 = {a-ra1-rf2:.4f}, a - ra2 - rf1 = {a-ra2-rf1:.4f}")
