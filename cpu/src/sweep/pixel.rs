//! The per-pixel stage of the sweep: what one pixel does in one slab, in the five steps of
//! `gpu/src/shaders/sweep.wgsl` (`sweep_slab`) and in its order, each step one call:
//!
//! 1. convolution of every light buffer (`crate::kernels`);
//! 2. intersection: the layer cursor (`crate::parity`);
//! 3. shading at one point (`crate::shading`);
//! 4. compositing and
//! 5. attenuation with the flush (`crate::composite`).
//!
//! `--path scalar` runs it on every pixel of every row ([`sweep_row`]); the SIMD path on the
//! pixels of a row's tail that fill no 8-lane chunk. The SIMD path's 8-lane chunks (`super::fast`)
//! must give its bits in every lane; the tests there hold them to it.
//!
//! Plain `f32` code, one pixel, as the shader writes it. The stage modules it calls are written
//! over `Lane` (their 8-lane instances serve the fast chunks), and this file calls their 1-lane
//! instances, so its arithmetic is theirs by construction; only the control flow around them is
//! written here for one pixel: which lights, the cursor, whether to shade. That control flow,
//! written once for both lane counts, carried the 8-lane path's machinery (lane masks, per-lane
//! scratch arrays, compile-time shapes, skipped cursors, known light) into the scalar path, where
//! it did nothing but hide the five steps.
//!
//! Where it reads its inputs differently from sweep.wgsl, the values are the same (none of these
//! changes a bit): the light buffers are pixel-interleaved (`crate::kernels::LightPlanes`); the
//! gather leaves out taps whose four weights are 0 (`crate::kernels::LightTaps`); the level search
//! visits one padding tap for all and reads a tap's four level corners as one 2×2 block minimum
//! (`crate::kernels::LevelPlane::corners`).

use convshadow_common::pixel::levels::{depth_coord, pixel_level};
use convshadow_common::plan::TfEntry;
use convshadow_common::plan::kernel::Tap;
use convshadow_common::plan::surface_hold::{ENTRY_HOLD_MASK, exit_of};

use super::kit::{
    MAX_LIGHT_CHANNELS, MAX_LIGHTS, RowContext, RowState, SlabContext, level_plane, light_block,
    light_planes,
};
use crate::composite::{
    HELD_PART_MAX, HOLD_LENGTH_MASK, HOLD_SHIFT, HOLD_SLAB_MASK, Held, HeldSlot, attenuate, deepen,
    hold_step, owned_depth, release_slab, shade_sample,
};
use crate::kernels::{LightPlanes, TapOrigin, distance_row, gather, gather_held, phase_at};
use crate::parity::{NO_CROSSING, advance, first_mesh, leaves_its_mesh, slab_part};
use crate::shading::{TfLanes, detail_at, material_at, pre_transfer, shading_depth, uses_normals};
use crate::subpixel::{exact_shift, removal_depth, shifted_gather};

/// The light a pixel gathered in step 1: every light's channels and (distance penumbra) its
/// occluder depth.
pub(crate) struct LightIn {
    /// Light l's channel c at `l · channels + c`.
    pub(crate) iin: [f32; MAX_LIGHT_CHANNELS],
    /// Light l's gathered depth plane.
    pub(crate) depth: [f32; MAX_LIGHTS],
}

impl LightIn {
    /// Nothing gathered yet.
    pub(crate) const ZERO: LightIn = LightIn {
        iin: [0.0; MAX_LIGHT_CHANNELS],
        depth: [0.0; MAX_LIGHTS],
    };
}

/// What step 2 found: the first and last fragments the cursor crossed in this slab
/// ([`NO_CROSSING`] if none), the inside mask it had at the slab's front, and the mesh the pixel
/// shades, if any.
#[derive(Clone, Copy)]
pub(crate) struct Hit {
    pub crossed: u32,
    pub last: u32,
    pub before: u32,
    pub mesh: Option<u32>,
}

