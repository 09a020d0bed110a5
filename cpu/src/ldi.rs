//! The layered depth image (paper §4.1), built in parallel.
//!
//! Counts → prefix sum → fill, in CSR form: pixel p's fragments are
//! `offsets[p] .. offsets[p+1]`, sorted front to back by (depth, triangle index). Triangles are
//! rasterized in parallel (split into bands of rows so one large triangle does not serialize the
//! build); pixels are claimed with atomics, and the per-pixel sort makes the result independent of
//! the thread count and scheduling.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use convshadow_common::hash::Fingerprint;
use convshadow_common::raster::{FIXED_ONE, RasterSetup, TriangleSetup};
use rayon::prelude::*;

/// Bytes the build needs per fragment at its peak (sort keys, then depth, triangle and mesh).
pub const BYTES_PER_FRAGMENT: u64 = 8 + 4 + 4 + 1;
/// Rows per work item when splitting triangles into bands.
const BAND_ROWS: i32 = 32;

/// Why the LDI could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LdiError {
    /// The fragments would not fit in the memory budget.
    #[error(
        "the LDI needs {fragments} fragments ({need_mib} MiB), more than the memory budget of \
         {budget_mib} MiB; lower the resolution, simplify the meshes or raise --max-memory"
    )]
    OverBudget {
        /// Fragments counted.
        fragments: u64,
        /// MiB needed.
        need_mib: u64,
        /// MiB allowed.
        budget_mib: u64,
    },
}

/// The layered depth image.
#[derive(Clone, Debug, PartialEq)]
pub struct Ldi {
    /// Grid width (image + guard band).
    pub width: u32,
    /// Grid height.
    pub height: u32,
    /// CSR offsets: `width·height + 1` entries.
    pub offsets: Vec<u32>,
    /// Fragment depth (camera z relative to the first slab's front), front to back per pixel.
    pub depth: Vec<f32>,
    /// Fragment triangle index into the `RasterSetup`.
    pub triangle: Vec<u32>,
    /// Fragment mesh index (scene order).
    pub mesh: Vec<u8>,
}

/// Summary numbers of an LDI.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct LdiStats {
    /// Total fragments.
    pub fragments: u64,
    /// Largest fragment count of a pixel.
    pub max_layers: u32,
    /// Pixels where some mesh has an odd fragment count (open or defective meshes).
    pub odd_pixels: u64,
}

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

/// Maps an f32 to a u32 whose unsigned order is the float's total order.
#[inline(always)]
pub fn sortable_bits(f: f32) -> u32 {
    let b = f.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Inverse of [`sortable_bits`].
#[inline(always)]
pub fn from_sortable_bits(s: u32) -> f32 {
    f32::from_bits(if s & 0x8000_0000 != 0 {
        s & 0x7fff_ffff
    } else {
        !s
    })
}

impl Ldi {
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
        let need = total * BYTES_PER_FRAGMENT;
        if need > budget_bytes || total > u64::from(u32::MAX) {
            return Err(LdiError::OverBudget {
                fragments: total,
                need_mib: need.div_ceil(1 << 20),
                budget_mib: budget_bytes >> 20,
            });
        }
        drop(counts);

        let cursor: Vec<AtomicU32> = offsets[..w * h]
            .iter()
            .map(|&o| AtomicU32::new(o))
            .collect();
        let keys: Vec<AtomicU64> = (0..total).map(|_| AtomicU64::new(0)).collect();
        items.par_iter().for_each(|&(t, y0, y1)| {
            let tri = &setup.triangles[t as usize];
            for_each_covered(tri, y0, y1, |i, j| {
                let slot = cursor[j as usize * w + i as usize].fetch_add(1, Ordering::Relaxed);
                let key = (u64::from(sortable_bits(tri.depth_at(i, j))) << 32) | u64::from(t);
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

    /// Assembles an LDI from CSR offsets and per-pixel sorted fragments (depth, triangle); the
    /// mesh ids come from the set-up. Shared by the CPU build and the GPU read-back.
    pub fn from_sorted(
        setup: &RasterSetup,
        offsets: Vec<u32>,
        depth: Vec<f32>,
        triangle: Vec<u32>,
    ) -> Ldi {
        let mesh = triangle
            .par_iter()
            .map(|&t| setup.triangles[t as usize].mesh as u8)
            .collect();
        Ldi {
            width: setup.width,
            height: setup.height,
            offsets,
            depth,
            triangle,
            mesh,
        }
    }

    /// The fragment index range of grid pixel (i, j).
    pub fn range(&self, i: u32, j: u32) -> std::ops::Range<usize> {
        let p = (j * self.width + i) as usize;
        self.offsets[p] as usize..self.offsets[p + 1] as usize
    }

    /// Fragments, max layers and odd pixels.
    pub fn stats(&self) -> LdiStats {
        let n = (self.width * self.height) as usize;
        let (max_layers, odd_pixels) = (0..n)
            .into_par_iter()
            .map(|p| {
                let (a, b) = (self.offsets[p] as usize, self.offsets[p + 1] as usize);
                let parity = self.mesh[a..b].iter().fold(0u32, |m, &id| m ^ (1 << id));
                ((b - a) as u32, u64::from(parity != 0))
            })
            .reduce(|| (0, 0), |x, y| (x.0.max(y.0), x.1 + y.1));
        LdiStats {
            fragments: u64::from(self.offsets[n]),
            max_layers,
            odd_pixels,
        }
    }

    /// 64-bit fingerprint of the CSR offsets, depths and mesh ids (the `ldi_hash`).
    pub fn fingerprint(&self) -> u64 {
        let mut f = Fingerprint::default();
        f.word(self.width);
        f.word(self.height);
        f.words(&self.offsets);
        f.floats(&self.depth);
        for &m in &self.mesh {
            f.word(u32::from(m));
        }
        f.finish()
    }

    /// Number of fragments whose depth lies exactly on a slab back face (reported by `ldi`).
    pub fn fragments_on(&self, faces: &[f32]) -> u64 {
        self.depth
            .par_iter()
            .filter(|d| faces.binary_search_by(|f| f.total_cmp(d)).is_ok())
            .count() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sortable_bits_orders_like_floats() {
        let v = [-1e30f32, -1.0, -1e-30, -0.0, 0.0, 1e-30, 0.5, 1.0, 1e30];
        for w in v.windows(2) {
            assert!(sortable_bits(w[0]) < sortable_bits(w[1]), "{w:?}");
        }
        for x in v {
            assert_eq!(from_sortable_bits(sortable_bits(x)).to_bits(), x.to_bits());
        }
    }
}
