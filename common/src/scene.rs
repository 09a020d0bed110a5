//! Scene files (TOML) parsed into a typed, validated model.
//!
//! The schema is documented in `docs/scene-format.md`. Parsing is strict: unknown keys, wrong
//! types, missing required keys and invalid values are errors naming the file, the key and what
//! was expected.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::guard::GuardBandSpec;
use crate::kernel::KernelSpec;
use crate::noise::DetailKind;
use crate::texture3d::VoxelType;
use crate::tonemap::{DisplayMap, Tonemap};

/// Largest accepted image width or height in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Largest accepted |exposure| in stops (2^64 is far past any useful brightening).
pub const MAX_EXPOSURE_STOPS: f64 = 64.0;
/// Largest accepted slab count.
pub const MAX_SLABS: u32 = 65536;
/// Smallest and largest accepted `sweep.slab_factor` (the modulation of `slabs = "auto"`).
pub const SLAB_FACTOR_RANGE: (f64, f64) = (1.0 / 1024.0, 1024.0);
/// Largest accepted |g| of a Henyey–Greenstein phase function (the function needs |g| < 1; this
/// bound keeps its largest value, (1 + 0.999)/(1 − 0.999)² ≈ 2·10⁶, finite with every colour in f32).
pub const MAX_PHASE_G: f64 = 0.999;
/// Largest accepted number of lights.
pub const MAX_LIGHTS: usize = 16;
/// Largest accepted number of meshes (the parity cursor keeps one inside bit per mesh in a u32).
pub const MAX_MESHES: usize = 32;
/// Largest icosphere subdivision level and torus segment count accepted.
pub const MAX_SPHERE_SUBDIVISIONS: u32 = 7;
/// Largest torus segment count accepted.
pub const MAX_TORUS_SEGMENTS: u32 = 1024;
/// Largest guard band in pixels.
pub const MAX_GUARD_BAND: u32 = 4096;
/// Largest magnitude of a world-space length, position or scale (the f32 stages keep 7 digits,
/// so a scene spanning more than this collapses; it also keeps squares and products finite).
pub const MAX_WORLD: f64 = 1e9;
/// Smallest positive world-space length (lengths, distances, sizes, scales, view width).
pub const MIN_WORLD: f64 = 1e-9;
/// Largest colour component (light, material, background, gradient) and specular strength: with
/// 16 lights, a specular highlight and 64 stops of exposure the f32 image stays finite.
pub const MAX_COLOR: f64 = 1e4;
/// Largest light variance σ² per unit distance (σ = 10⁴: far wider than a hemisphere; the sweep
/// and its tables stay finite up to it, tested at 2e6 in `sweep_accuracy` and at the bound here).
pub const MAX_VARIANCE: f64 = 1e8;
/// Largest magnitude of an angle in degrees (a rotation of more turns than this has no meaning
/// left in f64).
pub const MAX_ANGLE_DEG: f64 = 1e6;
/// Largest detail frequency ratio per octave (`lacunarity`) and amplitude ratio (`gain`): 16
/// octaves of ratio 16 stay within f32.
pub const MAX_OCTAVE_RATIO: f64 = 16.0;

/// The embedded default scene (procedural meshes only, so it needs no file).
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../scenes/default.toml");
/// The name used for the embedded default scene in messages.
pub const DEFAULT_SCENE_NAME: &str = "<embedded default scene>";

/// A scene error: names the file, the key and what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// The scene file (or `<embedded default scene>`).
    pub file: String,
    /// The key path, e.g. `light[1].tilt_deg`, or empty for a syntax error.
    pub key: String,
    /// What was wrong and what was expected.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: key `{}`: {}", self.file, self.key, self.message)
        }
    }
}

impl std::error::Error for SceneError {}

// ---------------------------------------------------------------------------------------------
// Raw (serde) form: exactly the file's keys, strictly typed.

/// An array of exactly `N` elements (serde's fixed-size arrays would ignore extra ones).
fn exact<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v = Vec::<T>::deserialize(d)?;
    let len = v.len();
    <[T; N]>::try_from(v)
        .map(Some)
        .map_err(|_| D::Error::custom(format!("expected an array of {N} numbers, got {len}")))
}

