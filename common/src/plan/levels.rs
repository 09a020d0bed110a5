//! Distance penumbra: the level plane before the first slab, from the initial light (built on
//! the host for both backends, with the per-pixel [`pixel_level`]).

use crate::pixel::levels::{level_at, pixel_level};
use crate::plan::RenderPlan;

/// The level planes before the first slab, `[row][light][x]` (one unused entry per row with the
/// iterated penumbra): from the initial light `light` (`[row][light][plane][x]`; a pattern's dark
/// parts are occluders at depth 0), each light's channels summed left to right from 0, as the
/// sweep sums them after a slab.
pub fn initial_levels(plan: &RenderPlan, light: &[f32]) -> Vec<u32> {
    let (w, h) = (plan.grid_width as usize, plan.grid_height as usize);
    let lrl = plan.level_row_len();
    let mut levels = vec![0u32; lrl * h];
    if plan.depth_planes() == 0 {
        return levels;
    }
    let (ch, row_len) = (plan.channels as usize, plan.light_row_len());
    for y in 0..h {
        for (l, light_plan) in plan.lights.iter().enumerate() {
            for x in 0..w {
                let at = |c: usize| light[y * row_len + plan.light_plane(l, c) * w + x];
                let mut lit = 0.0f32;
                for c in 0..ch {
                    lit += at(c);
                }
                let occluded = ch as f32 - lit;
                levels[y * lrl + l * w + x] =
                    pixel_level::<f32>(&light_plan.table, occluded, at(ch), level_at(plan, 0));
            }
        }
    }
    levels
}
