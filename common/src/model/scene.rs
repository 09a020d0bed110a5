//! Scene files (TOML) parsed into a typed, validated model.
//!
//! The schema is documented in `docs/scene-format.md`. Parsing is strict: unknown keys, wrong
//! types, missing required keys and invalid values are errors naming the file, the key and what
//! was expected.
//! The scene model: what a scene file says, typed and validated (`model::parse` reads the TOML
//! and checks every value), with its limits and the spec enums the stages read.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::model::display::DisplayMap;
use crate::model::display::Tonemap;
use crate::model::kernel::KernelSpec;
use glam::DVec3;

mod point;
pub use point::{PointLight, SpotCone};

/// Largest accepted image width or height in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Largest accepted |exposure| in stops (2^64 is far past any useful brightening).
pub const MAX_EXPOSURE_STOPS: f64 = 64.0;
/// Largest accepted slab count.
pub const MAX_SLABS: u32 = 65536;
/// Smallest and largest accepted `sweep.slab_factor` (the modulation of `slabs = "auto"`).
pub const SLAB_FACTOR_RANGE: (f64, f64) = (1.0 / 1024.0, 1024.0);

/// Range of `sweep.light_resolution`: the light grid's cells per image pixel.
pub const LIGHT_RESOLUTION_RANGE: (f64, f64) = (1.0 / 16.0, 16.0);
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
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../../scenes/default.toml");
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
    /// The camera (orthographic or perspective).
    pub camera: CameraSpec,
    /// Slab sweep parameters.
    pub sweep: SweepSpec,
    /// Distant Gaussian lights (at least one; a scene without `[[light]]` gets one white light).
    pub lights: Vec<LightSpec>,
    /// Meshes in scene order (which also resolves overlapping materials: first wins).
    pub meshes: Vec<MeshSpec>,
    /// Materials, indexed by `MeshSpec::material`.
    pub materials: Vec<MaterialSpec>,
    /// The pass of the lights from in front of the viewer ([`Scene::passes`]): the camera is
    /// turned round, so the sweep runs towards the viewer, who is at its far end (compositing
    /// back to front, shading for a viewer along +z). False for every scene as parsed.
    pub turned_round: bool,
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

/// The camera: orthographic (parallel rays along `direction`) or perspective (rays from the eye
/// at `center`, [`Projection::Perspective`]).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSpec {
    /// View direction (normalized); perspective: from the eye towards `look_at`.
    pub direction: [f64; 3],
    /// World direction shown at the top of the image.
    pub up: [f64; 3],
    /// Centre of the view; perspective: the eye.
    pub center: [f64; 3],
    /// World units across the image; perspective: across the image at the `look_at` distance
    /// (`2·d·tan(fov/2)·width/height`), the scale host code that needs one length per pixel
    /// takes.
    pub view_width: f64,
    /// How rays leave the image.
    pub projection: Projection,
}

/// `camera.projection`: how the camera's rays leave the image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Projection {
    /// Parallel rays along the view direction, `view_width` world units across the image.
    #[default]
    Orthographic,
    /// Rays from the eye (`camera.eye`, kept as [`CameraSpec::center`]) through each pixel.
    Perspective {
        /// The point looked at (`camera.look_at`): the view direction points at it.
        look_at: [f64; 3],
        /// The vertical field of view in degrees, in [`MIN_FOV_DEG`, `MAX_FOV_DEG`].
        fov_deg: f64,
        /// The view depth where the sweep starts (`camera.near`), if given; every mesh must lie
        /// beyond it.
        near: Option<f64>,
    },
}

/// The narrowest vertical field of view a perspective camera takes, in degrees.
pub const MIN_FOV_DEG: f64 = 1.0;
/// The widest vertical field of view a perspective camera takes, in degrees.
pub const MAX_FOV_DEG: f64 = 170.0;

impl CameraSpec {
    /// Whether rays leave the eye in perspective.
    pub fn is_perspective(&self) -> bool {
        matches!(self.projection, Projection::Perspective { .. })
    }

