//! The 8-lane chunk stage: the per-pixel stage (`crate::sweep::pixel`) for the 8 pixels x0.. of
//! one row at once, each lane running its IEEE operations in the same order. Written over `Lane`
//! and run as its 8-lane (`wide::f32x8`) instance, in instances that know the plan's light
//! channels and penumbra model at compile time ([`shape_of`]: loops of fixed length), with the
//! gathers of `super::gather`, `super::per_lane` and `super::levels`, the cursors skipped where
//! the chunk's summary shows that none crosses a fragment (`super::quiet`), and the chunk whose
//! depth planes alone move ([`dark_depth_chunk`]). Tests (`chunk/tests.rs`): every instance
//! against the per-pixel stage on random inputs, lane by lane, bit for bit.
//!
//! Lane work: the gather's arithmetic (and its loads, when a slab's phase is the same for every
//! pixel), the phase hash, the detail function, the transfer-function interpolation, shading,
//! compositing and attenuation. Per lane: the layer cursor (a short data-dependent loop) and
//! table look-ups. Lanes on different meshes are shaded one lane at a time, by the per-pixel
//! stage's shading.

use convshadow_common::pixel::lane::{Lane, Layout, MAX_LANES};
use convshadow_common::plan::kernel::PhaseMode;

use super::SimdSlab;
use super::gather::{gather_inside, gather_lanes, store_pixels};
use super::held::{exact_lanes, held_lanes, keep_released_lanes, lane_aheads};
use super::levels::{distance_rows, level_rows, phases};
use super::per_lane::{LaneRows, gather_per_lane};
use super::quiet::{ChunkState, Values};
use crate::composite::{Held, attenuate, deepen, owned_depth, shade_sample};
use crate::kernels::{LightPlanes, TapOrigin, phase_at};
use crate::parity::{NO_CROSSING, advance, first_mesh, slab_part};
use crate::shading::{TfLanes, detail_at, material_at, pre_transfer, shading_depth, uses_normals};
use crate::subpixel::removal_depth;
use crate::sweep::kit::{
    MAX_LIGHT_CHANNELS, MAX_LIGHTS, Previous, RowContext, RowState, SlabContext, level_plane,
    light_block,
};
use crate::sweep::pixel::{Hit, hold, shade_and_composite, subpixel_part};
use convshadow_common::pixel::levels::{depth_coord, pixel_level};
use convshadow_common::plan::{RenderPlan, TfEntry};
use wide::f32x8;

/// [`sweep_chunk`] for one lane type, light-channel capacity and shape.
pub(crate) type ChunkFn =
    fn(&SimdSlab<'_>, &RowContext<'_>, &mut RowState<'_>, Chunk<'_>) -> ChunkOutcome;

/// One chunk of a row as the 8-lane row hands it to [`sweep_chunk`]: where it is and what is
/// known about it.
#[derive(Clone, Copy)]
pub(crate) struct Chunk<'a> {
    /// Its first pixel: the chunk is pixels x0..x0 + LANES of the row.
    pub x0: usize,
    /// Every read of its gathers lies inside the grid.
    pub interior: bool,
    /// Every value its gathers read is this constant: the gathers are skipped.
    pub known_light: Option<f32>,
    /// Its gathers' result, already computed (light plane i's lanes at `i · LANES..`, see
    /// [`gather_pair`]).
    pub gathered: Option<&'a [f32]>,
    /// Its cursor summary, current: its lanes' cursors are not visited when it shows that none
    /// crosses a fragment in this slab.
    pub summary: Option<ChunkState>,
    /// A pixel held in the previous slab lies near its reads (`pixel::held_near`, `super::held`).
    pub held: bool,
}

/// What step 2 found in every lane: the first fragment its cursor crossed in this slab
/// ([`NO_CROSSING`] if none) and the mesh it shades, if any (the per-pixel stage's `Hit`, by lane).
struct LaneHits {
    crossed: [u32; MAX_LANES],
    /// The last fragment crossed (meaningful where `crossed` is one).
    last: [u32; MAX_LANES],
    /// The inside mask at the slab's front.
    before: [u32; MAX_LANES],
    mesh: [Option<u32>; MAX_LANES],
}

impl LaneHits {
    /// Lane i's hit, as the per-pixel stage has it.
    fn lane(&self, i: usize) -> Hit {
        Hit {
            crossed: self.crossed[i],
            last: self.last[i],
            before: self.before[i],
            mesh: self.mesh[i],
        }
    }
}

/// What one chunk's stages tell the lane path about their lanes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ChunkOutcome {
    /// Some outgoing light value is not exactly 1.
    pub not_one: bool,
    /// Some outgoing light value is not exactly 0.
    pub not_zero: bool,
    /// Some outgoing value of a light plane (not a depth plane) is not exactly 0.
    pub light_not_zero: bool,
    /// Some lane was shaded (a lane that crossed a fragment is): its alpha may have changed, so
    /// the chunk's quiet summary must be refreshed.
    pub shaded: bool,
    /// Some lane crossed a fragment: its cursor and inside mask changed too.
    pub crossed: bool,
}

