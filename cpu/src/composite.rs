//! Stages 4 and 5: front-to-back compositing and light attenuation with the explicit flush
//! (steps 4–5 of the per-pixel sweep). Mirrors `gpu/src/shaders/composite.wgsl`.
//!
//! Written once over [`Lane`]: the per-pixel stage (`crate::sweep::pixel`) calls the 1-lane
//! instance, the SIMD path's chunks the 8-lane one.

use std::sync::atomic::{AtomicU32, Ordering};

use convshadow_common::pixel::lane::Lane;
use convshadow_common::plan::{FLUSH_BELOW, MaterialPlan, RenderPlan, surface_hold};

use crate::shading::{LightTerms, Surface, TfLanes, shade_with};

/// One slab's sample of `material` with entry `tf` shaded and composited into (`color`, `alpha`)
/// in the lanes of `lanes` (composite.wgsl `shade_sample`): `tf` scaled to the part of the slab
/// inside the medium (`inside`, `lit_from`: [`part_of_slab`], which leaves `tf` as the slab's
/// scaled entry, its attenuation for the light buffers), shaded with the incoming light `iin` —
/// at crossed surfaces (`surface`: the normals and the lanes that crossed one) with the highlight
/// and, where opaque, the Lambert cosine, judged by the entry's opacity before scaling —, times
/// the light inside the slab, composited. The grid's sweep (both paths) and the eye pass share it.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn shade_sample<L: Lane>(
    plan: &RenderPlan,
    material: &MaterialPlan,
    tf: &mut TfLanes<L>,
    (inside, lit_from): (L, L),
    iin: &[L],
    surface: Option<([L; 3], L::M)>,
    (color, alpha): (&mut [L; 3], &mut L),
    lanes: L::M,
) {
    let terms = |l: usize| LightTerms::of(plan, material, l);
    shade_sample_with(
        plan,
        material,
        tf,
        (inside, lit_from),
        iin,
        surface,
        (color, alpha),
        lanes,
        terms,
    );
}

/// [`shade_sample`] with each light's shading terms given by `terms` (`shade_with`): the eye
/// pass's point lights, whose direction and falloff change from sample to sample.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn shade_sample_with<L: Lane>(
    plan: &RenderPlan,
    material: &MaterialPlan,
    tf: &mut TfLanes<L>,
    (inside, lit_from): (L, L),
    iin: &[L],
    surface: Option<([L; 3], L::M)>,
    (color, alpha): (&mut [L; 3], &mut L),
    lanes: L::M,
    terms: impl Fn(usize) -> LightTerms,
) {
    let surface = surface.map(|(normal, lanes)| Surface {
        normal,
        lanes,
        alpha: tf.alpha,
    });
    let light = part_of_slab(tf, inside, lit_from);
    let lights = material.light_color.len();
    let ch = plan.channels as usize;
    let shaded = shade_with(
        ch,
        lights,
        terms,
        material,
        tf.color,
        iin,
        surface.as_ref(),
        &plan.horizon,
    );
    let shaded = [0, 1, 2].map(|c| shaded[c] * light[c]);
    composite(color, alpha, shaded, tf.alpha, lanes, plan.turned_round);
}

/// Front to back, `C += (1 − A)·α·c`, `A += (1 − A)·α`, in that order; with `back_to_front`
/// (a turned-round pass, the viewer at the sweep's far end) `C = α·c + (1 − α)·C`,
/// `A = α + (1 − α)·A`. Applied only in the lanes of `lanes` (planar colours: one lane value
/// per channel).
#[inline(always)]
pub fn composite<L: Lane>(
    color: &mut [L; 3],
    alpha: &mut L,
    c: [L; 3],
    a: L,
    lanes: L::M,
    back_to_front: bool,
) {
    if back_to_front {
        let keep = L::splat(1.0) - a;
        for (dst, src) in color.iter_mut().zip(c) {
            *dst = L::select(lanes, a * src + keep * *dst, *dst);
        }
        *alpha = L::select(lanes, a + keep * *alpha, *alpha);
        return;
    }
    let t = (L::splat(1.0) - *alpha) * a;
    for (dst, src) in color.iter_mut().zip(c) {
        *dst = L::select(lanes, *dst + t * src, *dst);
    }
    *alpha = L::select(lanes, *alpha + t, *alpha);
}

/// What a fraction `f` of a slab takes out where the whole slab takes out `s` (an opacity, or
/// `1 − attenuation`): `1 − (1 − s)^f` to second order in `s`, `f·s·(1 + (1 − f)·s/2)`, exact at
/// `f` = 0 and 1 and between those two values for every `s` in 0…1 (powers are not bit-exact
/// across CPU and GPU, these four products and sums are).
#[inline(always)]
pub fn taken_out<L: Lane>(s: L, f: L) -> L {
    let one = L::splat(1.0);
    f * s * (one + (one - f) * s * L::splat(0.5))
}

