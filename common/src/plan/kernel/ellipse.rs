//! `ellipseN`: N points equally spaced in arc length on an ellipse.

use std::collections::HashMap;
use std::f64::consts::PI;
use std::hash::Hash;
use std::sync::{Arc, Mutex, OnceLock};

use wide::f64x4;

use super::*;

/// `(sin t, cos t)` at the midpoints of equal angle steps, computed once per process: the moment
/// integrals and the arc-length tables below are built for every light and every bisection
/// step, and their `sin_cos` calls dominated building the plan. Each table keeps its loop's own
/// expression for `t`, so the values are the same bits as computing them in place.
fn moment_sin_cos() -> &'static [(f64, f64)] {
    static TABLE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..MOMENT_STEPS)
            .map(|i| ((i as f64 + 0.5) * 2.0 * PI / MOMENT_STEPS as f64).sin_cos())
            .collect()
    })
}

/// [`moment_sin_cos`] for the arc-length table of [`ellipse_point_sets`].
fn arc_sin_cos() -> &'static [(f64, f64)] {
    static TABLE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let dt = 2.0 * PI / ARC_STEPS as f64;
        (0..ARC_STEPS)
            .map(|i| ((i as f64 + 0.5) * dt).sin_cos())
            .collect()
    })
}

/// Angle steps of [`ellipse_second_moments`].
const MOMENT_STEPS: usize = 4096;
/// Angle steps of the arc-length table of [`ellipse_point_sets`].
const ARC_STEPS: usize = 8192;

/// Arc-length statistics of an ellipse with semi-axes (1, r): (∮x² ds, ∮y² ds, L), by the
/// midpoint rule in the angle parameter (the integrand is smooth and periodic: converges fast).
pub(crate) fn ellipse_second_moments(r: f64) -> (f64, f64, f64) {
    const STEPS: usize = MOMENT_STEPS;
    let (mut sx, mut sy, mut len) = (0.0, 0.0, 0.0);
    let rr = f64x4::splat(r * r);
    // Four steps' terms at once, each in the one-step expression's order (products left to
    // right, one correctly rounded square root); the sums still add them one step at a time, so
    // every bit is the one-step loop's (`moments_by_lanes_are_the_bits_of_one_step_at_a_time`).
    // The plan evaluates this integral thousands of times; the square roots bounded it.
    for &(s, c) in moment_lanes() {
        let ds = (s * s + rr * c * c).sqrt();
        let (tx, ty) = ((c * c * ds).to_array(), (rr * s * s * ds).to_array());
        for (k, ds) in ds.to_array().into_iter().enumerate() {
            sx += tx[k];
            sy += ty[k];
            len += ds;
        }
    }
    (sx / len, sy / len, len * 2.0 * PI / STEPS as f64)
}

/// [`moment_sin_cos`] four steps to a lane vector (see [`by_fours`]).
fn moment_lanes() -> &'static [(f64x4, f64x4)] {
    static TABLE: OnceLock<Vec<(f64x4, f64x4)>> = OnceLock::new();
    TABLE.get_or_init(|| by_fours(moment_sin_cos()))
}

/// [`arc_sin_cos`] four steps to a lane vector (see [`by_fours`]).
fn arc_lanes() -> &'static [(f64x4, f64x4)] {
    static TABLE: OnceLock<Vec<(f64x4, f64x4)>> = OnceLock::new();
    TABLE.get_or_init(|| by_fours(arc_sin_cos()))
}

/// A `(sin, cos)` table as lane vectors: entry i holds steps 4i..4i + 4 ([`lanes_of_four`]).
fn by_fours(table: &[(f64, f64)]) -> Vec<(f64x4, f64x4)> {
    assert!(table.len().is_multiple_of(4), "whole lane vectors of steps");
    let (sin, cos): (Vec<f64>, Vec<f64>) = table.iter().copied().unzip();
    lanes_of_four(&sin)
        .into_iter()
        .zip(lanes_of_four(&cos))
        .collect()
}

/// [`ellipse_second_moments`] one step at a time: the plain loop its lanes must reproduce.
#[cfg(test)]
pub(crate) fn ellipse_second_moments_by_steps(r: f64) -> (f64, f64, f64) {
    let (mut sx, mut sy, mut len) = (0.0, 0.0, 0.0);
    for &(s, c) in moment_sin_cos() {
        let ds = (s * s + r * r * c * c).sqrt();
        sx += c * c * ds;
        sy += r * r * s * s * ds;
        len += ds;
    }
    (sx / len, sy / len, len * 2.0 * PI / MOMENT_STEPS as f64)
}

