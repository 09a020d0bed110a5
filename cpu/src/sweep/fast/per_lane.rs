//! The gather where each lane has its own tap row (per-pixel hashed phases, and distance levels
//! that differ between a chunk's lanes): the light's tap table by column ([`TapColumns`]), the
//! lanes' rows summarised ([`LaneRows`]), and [`gather_per_lane`]: gathered weights and, inside
//! the grid, two lanes' pixels to a value (the lane pairs and AVX2 gathers of
//! `convshadow_common::pixel::lane::Layout`), each lane's arithmetic that of the reference gather
//! (`crate::kernels::gather`) in the same order. Tests: `gather/tests.rs`.

use convshadow_common::pixel::lane::{Layout, MAX_LANES, halves, load_halves, splat_within_halves};
use convshadow_common::plan::kernel::KernelTable;
use wide::i32x8;

use super::gather::{add_bilinear, fetch_corners, reads_inside};
use crate::kernels::{LightPlanes, TapOrigin, level_taps};

/// A light's tap table by tap, as structure-of-arrays for the per-lane gather: tap k of row p
/// at `k * phase_count + p`, so that one gather by the lanes' rows reads a tap's column. Built
/// once per sweep from the plan's [`KernelTable`] (same values, another layout). Its fields are
/// only built by [`TapColumns::new`] (never changed after), so they agree with one another: the
/// per-lane gather's unchecked loads rely on it.
pub struct TapColumns {
    /// Rows of the table (levels × phases).
    pub(crate) phase_count: usize,
    /// The four corner weights of each tap, one column per tap.
    pub(crate) weights: Vec<[f32; 4]>,
    /// `dy · row_stride + dx · pixel_step` (wrapping: an `i32` offset in the light buffer).
    pub(crate) offset: Vec<u32>,
    /// Per phase, the taps' `[min dx, max dx, min dy, max dy]` (the top-left corners' extent).
    pub(crate) extent: Vec<[i32; 4]>,
    /// `dy · level_stride + dx` (wrapping): the taps' offsets in the level plane (distance
    /// penumbra).
    pub(crate) level_offset: Vec<u32>,
    /// Per row, the taps the light gather must visit: up to the last with a nonzero weight. The
    /// distance penumbra pads each level's rows to the widest level with zero taps; a zero
    /// weight adds +0 to a sum that is never −0 (weights and values are ≥ 0 and finite), so
    /// skipping trailing zero taps keeps every bit.
    pub(crate) gather_taps: Vec<u32>,
    /// Per row, the taps [`distance_rows`] must visit: up to the last that is not the zero tap at
    /// (0, 0), plus one such tap if any follows (every padding tap reads the same four level
    /// corners, so one stands for all: the same minimum).
    pub(crate) level_taps: Vec<u32>,
    /// Per row, `[−min dx, max dx, −min dy, max dy, gather_taps, level_taps, −min offset,
    /// max offset]` (offsets: its taps' [`TapColumns::offset`]s read as `i32`): every field of
    /// [`LaneRows`] is a maximum over lanes, so a chunk's summary is one 8-lane `max` per lane.
    pub(crate) summary: Vec<[i32; 8]>,
    /// The largest of every row's summary, field by field: a summary of any lanes' rows (wider
    /// extents and offset spans than theirs, which only proofs read), exact in its tap counts
    /// where `same_counts` holds.
    pub(crate) whole_summary: [i32; 8],
    /// Whether every row has the same `gather_taps` and the same `level_taps`.
    pub(crate) same_counts: bool,
    /// The light buffer's and the level plane's row strides and the light buffer's pixel step
    /// the offsets were built for: the unchecked gathers check them against the buffers they
    /// read.
    pub(crate) strides: [usize; 3],
}

/// What a chunk's lanes read through their rows: the union of the rows' extents, the most taps
/// any lane's gather (and level search) visits, and whether every lane has the same row.
pub struct LaneRows {
    /// `[min dx, max dx, min dy, max dy]` over the lanes' rows.
    pub extent: [i32; 4],
    /// The largest `TapColumns::gather_taps` of the lanes' rows.
    pub gather_taps: usize,
    /// The largest `TapColumns::level_taps` of the lanes' rows.
    pub level_taps: usize,
    /// The row of every lane, when they all have the same one.
    pub uniform: Option<u32>,
    /// `[min, max]` over the lanes' rows of their taps' `TapColumns::offset`s (as `i32`).
    pub offset_span: [i64; 2],
}

