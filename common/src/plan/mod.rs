//! The render plan: every table the sweep reads, computed once on the host and
//! shared by the scalar path, the SIMD path and the GPU port.
//!
//! Nothing per pixel calls a transcendental: kernel taps, slab hashes, the slab-thickness opacity
//! correction `α_slab = 1 − (1 − α)^(e/e_ref)`, attenuation factors and specular half vectors are
//! all here.

pub mod kernel;
pub mod levels;
pub mod pattern;
pub mod surface_hold;

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use rayon::prelude::*;

use crate::contract::files::{PlanFiles, TextureFile};
use crate::model::scene::{
    MaterialSpec, Penumbra, Scene, SpecularModel, SpecularSpec, SurfaceModel,
};
use crate::pixel::hash::{JITTER_STREAM, slab_hash};
use crate::pixel::{noise::Detail, texture3d::TextureError, volume::Volume};
use crate::plan::kernel::{
    KernelMoments, KernelTable, TableGuard, build_distance_table, build_table,
};
use crate::prepare::geometry::SceneGeometry;
use crate::prepare::guard::GuardBand;

/// Entries of a material's transfer-function table over detail values [0, 1].
pub const TF_SIZE: usize = 256;
/// Entries per axis of a pre-integration table: detail values [0, 1] at a slab's front face
/// × at its back face (see [`MaterialPlan::pre`]).
pub const PI_SIZE: usize = 128;
/// Sub-steps per unit of detail value when a pre-integration entry is integrated on the host:
/// a segment from front value `f` to back value `b` is cut into ⌈|b − f| · 512⌉ (at least
/// [`PI_MIN_STEPS`]) thin slabs of constant value, so a gradient feature 0.05 wide gets at least
/// 25.
pub const PI_STEPS_PER_UNIT: f64 = 512.0;
/// The fewest thin slabs a pre-integration entry is integrated over, also for a constant value
/// (`front == back`): the slab's self-shadowing is integrated alike everywhere in the table.
pub const PI_MIN_STEPS: f64 = 16.0;
/// The length a material's opacity is given for when it sets no `reference_length`: one world
/// unit, so that opacity is per unit length (as extinction is in Mitsuba or pbrt) and a material
/// looks the same at any slab count. (It was the slab distance, which made the same material
/// more opaque the fewer the slabs.)
pub const DEFAULT_REFERENCE_LENGTH: f64 = 1.0;
/// Light values below this are flushed to zero after attenuation (no subnormals, same zeros on
/// CPU and GPU); products with tap weights (≥ 2^-24) then stay far above f32's normal range.
pub const FLUSH_BELOW: f32 = 1.0e-20;

/// Distance penumbra: a pixel whose occluded light (channels − Σ light) is at most this has no
/// mean occluder depth to speak of (D / u would be rounding noise) and gathers through the
/// smallest kernel. 2^-16: the quotient's error from u's rounding stays below 0.1 %.
pub const OCCLUSION_EPS: f32 = 1.0 / 65536.0;

/// Distance penumbra: the level plane's value at a pixel with no occluder (every level is
/// smaller, so a minimum over a footprint ignores it).
pub const LIT_LEVEL: u32 = u32::MAX;

/// One transfer-function entry: colour, slab opacity, and per-channel attenuation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TfEntry {
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Opacity of one slab, `1 − (1 − α)^(e/e_ref)`.
    pub alpha: f32,
    /// Light attenuation per channel, `1 − α_slab·(1 − τ)`.
    pub attenuation: [f32; 3],
}

/// A material's per-render tables.
#[derive(Clone, Debug)]
pub struct MaterialPlan {
    /// Transfer function: `TF_SIZE` entries for detail materials, 1 for constant ones.
    pub tf: Vec<TfEntry>,
    /// With `sweep.preintegration`, for detail materials: the pre-integrated table, `PI_SIZE ×
    /// PI_SIZE` entries at `front · PI_SIZE + back` (front and back the detail values at the
    /// slab's faces, `i / (PI_SIZE − 1)`): the colour, opacity and attenuation of one slab whose
    /// detail varies linearly from front to back ([`preintegrated_entry`]). `None`: one sample.
    pub pre: Option<Vec<TfEntry>>,
    /// Procedural detail, if any.
    pub detail: Option<Detail>,
    /// 3D texture, if any (dense, or bricked: OpenVDB; sampled at normalised object coordinates).
    pub texture: Option<Arc<Volume>>,
    /// The texture's physical extent (NIfTI: dims · spacing, OpenVDB: dims · voxel size), whose
    /// aspect its mapping keeps; `None` (raw textures): stretched to the mesh's bounds.
    pub texture_extent: Option<[f64; 3]>,
    /// The specular highlight at crossed surfaces, if any.
    pub specular: Option<SpecularPlan>,
    /// Whether crossed opaque surfaces are shaded with the Lambert cosine (`surface =
    /// "lambert"`); false: flat (the medium's model everywhere).
    pub lambert: bool,
    /// Per light: the light's colour times this material's phase function at the light's
    /// scattering angle ([`phase_factor`]); exactly the light's colour for an isotropic medium
    /// (g = 0). Shading sums `Iin ⊙ light_color`; the specular term uses the bare colour.
    pub light_color: Vec<[f32; 3]>,
}