/// Processes one row of one slab, one pixel at a time (`--path scalar`).
pub(crate) fn sweep_row(row: &RowContext<'_>, state: &mut RowState<'_>) {
    let plan = row.ctx.plan;
    let (w, h) = (plan.grid_width as usize, plan.grid_height as usize);
    for x in 0..w {
        let inside = row.ctx.reach.interior(x, 1, row.y, w, h);
        sweep_pixel(row, state, x, inside);
    }
}

/// Pixel x of the row through this slab: sweep.wgsl's `sweep_slab` for one pixel. `inside`:
/// every read of its gathers lies inside the grid.
#[inline(always)]
pub(crate) fn sweep_pixel(row: &RowContext<'_>, state: &mut RowState<'_>, x: usize, inside: bool) {
    // 1. Convolution of every light buffer (and, distance penumbra, its depth plane).
    let mut light = LightIn::ZERO;
    let ahead = next_fragment(row.ctx, state, (x, row.y));
    convolve(row, x, inside, &mut light, ahead);
    // 2. Intersection: advance the layer cursor to the slab's back face.
    let hit = intersect(row.ctx, row.y, state, x);
    let held = hold(row.ctx, state, (x, row.y), (hit.crossed, hit.before));
    // Sub-pixel shadows: a crossed opaque surface's light read at its exact shift.
    let part = subpixel_part(row.ctx, &hit);
    let exact_in;
    let mut shade_in = &light.iin;
    if let Some(part) = part {
        let mut read = light.iin;
        exact_light(row, x, &light, (part, ahead), &mut read);
        exact_in = read;
        shade_in = &exact_in;
    }
    // 3. Shading at one point, if inside a mesh or a surface was crossed; 4. composite.
    let attenuation = match hit.mesh {
        Some(mesh) => shade_and_composite(row, state, x, shade_in, mesh, &hit),
        None => [1.0; 3],
    };
    // 5. Attenuate (and flush) into this slab's outgoing light buffer — a held surface passes
    // it, a released one removes it; distance penumbra: the light this slab removed, at its
    // depth (an opaque crossing's own, with sub-pixel shadows), into the depth plane, and the
    // next level.
    let slab = row.ctx.slab;
    let (attenuation, removed_at) = match held {
        Held::Free => (
            attenuation,
            part.map_or(slab as f32, |p| removal_depth(slab, p)),
        ),
        Held::Pass => ([1.0; 3], slab as f32),
        Held::Release { removed_at } => ([0.0; 3], removed_at as f32),
    };
    let released = matches!(held, Held::Release { .. });
    if released {
        keep_release(row, x, &light);
    }
    attenuate_light(
        row.ctx,
        state,
        x,
        &light,
        attenuation,
        (removed_at, released),
    );
}

/// Sub-pixel shadows: where in its slab (0 at the front face, 1 at the back) the pixel crossed
/// a surface of a mesh in [`RenderPlan::subpixel_meshes`](convshadow_common::plan::RenderPlan),
/// or `None`.
#[inline(always)]
pub(crate) fn subpixel_part(ctx: &SlabContext<'_>, hit: &Hit) -> Option<f32> {
    let meshes = &ctx.plan.subpixel_meshes;
    if meshes.is_empty() || hit.crossed == NO_CROSSING {
        return None;
    }
    let mesh = hit.mesh.expect("a crossing has a mesh") as usize;
    meshes[mesh]
        .then(|| (ctx.ldi.depth[hit.crossed as usize] - ctx.front) * ctx.plan.inv_slab_distance)
}