impl LaneRows {
    /// The summary of the lanes' rows `rows` in `columns`.
    #[inline(always)]
    pub fn of<L: Layout>(columns: &TapColumns, rows: L::U) -> LaneRows {
        let mut r = [0u32; MAX_LANES];
        L::u_store(rows, &mut r);
        let mut most = i32x8::splat(i32::MIN);
        for &row in &r[..L::LANES] {
            most = most.max(i32x8::new(columns.summary[row as usize]));
        }
        LaneRows::from_summary(most.to_array(), L::u_uniform(rows))
    }

    /// [`LaneRows::of`] for lanes whose every read the caller knows to lie inside the grid
    /// (`interior`): where every row of `columns` visits as many taps as any other, the table's
    /// [`TapColumns::whole_summary`] without a lookup per lane (the same tap counts; its wider
    /// extent and offset span hold for any rows, and inside the grid they only prove reads).
    /// Kept apart from `of`'s body: one shared body measured +3.7 % sweep instructions.
    #[inline(always)]
    pub fn within<L: Layout>(columns: &TapColumns, rows: L::U, interior: bool) -> LaneRows {
        if !(interior && columns.same_counts) {
            return LaneRows::of::<L>(columns, rows);
        }
        // Every lane's row is a row of the table, as `of`'s lookup checks (unchecked gathers
        // by these rows rely on it).
        let highest = L::u_largest(rows);
        assert!(
            (highest as usize) < columns.phase_count,
            "row {highest} beyond the table"
        );
        LaneRows::from_summary(columns.whole_summary, L::u_uniform(rows))
    }

    /// A summary from the fieldwise largest of rows' [`TapColumns::summary`] entries.
    #[inline(always)]
    fn from_summary(m: [i32; 8], uniform: Option<u32>) -> LaneRows {
        LaneRows {
            extent: [-m[0], m[1], -m[2], m[3]],
            gather_taps: m[4] as usize,
            level_taps: m[5] as usize,
            uniform,
            offset_span: [-i64::from(m[6]), i64::from(m[7])],
        }
    }
}

impl TapColumns {
    /// The columns of `table` for light buffers with rows `row_stride` and pixels `pixel_step`
    /// apart and level planes with rows `level_stride` apart.
    pub fn new(
        table: &KernelTable,
        row_stride: usize,
        pixel_step: usize,
        level_stride: usize,
    ) -> TapColumns {
        assert!(
            (1..=4).contains(&pixel_step),
            "a pixel pair of {pixel_step} planes exceeds 8 floats"
        );
        // Every row of every level: the per-lane gather picks a row per lane.
        let (pc, n) = (table.rows() as usize, table.taps_per_phase as usize);
        let mut columns = TapColumns {
            summary: Vec::new(),
            whole_summary: [i32::MIN; 8],
            same_counts: false,
            strides: [row_stride, level_stride, pixel_step],

            phase_count: pc,
            weights: (0..n * pc)
                .map(|j| table.taps[(j % pc) * n + j / pc].w)
                .collect(),
            offset: (0..n * pc)
                .map(|j| {
                    let t = &table.taps[(j % pc) * n + j / pc];
                    let dx = t.dx as i64 * pixel_step as i64;
                    (t.dy as i64 * row_stride as i64 + dx) as i32 as u32
                })
                .collect(),
            level_offset: (0..n * pc)
                .map(|j| {
                    let t = &table.taps[(j % pc) * n + j / pc];
                    (t.dy as i64 * level_stride as i64 + t.dx as i64) as i32 as u32
                })
                .collect(),
            gather_taps: (0..pc as u32)
                .map(|p| {
                    let taps = table.phase(p);
                    let last = taps.iter().rposition(|t| t.w.iter().any(|&w| w != 0.0));
                    last.map_or(0, |i| i + 1) as u32
                })
                .collect(),
            level_taps: (0..pc as u32).map(|p| level_taps(table, p)).collect(),
            extent: (0..pc as u32)
                .map(|p| {
                    let taps = table.phase(p);
                    let (dx, dy) = (taps.iter().map(|t| t.dx), taps.iter().map(|t| t.dy));
                    [
                        dx.clone().min().unwrap_or(0),
                        dx.max().unwrap_or(0),
                        dy.clone().min().unwrap_or(0),
                        dy.max().unwrap_or(0),
                    ]
                })
                .collect(),
        };
        // Each row's summary from the fields above (see `summary`).
        columns.summary = (0..pc)
            .map(|row| {
                let e = columns.extent[row];
                let (g, l) = (columns.gather_taps[row], columns.level_taps[row]);
                let offsets = (0..n).map(|k| columns.offset[k * pc + row] as i32);
                let (lo, hi) = (
                    offsets.clone().min().unwrap_or(0),
                    offsets.max().unwrap_or(0),
                );
                assert!(lo > i32::MIN, "tap offset {lo} out of range");
                [-e[0], e[1], -e[2], e[3], g as i32, l as i32, -lo, hi]
            })
            .collect();
        for row in &columns.summary {
            let most = i32x8::new(columns.whole_summary).max(i32x8::new(*row));
            columns.whole_summary = most.to_array();
        }
        let counts = |v: &[u32]| v.iter().all(|&c| c == v[0]);
        columns.same_counts = counts(&columns.gather_taps) && counts(&columns.level_taps);
        columns
    }
}

