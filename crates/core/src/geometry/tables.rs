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
//! the mating gear's region. Areas come from polygon clipping (`i_overlay`,
//! the engine under `geo`'s boolean operations).
//!
//! ## How the tables are built fast
//! A sample costs one polygon overlay, and only where the mating gear reaches
//! the space; everything else is worked out once or skipped
//! (`section_tables`: about 50-55 ms for the seed pump on one core, against
//! 0.7-1.4 s when every sample clipped whole polygons; docs/benchmarks.md):
//! - the outlines, the tooth space and the other gear's region are built
//!   once per gear in the body frame and placed at each angle by a rotation;
//! - the mating gear's solid and region are cut to a convex polygon round
//!   the space (its hull widened by `CROP_MARGIN_MM`) before the overlay,
//!   which subtracts both at once (non-zero fill): nothing outside that
//!   polygon can touch the space, so the fluid is the same;
//! - a space that nothing reaches is the free pocket turned to its angle
//!   (`SectionSample::rotate`), with its own groove overlaps;
//! - groove overlaps clip each fluid ring by the groove rectangle
//!   (Sutherland-Hodgman, exact for a convex clip);
//! - the meshing-zone boundary does not turn with the gears: its points'
//!   polar coordinates and half tooth angles are worked out once
//!   (`MeshBoundary`), each angle compares them with the teeth;
//! - samples and angles are independent and are shared out over the cores
//!   (scoped threads, `parallel_map`);
//! - the narrowest gap of a meshing-zone passage is looked for only round
//!   its run of the boundary and between the two teeth that bound it, on
//!   outlines sampled at a 25th of the run (about 7 ms of the build on one
//!   core).
//!
//! The clipper snaps coordinates to a grid of about 1e-10 m, so sample
//! values carry a scatter of about 1e-9 relative (area) to 1e-7 (perimeter,
//! loads of slivers); the tests hold the tables to a plain clipping of whole
//! polygons within 1e-6 of each column's scale and the interfaces to a
//! point-by-point test exactly (`tests` below).
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
use geo::{Coord, LineString, Polygon};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

const MM: f64 = 1.0e3; // polygons are built in millimetres for the clipper's robustness
const NF: usize = 24; // points per flank
const NA: usize = 6; // points per root/tip arc segment
/// Version of the way the section tables are built: raise it with any
/// change that moves a table value, so that cached tables of the old way
/// are refused ([`Pair::section_key`]).
pub const TABLES_VERSION: u64 = 4;
/// Sides of the polygon of a tip circle bounding the other gear's region.
const FOREIGN_SIDES: usize = 2880;

/// Quantities of one pocket in one spur section, per unit face width.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
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

impl SectionSample {
    /// The sample of gear k's pocket turned by `d` in its local angle: the
    /// loads turn with the pocket (gear 1's local angles run clockwise in
    /// the global frame), area, perimeter and torques stay.
    pub fn rotate(&mut self, k: usize, d: f64) {
        let rot = if k == 0 { d } else { -d };
        let (sn, cs) = rot.sin_cos();
        for g in 0..2 {
            let [x, y] = self.force[g];
            self.force[g] = [cs * x - sn * y, sn * x + cs * y];
        }
    }
}

/// A meshing-zone connection: driving-gear space, driven-gear space (body
/// indices at the sample's angle) and two measures of its opening per unit
/// face width, m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Interface {
    pub space: [usize; 2],
    /// Length of the boundary between the gears' regions that runs through
    /// fluid between the two spaces.
    pub length: f64,
    /// The narrowest gap between the two teeth that bound each run of that
    /// boundary, one of each gear (never more than the run's length): past
    /// an end of the path of contact, the gap between a tip corner and the
    /// mating flank. A run not bounded by a tooth of each gear counts its
    /// length ([`MeshBoundary::interfaces_at`]).
    pub gap: f64,
}

/// Section tables of both gears as functions of the pocket's local angle phi,
/// on a uniform grid over the mesh neighbourhood.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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

/// Clips a polygon (list of points) by the half-plane n.(x - p) >= 0
/// (Sutherland-Hodgman: exact for a convex polygon; a non-convex one may
/// keep zero-width slivers along the line).
fn clip_half_plane(poly: &[P2], p: P2, n: P2) -> Vec<P2> {
    let mut out = Vec::with_capacity(poly.len() + 2);
    clip_half_plane_into(poly, p, n, &mut out);
    out
}