/// A medium's slab as the part of it the pixel spends inside (`crate::parity::slab_part`):
/// its opacity and attenuation scaled to the fraction `inside` of the slab ([`taken_out`]), so
/// that a medium's entry and exit slabs take out only what lies inside it (a strip of thickness
/// t is t/e slabs thick, not t/e + 1); and returns, per channel, the light's attenuation over
/// the fraction `lit_from` of the slab, the way the light has come through the slab's medium
/// where it lights the sample (the middle of the part inside: without it a medium's colour
/// converged at first order in e). Lanes with opacity 1 (surfaces) keep every bit and get factor
/// 1; `inside` = 1 keeps the entry's opacity and attenuation, `lit_from` = 0 gives factor 1.
#[inline(always)]
pub fn part_of_slab<L: Lane>(tf: &mut TfLanes<L>, inside: L, lit_from: L) -> [L; 3] {
    let one = L::splat(1.0);
    let medium = tf.alpha.lt(one);
    let light = tf
        .attenuation
        .map(|a| L::select(medium, one - taken_out(one - a, lit_from), one));
    let partial = inside.lt(one);
    let part = |new: L, old: L| L::select(medium, L::select(partial, new, old), old);
    tf.alpha = part(taken_out(tf.alpha, inside), tf.alpha);
    for a in tf.attenuation.iter_mut() {
        *a = part(one - taken_out(one - *a, inside), *a);
    }
    light
}

/// `Iout = Iin · attenuation`, flushed to zero below [`FLUSH_BELOW`].
#[inline(always)]
pub fn attenuate<L: Lane>(iin: L, attenuation: L) -> L {
    let v = iin * attenuation;
    L::select(v.lt(L::splat(FLUSH_BELOW)), L::splat(0.0), v)
}

/// Distance penumbra: the occluder-depth plane after a slab, `D + at · removed` (`removed`:
/// the light the slab took out, summed over channels, at depth `at` (slabs) per lane: this
/// slab, where a held surface was crossed (see [`hold_step`]), or an opaque crossing's
/// `crate::subpixel::removal_depth`), flushed where its magnitude is below [`FLUSH_BELOW`]
/// (D is negative where light was removed before slab 0's middle).
#[inline(always)]
pub fn deepen<L: Lane>(depth: L, at: L, removed: L) -> L {
    let v = depth + at * removed;
    L::select(v.abs().lt(L::splat(FLUSH_BELOW)), L::splat(0.0), v)
}

/// Distance penumbra at a held surface's release: the surface owns the pixel's darkness, so the
/// occluder-depth plane becomes `at · occluded` (`occluded`: channels − Σ outgoing light, all
/// of it once released), not [`deepen`]'s `D + at · removed`. Behind an opaque surface every
/// shadow edge is the surface's own, and the hold (`RenderPlan::surface_hold`) is sized for a
/// released pixel whose level is its own distance; a mean with
/// an occluder whose penumbra fell on the surface gave it a larger level, which its neighbours'
/// level search took up, gathering the surface's own zeros (measured on a receiver 60° to the
/// slabs: RMSE 0.015 → 0.009 against the closed form; docs/accuracy.md §2b).
#[inline(always)]
pub fn owned_depth<L: Lane>(at: L, occluded: L) -> L {
    deepen(L::splat(0.0), at, occluded)
}

/// A pixel's surface hold (`RenderPlan::surface_hold`), packed in one `u32`: 0 when it holds
/// nothing, else the slab its surface was crossed in (the low [`HOLD_SHIFT`] bits: slabs are
/// fewer than 2¹⁶), how many slabs it passes the light (10 bits) and how many slabs of barrier
/// follow its release (the bits from [`HOLD_BARRIER_SHIFT`]).
pub const HOLD_SHIFT: u32 = 16;

/// Where a pixel's hold state keeps its barrier ([`HOLD_SHIFT`]).
pub const HOLD_BARRIER_SHIFT: u32 = 26;

/// A pixel's hold state's crossing slab bits.
pub const HOLD_SLAB_MASK: u32 = (1 << HOLD_SHIFT) - 1;

/// A pixel's hold state's hold length bits, below [`HOLD_SHIFT`] once shifted.
pub const HOLD_LENGTH_MASK: u32 = (1 << (HOLD_BARRIER_SHIFT - HOLD_SHIFT)) - 1;

/// A pixel's hold state of crossing slab `crossed`, hold `hold` and barrier `barrier`.
#[inline(always)]
pub const fn hold_state(crossed: u32, hold: u32, barrier: u32) -> u32 {
    crossed | (hold << HOLD_SHIFT) | (barrier << HOLD_BARRIER_SHIFT)
}

/// The slab in which a pixel's hold state `state` (non-zero) releases its light: from there on
/// it removes it, through its barrier.
#[inline(always)]
pub const fn release_slab(state: u32) -> u32 {
    (state & HOLD_SLAB_MASK) + ((state >> HOLD_SHIFT) & HOLD_LENGTH_MASK)
}

/// What step 5 does with a pixel's light, given its surface hold ([`hold_step`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Held {
    /// No hold: the slab's own attenuation.
    Free,
    /// Held: the light passes (attenuation 1) — behind a light-blocking surface crossed fewer
    /// than its hold's slabs ago, or at its crossing.
    Pass,
    /// Released: the light is removed (attenuation 0), and the distance penumbra records it at
    /// the crossing's slab `removed_at`, where the surface is.
    Release {
        /// The slab the held surface was crossed in.
        removed_at: u32,
    },
}