impl ChunkOutcome {
    /// What the chunk wrote, as the quiet spans record it.
    pub(crate) fn values(&self) -> Values {
        Values {
            not_one: self.not_one,
            not_zero: self.not_zero,
            light_not_zero: self.light_not_zero,
        }
    }
}

/// A [`sweep_chunk`] instance's `SHAPE`: it reads the light channels and the penumbra model from
/// the plan.
pub(crate) const ANY_SHAPE: u8 = 0;
/// A [`sweep_chunk`] instance's `SHAPE`: three light channels, iterated penumbra.
pub(crate) const RGB_ITERATED: u8 = 1;
/// A [`sweep_chunk`] instance's `SHAPE`: three light channels, distance penumbra (the default
/// scene's).
pub(crate) const RGB_DISTANCE: u8 = 2;

/// The `SHAPE` of the [`sweep_chunk`] instance that knows `plan`'s channels and penumbra model
/// at compile time, where there is one (three channels, at most two lights): its loops over
/// channels have fixed lengths (measured: 10 % of the default frame's sweep). Others read them
/// from the plan.
pub(crate) fn shape_of(plan: &RenderPlan) -> u8 {
    match (plan.channels, plan.lights.len(), plan.depth_planes() > 0) {
        (3, 1..=2, false) => RGB_ITERATED,
        (3, 1..=2, true) => RGB_DISTANCE,
        _ => ANY_SHAPE,
    }
}

/// The [`sweep_chunk`] instance for `planes` light channels and the shape `shape` (see
/// [`shape_of`]; [`ANY_SHAPE`] always serves): the smallest capacity that holds them (zeroing a
/// 48-entry array per chunk costs).
pub(crate) fn chunk_fn<L: Layout>(planes: usize, shape: u8) -> ChunkFn {
    match (planes, shape) {
        (3..=6, RGB_ITERATED) => sweep_chunk::<L, 6, RGB_ITERATED>,
        (3..=6, RGB_DISTANCE) => sweep_chunk::<L, 6, RGB_DISTANCE>,
        (0..=2, _) => sweep_chunk::<L, 2, ANY_SHAPE>,
        (3..=6, _) => sweep_chunk::<L, 6, ANY_SHAPE>,
        (7..=12, _) => sweep_chunk::<L, 12, ANY_SHAPE>,
        _ => sweep_chunk::<L, MAX_LIGHT_CHANNELS, ANY_SHAPE>,
    }
}

/// A `SHAPE` instance's light channels and planes per light: compile-time constants where the
/// shape fixes them (loops, the gather's dispatch and its pixel steps fold away), else the plan's.
#[inline(always)]
fn shape_planes<const SHAPE: u8>(plan: &RenderPlan) -> (usize, usize) {
    match SHAPE {
        ANY_SHAPE => (plan.channels as usize, plan.planes_per_light()),
        RGB_DISTANCE => (3, 4),
        _ => (3, 3),
    }
}

/// Light `l`'s channels in the previous slab's buffer, as the gather reads them (`shape`: the
/// channels and planes per light, [`shape_planes`]).
#[inline(always)]
fn light_planes<'a>(
    plan: &RenderPlan,
    prev: &Previous<'a>,
    l: usize,
    shape: (usize, usize),
) -> LightPlanes<'a> {
    let w = plan.grid_width as usize;
    let (ch, planes) = shape;
    LightPlanes {
        data: prev.light,
        base: light_block(plan, l),
        channels: ch,
        light_channels: ch,
        row_stride: plan.light_row_len(),
        pixel_step: planes,
        plane_step: 1,
        width: w as i32,
        height: plan.grid_height as i32,
    }
}

/// Whether [`gather_pair`] serves this plan: the iterated penumbra with one phase per slab for
/// every light (every lane of a chunk, and of its neighbour, reads through the same taps).
pub(crate) fn pairs_gathers(plan: &RenderPlan) -> bool {
    plan.depth_planes() == 0
        && plan
            .lights
            .iter()
            .all(|l| l.table.phase_mode != PhaseMode::PerPixel)
}

