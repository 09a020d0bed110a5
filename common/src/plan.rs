//! The render plan: every table the sweep reads, computed once on the host and
//! shared by the scalar path, the SIMD path and the GPU port.
//!
//! Nothing per pixel calls a transcendental: kernel taps, slab hashes, the slab-thickness opacity
//! correction `α_slab = 1 − (1 − α)^(e/e_ref)`, attenuation factors and specular half vectors are
//! all here.

use std::sync::Arc;

use glam::{DAffine3, DVec3};

use crate::geometry::SceneGeometry;
use crate::guard::GuardBand;
use crate::hash::{JITTER_STREAM, slab_hash};
use crate::kernel::{KernelMoments, KernelTable, build_distance_table, build_table};
use crate::noise::Detail;
use crate::scene::{MaterialSpec, Penumbra, Scene, TextureFormat, TextureSpec};
use crate::texture3d::{Texture3d, TextureError};

/// Entries of a material's transfer-function table over detail values [0, 1].
pub const TF_SIZE: usize = 256;
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
    /// Procedural detail, if any.
    pub detail: Option<Detail>,
    /// 3D texture, if any (sampled at normalised object coordinates).
    pub texture: Option<Arc<Texture3d>>,
    /// The texture's physical extent (NIfTI: dims · spacing), whose aspect its mapping keeps;
    /// `None` (raw textures): stretched to the mesh's bounds.
    pub texture_extent: Option<[f64; 3]>,
    /// Specular strength and exponent.
    pub specular: Option<(f32, u32)>,
    /// Per light: the light's colour times this material's phase function at the light's
    /// scattering angle ([`phase_factor`]); exactly the light's colour for an isotropic medium
    /// (g = 0). Shading sums `Iin ⊙ light_color`; the specular term uses the bare colour.
    pub light_color: Vec<[f32; 3]>,
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
    pub auto_slabs: Option<crate::auto_slabs::AutoSlabs>,
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
    /// The light buffer before the first slab (`[row][light][channel][x]`, like the sweep's),
    /// when a light has a pattern; `None`: every light starts at 1.
    pub initial_light: Option<Vec<f32>>,
}

impl RenderPlan {
    /// Builds all tables for a scene whose geometry is already set up.
    pub fn new(scene: &Scene, geometry: &SceneGeometry) -> Result<RenderPlan, PlanError> {
        RenderPlan::new_cancellable(scene, geometry, None)
    }

    /// [`RenderPlan::new`], with raw 3D textures loaded in chunks that stop with
    /// [`TextureError::Interrupted`] once `cancel` is raised.
    pub fn new_cancellable(
        scene: &Scene,
        geometry: &SceneGeometry,
        cancel: Option<&std::sync::atomic::AtomicBool>,
    ) -> Result<RenderPlan, PlanError> {
        let slabs = geometry.slabs;
        let e = geometry.slab_distance;
        let px = geometry.camera.pixel_size;
        let seed = scene.sweep.seed;
        let lights = scene
            .lights
            .iter()
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
                        (moments, build_table(kernel, &moments, slabs, compensate))
                    }
                    Penumbra::Distance => {
                        // A covariance step of f·e²·Σl is d1 = f·e in the iterated formula.
                        let per_e2 = |f: f64| moments_for(f * e);
                        let table = build_distance_table(kernel, &per_e2, slabs, compensate);
                        (per_e2(1.0), table)
                    }
                };
                let mu = spec.tilt_deg.map(|t| t.to_radians().tan());
                let to_light = DVec3::new(mu[0], mu[1], -1.0).normalize();
                let h = (to_light + DVec3::new(0.0, 0.0, -1.0)).normalize();
                LightPlan {
                    color: spec.color.map(flush_tiny),
                    moments,
                    table,
                    slab_hash: (0..slabs).map(|k| slab_hash(seed, l as u32, k)).collect(),
                    half_vector: [h.x as f32, h.y as f32, h.z as f32],
                }
            })
            .collect();
        let materials = scene
            .materials
            .iter()
            .map(|m| material_plan(m, e, cancel))
            .collect::<Result<Vec<_>, TextureError>>()
            .map_err(|source| PlanError {
                scene: scene.source.clone(),
                what: "material ``".to_string(),
                source,
            });
        let materials = match materials {
            Ok(m) => m,
            Err(mut err) => {
                // Name the material whose texture failed.
                if let Some(m) = scene.materials.iter().find(|m| {
                    m.texture.as_ref().is_some_and(|t| {
                        err.source
                            .to_string()
                            .contains(&t.path.display().to_string())
                    })
                }) {
                    err.what = format!("material `{}`", m.name);
                }
                return Err(err);
            }
        };
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
                        (lo, hi) = fit_extent(lo, hi, DVec3::from(extent));
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
        }
        .with_patterns(scene)
    }

    /// Samples every light's pattern into the initial light buffer (`None` without patterns);
    /// errors name the key and the file.
    pub fn with_patterns(mut self, scene: &Scene) -> Result<RenderPlan, PlanError> {
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
            let pattern = crate::pattern::load_pattern(&p.path).map_err(|source| PlanError {
                scene: scene.source.clone(),
                what: format!("key `light[{l}].pattern.path`"),
                source,
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

/// The largest box with the aspect of `extent`, centred in the bounds `lo..hi`: a NIfTI volume's
/// voxels keep their spacing's proportions (outside the box, sampling clamps to the edge voxels).
pub(crate) fn fit_extent(lo: DVec3, hi: DVec3, extent: DVec3) -> (DVec3, DVec3) {
    let size = hi - lo;
    let extent = extent.max(DVec3::splat(1e-30));
    let scale = (size / extent).min_element();
    let fitted = extent * scale;
    let centre = (lo + hi) * 0.5;
    (centre - fitted * 0.5, centre + fitted * 0.5)
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

/// Builds a material's tables for slab thickness `e`.
fn material_plan(
    m: &MaterialSpec,
    e: f64,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<MaterialPlan, TextureError> {
    let ratio = e / m.reference_length.unwrap_or(e);
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
    let (texture, texture_extent) = match &m.texture {
        Some(TextureSpec {
            path,
            format: TextureFormat::Raw { dims, voxel },
        }) => {
            // A folder or device is refused by name, not by its size ("file is 4096 bytes").
            crate::input::check_regular(path).map_err(|source| TextureError::Io {
                path: path.clone(),
                source,
            })?;
            (
                Some(Arc::new(Texture3d::load_raw_cancellable(
                    path, *dims, *voxel, cancel,
                )?)),
                None,
            )
        }
        Some(TextureSpec {
            path,
            format: TextureFormat::Nifti { window },
        }) => {
            let n = crate::nifti::load_nifti_cancellable(path, *window, cancel)?;
            let extent = n.extent();
            (Some(Arc::new(n.texture)), Some(extent))
        }
        None => (None, None),
    };
    Ok(MaterialPlan {
        tf,
        detail,
        texture,
        texture_extent,
        specular: m.specular.as_ref().map(|s| (s.strength, s.exponent)),
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
}
