//! From a scene to world-space meshes, the slab range and the rasterizer set-up.

use std::borrow::Cow;

use glam::DVec3;

use crate::contract::files::GeometryFiles;
use crate::model::scene::{MAX_SLABS, MeshSpec, Projection, Scene, ShapeSpec, SlabSpec};
use crate::prepare::auto_slabs::{AutoSlabs, auto_slabs};
use crate::prepare::camera::Camera;
use crate::prepare::error::GeometryError;
use crate::prepare::guard::{AutoGuardInput, GuardBand};
use crate::prepare::mesh::{MeshError, TriMesh};
use crate::prepare::placement::{WorldMesh, object_to_world};
use crate::prepare::raster::RasterSetup;

/// Everything geometric the LDI and the sweep need.
#[derive(Clone, Debug)]
pub struct SceneGeometry {
    /// The camera.
    pub camera: Camera,
    /// World meshes in scene order.
    pub meshes: Vec<WorldMesh>,
    /// Camera depth of the front of the first slab (the scene's nearest vertex; a perspective
    /// camera's `near` where given).
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

/// A mesh spec's object-space mesh: a built-in shape, or the mesh read from its file (`read`,
/// from [`GeometryFiles::meshes`]; `None` when the host did not read it).
pub fn object_mesh<'a>(
    spec: &MeshSpec,
    read: Option<&'a TriMesh>,
) -> Result<Cow<'a, TriMesh>, MeshError> {
    // A mesh file's mesh is borrowed: placing it makes a new one anyway.
    Ok(match &spec.shape {
        ShapeSpec::Obj { path } => {
            Cow::Borrowed(read.ok_or_else(|| MeshError::NotRead { path: path.clone() })?)
        }
        ShapeSpec::Box { size } => Cow::Owned(TriMesh::unit_box(DVec3::from(*size))),
        ShapeSpec::Sphere {
            radius,
            subdivisions,
        } => Cow::Owned(TriMesh::icosphere(*radius, *subdivisions)),
        ShapeSpec::Torus {
            major,
            minor,
            segments,
        } => Cow::Owned(TriMesh::torus(*major, *minor, *segments)),
        ShapeSpec::Cylinder {
            radius,
            height,
            segments,
        } => Cow::Owned(TriMesh::cylinder(*radius, *height, *segments)),
    })
}