/// [`gather_lanes`] where lane i uses phase `phases[i]` of `table` (per-pixel hashed phases; `columns`
/// is the same table by tap, `lane_rows` its [`LaneRows`] summary of `phases`), at the pixels
/// from `at`: gathered weights and, inside the grid, gathered loads; lane arithmetic in the same
/// order.
#[inline(always)]
pub(crate) fn gather_per_lane<L: Layout>(
    planes: &LightPlanes<'_>,
    table: &KernelTable,
    columns: &TapColumns,
    phases: L::U,
    lane_rows: &LaneRows,
    at: TapOrigin,
    acc: &mut [L],
) {
    let TapOrigin {
        x: x0,
        y,
        shift,
        inside: interior,
    } = at;
    let n = lane_rows.gather_taps;
    let pc = columns.phase_count;
    let (rs, step) = (planes.row_stride, planes.pixel_step);
    // Lane 0's pixel, and lane i's offset to its pixel at the slab's shifted origin.
    let pixel = planes.base + y as usize * rs + x0 as usize * step;
    let shift_offset = shift[1] as i64 * rs as i64 + shift[0] as i64 * step as i64;
    let lane_step = L::u_mul(L::u_iota(0), L::u_splat(step as u32));
    let lane_shift = L::u_add(lane_step, L::u_splat(shift_offset as i32 as u32));
    let (w, h) = (planes.width, planes.height);
    let pair_loads = PairLoads {
        planes,
        columns,
        phases,
        pixel,
        lane_shift,
        shift: shift_offset,
        offset_span: lane_rows.offset_span,
    };
    if interior || reads_inside(lane_rows.extent, at, L::LANES, w, h) {
        pair_loads.add_taps(0..n, acc, Bounds::WholeRows);
        return;
    }
    let mut lane_phase = [0u32; MAX_LANES];
    L::u_store(phases, &mut lane_phase);
    for k in 0..n {
        let mut sx = [0i32; MAX_LANES];
        let mut sy = [0i32; MAX_LANES];
        for i in 0..L::LANES {
            let t = &table.phase(lane_phase[i])[k];
            sx[i] = x0 + i as i32 + t.dx + shift[0];
            sy[i] = y + t.dy + shift[1];
        }
        let (xs, ys) = (&sx[..L::LANES], &sy[..L::LANES]);
        let lowest = |v: &[i32]| v.iter().fold(i32::MAX, |m, &a| m.min(a));
        let highest = |v: &[i32]| v.iter().fold(i32::MIN, |m, &a| m.max(a));
        let tap_inside =
            lowest(xs) >= 0 && highest(xs) + 1 < w && lowest(ys) >= 0 && highest(ys) + 1 < h;
        if tap_inside {
            // Near the edge, a tap whose corners all lie inside takes the interior path's
            // loads: the same terms in the same order.
            pair_loads.add_taps(k..k + 1, acc, Bounds::PerTap);
            continue;
        }
        let w4 = L::gather4(&columns.weights[k * pc..(k + 1) * pc], phases);
        // Signed coordinates as integer lanes ([`Layout::fetch_grid`] reads them back as i32).
        let (sx, sy) = (
            L::u_load(&sx.map(|v| v as u32), 0),
            L::u_load(&sy.map(|v| v as u32), 0),
        );
        for (c, a) in acc.iter_mut().enumerate().take(planes.channels) {
            let v = fetch_corners(&planes.plane(c), sx, sy);
            *a = add_bilinear(*a, &w4, &v);
        }
    }
}

