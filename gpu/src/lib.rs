//! The wgpu port of convshadow: device set-up, the WGSL shaders of the CPU stages (one shader file
//! per CPU stage module, named alike) and the host-side orchestration.
//!
//! The CPU path in `convshadow-cpu` is the oracle. This crate runs the same stages with the same
//! tables and hashes (all built once on the host by `convshadow-common` and uploaded, never
//! recomputed) and, on Mesa's lavapipe, produces the same bits: the same `ldi_hash` and the same
//! `image_hash`. See `docs/gpu.md` for the stage-by-stage mapping and every source of difference.
//!
//! - [`device`]: adapter choice (hardware first, software fallback), limits, the error type.
//! - [`ldi`]: the layered depth image (coverage, counts, host prefix sum, fill, per-pixel sort).
//! - [`sweep`]: the slab sweep (kernels, parity cursor, shading, compositing, attenuation).
//! - [`eye`]: the perspective camera's eye pass, dispatched before each slab of the sweep.
//! - [`shader`]: assembly of the WGSL modules from the stage files and their `#import`s.
//! - `layout`: the `#[repr(C)]` structs every buffer holds, mirrored by
//!   `shaders/shared/bindings.wgsl`, and the binding slots.

mod buffers;
pub mod device;
pub mod eye;
mod layout;
pub mod ldi;
pub mod shader;
pub mod sweep;

pub use device::{GpuContext, GpuError};