impl SceneGeometry {
    /// Places every mesh (built-in shapes built here, mesh files as the host read them:
    /// `convshadow_io::read_geometry_files`), finds the slab range and sets up rasterization.
    pub fn build(scene: &Scene, files: &GeometryFiles) -> Result<SceneGeometry, GeometryError> {
        let camera = Camera::new(&scene.camera, &scene.image);
        let mut meshes = Vec::with_capacity(scene.meshes.len());
        for (index, spec) in scene.meshes.iter().enumerate() {
            let read = files.meshes.get(index).and_then(Option::as_ref);
            let object = object_mesh(spec, read).map_err(|source| GeometryError::Mesh {
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
        let near = match scene.camera.projection {
            Projection::Orthographic => None,
            // In perspective every mesh lies beyond the near depth (the eye, or camera.near).
            Projection::Perspective { near, .. } => Some(near),
        };
        for (index, m) in meshes.iter().enumerate() {
            let mesh_min = m
                .mesh
                .positions
                .iter()
                .map(|p| camera.to_camera(*p).z)
                .fold(f64::INFINITY, f64::min);
            if let Some(near) = near
                && mesh_min <= near.unwrap_or(0.0)
            {
                return Err(GeometryError::BeforeNear {
                    scene: scene.source.clone(),
                    index,
                    depth: mesh_min,
                    near,
                });
            }
            for p in &m.mesh.positions {
                let z = camera.to_camera(*p).z;
                z_min = z_min.min(z);
                z_max = z_max.max(z);
            }
        }
        // A perspective sweep given camera.near starts there.
        if let Some(Some(near)) = near {
            z_min = near;
        }
        // Widen the far end slightly so the farthest surface lies strictly before the last back face.
        let depth = (z_max - z_min).max(1e-12 * z_min.abs().max(1.0));
        let depth = depth + depth * 1e-6;
        let mut auto = None;
        let (slab_distance, slabs) = match scene.sweep.slabs {
            SlabSpec::Count(n) => (depth / f64::from(n), n),
            SlabSpec::Auto => {
                let a = auto_slabs(scene, files, &camera, &meshes, z_min, depth)?;
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
        // Perspective: the LDI covers the image alone (where the perspective sweep's light
        // buffers live is its own choice: docs/how-it-works.md, "A perspective camera").
        let guard = if near.is_some() {
            GuardBand::default()
        } else {
            GuardBand::resolve(
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
            )
        };
        let mut raster = RasterSetup::new(&camera, guard, &refs, z_min).map_err(|source| {
            GeometryError::Raster {
                scene: scene.source.clone(),
                source,
            }
        })?;
        // Open meshes are thin shells: out of the parity test.
        for (i, m) in meshes.iter().enumerate() {
            if !m.report.is_closed() {
                raster.parity_meshes &= !(1u32 << i);
            }
        }
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

    /// The same geometry swept from `z_origin` in `slabs` slabs of `slab_distance` (a
    /// perspective camera's `near`, which its slab grid shares): the rasterizer set-up again,
    /// depths relative to the new origin; the guard band kept (it depends on where occluders
    /// and receivers are, not on where the sweep starts).
    pub fn with_slabs(
        mut self,
        scene: &Scene,
        z_origin: f64,
        slab_distance: f64,
        slabs: u32,
    ) -> Result<SceneGeometry, GeometryError> {
        let refs: Vec<(&[DVec3], &[[u32; 3]])> = self
            .meshes
            .iter()
            .map(|m| (m.mesh.positions.as_slice(), m.mesh.triangles.as_slice()))
            .collect();
        let parity_meshes = self.raster.parity_meshes;
        let mut raster = RasterSetup::new(&self.camera, self.raster.guard, &refs, z_origin)
            .map_err(|source| GeometryError::Raster {
                scene: scene.source.clone(),
                source,
            })?;
        raster.parity_meshes = parity_meshes;
        self.raster = raster;
        self.z_origin = z_origin;
        self.slab_distance = slab_distance;
        self.slabs = slabs;
        Ok(self)
    }

    /// Back face of every slab relative to `z_origin`, in f32: a fragment is crossed in slab k
    /// when its depth is `< back[k]` and it was not crossed before.
    pub fn slab_back_faces(&self) -> Vec<f32> {
        (0..self.slabs)
            .map(|k| (f64::from(k + 1) * self.slab_distance) as f32)
            .collect()
    }

    /// One warning per open mesh (rendered as a thin shell) and per closed mesh with closed
    /// non-manifold edges (used as often in each direction: accepted, since the parity test
    /// holds, but worth knowing).
    pub fn mesh_warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        for (i, m) in self.meshes.iter().enumerate() {
            let r = &m.report;
            if !r.is_closed() {
                warnings.push(format!(
                    "mesh[{i}] is not closed ({} boundary, {} non-manifold and {} flipped \
                     edges): rendered as a thin shell, each crossing of its surface one \
                     reference length of its material, with no inside (docs/scene-format.md, \
                     \"Open meshes\")",
                    r.boundary_edges, r.nonmanifold_edges, r.flipped_edges
                ));
            } else if r.paired_nonmanifold_edges > 0 {
                warnings.push(format!(
                    "mesh[{i}] has {} non-manifold edges, each used as often in each direction \
                     (closed for the parity test; accepted)",
                    r.paired_nonmanifold_edges
                ));
            }
        }
        warnings
    }

    /// The meshes rendered as thin shells (not closed), by index.
    pub fn shell_meshes(&self) -> Vec<usize> {
        (0..self.meshes.len())
            .filter(|&i| self.raster.parity_meshes & (1u32 << i) == 0)
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