/// Sub-pixel shadows at pixel x, which crossed an opaque surface at `part` of the slab (the
/// fragment `ahead` of its cursor before the slab): every occluded light's channels in
/// `shade_in` read again where the exact drift puts them ([`exact_shift`], [`shifted_gather`]),
/// through the tap row step 1 used, reading corners as step 1 did ([`held_fix`]).
pub(crate) fn exact_light(
    row: &RowContext<'_>,
    x: usize,
    light: &LightIn,
    (part, ahead): (f32, Option<u32>),
    shade_in: &mut [f32; MAX_LIGHT_CHANNELS],
) {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    let ch = plan.channels as usize;
    let mut reader = None;
    for (l, light_plan) in plan.lights.iter().enumerate() {
        let channels = &light.iin[l * ch..(l + 1) * ch];
        let lit = channels.iter().fold(0.0f32, |a, &v| a + v);
        let gathered = (lit, plan.channels);
        let at = TapOrigin {
            x: x as i32,
            y: row.y as i32,
            shift: light_plan.table.slab_shift[ctx.slab as usize],
            inside: false,
        };
        // The row of the level step 1 would search (bounds-checked reads: the same values).
        let tap_row = tap_row(row, l, at, true);
        let row_level = tap_row / light_plan.table.phase_count;
        let (slab, depth) = ((ctx.slab, part), light.depth[l]);
        let Some(shift) = exact_shift(light_plan, slab, gathered, depth, row_level) else {
            continue;
        };
        let planes = LightPlanes {
            channels: ch,
            ..light_planes(plan, row.prev.light, l)
        };
        let taps = ctx.taps[l].weighted(tap_row);
        // The hint for the gathers at the moved origins (their reach moved by the shift).
        let (ix, iy) = (shift[0].floor() as i32, shift[1].floor() as i32);
        let (xs, ys) = ((at.x + ix, at.x + ix + 1), (at.y + iy, at.y + iy + 1));
        let reach = &ctx.reach;
        let xs = (xs.0 + reach.x0, xs.1 + reach.x1);
        let ys = (ys.0 + reach.y0, ys.1 + reach.y1);
        let sums = if ctx.held.any_in(xs, ys, ctx.slab) {
            // Released corners as step 1 read them; held ones from everywhere.
            let reader = *reader.get_or_insert_with(|| Reader::of(row, x, ahead));
            let fix = held_fix(row, reader, l, false);
            let fixed = |p: &LightPlanes<'_>, t: &[Tap], a| gather_held(p, t, a, &fix);
            shifted_gather(&planes, taps, at, shift, fixed)
        } else {
            shifted_gather(&planes, taps, at, shift, gather)
        };
        shade_in[l * ch..(l + 1) * ch].copy_from_slice(&sums[..ch]);
    }
}

/// Step 2's surface hold at pixel x of row y, whose cursor crossed fragment `crossed` in this
/// slab ([`NO_CROSSING`]: none) from the inside mask `inside_before`: [`hold_step`] with the crossed triangle's hold word, ending a
/// pending hold where the pixel has fragments left behind the crossing, its barrier outside
/// every closed mesh; else the **exit hold**
/// ([`exit_hold`](convshadow_common::plan::surface_hold::exit_hold)): a pixel inside the mesh
/// of its next fragment passes its light while that fragment lies fewer than its triangle's
/// exit hold slabs beyond the slab's back face.
#[inline(always)]
pub(crate) fn hold(
    ctx: &SlabContext<'_>,
    state: &mut RowState<'_>,
    (x, y): (usize, usize),
    (crossed, inside_before): (u32, u32),
) -> Held {
    let (plan, ldi) = (ctx.plan, ctx.ldi);
    if !plan.has_surface_hold() {
        return Held::Free;
    }
    let end = ldi.offsets[y * plan.grid_width as usize + x + 1];
    let (crossed_word, ends_hold) = if crossed == NO_CROSSING {
        (0, false)
    } else {
        let word = plan.surface_hold[ldi.triangle[crossed as usize] as usize];
        // Leaving a closed mesh starts no hold: there is no attenuation to delay, and its
        // release would take out, far behind the face, light the pixel has gathered since.
        let word = if leaves_its_mesh(ldi, crossed, inside_before) {
            word & !ENTRY_HOLD_MASK
        } else {
            word
        };
        (word, state.next[x] < end)
    };
    let inside = state.inside[x] != 0;
    let before = state.hold[x];
    let held = hold_step(
        &mut state.hold[x],
        ctx.slab,
        crossed_word,
        ends_hold,
        inside,
    );
    record_held(ctx, (x, y), (before, state.hold[x]), held, crossed);
    // Outside every mesh (most pixels, and every pixel of an open mesh) no exit is near.
    if held != Held::Free || !inside || state.next[x] >= end {
        return held;
    }
    let next = state.next[x] as usize;
    let exit = exit_of(plan.surface_hold[ldi.triangle[next] as usize]);
    let in_its_mesh = state.inside[x] & (1 << ldi.mesh[next]) != 0;
    if exit != 0
        && in_its_mesh
        && (ldi.depth[next] - ctx.back) * plan.inv_slab_distance < exit as f32
    {
        return Held::Pass;
    }
    Held::Free
}