/// Advances a pixel's packed surface hold `hold` ([`HOLD_SHIFT`]) through slab `slab`, in
/// which its cursor crossed a triangle whose packed hold word
/// (`convshadow_common::plan::surface_hold::pack_holds`) is `crossed` (0: no crossing, or one
/// that neither holds nor bars). A pending hold passes the light until its release slab, or
/// until `ends_hold` — the pixel crossed a fragment in this slab and has more ahead: its column
/// leaves the held mesh (or meets another surface) with something behind, which light held on
/// would reach through the mesh (a thin plate steep to a soft point light lost its whole shadow
/// on a sheet behind it to a 1023-slab hold), and the light is removed in that slab only. A
/// release at the hold's end removes it in that slab and then, outside every closed mesh
/// (`inside`: the pixel is in one, whose slabs remove it; a crossing there starts a hold as
/// anywhere), through a thin shell's **barrier** (`surface_hold::barrier`); a shell's crossing
/// that holds nothing starts its barrier in the slab after it (its own attenuation removes the
/// light in its slab). Else a crossing with a hold starts one. Every lane path runs it in every
/// slab from a hold's release to its barrier's end and where a pixel crosses a fragment, so its
/// state never goes stale.
#[inline(always)]
pub fn hold_step(hold: &mut u32, slab: u32, crossed: u32, ends_hold: bool, inside: bool) -> Held {
    let entry = surface_hold::entry_of(crossed);
    let barrier = surface_hold::barrier_of(crossed);
    let packed = *hold;
    if packed != 0 {
        let start = packed & ((1 << HOLD_SHIFT) - 1);
        let (mut release, mut bar) = (release_slab(packed), packed >> HOLD_BARRIER_SHIFT);
        if slab < release {
            if !ends_hold {
                return Held::Pass;
            }
            (release, bar) = (slab, 0);
        }
        if slab <= release + bar {
            if slab == release + bar {
                *hold = 0;
            }
            if slab == release || !inside {
                return Held::Release { removed_at: start };
            }
            // Inside a closed mesh: its slabs remove the light; a crossing may hold anew.
            if entry == 0 {
                return Held::Free;
            }
        }
        *hold = 0;
    }
    if entry != 0 {
        *hold = hold_state(slab, entry, barrier);
        return Held::Pass;
    }
    if barrier != 0 && !inside {
        *hold = hold_state(slab, 0, barrier);
    }
    Held::Free
}

pub use convshadow_common::plan::surface_hold::{
    HELD_PART_MAX, HELD_SLOT_WORDS, HELD_WORDS, NO_HELD_SLAB,
};

/// One recorded hold of a pixel ([`HeldPlanes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldSlot {
    /// The slab the hold started in (the surface's crossing).
    pub from: u32,
    /// The first slab it no longer passes the light in (its release, or the crossing that cut it).
    pub until: u32,
    /// The crossing's depth in slabs (slab `from` plus the fragment's place in it, below 0.99).
    pub z0: f32,
    /// The crossed triangle (`RenderPlan::hold_slopes` gives its plane's slopes).
    pub triangle: u32,
}

impl HeldSlot {
    /// Whether the pixel passed its light under this hold in slab `slab − 1`.
    #[inline(always)]
    pub fn held_before(&self, slab: u32) -> bool {
        self.from < slab && slab - 1 < self.until
    }
}

/// Every pixel's last two entry holds (`surface_hold`, "Who reads the held light"), which the
/// gathers of its neighbours read: two slots of [`HELD_SLOT_WORDS`] per pixel. A pixel writes only
/// its own record, in the slab its hold starts (into the slot of the older hold) or is cut (its
/// `until`), while its neighbours read it in the same slab from other threads; a reader in slab k
/// takes the slot with the latest start before k, which no write of slab k touches, and asks
/// whether it held in slab k − 1, which a cut in slab k does not change — so every read gives the
/// record as it stood after slab k − 1, whatever the order (composite.wgsl reads its `hold`
/// buffer's records the same way).
#[derive(Clone, Copy)]
pub struct HeldPlanes<'a> {
    /// `HELD_WORDS` per grid pixel, row after row (empty where no surface holds).
    pub words: &'a [AtomicU32],
    /// Per cell of [`HELD_CELL`] pixels of a grid row (`cells_per_row` per row), the latest
    /// `until` of a hold started in it: a gather whose cells all lie before slab k reads no held
    /// pixel and needs no test (a hint only: it decides no bit).
    pub cells: &'a [AtomicU32],
    /// Cells per grid row.
    pub cells_per_row: usize,
    /// Per grid row, bit c of word c / 64: some row within the gathers' vertical reach of it
    /// has cell c active in this slab ([`HeldRecords::prepare`]; empty where none is kept, as
    /// in unit tests: [`HeldPlanes::near`] then scans [`HeldPlanes::cells`]).
    pub window: &'a [u64],
    /// Words of [`HeldPlanes::window`] per grid row.
    pub words_per_row: usize,
    /// The vertical reach (row offsets) [`HeldPlanes::window`] was prepared for.
    pub window_rows: (i32, i32),
    /// Per light and grid pixel (light after light), [`HIDER_WORDS`] words: the pixel as a
    /// hider for the slab it was last asked in ([`HeldPlanes::hider`]). Every reader of a slab
    /// asks the same question of it, so the first to ask answers for all (a cache: it decides
    /// no bit).
    pub hiders: &'a [[AtomicU32; HIDER_WORDS]],
}

