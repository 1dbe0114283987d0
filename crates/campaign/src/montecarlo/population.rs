//! The clearance population of a Monte Carlo study: one distribution per
//! clearance (tip driving, tip driven, bearing driving, bearing driven),
//! drawn independently, and the counter-based draw of pump `i`.
//!
//! # Where the distributions come from
//! * **paper** (default): the seed paper's clearance statistics as `synth`
//!   uses them ([`crate::synth::SEED_CLEARANCE_STATS`]): normal with mean
//!   `h_d (1 + m_k)` and standard deviation `0.06 h_d` around the design's
//!   clearance `h_d`.
//! * **fitted** from a measured campaign CSV: each clearance normal with the
//!   mean and sample standard deviation (divisor n - 1) of the campaign's
//!   pumps (one value per sample id, the first row of each; at least two
//!   pumps).
//! * **a TOML file** of the user's: a table per clearance, named
//!   `tip1_um`, `tip2_um`, `bearing1_um`, `bearing2_um`, with
//!   `dist = "normal"` (`mean`, `std`), `"uniform"` (`low`, `high`) or
//!   `"fixed"` (`value`), all in um; a clearance the file does not name
//!   keeps the paper's distribution. Unknown tables or keys are refused.
//!
//! The clearances are drawn independently (the sensitivity indices assume
//! it; the seed reports no correlation). A normal draw outside the model's
//! clearance range ([`gearpump_core::limits::CLEARANCE_UM`]) or below 10 %
//! of its mean is drawn again (the truncation `synth` applies; with the
//! paper's 6 % spread it is more than 15 standard deviations out).
//!
//! # Reproducible draws, any chunk independently
//! Pump `i` of seed `s` is drawn from its own ChaCha8 stream: the generator
//! seeded with `s` and set to stream `i` (ChaCha's 64-bit stream number, a
//! counter-based, portable generator fixed by its specification), four
//! draws in the order above. So pump 7 is the same whether it is drawn
//! alone, in a chunk on another machine or in the whole study.

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;

use super::MonteCarloError;
use crate::data::Campaign;
use crate::synth::SEED_CLEARANCE_STATS;
use gearpump_core::design::Design;
use gearpump_core::limits::CLEARANCE_UM;
use gearpump_core::units::m_to_um;

/// The clearances' names (also the batch columns of the Python package).
pub const CLEARANCES: [&str; 4] = ["tip1_um", "tip2_um", "bearing1_um", "bearing2_um"];

/// One clearance's distribution, um.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "dist", rename_all = "lowercase")]
pub enum Dist {
    Normal { mean: f64, std: f64 },
    Uniform { low: f64, high: f64 },
    Fixed { value: f64 },
}

impl Dist {
    /// Refuses parameters outside the clearance range or absurd ones.
    fn check(&self, name: &str) -> Result<(), String> {
        let inside = |what: &str, v: f64| -> Result<(), String> {
            if (CLEARANCE_UM.min..=CLEARANCE_UM.max).contains(&v) {
                Ok(())
            } else {
                Err(format!(
                    "{name}: {what} = {v} um is outside [{}, {}] um ({})",
                    CLEARANCE_UM.min, CLEARANCE_UM.max, CLEARANCE_UM.reason
                ))
            }
        };
        match *self {
            Dist::Normal { mean, std } => {
                inside("mean", mean)?;
                if !(std.is_finite() && std >= 0.0 && std <= 0.5 * mean) {
                    return Err(format!(
                        "{name}: std = {std} um must be >= 0 and at most half the mean ({mean} um)"
                    ));
                }
                Ok(())
            }
            Dist::Uniform { low, high } => {
                inside("low", low)?;
                inside("high", high)?;
                if low >= high {
                    return Err(format!(
                        "{name}: low = {low} um must be below high = {high} um"
                    ));
                }
                Ok(())
            }
            Dist::Fixed { value } => inside("value", value),
        }
    }

    /// One draw (see the module doc for the truncation).
    fn sample(&self, rng: &mut ChaCha8Rng) -> f64 {
        match *self {
            Dist::Normal { mean, std } => loop {
                let z: f64 = StandardNormal.sample(rng);
                let x = mean + std * z;
                if x > 0.1 * mean && (CLEARANCE_UM.min..=CLEARANCE_UM.max).contains(&x) {
                    break x;
                }
            },
            Dist::Uniform { low, high } => rng.gen_range(low..high),
            Dist::Fixed { value } => value,
        }
    }