/// Keeps pixel (x, y)'s held-plane record ([`HeldPlanes`](crate::composite::HeldPlanes)) with its hold, which went from state
/// `before` to `after` in this slab: an entry hold that starts records its crossing's plane, one
/// that a crossing cut short records its end.
#[inline(always)]
fn record_held(
    ctx: &SlabContext<'_>,
    (x, y): (usize, usize),
    (before, after): (u32, u32),
    held: Held,
    crossed: u32,
) {
    if ctx.held.words.is_empty() {
        return;
    }
    let slab = ctx.slab;
    let p = y * ctx.plan.grid_width as usize + x;
    let entry_hold = |state: u32| state != 0 && (state >> HOLD_SHIFT) & HOLD_LENGTH_MASK != 0;
    let started = before != after && after & HOLD_SLAB_MASK == slab;
    if held == Held::Pass && crossed != NO_CROSSING && entry_hold(after) && started {
        let ldi = ctx.ldi;
        let depth = ldi.depth[crossed as usize];
        let part = ((depth - ctx.front) * ctx.plan.inv_slab_distance).clamp(0.0, HELD_PART_MAX);
        ctx.held.start(
            p,
            (x, y),
            HeldSlot {
                from: slab,
                until: release_slab(after),
                z0: slab as f32 + part,
                triangle: ldi.triangle[crossed as usize],
            },
        );
    } else if matches!(held, Held::Release { .. })
        && entry_hold(before)
        && slab < release_slab(before)
    {
        ctx.held.cut(p, slab);
    }
}

/// Step 1: every light's planes gathered at pixel x through its kernel's tap row for this slab
/// and pixel (distance penumbra: the row of the nearest occluder's level in reach), into `light`.
/// `ahead`: the fragment the pixel's cursor crosses next ([`next_fragment`]). (Filled in place: a
/// returned copy of it cost 5 % of the scalar sweep in store-forwarding stalls.)
#[inline(always)]
pub(crate) fn convolve(
    row: &RowContext<'_>,
    x: usize,
    inside: bool,
    light: &mut LightIn,
    ahead: Option<u32>,
) {
    if held_near(row, x, 1) {
        let reader = Reader::of(row, x, ahead);
        if reader.reads_otherwise(row.ctx) {
            return convolve_held(row, x, inside, light, reader);
        }
    }
    convolve_through(row, x, inside, light, None, |_, planes, taps, at| {
        gather(planes, taps, at)
    });
}