/// How [`PairLoads::add_taps`] proves its reads lie in the light buffer.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Bounds {
    /// Every tap of every lane's row reads inside the grid: one proof for them all.
    WholeRows,
    /// Only the taps added read inside: a check per tap.
    PerTap,
}

/// The per-lane gather's reads inside the grid: every plane's two pixel pairs per lane and tap
/// ([`Layout::acc_blocks`]), lane i at `pixel + lane_shift[i] +` its tap's offset.
struct PairLoads<'a, L: Layout> {
    planes: &'a LightPlanes<'a>,
    columns: &'a TapColumns,
    phases: L::U,
    pixel: usize,
    /// Lane i's offset `i + shift` to the shifted origin (wrapping; `shift` below).
    lane_shift: L::U,
    /// The slab's shift as an offset in the light buffer, `shift_y · row_stride + shift_x`.
    shift: i64,
    /// [`LaneRows::offset_span`] of the lanes' rows `phases`.
    offset_span: [i64; 2],
}

impl<L: Layout> PairLoads<'_, L> {
    /// Adds taps `taps` (every corner of every lane inside the grid) to `acc`, plane by plane.
    #[inline(always)]
    fn add_taps(&self, taps: std::ops::Range<usize>, acc: &mut [L], bounds: Bounds) {
        match self.planes.channels {
            1 => self.add_taps_to::<1>(taps, acc, bounds),
            2 => self.add_taps_to::<2>(taps, acc, bounds),
            3 => self.add_taps_to::<3>(taps, acc, bounds),
            4 => self.add_taps_to::<4>(taps, acc, bounds),
            n => panic!("a light has 1 or 3 channels and at most one depth plane, not {n} planes"),
        }
    }

    /// [`PairLoads::add_taps`] for `C` planes (a constant, so that the sums stay in registers):
    /// by pixel pairs of one plane in a planar buffer, of all planes in a pixel-interleaved one
    /// whose every plane is gathered, else by gathers.
    #[inline(always)]
    fn add_taps_to<const C: usize>(
        &self,
        taps: std::ops::Range<usize>,
        acc: &mut [L],
        bounds: Bounds,
    ) {
        let planes = self.planes;
        if planes.pixel_step == 1 {
            self.add_plane_pairs::<C>(taps, acc, bounds);
        } else if planes.every_plane_interleaved() {
            self.add_pixel_pairs::<C>(taps, acc, bounds);
        } else {
            self.add_gathered::<C>(taps, acc);
        }
    }

    /// [`PairLoads::add_taps_to`] in a planar buffer: every plane's two pixel pairs per lane.
    #[inline(always)]
    fn add_plane_pairs<const C: usize>(
        &self,
        taps: std::ops::Range<usize>,
        acc: &mut [L],
        bounds: Bounds,
    ) {
        let planes = self.planes;
        // C sums, a constant length: copied back in registers (a run-time length was a `memcpy`
        // call, two per chunk of the default scene).
        let acc = &mut acc[..C];
        // Every plane's accumulator, in the lane type's layout for pixel-pair loads (a shuffle).
        let mut sums = [L::acc_from(L::splat(0.0)); C];
        for (sum, a) in sums.iter_mut().zip(acc.iter()) {
            *sum = L::acc_from(*a);
        }
        let plane_step = planes.plane_step;
        let (data, rs) = (planes.data, planes.row_stride);
        if bounds == Bounds::PerTap {
            for k in taps {
                let (w, rel) = self.tap(k);
                L::acc_blocks(&mut sums, &w, data, self.pixel, plane_step, rel, rs);
            }
        } else {
            // One bounds proof for every tap: the lanes' rows' offset span, moved by the lanes'
            // shifts, with no wrap in the 32-bit offsets `rel`, puts every read of every plane in
            // `data`.
            let [lo, hi] = self.offset_span;
            let (lo, hi) = (lo + self.shift, hi + self.shift + L::LANES as i64 - 1);
            let last_plane = (C as i64 - 1) * plane_step as i64;
            let (first, last) = (self.pixel as i64 + lo, self.pixel as i64 + hi + last_plane);
            assert!(
                self.columns.strides[0] == rs
                    && self.columns.strides[2] == 1
                    && lo >= i64::from(i32::MIN)
                    && hi <= i64::from(i32::MAX)
                    && first >= 0
                    && last + rs as i64 + 1 < data.len() as i64,
                "per-lane gather reads {first}..={last} outside the light buffer"
            );
            for k in taps {
                let (w, rel) = self.tap(k);
                // SAFETY: lane i reads at `pixel + rel[i]` (and + 1, + rs, + rs + 1) in each
                // plane, and rel[i] = i + shift + the offset of a tap of lane i's row, within the
                // span proved above (`LaneRows::within` of these rows, from `TapColumns::new`).
                unsafe {
                    L::acc_blocks_unchecked(&mut sums, &w, data, self.pixel, plane_step, rel, rs);
                }
            }
        }
        for (a, sum) in acc.iter_mut().zip(sums.iter()) {
            *a = L::acc_finish(*sum);
        }
    }

    /// [`PairLoads::add_taps_to`] in a pixel-interleaved buffer of `C` planes (C ≤ 4), all
    /// gathered: two lanes to a value (lanes i and i + 4, [`Layout::to_lane_pairs`]), each corner
    /// pixel's planes one 16-byte read per lane ([`load_halves`]), times its weight spread over
    /// the lane's half ([`splat_within_halves`]), added in the fixed order: top left, top right,
    /// bottom left, bottom right. Each lane's arithmetic is its own, so any pairing gives the
    /// same bits; pairs halve the multiplies and adds of one value per lane.
    #[inline(always)]
    fn add_pixel_pairs<const C: usize>(
        &self,
        taps: std::ops::Range<usize>,
        acc: &mut [L],
        bounds: Bounds,
    ) {
        let columns = self.columns;
        let (data, rs, pc) = (
            self.planes.data,
            self.planes.row_stride,
            columns.phase_count,
        );
        let mut rows = [0u32; MAX_LANES];
        let mut lane_shift = [0u32; MAX_LANES];
        L::u_store(self.phases, &mut rows);
        L::u_store(self.lane_shift, &mut lane_shift);
        let mut sums = L::to_lane_pairs::<C>(&std::array::from_fn(|c| acc[c]));
        // One value per pair of lanes (i, i + 4); one lane alone shares its value with itself
        // (the high half's sums are dropped).
        let (pairs, partner) = if L::LANES == 8 { (4, 4) } else { (L::LANES, 0) };
        let checked = bounds == Bounds::PerTap;
        if !checked {
            // One bounds proof for every tap (as `add_plane_pairs`'): lane i reads 4 floats at
            // `pixel + rel[i]`, `+ C`, `+ rs` and `+ rs + C`, all below `+ rs + 8`.
            let [lo, hi] = self.offset_span;
            let lane_span = ((L::LANES - 1) * C) as i64;
            let (lo, hi) = (lo + self.shift, hi + self.shift + lane_span);
            let (first, last) = (
                self.pixel as i64 + lo,
                self.pixel as i64 + hi + rs as i64 + 7,
            );
            assert!(
                columns.strides[0] == rs
                    && columns.strides[2] == C
                    && lo >= i64::from(i32::MIN)
                    && hi <= i64::from(i32::MAX)
                    && first >= 0
                    && last < data.len() as i64,
                "per-lane gather reads {first}..={last} outside the light buffer"
            );
        }
        // Every lane's entry `k·pc + row` lies in the columns: rows below `pc`, taps below the
        // columns' count.
        let highest = L::u_largest(self.phases);
        assert!(
            (highest as usize) < pc
                && taps.end * pc <= columns.offset.len()
                && columns.weights.len() == columns.offset.len(),
            "per-lane gather: row {highest} or tap {} beyond the columns",
            taps.end
        );
        // Lane j's reads start `rel[j]` past `pixel`.
        let rel = |entry: usize, j: usize| {
            // SAFETY: `entry` lies in the columns (checked above).
            let offset = unsafe { *columns.offset.get_unchecked(entry) };
            offset.wrapping_add(lane_shift[j]) as i32 as isize
        };
        let origin = data.as_ptr().wrapping_add(self.pixel);
        for k in taps {
            for (i, sum) in sums.iter_mut().enumerate().take(pairs) {
                let (ea, eb) = (
                    k * pc + rows[i] as usize,
                    k * pc + rows[i + partner] as usize,
                );
                let (ra, rb) = (rel(ea, i), rel(eb, i + partner));
                // SAFETY: both entries lie in the weights column (checked above).
                let w = unsafe {
                    halves(
                        columns.weights.get_unchecked(ea),
                        columns.weights.get_unchecked(eb),
                    )
                };
                let w = splat_within_halves(w);
                let corner = |by: usize| {
                    if checked {
                        let (a, b) = (self.pixel as isize + ra, self.pixel as isize + rb);
                        let (a, b) = (a as usize + by, b as usize + by);
                        let four = |at: usize| <&[f32; 4]>::try_from(&data[at..at + 4]).unwrap();
                        halves(four(a), four(b))
                    } else {
                        // SAFETY: within the span proved above: rel[i] = i·C + shift + the
                        // offset of a tap of lane i's row (`LaneRows::within`, from
                        // `TapColumns::new`), and `by + 4 ≤ rs + 8`.
                        unsafe { load_halves(origin.offset(ra).add(by), origin.offset(rb).add(by)) }
                    }
                };
                // `a += p` is `a = a + p`: no fused multiply-add (DESIGN §3).
                *sum += corner(0) * w[0];
                *sum += corner(C) * w[1];
                *sum += corner(rs) * w[2];
                *sum += corner(rs + C) * w[3];
            }
        }
        acc[..C].copy_from_slice(&L::from_lane_pairs::<C>(&sums));
    }

    /// [`PairLoads::add_taps_to`] by one gather per corner, plane and tap (some planes of a
    /// pixel-interleaved buffer: a depth plane alone), each checked.
    #[inline(always)]
    fn add_gathered<const C: usize>(&self, taps: std::ops::Range<usize>, acc: &mut [L]) {
        let planes = self.planes;
        let (step, rs) = (planes.pixel_step as u32, planes.row_stride as u32);
        for k in taps {
            let col = k * self.columns.phase_count..(k + 1) * self.columns.phase_count;
            let w = L::gather4(&self.columns.weights[col.clone()], self.phases);
            let rel = L::u_add(
                L::u_gather(&self.columns.offset[col], self.phases),
                self.lane_shift,
            );
            for (c, a) in acc.iter_mut().enumerate().take(C) {
                let origin = (self.pixel + c * planes.plane_step) as u32;
                let top_left = L::u_add(L::u_splat(origin), rel);
                let corner = |by: u32| L::gather(planes.data, L::u_add(top_left, L::u_splat(by)));
                let v = [corner(0), corner(step), corner(rs), corner(rs + step)];
                *a = add_bilinear(*a, &w, &v);
            }
        }
    }

    /// Tap k's weights for the lanes' rows and each lane's offset `rel` from `pixel`.
    #[inline(always)]
    fn tap(&self, k: usize) -> (L::W4, L::U) {
        let columns = self.columns;
        let col = k * columns.phase_count..(k + 1) * columns.phase_count;
        let w = L::weights4(&columns.weights[col.clone()], self.phases);
        let rel = L::u_add(
            L::u_gather(&columns.offset[col], self.phases),
            self.lane_shift,
        );
        (w, rel)
    }
}