impl MaterialPlan {
    /// Whether every slab of this material takes out all light: attenuation exactly 0 in every
    /// channel of every transfer-function entry (and pre-integrated entry). Such a material's
    /// surfaces are held ([`RenderPlan::surface_hold`]).
    pub fn blocks_light(&self) -> bool {
        let blocks = |t: &TfEntry| t.attenuation == [0.0; 3];
        self.tf.iter().all(blocks) && self.pre.iter().flatten().all(blocks)
    }
}

/// A material's specular highlight, as the shading stage evaluates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularPlan {
    /// Which model.
    pub model: SpecularModel,
    /// The factor in front of the lobe: Blinn–Phong's strength; for Ashikmin–Shirley the
    /// strength times the normalisation (e + 1)/(8π), computed in f64.
    pub scale: f32,
    /// The lobe's exponent (repeated squaring).
    pub exponent: u32,
    /// Ashikmin–Shirley: reflectance at normal incidence (Schlick's Fresnel term); 0 for
    /// Blinn–Phong.
    pub f0: f32,
}

impl SpecularPlan {
    /// The plan of a material's `specular` table.
    pub fn new(s: &SpecularSpec) -> SpecularPlan {
        match s.model {
            SpecularModel::BlinnPhong => SpecularPlan {
                model: s.model,
                scale: s.strength,
                exponent: s.exponent,
                f0: 0.0,
            },
            SpecularModel::AshikminShirley { f0 } => SpecularPlan {
                model: s.model,
                scale: (f64::from(s.strength) * (f64::from(s.exponent) + 1.0)
                    / (8.0 * std::f64::consts::PI)) as f32,
                exponent: s.exponent,
                f0,
            },
        }
    }
}

/// The Ashikmin–Shirley constants of a light whose half vector `h` and direction towards the
/// light `to_light` are given (camera space, unit length): with k = l (h·l = h·v), Schlick's
/// F(h·k)/(h·k) = p/(h·k) + f0·(1 − p)/(h·k), p = (1 − h·k)^5; returns [p/(h·k), (1 − p)/(h·k)]
/// (f64 on the host; the shading stage forms `scale · (b + f0·c)` in f32).
pub fn fresnel_terms(h: DVec3, to_light: DVec3) -> [f32; 2] {
    let hk = h.dot(to_light);
    let p = (1.0 - hk).powi(5);
    [(p / hk) as f32, ((1.0 - p) / hk) as f32]
}

/// A light's per-render tables.
#[derive(Clone, Debug)]
pub struct LightPlan {
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Kernel moments per slab (pixels); for the distance penumbra, those of its smallest level
    /// (an occluder one slab in front).
    pub moments: KernelMoments,
    /// The tap table.
    pub table: KernelTable,
    /// Per slab: hash of (seed, light, slab), the prefix of every per-pixel phase hash.
    pub slab_hash: Vec<u32>,
    /// Blinn–Phong half vector in camera space (towards light + towards viewer, normalised).
    pub half_vector: [f32; 3],
    /// Unit direction towards the light in camera space, (tan ωx, tan ωy, −1)/‖·‖: the `l` of
    /// the Lambert cosine and of Ashikmin–Shirley (the mean direction of an area light).
    pub to_light: [f32; 3],
    /// Ashikmin–Shirley's Fresnel-over-(h·k) constants ([`fresnel_terms`]).
    pub fresnel: [f32; 2],
}

/// cos θ of the scattering angle of a distant light with tilt `tilt_deg` towards an orthographic
/// camera: θ is the angle between the light's propagation direction, ∝ (−tan ωx, −tan ωy, 1) in
/// camera space, and the direction to the camera, (0, 0, −1); so cos θ = −1/√(1 + tan²ωx +
/// tan²ωy) (−1 for a light straight behind the viewer: back-scattering).
pub fn scattering_cos(tilt_deg: [f64; 2]) -> f64 {
    let [mx, my] = tilt_deg.map(|t| t.to_radians().tan());
    -1.0 / (1.0 + mx * mx + my * my).sqrt()
}

/// The Henyey–Greenstein phase function normalised to 1 for an isotropic medium:
/// `(1 − g²) / (1 + g² − 2g·cos θ)^{3/2}` (its 1/4π dropped, so g = 0 gives exactly 1).
pub fn henyey_greenstein(g: f64, cos_theta: f64) -> f64 {
    if g == 0.0 {
        return 1.0;
    }
    (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta).powf(1.5)
}