/// The gathers of two neighbouring 8-pixel chunks (pixels x0.. and x0 + 8..) of row y, both
/// inside the grid, computed together ([`gather_inside`]): light plane i's lanes at
/// `8i..8i + 8` of each output, as [`sweep_chunk`]'s `gathered` takes them. Only where
/// [`pairs_gathers`] holds.
pub(crate) fn gather_pair(
    simd: &SimdSlab<'_>,
    row: &RowContext<'_>,
    x0: usize,
    out: &mut [[f32; 8 * MAX_LIGHT_CHANNELS]; 2],
) {
    let (ctx, prev) = (row.ctx, row.prev);
    let plan = ctx.plan;
    let (ch, slab) = (plan.channels as usize, ctx.slab as usize);
    for (l, light) in plan.lights.iter().enumerate() {
        let t = &light.table;
        let planes = light_planes(plan, prev, l, shape_planes::<ANY_SHAPE>(plan));
        let p = match t.phase_mode {
            PhaseMode::PerSlab => phase_at(t, ctx.slab, light.slab_hash[slab], 0, 0),
            _ => t.slab_phase[slab],
        };
        let (mut a, mut b) = ([f32x8::splat(0.0); 3], [f32x8::splat(0.0); 3]);
        let extent = simd.columns[l].extent[p as usize];
        let taps = ctx.taps[l].weighted(p);
        let at = TapOrigin {
            x: x0 as i32,
            y: row.y as i32,
            shift: t.slab_shift[slab],
            inside: true,
        };
        gather_inside(&planes, taps, extent, at, [&mut a[..ch], &mut b[..ch]]);
        for (k, sums) in [a, b].iter().enumerate() {
            for (c, v) in sums[..ch].iter().enumerate() {
                v.store(&mut out[k], (l * ch + c) * 8);
            }
        }
    }
}