/// Step 1 with `gather(l, planes, taps, at)` as light l's gather, through tap row `rows[l]`
/// where given (a chunk's own level search's), else [`tap_row`]'s.
#[inline(always)]
fn convolve_through(
    row: &RowContext<'_>,
    x: usize,
    inside: bool,
    light: &mut LightIn,
    rows: Option<&[u32]>,
    gather: impl Fn(usize, &LightPlanes<'_>, &[Tap], TapOrigin) -> [f32; 4],
) {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    let (ch, slab) = (plan.channels as usize, ctx.slab as usize);
    for l in 0..plan.lights.len() {
        let at = TapOrigin {
            x: x as i32,
            y: row.y as i32,
            shift: plan.lights[l].table.slab_shift[slab],
            inside,
        };
        let tap_row = match rows {
            Some(rows) => rows[l],
            None => tap_row(row, l, at, false),
        };
        // The light's channels, then its depth plane if any (0 without one).
        let planes = light_planes(plan, row.prev.light, l);
        let sums = gather(l, &planes, ctx.taps[l].weighted(tap_row), at);
        copy_planes(&mut light.iin[l * ch..(l + 1) * ch], &sums);
        light.depth[l] = sums[ch];
    }
}

/// Whether the gathers of pixels `x0 .. x0 + lanes` may read a pixel otherwise than from the
/// light buffer ([`held_fix`]): some pixel near what they read held its light in the previous
/// slab (`held_lit_side`) or released it recently (`HeldPlanes::near`, from the window prepared
/// for the gathers' reach). A hint that decides no bit.
#[inline(always)]
pub(crate) fn held_near(row: &RowContext<'_>, x0: usize, lanes: usize) -> bool {
    let (ctx, reach) = (row.ctx, &row.ctx.reach);
    let (x0, y) = (x0 as i32, row.y as i32);
    let xs = (x0 + reach.x0, x0 + lanes as i32 - 1 + reach.x1);
    debug_assert_eq!(ctx.held.window_rows, (reach.y0, reach.y1));
    ctx.held.near(xs, y, ctx.slab)
}

/// A gathering pixel as [`held_fix`] reads corners for it, found once per pixel and slab: its
/// position, whether it held its light in the previous slab, and the surface it lies on (its
/// held crossing's depth in slabs and triangle, else the fragment ahead of its cursor's).
#[derive(Clone, Copy)]
pub(crate) struct Reader {
    q: (i32, i32),
    held: bool,
    surface: Option<(f32, u32)>,
}

impl Reader {
    /// Pixel x of the row, whose cursor crosses fragment `ahead` next ([`next_fragment`]).
    #[inline(always)]
    pub(crate) fn of(row: &RowContext<'_>, x: usize, ahead: Option<u32>) -> Reader {
        let (ctx, plan, slab) = (row.ctx, row.ctx.plan, row.ctx.slab);
        let own = ctx
            .held
            .latest_before(row.y * plan.grid_width as usize + x, slab)
            .filter(|s| s.held_before(slab));
        let surface = match own {
            Some(held) => Some((held.z0, held.triangle)),
            None => ahead.map(|f| {
                let depth = ctx.ldi.depth[f as usize];
                let z = slab as f32 + (depth - ctx.front) * plan.inv_slab_distance;
                (z, ctx.ldi.triangle[f as usize])
            }),
        };
        Reader {
            q: (x as i32, row.y as i32),
            held: own.is_some(),
            surface,
        }
    }

    /// Whether [`held_fix`] may read some corner of its gathers otherwise at all: it reads held
    /// light from its lit side only (`held_lit_side`), or it lies on a surface that released
    /// pixels may be served on.
    #[inline(always)]
    pub(crate) fn reads_otherwise(&self, ctx: &SlabContext<'_>) -> bool {
        ctx.plan.held_lit_side || (!ctx.held.served.is_empty() && self.surface.is_some())
    }
}

/// [`convolve`] through [`gather_held`], reading corners as [`held_fix`] says. Where it changes
/// no corner, [`convolve`]'s bits.
#[inline(never)]
pub(crate) fn convolve_held(
    row: &RowContext<'_>,
    x: usize,
    inside: bool,
    light: &mut LightIn,
    reader: Reader,
) {
    convolve_held_rows(row, x, inside, light, None, reader);
}

/// [`convolve_held`], each light l through tap row `rows[l]` where given (the rows an 8-lane
/// chunk's level search already found for this pixel: [`tap_row`]'s, so the same bits).
#[inline(always)]
pub(crate) fn convolve_held_rows(
    row: &RowContext<'_>,
    x: usize,
    inside: bool,
    light: &mut LightIn,
    rows: Option<&[u32]>,
    reader: Reader,
) {
    let gather = |l, planes: &LightPlanes<'_>, taps: &[Tap], at| {
        gather_held(planes, taps, at, held_fix(row, reader, l, true))
    };
    convolve_through(row, x, inside, light, rows, gather);
}