/// Gradient stops, each exactly `[value, r, g, b, opacity]`.
fn exact_stops<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<[f64; 5]>>, D::Error> {
    let stops = Vec::<Vec<f64>>::deserialize(d)?;
    let mut out = Vec::with_capacity(stops.len());
    for (j, s) in stops.into_iter().enumerate() {
        let len = s.len();
        out.push(<[f64; 5]>::try_from(s).map_err(|_| {
            D::Error::custom(format!(
                "gradient stop {j}: expected 5 numbers [value, r, g, b, opacity], got {len}"
            ))
        })?);
    }
    Ok(Some(out))
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawScene {
    image: RawImage,
    camera: RawCamera,
    sweep: RawSweep,
    #[serde(default)]
    light: Vec<RawLight>,
    #[serde(default)]
    mesh: Vec<RawMesh>,
    #[serde(default)]
    material: BTreeMap<String, RawMaterial>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawImage {
    width: u32,
    height: u32,
    #[serde(default, deserialize_with = "exact")]
    background: Option<[f64; 3]>,
    exposure: Option<f64>,
    tonemap: Option<Tonemap>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    #[serde(default, deserialize_with = "exact")]
    direction: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    up: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    center: Option<[f64; 3]>,
    view_width: f64,
}

/// `sweep.slabs` as written: an integer or a word (only `"auto"` is valid; checked with the key).
#[derive(Debug)]
enum RawSlabs {
    Count(i64),
    Word(String),
}

impl<'de> Deserialize<'de> for RawSlabs {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = RawSlabs;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an integer slab count or \"auto\"")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<RawSlabs, E> {
                Ok(RawSlabs::Count(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<RawSlabs, E> {
                Ok(RawSlabs::Count(i64::try_from(v).unwrap_or(i64::MAX)))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawSlabs, E> {
                Ok(RawSlabs::Word(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawSweep {
    slabs: Option<RawSlabs>,
    slab_factor: Option<f64>,
    slab_distance: Option<f64>,
    optimal_distance: Option<f64>,
    penumbra: Option<String>,
    kernel: Option<String>,
    jitter: Option<bool>,
    seed: Option<u32>,
    variance_compensation: Option<bool>,
    guard_band: Option<toml::Value>,
    preintegration: Option<bool>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawLight {
    #[serde(default, deserialize_with = "exact")]
    color: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    tilt_deg: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "exact")]
    variance: Option<[f64; 2]>,
    rotation_deg: Option<f64>,
    pattern: Option<RawPattern>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawPattern {
    path: String,
    #[serde(default, deserialize_with = "exact")]
    size: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "exact")]
    center: Option<[f64; 2]>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    shape: String,
    size: Option<Vec<f64>>,
    path: Option<String>,
    #[serde(default, deserialize_with = "exact")]
    translate: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    rotate_deg: Option<[f64; 3]>,
    scale: Option<f64>,
    material: String,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    #[serde(default, deserialize_with = "exact")]
    color: Option<[f64; 3]>,
    opacity: Option<f64>,
    #[serde(default, deserialize_with = "exact")]
    transport: Option<[f64; 3]>,
    reference_length: Option<f64>,
    detail: Option<RawDetail>,
    texture: Option<RawTexture>,
    #[serde(default, deserialize_with = "exact_stops")]
    gradient: Option<Vec<[f64; 5]>>,
    specular: Option<RawSpecular>,
    phase: Option<RawPhase>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawPhase {
    g: f64,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawDetail {
    kind: DetailKind,
    frequency: Option<f64>,
    octaves: Option<u32>,
    lacunarity: Option<f64>,
    gain: Option<f64>,
    time: Option<f64>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawTexture {
    path: String,
    #[serde(default, deserialize_with = "exact")]
    dims: Option<[u32; 3]>,
    #[serde(rename = "type")]
    voxel: Option<VoxelType>,
    #[serde(default, deserialize_with = "exact")]
    window: Option<[f64; 2]>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawSpecular {
    strength: f64,
    exponent: u32,
}

// ---------------------------------------------------------------------------------------------
// Validated model.

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Where the scene came from (file path or the embedded name), for messages.
    pub source: String,
    /// Folder that relative paths (OBJ, textures) are resolved against.
    pub base_dir: PathBuf,
    /// Output image.
    pub image: ImageSpec,
    /// Orthographic camera.
    pub camera: CameraSpec,
    /// Slab sweep parameters.
    pub sweep: SweepSpec,
    /// Distant Gaussian lights (at least one; a scene without `[[light]]` gets one white light).
    pub lights: Vec<LightSpec>,
    /// Meshes in scene order (which also resolves overlapping materials: first wins).
    pub meshes: Vec<MeshSpec>,
    /// Materials, indexed by `MeshSpec::material`.
    pub materials: Vec<MaterialSpec>,
}

/// Output image size and background.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageSpec {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB composited behind everything.
    pub background: [f32; 3],
    /// PNG output only: exposure in stops (0 = as rendered).
    pub exposure: f64,
    /// PNG output only: the tone curve (default `aces`, which does not clip the default scene).
    pub tonemap: Tonemap,
}

impl ImageSpec {
    /// How PNG output maps the linear image to 8-bit sRGB.
    pub fn display_map(&self) -> DisplayMap {
        DisplayMap {
            exposure: self.exposure,
            tonemap: self.tonemap,
        }
    }
}

/// Orthographic camera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSpec {
    /// View direction (normalized).
    pub direction: [f64; 3],
    /// World direction shown at the top of the image.
    pub up: [f64; 3],
    /// Centre of the view.
    pub center: [f64; 3],
    /// World units across the image.
    pub view_width: f64,
}

/// How the slab thickness is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SlabSpec {
    /// A slab count over the scene's depth range.
    Count(u32),
    /// A slab thickness in world units.
    Distance(f64),
    /// Chosen from the detail: 2 slabs per finest period of the procedural detail or per voxel of
    /// a 3D texture along the view direction, times `SweepSpec::slab_factor`
    /// (see `crate::auto_slabs`).
    Auto,
}

/// How a light's kernel grows from slab to slab (`sweep.penumbra`; docs/accuracy.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Penumbra {
    /// The paper's model: the same kernel every slab, covariance d1·e·Σl, so after distance d the
    /// penumbra has covariance d·d1·Σl: right at d = d1 only.
    #[default]
    Iterated,
    /// The kernel follows each pixel's mean occluder depth z̄: covariance ((h+1)² − h²)·e²·Σl at
    /// h = (z − z̄)/e slabs, so a single occluder's penumbra has (z − z̄)²·Σl at every distance.
    Distance,
}

impl fmt::Display for Penumbra {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Penumbra::Iterated => "iterated",
            Penumbra::Distance => "distance",
        })
    }
}

impl std::str::FromStr for Penumbra {
    type Err = String;

    /// `iterated` or `distance`.
    fn from_str(s: &str) -> Result<Penumbra, String> {
        match s {
            "iterated" => Ok(Penumbra::Iterated),
            "distance" => Ok(Penumbra::Distance),
            _ => Err(format!("expected \"iterated\" or \"distance\", got {s:?}")),
        }
    }
}

/// Slab sweep parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSpec {
    /// Slab count or thickness.
    pub slabs: SlabSpec,
    /// Multiplies the count `slabs = "auto"` chooses (1 = 2 slabs per finest period).
    pub slab_factor: f64,
    /// The optimal shadow distance d1 (world units): where the iterated mode's shadows are right.
    /// Required with `penumbra = "iterated"`; optional (and unused) with `"distance"`.
    pub optimal_distance: Option<f64>,
    /// How the kernel grows with depth: the paper's fixed per-slab kernel, or one that follows
    /// each pixel's distance to its occluders.
    pub penumbra: Penumbra,
    /// Convolution kernel.
    pub kernel: KernelSpec,
    /// Jitter the shading point inside each slab.
    pub jitter: bool,
    /// Seed of every hash-derived random number.
    pub seed: u32,
    /// Compensate the variance that bilinear reads add (see docs/accuracy.md).
    pub variance_compensation: bool,
    /// Light buffer and LDI beyond the image edges, so objects just outside cast shadows into
    /// it: sized from the scene (`auto`, the default) or a fixed pixel count on every side.
    pub guard_band: GuardBandSpec,
    /// Pre-integrated compositing (Patel et al. 2013 §7, Engel, Kraus & Ertl 2001): materials
    /// with detail are shaded from a 2D table over the detail values at a slab's front and back
    /// faces instead of one sample (off by default: the images of before, bit for bit).
    pub preintegration: bool,
}

/// A distant Gaussian light behind the viewer.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSpec {
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Tilt angles (ωx, ωy) in degrees, each |ω| < 90.
    pub tilt_deg: [f64; 2],
    /// Variances (σx², σy²) on the virtual light plane at unit distance.
    pub variance: [f64; 2],
    /// Rotation α of the principal axes, degrees.
    pub rotation_deg: f64,
    /// A gobo: an image that is the light's initial light buffer (see `crate::pattern`).
    pub pattern: Option<PatternSpec>,
}

/// A light's pattern (`[[light]] pattern = { path, size, center }`).
#[derive(Clone, Debug, PartialEq)]
pub struct PatternSpec {
    /// Resolved image path.
    pub path: PathBuf,
    /// World-unit size [w, h] of the image on the first slab plane.
    pub size: [f64; 2],
    /// Centre of the image, camera-space [x right, y down] world units from the view's centre.
    pub center: [f64; 2],
}

/// The shape of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeSpec {
    /// Axis-aligned box with full extents.
    Box {
        /// Full extents.
        size: [f64; 3],
    },
    /// Icosphere.
    Sphere {
        /// Radius.
        radius: f64,
        /// Subdivision level (0 = icosahedron).
        subdivisions: u32,
    },
    /// Torus around the z axis.
    Torus {
        /// Radius of the centre circle.
        major: f64,
        /// Radius of the tube.
        minor: f64,
        /// Segments around the major circle.
        segments: u32,
    },
    /// Closed cylinder around the z axis.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Full height.
        height: f64,
        /// Segments around.
        segments: u32,
    },
    /// A Wavefront OBJ file.
    Obj {
        /// Resolved path.
        path: PathBuf,
    },
}