    /// The camera's world basis `[right, down, forward]` (camera x, y, z): forward the view
    /// direction, down opposite the part of `up` across the view, right = down × forward.
    pub fn basis(&self) -> [DVec3; 3] {
        frame(DVec3::from(self.direction), DVec3::from(self.up))
    }

    /// A world-space light ([`WorldLight`]) as the sweep takes it, on the slab plane: its tilt
    /// (ωx, ωy) with its camera-space travel ∝ (−tan ωx, −tan ωy, 1), and the covariance of its directions' slopes per unit depth,
    /// `J·R(α)·diag(σx², σy²)·R(α)ᵀ·Jᵀ` with J the derivative of the slope (camera x/z, y/z) by
    /// small turns of the direction along the light's own axes ([`frame`] of its direction and
    /// `up`), as `(variance, rotation_deg)`. Along the view with the camera's own `up`, J = 1 and
    /// the light keeps its numbers.
    /// A light travelling towards the viewer (more than 90° from the view direction) is taken
    /// as the camera turned round sees it ([`CameraSpec::turned_round`]), with `toward_viewer`
    /// set. `Err` with its travel's angle to the view direction, in degrees, where that is 90°
    /// (a light travelling along the slab planes: no sweep order suits it).
    pub fn light_on_slabs(&self, light: &WorldLight) -> Result<SlabLight, f64> {
        let travel = DVec3::from(light.direction).dot(DVec3::from(self.direction));
        if travel < 0.0 {
            let on_slabs = self.turned_round().light_on_slabs(light)?;
            return Ok(SlabLight {
                toward_viewer: true,
                ..on_slabs
            });
        }
        let [right, down, forward] = self.basis();
        let camera = |v: DVec3| DVec3::new(v.dot(right), v.dot(down), v.dot(forward));
        let [u, v, d] = frame(DVec3::from(light.direction), DVec3::from(light.up)).map(camera);
        let tilt_deg = tilt_of_travel(camera(DVec3::from(light.direction)))?;
        if [u, v, d] == [DVec3::X, DVec3::Y, DVec3::Z] {
            // The light's frame is the camera's (along the view, the camera's up): J = 1, and
            // its numbers are the slab plane's, bit for bit.
            return Ok(SlabLight {
                tilt_deg,
                variance: light.variance,
                rotation_deg: light.rotation_deg,
                toward_viewer: false,
            });
        }
        let (s, c) = light.rotation_deg.to_radians().sin_cos();
        let slope = |a: DVec3| {
            [
                (a.x * d.z - d.x * a.z) / (d.z * d.z),
                (a.y * d.z - d.y * a.z) / (d.z * d.z),
            ]
        };
        let (j1, j2) = (slope(u * c + v * s), slope(v * c - u * s));
        let [vx, vy] = light.variance;
        let cov = |p: usize, q: usize| vx * j1[p] * j1[q] + vy * j2[p] * j2[q];
        let (xx, yy, xy) = (cov(0, 0), cov(1, 1), cov(0, 1));
        if xy == 0.0 {
            return Ok(SlabLight {
                tilt_deg,
                variance: [xx, yy],
                rotation_deg: 0.0,
                toward_viewer: false,
            });
        }
        let alpha = 0.5 * (2.0 * xy).atan2(xx - yy);
        let (sa, ca) = alpha.sin_cos();
        let major = xx * ca * ca + 2.0 * xy * sa * ca + yy * sa * sa;
        let minor = xx * sa * sa - 2.0 * xy * sa * ca + yy * ca * ca;
        Ok(SlabLight {
            tilt_deg,
            variance: [major.max(0.0), minor.max(0.0)],
            rotation_deg: alpha.to_degrees(),
            toward_viewer: false,
        })
    }

    /// The camera turned round: the same centre, view width and `up`, looking the other way.
    /// Its x axis is the image's, mirrored (its pixel column i is the image's W − 1 − i); its
    /// rows and pixel centres are the image's.
    pub fn turned_round(&self) -> CameraSpec {
        CameraSpec {
            direction: self.direction.map(|c| -c),
            ..*self
        }
    }
}