/// All five stages for the pixels of `chunk` in `row`.
#[inline(always)]
pub(crate) fn sweep_chunk<L: Layout, const N: usize, const SHAPE: u8>(
    simd: &SimdSlab<'_>,
    row: &RowContext<'_>,
    state: &mut RowState<'_>,
    chunk: Chunk<'_>,
) -> ChunkOutcome {
    let (ctx, prev, y) = (row.ctx, row.prev, row.y);
    let Chunk {
        x0,
        interior,
        known_light,
        gathered,
        summary,
        held: near_held,
    } = chunk;
    let plan = ctx.plan;
    let ldi = ctx.ldi;
    let w = plan.grid_width as usize;
    debug_assert!(
        SHAPE == ANY_SHAPE || SHAPE == shape_of(plan),
        "an instance for another plan"
    );
    let (ch, planes_per_light) = shape_planes::<SHAPE>(plan);
    let slab = ctx.slab as usize;
    let n = plan.lights.len() * ch;

    // Ordered to hide latency (measured): every light's level search (distance penumbra:
    // dependent gathers), the cursors while those loads arrive, then the convolution.
    let distance = match SHAPE {
        ANY_SHAPE => plan.depth_planes() > 0,
        shape => shape == RGB_DISTANCE,
    };
    // Per light, sized N (lights ≤ lights · channels ≤ N): zeroing MAX_LIGHTS entries costs.
    let mut light_rows = [L::u_splat(0); N];
    let searched = distance && known_light.is_none() && gathered.is_none();
    if searched {
        every_light_rows::<L>(simd, row, x0, interior, &mut light_rows);
    }

    // 2. Intersection: every lane's cursor.
    let mut hits = LaneHits {
        crossed: [NO_CROSSING; MAX_LANES],
        last: [NO_CROSSING; MAX_LANES],
        before: [0; MAX_LANES],
        mesh: [None; MAX_LANES],
    };
    let (crossed, mesh) = (&mut hits.crossed, &mut hits.mesh);
    match summary {
        // No lane crosses a fragment (`advance` would not enter its loop): meshes from the
        // inside masks, none where no lane is inside one.
        Some(s) if s.crosses_nothing(ctx.back) => {
            if s.inside_any != 0 {
                let insides = &state.inside[x0..x0 + L::LANES];
                for ((m, b), &inside) in mesh.iter_mut().zip(&mut hits.before).zip(insides) {
                    *m = first_mesh(inside);
                    *b = inside;
                }
            }
        }
        _ => {
            for i in 0..L::LANES {
                let x = x0 + i;
                let end = ldi.offsets[y * w + x + 1];
                let (next, inside) = (&mut state.next[x], &mut state.inside[x]);
                hits.before[i] = *inside;
                crossed[i] = advance(ldi, next, end, inside, ctx.back);
                hits.last[i] = next.wrapping_sub(1);
                mesh[i] = if crossed[i] != NO_CROSSING {
                    Some(u32::from(ldi.mesh[crossed[i] as usize]))
                } else {
                    first_mesh(state.inside[x])
                };
            }
        }
    }

    // Every lane's surface hold (after its cursor, as in the per-pixel stage).
    let mut held = [Held::Free; MAX_LANES];
    let mut released = false;
    let crossing = hits.crossed[..L::LANES].iter().any(|&c| c != NO_CROSSING);
    // Most chunks hold, cross and lie in nothing: one look at their hold words and inside masks.
    if plan.has_surface_hold()
        && (crossing
            || state.hold[x0..x0 + L::LANES].iter().any(|&h| h != 0)
            || state.inside[x0..x0 + L::LANES].iter().any(|&m| m != 0))
    {
        for (i, h) in held.iter_mut().enumerate().take(L::LANES) {
            *h = hold(ctx, state, (x0 + i, y), (hits.crossed[i], hits.before[i]));
            released |= matches!(h, Held::Release { .. });
        }
    }

    // 1. Convolution of every light buffer (and, distance penumbra, its depth plane).
    let mut iin = [L::splat(0.0); N];
    let mut depth_in = [L::splat(0.0); N];
    match (known_light, gathered) {
        // Every value read is `v` and every depth read is 0 (the quiet spans track both).
        (Some(v), _) => iin[..n].fill(L::splat(v)),
        (None, Some(values)) => {
            for (i, v) in iin[..n].iter_mut().enumerate() {
                *v = L::load(values, i * L::LANES);
            }
        }
        (None, None) => {
            for (l, light) in plan.lights.iter().enumerate() {
                let t = &light.table;
                let planes = light_planes(plan, prev, l, (ch, planes_per_light));
                let at = TapOrigin {
                    x: x0 as i32,
                    y: y as i32,
                    shift: t.slab_shift[slab],
                    inside: interior,
                };
                let acc = &mut iin[l * ch..(l + 1) * ch];
                if distance {
                    // The light's channels and its depth plane, each lane through its level's row.
                    let planes = LightPlanes {
                        channels: ch + 1,
                        ..planes
                    };
                    let mut all = [L::splat(0.0); 4];
                    let gathered = &mut all[..=ch];
                    let rows = light_rows[l];
                    distance_gather(simd, ctx, l, &planes, rows, at, gathered);
                    copy_channels(acc, &all[..ch]);
                    depth_in[l] = all[ch];
                    continue;
                }
                let uniform = match t.phase_mode {
                    PhaseMode::PerPixel => None,
                    PhaseMode::PerSlab => Some(phase_at(t, ctx.slab, light.slab_hash[slab], 0, 0)),
                    PhaseMode::Schedule => Some(t.slab_phase[slab]),
                };
                match uniform {
                    Some(p) => {
                        let extent = simd.columns[l].extent[p as usize];
                        // Local sums (from 0, as `iin`'s), so they stay in registers.
                        let mut sums = [L::splat(0.0); 3];
                        let sums = &mut sums[..ch];
                        let taps = ctx.taps[l].weighted(p);
                        gather_lanes(&planes, taps, extent, at, sums);
                        copy_channels(acc, sums);
                    }
                    None => {
                        let ph = phases::<L>(t, row.light_hashes[l], plan.hash_x(x0 as u32));
                        let columns = &simd.columns[l];
                        let reads = LaneRows::within::<L>(columns, ph, interior);
                        gather_per_lane(&planes, t, columns, ph, &reads, at, acc);
                    }
                }
            }
        }
    }

    let aheads = (near_held || !plan.subpixel_meshes.is_empty())
        .then(|| lane_aheads::<L>(row, state, x0, &hits.crossed));
    if let Some(aheads) = &aheads
        && near_held
    {
        let rows = searched.then_some(&light_rows[..]);
        held_lanes::<L>(row, x0, (&mut iin[..n], &mut depth_in), rows, aheads);
    }
    if released {
        keep_released_lanes::<L>(row, x0, &held, (&iin[..n], &depth_in));
    }

    // Sub-pixel shadows: the lanes that crossed an opaque surface shade with their light read at
    // its exact shift (the per-pixel stage's, lane by lane); the buffer keeps `iin`.
    let mut parts = [None; MAX_LANES];
    let exact_in;
    let mut iin_shaded = &iin;
    if let Some(aheads) = &aheads
        && any_crossing_subpixel(row, &hits, &mut parts)
    {
        let mut shade_in = iin;
        exact_lanes::<L>(row, x0, (&parts, aheads), &mut shade_in[..n]);
        exact_in = shade_in;
        iin_shaded = &exact_in;
    }

    // 3–4. Shading and compositing.
    let mut attenuation = [L::splat(1.0); 3];
    let lane_mesh = &hits.mesh[..L::LANES];
    let any_crossed = hits.crossed[..L::LANES].iter().any(|&c| c != NO_CROSSING);
    let shaded = lane_mesh.iter().any(Option::is_some) || any_crossed;
    if let Some(m) = lane_mesh.iter().flatten().next().copied() {
        if lane_mesh.iter().all(|&k| k.is_none() || k == Some(m)) {
            attenuation = shade_chunk(row, state, x0, &iin_shaded[..n], m, &hits);
        } else {
            // Lanes on different meshes: the per-pixel stage's shading, lane by lane.
            let mut att = [[1.0f32; MAX_LANES]; 3];
            for (i, lm) in lane_mesh.iter().enumerate() {
                let Some(mi) = *lm else { continue };
                let mut lane_iin = [0.0f32; N];
                for (dst, v) in lane_iin.iter_mut().zip(&iin_shaded[..n]) {
                    *dst = v.lane(i);
                }
                let lane_iin = &lane_iin[..n];
                let a = shade_and_composite(row, state, x0 + i, lane_iin, mi, &hits.lane(i));
                for k in 0..3 {
                    att[k][i] = a[k];
                }
            }
            attenuation = [
                L::load(&att[0], 0),
                L::load(&att[1], 0),
                L::load(&att[2], 0),
            ];
        }
    }

    // 5. Attenuate (and flush) into this slab's outgoing light buffer: held lanes pass the
    // light, released ones remove it (recorded at their crossing's depth).
    let mut removed_at = L::splat(ctx.slab as f32);
    let mut release_lanes = None;
    if held[..L::LANES].iter().any(|&h| h != Held::Free) || parts.iter().any(Option::is_some) {
        let release;
        (attenuation, removed_at, release) = held_attenuation(ctx.slab, &held, &parts, attenuation);
        release_lanes = Some(release);
    }
    let (zero, one) = (L::splat(0.0), L::splat(1.0));
    let mut not_one = zero.ne(zero);
    let mut not_zero = not_one;
    let mut light_not_zero = not_one;
    let planes = planes_per_light;
    for l in 0..plan.lights.len() {
        let (mut lit_in, mut lit_out) = (zero, zero);
        let mut outs = [zero; 4];
        for c in 0..ch {
            let out = attenuate(iin[l * ch + c], attenuation[c]);
            not_one = L::m_or(not_one, out.ne(one));
            not_zero = L::m_or(not_zero, out.ne(zero));
            light_not_zero = L::m_or(light_not_zero, out.ne(zero));
            outs[c] = out;
            if distance {
                (lit_in, lit_out) = (lit_in + iin[l * ch + c], lit_out + out);
            }
        }
        if distance {
            // The light this slab removed, at this slab's depth; a depth plane's quiet value is 0.
            let removed = (lit_in, lit_out, removed_at);
            let depth = finish_depth(ctx, state, l, x0, depth_in[l], removed, release_lanes);
            let moved_depth = depth.ne(zero);
            not_one = L::m_or(not_one, moved_depth);
            not_zero = L::m_or(not_zero, moved_depth);
            outs[ch] = depth;
        }
        store_pixels(
            &outs[..planes],
            state.light,
            light_block(plan, l) + x0 * planes,
        );
    }

    ChunkOutcome {
        not_one: L::m_any(not_one),
        not_zero: L::m_any(not_zero),
        light_not_zero: L::m_any(light_not_zero),
        shaded,
        crossed: any_crossed || released,
    }
}

