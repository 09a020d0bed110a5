//! The layered depth image as both backends hand it over: CSR offsets and per-pixel sorted
//! fragments, its errors, statistics and fingerprint (the `ldi_hash`).
//!
//! Pixel p's fragments are `offsets[p] .. offsets[p+1]`, sorted front to back by (depth, triangle
//! index). The builders live with their backends (`convshadow_cpu::ldi::build`,
//! `convshadow_gpu::ldi::build_ldi`); both end in [`Ldi::from_sorted`], so statistics, hash and
//! the sweep input are the same code whichever built it.

use rayon::prelude::*;

use crate::pixel::hash::Fingerprint;
use crate::prepare::raster::RasterSetup;

/// Bytes the build needs per fragment at its peak (sort keys, then depth, triangle and mesh).
pub const BYTES_PER_FRAGMENT: u64 = 8 + 4 + 4 + 1;

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
    /// The fragments fit the budget, but the machine cannot allocate them (a budget above its
    /// memory): an error, never an allocation abort.
    #[error(
        "the LDI needs {fragments} fragments ({need_mib} MiB), within the memory budget, but the \
         machine cannot allocate them; lower the resolution, simplify the meshes or lower \
         --max-memory"
    )]
    Unallocatable {
        /// Fragments counted.
        fragments: u64,
        /// MiB needed.
        need_mib: u64,
    },
}

/// Checks, after counting, that `total` fragments can be stored: within `budget_bytes` at
/// [`BYTES_PER_FRAGMENT`] each and addressable by 32-bit offsets, else [`LdiError::OverBudget`];
/// and that the machine can allocate them, probed once with a fallible reservation (untouched,
/// so it costs no memory) before any fragment array, else [`LdiError::Unallocatable`]: a budget
/// above the machine's memory is an error, never an allocation abort. Both builders (CPU and the
/// GPU's host read-back) call it.
pub fn check_fragment_storage(total: u64, budget_bytes: u64) -> Result<(), LdiError> {
    fragment_storage(total, BYTES_PER_FRAGMENT, budget_bytes)
}

/// [`check_fragment_storage`] with the bytes per fragment as a parameter, so a test can ask for
/// more than any machine has without counting that many fragments.
fn fragment_storage(
    total: u64,
    bytes_per_fragment: u64,
    budget_bytes: u64,
) -> Result<(), LdiError> {
    let need = total.saturating_mul(bytes_per_fragment);
    let need_mib = need.div_ceil(1 << 20);
    if need > budget_bytes || total > u64::from(u32::MAX) {
        return Err(LdiError::OverBudget {
            fragments: total,
            need_mib,
            budget_mib: budget_bytes >> 20,
        });
    }
    let mut probe: Vec<u8> = Vec::new();
    if usize::try_from(need).map_or(true, |n| probe.try_reserve_exact(n).is_err()) {
        return Err(LdiError::Unallocatable {
            fragments: total,
            need_mib,
        });
    }
    Ok(())
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
    /// The meshes whose fragments toggle inside bits (`RasterSetup::parity_meshes`: the closed
    /// ones); an open mesh's fragments are thin-shell crossings.
    pub parity_meshes: u32,
}

impl Ldi {
    /// The LDI seen from its far end: each pixel's fragments in reverse order, each depth `d`
    /// replaced by `depth(d)` (a decreasing map, so every list stays sorted), the pixels where
    /// they are. A perspective camera's turned-round pass walks its rays far to near with it.
    pub fn turned_round(&self, depth: impl Fn(f32) -> f32) -> Ldi {
        let mut out = Ldi {
            width: self.width,
            height: self.height,
            offsets: self.offsets.clone(),
            depth: Vec::with_capacity(self.depth.len()),
            triangle: Vec::with_capacity(self.triangle.len()),
            mesh: Vec::with_capacity(self.mesh.len()),
            parity_meshes: self.parity_meshes,
        };
        for span in self.offsets.windows(2) {
            for f in (span[0] as usize..span[1] as usize).rev() {
                out.depth.push(depth(self.depth[f]));
                out.triangle.push(self.triangle[f]);
                out.mesh.push(self.mesh[f]);
            }
        }
        out
    }
}

/// Summary numbers of an LDI.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct LdiStats {
    /// Total fragments.
    pub fragments: u64,
    /// Largest fragment count of a pixel.
    pub max_layers: u32,
    /// Pixels where some closed mesh has an odd fragment count (a defect: the parity test would
    /// smear; open meshes are thin shells and not counted).
    pub odd_pixels: u64,
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
            parity_meshes: setup.parity_meshes,
        }
    }

    /// The fragment index range of grid pixel (i, j).
    pub fn range(&self, i: u32, j: u32) -> std::ops::Range<usize> {
        let p = (j * self.width + i) as usize;
        self.offsets[p] as usize..self.offsets[p + 1] as usize
    }

    /// Fragments, max layers and odd pixels (of the closed meshes).
    pub fn stats(&self) -> LdiStats {
        let n = (self.width * self.height) as usize;
        let (max_layers, odd_pixels) = (0..n)
            .into_par_iter()
            .map(|p| {
                let (a, b) = (self.offsets[p] as usize, self.offsets[p + 1] as usize);
                let parity = self.mesh[a..b]
                    .iter()
                    .fold(0u32, |m, &id| m ^ ((1 << id) & self.parity_meshes));
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
    fn fragment_storage_is_refused_over_the_budget_and_when_the_machine_cannot_allocate_it() {
        // Within the budget: 1000 fragments of 17 bytes fit exactly 17000 bytes, not 16999.
        assert_eq!(check_fragment_storage(1000, 17_000), Ok(()));
        assert_eq!(
            check_fragment_storage(1000, 16_999),
            Err(LdiError::OverBudget {
                fragments: 1000,
                need_mib: 1,
                budget_mib: 0
            })
        );
        // More fragments than 32-bit offsets address, whatever the budget.
        let too_many = u64::from(u32::MAX) + 1;
        assert!(matches!(
            check_fragment_storage(too_many, u64::MAX),
            Err(LdiError::OverBudget { .. })
        ));
        // 2^31 fragments of 2^31 bytes: 2^62 bytes (4 EiB) fit a budget of u64::MAX but no
        // machine's address space, so the probe's reservation fails: an error, not an abort.
        assert_eq!(
            fragment_storage(1 << 31, 1 << 31, u64::MAX),
            Err(LdiError::Unallocatable {
                fragments: 1 << 31,
                need_mib: 1 << 42
            })
        );
        // Beyond u64: the need saturates and is still refused.
        assert!(matches!(
            fragment_storage(1 << 31, u64::MAX, u64::MAX),
            Err(LdiError::Unallocatable { .. })
        ));
        let msg = fragment_storage(1 << 31, 1 << 31, u64::MAX)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("2147483648 fragments") && msg.contains("cannot allocate"),
            "{msg}"
        );
    }

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