/// The tilt (ωx, ωy) in degrees of a light travelling along `(x, y, z)` in camera space (∝
/// (−tan ωx, −tan ωy, 1)), or `Err` with its angle to the view direction where that is ≥ 90°
/// (only 90° reaches it from [`CameraSpec::light_on_slabs`]).
fn tilt_of_travel(t: DVec3) -> Result<[f64; 2], f64> {
    let (x, y, z) = (t.x, t.y, t.z);
    if z <= 0.0 {
        return Err(z.clamp(-1.0, 1.0).acos().to_degrees());
    }
    // `+ 0.0`: a light along the view gets tilt +0, not −0 (the bits of `tilt_deg = [0, 0]`).
    Ok([
        (-x / z).atan().to_degrees() + 0.0,
        (-y / z).atan().to_degrees() + 0.0,
    ])
}

/// The right-handed frame `[right, down, forward]` of a view or light direction `forward` and an
/// `up` not parallel to it: down is opposite the part of `up` across `forward`, right = down ×
/// forward (the camera's axes, and a world-space light's own axes).
pub fn frame(forward: DVec3, up: DVec3) -> [DVec3; 3] {
    let forward = forward.normalize();
    let down = -(up - forward * up.dot(forward)).normalize();
    // Right-handed frame: right × down = forward.
    let right = down.cross(forward);
    [right, down, forward]
}

/// A light given in world space (`[[light]] direction`): what it keeps when the camera turns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldLight {
    /// The world direction it travels (unit).
    pub direction: [f64; 3],
    /// The world direction its own frame's "up" follows (unit, not parallel to `direction`).
    pub up: [f64; 3],
    /// Variances (σx², σy²) of its directions along its own right and down axes, per unit
    /// distance.
    pub variance: [f64; 2],
    /// Rotation of its principal axes from its right axis towards its down axis, degrees.
    pub rotation_deg: f64,
}

/// A light on the slab plane, as the sweep takes every light (`LightSpec`'s tilt and spread).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlabLight {
    /// Tilt (ωx, ωy), degrees.
    pub tilt_deg: [f64; 2],
    /// Variances along the principal axes, per unit depth.
    pub variance: [f64; 2],
    /// Rotation of the principal axes, degrees.
    pub rotation_deg: f64,
    /// The light travels towards the viewer (more than 90° from the view direction): the
    /// numbers above are those the camera turned round sees ([`Scene::passes`]).
    pub toward_viewer: bool,
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
    /// (see `crate::prepare::auto_slabs`).
    Auto,
}

/// How a light's kernel grows from slab to slab (`sweep.penumbra`; docs/accuracy.md).
///
/// The default is `Distance`: against closed forms and the shadow-ray reference it has the lower
/// error on every case measured (docs/accuracy.md) at about 1.5× the iterated mode's sweep time
/// on the default scene, within the 2× that the distance mode was allowed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Penumbra {
    /// The paper's model: the same kernel every slab, covariance d1·e·Σl, so after distance d the
    /// penumbra has covariance d·d1·Σl: right at d = d1 only.
    Iterated,
    /// The kernel follows each pixel's mean occluder depth z̄: covariance ((h+1)² − h²)·e²·Σl at
    /// h = (z − z̄)/e slabs, so a single occluder's penumbra has (z − z̄)²·Σl at every distance.
    #[default]
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

/// How a slab of translucent medium is composited (`sweep.media`; docs/accuracy.md,
/// "Translucent media").
///
/// The default is `SecondOrder`: its error against the exact volume integral falls like e²
/// (measured order 1.9–2.0), the first-order model's like e.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Media {
    /// The paper's slab: opacity α and light attenuation `1 − α·(1 − τ)` of a whole slab
    /// wherever the pixel's slab meets a medium, shaded with the light at the slab's front.
    FirstOrder,
    /// A slab lets through the medium's exact transmittance `(1 − α)^(1 − τ)`; a medium's entry
    /// and exit slabs count only the part inside it; the shaded light is the light at the
    /// shading point.
    #[default]
    SecondOrder,
}

impl fmt::Display for Media {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Media::FirstOrder => "first-order",
            Media::SecondOrder => "second-order",
        })
    }
}

impl std::str::FromStr for Media {
    type Err = String;