/// A process-wide memo of a pure function of the key, which starts afresh at `capacity` entries.
/// A remembered value is the one computed, so every bit is the same whichever thread computed it
/// first (or whether it was remembered at all).
struct Remembered<K, V> {
    seen: OnceLock<Mutex<HashMap<K, V>>>,
    capacity: usize,
}

impl<K: Eq + Hash + Copy, V: Clone> Remembered<K, V> {
    const fn new(capacity: usize) -> Self {
        Remembered {
            seen: OnceLock::new(),
            capacity,
        }
    }

    /// The value of `key`, computed by `compute` unless remembered.
    fn get_or(&self, key: K, compute: impl FnOnce() -> V) -> V {
        let seen = self.seen.get_or_init(Default::default);
        // A panic elsewhere while the lock was held cannot leave a wrong entry (an insert is
        // whole).
        let lock = || seen.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(value) = lock().get(&key) {
            return value.clone();
        }
        let value = compute();
        let mut seen = lock();
        if seen.len() >= self.capacity {
            seen.clear();
        }
        seen.insert(key, value.clone());
        value
    }
}

/// [`ellipse_second_moments`] by the axis ratio's bits: the bisections of
/// [`ellipse_ratio_for_variance_ratio`] for nearby ratios walk the same first steps, and a plan
/// asks for many nearby ratios (every light and level of the distance penumbra, every round of
/// compensation): a 64×64 default-scene plan needs about 600 distinct integrals of the 6120 its
/// bisections evaluate (estimated from the ratios it found).
static MOMENTS: Remembered<u64, (f64, f64, f64)> = Remembered::new(1 << 16);

/// [`unit_phases`] by the axis ratio's bits and the point count: most of a plan's ellipse
/// patterns share one axis ratio (81 of the 102 a small default-scene plan built).
static UNIT_PHASES: Remembered<(u64, usize), Arc<UnitPhases>> = Remembered::new(1 << 10);

/// The phases of `ellipseN` on the ellipse with semi-axes (1, r) before scaling, and their
/// points' Σx² and Σy².
struct UnitPhases {
    phases: Vec<Vec<[f64; 2]>>,
    sum_x2: f64,
    sum_y2: f64,
}

/// [`UnitPhases`] of `n` points per phase on the ellipse with semi-axes (1, r).
fn unit_phases(r: f64, n: usize) -> Arc<UnitPhases> {
    UNIT_PHASES.get_or((r.to_bits(), n), || {
        let starts: Vec<f64> = (0..PHASES)
            .map(|p| p as f64 / (PHASES * n) as f64)
            .collect();
        let phases = ellipse_point_sets(1.0, r, &starts, n);
        let (mut sum_x2, mut sum_y2) = (0.0, 0.0);
        for pts in &phases {
            for q in pts {
                sum_x2 += q[0] * q[0];
                sum_y2 += q[1] * q[1];
            }
        }
        Arc::new(UnitPhases {
            phases,
            sum_x2,
            sum_y2,
        })
    })
}

