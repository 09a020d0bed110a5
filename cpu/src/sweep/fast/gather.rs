//! The lane gathers through one tap row for every lane (per-slab and scheduled phases, and a
//! distance level every lane of a chunk shares): what the reference gather
//! (`crate::kernels::gather`) computes for one pixel, for 8 pixels at once, lane by lane in the
//! same order. Inside the grid, contiguous loads after one bounds proof ([`gather_inside`], also
//! two neighbouring chunks at once: the pair gathers); near its edge, tap by tap, contiguous
//! loads where a tap's corners lie inside and [`RowRun`]s where they do not. A pixel-interleaved
//! buffer whose every plane is gathered is summed in its own order and put back in plane order
//! once. Also the lanes' stores into that buffer ([`store_pixels`]). Tests (`gather/tests.rs`):
//! every gather against the reference gather and against one another, bit for bit.

use convshadow_common::pixel::lane::{Grid, Layout, MAX_LANES};
use convshadow_common::plan::kernel::Tap;

use crate::kernels::{LightPlanes, Plane, TapOrigin};

#[cfg(test)]
mod tests;

/// `acc + w0·v0 + w1·v1 + w2·v2 + w3·v3`, added left to right (the fixed sum order).
#[inline(always)]
pub(super) fn add_bilinear<L: Layout>(acc: L, w: &[L; 4], v: &[L; 4]) -> L {
    let mut s = acc;
    for (wk, vk) in w.iter().zip(v) {
        s = s + *wk * *vk;
    }
    s
}

/// The four bilinear corners (0,0), (1,0), (0,1), (1,1) of lane i's sample at
/// (`sx[i]`, `sy[i]`) in `plane` (reads outside give its outside value; [`Layout::fetch_grid`]).
#[inline(always)]
pub(super) fn fetch_corners<L: Layout>(plane: &Plane<'_>, sx: L::U, sy: L::U) -> [L; 4] {
    let one = L::u_splat(1);
    let (sx1, sy1) = (L::u_add(sx, one), L::u_add(sy, one));
    let grid = Grid {
        data: plane.data,
        base: plane.base,
        stride: plane.row_stride,
        step: plane.pixel_step,
        width: plane.width,
        height: plane.height,
    };
    let fetch = |x, y| L::fetch_grid(&grid, x, y, plane.outside);
    [
        fetch(sx, sy),
        fetch(sx1, sy),
        fetch(sx, sy1),
        fetch(sx1, sy1),
    ]
}

/// Whether every bilinear read of the `lanes` pixels from `at` through taps whose top-left
/// corners span `extent` (`[min dx, max dx, min dy, max dy]`), moved by its shift, lies inside
/// the `width` × `height` grid. The sweep's per-chunk test uses the reach of every row of every
/// table; this one the rows a chunk actually reads, so that chunks near the grid's edge whose
/// kernels stay inside take the unchecked path (the same values: only reads beyond the grid differ).
#[inline(always)]
pub(crate) fn reads_inside(
    extent: [i32; 4],
    at: TapOrigin,
    lanes: usize,
    width: i32,
    height: i32,
) -> bool {
    let (x, y) = (i64::from(at.x + at.shift[0]), i64::from(at.y + at.shift[1]));
    let e = extent.map(i64::from);
    x + e[0] >= 0
        && x + lanes as i64 + e[1] < i64::from(width)
        && y + e[2] >= 0
        && y + e[3] + 1 < i64::from(height)
}

/// Gathers every channel of one light at the pixels from `at` (one per lane) when every lane
/// uses the same `taps` (per-slab and scheduled phases, and a distance level every lane shares):
/// contiguous loads when `at.inside` (every read inside the grid; one bounds check for the taps' whole
/// `extent`, see `TapColumns::extent`), else tap by tap: contiguous loads where the tap's
/// corners lie inside, `RowRun`s where they do not. Adds into `acc[c]` tap by tap,
/// corner by corner, so every lane has the bits of any other lane count.
#[inline(always)]
pub(crate) fn gather_lanes<L: Layout>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    extent: [i32; 4],
    at: TapOrigin,
    acc: &mut [L],
) {
    let (w, h) = (planes.width, planes.height);
    if at.inside || reads_inside(extent, at, L::LANES, w, h) {
        gather_inside(planes, taps, extent, at, [acc]);
        return;
    }
    match planes.channels {
        1 => gather_near_edge::<L, 1>(planes, taps, at, acc),
        2 => gather_near_edge::<L, 2>(planes, taps, at, acc),
        3 => gather_near_edge::<L, 3>(planes, taps, at, acc),
        4 => gather_near_edge::<L, 4>(planes, taps, at, acc),
        n => panic!("a light has 1 or 3 channels and at most one depth plane, not {n} planes"),
    }
}