/// Step 5's attenuation per lane under the lanes' surface holds `held`: 1 where held, 0 where
/// released, else `attenuation`; the depth (slabs) each lane's removed light is recorded at:
/// a released lane's crossing slab, a free lane's sub-pixel crossing at its part of the slab
/// (`parts`: [`removal_depth`]), else this slab; and the released lanes.
#[inline(always)]
fn held_attenuation<L: Layout>(
    slab: u32,
    held: &[Held; MAX_LANES],
    parts: &[Option<f32>; MAX_LANES],
    attenuation: [L; 3],
) -> ([L; 3], L, L::M) {
    let (mut pass, mut release, mut at) = (
        [0.0f32; MAX_LANES],
        [0.0f32; MAX_LANES],
        [0.0f32; MAX_LANES],
    );
    for i in 0..L::LANES {
        at[i] = slab as f32;
        match held[i] {
            Held::Free => {
                if let Some(part) = parts[i] {
                    at[i] = removal_depth(slab, part);
                }
            }
            Held::Pass => pass[i] = 1.0,
            Held::Release { removed_at } => {
                release[i] = 1.0;
                at[i] = removed_at as f32;
            }
        }
    }
    let (zero, one) = (L::splat(0.0), L::splat(1.0));
    let (pass, release) = (L::load(&pass, 0).gt(zero), L::load(&release, 0).gt(zero));
    let attenuation = attenuation.map(|a| L::select(pass, one, L::select(release, zero, a)));
    (attenuation, L::load(&at, 0), release)
}

/// Sub-pixel shadows: whether some lane crossed a surface that reads its light at the exact
/// shift, with each such lane's part of the slab in `parts` (`None` elsewhere).
#[inline(always)]
fn any_crossing_subpixel(
    row: &RowContext<'_>,
    hits: &LaneHits,
    parts: &mut [Option<f32>; MAX_LANES],
) -> bool {
    if row.ctx.plan.subpixel_meshes.is_empty() || hits.crossed.iter().all(|&c| c == NO_CROSSING) {
        return false;
    }
    let mut any = false;
    for (i, part) in parts.iter_mut().enumerate() {
        *part = subpixel_part(row.ctx, &hits.lane(i));
        any |= part.is_some();
    }
    any
}

