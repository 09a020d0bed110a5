//! From a scene to world-space meshes, the slab range and the rasterizer set-up.

use glam::{DAffine3, DMat3, DVec3};

use crate::auto_slabs::{AutoSlabs, auto_slabs};
use crate::camera::Camera;
use crate::guard::{AutoGuardInput, GuardBand};
use crate::mesh::{MeshError, MeshReport, TriMesh};
use crate::raster::{RasterError, RasterSetup};
use crate::scene::{MAX_SLABS, MeshSpec, Scene, ShapeSpec, SlabSpec};

/// A mesh placed in the world, with its defects and the way back to object space.
#[derive(Clone, Debug)]
pub struct WorldMesh {
    /// World-space triangles (degenerate ones dropped).
    pub mesh: TriMesh,
    /// Closure report (boundary, non-manifold and flipped edges, degenerate triangles).
    pub report: MeshReport,
    /// Maps world points to the mesh's object space (where detail functions are evaluated).
    pub world_to_object: DAffine3,
    /// Object-space bounding box (3D textures are mapped onto it).
    pub object_bounds: (DVec3, DVec3),
}

/// Why a scene's geometry could not be built.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// A mesh file could not be loaded.
    #[error("{scene}: mesh[{index}]: {source}")]
    Mesh {
        /// Scene file.
        scene: String,
        /// Mesh index in the scene.
        index: usize,
        /// The loader's error.
        source: MeshError,
    },
    /// A mesh has no triangle left after dropping degenerate ones.
    #[error("{scene}: mesh[{index}]: no non-degenerate triangle")]
    EmptyMesh {
        /// Scene file.
        scene: String,
        /// Mesh index.
        index: usize,
    },
    /// A triangle cannot be rasterized exactly.
    #[error("{scene}: {source}")]
    Raster {
        /// Scene file.
        scene: String,
        /// The rasterizer's error.
        source: RasterError,
    },
    /// The slab distance gives too many slabs for the scene's depth.
    #[error(
        "{scene}: key `sweep.slab_distance`: {distance} gives {count} slabs over the scene's depth of \
         {depth}, expected at most {MAX_SLABS}"
    )]
    TooManySlabs {
        /// Scene file.
        scene: String,
        /// Slab distance.
        distance: f64,
        /// Resulting count.
        count: f64,
        /// Scene depth.
        depth: f64,
    },
    /// `slabs = "auto"` needs more slabs than the limit.
    #[error(
        "{scene}: key `sweep.slabs`: \"auto\" needs {count} slabs (2 per finest period of \
         {period:.4e} world units of `{limited_by}` over the scene's depth of {depth:.4e}, times \
         sweep.slab_factor = {factor}), expected at most {MAX_SLABS}; lower `sweep.slab_factor` \
         or give `sweep.slabs` a count"
    )]
    TooManyAutoSlabs {
        /// Scene file.
        scene: String,
        /// The count auto needs.
        count: f64,
        /// Scene depth.
        depth: f64,
        /// The finest period (world units along the view).
        period: f64,
        /// The key of the detail that sets it.
        limited_by: String,
        /// `sweep.slab_factor`.
        factor: f64,
    },
    /// A NIfTI texture's header could not be read (`slabs = "auto"` reads its dims).
    #[error("{scene}: material `{material}`: {source}")]
    Texture {
        /// Scene file.
        scene: String,
        /// Material name.
        material: String,
        /// The loader's error.
        source: crate::texture3d::TextureError,
    },
}

/// Everything geometric the LDI and the sweep need.
#[derive(Clone, Debug)]
pub struct SceneGeometry {
    /// The camera.
    pub camera: Camera,
    /// World meshes in scene order.
    pub meshes: Vec<WorldMesh>,
    /// Camera depth of the front of the first slab (the scene's nearest vertex).
    pub z_origin: f64,
    /// Slab thickness (world units).
    pub slab_distance: f64,
    /// Number of slabs.
    pub slabs: u32,
    /// How `slabs = "auto"` chose the count (`None` for a count or distance given).
    pub auto_slabs: Option<AutoSlabs>,
    /// Rasterizer set-up of every triangle (depths relative to `z_origin`), on the grid of the
    /// image plus the guard band resolved for this scene (`raster.guard`).
    pub raster: RasterSetup,
}

/// Builds a mesh spec's object-space mesh.
pub fn object_mesh(spec: &MeshSpec) -> Result<TriMesh, MeshError> {
    Ok(match &spec.shape {
        ShapeSpec::Box { size } => TriMesh::unit_box(DVec3::from(*size)),
        ShapeSpec::Sphere {
            radius,
            subdivisions,
        } => TriMesh::icosphere(*radius, *subdivisions),
        ShapeSpec::Torus {
            major,
            minor,
            segments,
        } => TriMesh::torus(*major, *minor, *segments),
        ShapeSpec::Cylinder {
            radius,
            height,
            segments,
        } => TriMesh::cylinder(*radius, *height, *segments),
        ShapeSpec::Obj { path } => crate::mesh::load_obj(path)?,
    })
}