/// The axis ratio r ∈ [0, 1] whose arc-length-uniform point set has Vy/Vx = `ratio` (≤ 1).
pub fn ellipse_ratio_for_variance_ratio(ratio: f64) -> f64 {
    if ratio <= 0.0 {
        return 0.0;
    }
    if ratio >= 1.0 {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let (vx, vy, _) = MOMENTS.get_or(mid.to_bits(), || ellipse_second_moments(mid));
        if vy / vx < ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Points equally spaced in arc length on an ellipse with semi-axes (a, b), starting at
/// arc-length fraction `start` (of the whole circumference), `count` points.
#[cfg(test)]
pub(crate) fn ellipse_points(a: f64, b: f64, start: f64, count: usize) -> Vec<[f64; 2]> {
    ellipse_point_sets(a, b, &[start], count).remove(0)
}

/// [`ellipse_points`] for several start fractions, sharing one arc-length table (the angle
/// samples' `sin_cos` come from a table computed once).
pub(crate) fn ellipse_point_sets(
    a: f64,
    b: f64,
    starts: &[f64],
    count: usize,
) -> Vec<Vec<[f64; 2]>> {
    const STEPS: usize = ARC_STEPS;
    let dt = 2.0 * PI / STEPS as f64;
    let cum = cumulative_arc(a, b);
    let total = cum[STEPS];
    let points_from = |start: f64| -> Vec<[f64; 2]> {
        (0..count)
            .map(|i| {
                let frac = (start + i as f64 / count as f64).fract();
                let target = frac * total;
                let t = if total <= 0.0 {
                    0.0
                } else {
                    let j = cum.partition_point(|&c| c <= target).clamp(1, STEPS);
                    let (c0, c1) = (cum[j - 1], cum[j]);
                    let u = if c1 > c0 {
                        (target - c0) / (c1 - c0)
                    } else {
                        0.0
                    };
                    (j as f64 - 1.0 + u) * dt
                };
                [a * t.cos(), b * t.sin()]
            })
            .collect()
    };
    starts.iter().map(|&s| points_from(s)).collect()
}

/// Cumulative arc length of the ellipse with semi-axes (a, b) at the [`ARC_STEPS`] angle samples
/// (from 0), for inverting s(t). Four steps' lengths at once, each in the one-step expression's
/// order; the running sum still adds them one at a time (the bits of
/// [`cumulative_arc_by_steps`], as [`ellipse_second_moments`]' lanes).
pub(crate) fn cumulative_arc(a: f64, b: f64) -> Vec<f64> {
    let mut cum = Vec::with_capacity(ARC_STEPS + 1);
    cum.push(0.0);
    let dt = f64x4::splat(2.0 * PI / ARC_STEPS as f64);
    let (aa, bb) = (f64x4::splat(a * a), f64x4::splat(b * b));
    let mut length = 0.0;
    for &(s, c) in arc_lanes() {
        for ds in ((aa * s * s + bb * c * c).sqrt() * dt).to_array() {
            length += ds;
            cum.push(length);
        }
    }
    cum
}

/// [`cumulative_arc`] one step at a time: the plain loop its lanes must reproduce.
#[cfg(test)]
pub(crate) fn cumulative_arc_by_steps(a: f64, b: f64) -> Vec<f64> {
    let mut cum = vec![0.0];
    let dt = 2.0 * PI / ARC_STEPS as f64;
    for (i, &(s, c)) in arc_sin_cos().iter().enumerate() {
        let ds = (a * a * s * s + b * b * c * c).sqrt() * dt;
        cum.push(cum[i] + ds);
    }
    cum
}

/// The `ellipseN` pattern: PHASES phases of N arc-length-equispaced points, scaled so that the
/// union of all phases has exactly variances (λ1, λ2) along the principal axes.
pub(crate) fn ellipse_pattern(n: u32, l1: f64, l2: f64, e1: [f64; 2]) -> Pattern {
    let to_pixels = principal_to_pixels(e1);
    let n = n as usize;
    if l1 <= 0.0 {
        return vec![vec![([0.0, 0.0], 1.0)]; PHASES];
    }
    let r = ellipse_ratio_for_variance_ratio(l2 / l1);
    let unit = unit_phases(r, n);
    let (sx, sy) = (unit.sum_x2, unit.sum_y2);
    let count = (PHASES * n) as f64;
    let kx = (l1 / (sx / count)).sqrt();
    let ky = if sy > 0.0 {
        (l2 / (sy / count)).sqrt()
    } else {
        0.0
    };
    let w = 1.0 / n as f64;
    unit.phases
        .iter()
        .map(|pts| {
            pts.iter()
                .map(|q| (to_pixels(q[0] * kx, q[1] * ky), w))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembered_unit_phases_are_the_point_sets() {
        for (r, n) in [(0.633, 2), (0.633, 3), (0.1, 2), (0.633, 2)] {
            let starts: Vec<f64> = (0..PHASES)
                .map(|p| p as f64 / (PHASES * n) as f64)
                .collect();
            let fresh = ellipse_point_sets(1.0, r, &starts, n);
            // The first call may compute, a second may read the remembered value: both must be
            // the point sets.
            for unit in [unit_phases(r, n), unit_phases(r, n)] {
                let bits = |sets: &[Vec<[f64; 2]>]| -> Vec<u64> {
                    sets.iter()
                        .flatten()
                        .flatten()
                        .map(|v| v.to_bits())
                        .collect()
                };
                assert_eq!(bits(&unit.phases), bits(&fresh), "r {r}, n {n}");
                let sum_x2: f64 = fresh.iter().flatten().fold(0.0, |s, q| s + q[0] * q[0]);
                let sum_y2: f64 = fresh.iter().flatten().fold(0.0, |s, q| s + q[1] * q[1]);
                assert_eq!(unit.sum_x2.to_bits(), sum_x2.to_bits());
                assert_eq!(unit.sum_y2.to_bits(), sum_y2.to_bits());
            }
        }
    }
}
