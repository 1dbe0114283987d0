//! Look-up tables of the pockets (tooth spaces) over a mesh period, built from
//! the tooth profiles themselves (seed Sec. 2.3).
//!
//! ## How a pocket is defined
//! In a transverse section the fluid inside the two bores (tip circles) is
//! split between the two gears by the **line of action** inside the lens
//! where the bores overlap: a point of the lens on the driving gear's side of
//! the line belongs to the driving gear, the rest to the driven gear. Because
//! every contact point lies on the line of action and the line is normal to
//! both flanks there, each contact lies on a pocket boundary: a contact seals
//! one pocket from the next, exactly as in the gear pair. Pocket `m` of a gear
//! is then the fluid of its tooth space `m` in its own region, i.e. the space
//! polygon (flanks, root and tip circle) minus the mating gear's solid minus
//! the mating gear's region. Areas come from polygon clipping (`geo`).
//!
//! The boundary between the two gears' regions (a curve from the delivery-side
//! cusp along the driven bore, the line of action and the driving bore to the
//! suction-side cusp) is sampled; its fluid intervals are the meshing-zone
//! connections between a driving-gear pocket and a driven-gear pocket
//! (backlash side, and the narrowing gap at a contact on the contact side).
//!
//! Helical gears: the face width is cut into slices, each a spur section at
//! the driving-angle shift `z tan(beta) / r1`; quantities are summed over the
//! slices (seed Sec. 2.3). Spur = one slice.

use super::pair::{Pair, P2};
use geo::{Area, BooleanOps, Coord, LineString, MultiPolygon, Polygon};
use std::f64::consts::PI;

const MM: f64 = 1.0e3; // polygons are built in millimetres for the clipper's robustness
const NF: usize = 24; // points per flank
const NA: usize = 6; // points per root/tip arc segment

/// Quantities of one pocket in one spur section, per unit face width.
#[derive(Debug, Clone, Copy, Default)]
pub struct SectionSample {
    /// Pocket area, m^2.
    pub area: f64,
    /// Perimeter of the pocket's section (every ring of its fluid polygons:
    /// flanks, root, tip circle and, in the meshing zone, the line of action
    /// between the gears' regions), m: the wetted perimeter of the axial
    /// channel (`hydraulics::steps`).
    pub perimeter: f64,
    /// Force on the driving / driven gear per unit pressure, [Fx, Fy] (m), and
    /// torque about each gear's centre (m^2, counter-clockwise positive).
    pub force: [[f64; 2]; 2],
    pub torque: [f64; 2],
    /// Planform overlap with the delivery and the suction relief groove, m^2 (per face).
    pub groove: [f64; 2],
}

/// A meshing-zone connection: driving-gear space, driven-gear space (body
/// indices at the sample's angle) and the passage length, m.
#[derive(Debug, Clone, Copy)]
pub struct Interface {
    pub space: [usize; 2],
    pub length: f64,
}

/// Section tables of both gears as functions of the pocket's local angle phi,
/// on a uniform grid over the mesh neighbourhood.
#[derive(Debug, Clone)]
pub struct SectionTables {
    pub phi0: [f64; 2],
    pub dphi: [f64; 2],
    pub samples: [Vec<SectionSample>; 2],
    /// Value far from the mesh (full space, no mating gear).
    pub free: [SectionSample; 2],
    /// Interfaces over one driving-gear pitch, theta = i * dtheta_if.
    pub dtheta_if: f64,
    pub interfaces: Vec<Vec<Interface>>,
}

fn ring(points: impl Iterator<Item = P2>) -> LineString<f64> {
    let mut v: Vec<Coord<f64>> = points
        .map(|p| Coord {
            x: p[0] * MM,
            y: p[1] * MM,
        })
        .collect();
    if let Some(&f) = v.first() {
        v.push(f);
    }
    LineString::new(v)
}

fn circle(c: P2, r: f64, n: usize) -> Vec<P2> {
    (0..n)
        .map(|i| {
            let t = 2.0 * PI * i as f64 / n as f64;
            [c[0] + r * t.cos(), c[1] + r * t.sin()]
        })
        .collect()
}

