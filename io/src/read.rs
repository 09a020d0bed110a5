//! The files a render reads, in the order it needs them: the scene, the files its geometry
//! needs (mesh files, NIfTI headers for `slabs = "auto"`), then the files its plan needs (3D
//! textures, light patterns). Each step's errors are the stage's own typed errors, naming the
//! scene, the key and the file, so a caller maps them to exit codes as before.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use convshadow_common::contract::files::{GeometryFiles, PlanFiles, TextureFile, VolumeGrid};
use convshadow_common::model::scene::{Scene, SceneError, ShapeSpec, SlabSpec, TextureFormat};
use convshadow_common::pixel::texture3d::TextureError;
use convshadow_common::pixel::volume::Volume;
use convshadow_common::plan::kernel::TableGuard;
use convshadow_common::plan::{PlanError, RenderPlan};
use convshadow_common::prepare::error::GeometryError;
use convshadow_common::prepare::geometry::SceneGeometry;

use crate::input::{MAX_SCENE_BYTES, check_regular, read_text_limited};

/// Reads, parses and validates a scene file (at most [`MAX_SCENE_BYTES`]); relative paths in it
/// resolve against its folder.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let source = path.display().to_string();
    let text = read_text_limited(path, MAX_SCENE_BYTES).map_err(|e| SceneError {
        file: source.clone(),
        key: String::new(),
        message: format!("cannot read scene file: {e}"),
    })?;
    let base = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    Scene::parse(&text, &source, &base)
}

/// Reads what the geometry stage needs: every mesh file, and with `slabs = "auto"` the header of
/// every NIfTI texture and the grid of every OpenVDB texture (its voxels set the slab count).
pub fn read_geometry_files(scene: &Scene) -> Result<GeometryFiles, GeometryError> {
    let meshes = scene
        .meshes
        .iter()
        .enumerate()
        .map(|(index, spec)| match &spec.shape {
            ShapeSpec::Obj { path } => {
                crate::mesh::load_mesh(path)
                    .map(Some)
                    .map_err(|source| GeometryError::Mesh {
                        scene: scene.source.clone(),
                        index,
                        source,
                    })
            }
            _ => Ok(None),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let auto = scene.sweep.slabs == SlabSpec::Auto;
    let volume_grids = scene
        .materials
        .iter()
        .map(|m| match &m.texture {
            Some(t)
                if auto
                    && matches!(
                        t.format,
                        TextureFormat::Nifti { .. } | TextureFormat::Vdb { .. }
                    ) =>
            {
                match &t.format {
                    TextureFormat::Vdb { grid } => crate::vdb::grid_info(&t.path, grid),
                    _ => crate::nifti::header_grid(&t.path),
                }
                .map(|(dims, spacing)| Some(VolumeGrid { dims, spacing }))
                .map_err(|source| GeometryError::Texture {
                    scene: scene.source.clone(),
                    material: m.name.clone(),
                    source,
                })
            }
            _ => Ok(None),
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(GeometryFiles {
        meshes,
        volume_grids,
    })
}

/// Reads what the plan needs: every material's 3D texture (raw in chunks, NIfTI decoded and
/// windowed) and every light's pattern. Loading stops with [`TextureError::Interrupted`] once
/// `cancel` is raised.
pub fn read_plan_files(scene: &Scene, cancel: Option<&AtomicBool>) -> Result<PlanFiles, PlanError> {
    let textures = scene
        .materials
        .iter()
        .map(|m| {
            let Some(t) = &m.texture else { return Ok(None) };
            read_texture(&t.path, &t.format, cancel)
                .map(Some)
                .map_err(|source| PlanError {
                    scene: scene.source.clone(),
                    what: format!("material `{}`", m.name),
                    source,
                })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let patterns = scene
        .lights
        .iter()
        .enumerate()
        .map(|(l, spec)| {
            let Some(p) = &spec.pattern else {
                return Ok(None);
            };
            crate::pattern::load_pattern(&p.path)
                .map(Some)
                .map_err(|source| PlanError {
                    scene: scene.source.clone(),
                    what: format!("key `light[{l}].pattern.path`"),
                    source,
                })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PlanFiles { textures, patterns })
}

/// One 3D texture file.
fn read_texture(
    path: &Path,
    format: &TextureFormat,
    cancel: Option<&AtomicBool>,
) -> Result<TextureFile, TextureError> {
    match format {
        TextureFormat::Raw { dims, voxel } => {
            // A folder or device is refused by name, not by its size ("file is 4096 bytes").
            check_regular(path).map_err(|source| TextureError::Io {
                path: path.to_path_buf(),
                source,
            })?;
            let texture = crate::raw::load_raw_cancellable(path, *dims, *voxel, cancel)?;
            Ok(TextureFile {
                texture: Arc::new(texture.into()),
                extent: None,
            })
        }
        TextureFormat::Nifti { window } => {
            let n = crate::nifti::load_nifti_cancellable(path, *window, cancel)?;
            let extent = n.extent();
            Ok(TextureFile {
                texture: Arc::new(n.texture.into()),
                extent: Some(extent),
            })
        }
        TextureFormat::Vdb { grid } => {
            let v = crate::vdb::load_vdb_cancellable(path, grid, cancel)?;
            let extent = v.extent();
            Ok(TextureFile {
                texture: Arc::new(Volume::Bricked(v.texture)),
                extent: Some(extent),
            })
        }
    }
}

/// The scene's geometry with its files read: [`read_geometry_files`], then
/// [`SceneGeometry::build`].
pub fn build_geometry(scene: &Scene) -> Result<SceneGeometry, GeometryError> {
    SceneGeometry::build(scene, &read_geometry_files(scene)?)
}

/// The scene's plan with its files read: [`read_plan_files`], then [`RenderPlan::new`].
pub fn build_plan(scene: &Scene, geometry: &SceneGeometry) -> Result<RenderPlan, PlanError> {
    RenderPlan::new(scene, geometry, &read_plan_files(scene, None)?)
}

/// [`build_plan`] under `guard`: file loading stops once its cancel flag is raised, and the
/// kernel tables once it is raised or their bytes pass its limit (`Ok(None)`; the guard says
/// which).
pub fn build_plan_guarded(
    scene: &Scene,
    geometry: &SceneGeometry,
    guard: &TableGuard<'_>,
) -> Result<Option<RenderPlan>, PlanError> {
    let files = read_plan_files(scene, guard.cancel)?;
    RenderPlan::new_guarded(scene, geometry, &files, guard)
}