/// `dst = src` for a light's channels, as fixed-length copies for 1 and 3 channels (a run-time
/// length is a `memcpy` call per light and chunk).
#[inline(always)]
fn copy_channels<L: Layout>(dst: &mut [L], src: &[L]) {
    match (dst, src) {
        ([d], [s]) => *d = *s,
        ([d0, d1, d2], [s0, s1, s2]) => (*d0, *d1, *d2) = (*s0, *s1, *s2),
        (dst, src) => dst.copy_from_slice(src),
    }
}

/// Distance penumbra: for every light l, the rows (level and phase) the lanes at pixels x0.. of
/// the row gather through, the level each lane's neighbourhood picks ([`distance_rows`]), into
/// `all[l]` (in place: an array returned by value cost 1.9 % of the sweep's instructions in
/// copies). `interior`: every read lies inside the grid.
#[inline(always)]
fn every_light_rows<L: Layout>(
    simd: &SimdSlab<'_>,
    row: &RowContext<'_>,
    x0: usize,
    interior: bool,
    all: &mut [L::U],
) {
    let ctx = row.ctx;
    let plan = ctx.plan;
    let slab = ctx.slab as usize;
    for (l, (light, rows)) in plan.lights.iter().zip(all.iter_mut()).enumerate() {
        let t = &light.table;
        let phase = match t.phase_mode {
            PhaseMode::PerPixel => phases::<L>(t, row.light_hashes[l], plan.hash_x(x0 as u32)),
            PhaseMode::PerSlab => L::u_splat(phase_at(t, ctx.slab, light.slab_hash[slab], 0, 0)),
            PhaseMode::Schedule => L::u_splat(0),
        };
        // Every level one kernel: level 0's rows gather the same bits, no search needed.
        if plan.levels_share_one_kernel() {
            *rows = level_rows::<L>(t, L::u_splat(0), phase, plan.slabs, ctx.slab);
            continue;
        }
        let levels = level_plane(plan, row.prev, l);
        let at = TapOrigin {
            x: x0 as i32,
            y: row.y as i32,
            shift: t.slab_shift[slab],
            inside: interior,
        };
        let columns = &simd.columns[l];
        *rows = distance_rows::<L>(&levels, t, columns, phase, plan.slabs, ctx.slab, at);
    }
}

/// Distance penumbra: light `l`'s planes `planes` (its channels and depth plane, or the depth
/// plane alone) gathered from `at` (the chunk's first pixel), each lane through its row `rows`
/// ([`every_light_rows`]); contiguous loads when every lane has the same row.
#[inline(always)]
fn distance_gather<L: Layout>(
    simd: &SimdSlab<'_>,
    ctx: &SlabContext<'_>,
    l: usize,
    planes: &LightPlanes<'_>,
    rows: L::U,
    at: TapOrigin,
    acc: &mut [L],
) {
    let t = &ctx.plan.lights[l].table;
    let columns = &simd.columns[l];
    let reads = LaneRows::within::<L>(columns, rows, at.inside);
    match reads.uniform {
        // Every lane at the same level and phase: contiguous loads.
        Some(row) => {
            let extent = columns.extent[row as usize];
            gather_lanes(planes, ctx.taps[l].weighted(row), extent, at, acc);
        }
        None => gather_per_lane(planes, t, columns, rows, &reads, at, acc),
    }
}

/// Distance penumbra, step 5 for light `l`'s depth plane at pixels x0..: the gathered depth
/// `depth_in` deepened by the light the slab removed (`lit_in − lit_out`, summed over channels,
/// at depth `removed_at` per lane; `released` lanes: [`owned_depth`]), and the level each pixel
/// starts the next slab with (stored). Returns the outgoing depth, for the caller to store with
/// the light's channels.
#[inline(always)]
fn finish_depth<L: Layout>(
    ctx: &SlabContext<'_>,
    state: &mut RowState<'_>,
    l: usize,
    x0: usize,
    depth_in: L,
    (lit_in, lit_out, removed_at): (L, L, L),
    released: Option<L::M>,
) -> L {
    let plan = ctx.plan;
    let (w, ch) = (plan.grid_width as usize, plan.channels as usize);
    let occluded = L::splat(ch as f32) - lit_out;
    let removed_at = depth_coord(plan.depth_scale.as_ref(), removed_at);
    let mut out = deepen(depth_in, removed_at, lit_in - lit_out);
    if let Some(released) = released {
        out = L::select(released, owned_depth(removed_at, occluded), out);
    }
    let level = pixel_level::<L>(&plan.lights[l].table, occluded, out, ctx.next_level_at);
    let mut lanes = [0u32; MAX_LANES];
    L::u_store(level, &mut lanes);
    state.levels[l * w + x0..][..L::LANES].copy_from_slice(&lanes[..L::LANES]);
    out
}

