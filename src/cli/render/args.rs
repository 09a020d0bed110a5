//! The arguments of `convshadow render` ([`RenderArgs`], [`RenderBackend`]) and their value
//! parsers. What they do to the scene is `overrides.rs`; to the output files, `outputs.rs`.

use std::path::PathBuf;

use convshadow::pipeline::{Aov, CpuPath};
use convshadow_common::model::kernel::KERNEL_SYNTAX;
use convshadow_common::model::scene::GuardBandSpec;
use convshadow_common::model::scene::{Media, Penumbra, SlabSpec, SurfaceModel};

pub use convshadow::overrides::RenderBackend;

/// Arguments of `convshadow render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML); without it, the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Output image(s): `.png` (sRGB 8-bit) or `.exr` (linear float); may repeat.
    /// Default: render.png in the current folder.
    #[arg(short = 'o', long = "output")]
    pub outputs: Vec<PathBuf>,
    /// Extra EXR layers, comma-separated (may repeat): `depth` (the first-hit camera depth,
    /// channel `Z`, +inf where nothing is hit) and `lightN` (light N's contribution to the RGB,
    /// channels `lightN.R`, `lightN.G`, `lightN.B`; one more sweep each). EXR outputs only.
    #[arg(long, value_name = "LAYERS", value_delimiter = ',', value_parser = parse_aov)]
    pub aov: Vec<Aov>,
    /// Override the image width (the height stays, and so does camera.view_width: a wider image
    /// shows the same width of the scene, a taller one more of it; use --size to keep the view).
    #[arg(long, value_parser = crate::cli::parse_side)]
    pub width: Option<u32>,
    /// Override the image height (the width and camera.view_width stay).
    #[arg(long, value_parser = crate::cli::parse_side)]
    pub height: Option<u32>,
    /// Image size WxH; when the aspect changes, camera.view_width grows so the scene's whole
    /// view stays in frame (and says so).
    #[arg(long, value_name = "WxH", conflicts_with_all = ["width", "height"])]
    pub size: Option<String>,
    /// Override camera.view_width (world units across the image).
    #[arg(long, value_name = "W", allow_hyphen_values = true)]
    pub view_width: Option<f64>,
    /// Override camera.direction (X,Y,Z; normalised).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub camera_direction: Option<String>,
    /// Override camera.center (X,Y,Z).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub camera_center: Option<String>,
    /// Perspective camera: override camera.eye (X,Y,Z).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub eye: Option<String>,
    /// Perspective camera: override camera.look_at (X,Y,Z).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub look_at: Option<String>,
    /// Perspective camera: override camera.fov_deg (the vertical field of view, 1–170 degrees).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub fov: Option<f64>,
    /// PNG output: exposure in stops (overrides image.exposure; EXR stays linear).
    #[arg(long, value_name = "STOPS", allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// PNG output: tone curve clamp, reinhard or aces (overrides image.tonemap; default aces).
    #[arg(long, value_name = "CURVE")]
    pub tonemap: Option<String>,
    /// Render frames A..B (B excluded; A..=B includes it) of the 4D detail: frame k sets every
    /// detail material's time to its detail.time (or 0) + k·--time-step. Outputs need a frame
    /// pattern such as out_%04d.png. At most 1000000 frames a run.
    #[arg(long, value_name = "A..B", conflicts_with = "frame")]
    pub frames: Option<String>,
    /// Render frame K alone: the same bits as frame K of --frames.
    #[arg(long, value_name = "K")]
    pub frame: Option<u32>,
    /// Detail time advanced per frame (default 0.05).
    #[arg(long, value_name = "DT", allow_hyphen_values = true)]
    pub time_step: Option<f64>,
    /// Override the slab count: N, or `auto` (2 slabs per finest period of the detail along the
    /// view, times sweep.slab_factor; the count chosen is printed and in --stats-json).
    #[arg(long, value_name = "N|auto", value_parser = crate::cli::parse_slabs)]
    pub slabs: Option<SlabSpec>,
    /// Override the kernel (the help lists the kernels of `common::kernel::KERNEL_SYNTAX`).
    #[arg(long, help = format!("Override the kernel ({KERNEL_SYNTAX})"))]
    pub kernel: Option<String>,
    /// Override the seed.
    #[arg(long)]
    pub seed: Option<u32>,
    /// Override the penumbra model (`sweep.penumbra`): `iterated` (the paper's: right at
    /// sweep.optimal_distance only) or `distance` (follows each pixel's occluder distance).
    #[arg(long, value_name = "iterated|distance", value_parser = crate::cli::parse_penumbra)]
    pub penumbra: Option<Penumbra>,
    /// Override every material's surface model (`material.NAME.surface`): `lambert` (the
    /// cosine at crossed opaque surfaces, the default) or `flat` (colour × light).
    #[arg(long, value_name = "flat|lambert", value_parser = crate::cli::parse_surface)]
    pub surface: Option<SurfaceModel>,
    /// Override the guard band: `auto` (sized from the scene's lights, depth and meshes) or
    /// pixels beyond every image edge (0: none), as `sweep.guard_band`.
    #[arg(long, value_name = "auto|N", value_parser = parse_guard_band)]
    pub guard_band: Option<GuardBandSpec>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0, value_parser = crate::cli::parse_threads)]
    pub threads: usize,
    /// CPU code path: `simd` (8 pixels at a time) or `scalar` (the readable reference); both
    /// give the same bits.
    #[arg(long, value_enum, default_value_t = CpuPath::Simd)]
    pub path: CpuPath,
    /// SIMD path: compute every chunk, even those whose result is known exactly (unoccluded and
    /// empty, or opaque in the dark). Same image; only for measuring what skipping saves.
    #[arg(long)]
    pub no_skip_quiet: bool,
    /// Backend: the CPU oracle, the GPU (wgpu/Vulkan; exit code 5 without an adapter), auto
    /// (the GPU when an adapter exists, else the CPU with a message), or the slow ground-truth
    /// reference (Monte Carlo over light directions, for small images).
    #[arg(long, value_enum, default_value_t = RenderBackend::Cpu)]
    pub backend: RenderBackend,
    /// Light directions per shading point and light for `--backend reference` (rounded up to a
    /// square k²; default 64). Its error falls about as 1/√M.
    #[arg(long)]
    pub reference_samples: Option<u32>,
    /// Turn the bilinear-variance compensation on or off (overrides the scene).
    #[arg(long)]
    pub variance_compensation: Option<bool>,
    /// Pre-integrated compositing (overrides sweep.preintegration): `--preintegration` or
    /// `--preintegration true` turns it on, `--preintegration false` off.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true")]
    pub preintegration: Option<bool>,
    /// Override how slabs of translucent medium are composited (`sweep.media`):
    /// `second-order` (the default: exact slab transmittance, entry and exit slabs by the part
    /// inside, light at the shading point) or `first-order` (the paper's whole slabs).
    #[arg(long, value_name = "second-order|first-order", value_parser = crate::cli::parse_media)]
    pub media: Option<Media>,
    /// Override `sweep.subpixel_shadows` (all-opaque scenes, either penumbra): `true` (the
    /// default) reads the light at crossed opaque surfaces at its exact sub-pixel shift, `false`
    /// at the whole pixels the sweep carries it in.
    #[arg(long, value_name = "BOOL")]
    pub subpixel_shadows: Option<bool>,
    /// Override `sweep.held_lit_side`: `true` reads a held surface's light only from its lit
    /// side (thin plates and surfaces turned towards the light cast their whole shadow; slower
    /// near held surfaces), `false` (the default) from everywhere.
    #[arg(long, value_name = "BOOL")]
    pub held_lit_side: Option<bool>,
    /// Override `sweep.served_releases`: `true` (the default) lets a released surface serve the
    /// light it gathered at its release to gathers on the same surface (no self-shadowing on
    /// steep receivers in another occluder's penumbra), `false` does not (the images of before
    /// 2026-12-08).
    #[arg(long, value_name = "BOOL")]
    pub served_releases: Option<bool>,
    /// Override `sweep.horizon`: `true` (the default) limits the light at a crossed opaque
    /// surface to the part above its tangent plane, `false` does not (the images of before
    /// 2026-12-07).
    #[arg(long, value_name = "BOOL")]
    pub horizon: Option<bool>,
    /// Override `sweep.light_resolution`: the light grid's cells per image pixel (perspective:
    /// at `look_at`), 1/16 to 16 (default 1); below 1 faster, above 1 sharper edges; not 1, an
    /// orthographic camera's light gets a grid of its own.
    #[arg(long, value_name = "CELLS")]
    pub light_resolution: Option<f64>,
    /// Render even if a closed mesh leaves pixels with odd fragment counts (reported). Open
    /// meshes need no flag: they render as thin shells, with a warning.
    #[arg(long)]
    pub allow_open: bool,
    /// Memory budget in MiB for the LDI and the sweep's buffers (default: half the machine's
    /// memory); a scene that needs more is refused before allocating (exit code 4).
    #[arg(long)]
    pub max_memory: Option<u64>,
    /// Write the numbers as JSON (with --frames/--frame: one entry per frame under "frames").
    #[arg(long)]
    pub stats_json: Option<PathBuf>,
    /// No progress bar and no summary line.
    #[arg(long, short)]
    pub quiet: bool,
}

