//! The held-plane records (`convshadow_common::plan::surface_hold`, "Who reads the held light"
//! and "Released light served on its own surface"; composite.wgsl keeps them in its `hold`
//! buffer): every pixel's last two entry holds, the released light each keeps, and the hints
//! that let gathers far from them skip the tests.

use std::sync::atomic::{AtomicU32, Ordering};

use convshadow_common::plan::{RenderPlan, surface_hold};

pub use convshadow_common::plan::surface_hold::{
    HELD_PART_MAX, HELD_SLOT_WORDS, HELD_WORDS, NO_HELD_SLAB, SAME_SURFACE_SLABS,
    SERVED_HEAD_WORDS, SERVED_SLOPE_TOLERANCE,
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
    /// Whether held light is read only from its lit side (`RenderPlan::held_lit_side`): then
    /// [`HeldPlanes::cells`] mark where gathers may need [`HeldPlanes::hides`].
    pub lit_side: bool,
    /// Per cell (as [`HeldPlanes::cells`]), the latest slab a pixel in it released in, plus 1
    /// (0: none): a gather whose cells released nothing in the last [`HeldPlanes::served_age`]
    /// slabs is served nothing (a hint only).
    pub released: &'a [AtomicU32],
    /// Per grid pixel, per record slot, [`SERVED_HEAD_WORDS`] (the slab the slot's hold
    /// released in, `NO_HELD_SLAB` before) then 4 values per light: the light's channels and
    /// depth plane as the pixel gathered them in that slab ([`HeldPlanes::served`]).
    pub served: &'a [AtomicU32],
    /// Words per pixel and slot of [`HeldPlanes::served`].
    pub served_stride: usize,
    /// Per grid pixel where [`HeldPlanes::served`] is kept, the latest slab it kept a release
    /// in, plus 1 (0: none): most corners a gather reads are rejected on this one word.
    pub last_release: &'a [AtomicU32],
    /// Slabs after its release during which a pixel's kept light is served
    /// (`surface_hold::served_release_slabs` of the sweep's slab count).
    pub served_age: u32,
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
    lit_side: bool,
    released: Vec<AtomicU32>,
    served: Vec<AtomicU32>,
    served_stride: usize,
    last_release: Vec<AtomicU32>,
    served_age: u32,
}

impl HeldRecords {
    /// Empty records for every pixel of `plan`'s grid where a surface holds (the hiders only
    /// where `RenderPlan::held_lit_side` asks for them, the served releases where
    /// `RenderPlan::served_releases` does), else none (every read then as without them).
    pub fn new(plan: &RenderPlan) -> HeldRecords {
        let (w, h) = (plan.grid_width as usize, plan.grid_height as usize);
        let cells_per_row = w.div_ceil(HELD_CELL);
        let (pixels, cells) = if plan.has_surface_hold() {
            (w * h, cells_per_row * h)
        } else {
            (0, 0)
        };
        let lit_side = plan.held_lit_side;
        let served_stride = SERVED_HEAD_WORDS + 4 * plan.lights.len();
        let served = if plan.served_releases { pixels } else { 0 };
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
            hiders: (0..if lit_side {
                pixels * plan.lights.len()
            } else {
                0
            })
                .map(|_| std::array::from_fn(|_| AtomicU32::new(0)))
                .collect(),
            lit_side,
            released: (0..cells).map(|_| AtomicU32::new(0)).collect(),
            served: (0..served * 2 * served_stride)
                .map(|i| {
                    AtomicU32::new(if i % served_stride == 0 {
                        NO_HELD_SLAB
                    } else {
                        0
                    })
                })
                .collect(),
            served_stride,
            last_release: (0..served).map(|_| AtomicU32::new(0)).collect(),
            served_age: surface_hold::served_release_slabs(plan.slabs),
        }
    }

    /// Before slab `slab`: for every row, which cells hold some pixel that may have passed light
    /// in slab `slab − 1` (`cells ≥ slab`, with `held_lit_side`) or released within the last
    /// `served_age` slabs (as [`HeldPlanes::any_in`] asks), OR-ed over the rows
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
            let rows = self.cells.chunks(cpr).zip(self.released.chunks(cpr));
            for (y, (cells, released)) in rows.enumerate() {
                for (c, (cell, released)) in cells.iter().zip(released).enumerate() {
                    if cell_active((self.lit_side, self.served_age), cell, released, slab) {
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
            lit_side: self.lit_side,
            released: &self.released,
            served: &self.served,
            served_stride: self.served_stride,
            last_release: &self.last_release,
            served_age: self.served_age,
        }
    }
}

/// Whether a cell may hold a pixel a gather in slab `slab` reads differently from its light
/// buffer: with `lit_side`, a hold that may have passed light in slab `slab − 1`; or a release
/// within the last `age` slabs.
#[inline(always)]
fn cell_active(
    (lit_side, age): (bool, u32),
    until: &AtomicU32,
    released: &AtomicU32,
    slab: u32,
) -> bool {
    let released = released.load(Ordering::Relaxed);
    (lit_side && until.load(Ordering::Relaxed) >= slab)
        || (released != 0 && released - 1 + age >= slab)
}

