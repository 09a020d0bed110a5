//! Distance penumbra for 8 lanes: the level search ([`distance_rows`]: the reference's
//! `crate::kernels::distance_row` in every lane; inside the grid one block-minimum read per tap
//! and lane, a contiguous load where every lane has the same row, else an AVX2 gather), the tap
//! rows of levels, and the per-pixel phases on integer lanes ([`phases`]). Tests: the chunk
//! stage's (`chunk/tests.rs`) against the per-pixel stage.

use convshadow_common::pixel::lane::{Layout, MAX_LANES};
use convshadow_common::plan::LIT_LEVEL;
use convshadow_common::plan::kernel::{KernelTable, PhaseMode};

use super::gather::reads_inside;
use super::per_lane::{LaneRows, TapColumns};
use crate::kernels::{LevelPlane, TapOrigin};

/// Distance penumbra: the rows that pixels x0.. of row y gather through. A pixel takes the
/// smallest level among its own and those of every pixel its own level's kernel reads (level 0's
/// kernel when it has no occluder; pixels without one do not count): the kernel of the nearest
/// occluder in reach. So a fresh shadow's lit neighbours take its small kernel (a gather with a
/// larger one would erode it), and a pixel in a distant occluder's penumbra next to a surface
/// that was just crossed does not blur the darkness behind that surface over itself.
#[inline(always)]
pub(crate) fn distance_rows<L: Layout>(
    levels: &LevelPlane<'_>,
    table: &KernelTable,
    columns: &TapColumns,
    phase: L::U,
    slabs: u32,
    slab: u32,
    origin: TapOrigin,
) -> L::U {
    let TapOrigin {
        x: x0,
        y,
        shift,
        inside: interior,
    } = origin;
    let lit = L::u_splat(LIT_LEVEL);
    let zero = L::u_splat(0);
    let at = levels.base + y as usize * levels.row_stride + x0 as usize;
    let own = L::u_load(levels.data, at);
    let own_rows = level_rows::<L>(
        table,
        L::u_select(L::u_eq(own, lit), zero, own),
        phase,
        slabs,
        slab,
    );
    let mut nearest = own;
    let own_reads = LaneRows::within::<L>(columns, own_rows, interior);
    let n = own_reads.level_taps;
    let pc = columns.phase_count;
    let rs = levels.row_stride;
    let (w, h) = (levels.width, levels.height);
    if interior || reads_inside(own_reads.extent, origin, L::LANES, w, h) {
        let lane_shift = L::u_add(
            L::u_iota(at as u32),
            L::u_splat((shift[1] as i64 * rs as i64 + shift[0] as i64) as i32 as u32),
        );
        // Each tap's four corners are one block minimum (`level_block_minima`): `min` is exact
        // and order-free, so one read gives the bits of four.
        if let Some(row) = own_reads.uniform {
            // Every lane through the same row: each tap's blocks are one contiguous load.
            let origin = at as i64 + shift[1] as i64 * rs as i64 + shift[0] as i64;
            for k in 0..n {
                let rel = columns.level_offset[k * pc + row as usize] as i32;
                let top_left = (origin + i64::from(rel)) as usize;
                nearest = L::u_min(nearest, L::u_load(levels.blocks, top_left));
            }
            let nearest = L::u_select(L::u_eq(nearest, lit), zero, nearest);
            return level_rows::<L>(table, nearest, phase, slabs, slab);
        }
        // One proof for every gather below: `LaneRows::within` checked each lane's row against
        // a table of `pc` rows (so `rel` reads inside its column), and the test above (or the
        // sweep's reach) put every corner inside the grid, whose rows lie in `levels.data`.
        assert!(
            levels.data.len() <= i32::MAX as usize
                && levels.blocks.len() == levels.data.len()
                && columns.summary.len() == pc
        );
        // Crate-internal invariants (this function is crate-private): the sweep builds the level
        // plane and the columns from one plan.
        debug_assert!(
            columns.strides[1] == rs
                && levels.base + (levels.height.max(1) as usize - 1) * rs + levels.width as usize
                    <= levels.data.len(),
            "level search: a table for another level plane, or a grid beyond its data"
        );
        for k in 0..n {
            let column = &columns.level_offset[k * pc..(k + 1) * pc];
            // SAFETY: every lane's row is below `pc` (see above).
            let rel = unsafe { L::u_gather_unchecked(column, own_rows) };
            let top_left = L::u_add(lane_shift, rel);
            // SAFETY: every corner lies inside the grid (see above), so every top-left corner
            // lies in `blocks`, laid out as `data`.
            let block = unsafe { L::u_gather_unchecked(levels.blocks, top_left) };
            nearest = L::u_min(nearest, block);
        }
    } else {
        let mut rows = [0u32; MAX_LANES];
        let mut near = [0u32; MAX_LANES];
        L::u_store(own_rows, &mut rows);
        L::u_store(nearest, &mut near);
        let inside = |x: i32, y: i32| x >= 0 && y >= 0 && x < levels.width && y < levels.height;
        let at = |x: i32, y: i32| levels.base + y as usize * rs + x as usize;
        let fetch = |x: i32, y: i32| {
            if inside(x, y) {
                levels.data[at(x, y)]
            } else {
                LIT_LEVEL
            }
        };
        for i in 0..L::LANES {
            let used = columns.level_taps[rows[i] as usize] as usize;
            for t in &table.phase(rows[i])[..used] {
                let (sx, sy) = (x0 + i as i32 + t.dx + shift[0], y + t.dy + shift[1]);
                near[i] = near[i].min(if inside(sx, sy) {
                    // Its corners beyond the grid count as LIT_LEVEL there too.
                    levels.blocks[at(sx, sy)]
                } else {
                    let corners = [(sx, sy), (sx + 1, sy), (sx, sy + 1), (sx + 1, sy + 1)];
                    corners
                        .into_iter()
                        .map(|(cx, cy)| fetch(cx, cy))
                        .fold(LIT_LEVEL, u32::min)
                });
            }
        }
        nearest = L::u_gather(&near, L::u_iota(0));
    }
    let nearest = L::u_select(L::u_eq(nearest, lit), zero, nearest);
    level_rows::<L>(table, nearest, phase, slabs, slab)
}

