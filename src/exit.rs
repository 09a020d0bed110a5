//! Exit codes of the `convshadow` binary (documented in docs/errors.md).

/// Success.
pub const OK: i32 = 0;
/// An internal error (a bug): please report it.
pub const INTERNAL: i32 = 1;
/// Bad command-line arguments.
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
pub const OUTPUT_FAILED: i32 = 7;
/// Interrupted by SIGINT or SIGTERM (no output was written).
pub const INTERRUPTED: i32 = 130;

/// An error with the exit code it maps to.
#[derive(Debug)]
pub struct Failure {
    /// Exit code.
    pub code: i32,
    /// Message for stderr.
    pub message: String,
}

impl Failure {
    /// A failure with a code and message.
    pub fn new(code: i32, message: impl Into<String>) -> Failure {
        Failure {
            code,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<convshadow_common::scene::SceneError> for Failure {
    fn from(e: convshadow_common::scene::SceneError) -> Self {
        Failure::new(BAD_INPUT, e.to_string())
    }
}

impl From<convshadow_common::geometry::GeometryError> for Failure {
    fn from(e: convshadow_common::geometry::GeometryError) -> Self {
        use convshadow_common::geometry::GeometryError as G;
        let code = match e {
            G::TooManySlabs { .. } => RESOURCE_LIMIT,
            _ => BAD_INPUT,
        };
        Failure::new(code, e.to_string())
    }
}

impl From<convshadow_cpu::ldi::LdiError> for Failure {
    fn from(e: convshadow_cpu::ldi::LdiError) -> Self {
        Failure::new(RESOURCE_LIMIT, e.to_string())
    }
}

impl From<convshadow_common::image_io::OutputError> for Failure {
    fn from(e: convshadow_common::image_io::OutputError) -> Self {
        Failure::new(OUTPUT_FAILED, e.to_string())
    }
}