/// The phase factor of a medium of asymmetry `g` lit by a light of tilt `tilt_deg`.
pub fn phase_factor(g: f64, tilt_deg: [f64; 2]) -> f64 {
    henyey_greenstein(g, scattering_cos(tilt_deg))
}

/// Errors while planning: a material's 3D texture or a light's pattern that cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("{scene}: {what}: {source}")]
pub struct PlanError {
    /// Scene file.
    pub scene: String,
    /// What failed: "material `NAME`" (a 3D texture) or "key `light[i].pattern.path`".
    pub what: String,
    /// The loader's error (names the file).
    pub source: TextureError,
}

/// Everything the sweep needs besides the LDI.
#[derive(Clone, Debug)]
pub struct RenderPlan {
    /// Grid width (image + left and right guard band).
    pub grid_width: u32,
    /// Grid height (image + top and bottom guard band).
    pub grid_height: u32,
    /// Guard band per side, as resolved by the geometry (`geometry.raster.guard`): image pixel
    /// (x, y) is grid pixel (x + left, y + top).
    pub guard: GuardBand,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Slab count.
    pub slabs: u32,
    /// How `slabs = "auto"` chose the count (`None` when the scene gave it).
    pub auto_slabs: Option<crate::prepare::auto_slabs::AutoSlabs>,
    /// Pixel size (world units).
    pub pixel_size: f64,
    /// Slab thickness (world units) as f32.
    pub slab_distance: f32,
    /// Front face of each slab (depth relative to the first slab's front).
    pub slab_front: Vec<f32>,
    /// Back face of each slab.
    pub slab_back: Vec<f32>,
    /// Light-buffer channels: 1 when every transport colour is grey, else 3.
    pub channels: u32,
    /// How the kernels grow with depth. With [`Penumbra::Distance`] each light's buffer has one
    /// more plane after its channels: the occlusion-weighted occluder depth D (in slabs), so that
    /// the mean occluder depth is D / (channels − Σ light).
    pub penumbra: Penumbra,
    /// Lights.
    pub lights: Vec<LightPlan>,
    /// Materials.
    pub materials: Vec<MaterialPlan>,
    /// Material of each mesh.
    pub mesh_material: Vec<u32>,
    /// Per mesh: (image pixel x, image pixel y, relative depth) → detail coordinates, row-major
    /// 3×4. Image, not grid, pixels (negative inside the left and top guard band): a pixel's
    /// detail value then has the same bits whatever the band (see [`RenderPlan::image_xy`]).
    pub mesh_to_detail: Vec<[f32; 12]>,
    /// Jitter the shading point inside the slab.
    pub jitter: bool,
    /// Per slab: hash of (seed, jitter stream, slab).
    pub jitter_slab_hash: Vec<u32>,
    /// Background colour.
    pub background: [f32; 3],
    /// The light buffer before the first slab (`[row][light][channel][x]`, the sweep's input),
    /// when a light has a pattern; `None`: every light starts at 1.
    pub initial_light: Option<Vec<f32>>,
    /// Pre-integrated compositing (`sweep.preintegration`): materials with a
    /// [`MaterialPlan::pre`] table are shaded from their detail at the slab's faces, and the
    /// sweep keeps one more float per pixel (the next slab's front value).
    pub preintegration: bool,
    /// Per rasterized triangle (`RasterSetup::triangles`' order): how many slabs an opaque
    /// crossing of it keeps passing its pixel's light before removing it
    /// ([`surface_hold::surface_hold`]; 0: removed at the crossing).
    pub surface_hold: Vec<u32>,
}

impl RenderPlan {
    /// Builds all tables for a scene whose geometry is already set up, from its files as the
    /// host read them (`convshadow_io::read_plan_files`).
    pub fn new(
        scene: &Scene,
        geometry: &SceneGeometry,
        files: &PlanFiles,
    ) -> Result<RenderPlan, PlanError> {
        let plan = RenderPlan::new_guarded(scene, geometry, files, &TableGuard::unlimited())?;
        Ok(plan.expect("an unlimited guard never stops the tables"))
    }

