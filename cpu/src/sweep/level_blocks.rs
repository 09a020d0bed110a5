//! Distance penumbra: the level plane's 2×2 block minima ([`LevelBlocks`]), rebuilt after every
//! slab. The level search reads them: one value per tap where `kernels.wgsl` reads a tap's four
//! level corners (`crate::kernels::LevelPlane::corners`); a minimum is exact and order-free, so
//! one read gives the bits of four. (Measured: four corners per tap in the per-pixel stage made
//! the scalar path 7 % slower.) The SIMD path rebuilds a row only where its levels can have
//! changed (its quiet spans, see [`LevelBlocks::update`]).

use std::ops::Range;

use convshadow_common::plan::RenderPlan;
use rayon::prelude::*;

/// Distance penumbra: the level plane's 2×2 block minima ([`level_block_minima`]), laid out as
/// the plane, and per row the pixels
/// outside which every block is [`LIT_LEVEL`](convshadow_common::plan::LIT_LEVEL); empty
/// without depth planes.
pub(crate) struct LevelBlocks {
    pub(crate) blocks: Vec<u32>,
    /// Per row, `[lo, hi)`: every block of the row outside it (any light) is `LIT_LEVEL`.
    spans: Vec<(i32, i32)>,
    /// The grid's width and the plane's row stride.
    width: usize,
    row_stride: usize,
}

impl LevelBlocks {
    /// The block minima of `plan`'s level plane `levels`.
    pub(crate) fn new(plan: &RenderPlan, levels: &[u32]) -> LevelBlocks {
        if plan.depth_planes() == 0 {
            return LevelBlocks::of(&[], 1, 1);
        }
        LevelBlocks::of(levels, plan.grid_width as usize, plan.level_row_len())
    }

    /// The block minima of a level plane `levels` of rows `row_stride` apart, each holding
    /// every light's `width` levels.
    fn of(levels: &[u32], width: usize, row_stride: usize) -> LevelBlocks {
        let mut blocks = LevelBlocks {
            blocks: vec![0u32; levels.len()],
            spans: vec![(0, width as i32); levels.len() / row_stride],
            width,
            row_stride,
        };
        blocks.update(levels, |_| (0, width as i32));
        blocks
    }

    /// The block minima of the level plane `levels`, which may differ from the last one only
    /// where `not_one` allows: per row y, `not_one(y)` is the span `[lo, hi)` outside which every
    /// pixel's outgoing light was exactly 1 in every channel, so its level is `LIT_LEVEL`
    /// (`pixel_level`: nothing occluded); `(0, width)` where nothing is known. Rows are rebuilt
    /// in parallel, each only over the pixels whose block can differ from `LIT_LEVEL` now or did
    /// before.
    pub(crate) fn update(&mut self, levels: &[u32], not_one: impl Fn(usize) -> (i32, i32) + Sync) {
        let (w, rs) = (self.width, self.row_stride);
        assert_eq!(
            levels.len(),
            self.blocks.len(),
            "a level plane of another size"
        );
        self.blocks
            .par_chunks_mut(rs)
            .zip(self.spans.par_iter_mut())
            .enumerate()
            .for_each(|(y, (out, span))| {
                // Block x reads pixels x and x + 1 of rows y and y + 1.
                let (a, b) = (not_one(y), not_one(y + 1));
                let (lo, hi) = (a.0.min(b.0).saturating_sub(1), a.1.max(b.1));
                let now = if lo < hi {
                    (lo.max(0), hi.min(w as i32))
                } else {
                    (0, 0)
                };
                // The blocks outside both the old span and the new are LIT_LEVEL already.
                let (from, to) = if span.0 < span.1 {
                    (now.0.min(span.0), now.1.max(span.1))
                } else {
                    now
                };
                *span = now;
                if from < to {
                    let below = levels.get((y + 1) * rs..(y + 2) * rs);
                    let xs = from as usize..to as usize;
                    level_block_minima(&levels[y * rs..(y + 1) * rs], below, w, xs, out);
                }
            });
    }
}