/// How `reader`'s gathers of light l read a corner otherwise than from the light buffer
/// (`surface_hold`): with `held_lit_side` (and `lit_side`: step 1, not the sub-pixel read),
/// a pixel not held itself reads a held corner behind
/// whose surface it lies as no light, removed at the hold's crossing
/// ([`HeldPlanes::hides`](crate::composite::HeldPlanes::hides)); a pixel on a surface (its held
/// crossing, else the fragment ahead of its cursor) reads a corner released on that surface
/// as the light and depth plane the corner gathered in its release slab
/// ([`HeldPlanes::served`](crate::composite::HeldPlanes::served)).
#[inline(always)]
pub(crate) fn held_fix<'a>(
    row: &'a RowContext<'a>,
    reader: Reader,
    l: usize,
    lit_side: bool,
) -> impl Fn(i32, i32, &mut [f32]) + 'a {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    let (q, slab, surface) = (reader.q, ctx.slab, reader.surface);
    let hiding = lit_side && plan.held_lit_side && !reader.held;
    let ch = plan.channels as usize;
    move |cx, cy, values: &mut [f32]| {
        if hiding && let Some(from) = ctx.held.hides(plan, l, q, (cx, cy), slab) {
            for (c, value) in values.iter_mut().enumerate() {
                *value = if c < ch { 0.0 } else { from as f32 * ch as f32 };
            }
        } else if let Some(surface) = surface
            && let Some(kept) = ctx.held.served(plan, l, (q, surface), (cx, cy), slab)
        {
            let n = values.len();
            values.copy_from_slice(&kept[..n]);
        }
    }
}

/// Whether some corner that `reader`'s gathers through tap rows `rows` (every light's) read is
/// served a released pixel's light ([`held_fix`]'s second test; the first, with
/// `held_lit_side`, is not asked): where none is, the gathers read their light buffer.
pub(crate) fn serves_any(row: &RowContext<'_>, reader: Reader, rows: &[u32]) -> bool {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    let Some(surface) = reader.surface else {
        return false;
    };
    let (q, slab) = (reader.q, ctx.slab);
    rows.iter().enumerate().any(|(l, &r)| {
        let shift = plan.lights[l].table.slab_shift[slab as usize];
        ctx.taps[l].weighted(r).iter().any(|t| {
            let (sx, sy) = (q.0 + t.dx + shift[0], q.1 + t.dy + shift[1]);
            [(sx, sy), (sx + 1, sy), (sx, sy + 1), (sx + 1, sy + 1)]
                .into_iter()
                .any(|c| ctx.held.served(plan, l, (q, surface), c, slab).is_some())
        })
    })
}

/// The fragment pixel (x, y)'s cursor crosses next, before this slab's step 2 (`None`: it has
/// crossed all of them).
#[inline(always)]
pub(crate) fn next_fragment(
    ctx: &SlabContext<'_>,
    state: &RowState<'_>,
    (x, y): (usize, usize),
) -> Option<u32> {
    let end = ctx.ldi.offsets[y * ctx.plan.grid_width as usize + x + 1];
    (state.next[x] < end).then_some(state.next[x])
}

/// A released pixel keeps the light it gathered in its release slab (every light's channels,
/// then its depth plane) for the gathers of its surface ([`held_fix`]).
#[inline(always)]
pub(crate) fn keep_release(row: &RowContext<'_>, x: usize, light: &LightIn) {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    if ctx.held.served.is_empty() {
        return;
    }
    let ch = plan.channels as usize;
    let mut values = [[0.0f32; 4]; MAX_LIGHTS];
    for (l, v) in values.iter_mut().enumerate().take(plan.lights.len()) {
        v[..ch].copy_from_slice(&light.iin[l * ch..(l + 1) * ch]);
        v[ch] = light.depth[l];
    }
    let p = row.y * plan.grid_width as usize + x;
    let values = &values[..plan.lights.len()];
    ctx.held.keep_release(p, (x, row.y), ctx.slab, values);
}

