//! `dirac`: two fixed points alternating between the principal axes.

use super::*;

/// `dirac`: two fixed points ±√(2λ) along one principal axis, alternating axes from slab to slab
/// (two slabs together have covariance 2Σκ: a non-randomized pattern, as in the paper's fig. 3).
pub(crate) fn dirac_pattern(l1: f64, l2: f64, e1: [f64; 2]) -> Pattern {
    let to_pixels = principal_to_pixels(e1);
    let a = (2.0 * l1).sqrt();
    let b = (2.0 * l2).sqrt();
    vec![
        vec![(to_pixels(a, 0.0), 0.5), (to_pixels(-a, 0.0), 0.5)],
        vec![(to_pixels(0.0, b), 0.5), (to_pixels(0.0, -b), 0.5)],
    ]
}