/// Distance penumbra: a chunk of opaque pixels (alpha exactly 1) whose kernels read only exact
/// 0s in every light plane, while its depth planes are not 0 (the dark chunk of
/// [`super::quiet::ChunkWork::Dark`] needs both). Only the depth planes and the levels are
/// computed: every light value gathered is 0, so attenuated it stays 0, the slab removes
/// `0 − 0 = 0`, compositing an opaque pixel adds `(1 − 1)·α·c = 0`, and the depth and level are
/// those of the full stage, bit for bit. The caller advances the cursors. Returns whether some
/// depth value is not 0. `interior`: every read of the chunk's gathers lies inside the grid.
pub(crate) fn dark_depth_chunk(
    simd: &SimdSlab<'_>,
    row: &RowContext<'_>,
    state: &mut RowState<'_>,
    x0: usize,
    interior: bool,
) -> bool {
    let (ctx, prev) = (row.ctx, row.prev);
    let plan = ctx.plan;
    let ch = plan.channels as usize;
    let zero = f32x8::splat(0.0);
    let mut not_zero = false;
    // Every light's level search first (see `sweep_chunk`), then the gathers.
    let mut light_rows = [<f32x8 as Lane>::u_splat(0); MAX_LIGHTS];
    every_light_rows::<f32x8>(simd, row, x0, interior, &mut light_rows);
    for (l, &rows) in light_rows.iter().enumerate().take(plan.lights.len()) {
        let planes = light_planes(plan, prev, l, shape_planes::<ANY_SHAPE>(plan));
        let depth_plane = LightPlanes {
            base: planes.base + ch,
            channels: 1,
            light_channels: 0,
            ..planes
        };
        let at = TapOrigin {
            x: x0 as i32,
            y: row.y as i32,
            shift: plan.lights[l].table.slab_shift[ctx.slab as usize],
            inside: interior,
        };
        let mut depth_in = [zero];
        distance_gather(simd, ctx, l, &depth_plane, rows, at, &mut depth_in);
        // Σ of the gathered and of the attenuated light, as the stage sums them: 0 + 0 + … = 0.
        let at = f32x8::splat(ctx.slab as f32);
        let depth = finish_depth(ctx, state, l, x0, depth_in[0], (zero, zero, at), None);
        let mut outs = [zero; 4];
        outs[ch] = depth;
        let block = light_block(plan, l) + x0 * (ch + 1);
        store_pixels(&outs[..=ch], state.light, block);
        not_zero |= <f32x8 as Lane>::m_any(depth.ne(zero));
    }
    not_zero
}

/// Stages 3–4 for the lanes at pixels x0.. whose shaded pixels all lie in mesh `m`
/// (`hits.mesh[i]` is `None` in lanes without a mesh): shading and compositing. Returns the
/// attenuation per channel (1 in lanes without a mesh).
#[inline(always)]
fn shade_chunk<L: Layout>(
    row: &RowContext<'_>,
    state: &mut RowState<'_>,
    x0: usize,
    iin: &[L],
    m: u32,
    hits: &LaneHits,
) -> [L; 3] {
    let (ctx, y) = (row.ctx, row.y);
    let (mesh, crossed) = (&hits.mesh, &hits.crossed);
    let plan = ctx.plan;
    let ldi = ctx.ldi;
    let w = plan.grid_width as usize;
    let mut active = [false; MAX_LANES];
    let mut any_crossed = false;
    let mut is_crossed = [false; MAX_LANES];
    let mut xs = [0.0f32; MAX_LANES];
    let mut zs = [0.0f32; MAX_LANES];
    let mut insides = [1.0f32; MAX_LANES];
    let mut lit_froms = [0.0f32; MAX_LANES];
    for i in 0..L::LANES {
        active[i] = mesh[i].is_some();
        is_crossed[i] = crossed[i] != NO_CROSSING;
        any_crossed |= is_crossed[i];
        xs[i] = plan.image_xy(x0 + i, y).0;
        zs[i] = shading_depth(plan, ldi, crossed[i], ctx.front, row.jitter_hash, x0 + i);
        if active[i] {
            (insides[i], lit_froms[i]) = slab_part(
                ldi,
                (m, plan.second_order_media),
                (hits.before[i], state.inside[x0 + i]),
                (crossed[i], hits.last[i]),
                (ctx.front, ctx.back),
                plan.inv_slab_distance,
            );
        }
    }
    let active_lanes = active;
    let active = L::m_from(&active);
    let z = L::load(&zs, 0);
    let material = &plan.materials[plan.mesh_material[m as usize] as usize];
    let (xv, yv) = (L::load(&xs, 0), L::splat(plan.image_xy(x0, y).1));
    let mut lit_from = L::load(&lit_froms, 0);
    let mut tf = match &material.pre {
        Some(table) => {
            // A pre-integrated entry has the light's decay inside the slab in its colour.
            lit_from = L::splat(0.0);
            preintegrated(ctx, state, x0, m, table, [xv, yv], hits)
        }
        None => {
            if plan.preintegration {
                forget_front(state, x0, L::LANES, &active_lanes);
            }
            material_at(plan, m, xv, yv, z)
        }
    };
    // Lanes that crossed a surface get the highlight and, where opaque, the Lambert cosine and
    // the horizon, with their triangles' normals.
    let surface = if any_crossed && uses_normals(plan, material) {
        let mut normal = [[0.0f32; MAX_LANES]; 3];
        for i in 0..L::LANES {
            let nv = if is_crossed[i] {
                ctx.raster.triangles[ldi.triangle[crossed[i] as usize] as usize].normal
            } else {
                [0.0, 0.0, 1.0]
            };
            for k in 0..3 {
                normal[k][i] = nv[k];
            }
        }
        let normal = [0, 1, 2].map(|k| L::load(&normal[k], 0));
        Some((normal, L::m_from(&is_crossed)))
    } else {
        None
    };
    let mut color = [
        L::load(state.color, x0),
        L::load(state.color, w + x0),
        L::load(state.color, 2 * w + x0),
    ];
    let mut alpha = L::load(state.alpha, x0);
    let part = (L::load(&insides, 0), lit_from);
    let target = (&mut color, &mut alpha);
    shade_sample(plan, material, &mut tf, part, iin, surface, target, active);
    for (k, v) in color.iter().enumerate() {
        v.store(state.color, k * w + x0);
    }
    alpha.store(state.alpha, x0);
    let one = L::splat(1.0);
    [
        L::select(active, tf.attenuation[0], one),
        L::select(active, tf.attenuation[1], one),
        L::select(active, tf.attenuation[2], one),
    ]
}

