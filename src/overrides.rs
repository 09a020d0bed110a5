//! What the command line's scene flags do to a scene, for every front end: `--width` and
//! `--height` ([`override_size`]), the sweep's keys (`--slabs`, `--kernel`, `--seed`,
//! `--penumbra`, …: [`SweepOverrides`]), `--max-memory` ([`memory_budget`]), `--backend`
//! ([`RenderBackend`]) and `--reference-samples` ([`reference_samples`]), with the parsers of
//! their values. The binary (`src/cli/render/overrides.rs`) and the Python module's
//! `convshadow.render(scene, **overrides)` both go through here, so an override means the same
//! in both. Errors are typed; the binary turns them into its messages and exit codes.

use convshadow_common::model::kernel::KernelSpec;
use convshadow_common::model::scene::{
    GuardBandSpec, MAX_IMAGE_SIDE, MAX_SLABS, Media, Penumbra, Scene, SceneError, SlabSpec,
    SurfaceModel,
};
use convshadow_reference::ReferenceOptions;

use crate::pipeline::{Backend, MAX_THREADS};

/// Most light directions `--reference-samples` takes (256²: seconds per pixel at most, so even
/// a 1×1 image cannot run for minutes).
pub const MAX_REFERENCE_SAMPLES: u32 = 65536;

/// `--backend` of `convshadow render`: the pipeline's devices, or the ground-truth reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum RenderBackend {
    /// The CPU oracle.
    #[default]
    Cpu,
    /// The wgpu port (Vulkan: a hardware adapter, else Mesa lavapipe); exit code 5 without one.
    Gpu,
    /// The GPU when an adapter exists, else the CPU (and says so).
    Auto,
    /// The ground-truth reference: the sweep's view samples, with the light
    /// integrated over `--reference-samples` stratified directions of the Gaussian light and
    /// marched through the continuous scene. Slow (quadratic in depth): for small images.
    Reference,
}

impl RenderBackend {
    /// The pipeline's backend, or `None` for the reference.
    pub fn device(self) -> Option<Backend> {
        match self {
            RenderBackend::Cpu => Some(Backend::Cpu),
            RenderBackend::Gpu => Some(Backend::Gpu),
            RenderBackend::Auto => Some(Backend::Auto),
            RenderBackend::Reference => None,
        }
    }
}

impl std::str::FromStr for RenderBackend {
    type Err = String;

    /// `cpu`, `gpu`, `auto` or `reference`, as `--backend` takes them.
    fn from_str(s: &str) -> Result<Self, String> {
        <RenderBackend as clap::ValueEnum>::from_str(s, false)
            .map_err(|_| format!("expected cpu, gpu, auto or reference, got {s:?}"))
    }
}

/// Parses `--threads`: 0 (one per core) to [`MAX_THREADS`].
pub fn parse_threads(s: &str) -> Result<usize, String> {
    let max = MAX_THREADS;
    match s.parse::<usize>() {
        Ok(n) if n <= max => Ok(n),
        _ => Err(format!(
            "expected 0 (one per core) to {max} worker threads, got {s:?}"
        )),
    }
}

/// Parses `--width` / `--height`: 1 to the scene format's largest image side.
pub fn parse_side(s: &str) -> Result<u32, String> {
    let max = MAX_IMAGE_SIDE;
    match s.parse::<u32>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("expected an integer from 1 to {max}, got {s:?}")),
    }
}

/// `--surface`: `flat` or `lambert` (every material's `surface`).
pub fn parse_surface(s: &str) -> Result<SurfaceModel, String> {
    match s {
        "flat" => Ok(SurfaceModel::Flat),
        "lambert" => Ok(SurfaceModel::Lambert),
        _ => Err(format!("expected `flat` or `lambert`, got {s:?}")),
    }
}

/// `--slabs`: a slab count (its range is checked with the scene) or `auto`.
pub fn parse_slabs(s: &str) -> Result<SlabSpec, String> {
    if s == "auto" {
        return Ok(SlabSpec::Auto);
    }
    s.parse::<u32>()
        .map(SlabSpec::Count)
        .map_err(|_| format!("expected an integer from 1 to {MAX_SLABS} or `auto`, got {s:?}"))
}