    /// `first-order` or `second-order`.
    fn from_str(s: &str) -> Result<Media, String> {
        match s {
            "first-order" => Ok(Media::FirstOrder),
            "second-order" => Ok(Media::SecondOrder),
            _ => Err(format!(
                "expected \"second-order\" or \"first-order\", got {s:?}"
            )),
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
    /// How slabs of translucent medium are composited.
    pub media: Media,
    /// Distance penumbra: a crossed surface that blocks light reads its light at the exact
    /// sub-pixel shift from its mean occluder, not the whole pixels the sweep carries the light's
    /// drift in (`sweep.subpixel_shadows`, default on; docs/how-it-works.md).
    pub subpixel_shadows: bool,
    /// A held surface's light is read only from its lit side (`sweep.held_lit_side`, default
    /// off: the images of before, bit for bit): a gather reads no light from a pixel held behind
    /// a surface when it lies behind that surface itself (docs/how-it-works.md, "Who reads the
    /// held light").
    pub held_lit_side: bool,
    /// A released surface's pixels serve the light they gathered in their release slab to
    /// gathers on the same surface for a few slabs (`sweep.served_releases`, default on; off:
    /// the images of before 2026-12-08, bit for bit; docs/how-it-works.md, "Released light
    /// served on its own surface").
    pub served_releases: bool,
    /// At an opaque crossing, the part of each light below the surface's tangent plane is
    /// blocked (`sweep.horizon`, default on; off: the images of before 2026-12-07, bit for bit;
    /// docs/how-it-works.md, "The horizon").
    pub horizon: bool,
    /// The light grid's cells per image pixel (a perspective camera's: per pixel at the
    /// `look_at` distance; `sweep.light_resolution`, 1/16–16, default 1). At 1 an orthographic
    /// camera sweeps its light on its image's pixels; at any other value it gets a grid of its
    /// own, read by the eye's rays, as a perspective camera always does. Below 1 faster (soft
    /// shadows rarely need the image's resolution), above 1 sharper shadow edges.
    pub light_resolution: f64,
}

/// A distant Gaussian light: from behind the viewer, or (a world-space light with
/// `toward_viewer`) from in front of it.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSpec {
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Tilt angles (ωx, ωy) in degrees, each |ω| < 90: given (`tilt_deg`, camera space), or
    /// derived from `direction` and the camera ([`CameraSpec::light_on_slabs`]).
    pub tilt_deg: [f64; 2],
    /// The light as the scene gives it in world space (`direction`, `up`, and its own
    /// `variance` and `rotation_deg`), when it does: `tilt_deg`, `variance` and `rotation_deg`
    /// above are derived from it and the camera ([`CameraSpec::light_on_slabs`]), again when
    /// the camera turns (`Scene::override_camera`), so the light stays put in the world.
    pub world: Option<WorldLight>,
    /// Variances (σx², σy²) on the virtual light plane (parallel to the slabs) at unit distance.
    pub variance: [f64; 2],
    /// Rotation α of the principal axes, degrees.
    pub rotation_deg: f64,
    /// A gobo: an image that is the light's initial light buffer (see `convshadow_io::pattern`).
    pub pattern: Option<PatternSpec>,
    /// A world-space light travelling towards the viewer (more than 90° from the view): it is
    /// swept in the scene's turned-round pass ([`Scene::passes`]), and `tilt_deg`, `variance`
    /// and `rotation_deg` are those the turned-round camera sees.
    pub toward_viewer: bool,
    /// A point or spot light (`kind = "point" | "spot"`): its place, size and cone. Its tilt is
    /// then 0 and its variance 0 (they describe directional lights only): the CPU sweep renders
    /// it on a grid of its own (`src/pipeline/point.rs`), the shadow-ray reference anywhere.
    pub point: Option<PointLight>,
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
    /// A mesh file (`shape = "obj"` or `"file"`): Wavefront OBJ, PLY, glTF 2.0 or STL, the
    /// format chosen by the path's extension (`MeshFormat::from_path`).
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
    /// An OpenVDB file (`.vdb`): one float grid by name, its active bounding box in index space
    /// fitted into the bounds with the aspect of its voxel size; held sparse (8³ bricks).
    Vdb {
        /// The grid's name in the file (`grid = "density"`).
        grid: String,
    },
}

/// How a material shades the light at a crossed opaque surface (`surface = "flat" | "lambert"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SurfaceModel {
    /// The medium's model everywhere: colour × light, no dependence on the surface normal.
    Flat,
    /// Colour × light × max(0, n·l) where the shading point is a crossed surface whose slab
    /// opacity is exactly 1 (an opaque crossing); volume samples and translucent crossings keep
    /// the flat (purely diffuse, paper §4.2) model. The default.
    #[default]
    Lambert,
}

