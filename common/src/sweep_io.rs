//! What a sweep takes and gives on every backend: the shared options (progress, cancel, initial
//! light), the output buffers, the error, and the per-pixel light limit.
//!
//! Backend-specific knobs (the CPU's code path and quiet-pixel skipping) live with their backend.

use std::sync::atomic::AtomicBool;

/// Largest light count × channels handled per pixel (the CPU's stack arrays, the WGSL private
/// array; uploaded into the shader source, never copied).
pub const MAX_LIGHT_CHANNELS: usize = 48;

/// Why a sweep stopped early.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SweepError {
    /// The cancel flag was raised (Ctrl-C / SIGTERM).
    #[error("interrupted")]
    Interrupted,
}

/// The result of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOutput {
    /// Linear RGB, `width·height·3`, the guard band cropped away.
    pub image: Vec<f32>,
    /// The light buffers after the last slab (grid-sized, row-major `[row][light][channel][x]`).
    pub light: Vec<f32>,
}

/// Options of a sweep run that every backend honours.
pub struct SweepOptions<'a> {
    /// Called after every slab with the slab index.
    pub progress: &'a (dyn Fn(u32) + Sync),
    /// Checked between slabs; when raised the sweep stops with [`SweepError::Interrupted`].
    pub cancel: Option<&'a AtomicBool>,
    /// Initial light value per light and channel (`None` = 1, the unoccluded light).
    pub initial_light: Option<&'a [f32]>,
}

impl Default for SweepOptions<'_> {
    fn default() -> Self {
        SweepOptions {
            progress: &|_| {},
            cancel: None,
            initial_light: None,
        }
    }
}