    /// The variance of the distribution (before truncation).
    pub fn variance(&self) -> f64 {
        match *self {
            Dist::Normal { std, .. } => std * std,
            Dist::Uniform { low, high } => (high - low).powi(2) / 12.0,
            Dist::Fixed { .. } => 0.0,
        }
    }
}

/// The four clearances' distributions and where they came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Population {
    /// In the order of [`CLEARANCES`].
    pub dists: [Dist; 4],
    /// `paper`, `fitted to FILE` or the TOML file's path.
    pub source: String,
}

fn nominal_um(design: &Design) -> [f64; 4] {
    let c = &design.clearance;
    [
        m_to_um(c.tip[0]),
        m_to_um(c.tip[1]),
        m_to_um(c.bearing[0]),
        m_to_um(c.bearing[1]),
    ]
}

impl Population {
    /// The seed paper's statistics around the design's clearances.
    pub fn paper(design: &Design) -> Population {
        let h = nominal_um(design);
        let s = SEED_CLEARANCE_STATS;
        Population {
            dists: [0, 1, 2, 3].map(|k| Dist::Normal {
                mean: h[k] * (1.0 + s.mean[k]),
                std: h[k] * s.std[k],
            }),
            source: "paper".into(),
        }
    }

    /// Normal distributions fitted to a measured campaign's pumps.
    pub fn fitted(campaign: &Campaign) -> Result<Population, MonteCarloError> {
        let mut seen = std::collections::BTreeSet::new();
        let mut cols: [Vec<f64>; 4] = Default::default();
        for r in &campaign.rows {
            if seen.insert(r.sample.as_str()) {
                for (k, v) in r
                    .tip_clearance
                    .iter()
                    .chain(&r.bearing_clearance)
                    .enumerate()
                {
                    cols[k].push(m_to_um(*v));
                }
            }
        }
        let bad = |message: String| MonteCarloError::Population {
            file: campaign.file.clone(),
            message,
        };
        if seen.len() < 2 {
            return Err(bad(format!(
                "a fitted population needs at least two pumps, the campaign has {}",
                seen.len()
            )));
        }
        let mut dists = [Dist::Fixed { value: 0.0 }; 4];
        for k in 0..4 {
            let (m, s) = super::estimators::mean_std(&cols[k]);
            let (mean, std) = (m.unwrap_or(f64::NAN), s.unwrap_or(f64::NAN));
            dists[k] = Dist::Normal { mean, std };
            dists[k].check(CLEARANCES[k]).map_err(bad)?;
        }
        Ok(Population {
            dists,
            source: format!("fitted to {}", campaign.file),
        })
    }