/// The specular model of a material's highlight (`specular.model`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpecularModel {
    /// `strength · max(0, n·h)^exponent` (the default, and the meaning of a `specular` table
    /// without `model`).
    BlinnPhong,
    /// The isotropic Ashikmin–Shirley (2000) microfacet lobe with Schlick's Fresnel term:
    /// `strength · (e + 1)/(8π) · (n·h)^e / ((h·k)·max(n·l, n·v)) · F(h·k) · (n·l)`, where
    /// `F(x) = f0 + (1 − f0)(1 − x)^5`.
    AshikminShirley {
        /// Reflectance at normal incidence, 0–1.
        f0: f32,
    },
}

/// `specular.f0` of an Ashikmin–Shirley highlight when not given: 0.04, the reflectance at
/// normal incidence of a dielectric of refractive index 1.5 (((n − 1)/(n + 1))²).
pub const DEFAULT_F0: f64 = 0.04;

/// A specular highlight at crossed surfaces.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecularSpec {
    /// Which model.
    pub model: SpecularModel,
    /// Multiplier of the highlight.
    pub strength: f32,
    /// The lobe's exponent (Blinn–Phong's, or Ashikmin–Shirley's n_u = n_v; evaluated by
    /// repeated squaring).
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
    /// The diffuse model at crossed opaque surfaces.
    pub surface: SurfaceModel,
    /// Henyey–Greenstein asymmetry g of the medium's scattering (0 = isotropic, > 0 forward,
    /// < 0 backward); with distant lights and an orthographic camera the phase function is one
    /// constant per light, applied to the light's colour in shading (not to the specular term).
    pub phase_g: f64,
}

/// Whether `path` names a NIfTI file (`.nii` or `.nii.gz`, any case).
pub fn is_nifti_path(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    name.ends_with(".nii") || name.ends_with(".nii.gz")
}

/// Whether `path` names an OpenVDB file (`.vdb`, any case).
pub fn is_vdb_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("vdb"))
}

// ---------------------------------------------------------------------------------------------
// Spec enums the stages read.

/// Which detail function.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DetailKind {
    /// One octave of improved Perlin noise, `0.5 + 0.5·n`.
    Perlin,
    /// Fractional Brownian motion, `0.5 + 0.5·(Σ a_i n_i)·inv_amplitude_sum`.
    Fbm,
    /// Musgrave ridged multifractal (offset 1, weight = previous signal clamped to [0, 1]).
    Ridged,
    /// Perlin turbulence, `(Σ a_i |n_i|)·inv_amplitude_sum`.
    Turbulence,
}

/// Voxel format of a raw 3D texture file (little-endian, x fastest, then y, then z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VoxelType {
    /// Unsigned 8-bit, normalised by 1/255.
    U8,
    /// Unsigned 16-bit little-endian, normalised by 1/65535.
    U16,
    /// IEEE f32 little-endian, used as stored (must be finite).
    F32,
}

impl VoxelType {
    /// Bytes per voxel.
    pub fn bytes(self) -> u64 {
        match self {
            VoxelType::U8 => 1,
            VoxelType::U16 => 2,
            VoxelType::F32 => 4,
        }
    }
}

impl fmt::Display for VoxelType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            VoxelType::U8 => "u8",
            VoxelType::U16 => "u16",
            VoxelType::F32 => "f32",
        })
    }
}

/// How the scene asks for its guard band (`sweep.guard_band`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GuardBandSpec {
    /// Sized per side from the lights, the scene's depth and the meshes' projected bounds.
    #[default]
    Auto,
    /// The same number of pixels on every side (0: no band).
    Pixels(u32),
}