/// A mesh instance.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshSpec {
    /// Shape.
    pub shape: ShapeSpec,
    /// Translation (applied last).
    pub translate: [f64; 3],
    /// Rotation in degrees about x, then y, then z.
    pub rotate_deg: [f64; 3],
    /// Uniform scale (applied first).
    pub scale: f64,
    /// Index into `Scene::materials`.
    pub material: usize,
}

/// A volumetric detail function.
#[derive(Clone, Debug, PartialEq)]
pub struct DetailSpec {
    /// Which function.
    pub kind: DetailKind,
    /// Base frequency (per object-space unit).
    pub frequency: f64,
    /// Octave count.
    pub octaves: u32,
    /// Frequency ratio between octaves.
    pub lacunarity: f64,
    /// Amplitude ratio between octaves.
    pub gain: f64,
    /// Time for 4D animation; `None` means 3D noise.
    pub time: Option<f64>,
}

/// A 3D texture, mapped onto the mesh's object-space bounding box.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSpec {
    /// Resolved path.
    pub path: PathBuf,
    /// How the file is read.
    pub format: TextureFormat,
}

/// The file format of a 3D texture.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureFormat {
    /// A headerless raw file: dims and voxel type given in the scene; stretched to the bounds.
    Raw {
        /// Voxel counts in x, y, z.
        dims: [u32; 3],
        /// Voxel type.
        voxel: VoxelType,
    },
    /// NIfTI-1 (`.nii`, `.nii.gz`): dims, spacing and type from the header; the physical extent
    /// keeps its aspect inside the bounds.
    Nifti {
        /// Values mapped to [0, 1]; `None`: the data's min–max.
        window: Option<[f64; 2]>,
    },
}

/// A specular highlight at crossed surfaces.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecularSpec {
    /// Multiplier of the highlight.
    pub strength: f32,
    /// Blinn–Phong exponent (evaluated by repeated squaring).
    pub exponent: u32,
}

/// One gradient stop: detail value and (r, g, b, opacity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GradientStop {
    /// Detail value in [0, 1].
    pub value: f64,
    /// Linear RGB.
    pub color: [f64; 3],
    /// Opacity per reference length, in [0, 1].
    pub opacity: f64,
}

/// A material: constant, or volumetric detail through a colour/opacity gradient.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSpec {
    /// Name in the scene file.
    pub name: String,
    /// Colour of a constant material.
    pub color: [f64; 3],
    /// Opacity per reference length of a constant material.
    pub opacity: f64,
    /// Transport colour τ (chromatic attenuation: 1 lets that channel through).
    pub transport: [f64; 3],
    /// Length the opacities are given for; `None` = the slab distance.
    pub reference_length: Option<f64>,
    /// Procedural detail.
    pub detail: Option<DetailSpec>,
    /// 3D texture detail.
    pub texture: Option<TextureSpec>,
    /// Transfer function for detail values (sorted by value).
    pub gradient: Vec<GradientStop>,
    /// Optional specular highlight.
    pub specular: Option<SpecularSpec>,
    /// Henyey–Greenstein asymmetry g of the medium's scattering (0 = isotropic, > 0 forward,
    /// < 0 backward); with distant lights and an orthographic camera the phase function is one
    /// constant per light, applied to the light's colour in shading (not to the specular term).
    pub phase_g: f64,
}

impl Scene {
    /// Parses and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let source = path.display().to_string();
        let text =
            crate::input::read_text_limited(path, crate::input::MAX_SCENE_BYTES).map_err(|e| {
                SceneError {
                    file: source.clone(),
                    key: String::new(),
                    message: format!("cannot read scene file: {e}"),
                }
            })?;
        let base = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        Scene::parse(&text, &source, &base)
    }

    /// The embedded default scene.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE_TOML, DEFAULT_SCENE_NAME, Path::new("."))
            .expect("the embedded default scene is valid (tested)")
    }

    /// Parses and validates scene text; `source` names it in messages, `base_dir` resolves paths.
    pub fn parse(text: &str, source: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        let raw: RawScene = toml::from_str(text).map_err(|e| toml_error(source, text, &e))?;
        Validator { file: source }.scene(raw, base_dir)
    }

    /// Whether every material's transport is grey and no light has a pattern (which may be
    /// coloured), so one light-buffer channel suffices.
    pub fn is_monochrome(&self) -> bool {
        self.lights.iter().all(|l| l.pattern.is_none())
            && self
                .materials
                .iter()
                .all(|m| m.transport[0] == m.transport[1] && m.transport[1] == m.transport[2])
    }

    /// Overrides camera values (command line): the direction is normalised and checked against
    /// `up` like the file's, the centre must be finite and the view width positive.
    pub fn override_camera(
        &mut self,
        direction: Option<[f64; 3]>,
        center: Option<[f64; 3]>,
        view_width: Option<f64>,
    ) -> Result<(), SceneError> {
        let v = Validator { file: &self.source };
        if let Some(d) = direction {
            let d = v.unit_vector("--camera-direction", d)?;
            let u = self.camera.up;
            let cross = [
                d[1] * u[2] - d[2] * u[1],
                d[2] * u[0] - d[0] * u[2],
                d[0] * u[1] - d[1] * u[0],
            ];
            if (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt() < 1e-6 {
                return Err(v.err(
                    "--camera-direction",
                    "expected a direction not parallel to camera.up",
                ));
            }
            self.camera.direction = d;
        }
        if let Some(c) = center {
            self.camera.center = v.bounded3("--camera-center", c, MAX_WORLD)?;
        }
        if let Some(w) = view_width {
            self.camera.view_width = v.length("--view-width", w)?;
        }
        Ok(())
    }

    /// Re-checks the values that command-line overrides may have changed.
    pub fn revalidate(&self) -> Result<(), SceneError> {
        let v = Validator { file: &self.source };
        v.image_size(self.image.width, self.image.height)?;
        v.exposure(self.image.exposure)?;
        match self.sweep.slabs {
            SlabSpec::Count(n) => v.slab_count(n)?,
            SlabSpec::Distance(d) => {
                v.length("sweep.slab_distance", d)?;
            }
            SlabSpec::Auto => {}
        }
        if self.sweep.penumbra == Penumbra::Iterated && self.sweep.optimal_distance.is_none() {
            return Err(v.err(
                "sweep.optimal_distance",
                "missing: the iterated penumbra needs the distance d1 (world units) at which its \
                 shadows are right (or use the distance penumbra, which needs none)",
            ));
        }
        Ok(())
    }
}