    /// [`RenderPlan::new`], with the kernel tables built under `guard`: `Ok(None)` when it
    /// stopped them (cancelled, or past its byte limit; the guard says which).
    pub fn new_guarded(
        scene: &Scene,
        geometry: &SceneGeometry,
        files: &PlanFiles,
        guard: &TableGuard<'_>,
    ) -> Result<Option<RenderPlan>, PlanError> {
        let slabs = geometry.slabs;
        let e = geometry.slab_distance;
        let px = geometry.camera.pixel_size;
        let seed = scene.sweep.seed;
        // Lights are independent (their tables' bits do not depend on the thread count): built
        // in parallel, each with its levels in parallel (`build_distance_table`).
        let lights = scene
            .lights
            .par_iter()
            .enumerate()
            .map(|(l, spec)| {
                let moments_for = |d1: f64| {
                    KernelMoments::for_light(
                        spec.tilt_deg,
                        spec.variance,
                        spec.rotation_deg,
                        e,
                        d1,
                        px,
                    )
                };
                let compensate = scene.sweep.variance_compensation;
                let kernel = scene.sweep.kernel;
                let (moments, table) = match scene.sweep.penumbra {
                    Penumbra::Iterated => {
                        // Scene validation requires d1 with the iterated penumbra.
                        let moments = moments_for(scene.sweep.optimal_distance.unwrap_or(e));
                        if guard.stopped() {
                            return None;
                        }
                        let table = build_table(kernel, &moments, slabs, compensate);
                        let words = table.slab_phase.len() + 2 * table.slab_shift.len();
                        guard.charge(table.taps.len(), words);
                        (moments, table)
                    }
                    Penumbra::Distance => {
                        // A covariance step of f·e²·Σl is d1 = f·e in the iterated formula.
                        let per_e2 = |f: f64| moments_for(f * e);
                        let table =
                            build_distance_table(kernel, &per_e2, slabs, compensate, guard)?;
                        (per_e2(1.0), table)
                    }
                };
                let mu = spec.tilt_deg.map(|t| t.to_radians().tan());
                let to_light = DVec3::new(mu[0], mu[1], -1.0).normalize();
                let h = (to_light + DVec3::new(0.0, 0.0, -1.0)).normalize();
                Some(LightPlan {
                    color: spec.color.map(flush_tiny),
                    moments,
                    table,
                    slab_hash: (0..slabs).map(|k| slab_hash(seed, l as u32, k)).collect(),
                    half_vector: [h.x as f32, h.y as f32, h.z as f32],
                    to_light: [to_light.x as f32, to_light.y as f32, to_light.z as f32],
                    fresnel: fresnel_terms(h, to_light),
                })
            })
            .collect::<Option<Vec<LightPlan>>>();
        let Some(lights) = lights.filter(|_| !guard.stopped()) else {
            return Ok(None);
        };
        let materials = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let texture = files.textures.get(i).cloned().flatten();
                material_plan(m, e, scene.sweep.preintegration, texture).map_err(|source| {
                    PlanError {
                        scene: scene.source.clone(),
                        what: format!("material `{}`", m.name),
                        source,
                    }
                })
            })
            .collect::<Result<Vec<_>, PlanError>>()?;
        let mut materials = materials;
        for (plan, spec) in materials.iter_mut().zip(&scene.materials) {
            plan.light_color = scene
                .lights
                .iter()
                .map(|l| {
                    if spec.phase_g == 0.0 {
                        // Bit for bit the colour the shading used before phase functions.
                        l.color.map(flush_tiny)
                    } else {
                        let f = phase_factor(spec.phase_g, l.tilt_deg);
                        l.color.map(|c| flush_tiny((f64::from(c) * f) as f32))
                    }
                })
                .collect();
        }
        let mesh_to_detail = scene
            .meshes
            .iter()
            .zip(&geometry.meshes)
            .map(|(spec, wm)| {
                // Image pixel coordinates → world → object (→ texture).
                let cam = &geometry.camera;
                let origin = cam.pixel_to_world(0.0, 0.0, geometry.z_origin);
                let dx = cam.right * cam.pixel_size;
                let dy = cam.down * cam.pixel_size;
                let pixel_to_world = DAffine3::from_cols(dx, dy, cam.forward, origin);
                let mut m = wm.world_to_object * pixel_to_world;
                if scene.materials[spec.material].texture.is_some() {
                    let (mut lo, mut hi) = wm.object_bounds;
                    if let Some(extent) = materials[spec.material].texture_extent {
                        (lo, hi) =
                            crate::prepare::placement::fit_extent(lo, hi, DVec3::from(extent));
                    }
                    let size = (hi - lo).max(DVec3::splat(1e-30));
                    let to_unit = DAffine3::from_scale_rotation_translation(
                        size.recip(),
                        glam::DQuat::IDENTITY,
                        -lo / size,
                    );
                    m = to_unit * m;
                }
                let c = m.matrix3;
                let t = m.translation;
                [
                    c.x_axis.x, c.y_axis.x, c.z_axis.x, t.x, c.x_axis.y, c.y_axis.y, c.z_axis.y,
                    t.y, c.x_axis.z, c.y_axis.z, c.z_axis.z, t.z,
                ]
                .map(|v| v as f32)
            })
            .collect();
        RenderPlan {
            grid_width: geometry.raster.width,
            grid_height: geometry.raster.height,
            guard: geometry.raster.guard,
            width: scene.image.width,
            height: scene.image.height,
            slabs,
            auto_slabs: geometry.auto_slabs.clone(),
            slab_distance: e as f32,
            slab_front: (0..slabs).map(|k| (f64::from(k) * e) as f32).collect(),
            slab_back: geometry.slab_back_faces(),
            channels: if scene.is_monochrome() { 1 } else { 3 },
            penumbra: scene.sweep.penumbra,
            lights,
            materials,
            mesh_material: scene.meshes.iter().map(|m| m.material as u32).collect(),
            mesh_to_detail,
            jitter: scene.sweep.jitter,
            jitter_slab_hash: (0..slabs)
                .map(|k| slab_hash(seed, JITTER_STREAM, k))
                .collect(),
            background: scene.image.background,
            pixel_size: px,
            initial_light: None,
            preintegration: scene.sweep.preintegration,
            surface_hold: Vec::new(),
        }
        .with_surface_hold(scene, geometry)
        .with_patterns(scene, files)
        .map(Some)
    }

    /// Sets every triangle's surface hold ([`RenderPlan::surface_hold`]) from its depth slopes
    /// and the lights' kernels.
    fn with_surface_hold(mut self, scene: &Scene, geometry: &SceneGeometry) -> RenderPlan {
        let moments: Vec<KernelMoments> = self.lights.iter().map(|l| l.moments).collect();
        let e = geometry.slab_distance;
        let compensation = scene.sweep.variance_compensation;
        // Only surfaces that take out all light at every crossing are held: whether one does is
        // then known from the crossed triangle alone, before shading.
        let blocks: Vec<bool> = self
            .materials
            .iter()
            .map(MaterialPlan::blocks_light)
            .collect();
        let holds: Vec<u32> = geometry
            .raster
            .triangles
            .iter()
            .map(|t| {
                if !blocks[self.mesh_material[t.mesh as usize] as usize] {
                    return 0;
                }
                surface_hold::surface_hold(
                    &moments,
                    self.penumbra,
                    compensation,
                    t.depth_dx,
                    t.depth_dy,
                    e,
                )
            })
            .collect();
        // No per-pixel hold state where no surface holds (camera-facing receivers).
        self.surface_hold = if holds.iter().any(|&h| h != 0) {
            holds
        } else {
            Vec::new()
        };
        self
    }

    /// Whether some surface is held ([`RenderPlan::surface_hold`]): the sweep then keeps one
    /// hold state per pixel.
    #[inline(always)]
    pub fn has_surface_hold(&self) -> bool {
        !self.surface_hold.is_empty()
    }

    /// Samples every light's pattern into the initial light buffer (`None` without patterns);
    /// errors name the key and the file.
    pub fn with_patterns(
        mut self,
        scene: &Scene,
        files: &PlanFiles,
    ) -> Result<RenderPlan, PlanError> {
        if scene.lights.iter().all(|l| l.pattern.is_none()) {
            return Ok(self);
        }
        let w = self.grid_width as usize;
        let h = self.grid_height as usize;
        let ch = self.channels as usize;
        let row_len = self.light_row_len();
        let mut buf = self.unlit_light_buffer();
        for (l, spec) in scene.lights.iter().enumerate() {
            let Some(p) = &spec.pattern else { continue };
            let pattern = files
                .patterns
                .get(l)
                .and_then(Option::as_ref)
                .ok_or_else(|| PlanError {
                    scene: scene.source.clone(),
                    what: format!("key `light[{l}].pattern.path`"),
                    source: TextureError::NotRead {
                        path: p.path.clone(),
                    },
                })?;
            let (tw, th) = (f64::from(pattern.width), f64::from(pattern.height));
            let (left, top) = (f64::from(self.guard.left), f64::from(self.guard.top));
            for y in 0..h {
                // Camera-space y of the grid pixel centre, from the view's centre.
                let cy = (y as f64 - top + 0.5 - f64::from(self.height) * 0.5) * self.pixel_size;
                let ty = ((cy - p.center[1]) / p.size[1] + 0.5) * th;
                for c in 0..ch {
                    let row = &mut buf[y * row_len + self.light_plane(l, c) * w..][..w];
                    for (x, v) in row.iter_mut().enumerate() {
                        let cx =
                            (x as f64 - left + 0.5 - f64::from(self.width) * 0.5) * self.pixel_size;
                        let tx = ((cx - p.center[0]) / p.size[0] + 0.5) * tw;
                        let s = pattern.sample(tx, ty, c) as f32;
                        *v = if s < FLUSH_BELOW { 0.0 } else { s };
                    }
                }
            }
        }
        self.initial_light = Some(buf);
        Ok(self)
    }

    /// The column every per-pixel hash (kernel phase, jitter) is keyed by for grid column `x`:
    /// the image column, wrapping below 0 in the left guard band. The random pattern of an image
    /// pixel then does not depend on the band, so widening or narrowing it (as `auto` does when
    /// the scene moves) changes only what the band adds, not the noise.
    #[inline(always)]
    pub fn hash_x(&self, x: u32) -> u32 {
        x.wrapping_sub(self.guard.left)
    }

    /// The row every per-pixel hash is keyed by for grid row `y` (see [`RenderPlan::hash_x`]).
    #[inline(always)]
    pub fn hash_y(&self, y: u32) -> u32 {
        y.wrapping_sub(self.guard.top)
    }

    /// The image pixel coordinates, as f32, of grid column `x` and row `y` (negative inside the
    /// left and top guard band): what the detail affine `mesh_to_detail` is applied to.
    #[inline(always)]
    pub fn image_xy(&self, x: usize, y: usize) -> (f32, f32) {
        (
            (x as i64 - i64::from(self.guard.left)) as f32,
            (y as i64 - i64::from(self.guard.top)) as f32,
        )
    }

    /// Floats per light-buffer row: lights × planes per light × grid width.
    pub fn light_row_len(&self) -> usize {
        self.lights.len() * self.planes_per_light() * self.grid_width as usize
    }

    /// Entries per row of the level plane (distance penumbra: one per light and grid column; else
    /// 1, unused).
    pub fn level_row_len(&self) -> usize {
        if self.depth_planes() > 0 {
            self.lights.len() * self.grid_width as usize
        } else {
            1
        }
    }

    /// Depth planes per light: 1 (the occluder depth D) with the distance penumbra, else 0.
    pub fn depth_planes(&self) -> usize {
        usize::from(self.penumbra == Penumbra::Distance)
    }

    /// Planes per light in the light buffer: its channels, then its depth plane if any.
    pub fn planes_per_light(&self) -> usize {
        self.channels as usize + self.depth_planes()
    }

    /// Index of light `l`'s plane `c` within a light-buffer row, in units of the grid width
    /// (`c == channels` is its depth plane).
    pub fn light_plane(&self, l: usize, c: usize) -> usize {
        l * self.planes_per_light() + c
    }

    /// Whether plane `p` of a light-buffer row is a depth plane (whose unlit value is 0, not 1).
    pub fn is_depth_plane(&self, p: usize) -> bool {
        p % self.planes_per_light() >= self.channels as usize
    }

    /// The light buffer before the first slab without patterns: light 1, occluder depth 0.
    pub fn unlit_light_buffer(&self) -> Vec<f32> {
        let w = self.grid_width as usize;
        let row_len = self.light_row_len();
        let mut buf = vec![1.0f32; row_len * self.grid_height as usize];
        if self.depth_planes() > 0 {
            for row in buf.chunks_mut(row_len) {
                for (p, plane) in row.chunks_mut(w).enumerate() {
                    if self.is_depth_plane(p) {
                        plane.fill(0.0);
                    }
                }
            }
        }
        buf
    }
}

