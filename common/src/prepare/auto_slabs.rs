//! `sweep.slabs = "auto"`: the slab count from the detail the slabs must sample (Patel et al.
//! 2013, §7: "for sampled function representations we use the dimensions of the 3D texture as a
//! basis for automatically setting the number of slabs … the chosen frequency scale is taken into
//! account and an additional modulation factor can be specified by the user").
//!
//! Every mesh whose material has detail contributes a *finest period* in world units along the
//! view direction `d`:
//! - procedural detail: one lattice cell of its highest octave, `1 / (f_max · |M d|)` with
//!   `f_max = frequency · max(1, lacunarity)^(octaves − 1)` (one octave for `perlin`) per
//!   object-space unit and `M` the world → object map (`|M d| = 1 / scale`);
//! - a 3D texture: one voxel, `1 / |V M d|` with `V = diag(dims / size)` mapping object units to
//!   voxels (`size` is the object-space box the texture is mapped onto, the NIfTI extent fitted
//!   into it like the plan does).
//!
//! Every closed mesh contributes its thinnest feature along the view, measured on a subsampled
//! rasterization of the meshes ([`thickness`]): a sheet thinner than the slabs would fall
//! between two back faces or be sampled once, so it too gets 2 slabs across.
//!
//! The count is `⌈depth · 2 · slab_factor / p_min⌉` over the scene's depth range (2 slabs per
//! finest length p_min: the smallest detail period or mesh thickness), and at least
//! `⌈AUTO_MIN_SLABS · slab_factor⌉` (a scene with only thick meshes and coarse detail still gets
//! enough slabs for its shadows to iterate smoothly).

use glam::DVec3;

use crate::contract::files::GeometryFiles;
use crate::model::scene::{DetailKind, MAX_SLABS, Scene, TextureFormat};
use crate::pixel::texture3d::TextureError;
use crate::prepare::camera::Camera;
use crate::prepare::error::GeometryError;
use crate::prepare::placement::{WorldMesh, fit_extent};

pub mod thickness;

pub use thickness::Thinnest;

/// Slabs per finest period of the detail, or across the thinnest mesh feature (Nyquist: two
/// samples per period).
pub const SLABS_PER_PERIOD: f64 = 2.0;
/// The fewest slabs `"auto"` chooses (times `slab_factor`), also for scenes without detail.
pub const AUTO_MIN_SLABS: f64 = 64.0;

/// What `slabs = "auto"` chose, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct AutoSlabs {
    /// The slab count.
    pub count: u32,
    /// The finest length along the view direction the slabs sample twice, world units: the
    /// smallest detail period or mesh thickness (`None`: neither; the minimum count applies).
    pub finest_period: Option<f64>,
    /// What sets it: the scene key of a detail (`material.NAME.detail` or `.texture`) or
    /// `mesh[i] thickness`.
    pub limited_by: Option<String>,
    /// The thinnest mesh feature measured, whether or not it sets the count.
    pub thinnest: Option<Thinnest>,
    /// Whether the minimum count applies (the finest length asks for fewer slabs).
    pub minimum: bool,
    /// `sweep.slab_factor`.
    pub factor: f64,
}