/// Applies `--width`/`--height` overrides (each keeps the other side and `camera.view_width`)
/// and re-validates.
pub fn override_size(
    scene: &mut Scene,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<(), SceneError> {
    if let Some(w) = width {
        scene.image.width = w;
    }
    if let Some(h) = height {
        scene.image.height = h;
    }
    scene.revalidate()
}

/// The memory budget in bytes of `--max-memory MiB`: without it, the default (half the
/// machine's memory).
pub fn memory_budget(max_memory_mib: Option<u64>) -> u64 {
    max_memory_mib.map_or_else(convshadow_cpu::default_memory_budget, |m| {
        m.saturating_mul(1 << 20)
    })
}

/// `--reference-samples`: the light directions of the reference (0 for the other backends).
pub fn reference_samples(
    backend: RenderBackend,
    samples: Option<u32>,
) -> Result<u32, SamplesError> {
    Ok(match (backend, samples) {
        (RenderBackend::Reference, None) => ReferenceOptions::default().samples,
        (RenderBackend::Reference, Some(0)) => return Err(SamplesError::Zero),
        (RenderBackend::Reference, Some(m)) if m > MAX_REFERENCE_SAMPLES => {
            return Err(SamplesError::TooMany(m));
        }
        (RenderBackend::Reference, Some(m)) => m,
        (_, Some(_)) => return Err(SamplesError::NotReference),
        (_, None) => 0,
    })
}

/// Why a reference sample count was refused ([`reference_samples`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplesError {
    /// No light direction.
    Zero,
    /// More than [`MAX_REFERENCE_SAMPLES`].
    TooMany(u32),
    /// A sample count for another backend than the reference.
    NotReference,
}

impl SamplesError {
    /// The message, naming the sample count's option `samples` and the backend's `backend`.
    pub fn message(self, samples: &str, backend: &str) -> String {
        match self {
            SamplesError::Zero => format!("{samples}: expected at least 1 light direction, got 0"),
            SamplesError::TooMany(m) => format!(
                "{samples}: expected 1 to {MAX_REFERENCE_SAMPLES} light directions, got {m}"
            ),
            SamplesError::NotReference => {
                format!("{samples} only applies to {backend} reference")
            }
        }
    }
}

/// The sweep's scene keys a render may override (`--slabs`, `--kernel`, `--seed`, `--penumbra`,
/// `--surface`, `--guard-band`, `--variance-compensation`, `--preintegration`, `--media`, `--subpixel-shadows`); `None` leaves
/// the scene's value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SweepOverrides {
    /// `sweep.slabs`.
    pub slabs: Option<SlabSpec>,
    /// `sweep.kernel`, as written (parsed by [`SweepOverrides::apply`]).
    pub kernel: Option<String>,
    /// `sweep.seed`.
    pub seed: Option<u32>,
    /// `sweep.penumbra`.
    pub penumbra: Option<Penumbra>,
    /// Every material's `surface`.
    pub surface: Option<SurfaceModel>,
    /// `sweep.guard_band`.
    pub guard_band: Option<GuardBandSpec>,
    /// `sweep.variance_compensation`.
    pub variance_compensation: Option<bool>,
    /// `sweep.preintegration`.
    pub preintegration: Option<bool>,
    /// `sweep.media`.
    pub media: Option<Media>,
    /// `sweep.subpixel_shadows`.
    pub subpixel_shadows: Option<bool>,
    /// `sweep.held_lit_side`.
    pub held_lit_side: Option<bool>,
    /// `sweep.served_releases`.
    pub served_releases: Option<bool>,
    /// `sweep.horizon`.
    pub horizon: Option<bool>,
    /// `sweep.light_resolution`.
    pub light_resolution: Option<f64>,
}

/// Why a [`SweepOverrides`] was refused.
#[derive(Debug, thiserror::Error)]
pub enum OverrideError {
    /// The kernel does not parse.
    #[error("kernel: {0}")]
    Kernel(String),
    /// The values parse, but the scene's validation refuses the overridden scene.
    #[error(transparent)]
    Invalid(SceneError),
}

impl SweepOverrides {
    /// Sets each given key on `scene`, then re-validates it.
    pub fn apply(&self, scene: &mut Scene) -> Result<(), OverrideError> {
        if let Some(n) = self.slabs {
            scene.sweep.slabs = n;
        }
        if let Some(k) = &self.kernel {
            scene.sweep.kernel = k.parse::<KernelSpec>().map_err(OverrideError::Kernel)?;
        }
        if let Some(s) = self.seed {
            scene.sweep.seed = s;
        }
        if let Some(p) = self.penumbra {
            scene.sweep.penumbra = p;
        }
        if let Some(s) = self.surface {
            for m in &mut scene.materials {
                m.surface = s;
            }
        }
        if let Some(g) = self.guard_band {
            scene.sweep.guard_band = g;
        }
        if let Some(v) = self.variance_compensation {
            scene.sweep.variance_compensation = v;
        }
        if let Some(v) = self.preintegration {
            scene.sweep.preintegration = v;
        }
        if let Some(m) = self.media {
            scene.sweep.media = m;
        }
        if let Some(v) = self.subpixel_shadows {
            scene.sweep.subpixel_shadows = v;
        }
        if let Some(v) = self.held_lit_side {
            scene.sweep.held_lit_side = v;
        }
        if let Some(v) = self.served_releases {
            scene.sweep.served_releases = v;
        }
        if let Some(v) = self.horizon {
            scene.sweep.horizon = v;
        }
        if let Some(v) = self.light_resolution {
            scene.sweep.light_resolution = v;
        }
        scene.revalidate().map_err(OverrideError::Invalid)
    }
}