/// Colours below 2^-24 become 0, so products in shading never approach the subnormal range.
fn flush_tiny(c: f32) -> f32 {
    if c < 1.0 / 16_777_216.0 { 0.0 } else { c }
}

/// The transfer-function entry for colour `c`, opacity `a`, transport `tau`, thickness ratio.
fn tf_entry(c: [f64; 3], a: f64, tau: [f64; 3], ratio: f64) -> TfEntry {
    let alpha = 1.0 - (1.0 - a).powf(ratio);
    let alpha = if alpha < 1.0 / 16_777_216.0 {
        0.0
    } else {
        alpha.min(1.0)
    };
    TfEntry {
        color: c.map(|v| flush_tiny(v as f32)),
        alpha: alpha as f32,
        attenuation: tau.map(|t| (1.0 - alpha * (1.0 - t)) as f32),
    }
}

/// The pre-integrated entry of a slab of thickness ratio `ratio` (= e / reference length) whose
/// detail value runs linearly from `front` to `back` (Engel, Kraus & Ertl 2001; Patel et al.
/// 2013 §7). The slab is cut into `n` = max(16, ⌈|back − front| · [`PI_STEPS_PER_UNIT`]⌉) thin
/// slabs of constant value (their midpoints' gradient colour `c_i` and opacity), each of
/// opacity `a_i = 1 − (1 − α)^(ratio / n)` and light attenuation `1 − a_i·(1 − τ)`, and
/// composited front to back as the sweep would composite `n` slabs: opacity `A = 1 − Π(1 − a_i)`,
/// colour `Σ T_i·a_i·c_i·L_i` with `T_i` the view's and `L_i` the light's transmittance through
/// the thin slabs before i (the light entering the slab at its front, attenuated in the pixel's
/// column: the slab shadows itself as thin slabs would), attenuation `Π(1 − a_i·(1 − τ))`. The
/// entry keeps the sweep's single-sample form: colour = that sum / A (the sweep composites
/// `A·colour` times the entering light).
pub fn preintegrated_entry(m: &MaterialSpec, ratio: f64, front: f64, back: f64) -> TfEntry {
    let n = ((back - front).abs() * PI_STEPS_PER_UNIT)
        .ceil()
        .max(PI_MIN_STEPS) as usize;
    let mut view = 1.0f64;
    let mut light = [1.0f64; 3];
    let mut sum = [0.0f64; 3];
    let mut mean = [0.0f64; 3];
    for i in 0..n {
        let v = front + (back - front) * ((i as f64 + 0.5) / n as f64);
        let (c, a) = gradient_at(m, v);
        let a_i = if a >= 1.0 {
            1.0
        } else {
            1.0 - (1.0 - a).powf(ratio / n as f64)
        };
        for k in 0..3 {
            sum[k] += view * a_i * c[k] * light[k];
            mean[k] += c[k] / n as f64;
            light[k] *= 1.0 - a_i * (1.0 - m.transport[k]);
        }
        view *= 1.0 - a_i;
    }
    let alpha = 1.0 - view;
    let alpha = if alpha < 1.0 / 16_777_216.0 {
        0.0
    } else {
        alpha.min(1.0)
    };
    let color = if alpha > 0.0 {
        sum.map(|p| p / alpha)
    } else {
        mean
    };
    TfEntry {
        color: color.map(|v| flush_tiny(v as f32)),
        alpha: alpha as f32,
        attenuation: light.map(|t| t as f32),
    }
}