/// Words per light and pixel of [`HeldPlanes::hiders`]: the slab asked for with
/// [`HIDER_ASKED`] and [`HIDER_FOUND`], then the hider's crossing slab, depth bits and triangle.
pub const HIDER_WORDS: usize = 4;

/// The bits of a hider's first word that hold the slab it answers for (slabs < 2¹⁶).
const HIDER_SLAB_MASK: u32 = 0xffff;

/// The flag of a hider's first word: the pixel hides in that slab.
const HIDER_FOUND: u32 = 1 << 16;

/// The flag of a hider's first word: it answers for a slab (not set before any is asked).
const HIDER_ASKED: u32 = 1 << 17;

/// Pixels per cell of [`HeldPlanes::cells`].
pub const HELD_CELL: usize = 8;

/// The storage of [`HeldPlanes`], for one sweep.
pub struct HeldRecords {
    words: Vec<AtomicU32>,
    cells: Vec<AtomicU32>,
    cells_per_row: usize,
    window: Vec<u64>,
    words_per_row: usize,
    window_rows: (i32, i32),
    /// A row's active cells, the scratch of [`HeldRecords::prepare`].
    active: Vec<u64>,
    /// Per light and grid pixel, [`HeldPlanes::hiders`].
    hiders: Vec<[AtomicU32; HIDER_WORDS]>,
}

impl HeldRecords {
    /// Empty records for every pixel of `plan`'s grid where a surface holds and
    /// `RenderPlan::held_lit_side` asks for them, else none (every read then as without them).
    pub fn new(plan: &RenderPlan) -> HeldRecords {
        let (w, h) = (plan.grid_width as usize, plan.grid_height as usize);
        let cells_per_row = w.div_ceil(HELD_CELL);
        let (pixels, cells) = if plan.has_surface_hold() && plan.held_lit_side {
            (w * h, cells_per_row * h)
        } else {
            (0, 0)
        };
        let words_per_row = cells_per_row.div_ceil(64);
        let rows = if cells > 0 { h } else { 0 };
        HeldRecords {
            words: (0..pixels * HELD_WORDS)
                .map(|_| AtomicU32::new(NO_HELD_SLAB))
                .collect(),
            cells: (0..cells).map(|_| AtomicU32::new(0)).collect(),
            cells_per_row,
            window: vec![0; rows * words_per_row],
            words_per_row,
            window_rows: (0, 0),
            active: vec![0; rows * words_per_row],
            hiders: (0..pixels * plan.lights.len())
                .map(|_| std::array::from_fn(|_| AtomicU32::new(0)))
                .collect(),
        }
    }

    /// Before slab `slab`: for every row, which cells hold some pixel that may have passed light
    /// in slab `slab − 1` (`cells ≥ slab`, as [`HeldPlanes::any_in`] asks), OR-ed over the rows
    /// `y + rows.0 ..= y + rows.1` (the gathers' vertical reach), so that
    /// [`HeldPlanes::near`] answers [`HeldPlanes::any_in`]'s question for a pixel's reach in a
    /// few word operations. No write of slab `slab` is needed: a hold started in it is read
    /// from slab `slab + 1` on.
    pub fn prepare(&mut self, slab: u32, rows: (i32, i32)) {
        if self.cells.is_empty() {
            return;
        }
        let (wpr, cpr) = (self.words_per_row, self.cells_per_row);
        let h = self.cells.len() / cpr;
        self.active.fill(0);
        if slab > 0 {
            for (y, cells) in self.cells.chunks(cpr).enumerate() {
                for (c, cell) in cells.iter().enumerate() {
                    if cell.load(Ordering::Relaxed) >= slab {
                        self.active[y * wpr + c / 64] |= 1u64 << (c % 64);
                    }
                }
            }
        }
        for y in 0..h as i32 {
            let (y0, y1) = ((y + rows.0).max(0), (y + rows.1).min(h as i32 - 1));
            for k in 0..wpr {
                let mut word = 0u64;
                for r in y0..=y1 {
                    word |= self.active[r as usize * wpr + k];
                }
                self.window[y as usize * wpr + k] = word;
            }
        }
        self.window_rows = rows;
    }

    /// The records as the sweep reads and writes them.
    pub fn view(&self) -> HeldPlanes<'_> {
        HeldPlanes {
            words: &self.words,
            cells: &self.cells,
            cells_per_row: self.cells_per_row,
            window: &self.window,
            words_per_row: self.words_per_row,
            window_rows: self.window_rows,
            hiders: &self.hiders,
        }
    }
}

