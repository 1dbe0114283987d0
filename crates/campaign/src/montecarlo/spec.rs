//! A production specification: limits on a quantity at an operating point.
//!
//! # Syntax
//! `QUANTITY OP VALUE @ SPEED rpm, PRESSURE bar, TEMP degC`, e.g.
//! `eta_v>=0.85@500rpm,30bar,120degC` (spaces anywhere are ignored; the
//! three parts of the condition in any order, each with its unit).
//! `QUANTITY` is `eta_v`, `flow_lpm` (l/min) or `torque_nm` (N m); `OP` one
//! of `>=`, `<=`, `>`, `<`. Several specs make one specification: a pump
//! meets it when it meets every one (a pump whose simulation failed at a
//! spec's condition does not). A spec's condition is added to the study's
//! conditions when they lack it.

use serde::Serialize;

use super::Quantity;
use crate::data::Condition;

/// The comparison of a spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Op {
    #[serde(rename = ">=")]
    Ge,
    #[serde(rename = "<=")]
    Le,
    #[serde(rename = ">")]
    Gt,
    #[serde(rename = "<")]
    Lt,
}

impl Op {
    pub fn holds(self, x: f64, limit: f64) -> bool {
        match self {
            Op::Ge => x >= limit,
            Op::Le => x <= limit,
            Op::Gt => x > limit,
            Op::Lt => x < limit,
        }
    }
}

/// One limit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spec {
    /// As written by the user (spaces removed).
    pub text: String,
    pub quantity: Quantity,
    pub op: Op,
    pub limit: f64,
    pub condition: Condition,
}

impl Spec {
    /// Parses the syntax of the module doc; the error names what is wrong.
    pub fn parse(text: &str) -> Result<Spec, String> {
        let t: String = text.chars().filter(|c| !c.is_whitespace()).collect();
        let syntax = "expected QUANTITY>=VALUE@SPEEDrpm,PRESSUREbar,TEMPdegC, e.g. eta_v>=0.85@500rpm,30bar,120degC";
        let (lhs, cond) = t
            .split_once('@')
            .ok_or_else(|| format!("`{t}`: no `@` before the condition ({syntax})"))?;
        let (pos, op, width) = [(">=", Op::Ge), ("<=", Op::Le), (">", Op::Gt), ("<", Op::Lt)]
            .iter()
            .find_map(|(s, op)| lhs.find(s).map(|p| (p, *op, s.len())))
            .ok_or_else(|| format!("`{t}`: no comparison (>=, <=, >, <) ({syntax})"))?;
        let name = &lhs[..pos];
        let quantity = Quantity::from_name(name).ok_or_else(|| {
            format!("`{t}`: unknown quantity `{name}` (eta_v, flow_lpm or torque_nm)")
        })?;
        let value = &lhs[pos + width..];
        let limit: f64 = value
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite())
            .ok_or_else(|| format!("`{t}`: limit `{value}` is not a finite number"))?;
        let mut speed = None;
        let mut pressure = None;
        let mut temp = None;
        for part in cond.split(',') {
            let lower = part.to_ascii_lowercase();
            let (slot, unit, what) = if lower.ends_with("rpm") {
                (&mut speed, 3, "speed")
            } else if lower.ends_with("degc") {
                (&mut temp, 4, "temperature")
            } else if lower.ends_with("bar") {
                (&mut pressure, 3, "pressure")
            } else {
                return Err(format!(
                    "`{t}`: condition part `{part}` has no unit (rpm, bar or degC)"
                ));
            };
            let num = &part[..part.len() - unit];
            let v: f64 = num
                .parse()
                .ok()
                .filter(|x: &f64| x.is_finite())
                .ok_or_else(|| format!("`{t}`: {what} `{num}` is not a finite number"))?;
            if slot.replace(v).is_some() {
                return Err(format!("`{t}`: the {what} is given twice"));
            }
        }
        let missing = |v: Option<f64>, what: &str| {
            v.ok_or_else(|| format!("`{t}`: the condition lacks the {what} ({syntax})"))
        };
        let condition = Condition {
            speed_rpm: missing(speed, "speed (rpm)")?,
            pressure_bar: missing(pressure, "pressure (bar)")?,
            temp_c: missing(temp, "temperature (degC)")?,
        };
        Ok(Spec {
            text: t,
            quantity,
            op,
            limit,
            condition,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_bad_ones_are_named() {
        let s = Spec::parse(" eta_v >= 0.85 @ 500 rpm, 30 bar, 120 degC").unwrap();
        assert_eq!(s.text, "eta_v>=0.85@500rpm,30bar,120degC");
        assert_eq!((s.quantity, s.op, s.limit), (Quantity::EtaV, Op::Ge, 0.85));
        assert_eq!(
            s.condition,
            Condition {
                pressure_bar: 30.0,
                speed_rpm: 500.0,
                temp_c: 120.0
            }
        );
        let s = Spec::parse("torque_nm<8.5@60degC,1000rpm,30bar").unwrap();
        assert_eq!(
            (s.quantity, s.op, s.limit),
            (Quantity::TorqueNm, Op::Lt, 8.5)
        );
        assert!(Op::Ge.holds(0.85, 0.85) && !Op::Gt.holds(0.85, 0.85));
        for (bad, says) in [
            ("eta_v>=0.85", "no `@`"),
            ("eta_v=0.85@500rpm,30bar,120degC", "no comparison"),
            ("eta>=0.85@500rpm,30bar,120degC", "unknown quantity `eta`"),
            ("eta_v>=x@500rpm,30bar,120degC", "limit `x`"),
            ("eta_v>=0.8@500,30bar,120degC", "part `500` has no unit"),
            ("eta_v>=0.8@500rpm,30bar", "lacks the temperature"),
            (
                "eta_v>=0.8@500rpm,30bar,1degC,2degC",
                "temperature is given twice",
            ),
            ("eta_v>=0.8@fastrpm,30bar,120degC", "speed `fast`"),
        ] {
            let e = Spec::parse(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
