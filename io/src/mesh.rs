//! Mesh files: the format chosen by the file's extension ([`MeshFormat::from_path`]), one loader
//! per format (OBJ, PLY, glTF 2.0, STL), each ending in the one welding step
//! (`weld::Welder`), so closure is judged the same way (by position) whatever the format.

use std::path::Path;

use convshadow_common::prepare::mesh::{MeshError, MeshFormat, TriMesh};

/// Reads the mesh file `path` in the format its extension names: `.ply` ([`crate::ply`]),
/// `.gltf`/`.glb` ([`crate::gltf`]), `.stl` ([`crate::stl`]), anything else as OBJ
/// ([`crate::obj`]). Every loader validates before allocating by the file's counts, names the
/// file and the element in its errors, and welds vertices by exact position.
pub fn load_mesh(path: &Path) -> Result<TriMesh, MeshError> {
    match MeshFormat::from_path(path) {
        MeshFormat::Obj => crate::obj::load_obj(path),
        MeshFormat::Ply => crate::ply::load_ply(path),
        MeshFormat::Gltf | MeshFormat::Glb => crate::gltf::load_gltf(path),
        MeshFormat::Stl => crate::stl::load_stl(path),
    }
}

/// Bytes a mesh file needs in memory while it is read, held and placed (for the memory budget,
/// before it is read; 0 when the file cannot be inspected, which its loader then reports). OBJ:
/// counted from its lines ([`crate::obj::memory_need`]: vertices, fan triangles, the widest
/// face). Binary data, from its size at the per-vertex and per-triangle costs OBJ counts (96 B
/// and 160 B, see [`crate::obj::OBJ_BYTES_PER_TRIANGLE`]): a binary STL stores 50 bytes a
/// triangle, so 5 × the file; binary PLY and glTF buffers as little as 12 bytes a vertex and
/// 12 a triangle, so 12 × the bytes; their text (ASCII PLY or STL, glTF JSON) likewise (at
/// least as many bytes as binary). A `.gltf` up to 16 MiB is parsed for the `byteLength` of its
/// buffers, which live in other files.
pub fn memory_need(path: &Path) -> u64 {
    let Ok(meta) = std::fs::metadata(path) else {
        return 0;
    };
    let size = meta.len();
    match MeshFormat::from_path(path) {
        MeshFormat::Obj => crate::obj::memory_need(path).unwrap_or(2 * size),
        MeshFormat::Stl => 5 * size,
        MeshFormat::Ply | MeshFormat::Glb => 12 * size,
        MeshFormat::Gltf => {
            let buffers = if size <= 16 << 20 {
                crate::gltf::declared_buffer_bytes(path).unwrap_or(0)
            } else {
                0
            };
            (2 * size).saturating_add(buffers.saturating_mul(12))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::weld::{Welder, weld_indexed};

    #[test]
    fn the_extension_chooses_the_format_and_unknown_ones_are_obj() {
        let f = |p: &str| MeshFormat::from_path(Path::new(p));
        assert_eq!(f("a/bunny.PLY"), MeshFormat::Ply);
        assert_eq!(f("x.gltf"), MeshFormat::Gltf);
        assert_eq!(f("x.GLB"), MeshFormat::Glb);
        assert_eq!(f("x.stl"), MeshFormat::Stl);
        assert_eq!(f("x.obj"), MeshFormat::Obj);
        assert_eq!(f("x.mesh"), MeshFormat::Obj);
        assert_eq!(f("noext"), MeshFormat::Obj);
    }

    #[test]
    fn memory_need_counts_binary_files_at_obj_costs_and_obj_by_its_lines() {
        let dir = std::env::temp_dir().join(format!("cs-mesh-need-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, factor) in [("a.ply", 12), ("a.stl", 5), ("a.glb", 12)] {
            std::fs::write(dir.join(name), [0u8; 100]).unwrap();
            assert_eq!(memory_need(&dir.join(name)), factor * 100, "{name}");
        }
        // An OBJ without vertex or face lines: its text twice.
        std::fs::write(dir.join("a.obj"), [b'#'; 100]).unwrap();
        assert_eq!(memory_need(&dir.join("a.obj")), 200);
        // A .gltf counts its JSON twice and its buffers' byteLength twelve times.
        let json = r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"b.bin","byteLength":1000}]}"#;
        std::fs::write(dir.join("a.gltf"), json).unwrap();
        assert_eq!(
            memory_need(&dir.join("a.gltf")),
            2 * json.len() as u64 + 12_000
        );
        assert_eq!(memory_need(&dir.join("missing.ply")), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn welding_merges_equal_positions_and_signed_zeros_and_drops_unused_vertices() {
        let mut w = Welder::new();
        let positions = [
            [0.0, 0.0, 0.0],
            [9.0, 9.0, 9.0], // unused
            [1.0, 0.0, 0.0],
            [-0.0, 0.0, -0.0], // vertex 0 again
            [0.0, 1.0, 0.0],
        ];
        weld_indexed(&mut w, Path::new("t"), &positions, &[[0, 2, 4], [3, 4, 2]]).unwrap();
        let m = w.finish().expect("triangles");
        assert_eq!(m.positions.len(), 3);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 1]]);
        assert!(Welder::new().finish().is_none());
    }
}