/// [`clip_half_plane`] into `out` (cleared first).
fn clip_half_plane_into(poly: &[P2], p: P2, n: P2, out: &mut Vec<P2>) {
    out.clear();
    let side = |x: &P2| n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]);
    let Some(last) = poly.last() else {
        return;
    };
    let (mut a, mut sa) = (*last, side(last));
    for &b in poly {
        let sb = side(&b);
        if (sa >= 0.0) != (sb >= 0.0) {
            // the crossing of edge a -> b, worked out from a as it always was
            let t = sa / (sa - sb);
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
        if sb >= 0.0 {
            out.push(b);
        }
        (a, sa) = (b, sb);
    }
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

    /// The other gear's region inside gear k's bore: disk(other) on the
    /// other's side of the line of action. Its circle as a polygon of
    /// [`FOREIGN_SIDES`] vertices (m, counter-clockwise) and the half-plane
    /// (a point of the line, its normal into the region); the region is
    /// cut to each sample's neighbourhood ([`SectionGeometry::foreign_near`]).
    fn foreign_region(&self, k: usize) -> (Vec<P2>, P2, P2) {
        let other = 1 - k;
        let c = circle(self.centre(other), self.gears[other].ra, FOREIGN_SIDES);
        let n = self.loa_normal();
        let n = if other == 1 { n } else { [-n[0], -n[1]] };
        (c, self.pitch_point(), n)
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

    /// Groove rectangles (delivery, suction) in global coordinates (mm,
    /// counter-clockwise).
    fn grooves(&self, dg: f64, sg: f64, width: f64) -> [Vec<P2>; 2] {
        let p = self.pitch_point();
        let far = self.cusp()[1] + 2.0e-3;
        let rect = |y0: f64, y1: f64| {
            [
                [p[0] - width / 2.0, y0],
                [p[0] + width / 2.0, y0],
                [p[0] + width / 2.0, y1],
                [p[0] - width / 2.0, y1],
            ]
            .into_iter()
            .map(mm)
            .collect()
        };
        [rect(-far, -dg), rect(sg, far)]
    }

    /// The points of the boundary between the two gears' regions, every
    /// `ds` (m) along it, in its three pieces ([`Pair::mesh_boundary`]).
    fn boundary_pieces(&self, ds: f64) -> Vec<Vec<P2>> {
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
        pieces
    }

    /// The boundary between the two gears' regions, sampled every `ds` (m):
    /// a curve from the delivery-side cusp along the driven bore, the line of
    /// action and the driving bore to the suction-side cusp. It does not turn
    /// with the gears, so every point's polar coordinates about both centres
    /// are worked out once here and each angle only compares them with the
    /// teeth ([`MeshBoundary::interfaces_at`]).
    pub fn mesh_boundary(&self, ds: f64) -> MeshBoundary {
        let pieces = self.boundary_pieces(ds);
        let mut boundary = MeshBoundary {
            piece_end: Vec::with_capacity(pieces.len()),
            length: Vec::new(),
            mid: Vec::new(),
            psi: [Vec::new(), Vec::new()],
            half: [Vec::new(), Vec::new()],
        };
        for pts in &pieces {
            for w in pts.windows(2) {
                let x = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                boundary
                    .length
                    .push((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]));
                boundary.mid.push(x);
                for k in 0..2 {
                    let (rho, psi) = self.global_to_local(k, x);
                    boundary.psi[k].push(psi);
                    boundary.half[k].push(match self.gears[k].radial_zone(rho) {
                        RadialZone::Root => f64::INFINITY,
                        RadialZone::Outside => -1.0,
                        RadialZone::Flank(half) => half,
                    });
                }
            }
            boundary.piece_end.push(boundary.length.len());
        }
        boundary
    }

    /// Meshing-zone interfaces at driving angle theta (one section), the
    /// boundary sampled every `ds` (m). Building the tables samples the
    /// boundary once for every angle ([`Pair::mesh_boundary`]).
    pub fn interfaces_at(&self, theta: f64, ds: f64) -> Vec<Interface> {
        self.mesh_boundary(ds).interfaces_at(self, theta)
    }

    /// Fingerprint of everything [`Pair::section_tables`] depends on: the
    /// pair itself (every field of both gears and of the mesh, by its exact
    /// value), the arguments, the polygon resolutions and the method's
    /// version ([`TABLES_VERSION`]). Equal fingerprints, equal tables
    /// (`geometry::cache` keys its files by it).
    pub fn section_key(
        &self,
        dphi: f64,
        delivery_groove: f64,
        suction_groove: f64,
        groove_width: f64,
    ) -> crate::hash::Fingerprint {
        let mut h = crate::hash::Fnv1a::new();
        h.write_str("gearpump section tables");
        h.write_u64(TABLES_VERSION);
        // Debug prints every f64 in its shortest exact form: a changed bit
        // of any field changes the text
        h.write_str(&format!("{self:?}"));
        for x in [
            dphi,
            delivery_groove,
            suction_groove,
            groove_width,
            CROP_MARGIN_MM,
        ] {
            h.write_f64(x);
        }
        for n in [NF, NA, FOREIGN_SIDES] {
            h.write_u64(n as u64);
        }
        h.finish()
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
        let geometry = SectionGeometry::new(self, delivery_groove, suction_groove, groove_width);
        let mut phi0 = [0.0; 2];
        let mut dph = [0.0; 2];
        let mut count = [0usize; 2];
        let mut free = [SectionSample::default(); 2];
        for k in 0..2 {
            let reach = self.cusp_angle(k) + 1.5 * self.gears[k].pitch_angle();
            let n = (2.0 * reach / dphi).ceil() as usize;
            phi0[k] = -reach;
            dph[k] = 2.0 * reach / n as f64;
            count[k] = n + 1;
            free[k] = geometry.sample(k, PI, None);
        }
        let p1 = self.gears[0].pitch_angle();
        let nif = (p1 / dphi).ceil() as usize;
        let dtheta_if = p1 / nif as f64;
        let boundary = self.mesh_boundary(2.0e-6);
        // every sample and every interface angle is independent of the
        // others: shared out over the cores, each result in its own slot
        let mut samples = parallel_map(count[0] + count[1], |j| {
            let (k, i) = if j < count[0] {
                (0, j)
            } else {
                (1, j - count[0])
            };
            geometry.sample(k, phi0[k] + dph[k] * i as f64, Some(&free[k]))
        });
        let samples = [samples.drain(..count[0]).collect(), samples];
        let interfaces = parallel_map(nif, |i| boundary.interfaces_at(self, i as f64 * dtheta_if));
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

/// `f(0), f(1), ..., f(n - 1)` in that order, worked out on up to
/// [`TABLE_THREADS`] threads (no more than the cores this process may use,
/// `std::thread::available_parallelism`; `taskset -c 0` makes it one). The
/// threads are scoped: all have ended when this returns, so a library
/// unloaded afterwards (an FMU) leaves none behind. Every result is the
/// same on any number of threads.
fn parallel_map<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    parallel_map_on(threads.min(TABLE_THREADS), n, f)
}

/// [`parallel_map`] on `threads` threads at most.
pub(crate) fn parallel_map_on<T: Send>(
    threads: usize,
    n: usize,
    f: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let threads = threads.min(n.max(1));
    if threads <= 1 {
        return (0..n).map(f).collect();
    }
    let next = AtomicUsize::new(0);
    let work = || {
        let mut mine = Vec::new();
        loop {
            let j = next.fetch_add(1, Ordering::Relaxed);
            if j >= n {
                return mine;
            }
            mine.push((j, f(j)));
        }
    };
    let parts: Vec<Vec<(usize, T)>> = std::thread::scope(|scope| {
        let helpers: Vec<_> = (1..threads).map(|_| scope.spawn(work)).collect();
        let mut parts = vec![work()];
        parts.extend(helpers.into_iter().map(|h| match h.join() {
            Ok(part) => part,
            Err(panic) => std::panic::resume_unwind(panic),
        }));
        parts
    });
    let mut slots: Vec<Option<T>> = (0..n).map(|_| None).collect();
    for (j, value) in parts.into_iter().flatten() {
        slots[j] = Some(value);
    }
    slots
        .into_iter()
        .map(|v| v.expect("every job was taken"))
        .collect()
}

/// Most threads the pocket tables are built on.
pub const TABLE_THREADS: usize = 4;

/// Where a radius lies on a gear: inside the root circle (always solid),
/// outside the tip circle (never), or on the flanks, with the half angular
/// tooth thickness there.
#[derive(Debug, Clone, Copy)]
pub enum RadialZone {
    Root,
    Outside,
    Flank(f64),
}

impl super::gear::Gear {
    /// The radial zone of radius `rho` ([`RadialZone`]).
    pub fn radial_zone(&self, rho: f64) -> RadialZone {
        if rho <= self.rf {
            RadialZone::Root
        } else if rho > self.ra {
            RadialZone::Outside
        } else {
            RadialZone::Flank(self.half_angle(rho))
        }
    }

    /// Is a point of radial zone `zone` at body angle `alpha` inside the
    /// solid? The same test as [`Gear::contains_polar`](super::gear::Gear::contains_polar)
    /// with the radius's part worked out beforehand.
    pub fn zone_contains(&self, zone: RadialZone, alpha: f64) -> bool {
        match zone {
            RadialZone::Root => true,
            RadialZone::Outside => false,
            RadialZone::Flank(half) => {
                let p = self.pitch_angle();
                let a = alpha - p * super::gear::nearest_integer(alpha / p);
                a.abs() <= half
            }
        }
    }
}

/// The sampled boundary between the gears' regions ([`Pair::mesh_boundary`]),
/// segment by segment: its length, and its midpoint's polar angle about
/// each centre with the half tooth angle at its radius there (+inf inside
/// the root circle, where every angle is solid; -1 outside the tip circle,
/// where none is). Pieces end at `piece_end`.
#[derive(Debug, Clone)]
pub struct MeshBoundary {
    piece_end: Vec<usize>,
    length: Vec<f64>,
    /// Midpoint of each segment, m.
    mid: Vec<P2>,
    psi: [Vec<f64>; 2],
    half: [Vec<f64>; 2],
}

impl MeshBoundary {
    /// Meshing-zone interfaces at driving angle theta: the runs of fluid
    /// segments between the same two tooth spaces, their lengths summed.
    pub fn interfaces_at(&self, pair: &Pair, theta: f64) -> Vec<Interface> {
        use super::gear::nearest_integer;
        let z = [pair.gears[0].z as f64, pair.gears[1].z as f64];
        let offset = [pair.body_offset(0, theta), pair.body_offset(1, theta)];
        let pitch = [pair.gears[0].pitch_angle(), pair.gears[1].pitch_angle()];
        // each segment's tooth spaces as one code z1 * m1 + m2, or -1 where a
        // tooth covers it: `Gear::contains_polar` and the space index from
        // one quotient per gear, without branches (the loop vectorises)
        let n = self.length.len();
        let mut code = vec![0.0f64; n];
        for k in 0..2 {
            let (psi, half) = (&self.psi[k], &self.half[k]);
            let (off, p, zk) = (offset[k], pitch[k], z[k]);
            let inv_z = 1.0 / zk;
            let scale = if k == 0 { z[1] } else { 1.0 };
            for i in 0..n {
                let body = psi[i] - off;
                let q = body / p;
                let near = nearest_integer(q);
                let solid = (body - p * near).abs() <= half[i];
                // floor(q), then its remainder modulo z (exact on integers:
                // (f + 1/2) / z stays at least 1/(2z) from an integer)
                let f = near - if near > q { 1.0 } else { 0.0 };
                let t = (f + 0.5) * inv_z;
                let tn = nearest_integer(t);
                let m = f - zk * (tn - if tn > t { 1.0 } else { 0.0 });
                let c = code[i];
                code[i] = if solid || c < 0.0 {
                    -1.0
                } else {
                    c + scale * m
                };
            }
        }
        let mut out: Vec<Interface> = Vec::new();
        let mut start = 0;
        for &end in &self.piece_end {
            let mut current: Option<(f64, Interface)> = None;
            for (&c, &length) in code[start..end].iter().zip(&self.length[start..end]) {
                if c < 0.0 {
                    if let Some((_, itf)) = current.take() {
                        out.push(itf);
                    }
                    continue;
                }
                match &mut current {
                    Some((cc, itf)) if *cc == c => itf.length += length,
                    _ => {
                        if let Some((_, itf)) = current.take() {
                            out.push(itf);
                        }
                        let m1 = (c / z[1]).floor();
                        current = Some((
                            c,
                            Interface {
                                space: [m1 as usize, (c - m1 * z[1]) as usize],
                                length,
                                gap: length,
                            },
                        ));
                    }
                }
            }
            if let Some((_, itf)) = current.take() {
                out.push(itf);
            }
            start = end;
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
        // the narrowest gap of each run: the pieces join end to end (driven
        // bore, line of action, driving bore), so a run may cross a junction
        for m in &mut merged {
            m.gap = 0.0;
        }
        // the gear and the tooth that cover segment i (a tooth's root body
        // counts as the nearest tooth)
        let covering = |i: usize| -> (usize, i64) {
            let tooth = |k: usize| {
                let body = self.psi[k][i] - offset[k];
                let near = nearest_integer(body / pitch[k]);
                (near, (body - pitch[k] * near).abs() <= self.half[k][i])
            };
            match tooth(0) {
                (t, true) => (0, t as i64),
                _ => (1, tooth(1).0 as i64),
            }
        };
        let mut i = 0;
        while i < n {
            if code[i] < 0.0 {
                i += 1;
                continue;
            }
            let (c, i0) = (code[i], i);
            let mut length = 0.0;
            while i < n && code[i] == c {
                length += self.length[i];
                i += 1;
            }
            let i1 = i - 1;
            let mut gap = length;
            if i0 > 0 && i < n && code[i0 - 1] < 0.0 && code[i] < 0.0 {
                let (ka, ta) = covering(i0 - 1);
                let (kb, tb) = covering(i);
                if ka != kb {
                    let (a, b) = (self.mid[i0], self.mid[i1]);
                    let x = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                    let teeth = if ka == 0 { [ta, tb] } else { [tb, ta] };
                    gap = gap.min(narrowest_gap(
                        pair,
                        theta,
                        teeth,
                        x,
                        length + NARROWEST_MARGIN,
                    ));
                }
            }
            let m1 = (c / z[1]).floor();
            let space = [m1 as usize, (c - m1 * z[1]) as usize];
            if let Some(m) = merged.iter_mut().find(|m| m.space == space) {
                m.gap += gap;
            }
        }
        merged
    }
}

/// How far past a run's length the narrowest gap is looked for round the
/// run's midpoint, m: a few of the boundary's samples.
const NARROWEST_MARGIN: f64 = 4.0e-6;

/// The outline of tooth `t` (body index) of gear k within `r` of the point
/// `x` at driving angle theta, as runs of consecutive points (m) sampled
/// about every `r / 25` along the radius: its flanks, its tip arc and the
/// root arcs on either side.
fn outline_near(pair: &Pair, theta: f64, k: usize, t: i64, x: P2, r: f64) -> Vec<Vec<P2>> {
    let g = &pair.gears[k];
    let step = (r / 25.0).max(0.2e-6);
    let (rho_x, psi_x) = pair.global_to_local(k, x);
    let off = pair.body_offset(k, theta);
    let pitch = g.pitch_angle();
    let near = |p: &P2| (p[0] - x[0]).hypot(p[1] - x[1]) <= r + step;
    let mut runs: Vec<Vec<P2>> = Vec::new();
    let mut push = |pts: Vec<P2>| {
        let mut run = Vec::new();
        for p in pts {
            if near(&p) {
                run.push(p);
            } else if !run.is_empty() {
                runs.push(std::mem::take(&mut run));
            }
        }
        if !run.is_empty() {
            runs.push(run);
        }
    };
    // flanks: the radii within reach of x, and the tip corner
    let lo = (rho_x - r - step).max(g.rf);
    let hi = (rho_x + r + step).min(g.ra);
    let mut radii = Vec::new();
    if hi > lo {
        let m = ((hi - lo) / step).ceil() as usize;
        radii.extend((0..=m).map(|i| lo + (hi - lo) * i as f64 / m as f64));
    }
    // an arc of radius rho from angle a0 to a1, only near x
    let arc = |rho: f64, a0: f64, a1: f64| -> Vec<P2> {
        if (rho - rho_x).abs() > r + step {
            return Vec::new();
        }
        let reach = 2.0 * (r + step) / rho.min(rho_x).max(1e-9);
        let (b0, b1) = (a0.max(psi_x - reach), a1.min(psi_x + reach));
        if b1 <= b0 {
            return Vec::new();
        }
        let m = ((b1 - b0) * rho / step).ceil().max(1.0) as usize;
        (0..=m)
            .map(|i| pair.local_to_global(k, rho, b0 + (b1 - b0) * i as f64 / m as f64))
            .collect()
    };
    let ha = g.half_angle(g.ra);
    let hf = g.half_angle(g.rf);
    let c = off + t as f64 * pitch;
    for side in [-1.0, 1.0] {
        push(
            radii
                .iter()
                .map(|&rho| pair.local_to_global(k, rho, c + side * g.half_angle(rho)))
                .collect(),
        );
    }
    push(arc(g.ra, c - ha, c + ha));
    push(arc(g.rf, c + hf, c + pitch - hf));
    push(arc(g.rf, c - pitch + hf, c - hf));
    runs
}

/// The narrowest gap between tooth `teeth[0]` of the driving gear and tooth
/// `teeth[1]` of the driven gear (body indices) within `r` of the point `x`
/// at driving angle theta, m (infinite where one of them has no outline
/// there): the closest pair of sampled points, then each of the two against
/// the other outline's segments beside it.
fn narrowest_gap(pair: &Pair, theta: f64, teeth: [i64; 2], x: P2, r: f64) -> f64 {
    let a = outline_near(pair, theta, 0, teeth[0], x, r);
    let b = outline_near(pair, theta, 1, teeth[1], x, r);
    let d2 = |p: P2, q: P2| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
    let mut best = (f64::INFINITY, 0, 0, 0, 0);
    for (ra, pa) in a.iter().enumerate() {
        for (ia, &p) in pa.iter().enumerate() {
            for (rb, pb) in b.iter().enumerate() {
                for (ib, &q) in pb.iter().enumerate() {
                    let d = d2(p, q);
                    if d < best.0 {
                        best = (d, ra, ia, rb, ib);
                    }
                }
            }
        }
    }
    if !best.0.is_finite() {
        return f64::INFINITY;
    }
    let (_, ra, ia, rb, ib) = best;
    let to_segments = |p: P2, run: &[P2], i: usize| -> f64 {
        let lo = i.saturating_sub(2);
        let hi = (i + 2).min(run.len() - 1);
        (lo..hi)
            .map(|j| point_segment_distance(p, run[j], run[j + 1]))
            .fold(d2(p, run[i]).sqrt(), f64::min)
    };
    to_segments(a[ra][ia], &b[rb], ib).min(to_segments(b[rb][ib], &a[ra], ia))
}

fn point_segment_distance(p: P2, a: P2, b: P2) -> f64 {
    let (ux, uy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = ux * ux + uy * uy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * ux + (p[1] - a[1]) * uy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * ux).hypot(p[1] - a[1] - t * uy)
}

/// What every section sample of a pair shares, built once: each gear's
/// outline and tooth space in body polar coordinates, the other gear's
/// region inside each bore and the groove rectangles (mm).
struct SectionGeometry<'a> {
    pair: &'a Pair,
    /// Each gear's outline and tooth space 0 in its body frame, Cartesian,
    /// mm: placed at an angle by one rotation.
    outline: [Vec<P2>; 2],
    space: [Vec<P2>; 2],
    /// A convex polygon round each tooth space in its body frame, at least
    /// half of [`CROP_MARGIN_MM`] from it (mm, counter-clockwise): the region
    /// the clipping is cut to.
    space_hull: [Vec<P2>; 2],
    foreign: [(Vec<P2>, P2, P2); 2],
    grooves: [Vec<P2>; 2],
    /// Each gear's half tooth angle tabulated over its flank (the probes).
    flank: [FlankTable; 2],
}

/// Margin round a tooth space within which the other gear's solid and region
/// are kept for the clipping, mm: far larger than the chords' sagitta, so
/// nothing that touches the space is left out.
const CROP_MARGIN_MM: f64 = 0.05;

impl<'a> SectionGeometry<'a> {
    fn new(pair: &'a Pair, dg: f64, sg: f64, width: f64) -> SectionGeometry<'a> {
        SectionGeometry {
            pair,
            outline: [0, 1].map(|k| body_points(&pair.gears[k].outline_polar(NF, NA))),
            space: [0, 1].map(|k| body_points(&pair.gears[k].space_polar(0, NF, NA))),
            space_hull: [0, 1].map(|k| {
                hull_with_margin(
                    &body_points(&pair.gears[k].space_polar(0, NF, NA)),
                    CROP_MARGIN_MM,
                )
            }),
            foreign: [pair.foreign_region(0), pair.foreign_region(1)],
            grooves: pair.grooves(dg, sg, width),
            flank: [0, 1].map(|k| FlankTable::new(&pair.gears[k])),
        }
    }

    /// Body points `local` of gear k placed in the global frame at body
    /// offset `off` (mm): `local_to_global` by one rotation.
    fn place(&self, k: usize, off: f64, local: &[P2], out: &mut Vec<P2>) {
        let (sn, cs) = off.sin_cos();
        let a = self.pair.a * MM;
        out.extend(local.iter().map(|&[u, v]| {
            let (x, y) = (cs * u - sn * v, sn * u + cs * v);
            if k == 0 {
                [x, y]
            } else {
                [a - x, y]
            }
        }));
    }

    /// Angular range (about gear `other`'s centre, rad) of the convex region
    /// `region` (mm), which must not hold the centre: every point of the
    /// region lies in the wedge between the two.
    fn wedge(&self, other: usize, region: &[P2]) -> (f64, f64) {
        let c = self.pair.centre(other);
        let angle = |x: &P2| (x[1] / MM - c[1]).atan2(x[0] / MM - c[0]);
        let a0 = angle(&region[0]);
        let (mut amin, mut amax) = (a0, a0);
        for x in &region[1..] {
            let a = a0 + wrap_pi(angle(x) - a0);
            amin = amin.min(a);
            amax = amax.max(a);
        }
        (amin, amax)
    }

    /// The other gear's region cut to the convex `region` (mm, convex,
    /// counter-clockwise; fewer than three points when they do not meet).
    /// Only the circle's vertices in the region's wedge and the centre are
    /// kept before the half-plane and the region cut it: the same region
    /// there, the same cut points, a fraction of the vertices.
    fn foreign_near(&self, k: usize, region: &[P2], wedge: (f64, f64)) -> Vec<P2> {
        let other = 1 - k;
        let c = mm(self.pair.centre(other));
        if convex_contains(region, c) {
            // not met on a working gear pair: the whole region
            let (circle, p, n) = &self.foreign[k];
            let cut = clip_half_plane(circle, *p, *n);
            return clip_convex(&cut.into_iter().map(mm).collect::<Vec<_>>(), region);
        }
        let (circle, p, n) = &self.foreign[k];
        let (amin, amax) = wedge;
        let step = 2.0 * PI / FOREIGN_SIDES as f64;
        let i0 = (amin / step).floor() as i64 - 1;
        let i1 = (amax / step).ceil() as i64 + 1;
        let nv = FOREIGN_SIDES as i64;
        let mut sector: Vec<P2> = Vec::with_capacity((i1 - i0 + 2) as usize);
        sector.push(self.pair.centre(other));
        sector.extend((i0..=i1).map(|i| circle[i.rem_euclid(nv) as usize]));
        let cut = clip_half_plane(&sector, *p, *n);
        clip_convex(&cut.into_iter().map(mm).collect::<Vec<_>>(), region)
    }

    /// The other gear's solid near gear k's space (mm): the teeth of gear
    /// `other` that can reach the space, closed through its centre,
    /// counter-clockwise; empty when none can. Nothing of the solid outside
    /// the space's wedge takes part in the clipping, so the cut changes no
    /// fluid.
    fn solid_near(
        &self,
        other: usize,
        theta: f64,
        space: &[P2],
        region: &[P2],
        wedge: (f64, f64),
    ) -> Vec<P2> {
        let pair = self.pair;
        let g = &pair.gears[other];
        let c = mm(pair.centre(other));
        // the solid lies inside the tip circle: a space wholly outside it
        // meets no tooth
        if squared_distance_to_ring(c, space) > (g.ra * MM).powi(2) {
            return Vec::new();
        }
        let off = pair.body_offset(other, theta);
        let p = g.pitch_angle();
        let outline = &self.outline[other];
        let mut pts = Vec::with_capacity(outline.len() + 1);
        if convex_contains(region, c) {
            // not met on a working gear pair: the whole outline
            self.place(other, off, outline, &mut pts);
            return ccw(pts);
        }
        // the box's wedge in body angles (local angles run clockwise on
        // gear 1: local_to_global mirrors x)
        let (wmin, wmax) = wedge;
        let (amin, amax) = if other == 0 {
            (wmin - off, wmax - off)
        } else {
            (PI - wmax - off, PI - wmin - off)
        };
        // the blocks of outline_polar that cover the space's wedge: block m
        // runs from tooth m's trailing root (m p - hf) to the next tooth's
        // (m p + p - hf), and every bit of solid in the wedge belongs to
        // one of them or to the root disk (the blocks' root arcs and the
        // centre close it)
        let hf = g.half_angle(g.rf);
        let slack = 1.0e-9;
        let m0 = ((amin - slack + hf) / p).floor() as i64;
        let m1 = ((amax + slack + hf) / p).floor() as i64;
        let z = g.z as i64;
        if m1 - m0 + 1 >= z {
            // every tooth may take part: the whole outline
            self.place(other, off, outline, &mut pts);
            return ccw(pts);
        }
        let per_tooth = outline.len() / g.z;
        for m in m0..=m1 {
            let r = m.rem_euclid(z) as usize;
            let turn = (m - r as i64) as f64 * p;
            self.place(
                other,
                off + turn,
                &outline[r * per_tooth..(r + 1) * per_tooth],
                &mut pts,
            );
        }
        pts.push(c);
        ccw(pts)
    }

    /// One section sample of gear k's pocket centred at local angle phi: the
    /// tooth space minus the other gear's solid and region (one polygon
    /// overlay), its area, perimeter, groove overlaps and pressure loads.
    fn sample(&self, k: usize, phi: f64, free: Option<&SectionSample>) -> SectionSample {
        let pair = self.pair;
        let theta = pair.theta_for_space(k, phi);
        let off = pair.body_offset(k, theta);
        let mut space: Vec<P2> = Vec::with_capacity(self.space[k].len());
        self.place(k, off, &self.space[k], &mut space);
        // the convex region round the space turned with it: what lies
        // outside takes no part in the clipping
        let mut region = Vec::with_capacity(self.space_hull[k].len());
        self.place(k, off, &self.space_hull[k], &mut region);
        let region = ccw(region);
        let mut blockers: Vec<Vec<P2>> = Vec::with_capacity(2);
        // the region's wedge about the other centre (if the region held the
        // centre, both cuts below take everything and need none)
        let wedge = self.wedge(1 - k, &region);
        let solid = self.solid_near(1 - k, theta, &space, &region, wedge);
        if !solid.is_empty() {
            // the solid in the region (a non-convex polygon cut by a convex
            // one may keep zero-width slivers along the cut, away from the
            // space, which the non-zero fill ignores)
            let solid = clip_convex(&solid, &region);
            if solid.len() >= 3 {
                blockers.push(solid);
            }
        }
        let foreign = self.foreign_near(k, &region, wedge);
        if foreign.len() >= 3 {
            blockers.push(foreign);
        }
        if blockers.is_empty() {
            if let Some(free) = free {
                // the whole space is the pocket: the free pocket turned to
                // this angle, with its own groove overlaps
                let mut s = *free;
                s.rotate(k, phi - PI);
                s.groove = self.groove_overlaps(&[vec![space]]);
                return s;
            }
        }
        // fluid contours: per polygon, its exterior then its holes
        let fluid: Vec<Vec<Vec<P2>>> = if blockers.is_empty() {
            vec![vec![space]]
        } else {
            space.overlay(&blockers, OverlayRule::Difference, FillRule::NonZero)
        };
        let mut s = SectionSample {
            groove: self.groove_overlaps(&fluid),
            ..Default::default()
        };
        for poly in &fluid {
            for (i, ring) in poly.iter().enumerate() {
                let sign = if i == 0 { 1.0 } else { -1.0 };
                s.area += sign * signed_area(ring).abs() / (MM * MM);
                s.perimeter += ring_length(ring) / MM;
                self.add_loads(&mut s, theta, ring, i == 0);
            }
        }
        s
    }

    /// Planform overlaps of fluid polygons (exterior, then holes) with the
    /// delivery and the suction groove, m^2: each ring clipped by the
    /// rectangle (Sutherland-Hodgman), holes taken away.
    fn groove_overlaps(&self, fluid: &[Vec<Vec<P2>>]) -> [f64; 2] {
        let mut out = [0.0; 2];
        for (gi, groove) in self.grooves.iter().enumerate() {
            let (glo, ghi) = bounds(groove);
            for poly in fluid {
                for (i, ring) in poly.iter().enumerate() {
                    let (lo, hi) = bounds(ring);
                    if lo[0] > ghi[0] || hi[0] < glo[0] || lo[1] > ghi[1] || hi[1] < glo[1] {
                        continue;
                    }
                    let sign = if i == 0 { 1.0 } else { -1.0 };
                    out[gi] += sign * signed_area(&clip_box(ring, glo, ghi)).abs() / (MM * MM);
                }
            }
        }
        out
    }

    /// Is the probe point `x` (m) in gear k's solid at driving angle theta?
    /// [`Pair::solid_contains`] with the radius tests on squared distances,
    /// so most probes need neither a square root nor an angle.
    fn probe_in_solid(&self, k: usize, theta: f64, x: P2) -> bool {
        let pair = self.pair;
        let g = &pair.gears[k];
        let dx = if k == 0 { x[0] } else { pair.a - x[0] };
        let r2 = dx * dx + x[1] * x[1];
        if r2 <= g.rf * g.rf {
            return true;
        }
        if r2 > g.ra * g.ra {
            return false;
        }
        let rho = r2.sqrt();
        let alpha = x[1].atan2(dx) - pair.body_offset(k, theta);
        let p = g.pitch_angle();
        let a = (alpha - p * super::gear::nearest_integer(alpha / p)).abs();
        self.flank[k].within(g, rho, a)
    }

    /// Pressure loads of one ring of a fluid polygon: the fluid pushes on each
    /// solid across the edges it shares with it (a probe just outside each
    /// edge tells which gear, if any, is there).
    fn add_loads(&self, s: &mut SectionSample, theta: f64, ring: &[P2], exterior: bool) {
        let pair = self.pair;
        let pts: Vec<P2> = ring.iter().map(|x| [x[0] / MM, x[1] / MM]).collect();
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
                if self.probe_in_solid(gk, theta, probe) {
                    let c = pair.centre(gk);
                    s.force[gk][0] += f[0];
                    s.force[gk][1] += f[1];
                    s.torque[gk] += (m[0] - c[0]) * f[1] - (m[1] - c[1]) * f[0];
                    break;
                }
            }
        }
    }
}