/// One `--aov` layer name (clap reports a bad value with the option's name, exit code 2).
fn parse_aov(s: &str) -> Result<Aov, String> {
    s.parse()
}

/// `--guard-band auto|N` (clap reports a bad value with the option's name, exit code 2).
fn parse_guard_band(s: &str) -> Result<GuardBandSpec, String> {
    s.parse()
}

/// `convshadow render ARGS` as the command line parses it (for the tests of this folder).
#[cfg(test)]
pub(super) fn parse(argv: &[&str]) -> Result<RenderArgs, clap::Error> {
    use clap::Parser;
    #[derive(clap::Parser)]
    struct Render {
        #[command(flatten)]
        args: RenderArgs,
    }
    Render::try_parse_from(std::iter::once("render").chain(argv.iter().copied())).map(|r| r.args)
}

#[cfg(test)]
mod tests {
    use convshadow::pipeline::Backend;

    use super::*;

    fn ok(argv: &[&str]) -> RenderArgs {
        parse(argv).unwrap_or_else(|e| panic!("{argv:?}: {e}"))
    }

    #[test]
    fn without_flags_nothing_is_overridden_and_the_defaults_are_the_documented_ones() {
        let a = ok(&[]);
        assert_eq!(a.scene, None);
        assert!(a.outputs.is_empty());
        assert_eq!((a.width, a.height, a.size.as_deref()), (None, None, None));
        assert_eq!(
            (a.slabs, a.seed, a.penumbra, a.guard_band),
            (None, None, None, None)
        );
        assert_eq!((a.preintegration, a.variance_compensation), (None, None));
        assert_eq!(a.media, None);
        assert_eq!(a.subpixel_shadows, None);
        // --threads 0 (one per core), the SIMD path, the CPU, quiet-chunk skipping on.
        assert_eq!(a.threads, 0);
        assert_eq!(a.path, CpuPath::Simd);
        assert_eq!(a.backend, RenderBackend::Cpu);
        assert!(!a.no_skip_quiet && !a.quiet && !a.allow_open);
        assert!(a.aov.is_empty());
    }