/// Clips a convex polygon (list of points) by the half-plane n.(x - p) >= 0.
fn clip_half_plane(poly: &[P2], p: P2, n: P2) -> Vec<P2> {
    let side = |x: &P2| n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]);
    let mut out = Vec::new();
    for i in 0..poly.len() {
        let a = poly[i];
        let b = poly[(i + 1) % poly.len()];
        let (sa, sb) = (side(&a), side(&b));
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa >= 0.0) != (sb >= 0.0) {
            let t = sa / (sa - sb);
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

impl Pair {
    /// Global outline polygon of gear k's solid at driving angle theta.
    pub fn solid_polygon(&self, k: usize, theta: f64) -> Polygon<f64> {
        let g = &self.gears[k];
        let off = self.body_offset(k, theta);
        let pts = g.outline_polar(NF, NA);
        let ext = ring(
            pts.iter()
                .map(|&(rho, a)| self.local_to_global(k, rho, off + a)),
        );
        Polygon::new(ext, vec![])
    }

    /// The other gear's region inside this gear's bore: disk(other) on the
    /// other's side of the line of action.
    fn foreign_region(&self, k: usize) -> Polygon<f64> {
        let other = 1 - k;
        let c = circle(self.centre(other), self.gears[other].ra, 2880);
        let n = self.loa_normal();
        let n = if other == 1 { n } else { [-n[0], -n[1]] };
        let clipped = clip_half_plane(&c, self.pitch_point(), n);
        Polygon::new(ring(clipped.into_iter()), vec![])
    }

    /// Driving angle at which space 0 of gear k is centred on local angle phi.
    pub fn theta_for_space(&self, k: usize, phi: f64) -> f64 {
        let z = self.gears[k].z as f64;
        if k == 0 {
            phi - PI / z
        } else {
            // space m centre: theta z1/z2 - lag + 2 pi (m + 1)/z2
            (phi - 2.0 * PI / z + self.lag2) / self.ratio()
        }
    }

    /// Local angle of the centre of gear k's body space m at driving angle theta.
    pub fn space_centre(&self, k: usize, m: usize, theta: f64) -> f64 {
        let g = &self.gears[k];
        self.body_offset(k, theta) + (m as f64 + 0.5) * g.pitch_angle()
    }

    /// Groove rectangles (delivery, suction) in global coordinates.
    fn grooves(&self, dg: f64, sg: f64, width: f64) -> [Polygon<f64>; 2] {
        let p = self.pitch_point();
        let far = self.cusp()[1] + 2.0e-3;
        let rect = |y0: f64, y1: f64| {
            Polygon::new(
                ring(
                    [
                        [p[0] - width / 2.0, y0],
                        [p[0] + width / 2.0, y0],
                        [p[0] + width / 2.0, y1],
                        [p[0] - width / 2.0, y1],
                    ]
                    .into_iter(),
                ),
                vec![],
            )
        };
        [rect(-far, -dg), rect(sg, far)]
    }

    /// One section sample of gear k's pocket centred at local angle phi.
    pub fn section_sample(
        &self,
        k: usize,
        phi: f64,
        grooves: &[Polygon<f64>; 2],
    ) -> (SectionSample, MultiPolygon<f64>) {
        let theta = self.theta_for_space(k, phi);
        let g = &self.gears[k];
        let off = self.body_offset(k, theta);
        let space = Polygon::new(
            ring(
                g.space_polar(0, NF, NA)
                    .into_iter()
                    .map(|(rho, a)| self.local_to_global(k, rho, off + a)),
            ),
            vec![],
        );
        let other = 1 - k;
        let solid = self.solid_polygon(other, theta);
        let fluid = space.difference(&solid).difference(&self.foreign_region(k));
        let mut s = SectionSample {
            area: fluid.unsigned_area() / (MM * MM),
            perimeter: fluid
                .iter()
                .flat_map(|poly| std::iter::once(poly.exterior()).chain(poly.interiors()))
                .map(|ring| {
                    ring.lines()
                        .map(|l| (l.end.x - l.start.x).hypot(l.end.y - l.start.y))
                        .sum::<f64>()
                })
                .sum::<f64>()
                / MM,
            ..Default::default()
        };
        for (gi, groove) in grooves.iter().enumerate() {
            s.groove[gi] = fluid.intersection(groove).unsigned_area() / (MM * MM);
        }
        // pressure loads: fluid pushes on each solid across the edges it shares with it
        for poly in fluid.iter() {
            let mut rings: Vec<(Vec<P2>, bool)> = vec![(to_pts(poly.exterior()), true)];
            for h in poly.interiors() {
                rings.push((to_pts(h), false));
            }
            for (pts, exterior) in rings {
                let ccw = signed_area(&pts) > 0.0;
                // fluid must be on the left of every edge
                let forward = ccw == exterior;
                let n = pts.len();
                for i in 0..n {
                    let (a, b) = if forward {
                        (pts[i], pts[(i + 1) % n])
                    } else {
                        (pts[(i + 1) % n], pts[i])
                    };
                    let d = [b[0] - a[0], b[1] - a[1]];
                    let len = d[0].hypot(d[1]);
                    if len < 1e-12 {
                        continue;
                    }
                    let f = [d[1], -d[0]]; // outward normal x length: force per unit pressure and width
                    let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                    let probe = [m[0] + f[0] / len * 2e-6, m[1] + f[1] / len * 2e-6];
                    for gk in 0..2 {
                        if self.solid_contains(gk, theta, probe) {
                            let c = self.centre(gk);
                            s.force[gk][0] += f[0];
                            s.force[gk][1] += f[1];
                            s.torque[gk] += (m[0] - c[0]) * f[1] - (m[1] - c[1]) * f[0];
                            break;
                        }
                    }
                }
            }
        }
        (s, fluid)
    }

    /// Meshing-zone interfaces at driving angle theta (one section).
    pub fn interfaces_at(&self, theta: f64, ds: f64) -> Vec<Interface> {
        let mut out: Vec<Interface> = Vec::new();
        let p = self.pitch_point();
        let u = self.loa_dir();
        let n = self.loa_normal();
        let (o1, o2) = (self.centre(0), self.centre(1));
        let (ra1, ra2) = (self.gears[0].ra, self.gears[1].ra);
        let in_disk = |x: P2, c: P2, r: f64| (x[0] - c[0]).hypot(x[1] - c[1]) <= r;
        let side = |x: P2| n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]);
        // piece 1: circle 2 arc inside disk 1 on the driven side; piece 2: the line of
        // action inside the lens; piece 3: circle 1 arc inside disk 2 on the driving side
        let cusp = self.cusp();
        let mut pieces: Vec<Vec<P2>> = Vec::new();
        let arc = |c: P2, r: f64, from: P2, to: P2| -> Vec<P2> {
            let a0 = (from[1] - c[1]).atan2(from[0] - c[0]);
            let mut a1 = (to[1] - c[1]).atan2(to[0] - c[0]);
            // the short way between the cusps, facing the other centre
            let mut da = a1 - a0;
            while da > PI {
                da -= 2.0 * PI;
            }
            while da < -PI {
                da += 2.0 * PI;
            }
            a1 = a0 + da;
            let len = (a1 - a0).abs() * r;
            let m = (len / ds).ceil().max(1.0) as usize;
            (0..=m)
                .map(|i| {
                    let t = a0 + (a1 - a0) * i as f64 / m as f64;
                    [c[0] + r * t.cos(), c[1] + r * t.sin()]
                })
                .collect()
        };
        let lower = [cusp[0], -cusp[1]];
        let upper = cusp;
        pieces.push(
            arc(o2, ra2, lower, upper)
                .into_iter()
                .filter(|&x| side(x) >= 0.0 && in_disk(x, o1, ra1 + 1e-12))
                .collect(),
        );
        {
            let span = 2.0 * (ra1 + ra2);
            let m = (span / ds).ceil() as usize;
            let line: Vec<P2> = (0..=m)
                .map(|i| {
                    let t = -span / 2.0 + span * i as f64 / m as f64;
                    [p[0] + t * u[0], p[1] + t * u[1]]
                })
                .filter(|&x| in_disk(x, o1, ra1) && in_disk(x, o2, ra2))
                .collect();
            pieces.push(line);
        }
        pieces.push(
            arc(o1, ra1, lower, upper)
                .into_iter()
                .filter(|&x| side(x) <= 0.0 && in_disk(x, o2, ra2 + 1e-12))
                .collect(),
        );
        let z = [self.gears[0].z, self.gears[1].z];
        for pts in pieces {
            let mut current: Option<Interface> = None;
            for w in pts.windows(2) {
                let x = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                let seg = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
                let fluid = !self.solid_contains(0, theta, x) && !self.solid_contains(1, theta, x);
                if !fluid {
                    if let Some(c) = current.take() {
                        out.push(c);
                    }
                    continue;
                }
                let sp = [0, 1].map(|k| {
                    let (_, psi) = self.global_to_local(k, x);
                    let body = psi - self.body_offset(k, theta);
                    let pa = self.gears[k].pitch_angle();
                    (((body / pa).floor() as i64).rem_euclid(z[k] as i64)) as usize
                });
                match &mut current {
                    Some(c) if c.space == sp => c.length += seg,
                    _ => {
                        if let Some(c) = current.take() {
                            out.push(c);
                        }
                        current = Some(Interface {
                            space: sp,
                            length: seg,
                        });
                    }
                }
            }
            if let Some(c) = current.take() {
                out.push(c);
            }
        }
        // merge duplicates
        let mut merged: Vec<Interface> = Vec::new();
        for i in out {
            if let Some(m) = merged.iter_mut().find(|m| m.space == i.space) {
                m.length += i.length;
            } else {
                merged.push(i);
            }
        }
        merged
    }

    /// Builds the section tables with angular resolution `dphi`, grooves at
    /// the given edges (m) and width (m).
    pub fn section_tables(
        &self,
        dphi: f64,
        delivery_groove: f64,
        suction_groove: f64,
        groove_width: f64,
    ) -> SectionTables {
        let grooves = self.grooves(delivery_groove, suction_groove, groove_width);
        let mut phi0 = [0.0; 2];
        let mut dph = [0.0; 2];
        let mut samples: [Vec<SectionSample>; 2] = [Vec::new(), Vec::new()];
        let mut free = [SectionSample::default(); 2];
        for k in 0..2 {
            let reach = self.cusp_angle(k) + 1.5 * self.gears[k].pitch_angle();
            let n = (2.0 * reach / dphi).ceil() as usize;
            let step = 2.0 * reach / n as f64;
            phi0[k] = -reach;
            dph[k] = step;
            samples[k] = (0..=n)
                .map(|i| self.section_sample(k, -reach + step * i as f64, &grooves).0)
                .collect();
            free[k] = self.section_sample(k, PI, &grooves).0;
        }
        let p1 = self.gears[0].pitch_angle();
        let nif = (p1 / dphi).ceil() as usize;
        let dtheta_if = p1 / nif as f64;
        let interfaces = (0..nif)
            .map(|i| self.interfaces_at(i as f64 * dtheta_if, 2.0e-6))
            .collect();
        SectionTables {
            phi0,
            dphi: dph,
            samples,
            free,
            dtheta_if,
            interfaces,
        }
    }
}

