//! The backend-neutral core of convshadow, in the order a frame's data flows through it. Both
//! the CPU oracle and the GPU port depend on this crate; it opens no file (the `convshadow-io`
//! crate reads what a scene names and hands it over as [`contract::files`]).
//!
//! - [`model`]: the scene as the user wrote it — types, limits, parsing and validation, the spec
//!   enums (kernels, display mapping). Host code, f64.
//! - [`prepare`]: from the model to geometry — camera, meshes, slab count, guard band,
//!   rasterizer set-up. Host code, f64.
//! - [`plan`]: every table the sweep reads (kernel taps, transfer functions, hashes), built once
//!   per render on the host.
//! - [`pixel`]: what runs per pixel under the bit-exactness rules — the lane type, integer
//!   hashes, noise and 3D-texture evaluation, the distance penumbra's level.
//! - [`contract`]: the data the backends exchange — the LDI, the sweep's options and output,
//!   the files read for a scene.

pub mod contract;
pub mod model;
pub mod pixel;
pub mod plan;
pub mod prepare;