/// A gear's half tooth angle on a uniform grid of radii over its involute
/// flank, linearly interpolated, with a bound on the interpolation error:
/// the largest error at the intervals' midpoints (where a linear
/// interpolant's error peaks) times ten. The probes of the loads use it and
/// fall back to [`Gear::half_angle`](super::gear::Gear::half_angle) within
/// the bound, so every probe is decided as the exact test decides it.
#[derive(Debug, Clone)]
struct FlankTable {
    r0: f64,
    dr: f64,
    half: Vec<f64>,
    bound: f64,
}

impl FlankTable {
    const NODES: usize = 2048;

    fn new(g: &super::gear::Gear) -> FlankTable {
        // below the base circle the half angle is that of the base circle
        let r0 = g.rb.max(g.rf).min(g.ra);
        let dr = (g.ra - r0) / (Self::NODES - 1) as f64;
        let half: Vec<f64> = (0..Self::NODES)
            .map(|i| g.half_angle(r0 + dr * i as f64))
            .collect();
        let worst = (0..Self::NODES - 1)
            .map(|i| {
                let mid = g.half_angle(r0 + dr * (i as f64 + 0.5));
                (0.5 * (half[i] + half[i + 1]) - mid).abs()
            })
            .fold(0.0, f64::max);
        FlankTable {
            r0,
            dr,
            half,
            bound: 10.0 * worst + 1e-12,
        }
    }

