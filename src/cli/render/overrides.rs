//! What the arguments of `convshadow render` do to the scene: the view (`--size`, the camera,
//! `--exposure`, `--tonemap`), the sweep's keys (`--slabs`, `--kernel`, …), the frames of a
//! sequence and the reference's sample count. A bad value is refused with exit code 2, naming
//! its flag; an override the scene's validation refuses too. What the sweep's flags and the
//! sample count do is the library's (`convshadow::overrides`, shared with the Python module).

use convshadow::overrides::{OverrideError, SweepOverrides};
use convshadow_common::model::display::Tonemap;
use convshadow_common::model::scene::Scene;

use super::args::RenderArgs;
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
            convshadow::errln!("note: {}", crate::cli::exit::escape_line(&note));
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
    let vec3 = |flag: &str, text: &Option<String>| {
        text.as_deref()
            .map(frames::parse_vec3)
            .transpose()
            .map_err(|e| bad(flag, e))
    };
    let (eye, look_at) = (vec3("--eye", &args.eye)?, vec3("--look-at", &args.look_at)?);
    scene
        .override_perspective(eye, look_at, args.fov)
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

/// `--slabs`, `--kernel`, `--seed`, `--penumbra`, `--surface`, `--guard-band`,
/// `--variance-compensation`, `--preintegration`, `--media` and `--subpixel-shadows`, then the scene re-validated
/// ([`SweepOverrides::apply`], shared with the Python module).
pub(super) fn apply_sweep_overrides(scene: &mut Scene, args: &RenderArgs) -> Result<(), Failure> {
    let overrides = SweepOverrides {
        slabs: args.slabs,
        kernel: args.kernel.clone(),
        seed: args.seed,
        penumbra: args.penumbra,
        surface: args.surface,
        guard_band: args.guard_band,
        variance_compensation: args.variance_compensation,
        preintegration: args.preintegration,
        media: args.media,
        subpixel_shadows: args.subpixel_shadows,
        held_lit_side: args.held_lit_side,
        served_releases: args.served_releases,
        horizon: args.horizon,
        light_resolution: args.light_resolution,
    };
    overrides.apply(scene).map_err(|e| match e {
        OverrideError::Kernel(e) => Failure::new(exit::BAD_ARGUMENTS, format!("--kernel: {e}")),
        OverrideError::Invalid(e) => {
            Failure::new(exit::BAD_ARGUMENTS, format!("command-line override: {e}"))
        }
    })
}

/// `--reference-samples`: the light directions of the reference (0 for the other backends).
pub(super) fn reference_samples(args: &RenderArgs) -> Result<u32, Failure> {
    convshadow::overrides::reference_samples(args.backend, args.reference_samples).map_err(|e| {
        Failure::new(
            exit::BAD_ARGUMENTS,
            e.message("--reference-samples", "--backend"),
        )
    })
}

#[cfg(test)]
mod tests {
    use convshadow_common::model::scene::GuardBandSpec;
    use convshadow_common::model::scene::{Penumbra, SlabSpec};

    use super::super::args::parse;
    use super::*;

    fn args(argv: &[&str]) -> RenderArgs {
        parse(argv).unwrap_or_else(|e| panic!("{argv:?}: {e}"))
    }

    /// The default scene at 200×100 pixels, 4 world units wide (so 2 high), quiet.
    fn wide_scene() -> Scene {
        let mut s = Scene::default_scene();
        s.image.width = 200;
        s.image.height = 100;
        s.camera.view_width = 4.0;
        s.revalidate().unwrap();
        s
    }

    /// The scene after the view and sweep overrides of `argv` (as `run` applies them).
    fn overridden(argv: &[&str]) -> Result<Scene, Failure> {
        let a = args(argv);
        let mut s = wide_scene();
        apply_view_overrides(&mut s, &a)?;
        apply_sweep_overrides(&mut s, &a)?;
        Ok(s)
    }

    fn refused(argv: &[&str]) -> Failure {
        overridden(argv)
            .err()
            .unwrap_or_else(|| panic!("{argv:?} accepted"))
    }

    #[test]
    fn no_flags_leave_the_scene_as_it_is() {
        assert_eq!(overridden(&["-q"]).unwrap(), wide_scene());
    }

    #[test]
    fn sweep_flags_set_their_scene_keys_and_nothing_else() {
        let s = overridden(&[
            "--slabs",
            "33",
            "--kernel",
            "ellipse5",
            "--seed",
            "7",
            "--penumbra",
            "distance",
            "--guard-band",
            "3",
            "--variance-compensation",
            "false",
            "--preintegration",
        ])
        .unwrap();
        assert_eq!(s.sweep.slabs, SlabSpec::Count(33));
        assert_eq!(s.sweep.kernel.to_string(), "ellipse5");
        assert_eq!(s.sweep.seed, 7);
        assert_eq!(s.sweep.penumbra, Penumbra::Distance);
        assert_eq!(s.sweep.guard_band, GuardBandSpec::Pixels(3));
        assert!(!s.sweep.variance_compensation);
        assert!(s.sweep.preintegration);
        // Everything else is the scene's: put the overridden keys back and compare.
        let mut back = s.clone();
        back.sweep = wide_scene().sweep;
        assert_eq!(back, wide_scene());
        let off = overridden(&["--preintegration", "false"]).unwrap();
        assert!(!off.sweep.preintegration);
    }