/// [`gather_lanes`] of a chunk whose reads may leave the grid, for `C` planes (a constant, so that
/// the sums stay in registers): tap by tap, contiguous loads where the tap's corners lie inside,
/// [`RowRun`]s where they do not. Every plane of a pixel-interleaved buffer is summed in the
/// buffer's order (the runs' values put in it), as [`gather_inside`] sums it.
#[inline(always)]
fn gather_near_edge<L: Layout, const C: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    at: TapOrigin,
    acc: &mut [L],
) {
    let TapOrigin {
        x: x0, y, shift, ..
    } = at;
    let (w, h, rs) = (planes.width, planes.height, planes.row_stride);
    let (step, plane_step) = (planes.pixel_step, planes.plane_step);
    let interleaved = planes.every_plane_interleaved();
    let lanes = L::LANES as i32;
    let mut sums = [L::splat(0.0); C];
    sums.copy_from_slice(&acc[..C]);
    if interleaved {
        sums = L::pixel_order(sums);
    }
    for t in taps {
        let sx = x0 + t.dx + shift[0];
        let sy = y + t.dy + shift[1];
        let weights = [
            L::splat(t.w[0]),
            L::splat(t.w[1]),
            L::splat(t.w[2]),
            L::splat(t.w[3]),
        ];
        if sx >= 0 && sx + 1 + lanes <= w && sy >= 0 && sy + 1 < h {
            // This tap's corners lie inside: the interior's loads.
            let at = planes.base + sy as usize * rs + sx as usize * step;
            for (c, sum) in sums.iter_mut().enumerate() {
                let v = if interleaved {
                    let at = at + c * L::LANES;
                    let load = |at| L::load(planes.data, at);
                    [load(at), load(at + C), load(at + rs), load(at + rs + C)]
                } else {
                    let at = at + c * plane_step;
                    let load = |at| load_step::<L>(planes.data, at, step);
                    [
                        load(at),
                        load(at + step),
                        load(at + rs),
                        load(at + rs + step),
                    ]
                };
                *sum = add_bilinear(*sum, &weights, &v);
            }
            continue;
        }
        // The same four runs in every plane: placed once per tap.
        let runs = [
            RowRun::at::<L>(w, h, [rs, step], sx, sy),
            RowRun::at::<L>(w, h, [rs, step], sx + 1, sy),
            RowRun::at::<L>(w, h, [rs, step], sx, sy + 1),
            RowRun::at::<L>(w, h, [rs, step], sx + 1, sy + 1),
        ];
        let mut corners = [[L::splat(0.0); C]; 4];
        for c in 0..C {
            let plane = planes.plane(c);
            for (corner, run) in corners.iter_mut().zip(&runs) {
                corner[c] = run.read(&plane);
            }
        }
        if interleaved {
            for corner in corners.iter_mut() {
                *corner = L::pixel_order(*corner);
            }
        }
        for (j, sum) in sums.iter_mut().enumerate() {
            let v = [corners[0][j], corners[1][j], corners[2][j], corners[3][j]];
            *sum = add_bilinear(*sum, &weights, &v);
        }
    }
    if interleaved {
        sums = L::plane_order(sums);
    }
    acc[..C].copy_from_slice(&sums);
}

/// Where the `LANES` values at (x.., y) of a plane come from, each what [`Plane::fetch`] gives;
/// the same for every plane of a grid, so placed once and read per plane.
#[derive(Clone, Copy)]
enum RowRun {
    /// Wholly beyond the grid: the plane's outside value.
    Outside,
    /// `LANES` values from `at` (past the plane's pixel (0, 0)) moved by `by` lanes
    /// ([`Layout::shift_lanes`]): 0 inside the grid; where the run crosses the grid's left or
    /// right edge, the row's first or last `LANES` values moved into place.
    Load { at: usize, by: i32 },
    /// Crossing an edge of a grid narrower than `LANES`: lane by lane.
    Fetch { x: i32, y: i32 },
}

