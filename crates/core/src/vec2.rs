//! Plane vectors as `[f64; 2]` or `(x, y)`: what the hydraulics, the
//! mechanics and the predictor share, below all of them.

/// The length of the vector (x, y). Unlike `f64::hypot` it does not guard
/// against overflow and underflow of the squares, which the forces (N),
/// offsets (m) and ratios it measures are far from, at a third of the
/// cost (it is on every angular step's micromotion path).
#[inline]
pub fn norm(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}