/// Pre-integrated shading (`sweep.preintegration`) of the lanes at pixels x0.. (image
/// coordinates `xy`) of mesh `m` (those whose `hits.mesh` is some) whose material has the
/// pre-integration table `table`: the table's entry at the detail values on the slab's front and
/// back faces. The front value is the one the previous slab kept in `state.pre` (NaN: none), else evaluated at the front face, or at the crossed fragment's depth
/// where the pixel crosses a surface in this slab. The back value is kept for the next slab when
/// the pixel is still in mesh `m` at the back face (the next slab shades `m` unless it crosses a
/// surface), else NaN. The detail is a pure function of pixel, mesh and depth, and slab k's back
/// face is slab k + 1's front face bit for bit, so a kept value has the bits of a fresh one:
/// keeping it only saves an evaluation, and forgetting it never changes the image.
#[inline(always)]
fn preintegrated<L: Layout>(
    ctx: &SlabContext<'_>,
    state: &mut RowState<'_>,
    x0: usize,
    m: u32,
    table: &[TfEntry],
    [x, y]: [L; 2],
    hits: &LaneHits,
) -> TfLanes<L> {
    let plan = ctx.plan;
    let crossed = &hits.crossed;
    let active: [bool; MAX_LANES] = std::array::from_fn(|i| hits.mesh[i].is_some());
    let mut zf = [ctx.front; MAX_LANES];
    let mut use_kept = [false; MAX_LANES];
    let mut fresh = false;
    for i in 0..L::LANES {
        let is_crossed = crossed[i] != NO_CROSSING;
        if is_crossed {
            zf[i] = ctx.ldi.depth[crossed[i] as usize];
        }
        use_kept[i] = !is_crossed && !state.pre[x0 + i].is_nan();
        fresh |= active[i] && !use_kept[i];
    }
    let kept = L::load(state.pre, x0);
    let front = if fresh {
        let v = detail_at(plan, m, x, y, L::load(&zf, 0));
        L::select(L::m_from(&use_kept), kept, v)
    } else {
        kept
    };
    let back = detail_at(plan, m, x, y, L::splat(ctx.back));
    for (i, _) in active[..L::LANES].iter().enumerate().filter(|(_, a)| **a) {
        let xi = x0 + i;
        state.pre[xi] = if first_mesh(state.inside[xi]) == Some(m) {
            back.lane(i)
        } else {
            f32::NAN
        };
    }
    pre_transfer(table, front, back)
}

/// Forgets the kept front value (see [`preintegrated`]) of the `active` lanes of pixels x0..:
/// they were shaded by a material without a pre-integration table.
#[inline(always)]
fn forget_front(state: &mut RowState<'_>, x0: usize, lanes: usize, active: &[bool; MAX_LANES]) {
    for (i, _) in active[..lanes].iter().enumerate().filter(|(_, a)| **a) {
        state.pre[x0 + i] = f32::NAN;
    }
}

#[cfg(test)]
mod tests;
