//! `convshadow render --backend reference`: the library's ground-truth shadow-ray renderer
//! ([`convshadow::pipeline::render_reference`]).

use convshadow::pipeline::{Aov, Rendered};
use convshadow_common::model::scene::Scene;

use crate::cli::exit::{self, Failure};

/// Renders with the ground-truth reference (`--backend reference`). No interrupt handler is
/// installed for it: a signal ends the process at once, before any output is written (outputs
/// are only ever renamed into place complete).
pub(super) fn render_reference(
    scene: &Scene,
    threads: usize,
    samples: u32,
    budget: u64,
    allow_open: bool,
    aovs: &[Aov],
) -> Result<Rendered, Failure> {
    let cancel = Some(&exit::INTERRUPT);
    Ok(convshadow::pipeline::render_reference(
        scene, threads, samples, budget, allow_open, aovs, cancel,
    )?)
}