/// Light l's tap row at the pixel of `at` in this slab: its phase's, or (distance penumbra) the
/// row of the nearest occluder's level in its reach. Where every level is one kernel
/// ([`RenderPlan::levels_share_one_kernel`](convshadow_common::plan::RenderPlan::levels_share_one_kernel)) the gather reads level 0's row, the same bits,
/// unless `search_shared` asks for the level (the sub-pixel read).
#[inline(always)]
fn tap_row(row: &RowContext<'_>, l: usize, at: TapOrigin, search_shared: bool) -> u32 {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    let (light, table) = (&plan.lights[l], &plan.lights[l].table);
    let hashes = (light.slab_hash[ctx.slab as usize], row.light_hashes[l]);
    let phase = phase_at(
        table,
        ctx.slab,
        hashes.0,
        hashes.1,
        plan.hash_x(at.x as u32),
    );
    if plan.depth_planes() == 0 || (!search_shared && plan.levels_share_one_kernel()) {
        return phase;
    }
    let levels = level_plane(plan, row.prev, l);
    distance_row(
        &levels,
        table,
        &ctx.taps[l],
        phase,
        ctx.slab,
        plan.slabs,
        at,
    )
}

/// Step 2: pixel x's layer cursor advanced past every fragment before the slab's back face.
#[inline(always)]
pub(crate) fn intersect(
    ctx: &SlabContext<'_>,
    y: usize,
    state: &mut RowState<'_>,
    x: usize,
) -> Hit {
    let ldi = ctx.ldi;
    let end = ldi.offsets[y * ldi.width as usize + x + 1];
    let before = state.inside[x];
    let crossed = advance(ldi, &mut state.next[x], end, &mut state.inside[x], ctx.back);
    let mesh = if crossed != NO_CROSSING {
        Some(u32::from(ldi.mesh[crossed as usize]))
    } else {
        first_mesh(state.inside[x])
    };
    Hit {
        crossed,
        last: state.next[x].wrapping_sub(1),
        before,
        mesh,
    }
}

/// Steps 3 and 4 at pixel x, which lies in mesh `mesh` or crossed its surface at fragment
/// `hit.crossed`: the transfer-function entry at the one point it shades, as much of it as the
/// slab's part inside the mesh (a medium's entry and exit slabs, [`part_of_slab`]), the light
/// `iin` (every light's channels) shaded with it, composited front to back. Returns the
/// attenuation per channel for step 5.
pub(crate) fn shade_and_composite(
    row: &RowContext<'_>,
    state: &mut RowState<'_>,
    x: usize,
    iin: &[f32],
    mesh: u32,
    hit: &Hit,
) -> [f32; 3] {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    let crossed = hit.crossed;
    let z = shading_depth(plan, ctx.ldi, crossed, ctx.front, row.jitter_hash, x);
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    let (xi, yi) = plan.image_xy(x, row.y);
    let (inside, mut lit_from) = slab_part(
        ctx.ldi,
        (mesh, plan.second_order_media),
        (hit.before, state.inside[x]),
        (crossed, hit.last),
        (ctx.front, ctx.back),
        plan.inv_slab_distance,
    );
    let mut tf = match &material.pre {
        // Pre-integrated compositing (shading.wgsl `preintegrated`).
        Some(table) => {
            // A pre-integrated entry has the light's decay inside the slab in its colour.
            lit_from = 0.0;
            preintegrated(row, state, x, mesh, table, crossed)
        }
        None => {
            if plan.preintegration {
                state.pre[x] = f32::NAN;
            }
            material_at(plan, mesh, xi, yi, z)
        }
    };
    // A crossed surface (its triangle's normal) gets the highlight and, where opaque, the
    // Lambert cosine and the horizon.
    let surface = (crossed != NO_CROSSING && uses_normals(plan, material)).then(|| {
        let triangle = ctx.ldi.triangle[crossed as usize] as usize;
        (ctx.raster.triangles[triangle].normal, true)
    });
    let w = plan.grid_width as usize;
    let mut color = [state.color[x], state.color[w + x], state.color[2 * w + x]];
    shade_sample(
        plan,
        material,
        &mut tf,
        (inside, lit_from),
        iin,
        surface,
        (&mut color, &mut state.alpha[x]),
        true,
    );
    [state.color[x], state.color[w + x], state.color[2 * w + x]] = color;
    tf.attenuation
}

