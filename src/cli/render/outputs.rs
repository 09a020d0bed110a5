//! The output files of `convshadow render`, checked before any work (a refusal costs no render):
//! the defaults, frame-number patterns, image extensions, collisions between outputs, and
//! whether each can be written.

use std::path::PathBuf;

use super::args::{RenderArgs, RenderBackend};
use crate::cli::exit::{self, Failure};
use crate::cli::frames;

/// The output files (defaults, frame patterns), checked before any work: writable, not colliding,
/// with an image extension.
pub(super) fn output_paths(
    args: &RenderArgs,
    frame_list: Option<&[u32]>,
) -> Result<Vec<PathBuf>, Failure> {
    let outputs = if args.outputs.is_empty() {
        match frame_list {
            Some(_) => vec![PathBuf::from("render_%04d.png")],
            None => vec![PathBuf::from("render.png")],
        }
    } else {
        args.outputs.clone()
    };
    if let Some(list) = frame_list
        && list.len() > 1
        && let Some(p) = outputs.iter().find(|p| !frames::has_frame_pattern(p))
    {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            format!(
                "{}: {} frames would overwrite one file; put a frame number pattern in the \
                 name, such as out_%04d.png",
                p.display(),
                list.len()
            ),
        ));
    }
    if args.backend == RenderBackend::Reference && frame_list.is_some() {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            "--frames/--frame do not apply to --backend reference",
        ));
    }
    let first_outputs: Vec<PathBuf> = match frame_list {
        Some(list) => outputs
            .iter()
            .map(|p| frames::frame_path(p, list[0]))
            .collect(),
        None => outputs.clone(),
    };
    crate::cli::refuse_collisions(first_outputs.iter().chain(&args.stats_json))?;
    for p in first_outputs.iter().chain(&args.stats_json) {
        convshadow_common::image_io::check_writable(p)?;
        let ext = p
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if args.stats_json.as_ref() != Some(p) && !matches!(ext.as_deref(), Some("png" | "exr")) {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                format!(
                    "{}: unknown image extension; expected .png or .exr",
                    p.display()
                ),
            ));
        }
    }

    Ok(outputs)
}
