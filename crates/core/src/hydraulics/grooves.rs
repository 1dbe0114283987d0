//! Does a relief-groove layout bridge the ports? A pocket (or a fluid region
//! of the meshing zone: pockets of both gears joined by an open passage)
//! that overlaps the delivery groove and the suction groove at the same
//! angle short-circuits the outlet to the inlet through the trapped volume.
//! The default layout (`design::relief_groove_edge`) never does; a layout
//! given by hand is checked here, on the mid-face section on which the
//! grooves are evaluated (`hydraulics::steps`).

use crate::design::Casing;
use crate::geometry::pair::Pair;
use crate::geometry::tables::SectionTables;

/// Overlap below which a groove is taken as not touching a region, m^2
/// (1e-4 mm^2: a contact closing on a groove edge).
const TOUCH_AREA: f64 = 1.0e-10;
/// Passage length below which two pockets are taken as separated, m (a
/// closing contact).
const OPEN_PASSAGE: f64 = 1.0e-6;

/// The angles at which a region touches both grooves, and what that costs.
#[derive(Debug, Clone, PartialEq)]
pub struct GrooveBridge {
    /// Driving-gear angles within the mesh period (from the period's start)
    /// over which a region touches both grooves, deg: (first, last) of each
    /// run of bridged samples.
    pub ranges_deg: Vec<(f64, f64)>,
    /// Fraction of the mesh period bridged.
    pub period_fraction: f64,
    /// Mean over the mesh period of the bridge's effective orifice area
    /// (delivery and suction groove passages in series, both plates), m^2.
    pub mean_cda: f64,
}

impl GrooveBridge {
    /// The flow the bridge passes at a pressure difference `dp` (Pa) and
    /// oil density `rho` (kg/m^3), m^3/s (orifice law, seed Eq. 11; the
    /// meshing-zone passages on the way are not counted, so an upper
    /// estimate).
    pub fn flow(&self, dp: f64, rho: f64) -> f64 {
        self.mean_cda * (2.0 * dp.max(0.0) / rho).sqrt()
    }
}

/// Checks the groove layout of `sec` (built with the casing's grooves) over
/// one mesh period; None when no region touches both grooves at any angle.
pub fn groove_bridge(pair: &Pair, sec: &SectionTables, casing: &Casing) -> Option<GrooveBridge> {
    let z = [pair.gears[0].z, pair.gears[1].z];
    let np = z[0] + z[1];
    let section = casing.groove_width * casing.groove_depth;
    // a groove overlap's orifice area, limited by the groove's own section
    let eff = |a: f64| {
        if a <= 0.0 || section <= 0.0 {
            0.0
        } else {
            1.0 / (1.0 / (a * a) + 1.0 / (section * section)).sqrt()
        }
    };
    let n = sec.interfaces.len();
    let mut bridged = vec![false; n];
    let mut cda_sum = 0.0;
    for (i, itfs) in sec.interfaces.iter().enumerate() {
        let theta = i as f64 * sec.dtheta_if;
        let mut parent: Vec<usize> = (0..np).collect();
        fn root(p: &[usize], mut x: usize) -> usize {
            while p[x] != x {
                x = p[x];
            }
            x
        }
        for itf in itfs.iter().filter(|f| f.length > OPEN_PASSAGE) {
            let (a, b) = (
                root(&parent, itf.space[0]),
                root(&parent, z[0] + itf.space[1]),
            );
            parent[a] = b;
        }
        let mut touch = vec![[0.0f64; 2]; np];
        for k in 0..2 {
            for m in 0..z[k] {
                let idx = if k == 0 { m } else { z[0] + m };
                let s = sec.sample(k, pair.space_centre(k, m, theta));
                let r = root(&parent, idx);
                touch[r][0] += s.groove[0];
                touch[r][1] += s.groove[1];
            }
        }
        let mut worst: f64 = 0.0;
        for t in touch
            .iter()
            .filter(|t| t[0] > TOUCH_AREA && t[1] > TOUCH_AREA)
        {
            // both plates, each groove's passage; the two in series
            let (d, s) = (2.0 * eff(t[0]), 2.0 * eff(t[1]));
            worst = worst.max(casing.groove_cd / (1.0 / (d * d) + 1.0 / (s * s)).sqrt());
            bridged[i] = true;
        }
        cda_sum += worst;
    }
    if !bridged.contains(&true) {
        return None;
    }
    let mut ranges_deg = Vec::new();
    let mut i = 0;
    while i < n {
        if bridged[i] {
            let start = i;
            while i + 1 < n && bridged[i + 1] {
                i += 1;
            }
            let deg = |j: usize| (j as f64 * sec.dtheta_if).to_degrees();
            ranges_deg.push((deg(start), deg(i)));
        }
        i += 1;
    }
    Some(GrooveBridge {
        ranges_deg,
        period_fraction: bridged.iter().filter(|&&b| b).count() as f64 / n as f64,
        mean_cda: cda_sum / n as f64,
    })
}

#[cfg(test)]
mod tests {
    use crate::design::Design;
    use crate::model::Pump;

    fn with_edges(edge_mm: f64) -> Pump {
        let d = crate::design::from_toml_str(
            crate::design::SEED_PUMP_TOML,
            &[
                format!("casing.delivery_groove_edge_mm={edge_mm}"),
                format!("casing.suction_groove_edge_mm={edge_mm}"),
            ],
        )
        .expect("seed design with edges");
        Pump::new(d)
    }

    #[test]
    fn the_default_layout_never_bridges_the_ports() {
        let pump = Pump::new(Design::seed());
        let c = &pump.design.casing;
        // the rule: pbt cos(alpha_w) / 2 each side of the pitch point
        let pbt = pump.pair.gears[0].rb * 2.0 * std::f64::consts::PI / 14.0;
        let want = 0.5 * pbt * pump.pair.alpha_w.cos();
        assert!((c.delivery_groove_edge - want).abs() < 1e-12);
        assert!((c.suction_groove_edge - want).abs() < 1e-12);
        assert_eq!(pump.groove_bridge, None);
    }

    #[test]
    fn a_narrow_band_bridges_through_the_trapped_volume() {
        // 1.5 mm each side: the trapped volume (contacts about 3 mm either
        // side of the pitch point) touches both grooves in double contact
        let pump = with_edges(1.5);
        let b = pump.groove_bridge.as_ref().expect("1.5 mm bridges");
        assert!(b.period_fraction > 0.1 && b.period_fraction < 0.5, "{b:?}");
        assert!(!b.ranges_deg.is_empty());
        // a wide band does not
        assert_eq!(with_edges(3.5).groove_bridge, None);
    }
}
