//! The exit codes of the `convshadow` command line (docs/errors.md) and the one each library
//! error maps to. The binary exits with them (`src/cli/exit.rs` re-exports them); the Python
//! module (`python/`) carries them on its exceptions (`convshadow.Error.exit_code`), so a script
//! sees the code the command line would have given for the same failure.

use convshadow_common::prepare::error::GeometryError;
use convshadow_gpu::GpuError;

use crate::pipeline::RenderError;

/// Success.
pub const OK: i32 = 0;
/// An internal error (a bug): please report it.
pub const INTERNAL: i32 = 1;
/// Bad command-line arguments (in Python: a bad keyword argument's value).
pub const BAD_ARGUMENTS: i32 = 2;
/// A bad scene or mesh file (parse error, invalid value, unreadable file).
pub const BAD_INPUT: i32 = 3;
/// A resource limit: memory budget, image, slab or fragment limits.
pub const RESOURCE_LIMIT: i32 = 4;
/// The GPU backend was requested but no adapter is available.
pub const GPU_UNAVAILABLE: i32 = 5;
/// The meshes are not closed (open, non-manifold or inconsistently wound; or odd LDI pixels).
pub const MESH_DEFECT: i32 = 6;
/// The output could not be written.
pub const OUTPUT_FAILED: i32 = crate::console::OUTPUT_FAILED;
/// This build uses instructions (x86-64-v3: AVX2, FMA, BMI) the processor lacks; checked
/// before `main` (`src/cli/cpu_check.rs`).
pub const UNSUPPORTED_CPU: i32 = 8;
/// Interrupted by SIGINT or SIGTERM (no output was written).
pub const INTERRUPTED: i32 = 130;

/// The exit code of a render's (or an LDI build's) error.
pub fn of_render_error(e: &RenderError) -> i32 {
    use RenderError as R;
    match e {
        R::Scene(_) | R::BadPlan(_) => BAD_INPUT,
        R::Geometry(g) => of_geometry_error(g),
        R::Ldi(_) | R::OutOfMemory(_) => RESOURCE_LIMIT,
        R::Gpu(g) => of_gpu_error(g),
        R::MeshDefect(_) => MESH_DEFECT,
        R::Interrupted => INTERRUPTED,
        R::Threads(_) => INTERNAL,
        R::BadRequest(_) => BAD_ARGUMENTS,
    }
}

/// The exit code of a geometry error: too many slabs is a limit, the rest bad input.
pub fn of_geometry_error(e: &GeometryError) -> i32 {
    use GeometryError as G;
    match e {
        G::TooManySlabs { .. } | G::TooManyAutoSlabs { .. } => RESOURCE_LIMIT,
        _ => BAD_INPUT,
    }
}

/// The exit code of a GPU error.
pub fn of_gpu_error(e: &GpuError) -> i32 {
    use GpuError as G;
    match e {
        G::TooLarge { .. } | G::Ldi(_) => RESOURCE_LIMIT,
        G::Interrupted => INTERRUPTED,
        G::NoAdapter { .. } | G::Device { .. } | G::Unsupported(_) | G::ReadBack(_) => {
            GPU_UNAVAILABLE
        }
    }
}