    /// Is angle `a` (>= 0, from a tooth's centre line) at radius `rho` on
    /// the flank's tooth side, `a <= g.half_angle(rho)`? The tabulated half
    /// angle decides unless `a` lies within the table's error bound of it;
    /// there the exact half angle does.
    fn within(&self, g: &super::gear::Gear, rho: f64, a: f64) -> bool {
        let (half, bound) = self.half_angle(rho);
        if a <= half - bound {
            true
        } else if a > half + bound {
            false
        } else {
            a <= g.half_angle(rho)
        }
    }

    /// The interpolated half angle at `rho` and the error bound.
    fn half_angle(&self, rho: f64) -> (f64, f64) {
        if self.dr <= 0.0 || rho <= self.r0 {
            return (self.half[0], self.bound);
        }
        let t = (rho - self.r0) / self.dr;
        let i = (t as usize).min(Self::NODES - 2);
        let f = (t - i as f64).min(1.0);
        (
            self.half[i] + f * (self.half[i + 1] - self.half[i]),
            self.bound,
        )
    }
}

/// Body polar points (rho, alpha) as Cartesian body points, mm.
fn body_points(polar: &[(f64, f64)]) -> Vec<P2> {
    polar
        .iter()
        .map(|&(rho, a)| [rho * a.cos() * MM, rho * a.sin() * MM])
        .collect()
}