/// The object-to-world transform of a mesh spec: p' = R·(s·p) + t, R = Rz·Ry·Rx.
pub fn object_to_world(spec: &MeshSpec) -> DAffine3 {
    let [rx, ry, rz] = spec.rotate_deg.map(f64::to_radians);
    let r = DMat3::from_rotation_z(rz) * DMat3::from_rotation_y(ry) * DMat3::from_rotation_x(rx);
    DAffine3::from_mat3_translation(r * spec.scale, DVec3::from(spec.translate))
}

impl SceneGeometry {
    /// Loads and places every mesh, finds the slab range and sets up rasterization.
    pub fn build(scene: &Scene) -> Result<SceneGeometry, GeometryError> {
        let camera = Camera::new(&scene.camera, &scene.image);
        let mut meshes = Vec::with_capacity(scene.meshes.len());
        for (index, spec) in scene.meshes.iter().enumerate() {
            let object = object_mesh(spec).map_err(|source| GeometryError::Mesh {
                scene: scene.source.clone(),
                index,
                source,
            })?;
            let world = object.transformed(
                spec.scale,
                DVec3::from(spec.rotate_deg),
                DVec3::from(spec.translate),
            );
            let (mesh, report) = world.analyze();
            if mesh.triangles.is_empty() {
                return Err(GeometryError::EmptyMesh {
                    scene: scene.source.clone(),
                    index,
                });
            }
            meshes.push(WorldMesh {
                mesh,
                report,
                world_to_object: object_to_world(spec).inverse(),
                object_bounds: object.bounds(),
            });
        }
        let (mut z_min, mut z_max) = (f64::INFINITY, f64::NEG_INFINITY);
        for m in &meshes {
            for p in &m.mesh.positions {
                let z = camera.to_camera(*p).z;
                z_min = z_min.min(z);
                z_max = z_max.max(z);
            }
        }
        // Widen the far end slightly so the farthest surface lies strictly before the last back face.
        let depth = (z_max - z_min).max(1e-12 * z_min.abs().max(1.0));
        let depth = depth + depth * 1e-6;
        let mut auto = None;
        let (slab_distance, slabs) = match scene.sweep.slabs {
            SlabSpec::Count(n) => (depth / f64::from(n), n),
            SlabSpec::Auto => {
                let a = auto_slabs(scene, camera.forward, &meshes, depth)?;
                let n = a.count;
                auto = Some(a);
                (depth / f64::from(n), n)
            }
            SlabSpec::Distance(e) => {
                let count = (depth / e).ceil();
                if count > f64::from(MAX_SLABS) {
                    return Err(GeometryError::TooManySlabs {
                        scene: scene.source.clone(),
                        distance: e,
                        count,
                        depth,
                    });
                }
                (e, (count as u32).max(1))
            }
        };
        let refs: Vec<(&[DVec3], &[[u32; 3]])> = meshes
            .iter()
            .map(|m| (m.mesh.positions.as_slice(), m.mesh.triangles.as_slice()))
            .collect();
        let guard = GuardBand::resolve(
            scene.sweep.guard_band,
            &AutoGuardInput {
                camera: &camera,
                meshes: refs.clone(),
                lights: &scene.lights,
                slabs,
                slab_distance,
                optimal_distance: scene.sweep.optimal_distance,
                penumbra: scene.sweep.penumbra,
                variance_compensation: scene.sweep.variance_compensation,
            },
        );
        let raster = RasterSetup::new(&camera, guard, &refs, z_min).map_err(|source| {
            GeometryError::Raster {
                scene: scene.source.clone(),
                source,
            }
        })?;
        Ok(SceneGeometry {
            camera,
            meshes,
            z_origin: z_min,
            slab_distance,
            slabs,
            auto_slabs: auto,
            raster,
        })
    }

    /// Back face of every slab relative to `z_origin`, in f32: a fragment is crossed in slab k
    /// when its depth is `< back[k]` and it was not crossed before.
    pub fn slab_back_faces(&self) -> Vec<f32> {
        (0..self.slabs)
            .map(|k| (f64::from(k + 1) * self.slab_distance) as f32)
            .collect()
    }

    /// One warning per mesh with closed non-manifold edges (used as often in each direction:
    /// accepted, since the parity test holds, but worth knowing).
    pub fn mesh_warnings(&self) -> Vec<String> {
        self.meshes
            .iter()
            .enumerate()
            .filter(|(_, m)| m.report.paired_nonmanifold_edges > 0)
            .map(|(i, m)| {
                format!(
                    "mesh[{i}] has {} non-manifold edges, each used as often in each direction \
                     (closed for the parity test; accepted)",
                    m.report.paired_nonmanifold_edges
                )
            })
            .collect()
    }

    /// Boundary + non-manifold + flipped edges summed over meshes.
    pub fn defect_edges(&self) -> usize {
        self.meshes
            .iter()
            .map(|m| m.report.boundary_edges + m.report.nonmanifold_edges + m.report.flipped_edges)
            .sum()
    }
}