/// The rows of levels `level` at the lanes' phases: `level · phase_count + phase`, or for a
/// scheduled kernel the level's phase of slab `slab`, `slab_phase[level · slabs + slab]`.
#[inline(always)]
pub(crate) fn level_rows<L: Layout>(
    table: &KernelTable,
    level: L::U,
    phase: L::U,
    slabs: u32,
    slab: u32,
) -> L::U {
    let rows = L::u_mul(level, L::u_splat(table.phase_count));
    match table.phase_mode {
        PhaseMode::Schedule => schedule_rows::<L>(table, rows, slabs, slab),
        _ => L::u_add(rows, phase),
    }
}

/// Distance penumbra with a scheduled kernel: `rows` (level · phase_count, phase 0) moved to the
/// level's phase of slab `slab`, `slab_phase[level · slabs + slab]`.
#[inline(always)]
pub fn schedule_rows<L: Layout>(table: &KernelTable, rows: L::U, slabs: u32, slab: u32) -> L::U {
    let mut r = [0u32; MAX_LANES];
    L::u_store(rows, &mut r);
    let pc = table.phase_count;
    for v in r.iter_mut().take(L::LANES) {
        let level = *v / pc;
        *v = level * pc + table.slab_phase[(level * slabs + slab) as usize];
    }
    L::u_gather(&r, L::u_iota(0))
}

/// The per-pixel phases of pixels x0.. as integer lanes ([`phase_at`] for `PerPixel` tables): the
/// pixel hash on integer lanes.
#[inline(always)]
pub fn phases<L: Layout>(table: &KernelTable, row_hash_v: u32, x0: u32) -> L::U {
    let bits = table.phase_bits();
    if bits == 0 {
        return L::u_splat(0);
    }
    let x = L::u_iota(x0);
    let h = L::u_mix32(L::u_xor(
        L::u_splat(row_hash_v),
        L::u_mul(x, L::u_splat(0x9e37_79b9)),
    ));
    L::u_shr(h, 32 - bits)
}