    #[test]
    fn each_flag_lands_in_its_own_field() {
        let a = ok(&[
            "scene.toml",
            "-o",
            "a.png",
            "--output",
            "b.exr",
            "--slabs",
            "auto",
            "--seed",
            "7",
            "--penumbra",
            "distance",
            "--guard-band",
            "0",
            "--variance-compensation",
            "false",
            "--preintegration",
            "--media",
            "first-order",
            "--subpixel-shadows",
            "false",
            "--threads",
            "3",
            "--path",
            "scalar",
            "--backend",
            "reference",
            "--reference-samples",
            "9",
            "--camera-direction",
            "-1,0,0",
            "--view-width",
            "-2",
            "--aov",
            "depth,light1",
            "--aov",
            "light0",
        ]);
        assert_eq!(a.scene, Some(PathBuf::from("scene.toml")));
        assert_eq!(a.outputs, [PathBuf::from("a.png"), PathBuf::from("b.exr")]);
        assert_eq!(a.slabs, Some(SlabSpec::Auto));
        assert_eq!(a.seed, Some(7));
        assert_eq!(a.penumbra, Some(Penumbra::Distance));
        assert_eq!(a.guard_band, Some(GuardBandSpec::Pixels(0)));
        assert_eq!(a.variance_compensation, Some(false));
        // A bare --preintegration turns it on.
        assert_eq!(a.preintegration, Some(true));
        assert_eq!(a.media, Some(Media::FirstOrder));
        assert_eq!(a.subpixel_shadows, Some(false));
        assert_eq!(a.threads, 3);
        assert_eq!(a.path, CpuPath::Scalar);
        assert_eq!(a.backend.device(), None);
        assert_eq!(a.reference_samples, Some(9));
        // Values that start with a minus sign are values, not flags.
        assert_eq!(a.camera_direction.as_deref(), Some("-1,0,0"));
        assert_eq!(a.view_width, Some(-2.0));
        // Comma-separated and repeated layers, in order.
        assert_eq!(a.aov, [Aov::Depth, Aov::Light(1), Aov::Light(0)]);
        assert_eq!(
            ok(&["--preintegration", "false"]).preintegration,
            Some(false)
        );
        assert_eq!(ok(&["--slabs", "96"]).slabs, Some(SlabSpec::Count(96)));
        assert_eq!(
            ok(&["--guard-band", "auto"]).guard_band,
            Some(GuardBandSpec::Auto)
        );
        // Each backend names the pipeline's device of the same name.
        for (name, device) in [
            ("cpu", Backend::Cpu),
            ("gpu", Backend::Gpu),
            ("auto", Backend::Auto),
        ] {
            assert_eq!(ok(&["--backend", name]).backend.device(), Some(device));
        }
    }

    #[test]
    fn conflicting_or_out_of_range_flags_are_refused_by_the_parser() {
        for argv in [
            &["--size", "8x8", "--width", "8"][..],
            &["--size", "8x8", "--height", "8"],
            &["--frames", "0..2", "--frame", "1"],
            &["--threads", "1025"],
            &["--width", "0"],
            &["--slabs", "many"],
            &["--penumbra", "soft"],
            &["--media", "third-order"],
            &["--guard-band", "-1"],
            &["--path", "gpu"],
            &["--aov", "normal"],
            &["--aov", "depth,"],
            &["--aov", "light"],
        ] {
            let e = parse(argv)
                .err()
                .unwrap_or_else(|| panic!("{argv:?} accepted"));
            // clap's usage errors go to stderr (the binary exits 2 for them).
            assert!(e.use_stderr(), "{argv:?}: {e}");
        }
    }
}
