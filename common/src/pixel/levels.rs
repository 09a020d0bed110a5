//! Distance penumbra: the level each pixel gathers through (docs/accuracy.md §1b). One
//! implementation for the CPU sweep (every lane type) and the host's initial level plane
//! (`plan::levels`); `gpu/src/shaders/kernels.wgsl` mirrors [`pixel_level`] operation for
//! operation.

use crate::pixel::lane::{Lane, MAX_LANES};
use crate::plan::depth_scale::DepthScale;
use crate::plan::kernel::KernelTable;
use crate::plan::{LIT_LEVEL, OCCLUSION_EPS, RenderPlan};

/// Where the level search of [`pixel_level`] stands: the coordinate of the slab being gathered
/// in the depth plane's units (a slab grid's: the slab index), and for a point light's grid
/// ([`DepthScale`]) the slab's step `n` in those units, which scales the distance to the level
/// whose covariance step is the slab's ([`level_at`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelAt {
    /// The slab's coordinate.
    pub coord: f32,
    /// A point light's grid: the slab's step in the depth plane's units (≤ 1).
    pub step: Option<f32>,
}

impl LevelAt {
    /// Slab `slab` of a slab grid: its index, no scale.
    #[inline(always)]
    pub fn slab(slab: u32) -> LevelAt {
        LevelAt {
            coord: slab as f32,
            step: None,
        }
    }
}

/// Where `plan`'s distance penumbra stands in slab `slab` ([`LevelAt`]): the slab index, or on
/// a soft point light's grid its ψ and step (`RenderPlan::depth_scale`).
#[inline(always)]
pub fn level_at(plan: &RenderPlan, slab: u32) -> LevelAt {
    match &plan.depth_scale {
        None => LevelAt::slab(slab),
        Some(d) => LevelAt {
            coord: d.at(slab as f32),
            step: Some(d.step(slab)),
        },
    }
}

/// The depth plane's coordinate of removal depth `t` (slabs, per lane): `t` itself on a slab
/// grid, the [`DepthScale`] of a point light's grid.
#[inline(always)]
pub fn depth_coord<L: Lane>(scale: Option<&DepthScale>, t: L) -> L {
    let Some(scale) = scale else {
        return t;
    };
    let mut v = [0.0f32; MAX_LANES];
    for (i, out) in v.iter_mut().enumerate().take(L::LANES) {
        *out = scale.at(t.lane(i));
    }
    L::load(&v, 0)
}

/// Distance penumbra: the level a pixel gathers through in the slab at `at`, from its light
/// after the previous slab: the occluded light `occluded = channels − Σ I` and the
/// occlusion-weighted depth `depth` give the mean occluder depth `z̄ = depth / occluded` (slabs);
/// the distance `h = slab − z̄` is rounded (`+ ½`, truncated) and clamped to 1..=slabs, and
/// [`KernelTable::level_of`] maps it to a level. [`LIT_LEVEL`] where `occluded ≤ OCCLUSION_EPS`:
/// no occluder to speak of (`depth / occluded` would be rounding noise). On a point light's grid
/// the distance is in the depth plane's units and the slab's step n there gives the level of
/// the same covariance step: `n·h − (n² − 1)/2` ([`DepthScale`]).
#[inline(always)]
pub fn pixel_level<L: Lane>(table: &KernelTable, occluded: L, depth: L, at: LevelAt) -> L::U {
    let one = L::splat(1.0);
    let has_occluder = occluded.gt(L::splat(OCCLUSION_EPS));
    let mean_depth = depth / L::select(has_occluder, occluded, one);
    let h = L::splat(at.coord) - mean_depth;
    let h = match at.step {
        None => h,
        Some(n) => L::splat(n) * h - L::splat((n * n - 1.0) * 0.5),
    };
    let h = h + L::splat(0.5);
    // The table's last entry bounds the distance (a value) and the index (a proof, below).
    let entries = table.level_of.len();
    assert!(
        (1..=i32::MAX as usize).contains(&entries),
        "a level table of {entries} entries"
    );
    let last = entries - 1;
    let top = L::splat(last as f32);
    let h = L::select(h.lt(one), one, h);
    let h = L::select(h.gt(top), top, h);
    let h = L::select(has_occluder, h, one).trunc_u32();
    // h ≤ top already (NaN truncates to 0): the minimum changes no index and proves the bounds
    // once, where a checked gather reduced the lanes to their largest per chunk. A proof, not an
    // operation on the value: the WGSL mirror has no counterpart.
    let h = L::u_min(h, L::u_splat(last as u32));
    // SAFETY: every lane's index is at most `last`, below `level_of.len()`.
    let level = unsafe { L::u_gather_unchecked(&table.level_of, h) };
    L::u_select(has_occluder, level, L::u_splat(LIT_LEVEL))
}
