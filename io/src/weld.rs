//! The step every mesh loader ends in ([`Welder`]), and what the loaders share to get there:
//! reading the file within its limits, indexed triangles welded, the vertex-count error. Its own
//! module so that the loaders and `mesh` (which picks a loader) import it, not each other.

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::path::Path;

use glam::DVec3;

use convshadow_common::prepare::mesh::{MeshError, MeshFormat, TriMesh};

/// The one welding step of every mesh loader: vertices with bit-identical positions (−0.0 =
/// 0.0) become one, in the order they are first given, so closure is judged by position.
pub(crate) struct Welder {
    /// The mesh so far.
    mesh: TriMesh,
    /// Position bits → vertex id.
    ids: HashMap<[u64; 3], u32>,
}

impl Welder {
    /// An empty mesh.
    pub(crate) fn new() -> Welder {
        Welder {
            mesh: TriMesh::default(),
            ids: HashMap::new(),
        }
    }

    /// The id of the vertex at `p` (a new one the first time a position is seen). `p` must be
    /// finite (loaders check it and name the element); `None` when more distinct positions
    /// than u32 indices address.
    pub(crate) fn vertex(&mut self, p: [f64; 3]) -> Option<u32> {
        debug_assert!(p.iter().all(|c| c.is_finite()));
        // +0.0 normalises -0.0 to 0.0.
        let key = p.map(|c| (c + 0.0).to_bits());
        match self.ids.entry(key) {
            Entry::Occupied(e) => Some(*e.get()),
            Entry::Vacant(e) => {
                let next = u32::try_from(self.mesh.positions.len()).ok()?;
                self.mesh.positions.push(DVec3::from_array(p));
                Some(*e.insert(next))
            }
        }
    }

    /// Adds a triangle of ids returned by [`Welder::vertex`].
    pub(crate) fn triangle(&mut self, t: [u32; 3]) {
        self.mesh.triangles.push(t);
    }

    /// The mesh, or `None` when it has no triangle.
    pub(crate) fn finish(self) -> Option<TriMesh> {
        (!self.mesh.triangles.is_empty()).then_some(self.mesh)
    }
}

/// The error for more distinct positions than u32 indices address.
pub(crate) fn too_many_vertices(path: &Path) -> MeshError {
    MeshError::Invalid {
        path: path.to_path_buf(),
        message: format!(
            "more than {} distinct vertex positions (expected a mesh addressable with u32 indices)",
            u32::MAX
        ),
    }
}

/// Welds the triangles `triangles` over `positions` (already checked: indices in range,
/// positions finite), keeping only the vertices some triangle uses, in their order in
/// `positions`, as tobj does for OBJ.
pub(crate) fn weld_indexed(
    welder: &mut Welder,
    path: &Path,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<(), MeshError> {
    let mut used = vec![false; positions.len()];
    for t in triangles {
        for &i in t {
            used[i as usize] = true;
        }
    }
    let mut local = vec![0u32; positions.len()];
    for (i, p) in positions.iter().enumerate() {
        if used[i] {
            local[i] = welder.vertex(*p).ok_or_else(|| too_many_vertices(path))?;
        }
    }
    for t in triangles {
        welder.triangle(t.map(|i| local[i as usize]));
    }
    Ok(())
}

/// Reads the file for a loader of `format`, mapping I/O errors to [`MeshError::Io`].
pub(crate) fn read_file(path: &Path, format: MeshFormat) -> Result<Vec<u8>, MeshError> {
    crate::input::read_limited(path, crate::input::MAX_MESH_BYTES).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        format,
        source,
    })
}