fn to_pts(ls: &LineString<f64>) -> Vec<P2> {
    let mut v: Vec<P2> = ls.coords().map(|c| [c.x / MM, c.y / MM]).collect();
    if v.len() > 1 && v.first() == v.last() {
        v.pop();
    }
    v
}

fn signed_area(p: &[P2]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1])
        .sum::<f64>()
        / 2.0
}

impl SectionTables {
    /// Gear k's pocket quantities at local angle phi (linear interpolation; the
    /// free value away from the mesh).
    pub fn sample(&self, k: usize, phi: f64) -> SectionSample {
        let phi = wrap_pi(phi);
        let t = (phi - self.phi0[k]) / self.dphi[k];
        let s = &self.samples[k];
        if t < 0.0 || t >= (s.len() - 1) as f64 {
            // away from the mesh: the free pocket, its load rotated with it
            let mut f = self.free[k];
            let d = phi - PI;
            let rot = if k == 0 { d } else { -d };
            let (sn, cs) = rot.sin_cos();
            for g in 0..2 {
                let [x, y] = f.force[g];
                f.force[g] = [cs * x - sn * y, sn * x + cs * y];
            }
            return f;
        }
        let i = t.floor() as usize;
        let f = t - i as f64;
        let (a, b) = (&s[i], &s[i + 1]);
        let lerp = |x: f64, y: f64| x + f * (y - x);
        SectionSample {
            area: lerp(a.area, b.area),
            perimeter: lerp(a.perimeter, b.perimeter),
            force: [
                [
                    lerp(a.force[0][0], b.force[0][0]),
                    lerp(a.force[0][1], b.force[0][1]),
                ],
                [
                    lerp(a.force[1][0], b.force[1][0]),
                    lerp(a.force[1][1], b.force[1][1]),
                ],
            ],
            torque: [
                lerp(a.torque[0], b.torque[0]),
                lerp(a.torque[1], b.torque[1]),
            ],
            groove: [
                lerp(a.groove[0], b.groove[0]),
                lerp(a.groove[1], b.groove[1]),
            ],
        }
    }
}