/// Pre-integrated shading (`sweep.preintegration`) at pixel x in mesh `mesh`, whose material has
/// the pre-integration table `table`: the table's entry at the detail values on the slab's front
/// and back faces. The front value is the one the previous slab kept in `state.pre` (NaN: none),
/// else evaluated at the front face, or at the crossed fragment's depth where the pixel crosses a
/// surface in this slab. The back value is kept for the next slab when the pixel is still in
/// mesh `mesh` at the back face (the next slab shades it unless it crosses a surface), else NaN.
/// The detail is a pure function of pixel, mesh and depth, and slab k's back face is slab
/// k + 1's front face bit for bit, so a kept value has the bits of a fresh one: keeping it only
/// saves an evaluation, and forgetting it never changes the image.
fn preintegrated(
    row: &RowContext<'_>,
    state: &mut RowState<'_>,
    x: usize,
    mesh: u32,
    table: &[TfEntry],
    crossed: u32,
) -> TfLanes<f32> {
    let (ctx, plan) = (row.ctx, row.ctx.plan);
    let (xi, yi) = plan.image_xy(x, row.y);
    let kept = state.pre[x];
    let front = if crossed == NO_CROSSING && !kept.is_nan() {
        kept
    } else if crossed != NO_CROSSING {
        detail_at(plan, mesh, xi, yi, ctx.ldi.depth[crossed as usize])
    } else {
        detail_at(plan, mesh, xi, yi, ctx.front)
    };
    let back = detail_at(plan, mesh, xi, yi, ctx.back);
    state.pre[x] = if first_mesh(state.inside[x]) == Some(mesh) {
        back
    } else {
        f32::NAN
    };
    pre_transfer(table, front, back)
}

/// Step 5 at pixel x: every light's gathered channels attenuated (and flushed) into this slab's
/// outgoing buffer; with the distance penumbra, the light the slab removed (Σ in − Σ out) at
/// depth `removed_at` (slabs) deepens the occluder depth (`released`: a held surface's release
/// owns it all, [`owned_depth`]), stored with the channels, and gives the level the pixel
/// gathers through in the next slab.
#[inline(always)]
fn attenuate_light(
    ctx: &SlabContext<'_>,
    state: &mut RowState<'_>,
    x: usize,
    light: &LightIn,
    attenuation: [f32; 3],
    (removed_at, released): (f32, bool),
) {
    let plan = ctx.plan;
    let (w, ch, planes) = (
        plan.grid_width as usize,
        plan.channels as usize,
        plan.planes_per_light(),
    );
    for l in 0..plan.lights.len() {
        let (mut lit_in, mut lit_out) = (0.0f32, 0.0f32);
        let mut out = [0.0f32; 4];
        for c in 0..ch {
            let iin = light.iin[l * ch + c];
            out[c] = attenuate(iin, attenuation[c]);
            lit_in += iin;
            lit_out += out[c];
        }
        if plan.depth_planes() > 0 {
            let occluded = ch as f32 - lit_out;
            let removed_at = depth_coord(plan.depth_scale.as_ref(), removed_at);
            out[ch] = if released {
                owned_depth(removed_at, occluded)
            } else {
                deepen(light.depth[l], removed_at, lit_in - lit_out)
            };
            let table = &plan.lights[l].table;
            state.levels[l * w + x] =
                pixel_level::<f32>(table, occluded, out[ch], ctx.next_level_at);
        }
        copy_planes(
            &mut state.light[light_block(plan, l) + x * planes..][..planes],
            &out,
        );
    }
}

/// `dst = src[..dst.len()]` for one light's channels or planes (1 to 4), as fixed-length copies:
/// a run-time length is a `memcpy` call per light and pixel.
#[inline(always)]
fn copy_planes(dst: &mut [f32], src: &[f32; 4]) {
    match dst {
        [d] => *d = src[0],
        [d0, d1, d2] => (*d0, *d1, *d2) = (src[0], src[1], src[2]),
        [d0, d1, d2, d3] => (*d0, *d1, *d2, *d3) = (src[0], src[1], src[2], src[3]),
        dst => dst.copy_from_slice(&src[..dst.len()]),
    }
}