impl HeldPlanes<'_> {
    /// Whether some pixel in columns `xs` of rows `ys` (grid coordinates, clamped to the grid)
    /// may be read differently from its light buffer in slab `slab` ([`cell_active`]).
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
            let at = y as usize * self.cells_per_row;
            let (row, released) = (&self.cells[at..][c0..=c1], &self.released[at..][c0..=c1]);
            row.iter()
                .zip(released)
                .any(|(c, r)| cell_active((self.lit_side, self.served_age), c, r, slab))
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

    /// Pixel `p`, released in slab `slab`, keeps the light it gathered then (`values`: per light,
    /// its channels then its depth plane) with the record of the hold it released
    /// ([`HeldPlanes::served`]); a release with no record (no entry hold) keeps nothing.
    #[inline(always)]
    pub fn keep_release(&self, p: usize, (x, y): (usize, usize), slab: u32, values: &[[f32; 4]]) {
        let Some(slot) = self.newest_slot(p, slab + 1) else {
            return;
        };
        if self.word(p, slot, 1) != slab {
            return;
        }
        let cell = y * self.cells_per_row + x / HELD_CELL;
        self.released[cell].fetch_max(slab + 1, Ordering::Relaxed);
        self.last_release[p].store(slab + 1, Ordering::Relaxed);
        let kept = &self.served[(p * 2 + slot) * self.served_stride..][..self.served_stride];
        for (l, light) in values.iter().enumerate() {
            for (c, &v) in light.iter().enumerate() {
                kept[SERVED_HEAD_WORDS + 4 * l + c].store(v.to_bits(), Ordering::Relaxed);
            }
        }
        kept[0].store(slab, Ordering::Relaxed);
    }

    /// What a gather at pixel `q` on `surface` (its depth in slabs there and its triangle) reads
    /// of light `light` at pixel `p` in slab `slab` instead of its light buffer, if anything
    /// (`surface_hold`, "Released light served on its own surface"): the light and depth plane
    /// `p` gathered in its release slab, where `p` released within the last
    /// `served_age` slabs and `q`'s surface lies on `p`'s plane. Reads the record
    /// as slab `slab − 1` left it: a cut in slab `slab` leaves `until ≥ slab`, a start writes
    /// the older slot, and a release's values were kept in an earlier slab.
    #[inline(always)]
    pub fn served(
        &self,
        plan: &RenderPlan,
        light: usize,
        (q, surface): ((i32, i32), (f32, u32)),
        p: (i32, i32),
        slab: u32,
    ) -> Option<[f32; 4]> {
        let (w, h) = (plan.grid_width as i32, plan.grid_height as i32);
        if self.served.is_empty() || p.0 < 0 || p.1 < 0 || p.0 >= w || p.1 >= h {
            return None;
        }
        let at = (p.1 * w + p.0) as usize;
        // No release kept within the age (a release of this slab, written meanwhile, passes on
        // to the record's own test, which rejects it): the record's test would reject it too.
        let last = self.last_release[at].load(Ordering::Relaxed);
        if last == 0 || last - 1 + self.served_age < slab {
            return None;
        }
        let slot = self.newest_slot(at, slab)?;
        let until = self.word(at, slot, 1);
        let kept = &self.served[(at * 2 + slot) * self.served_stride..][..self.served_stride];
        if until >= slab
            || slab - until > self.served_age
            || kept[0].load(Ordering::Relaxed) != until
        {
            return None;
        }
        let z0 = f32::from_bits(self.word(at, slot, 2));
        let [gx, gy] = plan.hold_slopes[self.word(at, slot, 3) as usize];
        let [hx, hy] = plan.hold_slopes[surface.1 as usize];
        let (dx, dy) = ((q.0 - p.0) as f32, (q.1 - p.1) as f32);
        let plane = z0 + gx * dx + gy * dy;
        let tolerance = SERVED_SLOPE_TOLERANCE + SERVED_SLOPE_TOLERANCE * (gx.abs() + gy.abs());
        let on_plane = (surface.0 - plane).abs() < SAME_SURFACE_SLABS
            && (hx - gx).abs() + (hy - gy).abs() < tolerance;
        on_plane.then(|| {
            let value = |c: usize| {
                f32::from_bits(kept[SERVED_HEAD_WORDS + 4 * light + c].load(Ordering::Relaxed))
            };
            [value(0), value(1), value(2), value(3)]
        })
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
        // Releases (slab + 1, 0: none) in other scattered cells.
        let released: Vec<AtomicU32> = (0..cells_per_row * rows)
            .map(|_| AtomicU32::new(if next(6) == 0 { next(40) } else { 0 }))
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
            lit_side: true,
            released,
            served: Vec::new(),
            served_stride: 0,
            last_release: Vec::new(),
            served_age: 8,
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
        let (cells, released) = ([AtomicU32::new(0)], [AtomicU32::new(0)]);
        let held = HeldPlanes {
            words: &words,
            cells: &cells,
            cells_per_row: 1,
            window: &[],
            words_per_row: 1,
            window_rows: (-1, 1),
            hiders: &[],
            lit_side: true,
            released: &released,
            served: &[],
            served_stride: 0,
            last_release: &[],
            served_age: 8,
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
}
