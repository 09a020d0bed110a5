//! The layered depth image (paper §4.1), built in parallel.
//!
//! Counts → prefix sum → fill, in CSR form: pixel p's fragments are
//! `offsets[p] .. offsets[p+1]`, sorted front to back by (depth, triangle index). Triangles are
//! rasterized in parallel (split into bands of rows so one large triangle does not serialize the
//! build); pixels are claimed with atomics, and the per-pixel sort makes the result independent of
//! the thread count and scheduling.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use convshadow_common::prepare::raster::{FIXED_ONE, RasterSetup, TriangleSetup};
use rayon::prelude::*;

// The LDI type and its contract live in `convshadow-common`, shared with the GPU builder.
pub use convshadow_common::contract::ldi::{
    BYTES_PER_FRAGMENT, Ldi, LdiError, LdiStats, check_fragment_storage, from_sortable_bits,
    sortable_bits,
};

/// Rows per work item when splitting triangles into bands.
const BAND_ROWS: i32 = 32;

/// Calls `f(i, j)` for every covered grid pixel of `tri` in rows `y0..=y1`.
#[inline]
fn for_each_covered(tri: &TriangleSetup, y0: i32, y1: i32, mut f: impl FnMut(i32, i32)) {
    let [x0, _, x1, _] = tri.bbox;
    let px0 = i64::from(x0) * FIXED_ONE + FIXED_ONE / 2;
    let bias = [tri.edge_bias(0), tri.edge_bias(1), tri.edge_bias(2)];
    // Stepping one pixel right changes edge k by −dy_k·ONE.
    let step: [i64; 3] = std::array::from_fn(|k| {
        let a = tri.v[k];
        let b = tri.v[(k + 1) % 3];
        -i64::from(b[1] - a[1]) * FIXED_ONE
    });
    for j in y0..=y1 {
        let py = i64::from(j) * FIXED_ONE + FIXED_ONE / 2;
        let mut e = [
            tri.edge(0, px0, py) + bias[0],
            tri.edge(1, px0, py) + bias[1],
            tri.edge(2, px0, py) + bias[2],
        ];
        for i in x0..=x1 {
            if (e[0] | e[1] | e[2]) >= 0 {
                f(i, j);
            }
            e[0] += step[0];
            e[1] += step[1];
            e[2] += step[2];
        }
    }
}

/// Work items: (triangle, first row, last row).
fn bands(setup: &RasterSetup) -> Vec<(u32, i32, i32)> {
    let mut items = Vec::with_capacity(setup.triangles.len());
    for (t, tri) in setup.triangles.iter().enumerate() {
        let mut y = tri.bbox[1];
        while y <= tri.bbox[3] {
            let y1 = (y + BAND_ROWS - 1).min(tri.bbox[3]);
            items.push((t as u32, y, y1));
            y = y1 + 1;
        }
    }
    items
}

/// Builds the LDI; refuses before allocating fragments if they exceed `budget_bytes`.
pub fn build(setup: &RasterSetup, budget_bytes: u64) -> Result<Ldi, LdiError> {
    let (w, h) = (setup.width as usize, setup.height as usize);
    let items = bands(setup);

    let counts: Vec<AtomicU32> = (0..w * h).map(|_| AtomicU32::new(0)).collect();
    items.par_iter().for_each(|&(t, y0, y1)| {
        for_each_covered(&setup.triangles[t as usize], y0, y1, |i, j| {
            counts[j as usize * w + i as usize].fetch_add(1, Ordering::Relaxed);
        });
    });

    let mut offsets = Vec::with_capacity(w * h + 1);
    let mut total: u64 = 0;
    offsets.push(0u32);
    for c in &counts {
        total += u64::from(c.load(Ordering::Relaxed));
        offsets.push(total.min(u64::from(u32::MAX)) as u32);
    }
    drop(counts);
    // Refuse over the budget, or when the machine cannot allocate the fragment arrays.
    check_fragment_storage(total, budget_bytes)?;

    let cursor: Vec<AtomicU32> = offsets[..w * h]
        .iter()
        .map(|&o| AtomicU32::new(o))
        .collect();
    let keys: Vec<AtomicU64> = (0..total).map(|_| AtomicU64::new(0)).collect();
    items.par_iter().for_each(|&(t, y0, y1)| {
        let tri = &setup.triangles[t as usize];
        for_each_covered(tri, y0, y1, |i, j| {
            let slot = cursor[j as usize * w + i as usize].fetch_add(1, Ordering::Relaxed);
            let key =
                (u64::from(sortable_bits(setup.fragment_depth(tri, i, j))) << 32) | u64::from(t);
            keys[slot as usize].store(key, Ordering::Relaxed);
        });
    });
    drop(cursor);
    let mut keys: Vec<u64> = keys.into_iter().map(AtomicU64::into_inner).collect();

    // Sort each pixel's fragments, rows in parallel.
    let mut rows: Vec<&mut [u64]> = Vec::with_capacity(h);
    let mut rest: &mut [u64] = &mut keys;
    for j in 0..h {
        let len = (offsets[(j + 1) * w] - offsets[j * w]) as usize;
        let (row, tail) = rest.split_at_mut(len);
        rows.push(row);
        rest = tail;
    }
    rows.into_par_iter().enumerate().for_each(|(j, row)| {
        let base = offsets[j * w];
        for i in 0..w {
            let a = (offsets[j * w + i] - base) as usize;
            let b = (offsets[j * w + i + 1] - base) as usize;
            row[a..b].sort_unstable();
        }
    });

    let depth = keys
        .par_iter()
        .map(|k| from_sortable_bits((k >> 32) as u32))
        .collect();
    let triangle: Vec<u32> = keys.par_iter().map(|k| *k as u32).collect();
    Ok(Ldi::from_sorted(setup, offsets, depth, triangle))
}

/// `Ldi::build(setup, budget)` spelling of [`build`] (the type lives in `convshadow-common`).
pub trait BuildLdi: Sized {
    /// See [`build`].
    fn build(setup: &RasterSetup, budget_bytes: u64) -> Result<Self, LdiError>;
}

impl BuildLdi for Ldi {
    fn build(setup: &RasterSetup, budget_bytes: u64) -> Result<Ldi, LdiError> {
        build(setup, budget_bytes)
    }
}