/// The pre-integration table of a detail material ([`MaterialPlan::pre`]).
fn preintegration_table(m: &MaterialSpec, ratio: f64) -> Vec<TfEntry> {
    let step = 1.0 / (PI_SIZE - 1) as f64;
    let mut table = Vec::with_capacity(PI_SIZE * PI_SIZE);
    for f in 0..PI_SIZE {
        for b in 0..PI_SIZE {
            table.push(preintegrated_entry(
                m,
                ratio,
                f as f64 * step,
                b as f64 * step,
            ));
        }
    }
    table
}

/// Builds a material's tables for slab thickness `e` (with the pre-integration table when
/// `preintegration` is on and the material has detail).
fn material_plan(
    m: &MaterialSpec,
    e: f64,
    preintegration: bool,
    texture: Option<TextureFile>,
) -> Result<MaterialPlan, TextureError> {
    let ratio = e / m.reference_length.unwrap_or(DEFAULT_REFERENCE_LENGTH);
    let tf = if m.gradient.is_empty() {
        vec![tf_entry(m.color, m.opacity, m.transport, ratio)]
    } else {
        (0..TF_SIZE)
            .map(|i| {
                let v = i as f64 / (TF_SIZE - 1) as f64;
                let (c, a) = gradient_at(m, v);
                tf_entry(c, a, m.transport, ratio)
            })
            .collect()
    };
    let detail = m.detail.as_ref().map(|d| {
        Detail::new(
            d.kind,
            d.frequency as f32,
            d.octaves,
            d.lacunarity as f32,
            d.gain as f32,
            d.time.map(|t| t as f32),
        )
    });
    let (texture, texture_extent) = match (&m.texture, texture) {
        (Some(_), Some(t)) => (Some(t.texture), t.extent),
        (Some(t), None) => {
            return Err(TextureError::NotRead {
                path: t.path.clone(),
            });
        }
        (None, _) => (None, None),
    };
    let pre = (preintegration && !m.gradient.is_empty()).then(|| preintegration_table(m, ratio));
    Ok(MaterialPlan {
        tf,
        pre,
        detail,
        texture,
        texture_extent,
        specular: m.specular.as_ref().map(SpecularPlan::new),
        lambert: m.surface == SurfaceModel::Lambert,
        light_color: Vec::new(),
    })
}

