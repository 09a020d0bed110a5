//! [`RenderError`]: every way a render or an LDI build can fail, typed. The library never exits
//! or prints; each variant maps to an exit code (`crate::exit_code`, docs/errors.md) that the
//! binary exits with and the Python module raises.

use convshadow_common::model::scene::SceneError;
use convshadow_common::prepare::error::GeometryError;
use convshadow_cpu::ldi::LdiError;
use convshadow_gpu::GpuError;

/// Why a render (or an LDI build) failed. The CLI maps each to an exit code (docs/errors.md);
/// the message is the error's `Display`.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The geometry could not be built (a bad mesh, or too many slabs).
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// The LDI exceeds its fragment budget.
    #[error(transparent)]
    Ldi(#[from] LdiError),
    /// The GPU backend failed: no adapter, a device error, or a limit.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The per-pixel buffers alone exceed the memory budget (the message has the numbers).
    #[error("{0}")]
    OutOfMemory(String),
    /// The meshes are open, non-manifold or inconsistently wound (the message names them).
    #[error("{0}")]
    MeshDefect(String),
    /// The scene's tables could not be planned.
    #[error("{0}")]
    BadPlan(String),
    /// The cancel flag was raised; nothing was written.
    #[error("interrupted; no output written")]
    Interrupted,
    /// The request does not fit the scene (an `--aov` light layer for a light it lacks).
    #[error("{0}")]
    BadRequest(String),
    /// The worker threads could not start.
    #[error("cannot start threads: {0}")]
    Threads(String),
}