impl HeldPlanes<'_> {
    /// Whether a hold of some pixel in columns `xs` of rows `ys` (grid coordinates, clamped to
    /// the grid) may have passed light in slab `slab − 1`.
    #[inline(always)]
    pub fn any_in(&self, xs: (i32, i32), ys: (i32, i32), slab: u32) -> bool {
        if self.cells.is_empty() || slab == 0 {
            return false;
        }
        let rows = (self.cells.len() / self.cells_per_row) as i32;
        let last_x = (self.cells_per_row * HELD_CELL) as i32 - 1;
        let (x0, x1) = (xs.0.max(0), xs.1.min(last_x));
        let (y0, y1) = (ys.0.max(0), ys.1.min(rows - 1));
        if x0 > x1 || y0 > y1 {
            return false;
        }
        let (c0, c1) = (x0 as usize / HELD_CELL, x1 as usize / HELD_CELL);
        (y0..=y1).any(|y| {
            let row = &self.cells[y as usize * self.cells_per_row..][c0..=c1];
            row.iter().any(|c| c.load(Ordering::Relaxed) >= slab)
        })
    }

    /// [`HeldPlanes::any_in`] for columns `xs` of the rows within the prepared vertical reach of
    /// row `y` ([`HeldRecords::prepare`]), in slab `slab`: the same answer from the prepared
    /// window (scanning the cells where none is prepared).
    #[inline(always)]
    pub fn near(&self, xs: (i32, i32), y: i32, slab: u32) -> bool {
        if self.window.is_empty() {
            let rows = self.window_rows;
            return self.any_in(xs, (y + rows.0, y + rows.1), slab);
        }
        let rows = (self.window.len() / self.words_per_row) as i32;
        let last_x = (self.cells_per_row * HELD_CELL) as i32 - 1;
        let (x0, x1) = (xs.0.max(0), xs.1.min(last_x));
        if x0 > x1 || y < 0 || y >= rows {
            return false;
        }
        let (c0, c1) = (x0 as usize / HELD_CELL, x1 as usize / HELD_CELL);
        let row = &self.window[y as usize * self.words_per_row..][..self.words_per_row];
        (c0 / 64..=c1 / 64).any(|k| {
            let lo = if k == c0 / 64 { c0 % 64 } else { 0 };
            let hi = if k == c1 / 64 { c1 % 64 } else { 63 };
            let mask = (u64::MAX >> (63 - hi)) & (u64::MAX << lo);
            row[k] & mask != 0
        })
    }

    #[inline(always)]
    fn word(&self, p: usize, slot: usize, k: usize) -> u32 {
        self.words[p * HELD_WORDS + slot * HELD_SLOT_WORDS + k].load(Ordering::Relaxed)
    }

    #[inline(always)]
    fn set(&self, p: usize, slot: usize, k: usize, v: u32) {
        self.words[p * HELD_WORDS + slot * HELD_SLOT_WORDS + k].store(v, Ordering::Relaxed);
    }

    /// Pixel `p`'s slot whose hold started last before slab `slab` (`NO_HELD_SLAB`: any).
    #[inline(always)]
    fn newest_slot(&self, p: usize, slab: u32) -> Option<usize> {
        let (a, b) = (self.word(p, 0, 0), self.word(p, 1, 0));
        // An empty slot's `from` is NO_HELD_SLAB, never below `slab`.
        match (a < slab, b < slab) {
            (false, false) => None,
            (true, false) => Some(0),
            (false, true) => Some(1),
            (true, true) => Some(usize::from(b > a)),
        }
    }

    /// Pixel `p`'s hold with the latest start before slab `slab`, if it has one.
    #[inline(always)]
    pub fn latest_before(&self, p: usize, slab: u32) -> Option<HeldSlot> {
        let slot = self.newest_slot(p, slab)?;
        Some(HeldSlot {
            from: self.word(p, slot, 0),
            until: self.word(p, slot, 1),
            z0: f32::from_bits(self.word(p, slot, 2)),
            triangle: self.word(p, slot, 3),
        })
    }

    /// Whether pixel `p` passed its light under an entry hold in slab `slab − 1`.
    #[inline(always)]
    pub fn held_before(&self, p: usize, slab: u32) -> bool {
        self.latest_before(p, slab)
            .is_some_and(|s| s.held_before(slab))
    }

    /// Records a hold of pixel `p` starting in slab `held.from`, in its empty slot or the slot
    /// of its older hold.
    #[inline(always)]
    pub fn start(&self, p: usize, (x, y): (usize, usize), held: HeldSlot) {
        let cell = y * self.cells_per_row + x / HELD_CELL;
        self.cells[cell].fetch_max(held.until, Ordering::Relaxed);
        let (a, b) = (self.word(p, 0, 0), self.word(p, 1, 0));
        let slot = if a == NO_HELD_SLAB {
            0
        } else if b == NO_HELD_SLAB {
            1
        } else {
            usize::from(b < a)
        };
        self.set(p, slot, 1, held.until);
        self.set(p, slot, 2, held.z0.to_bits());
        self.set(p, slot, 3, held.triangle);
        self.set(p, slot, 0, held.from);
    }

    /// Pixel `p`'s latest hold stops passing in slab `slab` (a crossing cut it).
    #[inline(always)]
    pub fn cut(&self, p: usize, slab: u32) {
        if let Some(slot) = self.newest_slot(p, NO_HELD_SLAB) {
            self.set(p, slot, 1, slab);
        }
    }

    /// Whether a gather at pixel `q` in slab `slab` reads no light of light `light` from pixel
    /// `p` (`surface_hold`, "Who reads the held light"): `p` held in slab `slab − 1` and the
    /// column the light reaching it came from crossed that surface ([`HeldPlanes::hider`]),
    /// and `q` lies more than `HELD_BEHIND_MARGIN` slabs behind its surface's plane. Returns
    /// the hold's crossing slab then. The caller has checked that `q` is not held.
    #[inline(always)]
    pub fn hides(
        &self,
        plan: &RenderPlan,
        light: usize,
        q: (i32, i32),
        p: (i32, i32),
        slab: u32,
    ) -> Option<u32> {
        let (w, h) = (plan.grid_width as i32, plan.grid_height as i32);
        if p.0 < 0 || p.1 < 0 || p.0 >= w || p.1 >= h {
            return None;
        }
        let at = light * (w * h) as usize + (p.1 * w + p.0) as usize;
        let words = &self.hiders[at];
        let meta = words[0].load(Ordering::Acquire);
        let hider = if meta & (HIDER_SLAB_MASK | HIDER_ASKED) == slab | HIDER_ASKED {
            (meta & HIDER_FOUND != 0).then(|| {
                let word = |k: usize| words[k].load(Ordering::Relaxed);
                (word(1), f32::from_bits(word(2)), word(3))
            })
        } else {
            self.ask_hider(plan, light, p, slab, words)
        };
        let (from, z0, triangle) = hider?;
        let [gx, gy] = plan.hold_slopes[triangle as usize];
        let (dx, dy) = ((q.0 - p.0) as f32, (q.1 - p.1) as f32);
        let at_reader = z0 + gx * dx + gy * dy;
        // Every value here is finite (`MAX_HOLD_SLOPE`).
        (at_reader < slab as f32 - surface_hold::HELD_BEHIND_MARGIN).then_some(from)
    }

    /// [`HeldPlanes::hider`], written into pixel `p`'s `words` of light `light` for the other
    /// readers of slab `slab` (the first reader's path, kept out of the gathers' loop).
    #[cold]
    #[inline(never)]
    fn ask_hider(
        &self,
        plan: &RenderPlan,
        light: usize,
        p: (i32, i32),
        slab: u32,
        words: &[AtomicU32; HIDER_WORDS],
    ) -> Option<(u32, f32, u32)> {
        let hider = self.hider(plan, light, p, slab);
        if let Some((from, z0, triangle)) = hider {
            words[1].store(from, Ordering::Relaxed);
            words[2].store(z0.to_bits(), Ordering::Relaxed);
            words[3].store(triangle, Ordering::Relaxed);
        }
        let found = if hider.is_some() { HIDER_FOUND } else { 0 };
        // Release: a reader that sees this slab's stamp sees the words above.
        words[0].store(slab | HIDER_ASKED | found, Ordering::Release);
        hider
    }

    /// Pixel `p` as a hider of light `light` in slab `slab` (its hold's crossing slab, depth
    /// and triangle): held in slab `slab − 1`, and the column the light reaching it came from,
    /// `t` slabs back along the light's drift, crossed a surface within `SAME_SURFACE_SLABS` of
    /// the held surface's plane there. Depends only on the records as slab `slab − 1` left
    /// them (no write of slab `slab` changes what `latest_before` gives it), so every reader
    /// of the slab gets one answer.
    fn hider(
        &self,
        plan: &RenderPlan,
        light: usize,
        p: (i32, i32),
        slab: u32,
    ) -> Option<(u32, f32, u32)> {
        let (w, h) = (plan.grid_width as i32, plan.grid_height as i32);
        let held = self
            .latest_before((p.1 * w + p.0) as usize, slab)
            .filter(|s| s.held_before(slab))?;
        let drift = plan.lights[light].drift;
        let [gx, gy] = plan.hold_slopes[held.triangle as usize];
        let k = slab as f32;
        // Where the light reaching p left the plane: t slabs back, against the drift.
        let a = 1.0 - (gx * drift[0] + gy * drift[1]);
        let t = ((k - 1.0) - held.z0 + 0.5) / a.max(1.0e-6);
        let ux = (p.0 as f32 - t * drift[0] + 0.5).floor();
        let uy = (p.1 as f32 - t * drift[1] + 0.5).floor();
        if ux < 0.0 || uy < 0.0 || ux >= w as f32 || uy >= h as f32 {
            return None;
        }
        let u = uy as usize * w as usize + ux as usize;
        let there = self.latest_before(u, slab)?;
        let plane = held.z0 + gx * (ux - p.0 as f32) + gy * (uy - p.1 as f32);
        ((there.z0 - plane).abs() < surface_hold::SAME_SURFACE_SLABS).then_some((
            held.from,
            held.z0,
            held.triangle,
        ))
    }
}