    /// The distributions of a TOML text (module doc); unnamed clearances
    /// keep the paper's.
    pub fn from_toml_str(
        design: &Design,
        file: &str,
        text: &str,
    ) -> Result<Population, MonteCarloError> {
        let bad = |message: String| MonteCarloError::Population {
            file: file.to_string(),
            message,
        };
        let root: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let (line, column) = e.span().map_or((0, 0), |s| {
                gearpump_core::design::line_column(text, s.start)
            });
            bad(format!(
                "line {line}, column {column}: {}",
                e.message().trim().replace('\n', "; ")
            ))
        })?;
        let mut pop = Population::paper(design);
        pop.source = file.to_string();
        for (name, v) in &root {
            let Some(k) = CLEARANCES.iter().position(|c| c == name) else {
                return Err(bad(format!(
                    "unknown table [{name}] (known: {})",
                    CLEARANCES.join(", ")
                )));
            };
            let t = v
                .as_table()
                .ok_or_else(|| bad(format!("{name}: expected a table [{name}]")))?;
            let kind = t.get("dist").and_then(|d| d.as_str()).ok_or_else(|| {
                bad(format!(
                    "{name}: missing dist = \"normal\" | \"uniform\" | \"fixed\""
                ))
            })?;
            let keys: &[&str] = match kind {
                "normal" => &["mean", "std"],
                "uniform" => &["low", "high"],
                "fixed" => &["value"],
                other => {
                    return Err(bad(format!(
                        "{name}: unknown dist {other:?} (normal, uniform or fixed)"
                    )))
                }
            };
            for key in t.keys() {
                if key != "dist" && !keys.contains(&key.as_str()) {
                    return Err(bad(format!(
                        "{name}: unknown key {key:?} for dist = {kind:?} (expected {})",
                        keys.join(", ")
                    )));
                }
            }
            let num = |key: &str| -> Result<f64, MonteCarloError> {
                match t.get(key) {
                    Some(toml::Value::Float(x)) => Ok(*x),
                    Some(toml::Value::Integer(i)) => Ok(*i as f64),
                    Some(other) => Err(bad(format!(
                        "{name}.{key}: expected a number in um, got {other}"
                    ))),
                    None => Err(bad(format!("{name}: missing {key} (um)"))),
                }
            };
            let d = match kind {
                "normal" => Dist::Normal {
                    mean: num("mean")?,
                    std: num("std")?,
                },
                "uniform" => Dist::Uniform {
                    low: num("low")?,
                    high: num("high")?,
                },
                _ => Dist::Fixed {
                    value: num("value")?,
                },
            };
            d.check(name).map_err(bad)?;
            pop.dists[k] = d;
        }
        Ok(pop)
    }

    /// [`Population::from_toml_str`] of a file.
    pub fn from_toml_file(design: &Design, path: &Path) -> Result<Population, MonteCarloError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| MonteCarloError::Population {
            file: file.clone(),
            message: e.to_string(),
        })?;
        Population::from_toml_str(design, &file, &text)
    }

    /// Pump `i`'s four clearances, um, for `seed` (module doc).
    pub fn draw(&self, seed: u64, i: u64) -> [f64; 4] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(i);
        self.dists.map(|d| d.sample(&mut rng))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pump_is_drawn_alike_alone_or_among_others() {
        let pop = Population::paper(&Design::seed());
        let all: Vec<[f64; 4]> = (0..50).map(|i| pop.draw(9, i)).collect();
        assert_eq!(pop.draw(9, 37), all[37]);
        assert_ne!(pop.draw(10, 37), all[37]);
        assert_ne!(all[36], all[37]);
        // the paper's statistics (mean 1 + m_k, std 0.06 of nominal)
        let h = nominal_um(&Design::seed());
        let n = 4000;
        for (k, hk) in h.iter().enumerate() {
            let x: Vec<f64> = (0..n).map(|i| pop.draw(1, i)[k] / hk - 1.0).collect();
            let (m, s) = crate::montecarlo::estimators::mean_std(&x);
            assert!(
                (m.unwrap() - SEED_CLEARANCE_STATS.mean[k]).abs() < 0.005,
                "{k}"
            );
            assert!((s.unwrap() - 0.06).abs() < 0.005, "{k}");
        }
    }

    #[test]
    fn toml_distributions_and_their_refusals() {
        let d = Design::seed();
        let p = Population::from_toml_str(
            &d,
            "p.toml",
            "[tip1_um]\ndist = \"uniform\"\nlow = 20\nhigh = 30.5\n[bearing2_um]\ndist = \"fixed\"\nvalue = 12\n",
        )
        .unwrap();
        assert_eq!(
            p.dists[0],
            Dist::Uniform {
                low: 20.0,
                high: 30.5
            }
        );
        assert_eq!(p.dists[3], Dist::Fixed { value: 12.0 });
        assert_eq!(p.dists[1], Population::paper(&d).dists[1]);
        for x in (0..200).map(|i| p.draw(4, i)) {
            assert!((20.0..30.5).contains(&x[0]) && x[3] == 12.0);
        }
        for (text, says) in [
            (
                "[tip3_um]\ndist = \"fixed\"\nvalue = 1\n",
                "unknown table [tip3_um]",
            ),
            ("[tip1_um]\ndist = \"gamma\"\n", "unknown dist \"gamma\""),
            (
                "[tip1_um]\ndist = \"normal\"\nmean = 30\n",
                "tip1_um: missing std",
            ),
            (
                "[tip1_um]\ndist = \"normal\"\nmean = 30\nstd = -1\n",
                "std = -1 um",
            ),
            (
                "[tip1_um]\ndist = \"normal\"\nmean = 3e6\nstd = 1\n",
                "mean = 3000000 um is outside",
            ),
            (
                "[tip1_um]\ndist = \"uniform\"\nlow = 30\nhigh = 20\n",
                "must be below high",
            ),
            (
                "[tip1_um]\ndist = \"fixed\"\nvalue = \"a\"\n",
                "tip1_um.value: expected a number",
            ),
            (
                "[tip1_um]\ndist = \"fixed\"\nvalue = 3\nmean = 2\n",
                "unknown key \"mean\"",
            ),
            ("tip1_um = 3\n", "expected a table"),
            ("[tip1_um\n", "p.toml"),
        ] {
            let e = Population::from_toml_str(&d, "p.toml", text)
                .unwrap_err()
                .to_string();
            assert!(e.contains(says) && e.starts_with("p.toml"), "{text}: {e}");
        }
    }
}