fn toml_error(source: &str, text: &str, e: &toml::de::Error) -> SceneError {
    let (line, col) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
    let line_text = text
        .lines()
        .nth(line.saturating_sub(1))
        .unwrap_or("")
        .trim();
    let key = line_text
        .split('=')
        .next()
        .filter(|_| line_text.contains('='))
        .map(|k| k.trim().to_string())
        .unwrap_or_default();
    let mut message = e.message().to_string();
    if line > 0 {
        message = format!("line {line}, column {col}: {message} (in `{line_text}`)");
    }
    SceneError {
        file: source.to_string(),
        key,
        message,
    }
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

struct Validator<'a> {
    file: &'a str,
}

impl Validator<'_> {
    fn err(&self, key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            key: key.into(),
            message: message.into(),
        }
    }

    fn finite(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(key, format!("expected a finite number, got {v}")))
        }
    }

    fn finite3(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        for (i, c) in v.iter().enumerate() {
            self.finite(&format!("{key}[{i}]"), *c)?;
        }
        Ok(v)
    }

    fn positive(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(key, format!("expected a number > 0, got {v}")))
        }
    }

    /// A finite number with |v| <= `max`.
    fn bounded(&self, key: &str, v: f64, max: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v.abs() <= max {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("expected a number from -{max:e} to {max:e}, got {v:e}"),
            ))
        }
    }

    /// Three numbers, each with |v| <= `max`.
    fn bounded3(&self, key: &str, v: [f64; 3], max: f64) -> Result<[f64; 3], SceneError> {
        for (i, c) in v.iter().enumerate() {
            self.bounded(&format!("{key}[{i}]"), *c, max)?;
        }
        Ok(v)
    }

    /// A positive world-space length in [`MIN_WORLD`, `MAX_WORLD`].
    fn length(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.positive(key, v)?;
        self.in_range(key, v, MIN_WORLD, MAX_WORLD)
    }

    /// A positive number in [`lo`, `hi`], the message giving the range.
    fn in_range(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("expected a number from {lo:e} to {hi:e}, got {v:e}"),
            ))
        }
    }

    fn unit_interval(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if (0.0..=1.0).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(key, format!("expected a number in [0, 1], got {v}")))
        }
    }

    fn color(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        self.finite3(key, v)?;
        for (i, c) in v.iter().enumerate() {
            if *c < 0.0 {
                return Err(self.err(
                    format!("{key}[{i}]"),
                    format!("expected a colour component >= 0, got {c}"),
                ));
            }
            if *c > MAX_COLOR {
                return Err(self.err(
                    format!("{key}[{i}]"),
                    format!("expected a colour component from 0 to {MAX_COLOR:e}, got {c:e}"),
                ));
            }
        }
        Ok(v)
    }

    /// One colour component in [0, [`MAX_COLOR`]], the key naming its exact index.
    fn color_component(&self, key: &str, c: f64) -> Result<f64, SceneError> {
        self.finite(key, c)?;
        if (0.0..=MAX_COLOR).contains(&c) {
            Ok(c)
        } else {
            Err(self.err(
                key,
                format!("expected a colour component from 0 to {MAX_COLOR:e}, got {c:e}"),
            ))
        }
    }

    fn unit_vector(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        self.finite3(key, v)?;
        // Divided by the largest component first, so that 1e308 or 1e-300 do not overflow.
        let big = v[0].abs().max(v[1].abs()).max(v[2].abs());
        if big == 0.0 {
            return Err(self.err(key, "expected a non-zero direction vector, got [0, 0, 0]"));
        }
        let v = v.map(|c| c / big);
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        Ok([v[0] / len, v[1] / len, v[2] / len])
    }

    fn image_size(&self, width: u32, height: u32) -> Result<(), SceneError> {
        for (key, v) in [("image.width", width), ("image.height", height)] {
            if v == 0 || v > MAX_IMAGE_SIDE {
                return Err(self.err(
                    key,
                    format!("expected an integer from 1 to {MAX_IMAGE_SIDE}, got {v}"),
                ));
            }
        }
        Ok(())
    }

    fn exposure(&self, stops: f64) -> Result<f64, SceneError> {
        let stops = self.finite("image.exposure", stops)?;
        if stops.abs() > MAX_EXPOSURE_STOPS {
            return Err(self.err(
                "image.exposure",
                format!(
                    "expected stops in [-{MAX_EXPOSURE_STOPS}, {MAX_EXPOSURE_STOPS}], got {stops}"
                ),
            ));
        }
        Ok(stops)
    }

    fn slab_count(&self, n: u32) -> Result<(), SceneError> {
        if n == 0 || n > MAX_SLABS {
            return Err(self.err(
                "sweep.slabs",
                format!("expected an integer from 1 to {MAX_SLABS}, got {n}"),
            ));
        }
        Ok(())
    }

    fn scene(&self, raw: RawScene, base_dir: &Path) -> Result<Scene, SceneError> {
        self.image_size(raw.image.width, raw.image.height)?;
        let background =
            self.color("image.background", raw.image.background.unwrap_or([0.0; 3]))?;
        let image = ImageSpec {
            width: raw.image.width,
            height: raw.image.height,
            background: background.map(|c| c as f32),
            exposure: self.exposure(raw.image.exposure.unwrap_or(0.0))?,
            tonemap: raw.image.tonemap.unwrap_or_default(),
        };

        let direction = self.unit_vector(
            "camera.direction",
            raw.camera.direction.unwrap_or([0.0, 0.0, 1.0]),
        )?;
        let up = self.unit_vector("camera.up", raw.camera.up.unwrap_or([0.0, 1.0, 0.0]))?;
        let cross = [
            direction[1] * up[2] - direction[2] * up[1],
            direction[2] * up[0] - direction[0] * up[2],
            direction[0] * up[1] - direction[1] * up[0],
        ];
        if (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt() < 1e-6 {
            return Err(self.err(
                "camera.up",
                "expected a direction not parallel to camera.direction",
            ));
        }
        let camera = CameraSpec {
            direction,
            up,
            center: self.bounded3(
                "camera.center",
                raw.camera.center.unwrap_or([0.0; 3]),
                MAX_WORLD,
            )?,
            view_width: self.length("camera.view_width", raw.camera.view_width)?,
        };

        let sweep = self.sweep(raw.sweep)?;

        if raw.light.len() > MAX_LIGHTS {
            return Err(self.err(
                "light",
                format!(
                    "expected at most {MAX_LIGHTS} lights, got {}",
                    raw.light.len()
                ),
            ));
        }
        let mut lights = Vec::new();
        for (i, l) in raw.light.into_iter().enumerate() {
            lights.push(self.light(i, l, base_dir)?);
        }
        if lights.is_empty() {
            lights.push(LightSpec {
                color: [1.0; 3],
                tilt_deg: [0.0; 2],
                variance: [0.0; 2],
                rotation_deg: 0.0,
                pattern: None,
            });
        }

        let names: Vec<String> = raw.material.keys().cloned().collect();
        let mut materials = Vec::new();
        for (name, m) in raw.material {
            materials.push(self.material(&name, m, base_dir)?);
        }

        if raw.mesh.is_empty() {
            return Err(self.err("mesh", "expected at least one [[mesh]]"));
        }
        if raw.mesh.len() > MAX_MESHES {
            return Err(self.err(
                "mesh",
                format!(
                    "expected at most {MAX_MESHES} meshes, got {}",
                    raw.mesh.len()
                ),
            ));
        }
        let mut meshes = Vec::new();
        for (i, m) in raw.mesh.into_iter().enumerate() {
            meshes.push(self.mesh(i, m, &names, base_dir)?);
        }

        Ok(Scene {
            source: self.file.to_string(),
            base_dir: base_dir.to_path_buf(),
            image,
            camera,
            sweep,
            lights,
            meshes,
            materials,
        })
    }

    fn sweep(&self, raw: RawSweep) -> Result<SweepSpec, SceneError> {
        let slabs = match (raw.slabs, raw.slab_distance) {
            (Some(_), Some(_)) => {
                return Err(self.err(
                    "sweep.slabs",
                    "expected only one of `slabs` and `slab_distance`, got both",
                ));
            }
            (None, None) => {
                return Err(self.err(
                    "sweep.slabs",
                    "expected one of `slabs` (a count) or `slab_distance` (world units)",
                ));
            }
            (Some(RawSlabs::Count(n)), None) => match u32::try_from(n) {
                Ok(n) if (1..=MAX_SLABS).contains(&n) => SlabSpec::Count(n),
                _ => {
                    return Err(self.err(
                        "sweep.slabs",
                        format!("expected an integer from 1 to {MAX_SLABS} or \"auto\", got {n}"),
                    ));
                }
            },
            (Some(RawSlabs::Word(w)), None) => {
                if w != "auto" {
                    return Err(self.err(
                        "sweep.slabs",
                        format!("expected an integer from 1 to {MAX_SLABS} or \"auto\", got {w:?}"),
                    ));
                }
                SlabSpec::Auto
            }
            (None, Some(d)) => SlabSpec::Distance(self.length("sweep.slab_distance", d)?),
        };
        if let Some(f) = raw.slab_factor {
            if slabs != SlabSpec::Auto {
                return Err(self.err(
                    "sweep.slab_factor",
                    "`slab_factor` modulates `slabs = \"auto\"` only; remove it or set \
                     `slabs = \"auto\"`",
                ));
            }
            let (lo, hi) = SLAB_FACTOR_RANGE;
            self.in_range("sweep.slab_factor", f, lo, hi)?;
        }
        let kernel_text = raw.kernel.unwrap_or_else(|| "ellipse2".to_string());
        let kernel = kernel_text
            .parse::<KernelSpec>()
            .map_err(|e| self.err("sweep.kernel", e))?;
        let guard_band = match raw.guard_band {
            None => GuardBandSpec::Auto,
            Some(toml::Value::String(s)) if s == "auto" => GuardBandSpec::Auto,
            Some(toml::Value::Integer(g)) if (0..=i64::from(MAX_GUARD_BAND)).contains(&g) => {
                GuardBandSpec::Pixels(g as u32)
            }
            Some(other) => {
                return Err(self.err(
                    "sweep.guard_band",
                    format!(
                        "expected \"auto\" or a pixel count 0 to {MAX_GUARD_BAND}, got {other}"
                    ),
                ));
            }
        };
        let penumbra = match raw.penumbra.as_deref() {
            None => Penumbra::default(),
            Some(p) => p
                .parse::<Penumbra>()
                .map_err(|e| self.err("sweep.penumbra", e))?,
        };
        let optimal_distance = match raw.optimal_distance {
            Some(d) => Some(self.length("sweep.optimal_distance", d)?),
            None if penumbra == Penumbra::Iterated => {
                return Err(self.err(
                    "sweep.optimal_distance",
                    "missing: the iterated penumbra needs the distance d1 (world units) at which \
                     its shadows are right (or set penumbra = \"distance\", which needs none)",
                ));
            }
            None => None,
        };
        Ok(SweepSpec {
            slabs,
            slab_factor: raw.slab_factor.unwrap_or(1.0),
            optimal_distance,
            penumbra,
            kernel,
            jitter: raw.jitter.unwrap_or(true),
            seed: raw.seed.unwrap_or(0),
            variance_compensation: raw.variance_compensation.unwrap_or(true),
            guard_band,
            preintegration: raw.preintegration.unwrap_or(false),
        })
    }

    fn light(&self, i: usize, raw: RawLight, base_dir: &Path) -> Result<LightSpec, SceneError> {
        let key = |k: &str| format!("light[{i}].{k}");
        let color = self.color(&key("color"), raw.color.unwrap_or([1.0; 3]))?;
        let tilt = raw.tilt_deg.unwrap_or([0.0; 2]);
        for (j, t) in tilt.iter().enumerate() {
            let k = format!("light[{i}].tilt_deg[{j}]");
            self.finite(&k, *t)?;
            if t.abs() >= 90.0 {
                return Err(self.err(k, format!("expected |angle| < 90 degrees, got {t}")));
            }
        }
        let variance = raw.variance.unwrap_or([0.0; 2]);
        for (j, v) in variance.iter().enumerate() {
            let k = format!("light[{i}].variance[{j}]");
            self.finite(&k, *v)?;
            if *v < 0.0 {
                return Err(self.err(k, format!("expected a variance >= 0, got {v}")));
            }
            if *v > MAX_VARIANCE {
                return Err(self.err(
                    k,
                    format!("expected a variance from 0 to {MAX_VARIANCE:e}, got {v:e}"),
                ));
            }
        }
        let pattern = match raw.pattern {
            None => None,
            Some(p) => {
                let size = p.size.ok_or_else(|| {
                    self.err(
                        key("pattern.size"),
                        "expected `size = [w, h]`: the pattern's world-unit size on the first slab plane",
                    )
                })?;
                for (j, v) in size.iter().enumerate() {
                    self.length(&format!("light[{i}].pattern.size[{j}]"), *v)?;
                }
                let center = p.center.unwrap_or([0.0; 2]);
                for (j, v) in center.iter().enumerate() {
                    self.bounded(&format!("light[{i}].pattern.center[{j}]"), *v, MAX_WORLD)?;
                }
                Some(PatternSpec {
                    path: base_dir.join(p.path),
                    size,
                    center,
                })
            }
        };
        Ok(LightSpec {
            pattern,
            color: color.map(|c| c as f32),
            tilt_deg: tilt,
            variance,
            rotation_deg: self.bounded(
                &key("rotation_deg"),
                raw.rotation_deg.unwrap_or(0.0),
                MAX_ANGLE_DEG,
            )?,
        })
    }

    /// The shape of mesh `i`: its `shape`, `size` and `path` keys.
    fn shape(&self, i: usize, raw: &RawMesh, base_dir: &Path) -> Result<ShapeSpec, SceneError> {
        let key = |k: &str| format!("mesh[{i}].{k}");
        let size = |n: usize, what: &str| -> Result<Vec<f64>, SceneError> {
            let s = raw.size.clone().ok_or_else(|| {
                self.err(
                    key("size"),
                    format!("expected `size` = {what} for this shape"),
                )
            })?;
            if s.len() != n {
                return Err(self.err(
                    key("size"),
                    format!("expected {n} numbers ({what}), got {}", s.len()),
                ));
            }
            for (j, v) in s.iter().enumerate() {
                self.bounded(&format!("mesh[{i}].size[{j}]"), *v, MAX_WORLD)?;
            }
            Ok(s)
        };
        let whole = |v: f64, k: &str, min: u32, max: u32| -> Result<u32, SceneError> {
            if v.fract() != 0.0 || v < f64::from(min) || v > f64::from(max) {
                return Err(self.err(
                    key(k),
                    format!("expected a whole number from {min} to {max}, got {v}"),
                ));
            }
            Ok(v as u32)
        };
        if raw.path.is_some() && raw.shape != "obj" {
            return Err(self.err(key("path"), "`path` is only for shape = \"obj\""));
        }
        Ok(match raw.shape.as_str() {
            "box" => {
                let s = size(3, "[x, y, z] full extents")?;
                for (j, v) in s.iter().enumerate() {
                    self.length(&format!("mesh[{i}].size[{j}]"), *v)?;
                }
                ShapeSpec::Box {
                    size: [s[0], s[1], s[2]],
                }
            }
            "sphere" => {
                let s = size(2, "[radius, subdivisions]")?;
                self.length(&format!("mesh[{i}].size[0]"), s[0])?;
                ShapeSpec::Sphere {
                    radius: s[0],
                    subdivisions: whole(s[1], "size[1]", 0, MAX_SPHERE_SUBDIVISIONS)?,
                }
            }
            "torus" => {
                let s = size(3, "[major radius, minor radius, segments]")?;
                self.length(&format!("mesh[{i}].size[0]"), s[0])?;
                self.length(&format!("mesh[{i}].size[1]"), s[1])?;
                if s[1] >= s[0] {
                    return Err(self.err(
                        key("size"),
                        format!(
                            "expected minor radius < major radius, got {} >= {}",
                            s[1], s[0]
                        ),
                    ));
                }
                let segments = whole(s[2], "size[2]", 3, MAX_TORUS_SEGMENTS)?;
                ShapeSpec::Torus {
                    major: s[0],
                    minor: s[1],
                    segments,
                }
            }
            "cylinder" => {
                let s = size(3, "[radius, height, segments]")?;
                self.length(&format!("mesh[{i}].size[0]"), s[0])?;
                self.length(&format!("mesh[{i}].size[1]"), s[1])?;
                let segments = whole(s[2], "size[2]", 3, MAX_TORUS_SEGMENTS)?;
                ShapeSpec::Cylinder {
                    radius: s[0],
                    height: s[1],
                    segments,
                }
            }
            "obj" => {
                if raw.size.is_some() {
                    return Err(self.err(key("size"), "an obj mesh takes `path`, not `size`"));
                }
                let p = raw.path.as_ref().ok_or_else(|| {
                    self.err(
                        key("path"),
                        "expected `path` = the OBJ file, relative to the scene",
                    )
                })?;
                ShapeSpec::Obj {
                    path: base_dir.join(p),
                }
            }
            other => {
                return Err(self.err(
                    key("shape"),
                    format!("expected one of box, sphere, torus, cylinder, obj; got {other:?}"),
                ));
            }
        })
    }

    fn mesh(
        &self,
        i: usize,
        raw: RawMesh,
        materials: &[String],
        base_dir: &Path,
    ) -> Result<MeshSpec, SceneError> {
        let key = |k: &str| format!("mesh[{i}].{k}");
        let shape = self.shape(i, &raw, base_dir)?;
        let material = materials
            .iter()
            .position(|n| *n == raw.material)
            .ok_or_else(|| {
                self.err(
                    key("material"),
                    format!(
                        "no material named {:?}; expected one of [{}]",
                        raw.material,
                        materials.join(", ")
                    ),
                )
            })?;
        let scale = self.bounded(&key("scale"), raw.scale.unwrap_or(1.0), MAX_WORLD)?;
        if scale.abs() < MIN_WORLD {
            return Err(self.err(
                key("scale"),
                format!("expected a non-zero scale with |scale| >= {MIN_WORLD:e}, got {scale:e}"),
            ));
        }
        Ok(MeshSpec {
            shape,
            translate: self.bounded3(
                &key("translate"),
                raw.translate.unwrap_or([0.0; 3]),
                MAX_WORLD,
            )?,
            rotate_deg: self.bounded3(
                &key("rotate_deg"),
                raw.rotate_deg.unwrap_or([0.0; 3]),
                MAX_ANGLE_DEG,
            )?,
            scale,
            material,
        })
    }

    /// The `gradient` of material `name`: stops sorted by value (`needed`: the material has
    /// detail or a texture, which the gradient maps to colour and opacity).
    fn gradient(
        &self,
        name: &str,
        raw: Option<Vec<[f64; 5]>>,
        needed: bool,
    ) -> Result<Vec<GradientStop>, SceneError> {
        let key = |k: &str| format!("material.{name}.{k}");
        let mut gradient = Vec::new();
        if let Some(g) = raw {
            if g.is_empty() {
                return Err(self.err(key("gradient"), "expected at least one stop"));
            }
            for (j, s) in g.iter().enumerate() {
                let k = format!("material.{name}.gradient[{j}]");
                for (c, v) in s.iter().enumerate() {
                    self.finite(&format!("{k}[{c}]"), *v)?;
                }
                self.unit_interval(&format!("{k}[0]"), s[0])?;
                for (c, v) in s.iter().enumerate().take(4).skip(1) {
                    self.color_component(&format!("{k}[{c}]"), *v)?;
                }
                self.unit_interval(&format!("{k}[4]"), s[4])?;
                if let Some(prev) = gradient.last().map(|p: &GradientStop| p.value)
                    && s[0] < prev
                {
                    return Err(self.err(k, "expected stops sorted by value"));
                }
                gradient.push(GradientStop {
                    value: s[0],
                    color: [s[1], s[2], s[3]],
                    opacity: s[4],
                });
            }
        } else if needed {
            return Err(self.err(
                key("gradient"),
                "a material with detail or texture needs `gradient` = [[value, r, g, b, opacity], ...]",
            ));
        }
        Ok(gradient)
    }

    fn material(
        &self,
        name: &str,
        raw: RawMaterial,
        base_dir: &Path,
    ) -> Result<MaterialSpec, SceneError> {
        let key = |k: &str| format!("material.{name}.{k}");
        let color = self.color(&key("color"), raw.color.unwrap_or([1.0; 3]))?;
        let opacity = self.unit_interval(&key("opacity"), raw.opacity.unwrap_or(1.0))?;
        let transport = raw.transport.unwrap_or([0.0; 3]);
        for (j, t) in transport.iter().enumerate() {
            self.unit_interval(&format!("material.{name}.transport[{j}]"), *t)?;
        }
        let reference_length = raw
            .reference_length
            .map(|r| self.length(&key("reference_length"), r))
            .transpose()?;
        let detail = raw.detail.map(|d| self.detail(&key, d)).transpose()?;
        let texture = raw
            .texture
            .map(|t| self.texture(&key, t, base_dir))
            .transpose()?;
        if detail.is_some() && texture.is_some() {
            return Err(self.err(
                key("texture"),
                "expected either `detail` or `texture`, not both",
            ));
        }
        let gradient = self.gradient(name, raw.gradient, detail.is_some() || texture.is_some())?;
        if raw.opacity.is_some() && !gradient.is_empty() {
            return Err(self.err(
                key("opacity"),
                "a gradient material takes its opacity from the gradient; remove `opacity`",
            ));
        }
        let specular = raw.specular.map(|s| self.specular(&key, s)).transpose()?;
        let phase_g = match raw.phase {
            None => 0.0,
            Some(p) => {
                let k = key("phase.g");
                self.finite(&k, p.g)?;
                if p.g.abs() > MAX_PHASE_G {
                    return Err(self.err(
                        k,
                        format!(
                            "expected a Henyey-Greenstein asymmetry from -{MAX_PHASE_G} to \
                             {MAX_PHASE_G} (the function needs -1 < g < 1), got {}",
                            p.g
                        ),
                    ));
                }
                p.g
            }
        };
        Ok(MaterialSpec {
            name: name.to_string(),
            color,
            opacity,
            transport,
            reference_length,
            detail,
            texture,
            gradient,
            specular,
            phase_g,
        })
    }

    /// A material's procedural detail (`material.NAME.detail`).
    fn detail(&self, key: &dyn Fn(&str) -> String, d: RawDetail) -> Result<DetailSpec, SceneError> {
        let octaves = d.octaves.unwrap_or(4);
        if octaves == 0 || octaves > 16 {
            return Err(self.err(
                key("detail.octaves"),
                format!("expected 1 to 16 octaves, got {octaves}"),
            ));
        }
        Ok(DetailSpec {
            kind: d.kind,
            frequency: self.length(&key("detail.frequency"), d.frequency.unwrap_or(1.0))?,
            octaves,
            lacunarity: self.in_range(
                &key("detail.lacunarity"),
                d.lacunarity.unwrap_or(2.0),
                1.0 / MAX_OCTAVE_RATIO,
                MAX_OCTAVE_RATIO,
            )?,
            gain: self.in_range(
                &key("detail.gain"),
                d.gain.unwrap_or(0.5),
                1.0 / MAX_OCTAVE_RATIO,
                MAX_OCTAVE_RATIO,
            )?,
            time: d
                .time
                .map(|t| self.bounded(&key("detail.time"), t, MAX_WORLD))
                .transpose()?,
        })
    }

    /// A material's 3D texture (`material.NAME.texture`): NIfTI by extension, else raw.
    fn texture(
        &self,
        key: &dyn Fn(&str) -> String,
        t: RawTexture,
        base_dir: &Path,
    ) -> Result<TextureSpec, SceneError> {
        let path = base_dir.join(&t.path);
        let format = if crate::nifti::is_nifti_path(&path) {
            if t.dims.is_some() || t.voxel.is_some() {
                return Err(self.err(
                    key("texture"),
                    "a NIfTI texture (.nii, .nii.gz) takes dims and type from its header; \
                     remove `dims` and `type`",
                ));
            }
            if let Some([lo, hi]) = t.window
                && !(lo.is_finite() && hi.is_finite() && lo < hi)
            {
                return Err(self.err(
                    key("texture.window"),
                    format!("expected [lo, hi] with finite lo < hi, got [{lo}, {hi}]"),
                ));
            }
            TextureFormat::Nifti { window: t.window }
        } else {
            let (Some(dims), Some(voxel)) = (t.dims, t.voxel) else {
                return Err(self.err(
                    key("texture"),
                    "a raw texture needs `dims = [x, y, z]` and `type` (u8, u16, f32); \
                     NIfTI files end in .nii or .nii.gz",
                ));
            };
            if dims.contains(&0) {
                return Err(self.err(key("texture.dims"), "expected three dimensions >= 1"));
            }
            if t.window.is_some() {
                return Err(self.err(
                    key("texture.window"),
                    "`window` applies to NIfTI textures only (raw ones are normalised by type)",
                ));
            }
            TextureFormat::Raw { dims, voxel }
        };
        Ok(TextureSpec { path, format })
    }

    /// A material's specular highlight (`material.NAME.specular`).
    fn specular(
        &self,
        key: &dyn Fn(&str) -> String,
        s: RawSpecular,
    ) -> Result<SpecularSpec, SceneError> {
        self.finite(&key("specular.strength"), s.strength)?;
        if !(0.0..=MAX_COLOR).contains(&s.strength) {
            return Err(self.err(
                key("specular.strength"),
                format!(
                    "expected a strength from 0 to {MAX_COLOR:e}, got {:e}",
                    s.strength
                ),
            ));
        }
        if s.exponent == 0 || s.exponent > 4096 {
            return Err(self.err(key("specular.exponent"), "expected 1 to 4096"));
        }
        Ok(SpecularSpec {
            strength: s.strength as f32,
            exponent: s.exponent,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
[image]
width = 64
height = 32
[camera]
view_width = 2.0
[sweep]
slabs = 16
optimal_distance = 0.5
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
material = "m"
[material.m]
"#;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        Scene::parse(text, "test.toml", Path::new("."))
    }

    #[test]
    fn defaults_are_the_documented_ones() {
        let s = parse(MINIMAL).unwrap();
        assert_eq!(s.camera.direction, [0.0, 0.0, 1.0]);
        assert_eq!(s.camera.up, [0.0, 1.0, 0.0]);
        assert_eq!(s.camera.center, [0.0; 3]);
        assert_eq!(s.image.background, [0.0; 3]);
        assert_eq!(s.sweep.kernel, KernelSpec::default());
        assert!(s.sweep.jitter);
        assert_eq!(s.sweep.seed, 0);
        assert_eq!(s.lights.len(), 1);
        assert_eq!(s.lights[0].color, [1.0; 3]);
        assert_eq!(s.meshes[0].scale, 1.0);
        assert_eq!(s.materials[0].transport, [0.0; 3]);
        assert_eq!(s.materials[0].reference_length, None);
        assert!(s.is_monochrome());
    }

    #[test]
    fn the_embedded_default_scene_parses() {
        let s = Scene::default_scene();
        assert!(s.lights.len() >= 2);
        assert!(
            s.meshes
                .iter()
                .all(|m| !matches!(m.shape, ShapeSpec::Obj { .. }))
        );
    }

    fn expect_err(text: &str, key: &str, words: &str) {
        let e = parse(text).expect_err("must be rejected");
        let msg = e.to_string();
        assert!(msg.contains("test.toml"), "{msg}");
        assert!(msg.contains(key), "message should name key {key}: {msg}");
        assert!(msg.contains(words), "message should say {words}: {msg}");
    }

    #[test]
    fn invalid_values_name_file_key_and_expectation() {
        expect_err(
            &MINIMAL.replace("width = 64", "width = 0"),
            "image.width",
            "1 to 16384",
        );
        expect_err(
            &MINIMAL.replace("width = 64", "width = 100000"),
            "image.width",
            "16384",
        );
        expect_err(
            &MINIMAL.replace("slabs = 16", "slabs = 0"),
            "sweep.slabs",
            "1 to",
        );
        expect_err(
            &MINIMAL.replace("slabs = 16", "slab_distance = 0.0"),
            "sweep.slab_distance",
            "> 0",
        );
        expect_err(
            &MINIMAL.replace("slabs = 16", ""),
            "sweep.slabs",
            "expected one of",
        );
        expect_err(
            &format!("{MINIMAL}\n[[light]]\ntilt_deg = [90.0, 0.0]\n"),
            "light[0].tilt_deg[0]",
            "< 90",
        );
        expect_err(
            &format!("{MINIMAL}\n[[light]]\nvariance = [-1.0, 0.0]\n"),
            "light[0].variance[0]",
            ">= 0",
        );
        expect_err(
            &MINIMAL.replace("size = [1.0, 1.0, 1.0]", "size = [1.0, 0.0, 1.0]"),
            "mesh[0].size[1]",
            "> 0",
        );
        expect_err(
            &MINIMAL.replace("material = \"m\"", "material = \"x\""),
            "mesh[0].material",
            "no material named",
        );
        expect_err(
            &MINIMAL.replace("view_width = 2.0", "view_width = nan"),
            "camera.view_width",
            "finite",
        );
        expect_err(
            &MINIMAL.replace("view_width = 2.0", "view_width = inf"),
            "camera.view_width",
            "finite",
        );
        expect_err(
            &MINIMAL.replace("shape = \"box\"", "shape = \"cone\""),
            "mesh[0].shape",
            "expected one of",
        );
        expect_err(
            &MINIMAL.replace("slabs = 16", "slabs = 16\nkernel = \"blur\""),
            "sweep.kernel",
            "ellipse",
        );
    }

    #[test]
    fn syntax_unknown_keys_and_wrong_types_are_errors() {
        expect_err(
            &MINIMAL.replace("height = 32", "height = 32\ncolour = 3"),
            "",
            "unknown field `colour`",
        );
        expect_err(
            &MINIMAL.replace("height = 32", "height = \"tall\""),
            "height",
            "line 4",
        );
        // Without the [camera] header its key lands in [image]: an unknown field there.
        let e = parse(&MINIMAL.replace("[camera]\n", "")).unwrap_err();
        assert!(e.to_string().contains("unknown field `view_width`"), "{e}");
        // Without the whole table: a missing required table.
        let e = parse(&MINIMAL.replace("[camera]\nview_width = 2.0\n", "")).unwrap_err();
        assert!(e.to_string().contains("missing field `camera`"), "{e}");
    }
}
