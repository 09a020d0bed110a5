//! Exit codes of the `convshadow` binary (documented in docs/errors.md) and the interrupt flag.

use std::sync::atomic::{AtomicBool, Ordering};

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
pub const OUTPUT_FAILED: i32 = convshadow::console::OUTPUT_FAILED;
/// This build uses instructions (x86-64-v3: AVX2, FMA, BMI) the processor lacks; checked
/// before `main` (`src/cli/cpu_check.rs`).
pub const UNSUPPORTED_CPU: i32 = 8;
/// Interrupted by SIGINT or SIGTERM (no output was written).
pub const INTERRUPTED: i32 = 130;

/// Raised by SIGINT/SIGTERM/SIGHUP once [`install_interrupt_handler`] has run.
pub static INTERRUPT: AtomicBool = AtomicBool::new(false);

/// Installs the SIGINT/SIGTERM/SIGHUP handler (once) and returns the flag it raises. The first
/// signal only raises the flag: the sweep stops before its next slab, nothing is written and the
/// process exits with [`INTERRUPTED`]. A second signal exits with [`INTERRUPTED`] at once.
pub fn install_interrupt_handler() -> &'static AtomicBool {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // If a handler cannot be installed, signals keep their default action (terminate):
        // still no partial output, as files are only ever renamed into place complete.
        let _ = ctrlc::set_handler(|| {
            if INTERRUPT.swap(true, Ordering::SeqCst) {
                std::process::exit(INTERRUPTED);
            }
        });
    });
    &INTERRUPT
}

/// Installs a SIGINT/SIGTERM/SIGHUP handler (once) for commands without a cancellable stage
/// (`ldi`, `report`, `render --backend reference`): the first signal prints the interrupted
/// message and exits with [`INTERRUPTED`] at once. Outputs are only ever renamed into place
/// complete, so nothing partial is left; `cleanup`, a folder this run created, is removed if
/// it is still empty.
pub fn install_exit_on_signal(cleanup: Option<std::path::PathBuf>) {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = ctrlc::set_handler(move || {
            if let Some(dir) = &cleanup {
                // Only an empty folder: remove_dir refuses one with files in it.
                let _ = std::fs::remove_dir(dir);
            }
            convshadow::errln!("error: interrupted; no output written");
            std::process::exit(INTERRUPTED);
        });
    });
}

/// The interrupted failure (exit code 130) if a signal has raised [`INTERRUPT`].
pub fn check_interrupt() -> Result<(), Failure> {
    check_interrupt_after(&[])
}

/// The interrupted failure (exit code 130) if a signal has raised [`INTERRUPT`], naming the
/// output files `written` (complete: each was renamed into place whole) before it was seen.
/// Outputs are written one after the other with this check before each, so a signal that
/// arrives while they are written stops the run before the next one (docs/errors.md).
pub fn check_interrupt_after(written: &[std::path::PathBuf]) -> Result<(), Failure> {
    if INTERRUPT.load(Ordering::SeqCst) {
        return Err(interrupted_after(written));
    }
    Ok(())
}

/// The interrupted failure naming the complete output files `written` before the signal: all
/// of them up to 8, else the count, the first and the last.
pub fn interrupted_after(written: &[std::path::PathBuf]) -> Failure {
    let name = |p: &std::path::PathBuf| escape_line(&p.display().to_string());
    let message = match written {
        [] => "interrupted; no output written".to_string(),
        [first, .., last] if written.len() > 8 => format!(
            "interrupted; written before the signal, complete: {} files, {} … {}",
            written.len(),
            name(first),
            name(last)
        ),
        _ => {
            let names: Vec<String> = written.iter().map(name).collect();
            format!(
                "interrupted; written before the signal, complete: {}",
                names.join(", ")
            )
        }
    };
    Failure::new(INTERRUPTED, message)
}

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

/// Every library error reaches the CLI through here: the exit code of each kind (docs/errors.md);
/// the message is the error's own.
impl From<convshadow::pipeline::RenderError> for Failure {
    fn from(e: convshadow::pipeline::RenderError) -> Self {
        use convshadow::pipeline::RenderError as R;
        let code = match &e {
            R::Scene(_) | R::BadPlan(_) => BAD_INPUT,
            R::Geometry(g) => geometry_code(g),
            R::Ldi(_) | R::OutOfMemory(_) => RESOURCE_LIMIT,
            R::Gpu(g) => gpu_code(g),
            R::MeshDefect(_) => MESH_DEFECT,
            R::Interrupted => INTERRUPTED,
            R::Threads(_) => INTERNAL,
            R::BadRequest(_) => BAD_ARGUMENTS,
        };
        Failure::new(code, e.to_string())
    }
}

/// The exit code of a geometry error: too many slabs is a limit, the rest bad input.
fn geometry_code(e: &convshadow_common::prepare::error::GeometryError) -> i32 {
    use convshadow_common::prepare::error::GeometryError as G;
    match e {
        G::TooManySlabs { .. } | G::TooManyAutoSlabs { .. } => RESOURCE_LIMIT,
        _ => BAD_INPUT,
    }
}

/// The exit code of a GPU error.
fn gpu_code(e: &convshadow_gpu::GpuError) -> i32 {
    use convshadow_gpu::GpuError as G;
    match e {
        G::TooLarge { .. } | G::Ldi(_) => RESOURCE_LIMIT,
        G::Interrupted => INTERRUPTED,
        G::NoAdapter { .. } | G::Device { .. } | G::Unsupported(_) | G::ReadBack(_) => {
            GPU_UNAVAILABLE
        }
    }
}

impl From<convshadow_common::model::scene::SceneError> for Failure {
    fn from(e: convshadow_common::model::scene::SceneError) -> Self {
        Failure::new(BAD_INPUT, e.to_string())
    }
}

impl From<convshadow_common::prepare::error::GeometryError> for Failure {
    fn from(e: convshadow_common::prepare::error::GeometryError) -> Self {
        Failure::new(geometry_code(&e), e.to_string())
    }
}

impl From<convshadow_cpu::ldi::LdiError> for Failure {
    fn from(e: convshadow_cpu::ldi::LdiError) -> Self {
        Failure::new(RESOURCE_LIMIT, e.to_string())
    }
}

impl From<convshadow_io::image::OutputError> for Failure {
    fn from(e: convshadow_io::image::OutputError) -> Self {
        Failure::new(OUTPUT_FAILED, e.to_string())
    }
}

impl From<convshadow_gpu::GpuError> for Failure {
    fn from(e: convshadow_gpu::GpuError) -> Self {
        Failure::new(gpu_code(&e), e.to_string())
    }
}

/// `text` with every control character but newline (ESC, BEL, NUL, CR, …) written as a Rust
/// escape (`\u{1b}`), so a message quoting a file or a path cannot drive the terminal.
pub fn escape_controls(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() && c != '\n' {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// [`escape_controls`], newlines included: for one-line messages.
pub fn escape_line(text: &str) -> String {
    escape_controls(text).replace('\n', "\\n")
}
