//! Distance penumbra: the level each pixel gathers through (docs/accuracy.md §1b). One
//! implementation for the CPU sweep (every lane type) and the host's initial level plane
//! (`plan::levels`); `gpu/src/shaders/kernels.wgsl` mirrors [`pixel_level`] operation for
//! operation.

use crate::pixel::lane::Lane;
use crate::plan::kernel::KernelTable;
use crate::plan::{LIT_LEVEL, OCCLUSION_EPS};

/// Distance penumbra: the level a pixel gathers through in slab `slab`, from its light after
/// the previous slab: the occluded light `occluded = channels − Σ I` and the occlusion-weighted
/// depth `depth` give the mean occluder depth `z̄ = depth / occluded` (slabs); the distance
/// `h = slab − z̄` is rounded (`+ ½`, truncated) and clamped to 1..=slabs, and
/// [`KernelTable::level_of`] maps it to a level. [`LIT_LEVEL`] where `occluded ≤ OCCLUSION_EPS`:
/// no occluder to speak of (`depth / occluded` would be rounding noise).
#[inline(always)]
pub fn pixel_level<L: Lane>(table: &KernelTable, occluded: L, depth: L, slab: u32) -> L::U {
    let one = L::splat(1.0);
    let has_occluder = occluded.gt(L::splat(OCCLUSION_EPS));
    let mean_depth = depth / L::select(has_occluder, occluded, one);
    let h = (L::splat(slab as f32) - mean_depth) + L::splat(0.5);
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