    #[test]
    fn view_flags_set_the_camera_and_the_display_map() {
        let s = overridden(&[
            "--camera-direction",
            "0,0,-2",
            "--camera-center",
            "1,2,3",
            "--exposure",
            "-2.5",
            "--tonemap",
            "reinhard",
        ])
        .unwrap();
        // The direction is normalised.
        assert_eq!(s.camera.direction, [0.0, 0.0, -1.0]);
        assert_eq!(s.camera.center, [1.0, 2.0, 3.0]);
        assert_eq!(s.image.exposure, -2.5);
        assert_eq!(s.image.tonemap, Tonemap::Reinhard);
        assert_eq!(s.camera.view_width, 4.0);
    }

    #[test]
    fn bad_values_are_refused_with_code_2_naming_their_flag() {
        for (argv, flag) in [
            (&["--kernel", "nope"][..], "--kernel"),
            (&["--tonemap", "sepia"], "--tonemap"),
            (&["--camera-direction", "1,2"], "--camera-direction"),
            (&["--camera-center", "x,0,0"], "--camera-center"),
            (&["--size", "800"], "--size"),
            (&["--size", "0x10"], "--size"),
            // Parallel to the default scene's camera.up (0, 1, 0).
            (&["--camera-direction", "0,3,0"], "--camera-direction"),
            (&["--view-width", "-1"], "--view-width"),
        ] {
            let f = refused(argv);
            assert_eq!(f.code, exit::BAD_ARGUMENTS, "{argv:?}: {}", f.message);
            assert!(f.message.contains(flag), "{argv:?}: {}", f.message);
        }
        // A value the flag's parser accepts but the scene's validation does not (0 slabs).
        let f = refused(&["--slabs", "0"]);
        assert_eq!(f.code, exit::BAD_ARGUMENTS);
        assert!(
            f.message.starts_with("command-line override:") && f.message.contains("sweep.slabs"),
            "{}",
            f.message
        );
    }

    #[test]
    fn size_widens_the_view_to_keep_the_whole_scene_in_frame_and_width_does_not() {
        // The scene shows 4 × 2 world units. At W×H pixels, square pixels show view_width ×
        // view_width·H/W, which must hold 4 × 2: view_width = max(4, 2·W/H).
        for (size, view_width) in [
            ("400x100", 8.0), // 2·4 = 8
            ("300x50", 12.0), // 2·6 = 12
            ("300x150", 4.0), // the same aspect
            ("100x100", 4.0), // taller: the width already holds it
            ("100x400", 4.0),
        ] {
            let s = overridden(&["--size", size]).unwrap();
            let (w, h) = size.split_once('x').unwrap();
            assert_eq!(s.image.width.to_string(), w);
            assert_eq!(s.image.height.to_string(), h);
            assert_eq!(s.camera.view_width, view_width, "--size {size}");
        }
        // --view-width applies after --size, so it wins.
        let s = overridden(&["--size", "400x100", "--view-width", "5"]).unwrap();
        assert_eq!(s.camera.view_width, 5.0);
        // --width alone keeps view_width: the same width of the scene, more or less of it high.
        let mut s = wide_scene();
        crate::cli::override_size(&mut s, Some(400), None).unwrap();
        assert_eq!((s.image.width, s.image.height), (400, 100));
        assert_eq!(s.camera.view_width, 4.0);
    }

    #[test]
    fn frames_list_their_numbers_and_time_steps_need_frames() {
        let list = |argv: &[&str]| frame_list(&args(argv));
        assert_eq!(list(&[]).unwrap(), (None, 0.05));
        assert_eq!(
            list(&["--frames", "2..5"]).unwrap(),
            (Some(vec![2, 3, 4]), 0.05)
        );
        assert_eq!(
            list(&["--frames", "2..=5"]).unwrap().0,
            Some(vec![2, 3, 4, 5])
        );
        assert_eq!(
            list(&["--frame", "3", "--time-step", "-0.5"]).unwrap(),
            (Some(vec![3]), -0.5)
        );
        for argv in [
            &["--time-step", "0.1"][..],
            &["--frames", "0..2", "--time-step", "inf"],
            &["--frames", "0..2", "--time-step", "NaN"],
            &["--frames", "5..5"],
            &["--frames", "5..2"],
        ] {
            let f = list(argv)
                .err()
                .unwrap_or_else(|| panic!("{argv:?} accepted"));
            assert_eq!(f.code, exit::BAD_ARGUMENTS, "{argv:?}");
            assert!(f.message.starts_with(argv[argv.len() - 2]), "{}", f.message);
        }
    }

    #[test]
    fn reference_samples_apply_to_the_reference_alone_from_1_to_65536() {
        let samples = |argv: &[&str]| reference_samples(&args(argv));
        assert_eq!(samples(&[]).unwrap(), 0);
        // The documented default: 64 light directions.
        assert_eq!(samples(&["--backend", "reference"]).unwrap(), 64);
        for m in ["1", "65536"] {
            let got = samples(&["--backend", "reference", "--reference-samples", m]).unwrap();
            assert_eq!(got.to_string(), m);
        }
        for argv in [
            &["--backend", "reference", "--reference-samples", "0"][..],
            &["--backend", "reference", "--reference-samples", "65537"],
            &["--reference-samples", "16"],
            &["--backend", "gpu", "--reference-samples", "16"],
        ] {
            let f = samples(argv)
                .err()
                .unwrap_or_else(|| panic!("{argv:?} accepted"));
            assert_eq!(f.code, exit::BAD_ARGUMENTS);
            assert!(f.message.contains("--reference-samples"), "{}", f.message);
        }
    }
}
