//! What the arguments of `convshadow render` do to the scene: the view (`--size`, the camera,
//! `--exposure`, `--tonemap`), the sweep's keys (`--slabs`, `--kernel`, …), the frames of a
//! sequence and the reference's sample count. A bad value is refused with exit code 2, naming
//! its flag; an override the scene's validation refuses too.

use convshadow_common::kernel::KernelSpec;
use convshadow_common::scene::Scene;
use convshadow_common::tonemap::Tonemap;
use convshadow_cpu::reference::ReferenceOptions;

use super::args::{MAX_REFERENCE_SAMPLES, RenderArgs, RenderBackend};
use crate::cli::exit::{self, Failure};
use crate::cli::frames;

/// The error of a bad value for `flag`.
fn bad_flag(flag: &str, e: String) -> Failure {
    Failure::new(exit::BAD_ARGUMENTS, format!("{flag}: {e}"))
}

/// `--size`, the camera overrides, `--exposure` and `--tonemap`.
pub(super) fn apply_view_overrides(scene: &mut Scene, args: &RenderArgs) -> Result<(), Failure> {
    let bad = bad_flag;
    if let Some(text) = &args.size {
        let (w, h) = frames::parse_size(text).map_err(|e| bad("--size", e))?;
        if let Some(note) = frames::apply_size(scene, w, h)?
            && !args.quiet
        {
            eprintln!("note: {}", crate::cli::exit::escape_line(&note));
        }
    }
    let direction = args
        .camera_direction
        .as_deref()
        .map(frames::parse_vec3)
        .transpose()
        .map_err(|e| bad("--camera-direction", e))?;
    let center = args
        .camera_center
        .as_deref()
        .map(frames::parse_vec3)
        .transpose()
        .map_err(|e| bad("--camera-center", e))?;
    scene
        .override_camera(direction, center, args.view_width)
        .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, e.to_string()))?;
    if let Some(x) = args.exposure {
        scene.image.exposure = x;
    }
    if let Some(t) = &args.tonemap {
        scene.image.tonemap = t.parse::<Tonemap>().map_err(|e| bad("--tonemap", e))?;
    }
    Ok(())
}

/// The frames to render (`--frames`/`--frame`, `None` for a single image) and the time step.
pub(super) fn frame_list(args: &RenderArgs) -> Result<(Option<Vec<u32>>, f64), Failure> {
    let bad = bad_flag;
    let frame_list: Option<Vec<u32>> = match (&args.frames, args.frame) {
        (Some(text), _) => {
            let r = frames::FrameRange::parse(text).map_err(|e| bad("--frames", e))?;
            Some((r.start..r.end).collect())
        }
        (None, Some(k)) => Some(vec![k]),
        (None, None) => None,
    };
    let time_step = args.time_step.unwrap_or(frames::DEFAULT_TIME_STEP);
    if !time_step.is_finite() {
        return Err(bad(
            "--time-step",
            format!("expected a finite number, got {time_step}"),
        ));
    }
    if args.time_step.is_some() && frame_list.is_none() {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            "--time-step only applies with --frames or --frame",
        ));
    }
    Ok((frame_list, time_step))
}

/// `--slabs`, `--kernel`, `--seed`, `--penumbra`, `--guard-band`, `--variance-compensation` and
/// `--preintegration`, then the scene re-validated.
pub(super) fn apply_sweep_overrides(scene: &mut Scene, args: &RenderArgs) -> Result<(), Failure> {
    if let Some(n) = args.slabs {
        scene.sweep.slabs = n;
    }
    if let Some(k) = &args.kernel {
        scene.sweep.kernel = k
            .parse::<KernelSpec>()
            .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, format!("--kernel: {e}")))?;
    }
    if let Some(s) = args.seed {
        scene.sweep.seed = s;
    }
    if let Some(p) = args.penumbra {
        scene.sweep.penumbra = p;
    }
    if let Some(g) = args.guard_band {
        scene.sweep.guard_band = g;
    }
    if let Some(v) = args.variance_compensation {
        scene.sweep.variance_compensation = v;
    }
    if let Some(v) = args.preintegration {
        scene.sweep.preintegration = v;
    }
    scene
        .revalidate()
        .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, format!("command-line override: {e}")))?;
    Ok(())
}

/// `--reference-samples`: the light directions of the reference (0 for the other backends).
pub(super) fn reference_samples(args: &RenderArgs) -> Result<u32, Failure> {
    Ok(match (args.backend, args.reference_samples) {
        (RenderBackend::Reference, None) => ReferenceOptions::default().samples,
        (RenderBackend::Reference, Some(0)) => {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                "--reference-samples: expected at least 1 light direction, got 0",
            ));
        }
        (RenderBackend::Reference, Some(m)) if m > MAX_REFERENCE_SAMPLES => {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                format!(
                    "--reference-samples: expected 1 to {MAX_REFERENCE_SAMPLES} light directions, got {m}"
                ),
            ));
        }
        (RenderBackend::Reference, Some(m)) => m,
        (_, Some(_)) => {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                "--reference-samples only applies to --backend reference",
            ));
        }
        (_, None) => 0,
    })
}