/// Bounding box of points.
fn bounds(p: &[P2]) -> (P2, P2) {
    let (mut lo, mut hi) = (p[0], p[0]);
    for x in p {
        for i in 0..2 {
            lo[i] = lo[i].min(x[i]);
            hi[i] = hi[i].max(x[i]);
        }
    }
    (lo, hi)
}

/// Least squared distance from point `c` to a closed ring's edges.
fn squared_distance_to_ring(c: P2, ring: &[P2]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let l2 = d[0] * d[0] + d[1] * d[1];
            let t = if l2 > 0.0 {
                (((c[0] - a[0]) * d[0] + (c[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (x, y) = (a[0] + t * d[0] - c[0], a[1] + t * d[1] - c[1]);
            x * x + y * y
        })
        .fold(f64::INFINITY, f64::min)
}

/// Metres to the clipping's millimetres.
fn mm(p: P2) -> P2 {
    [p[0] * MM, p[1] * MM]
}

/// The points counter-clockwise (reversed if they were not).
fn ccw(mut pts: Vec<P2>) -> Vec<P2> {
    if signed_area(&pts) < 0.0 {
        pts.reverse();
    }
    pts
}

/// A polygon clipped to the convex polygon `region` (counter-clockwise),
/// one half-plane per side ([`clip_half_plane`]).
fn clip_convex(poly: &[P2], region: &[P2]) -> Vec<P2> {
    let mut a = poly.to_vec();
    let mut b = Vec::with_capacity(poly.len() + 8);
    for i in 0..region.len() {
        let (p, q) = (region[i], region[(i + 1) % region.len()]);
        // inward normal of a counter-clockwise side
        let n = [p[1] - q[1], q[0] - p[0]];
        if a.iter()
            .all(|x| n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]) >= 0.0)
        {
            continue; // wholly inside this side: the pass would copy it
        }
        clip_half_plane_into(&a, p, n, &mut b);
        std::mem::swap(&mut a, &mut b);
    }
    a
}

/// A convex polygon round the points `pts` (counter-clockwise) with at
/// least `margin / 2` between them: their convex hull, its vertices thinned
/// while a dropped vertex lies within `margin / 2` of the new side, its
/// sides then moved out by `margin`.
fn hull_with_margin(pts: &[P2], margin: f64) -> Vec<P2> {
    let mut sorted = pts.to_vec();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let cross = |o: P2, a: P2, b: P2| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    // Andrew's monotone chain
    let mut hull: Vec<P2> = Vec::with_capacity(2 * sorted.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &P2>> = if pass == 0 {
            Box::new(sorted.iter())
        } else {
            Box::new(sorted.iter().rev())
        };
        for &x in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], x) <= 0.0
            {
                hull.pop();
            }
            hull.push(x);
        }
        hull.pop();
    }
    // thin: drop vertices that stay close to the side that replaces them
    let dist = |a: P2, b: P2, x: P2| cross(a, b, x).abs() / (b[0] - a[0]).hypot(b[1] - a[1]);
    let mut thin = vec![hull[0]];
    let mut i = 0;
    while i + 1 < hull.len() {
        let mut j = i + 1;
        while j + 1 < hull.len()
            && (i + 1..=j).all(|m| dist(hull[i], hull[j + 1], hull[m]) < margin / 2.0)
        {
            j += 1;
        }
        thin.push(hull[j]);
        i = j;
    }
    // sides moved out: each vertex where its two moved sides meet
    let n = thin.len();
    let outward = |a: P2, b: P2| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = dx.hypot(dy);
        [dy / l, -dx / l]
    };
    (0..n)
        .map(|i| {
            let (prev, x, next) = (thin[(i + n - 1) % n], thin[i], thin[(i + 1) % n]);
            let (n1, n2) = (outward(prev, x), outward(x, next));
            let f = margin / (1.0 + n1[0] * n2[0] + n1[1] * n2[1]);
            [x[0] + f * (n1[0] + n2[0]), x[1] + f * (n1[1] + n2[1])]
        })
        .collect()
}

