//! Convolution kernels: their names, their per-slab moments, and the per-light tap tables that
//! every path (scalar, SIMD, GPU) reads: computed once on the host, never per pixel.
//!
//! A kernel is a gather: the light entering slab k at pixel p is
//! `Σ_taps w · I_{k-1}(p + offset)`, each tap read with bilinear interpolation. The offsets are
//! `−(μκ + o)` where `o` is a zero-mean sample of the kernel's pattern, so the light buffer's
//! impulse response moves by `+μκ` per slab and spreads by `Σκ`, with
//! μκ = −e·μl and Σκ = d1·e·R(α)·diag(σx², σy²)·R(α)ᵀ (e the slab thickness, d1 the optimal
//! shadow distance, μl = (tan ωx, tan ωy) the light's mean direction per unit depth).
//!
//! Because every pixel shares the same sub-pixel offsets for a given phase, a tap is stored as an
//! integer offset plus four bilinear corner weights: no per-pixel `floor`, and the same table on
//! the GPU. All host maths here is f64; only the final weights are rounded to f32.
//!
//! One file per topic: `crate::model::kernel` (names), [`moments`] (μκ, Σκ), [`table`] (taps, discretisation),
//! `compensation` (bilinear variance), and one file per kernel family; every item is
//! re-exported here, so `kernel::X` paths do not depend on the file layout.

mod box_kernel;
mod compensation;
mod dirac;
mod ellipse;
mod gaussian;
pub mod moments;
mod poisson;
pub mod table;
#[cfg(test)]
mod tests;

use crate::model::kernel::{KernelKind, KernelSpec};
use box_kernel::*;
use compensation::*;
use dirac::*;
pub use ellipse::*;
use gaussian::*;
pub use moments::*;
pub use poisson::*;
pub use table::*;

/// `values` four to a lane vector (entry i holds values 4i..4i + 4; the last padded with 0), for
/// host loops that compute four terms at once and still sum them one at a time.
pub(crate) fn lanes_of_four(values: &[f64]) -> Vec<wide::f64x4> {
    values
        .chunks(4)
        .map(|q| wide::f64x4::new(std::array::from_fn(|k| q.get(k).copied().unwrap_or(0.0))))
        .collect()
}