/// The gradient's colour and opacity at value `v` (piecewise linear, constant beyond the ends).
fn gradient_at(m: &MaterialSpec, v: f64) -> ([f64; 3], f64) {
    let g = &m.gradient;
    if v <= g[0].value {
        return (g[0].color, g[0].opacity);
    }
    for w in g.windows(2) {
        if v <= w[1].value {
            let span = w[1].value - w[0].value;
            let t = if span > 0.0 {
                (v - w[0].value) / span
            } else {
                1.0
            };
            let lerp = |a: f64, b: f64| a + t * (b - a);
            return (
                [
                    lerp(w[0].color[0], w[1].color[0]),
                    lerp(w[0].color[1], w[1].color[1]),
                    lerp(w[0].color[2], w[1].color[2]),
                ],
                lerp(w[0].opacity, w[1].opacity),
            );
        }
    }
    let last = g[g.len() - 1];
    (last.color, last.opacity)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_opacity_correction_composes() {
        // Two slabs of half the reference length let through what one reference slab does.
        let half = tf_entry([1.0; 3], 0.6, [0.0; 3], 0.5);
        let full = tf_entry([1.0; 3], 0.6, [0.0; 3], 1.0);
        let through_two = (1.0 - f64::from(half.alpha)).powi(2);
        assert!((through_two - (1.0 - f64::from(full.alpha))).abs() < 1e-6);
        // Transport 1 lets the light through untouched.
        let clear = tf_entry([1.0; 3], 0.9, [1.0, 0.0, 0.5], 1.0);
        assert_eq!(clear.attenuation[0], 1.0);
        assert!((clear.attenuation[1] - 0.1).abs() < 1e-6);
        assert!((clear.attenuation[2] - 0.55).abs() < 1e-6);
    }

    /// A detail material whose gradient is the given stops (value, grey colour, opacity).
    fn graded(stops: &[(f64, f64, f64)], transport: [f64; 3]) -> MaterialSpec {
        MaterialSpec {
            name: "m".into(),
            color: [1.0; 3],
            opacity: 1.0,
            transport,
            reference_length: None,
            detail: None,
            texture: None,
            gradient: stops
                .iter()
                .map(|&(value, c, opacity)| crate::model::scene::GradientStop {
                    value,
                    color: [c; 3],
                    opacity,
                })
                .collect(),
            specular: None,
            surface: crate::model::scene::SurfaceModel::Lambert,
            phase_g: 0.0,
        }
    }

    #[test]
    fn a_constant_preintegrated_slab_matches_the_closed_form_of_its_thin_slabs() {
        // Constant value: 16 thin slabs of opacity a = 1 − (1 − α)^(r/16); the slab passes
        // T = (1 − α)^r of the view. With τ = 0 the light passes the same, so thin slab i is
        // seen through (1 − a)^i and lit through (1 − a)^i: Σ a·(1 − a)^{2i}·c
        // = c·a·(1 − T²)/(1 − (1 − a)²), i.e. colour = c·(1 + T)/(2 − a) after dividing by
        // A = 1 − T. With τ = 1 the light is not attenuated and the colour is c itself.
        let (alpha, r, c) = (0.6, 0.5, 0.8);
        let m = graded(&[(0.0, c, alpha), (1.0, c, alpha)], [0.0; 3]);
        let e = preintegrated_entry(&m, r, 0.3, 0.3);
        let t = (1.0f64 - alpha).powf(r);
        let a = 1.0 - (1.0f64 - alpha).powf(r / 16.0);
        assert!((f64::from(e.alpha) - (1.0 - t)).abs() < 1e-6, "{e:?}");
        assert!((f64::from(e.color[0]) - c * (1.0 + t) / (2.0 - a)).abs() < 1e-6);
        assert!((f64::from(e.attenuation[1]) - t).abs() < 1e-6);
        let clear = preintegrated_entry(&graded(&[(0.0, c, alpha)], [1.0; 3]), r, 0.3, 0.3);
        assert!((f64::from(clear.color[2]) - c).abs() < 1e-6);
        assert_eq!(clear.attenuation, [1.0; 3]);
        assert!((f64::from(clear.alpha) - (1.0 - t)).abs() < 1e-6);
    }

    #[test]
    fn a_preintegrated_slab_is_its_two_halves_composited() {
        // Front 0.2 → back 0.8 over a gradient with a narrow band: 308 thin slabs; each half
        // (0.2 → 0.5, 0.5 → 0.8, half the thickness) is 154 of the same thin slabs. Compositing
        // the halves as the sweep composites slabs — the second seen through the first's opacity
        // and lit through its attenuation — must give the whole slab.
        let m = graded(
            &[
                (0.0, 0.2, 0.0),
                (0.45, 0.9, 0.0),
                (0.5, 0.5, 0.9),
                (0.55, 0.1, 0.0),
            ],
            [0.3, 0.6, 0.9],
        );
        let r = 2.0;
        let whole = preintegrated_entry(&m, r, 0.2, 0.8);
        let (h1, h2) = (
            preintegrated_entry(&m, r / 2.0, 0.2, 0.5),
            preintegrated_entry(&m, r / 2.0, 0.5, 0.8),
        );
        let (a1, a2) = (f64::from(h1.alpha), f64::from(h2.alpha));
        let alpha = 1.0 - (1.0 - a1) * (1.0 - a2);
        assert!(whole.alpha > 0.2, "the band is crossed: {whole:?}");
        assert!((f64::from(whole.alpha) - alpha).abs() < 1e-6);
        for k in 0..3 {
            let l1 = f64::from(h1.attenuation[k]);
            let color = a1 * f64::from(h1.color[k]) + (1.0 - a1) * l1 * a2 * f64::from(h2.color[k]);
            assert!(
                (f64::from(whole.color[k]) * alpha - color).abs() < 1e-6,
                "channel {k}: {whole:?} vs {h1:?} + {h2:?}"
            );
            let att = l1 * f64::from(h2.attenuation[k]);
            assert!((f64::from(whole.attenuation[k]) - att).abs() < 1e-6);
        }
        // The band is inside the slab, not at its faces: one sample at either face misses it.
        assert_eq!(gradient_at(&m, 0.2).1, 0.0);
        assert_eq!(gradient_at(&m, 0.8).1, 0.0);
    }
}