/// Is `x` inside (or on) the convex counter-clockwise polygon `region`?
fn convex_contains(region: &[P2], x: P2) -> bool {
    (0..region.len()).all(|i| {
        let (p, q) = (region[i], region[(i + 1) % region.len()]);
        (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0]) >= 0.0
    })
}

/// A polygon clipped to the box `lo..hi` ([`clip_half_plane`]).
fn clip_box(poly: &[P2], lo: P2, hi: P2) -> Vec<P2> {
    let mut a = Vec::with_capacity(poly.len() + 8);
    let mut b = Vec::with_capacity(poly.len() + 8);
    clip_half_plane_into(poly, lo, [1.0, 0.0], &mut a);
    clip_half_plane_into(&a, lo, [0.0, 1.0], &mut b);
    clip_half_plane_into(&b, hi, [-1.0, 0.0], &mut a);
    clip_half_plane_into(&a, hi, [0.0, -1.0], &mut b);
    b
}

/// Length of a closed ring (its last point joined to its first).
fn ring_length(p: &[P2]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .sum()
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
            f.rotate(k, phi - PI);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::Design;
    use geo::{Area, BooleanOps, MultiPolygon};

    /// The straightforward way to one section sample, kept as the reference
    /// of the fast one: whole polygons clipped one after the other (the
    /// space minus the mating gear's whole solid minus its whole region),
    /// groove overlaps by polygon intersection, loads by a probe at every
    /// edge through `Pair::solid_contains`.
    fn plain_sample(pair: &Pair, k: usize, phi: f64, grooves: &[Vec<P2>; 2]) -> SectionSample {
        let theta = pair.theta_for_space(k, phi);
        let off = pair.body_offset(k, theta);
        let poly = |pts: Vec<P2>| Polygon::new(ring(pts.into_iter()), vec![]);
        let g = &pair.gears[k];
        let space = poly(
            g.space_polar(0, NF, NA)
                .into_iter()
                .map(|(rho, a)| pair.local_to_global(k, rho, off + a))
                .collect(),
        );
        let (circle, p, n) = pair.foreign_region(k);
        let foreign = poly(clip_half_plane(&circle, p, n));
        let fluid: MultiPolygon<f64> = space
            .difference(&pair.solid_polygon(1 - k, theta))
            .difference(&foreign);
        let mut s = SectionSample {
            area: fluid.unsigned_area() / (MM * MM),
            ..Default::default()
        };
        for (gi, rect) in grooves.iter().enumerate() {
            let rect = poly(rect.iter().map(|x| [x[0] / MM, x[1] / MM]).collect());
            s.groove[gi] = fluid.intersection(&rect).unsigned_area() / (MM * MM);
        }
        for polygon in fluid.iter() {
            let rings = std::iter::once((polygon.exterior(), true))
                .chain(polygon.interiors().iter().map(|r| (r, false)));
            for (ring, exterior) in rings {
                let mut pts: Vec<P2> = ring.coords().map(|c| [c.x / MM, c.y / MM]).collect();
                pts.pop(); // the closing point
                s.perimeter += ring_length(&pts);
                let forward = (signed_area(&pts) > 0.0) == exterior;
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
                    let f = [d[1], -d[0]];
                    let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                    let probe = [m[0] + f[0] / len * 2e-6, m[1] + f[1] / len * 2e-6];
                    if let Some(gk) = (0..2).find(|&gk| pair.solid_contains(gk, theta, probe)) {
                        let c = pair.centre(gk);
                        s.force[gk][0] += f[0];
                        s.force[gk][1] += f[1];
                        s.torque[gk] += (m[0] - c[0]) * f[1] - (m[1] - c[1]) * f[0];
                    }
                }
            }
        }
        s
    }

    fn columns(s: &SectionSample) -> [f64; 10] {
        [
            s.area,
            s.perimeter,
            s.force[0][0],
            s.force[0][1],
            s.force[1][0],
            s.force[1][1],
            s.torque[0],
            s.torque[1],
            s.groove[0],
            s.groove[1],
        ]
    }

    /// Every sample of the seed pump's tables against the plain clipping of
    /// whole polygons: within 1e-6 of each column's largest value (the
    /// clipper's snapping leaves up to about 3e-7 on the loads of slivers;
    /// measured worst 2.5e-7, on a pocket's torque as it closes).
    #[test]
    fn fast_tables_match_a_plain_clipping_of_whole_polygons() {
        let d = Design::seed();
        let pair = d.pair();
        let c = &d.casing;
        let t = pair.section_tables(
            d.numerics.table_step,
            c.delivery_groove_edge,
            c.suction_groove_edge,
            c.groove_width,
        );
        let grooves = pair.grooves(
            c.delivery_groove_edge,
            c.suction_groove_edge,
            c.groove_width,
        );
        for k in 0..2 {
            let mut plain: Vec<[f64; 10]> = (0..t.samples[k].len())
                .map(|i| {
                    columns(&plain_sample(
                        &pair,
                        k,
                        t.phi0[k] + t.dphi[k] * i as f64,
                        &grooves,
                    ))
                })
                .collect();
            let mut fast: Vec<[f64; 10]> = t.samples[k].iter().map(columns).collect();
            // the free pocket too (turned copies stand for every sample nothing reaches)
            plain.push(columns(&plain_sample(&pair, k, PI, &grooves)));
            fast.push(columns(&t.free[k]));
            for col in 0..10 {
                let scale = plain.iter().map(|r| r[col].abs()).fold(0.0, f64::max);
                assert!(scale > 0.0, "gear {k} column {col} is all zero");
                for (i, (fast, plain)) in fast.iter().zip(&plain).enumerate() {
                    let diff = (fast[col] - plain[col]).abs() / scale;
                    assert!(
                        diff < 1e-6,
                        "gear {k} sample {i} column {col}: fast {} plain {} ({diff:.2e} of {scale:.3e})",
                        fast[col],
                        plain[col]
                    );
                }
            }
        }
    }

    /// The interfaces at every angle are exactly those of testing each
    /// boundary point with `Pair::solid_contains` and reading its spaces
    /// from its polar angles, point by point.
    #[test]
    fn interfaces_match_a_point_by_point_test_exactly() {
        let pair = Design::seed().pair();
        let ds = 2.0e-6;
        let boundary = pair.mesh_boundary(ds);
        let pieces = pair.boundary_pieces(ds);
        let z = [pair.gears[0].z, pair.gears[1].z];
        for i in 0..40 {
            let theta = pair.gears[0].pitch_angle() * i as f64 / 40.0;
            let mut runs: Vec<Interface> = Vec::new();
            for pts in &pieces {
                let mut current: Option<Interface> = None;
                for w in pts.windows(2) {
                    let x = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                    let length = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
                    if pair.solid_contains(0, theta, x) || pair.solid_contains(1, theta, x) {
                        runs.extend(current.take());
                        continue;
                    }
                    let space = [0, 1].map(|k| {
                        let body = pair.global_to_local(k, x).1 - pair.body_offset(k, theta);
                        let m = (body / pair.gears[k].pitch_angle()).floor() as i64;
                        m.rem_euclid(z[k] as i64) as usize
                    });
                    match &mut current {
                        Some(c) if c.space == space => c.length += length,
                        _ => {
                            runs.extend(current.take());
                            current = Some(Interface {
                                space,
                                length,
                                gap: length,
                            });
                        }
                    }
                }
                runs.extend(current.take());
            }
            let mut expected: Vec<Interface> = Vec::new();
            for r in runs {
                match expected.iter_mut().find(|e| e.space == r.space) {
                    Some(e) => e.length += r.length,
                    None => expected.push(r),
                }
            }
            let got = boundary.interfaces_at(&pair, theta);
            assert_eq!(
                got.len(),
                expected.len(),
                "theta {theta}: {got:?} vs {expected:?}"
            );
            assert!(
                !got.is_empty(),
                "theta {theta}: the mesh always has a passage"
            );
            for (g, e) in got.iter().zip(&expected) {
                assert_eq!(g.space, e.space, "theta {theta}");
                assert_eq!(g.length.to_bits(), e.length.to_bits(), "theta {theta}");
            }
        }
    }

    /// The shared-out map gives each result in its slot, on any number of
    /// threads.
    #[test]
    fn parallel_map_keeps_the_order_on_any_number_of_threads() {
        let serial: Vec<u64> = (0..1000u64).map(|i| i * i + 7).collect();
        for threads in [1, 2, 3, 8] {
            assert_eq!(
                parallel_map_on(threads, 1000, |i| (i as u64) * (i as u64) + 7),
                serial
            );
        }
        assert!(parallel_map_on(4, 0, |i| i).is_empty());
    }

    /// The tabulated flank decides every angle as the exact half tooth
    /// angle does, at and around the flank of both gears from root to tip.
    #[test]
    fn the_tabulated_flank_decides_as_the_exact_one() {
        let pair = Design::seed().pair();
        for g in &pair.gears {
            let table = FlankTable::new(g);
            // well inside the probes' 2 um offset, so the table decides
            // nearly every probe alone
            assert!(table.bound * g.ra < 0.2e-6, "bound {}", table.bound);
            for i in 0..=20000 {
                let rho = g.rf + (g.ra - g.rf) * i as f64 / 20000.0;
                let h = g.half_angle(rho);
                for d in [-1e-5, -1e-7, -1e-9, -1e-12, 0.0, 1e-12, 1e-9, 1e-7, 1e-5] {
                    let a = (h + d).max(0.0);
                    assert_eq!(table.within(g, rho, a), a <= h, "rho {rho} a {a} h {h}");
                }
            }
        }
    }

    /// Cheap roundings used by the tooth tests agree with the library's
    /// away from ties, and floor is exact.
    #[test]
    fn cheap_roundings_agree_with_the_library() {
        use super::super::gear::{floor_exact, nearest_integer};
        for i in -20000..20000 {
            let x = i as f64 * 0.000731 + 0.0001;
            if x.fract().abs() != 0.5 {
                // ties go to even, where the tooth test does not care
                assert_eq!(nearest_integer(x), x.round(), "{x}");
            }
            assert_eq!(floor_exact(x), x.floor(), "{x}");
        }
        for x in [-3.0, -1.0, 0.0, 2.0, 1e15, -1e15] {
            assert_eq!(floor_exact(x), x);
        }
    }
}