impl RowRun {
    /// The run at (x.., y) of a `width` × `height` grid with rows and pixels `[row_stride,
    /// pixel_step]` apart.
    #[inline(always)]
    fn at<L: Layout>(width: i32, height: i32, strides: [usize; 2], x: i32, y: i32) -> RowRun {
        let [row_stride, step] = strides;
        let lanes = L::LANES as i32;
        if y < 0 || y >= height || x >= width || x + lanes <= 0 {
            return RowRun::Outside;
        }
        let row = y as usize * row_stride;
        if x >= 0 && x + lanes <= width {
            return RowRun::Load {
                at: row + x as usize * step,
                by: 0,
            };
        }
        if width < lanes {
            return RowRun::Fetch { x, y };
        }
        // Columns 0.. (x < 0) or width − LANES.. (the run ends beyond the grid): lane i then
        // holds column x + i.
        let first = if x < 0 { 0 } else { width - lanes };
        RowRun::Load {
            at: row + first as usize * step,
            by: x - first,
        }
    }

    /// The run's values in `plane`.
    #[inline(always)]
    fn read<L: Layout>(self, plane: &Plane<'_>) -> L {
        match self {
            RowRun::Outside => L::splat(plane.outside),
            RowRun::Load { at, by } => {
                load_step::<L>(plane.data, plane.base + at, plane.pixel_step)
                    .shift_lanes(by, plane.outside)
            }
            RowRun::Fetch { x, y } => {
                let mut v = [0.0f32; MAX_LANES];
                for (i, value) in v.iter_mut().enumerate().take(L::LANES) {
                    *value = plane.fetch(x + i as i32, y);
                }
                L::load(&v, 0)
            }
        }
    }
}

/// `data[at + i·step]` in lane i: one contiguous load when `step` is 1, else a gather (a plane
/// of a pixel-interleaved buffer read on its own).
#[inline(always)]
pub(super) fn load_step<L: Layout>(data: &[f32], at: usize, step: usize) -> L {
    if step == 1 {
        return L::load(data, at);
    }
    assert!(
        at <= u32::MAX as usize,
        "load at {at} beyond 32-bit indices"
    );
    let lanes = L::u_mul(L::u_iota(0), L::u_splat(step as u32));
    L::gather(data, L::u_add(L::u_splat(at as u32), lanes))
}

/// Writes planes `planes` of pixels x.. (lane i: pixel x + i) to a pixel-interleaved buffer
/// whose pixel x's plane 0 is `data[at]` (the planes of a pixel side by side, `planes.len()` of
/// them).
#[inline(always)]
pub fn store_pixels<L: Layout>(planes: &[L], data: &mut [f32], at: usize) {
    match planes {
        [p] => p.store(data, at),
        [a, b] => store_in_pixel_order(&[*a, *b], data, at),
        [a, b, c] => store_in_pixel_order(&[*a, *b, *c], data, at),
        [a, b, c, d] => store_in_pixel_order(&[*a, *b, *c, *d], data, at),
        _ => panic!("a light has 1 to 4 planes, not {}", planes.len()),
    }
}

/// [`store_pixels`] for `C` planes.
#[inline(always)]
fn store_in_pixel_order<L: Layout, const C: usize>(planes: &[L; C], data: &mut [f32], at: usize) {
    // One bounds check for the run (a check per value cost 1 % of the sweep's instructions).
    let run = &mut data[at..at + C * L::LANES];
    for (j, v) in L::pixel_order(*planes).iter().enumerate() {
        v.store(run, j * L::LANES);
    }
}

