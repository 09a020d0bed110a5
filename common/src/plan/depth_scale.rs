//! A soft point light's depth coordinate for the distance penumbra (docs/how-it-works.md, "The
//! sweep's point lights"): ψ, the light's φ = −1/(depth from the light) in units of its first
//! slab's step.

/// A point light's grid with a spread (a soft point light, docs/how-it-works.md "The sweep's
/// point lights"): its penumbra grows with `φ = −1/(depth from the light)`, not with depth, so
/// the distance penumbra's depth plane and level search run in `ψ = (φ − φ_0)/Δφ_1`, φ over its
/// first slab's step: slab k's ψ_k, ψ_0 = 0, ψ_1 = 1, steps `n_k = ψ_k − ψ_{k−1}` ≤ 1 falling
/// away from the light. The level of a pixel whose mean occluder lies h (in ψ) before slab k has
/// the step `n_k·(2h − n_k)` (the growth of `h²` over the slab), the step `2H − 1` of the slab
/// grid's level `H = n_k·h − (n_k² − 1)/2`, so the slab grid's tables serve, with the light's
/// per-slab covariance that of its first slab.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthScale {
    /// ψ at slab coordinates 0..=slabs + 1 (slab k's front is coordinate k).
    pub psi: Vec<f32>,
}

impl DepthScale {
    /// The scale of a grid whose relative depth 0 lies `origin` from the light (view depth),
    /// `slabs` slabs of `slab_distance`.
    pub fn new(origin: f64, slab_distance: f64, slabs: u32) -> DepthScale {
        let phi = |k: u32| -1.0 / (origin + f64::from(k) * slab_distance);
        let first = phi(1) - phi(0);
        DepthScale {
            psi: (0..=slabs + 1)
                .map(|k| ((phi(k) - phi(0)) / first) as f32)
                .collect(),
        }
    }

    /// ψ at slab coordinate `t` (fractional between slabs: linear; beyond the ends: the end
    /// slab's step continued).
    pub fn at(&self, t: f32) -> f32 {
        let last = self.psi.len() - 2;
        let k = (t.floor().max(0.0) as usize).min(last);
        let f = t - k as f32;
        self.psi[k] + f * (self.psi[k + 1] - self.psi[k])
    }

    /// The step of slab coordinate `k` (from `k − 1`; slab 0's is the first slab's, 1).
    pub fn step(&self, k: u32) -> f32 {
        let k = (k as usize).clamp(1, self.psi.len() - 1);
        self.psi[k] - self.psi[k - 1]
    }
}
