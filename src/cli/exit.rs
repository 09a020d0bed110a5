//! Exit codes of the `convshadow` binary (documented in docs/errors.md; defined with the mapping
//! of each library error in the library's `convshadow::exit_code`, which the Python module shares)
//! and the interrupt flag.

use std::sync::atomic::{AtomicBool, Ordering};

pub use convshadow::exit_code::{
    BAD_ARGUMENTS, BAD_INPUT, INTERNAL, INTERRUPTED, MESH_DEFECT, OK, OUTPUT_FAILED,
    RESOURCE_LIMIT, UNSUPPORTED_CPU,
};

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

/// Every library error reaches the CLI through here: the exit code of each kind
/// ([`convshadow::exit_code::of_render_error`], docs/errors.md); the message is the error's own.
impl From<convshadow::pipeline::RenderError> for Failure {
    fn from(e: convshadow::pipeline::RenderError) -> Self {
        Failure::new(convshadow::exit_code::of_render_error(&e), e.to_string())
    }
}

impl From<convshadow_common::model::scene::SceneError> for Failure {
    fn from(e: convshadow_common::model::scene::SceneError) -> Self {
        Failure::new(BAD_INPUT, e.to_string())
    }
}

impl From<convshadow_common::prepare::error::GeometryError> for Failure {
    fn from(e: convshadow_common::prepare::error::GeometryError) -> Self {
        Failure::new(convshadow::exit_code::of_geometry_error(&e), e.to_string())
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
        Failure::new(convshadow::exit_code::of_gpu_error(&e), e.to_string())
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