/// The final `C += (1 − A)·background`.
#[inline(always)]
pub fn finish(color: &mut [f32; 3], alpha: f32, background: [f32; 3]) {
    let t = 1.0 - alpha;
    color[0] += t * background[0];
    color[1] += t * background[1];
    color[2] += t * background[2];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prepared_window_answers_as_the_cells_scan_does() {
        // 25 cells (200 pixels) a row over 30 rows, holds lasting until scattered slabs; the
        // window prepared for a reach of rows −3 ..= 2 against `any_in` over those rows.
        let (cells_per_row, rows) = (25usize, 30usize);
        let mut state = 12345u32;
        let mut next = |n: u32| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state % n
        };
        let cells: Vec<AtomicU32> = (0..cells_per_row * rows)
            .map(|_| AtomicU32::new(if next(4) == 0 { next(40) } else { 0 }))
            .collect();
        let words_per_row = cells_per_row.div_ceil(64);
        let mut records = HeldRecords {
            words: Vec::new(),
            cells,
            cells_per_row,
            window: vec![0; rows * words_per_row],
            words_per_row,
            window_rows: (0, 0),
            active: vec![0; rows * words_per_row],
            hiders: Vec::new(),
        };
        let reach = (-3, 2);
        let mut checked = [0usize; 2];
        for slab in 0..42 {
            records.prepare(slab, reach);
            let held = records.view();
            for _ in 0..300 {
                let y = next(rows as u32) as i32;
                let x0 = next(230) as i32 - 15;
                let xs = (x0, x0 + next(30) as i32);
                let want = held.any_in(xs, (y + reach.0, y + reach.1), slab);
                assert_eq!(
                    held.near(xs, y, slab),
                    want,
                    "slab {slab}, xs {xs:?}, y {y}"
                );
                checked[usize::from(want)] += 1;
            }
        }
        assert!(
            checked[0] > 100 && checked[1] > 100,
            "both answers met: {checked:?}"
        );
    }

    #[test]
    fn held_records_read_as_they_stood_after_the_previous_slab_whatever_the_write_order() {
        let words: Vec<AtomicU32> = (0..HELD_WORDS)
            .map(|_| AtomicU32::new(NO_HELD_SLAB))
            .collect();
        let cells = [AtomicU32::new(0)];
        let held = HeldPlanes {
            words: &words,
            cells: &cells,
            cells_per_row: 1,
            window: &[],
            words_per_row: 1,
            window_rows: (-1, 1),
            hiders: &[],
        };
        let slot = |from: u32, until| HeldSlot {
            from,
            until,
            z0: from as f32 + 0.25,
            triangle: from * 10,
        };
        // No record: nothing held, nothing near.
        assert_eq!(held.latest_before(0, 5), None);
        assert!(!held.any_in((0, 7), (0, 0), 5));
        // A hold crossed in slab 10, released in 15: held in slabs 10–14, so read as held by
        // the gathers of slabs 11–15; the hint of its cell lasts as long.
        held.start(0, (0, 0), slot(10, 15));
        assert!(!held.held_before(0, 10), "slab 10's readers see slab 9");
        assert!((11..=15).all(|k| held.held_before(0, k)));
        assert!(!held.held_before(0, 16));
        assert!(held.any_in((-3, 3), (-1, 1), 15) && !held.any_in((0, 7), (0, 0), 16));
        // Cut by a crossing in slab 13: slab 13's readers see it held in slab 12 before the cut
        // is written and after, slab 14's no longer.
        assert!(held.held_before(0, 13));
        held.cut(0, 13);
        assert!(held.held_before(0, 13) && !held.held_before(0, 14));
        // A second hold crossed in slab 20 until 30 takes the empty slot; a third, crossed in
        // slab 30 where the second is released, takes the older slot — and slab 30's readers
        // see the second held in slab 29 before and after it is written.
        held.start(0, (0, 0), slot(20, 30));
        assert_eq!(held.latest_before(0, 25), Some(slot(20, 30)));
        assert!(held.held_before(0, 30));
        held.start(0, (0, 0), slot(30, 40));
        assert_eq!(held.latest_before(0, 30), Some(slot(20, 30)));
        assert!(held.held_before(0, 30));
        assert_eq!(held.latest_before(0, 31), Some(slot(30, 40)));
        assert!(held.held_before(0, 31));
        // The first hold's slot was the one overwritten.
        assert!(held.latest_before(0, 20).is_none());
    }

    #[test]
    fn a_hold_passes_until_its_release_or_a_crossing_with_something_behind() {
        // Crossed in slab 10 with a hold of 5: passes through slab 14, released in 15.
        let mut hold = 0;
        let step =
            |hold: &mut u32, slab, crossed, ends| hold_step(hold, slab, crossed, ends, false);
        assert_eq!(step(&mut hold, 10, 5, false), Held::Pass);
        for slab in 11..15 {
            assert_eq!(step(&mut hold, slab, 0, false), Held::Pass, "{slab}");
        }
        let released = Held::Release { removed_at: 10 };
        assert_eq!(step(&mut hold, 15, 0, false), released);
        assert_eq!((hold, step(&mut hold, 16, 0, false)), (0, Held::Free));
        // The mesh's far face with nothing behind it (a floor) does not end the hold.
        assert_eq!(step(&mut hold, 10, 5, false), Held::Pass);
        assert_eq!(step(&mut hold, 12, 0, false), Held::Pass);
        // A crossing with fragments behind it ends it there, at the first crossing's depth,
        // and starts no new hold (the light is gone).
        assert_eq!(step(&mut hold, 13, 7, true), released);
        assert_eq!((hold, step(&mut hold, 14, 0, false)), (0, Held::Free));
    }

    #[test]
    fn a_released_light_stays_out_through_the_barrier_outside_closed_meshes() {
        use surface_hold::pack_holds;
        // A shell held 5 with barrier 3: passes 10..=14, removed 15..=18 (at its depth), free.
        let mut hold = 0;
        let shell = pack_holds(5, 0, 3);
        assert_eq!(hold_step(&mut hold, 10, shell, false, false), Held::Pass);
        for slab in 11..15 {
            assert_eq!(hold_step(&mut hold, slab, 0, false, false), Held::Pass);
        }
        let released = Held::Release { removed_at: 10 };
        for slab in 15..19 {
            assert_eq!(
                hold_step(&mut hold, slab, 0, false, false),
                released,
                "{slab}"
            );
        }
        assert_eq!(
            (hold, hold_step(&mut hold, 19, 0, false, false)),
            (0, Held::Free)
        );
        // Inside a closed mesh the barrier leaves the light to the mesh's slabs (the release
        // slab itself removes it), and a crossing there holds anew.
        hold_step(&mut hold, 10, shell, false, false);
        assert_eq!(hold_step(&mut hold, 15, 0, false, true), released);
        assert_eq!(hold_step(&mut hold, 16, 0, false, true), Held::Free);
        assert_eq!(hold_step(&mut hold, 17, 0, false, false), released);
        assert_eq!(hold_step(&mut hold, 18, 4, false, true), Held::Pass);
        assert_eq!(release_slab(hold), 22);
        // A crossing that cuts a hold short removes the light in its slab only.
        let mut hold = 0;
        hold_step(&mut hold, 10, pack_holds(50, 0, 4), false, false);
        assert_eq!(
            hold_step(&mut hold, 20, pack_holds(0, 0, 2), true, false),
            released
        );
        assert_eq!(
            (hold, hold_step(&mut hold, 21, 0, false, false)),
            (0, Held::Free)
        );
        // A shell's crossing that holds nothing bars the slabs after its own, outside closed
        // meshes only.
        let bars = pack_holds(0, 0, 2);
        assert_eq!(hold_step(&mut hold, 30, bars, false, false), Held::Free);
        let released = Held::Release { removed_at: 30 };
        assert_eq!(hold_step(&mut hold, 31, 0, false, false), released);
        assert_eq!(hold_step(&mut hold, 32, 0, false, false), released);
        assert_eq!(
            (hold, hold_step(&mut hold, 33, 0, false, false)),
            (0, Held::Free)
        );
        assert_eq!(hold_step(&mut hold, 30, bars, false, true), Held::Free);
        assert_eq!(hold, 0);
    }

    #[test]
    fn a_part_of_a_slab_takes_out_the_power_to_second_order() {
        for s in [0.0f32, 0.01, 0.1, 0.3, 0.7, 1.0] {
            // Exact at the ends: nothing, and the whole slab.
            assert_eq!(taken_out(s, 0.0), 0.0);
            assert_eq!(taken_out(s, 1.0), s);
            for f in [0.1f32, 0.25, 0.5, 0.9] {
                let got = f64::from(taken_out(s, f));
                let exact = 1.0 - (1.0 - f64::from(s)).powf(f64::from(f));
                // The neglected terms all take out more, each at most s times the one before:
                // the first, f(1 − f)(2 − f)s³/6, over (1 − s) bounds them (plus f32 rounding).
                if s < 1.0 {
                    let first = f64::from(f * (1.0 - f) * (2.0 - f) * s * s * s) / 6.0;
                    let bound = first / (1.0 - f64::from(s)) + 1e-6;
                    assert!(got <= exact + 1e-6 && exact - got <= bound, "s {s} f {f}");
                }
                // Between the ends' values, for every s.
                assert!((0.0..=f64::from(s) + 1e-7).contains(&got));
            }
        }
    }

    #[test]
    fn only_a_translucent_slab_is_scaled() {
        let entry = |alpha: f32| TfLanes {
            color: [0.5f32; 3],
            alpha,
            attenuation: [0.2, 0.6, 1.0],
        };
        // An opaque entry (a surface) keeps its bits and its light.
        let mut opaque = entry(1.0);
        assert_eq!(part_of_slab(&mut opaque, 0.3, 0.15), [1.0; 3]);
        assert_eq!((opaque.alpha, opaque.attenuation), (1.0, [0.2, 0.6, 1.0]));
        // A whole slab lit at its front is the entry itself.
        let mut whole = entry(0.4);
        assert_eq!(part_of_slab(&mut whole, 1.0, 0.0), [1.0; 3]);
        assert_eq!((whole.alpha, whole.attenuation), (0.4, [0.2, 0.6, 1.0]));
        // A third of a slab, lit in its middle.
        let mut part = entry(0.4);
        let light = part_of_slab(&mut part, 1.0 / 3.0, 1.0 / 6.0);
        assert_eq!(part.alpha, taken_out(0.4, 1.0 / 3.0));
        for (c, a) in [0.2f32, 0.6, 1.0].iter().enumerate() {
            assert_eq!(part.attenuation[c], 1.0 - taken_out(1.0 - a, 1.0 / 3.0));
            assert_eq!(light[c], 1.0 - taken_out(1.0 - a, 1.0 / 6.0));
        }
        assert_eq!(part.color, [0.5; 3]);
        assert_eq!(light[2], 1.0, "a clear channel loses no light");
    }
}