/// [`gather_lanes`] of `K` neighbouring chunks at once (chunk k at pixels x0 + k·LANES..), every read
/// inside the grid: each tap's weights are splat once for all chunks, and the chunks' sums are
/// independent chains the processor overlaps (one chunk's sums wait on the add latency). Each
/// lane's sum has the same terms in the same order as one chunk alone: the same bits. A
/// pixel-interleaved buffer whose every plane is gathered is summed in its own order (every
/// value's sum apart, so the same terms) and put back in plane order once
/// ([`Layout::plane_order`]).
#[inline(always)]
pub(crate) fn gather_inside<L: Layout, const K: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    extent: [i32; 4],
    at: TapOrigin,
    accs: [&mut [L]; K],
) {
    let TapOrigin {
        x: x0, y, shift, ..
    } = at;
    // The lowest index any tap's top-left corner reads, and the highest index any read reaches,
    // over every plane and chunk.
    let rs = planes.row_stride as i64;
    let (step, plane_step) = (planes.pixel_step as i64, planes.plane_step as i64);
    let (x, y) = (i64::from(x0 + shift[0]), i64::from(y + shift[1]));
    let base = planes.base as i64;
    let lo = base + (y + i64::from(extent[2])) * rs + (x + i64::from(extent[0])) * step;
    let last_plane = (planes.channels as i64 - 1) * plane_step;
    let last_pixel = x + i64::from(extent[1]) + (K * L::LANES) as i64;
    let hi = base + last_plane + (y + i64::from(extent[3]) + 1) * rs + last_pixel * step;
    assert!(
        lo >= 0 && hi < planes.data.len() as i64,
        "gather footprint {lo}..={hi} outside the light buffer"
    );
    let interleaved = planes.every_plane_interleaved();
    match planes.channels {
        2 if interleaved => gather_pixels::<L, K, 2>(planes, taps, x, y, accs),
        3 if interleaved => gather_pixels::<L, K, 3>(planes, taps, x, y, accs),
        4 if interleaved => gather_pixels::<L, K, 4>(planes, taps, x, y, accs),
        _ => gather_planes(planes, taps, x, y, accs),
    }
}

/// [`gather_inside`] plane by plane, after its bounds proof (`x`, `y`: the chunks' shifted
/// origin): contiguous loads in a planar buffer, strided ones otherwise.
#[inline(always)]
fn gather_planes<L: Layout, const K: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    x: i64,
    y: i64,
    mut accs: [&mut [L]; K],
) {
    let (rs, step) = (planes.row_stride, planes.pixel_step);
    for t in taps {
        let w = [t.w[0], t.w[1], t.w[2], t.w[3]].map(L::splat);
        let at0 = planes.base as i64
            + (y + i64::from(t.dy)) * rs as i64
            + (x + i64::from(t.dx)) * step as i64;
        for c in 0..planes.channels {
            let first = (at0 + (c * planes.plane_step) as i64) as usize;
            for (k, acc) in accs.iter_mut().enumerate() {
                let at = first + k * L::LANES * step;
                let below = at + rs;
                let v = if step == 1 {
                    // SAFETY: every load lies in the footprint `gather_inside` checked.
                    unsafe {
                        [
                            L::load_unchecked(planes.data, at),
                            L::load_unchecked(planes.data, at + 1),
                            L::load_unchecked(planes.data, below),
                            L::load_unchecked(planes.data, below + 1),
                        ]
                    }
                } else {
                    let load = |at| load_step::<L>(planes.data, at, step);
                    [load(at), load(at + step), load(below), load(below + step)]
                };
                acc[c] = add_bilinear(acc[c], &w, &v);
            }
        }
    }
}

/// [`gather_inside`] of every plane of a pixel-interleaved buffer (`C` planes per pixel), after
/// its bounds proof: `C` contiguous loads per corner and chunk, summed value by value in the
/// buffer's order, then put in plane order.
#[inline(always)]
fn gather_pixels<L: Layout, const K: usize, const C: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    x: i64,
    y: i64,
    accs: [&mut [L]; K],
) {
    let rs = planes.row_stride;
    let mut sums = [[L::splat(0.0); C]; K];
    for (sum, acc) in sums.iter_mut().zip(&accs) {
        sum.copy_from_slice(&acc[..C]);
        *sum = L::pixel_order(*sum);
    }
    for t in taps {
        let w = [t.w[0], t.w[1], t.w[2], t.w[3]].map(L::splat);
        let at0 = (planes.base as i64
            + (y + i64::from(t.dy)) * rs as i64
            + (x + i64::from(t.dx)) * C as i64) as usize;
        for (k, chunk) in sums.iter_mut().enumerate() {
            for (j, sum) in chunk.iter_mut().enumerate() {
                let at = at0 + (k * C + j) * L::LANES;
                let below = at + rs;
                // SAFETY: every load lies in the footprint `gather_inside` checked (pixel x + 1's
                // planes of the chunk's last pixel end at its highest index).
                let v = unsafe {
                    [
                        L::load_unchecked(planes.data, at),
                        L::load_unchecked(planes.data, at + C),
                        L::load_unchecked(planes.data, below),
                        L::load_unchecked(planes.data, below + C),
                    ]
                };
                *sum = add_bilinear(*sum, &w, &v);
            }
        }
    }
    for (acc, chunk) in accs.into_iter().zip(&sums) {
        acc[..C].copy_from_slice(&L::plane_order(*chunk));
    }
}