impl fmt::Display for GuardBandSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GuardBandSpec::Auto => f.write_str("auto"),
            GuardBandSpec::Pixels(g) => write!(f, "{g}"),
        }
    }
}

impl std::str::FromStr for GuardBandSpec {
    type Err = String;

    /// `auto` or a pixel count 0–[`MAX_GUARD_BAND`].
    fn from_str(s: &str) -> Result<GuardBandSpec, String> {
        if s == "auto" {
            return Ok(GuardBandSpec::Auto);
        }
        match s.parse::<u32>() {
            Ok(g) if g <= MAX_GUARD_BAND => Ok(GuardBandSpec::Pixels(g)),
            _ => Err(format!(
                "expected \"auto\" or a pixel count 0 to {MAX_GUARD_BAND}, got {s:?}"
            )),
        }
    }
}

/// A scene split by the end of the sweep its lights need ([`Scene::passes`]).
#[derive(Clone, Debug)]
pub struct ScenePasses {
    /// The lights from behind the viewer, swept away from it.
    pub front: Option<Scene>,
    /// The lights from in front of the viewer, swept towards it (the camera turned round).
    pub back: Option<Scene>,
}

impl ScenePasses {
    /// Light `l` of the scene as (pass, index in that pass): 0 = front, 1 = back.
    pub fn light(&self, scene: &Scene, l: usize) -> (usize, usize) {
        let toward = scene.lights[l].toward_viewer;
        let index = scene.lights[..l]
            .iter()
            .filter(|o| o.toward_viewer == toward)
            .count();
        (usize::from(toward), index)
    }
}

impl Scene {
    /// Whether every material's transport is grey and no light has a pattern (which may be
    /// coloured), so one light-buffer channel suffices.
    pub fn is_monochrome(&self) -> bool {
        self.lights.iter().all(|l| l.pattern.is_none())
            && self
                .materials
                .iter()
                .all(|m| m.transport[0] == m.transport[1] && m.transport[1] == m.transport[2])
    }

    /// The scene as the sweeps take it: one pass per end the lights need the sweep to start
    /// from. `front` has the lights from behind the viewer (`None` when there is none), `back`
    /// the lights travelling towards the viewer, its camera turned round
    /// ([`CameraSpec::turned_round`], [`Scene::turned_round`]; `None` when there is none). The
    /// image is linear in each light, so the image is front's plus back's mirrored in x; the
    /// background is composited once, in `front` when there is one (back's is then black).
    /// Each pass numbers its lights in scene order.
    pub fn passes(&self) -> ScenePasses {
        let with_lights = |toward: bool| -> Option<Scene> {
            let lights: Vec<LightSpec> = self
                .lights
                .iter()
                .filter(|l| l.toward_viewer == toward)
                .cloned()
                .collect();
            (!lights.is_empty()).then(|| Scene {
                lights,
                ..self.clone()
            })
        };
        let front = with_lights(false);
        let back = with_lights(true).map(|mut s| {
            s.camera = s.camera.turned_round();
            s.turned_round = true;
            if front.is_some() {
                s.image.background = [0.0; 3];
            }
            s
        });
        ScenePasses { front, back }
    }

    /// Every file the scene reads, with the key that names it (`mesh[0].path`,
    /// `material.NAME.texture.path`, `light[0].pattern.path`), in scene order: an output of the
    /// run must not replace one of them.
    pub fn input_files(&self) -> Vec<(String, &Path)> {
        let mut files: Vec<(String, &Path)> = Vec::new();
        for (i, m) in self.meshes.iter().enumerate() {
            if let ShapeSpec::Obj { path } = &m.shape {
                files.push((format!("mesh[{i}].path"), path));
            }
        }
        for m in &self.materials {
            if let Some(t) = &m.texture {
                files.push((format!("material.{}.texture.path", m.name), &t.path));
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            if let Some(p) = &l.pattern {
                files.push((format!("light[{i}].pattern.path"), &p.path));
            }
        }
        files
    }
}

#[cfg(test)]
mod tests;