/// Wraps an angle to (-pi, pi].
pub fn wrap_pi(a: f64) -> f64 {
    let mut x = a % (2.0 * PI);
    if x > PI {
        x -= 2.0 * PI;
    }
    if x <= -PI {
        x += 2.0 * PI;
    }
    x
}

impl Pair {
    /// Displacement per driving-gear revolution from the pocket tables alone
    /// (docs/model.md section 3, way (b)): at every angle, pockets joined by an open
    /// meshing-zone passage form one fluid region; a region whose volume
    /// shrinks delivers (ideal relief of the trapped volume), and the sum of
    /// the shrinking rates is integrated over a revolution, slice by slice.
    pub fn displacement_from_tables(&self, t: &SectionTables, slices: usize) -> f64 {
        let z = [self.gears[0].z, self.gears[1].z];
        let n = t.interfaces.len();
        let dth = t.dtheta_if;
        let h = 0.25 * dth;
        let mut per_section = 0.0;
        for i in 0..n {
            let theta = i as f64 * dth;
            // dA/dtheta of each pocket (same identity) by central differences
            let rate = |k: usize, m: usize| {
                let a = t.sample(k, self.space_centre(k, m, theta + h)).area;
                let b = t.sample(k, self.space_centre(k, m, theta - h)).area;
                (a - b) / (2.0 * h)
            };
            let nodes = z[0] + z[1];
            let mut parent: Vec<usize> = (0..nodes).collect();
            fn find(p: &mut [usize], x: usize) -> usize {
                let mut r = x;
                while p[r] != r {
                    r = p[r];
                }
                let mut y = x;
                while p[y] != r {
                    let nx = p[y];
                    p[y] = r;
                    y = nx;
                }
                r
            }
            for itf in &t.interfaces[i] {
                let a = find(&mut parent, itf.space[0]);
                let b = find(&mut parent, z[0] + itf.space[1]);
                parent[a] = b;
            }
            let mut region = vec![0.0; nodes];
            for m in 0..z[0] {
                let r = find(&mut parent, m);
                region[r] += rate(0, m);
            }
            for m in 0..z[1] {
                let r = find(&mut parent, z[0] + m);
                region[r] += rate(1, m);
            }
            per_section += region.iter().map(|&d| (-d).max(0.0)).sum::<f64>() * dth;
        }
        // one pitch of the driving gear covered; a revolution has z1 pitches;
        // every slice is the same spur section shifted in angle, so over a whole
        // revolution each contributes its width times the section integral
        let _ = slices;
        per_section * z[0] as f64 * self.b
    }
}