/// Distance penumbra: one row of the level plane's 2×2 block minima, at pixels `xs` of every
/// light. `levels` is row y of the plane (every light's `width` levels side by side), `below`
/// row y + 1 (`None` for the last row); `out[i]` becomes the smallest of `levels[i]`,
/// `levels[i + 1]`, `below[i]` and `below[i + 1]`, where a corner beyond the grid counts as
/// [`LIT_LEVEL`] (no occluder, the largest level), as the level search's edge path reads it.
/// Built once per slab so that the level search reads one value per tap (and lane), not four.
pub(crate) fn level_block_minima(
    levels: &[u32],
    below: Option<&[u32]>,
    width: usize,
    xs: Range<usize>,
    out: &mut [u32],
) {
    assert!(width > 0 && levels.len().is_multiple_of(width) && out.len() == levels.len());
    assert!(
        xs.start <= xs.end && xs.end <= width,
        "pixels {xs:?} of {width}"
    );
    // Pixels whose right neighbour lies in the grid, then (if in `xs`) the last pixel.
    let inner = xs.start.min(width - 1)..xs.end.min(width - 1);
    for (l, out) in out.chunks_exact_mut(width).enumerate() {
        let top = &levels[l * width..][..width];
        let bottom = below.map(|b| &b[l * width..][..width]);
        let (left, right) = (inner.clone(), inner.start + 1..inner.end + 1);
        for ((o, a), b) in out[left.clone()]
            .iter_mut()
            .zip(&top[left.clone()])
            .zip(&top[right.clone()])
        {
            *o = (*a).min(*b);
        }
        if let Some(bottom) = bottom {
            let pairs = bottom[left.clone()].iter().zip(&bottom[right]);
            for (o, (a, b)) in out[left].iter_mut().zip(pairs) {
                *o = (*o).min((*a).min(*b));
            }
        }
        if xs.end == width {
            let last = width - 1;
            out[last] = bottom.map_or(top[last], |b| top[last].min(b[last]));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::LevelBlocks;
    use convshadow_common::plan::LIT_LEVEL;
    use convshadow_testkit::TestRng;

    /// The smallest level of the 2×2 block at pixel x of row y of light l, corners beyond the
    /// grid read as `LIT_LEVEL`: straight from the definition.
    fn block_at(
        levels: &[u32],
        (w, lights, h): (usize, usize, usize),
        l: usize,
        x: usize,
        y: usize,
    ) -> u32 {
        let mut m = LIT_LEVEL;
        for (cx, cy) in [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)] {
            if cx < w && cy < h {
                m = m.min(levels[cy * w * lights + l * w + cx]);
            }
        }
        m
    }

    #[test]
    fn level_blocks_are_the_smallest_level_of_each_two_by_two_block() {
        let mut rng = TestRng::new(5);
        for (w, lights, h) in [(1, 1, 1), (2, 2, 3), (11, 2, 6), (9, 1, 2)] {
            let levels: Vec<u32> = (0..w * lights * h)
                .map(|_| match rng.below(3) {
                    0 => LIT_LEVEL,
                    _ => rng.below(6),
                })
                .collect();
            let blocks = LevelBlocks::of(&levels, w, w * lights).blocks;
            for (i, &b) in blocks.iter().enumerate() {
                let (y, l, x) = (i / (w * lights), i % (w * lights) / w, i % w);
                let want = block_at(&levels, (w, lights, h), l, x, y);
                assert_eq!(b, want, "{w}×{h}, light {l}, pixel ({x}, {y})");
            }
        }
    }

    #[test]
    fn level_blocks_rebuilt_within_spans_are_the_blocks_rebuilt_whole() {
        // Planes that are LIT_LEVEL outside one random span per row (sometimes none), told
        // with that span or a wider one: the blocks must be those of the whole plane, also where
        // the last plane had levels and this one has none.
        let (w, lights, h) = (13, 2, 7);
        let mut rng = TestRng::new(9);
        let mut blocks = LevelBlocks::of(&vec![LIT_LEVEL; w * lights * h], w, w * lights);
        let mut rebuilt = 0;
        for round in 0..200 {
            let mut levels = vec![LIT_LEVEL; w * lights * h];
            let mut spans = vec![(i32::MAX, i32::MIN); h];
            for y in 0..h {
                if rng.below(3) == 0 {
                    continue;
                }
                let lo = rng.below(w as u32) as usize;
                let hi = lo + 1 + rng.below((w - lo) as u32) as usize;
                for l in 0..lights {
                    for x in lo..hi {
                        if rng.below(2) == 0 {
                            levels[y * w * lights + l * w + x] = rng.below(5);
                        }
                    }
                }
                // The told span holds every level that is not LIT_LEVEL, maybe with room.
                let wider = (
                    lo.saturating_sub(rng.below(2) as usize),
                    (hi + rng.below(2) as usize).min(w),
                );
                spans[y] = (wider.0 as i32, wider.1 as i32);
            }
            blocks.update(&levels, |y| {
                spans.get(y).copied().unwrap_or((i32::MAX, i32::MIN))
            });
            let whole = LevelBlocks::of(&levels, w, w * lights);
            assert_eq!(blocks.blocks, whole.blocks, "round {round}");
            rebuilt += usize::from(blocks.spans.iter().any(|s| s.0 < s.1));
        }
        assert!(rebuilt > 100, "rounds with levels {rebuilt}");
    }
}
