//! `poisson8` / `poisson16`: a fixed, whitened Poisson-disk pattern, randomly rotated.

use std::f64::consts::PI;

use super::*;

/// A fixed Poisson-disk pattern of `n` points (deterministic dart throwing with the hash),
/// centred and whitened to identity covariance.
pub fn poisson_disk_whitened(n: u32) -> Vec<[f64; 2]> {
    let n = n as usize;
    let mut pts: Vec<[f64; 2]> = Vec::new();
    let mut radius = 2.0 / (n as f64).sqrt();
    let mut tries = 0u32;
    let mut counter = 0u32;
    while pts.len() < n {
        counter += 1;
        let u =
            f64::from(crate::pixel::hash::mix32(counter.wrapping_mul(2).wrapping_add(0x51)) >> 8)
                / 16_777_216.0;
        let v =
            f64::from(crate::pixel::hash::mix32(counter.wrapping_mul(2).wrapping_add(0x52)) >> 8)
                / 16_777_216.0;
        let p = [2.0 * u - 1.0, 2.0 * v - 1.0];
        if p[0] * p[0] + p[1] * p[1] > 1.0 {
            continue;
        }
        if pts
            .iter()
            .all(|q| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) >= radius * radius)
        {
            pts.push(p);
            tries = 0;
        } else {
            tries += 1;
            if tries > 1000 {
                radius *= 0.95;
                tries = 0;
            }
        }
    }
    let mean = pts
        .iter()
        .fold([0.0, 0.0], |m, p| [m[0] + p[0], m[1] + p[1]]);
    let mean = [mean[0] / n as f64, mean[1] / n as f64];
    for p in &mut pts {
        p[0] -= mean[0];
        p[1] -= mean[1];
    }
    let mut c = [[0.0; 2]; 2];
    for p in &pts {
        c[0][0] += p[0] * p[0] / n as f64;
        c[0][1] += p[0] * p[1] / n as f64;
        c[1][1] += p[1] * p[1] / n as f64;
    }
    c[1][0] = c[0][1];
    // C^{-1/2} via the eigen-decomposition.
    let (a, b, e) = eigen2(c);
    let f = [-e[1], e[0]];
    let (ia, ib) = (1.0 / a.sqrt(), 1.0 / b.sqrt());
    pts.iter()
        .map(|p| {
            let u = (p[0] * e[0] + p[1] * e[1]) * ia;
            let v = (p[0] * f[0] + p[1] * f[1]) * ib;
            [u * e[0] + v * f[0], u * e[1] + v * f[1]]
        })
        .collect()
}

/// The `poissonN` pattern: the whitened disk rotated by PHASES angles, shaped by Σκ^½.
pub(crate) fn poisson_pattern(n: u32, l1: f64, l2: f64, e1: [f64; 2]) -> Pattern {
    let to_pixels = principal_to_pixels(e1);
    let base = poisson_disk_whitened(n);
    let (s1, s2) = (l1.sqrt(), l2.sqrt());
    let w = 1.0 / f64::from(n);
    (0..PHASES)
        .map(|p| {
            let (s, c) = (2.0 * PI * p as f64 / PHASES as f64).sin_cos();
            base.iter()
                .map(|q| {
                    let (u, v) = (c * q[0] - s * q[1], s * q[0] + c * q[1]);
                    (to_pixels(u * s1, v * s2), w)
                })
                .collect()
        })
        .collect()
}
