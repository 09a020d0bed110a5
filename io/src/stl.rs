//! STL reading (ASCII and binary) through the `stl_io` crate's triangle iterator, then the
//! shared welding (`weld::Welder`): STL stores every triangle's three corners on their
//! own, so welding by exact position is what recovers the mesh's topology.
//!
//! What is read: the three vertices of every facet, in their order (the stored facet normal and
//! a binary file's attribute bytes are ignored; winding alone orients a triangle, as in OBJ).

use std::io::Cursor;
use std::path::Path;

use stl_io::TriangleIterator;

use convshadow_common::prepare::mesh::{MeshError, MeshFormat, TriMesh};

use crate::weld::{Welder, read_file, too_many_vertices};

/// Bytes of a binary STL's header (80) and triangle count (4).
const BINARY_HEADER: usize = 84;
/// Bytes of one binary STL facet: normal and 3 vertices (12 f32) and the attribute count.
const BINARY_FACET: u64 = 50;

/// Loads an STL file (read whole, at most [`crate::input::MAX_MESH_BYTES`]).
///
/// Binary or ASCII is decided by the size first: a file of exactly 84 + 50·n bytes, n the
/// count in bytes 80–83, is binary even when its header starts with `solid` (many exporters
/// write that); otherwise a file starting with `solid` is ASCII, and anything else is a
/// binary file whose size does not match its count (refused, before any facet is read).
/// Errors name the facet (from 0): `part.stl: facet 7: non-finite coordinate …`.
pub fn load_stl(path: &Path) -> Result<TriMesh, MeshError> {
    let mut bytes = read_file(path, MeshFormat::Stl)?;
    let format = |message: String| MeshError::Format {
        path: path.to_path_buf(),
        format: MeshFormat::Stl,
        message,
    };
    let declared = bytes
        .get(80..BINARY_HEADER)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]));
    let binary_len = declared.map(|n| BINARY_HEADER as u64 + BINARY_FACET * u64::from(n));
    let is_binary = binary_len == Some(bytes.len() as u64);
    let starts_solid = bytes.starts_with(b"solid");
    if is_binary {
        // stl_io reads a file starting with "solid " as ASCII: blank the header, which holds
        // no data, so the binary reader takes it.
        bytes[..5].copy_from_slice(b"     ");
    } else if starts_solid {
        // stl_io wants "solid " with a space; "solid" alone on the first line (no name) is
        // valid STL too.
        if matches!(bytes.get(5), None | Some(b'\n' | b'\r')) {
            bytes.insert(5, b' ');
        }
    } else {
        return Err(match (declared, binary_len) {
            (Some(n), Some(len)) => format(format!(
                "binary STL header declares {n} triangles, which take {len} bytes, but the file \
                 has {} bytes (a truncated file or a wrong count; an ASCII STL starts with \
                 \"solid\")",
                bytes.len()
            )),
            _ => format(format!(
                "{} bytes, shorter than a binary STL's 84-byte header, and not ASCII STL (which \
                 starts with \"solid\")",
                bytes.len()
            )),
        });
    }
    let mut cursor = Cursor::new(bytes.as_slice());
    let triangles = stl_io::create_stl_reader(&mut cursor)
        .map_err(|e| format(format!("cannot start reading: {e}")))?;
    weld_facets(path, triangles)
}

/// Welds the facets of `triangles` in order; errors name the facet.
fn weld_facets(
    path: &Path,
    triangles: Box<dyn TriangleIterator<Item = std::io::Result<stl_io::Triangle>> + '_>,
) -> Result<TriMesh, MeshError> {
    let facet = |i: usize, message: String| MeshError::Element {
        path: path.to_path_buf(),
        element: format!("facet {i}"),
        message,
    };
    let mut welder = Welder::new();
    for (i, t) in triangles.enumerate() {
        let t = t.map_err(|e| facet(i, format!("cannot read it: {e} (expected \"facet normal nx ny nz\", \"outer loop\", 3 \"vertex x y z\" lines, \"endloop\", \"endfacet\", or 50 bytes in a binary file)")))?;
        let mut ids = [0u32; 3];
        for (k, v) in t.vertices.iter().enumerate() {
            let p = [v[0], v[1], v[2]].map(f64::from);
            if p.iter().any(|c| !c.is_finite()) {
                return Err(facet(
                    i,
                    format!(
                        "vertex {k} has a non-finite coordinate {p:?} (expected finite numbers)"
                    ),
                ));
            }
            ids[k] = welder.vertex(p).ok_or_else(|| too_many_vertices(path))?;
        }
        welder.triangle(ids);
    }
    welder.finish().ok_or_else(|| MeshError::Format {
        path: path.to_path_buf(),
        format: MeshFormat::Stl,
        message: "no triangles (expected at least one facet)".into(),
    })
}