/// The finest period (world units along `forward`) of the detail of every mesh, and the key of
/// the one that sets it. NIfTI volumes contribute the grids their headers give
/// ([`GeometryFiles::volume_grids`]).
pub fn finest_period(
    scene: &Scene,
    files: &GeometryFiles,
    forward: DVec3,
    meshes: &[WorldMesh],
) -> Result<Option<(f64, String)>, GeometryError> {
    let mut best: Option<(f64, String)> = None;
    for (spec, wm) in scene.meshes.iter().zip(meshes) {
        let material = &scene.materials[spec.material];
        // The world → object image of one world unit along the view direction.
        let step = wm.world_to_object.matrix3 * forward;
        let mut candidates = Vec::new();
        if let Some(d) = &material.detail {
            let octaves = if d.kind == DetailKind::Perlin {
                1
            } else {
                d.octaves.max(1)
            };
            let mut f_max = d.frequency;
            for _ in 1..octaves {
                f_max *= d.lacunarity.max(1.0);
            }
            let rate = f_max * step.length();
            candidates.push((rate, format!("material.{}.detail", material.name)));
        }
        if let Some(t) = &material.texture {
            let (mut lo, mut hi) = wm.object_bounds;
            let dims = match &t.format {
                TextureFormat::Raw { dims, .. } => *dims,
                TextureFormat::Nifti { .. } | TextureFormat::Vdb { .. } => {
                    let grid = files
                        .volume_grids
                        .get(spec.material)
                        .copied()
                        .flatten()
                        .ok_or_else(|| GeometryError::Texture {
                            scene: scene.source.clone(),
                            material: material.name.clone(),
                            source: TextureError::NotRead {
                                path: t.path.clone(),
                            },
                        })?;
                    let (dims, spacing) = (grid.dims, grid.spacing);
                    let extent = DVec3::new(
                        f64::from(dims[0]) * spacing[0],
                        f64::from(dims[1]) * spacing[1],
                        f64::from(dims[2]) * spacing[2],
                    );
                    (lo, hi) = fit_extent(lo, hi, extent);
                    dims
                }
            };
            let size = (hi - lo).max(DVec3::splat(1e-30));
            let voxels =
                DVec3::new(f64::from(dims[0]), f64::from(dims[1]), f64::from(dims[2])) / size;
            let rate = (voxels * step).length();
            candidates.push((rate, format!("material.{}.texture", material.name)));
        }
        for (rate, key) in candidates {
            if rate > 0.0 && rate.is_finite() {
                let period = 1.0 / rate;
                if best.as_ref().is_none_or(|(p, _)| period < *p) {
                    best = Some((period, key));
                }
            }
        }
    }
    Ok(best)
}

/// The `"auto"` slab count over a depth range of `depth` world units starting at camera depth
/// `z_origin` (see the module documentation); more than [`MAX_SLABS`] is an error naming
/// `sweep.slabs`.
pub fn auto_slabs(
    scene: &Scene,
    files: &GeometryFiles,
    camera: &Camera,
    meshes: &[WorldMesh],
    z_origin: f64,
    depth: f64,
) -> Result<AutoSlabs, GeometryError> {
    let factor = scene.sweep.slab_factor;
    let detail = finest_period(scene, files, camera.forward, meshes)?;
    let thinnest =
        thickness::thinnest_feature(camera, meshes, z_origin, depth).map_err(|source| {
            GeometryError::Raster {
                scene: scene.source.clone(),
                source,
            }
        })?;
    let mut found = detail;
    if let Some(t) = thinnest
        && found.as_ref().is_none_or(|(p, _)| t.thickness < *p)
    {
        found = Some((t.thickness, format!("mesh[{}] thickness", t.mesh)));
    }
    let floor = (AUTO_MIN_SLABS * factor).ceil().max(1.0);
    let needed = match &found {
        Some((period, _)) => (depth * SLABS_PER_PERIOD * factor / period).ceil(),
        None => floor,
    };
    let count = needed.max(floor);
    if count.is_nan() || count > f64::from(MAX_SLABS) {
        let (period, key) = found.clone().unwrap_or((f64::NAN, String::new()));
        return Err(GeometryError::TooManyAutoSlabs {
            scene: scene.source.clone(),
            count,
            depth,
            period,
            limited_by: key,
            factor,
        });
    }
    Ok(AutoSlabs {
        count: count as u32,
        finest_period: found.as_ref().map(|f| f.0),
        limited_by: found.map(|f| f.1),
        thinnest,
        minimum: needed.is_nan() || needed <= floor,
        factor,
    })
}

#[cfg(test)]
mod tests;
