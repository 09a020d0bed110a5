//! glTF 2.0 reading (`.gltf` JSON and `.glb` binary): the `gltf` crate parses and validates the
//! document; the vertex data is read here with checked bounds, then welded with every other
//! format's vertices (`weld::Welder`).
//!
//! What is read: the scene to show (the file's `scene`, else its first scene; a file with no
//! scene at all: every mesh once, untransformed), walked from its root nodes with each node's
//! transform (matrix, or translation · rotation · scale) composed in f64 down the tree; every
//! primitive of mode TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN of every mesh a node holds: its
//! POSITION accessor (VEC3 of f32) and its indices (u8, u16 or u32 scalars; none: the vertices
//! in order). A node whose transform mirrors (negative determinant) has its triangles' winding
//! reversed, as the glTF specification asks, so the mesh stays outward. Points and lines are
//! skipped, as are normals, materials, skins, morph targets and animation. Sparse accessors,
//! accessors without a buffer view, and quantized positions (KHR_mesh_quantization) are refused
//! with an error naming the accessor.
//!
//! Why not the crate's own readers (`Primitive::reader`): they compute accessor ranges with
//! unchecked arithmetic and assume the accessor's type, which a malformed file can make panic;
//! here every offset, stride and count is checked against its buffer before a byte is read.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use glam::{DMat4, DQuat, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::buffer::Source;
use gltf::mesh::{Mode, Semantic};
use gltf::scene::Transform;

use convshadow_common::prepare::mesh::{MeshError, MeshFormat, TriMesh};

use crate::weld::{Welder, read_file, weld_indexed};

/// The file's buffers, each as bytes (the GLB chunk, a decoded data URI, or a file beside it).
type Buffers = Vec<Vec<u8>>;

/// An error in one element of the file.
fn element(path: &Path, element: impl Into<String>, message: impl Into<String>) -> MeshError {
    MeshError::Element {
        path: path.to_path_buf(),
        element: element.into(),
        message: message.into(),
    }
}

/// The format of `path` (`.glb` or `.gltf`).
fn format_of(path: &Path) -> MeshFormat {
    match MeshFormat::from_path(path) {
        MeshFormat::Glb => MeshFormat::Glb,
        _ => MeshFormat::Gltf,
    }
}

/// Parses and validates the document (the `gltf` crate). The crate's validation indexes a
/// primitive's POSITION accessor without a bounds check (gltf-json 1.4.1, `mesh.rs`
/// `primitive_validate_hook`), so that reference is checked here first.
fn parse(path: &Path, bytes: &[u8]) -> Result<gltf::Gltf, MeshError> {
    let invalid = |message: String| MeshError::Format {
        path: path.to_path_buf(),
        format: format_of(path),
        message,
    };
    let raw =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| invalid(e.to_string()))?;
    let json = raw.document.as_json();
    let accessors = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= accessors {
                    return Err(element(
                        path,
                        format!("mesh {m} primitive {p}"),
                        format!(
                            "attribute {semantic:?} refers to accessor {}, but the file has {accessors}",
                            index.value()
                        ),
                    ));
                }
            }
        }
    }
    let document =
        gltf::Document::from_json(raw.document.into_json()).map_err(|e| invalid(e.to_string()))?;
    Ok(gltf::Gltf {
        document,
        blob: raw.blob,
    })
}

/// The sum of the `byteLength` of a `.gltf` file's buffers (for the memory budget), or `None`
/// when the file cannot be read or parsed.
pub(crate) fn declared_buffer_bytes(path: &Path) -> Option<u64> {
    let bytes = crate::input::read_limited(path, 16 << 20).ok()?;
    let gltf = gltf::Gltf::from_slice(&bytes).ok()?;
    Some(
        gltf.document
            .buffers()
            .map(|b| b.length() as u64)
            .fold(0, u64::saturating_add),
    )
}

/// Reads every buffer: the GLB binary chunk, a base64 `data:` URI, or a file named by a
/// relative URI (percent-escapes decoded), resolved against the folder of `path` and read as
/// any input file is (a regular file, at most [`crate::input::MAX_MESH_BYTES`]). Each must hold
/// its `byteLength`.
fn read_buffers(path: &Path, gltf: &gltf::Gltf) -> Result<Buffers, MeshError> {
    let mut out = Vec::new();
    for b in gltf.document.buffers() {
        let what = format!("buffer {}", b.index());
        let data = match b.source() {
            Source::Bin => gltf.blob.clone().ok_or_else(|| {
                element(
                    path,
                    &what,
                    "has no uri, so it is the GLB binary chunk, but the file has none",
                )
            })?,
            Source::Uri(uri) if uri.starts_with("data:") => {
                let Some((_, data)) = uri.split_once(";base64,") else {
                    return Err(element(
                        path,
                        &what,
                        "a data URI that is not base64 (expected \"data:application/octet-stream;base64,…\")",
                    ));
                };
                base64::engine::general_purpose::STANDARD
                    .decode(data)
                    .map_err(|e| element(path, &what, format!("bad base64 data URI: {e}")))?
            }
            Source::Uri(uri) => {
                if uri.contains("://") || uri.starts_with('/') {
                    return Err(element(
                        path,
                        &what,
                        format!(
                            "uri \"{uri}\" is not a relative file name (expected a file beside the glTF file, or a data URI)"
                        ),
                    ));
                }
                let name = urlencoding::decode(uri)
                    .map_err(|e| element(path, &what, format!("bad uri \"{uri}\": {e}")))?;
                let file: PathBuf = path
                    .parent()
                    .unwrap_or_else(|| Path::new("."))
                    .join(name.as_ref());
                crate::input::read_limited(&file, crate::input::MAX_MESH_BYTES).map_err(|e| {
                    element(path, &what, format!("cannot read {}: {e}", file.display()))
                })?
            }
        };
        if data.len() < b.length() {
            return Err(element(
                path,
                &what,
                format!(
                    "holds {} bytes, fewer than its byteLength {}",
                    data.len(),
                    b.length()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of an accessor's elements (checked against its view and buffer) and the stride
/// between them, for elements of `elem` bytes.
fn accessor_bytes<'b>(
    path: &Path,
    acc: &gltf::Accessor<'_>,
    elem: usize,
    buffers: &'b Buffers,
) -> Result<(&'b [u8], usize), MeshError> {
    let what = format!("accessor {}", acc.index());
    if acc.sparse().is_some() {
        return Err(element(path, what, "sparse accessors are not supported"));
    }
    let Some(view) = acc.view() else {
        return Err(element(
            path,
            what,
            "has no bufferView (zero-filled accessors are not supported)",
        ));
    };
    let buffer = &buffers[view.buffer().index()];
    let view_what = format!("bufferView {}", view.index());
    let view_bytes = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| {
            element(
                path,
                &view_what,
                format!(
                    "bytes {}..{} + {} lie beyond its buffer's {} bytes",
                    view.offset(),
                    view.offset(),
                    view.length(),
                    buffer.len()
                ),
            )
        })?;
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(element(
            path,
            &view_what,
            format!("byteStride {stride} is less than the {elem} bytes of an element"),
        ));
    }
    let count = acc.count();
    if count == 0 {
        return Ok((&[], stride));
    }
    let span = (count - 1)
        .checked_mul(stride)
        .and_then(|s| s.checked_add(elem))
        .and_then(|s| s.checked_add(acc.offset()));
    let bytes = span
        .and_then(|end| view_bytes.get(acc.offset()..end))
        .ok_or_else(|| {
            element(
                path,
                &what,
                format!(
                    "{count} elements of {elem} bytes every {stride} from byte {} do not fit \
                     its bufferView's {} bytes (a wrong count or a truncated buffer)",
                    acc.offset(),
                    view_bytes.len()
                ),
            )
        })?;
    Ok((bytes, stride))
}

/// The POSITION accessor's vertices (VEC3 f32), each checked finite.
fn read_positions(
    path: &Path,
    acc: &gltf::Accessor<'_>,
    buffers: &Buffers,
) -> Result<Vec<[f64; 3]>, MeshError> {
    let what = format!("accessor {}", acc.index());
    if acc.dimensions() != Dimensions::Vec3 || acc.data_type() != DataType::F32 {
        return Err(element(
            path,
            what,
            format!(
                "POSITION is {:?} of {:?} (expected VEC3 of FLOAT; quantized positions, \
                 KHR_mesh_quantization, are not supported)",
                acc.dimensions(),
                acc.data_type()
            ),
        ));
    }
    let (bytes, stride) = accessor_bytes(path, acc, 12, buffers)?;
    let mut out = Vec::new();
    out.try_reserve_exact(acc.count()).map_err(|e| {
        element(
            path,
            &what,
            format!("cannot allocate {} vertices: {e}", acc.count()),
        )
    })?;
    for i in 0..acc.count() {
        let at = i * stride;
        let f = |k: usize| {
            let b = &bytes[at + 4 * k..at + 4 * k + 4];
            f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        let p = [f(0), f(1), f(2)];
        if p.iter().any(|c| !c.is_finite()) {
            return Err(element(
                path,
                &what,
                format!("vertex {i} has a non-finite coordinate {p:?} (expected finite numbers)"),
            ));
        }
        out.push(p);
    }
    Ok(out)
}

/// The indices accessor's values (SCALAR u8, u16 or u32).
fn read_indices(
    path: &Path,
    acc: &gltf::Accessor<'_>,
    buffers: &Buffers,
) -> Result<Vec<u32>, MeshError> {
    let what = format!("accessor {}", acc.index());
    let size = match (acc.dimensions(), acc.data_type()) {
        (Dimensions::Scalar, DataType::U8) => 1,
        (Dimensions::Scalar, DataType::U16) => 2,
        (Dimensions::Scalar, DataType::U32) => 4,
        (d, t) => {
            return Err(element(
                path,
                what,
                format!(
                    "indices are {d:?} of {t:?} (expected SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT)"
                ),
            ));
        }
    };
    let (bytes, stride) = accessor_bytes(path, acc, size, buffers)?;
    let mut out = Vec::new();
    out.try_reserve_exact(acc.count()).map_err(|e| {
        element(
            path,
            &what,
            format!("cannot allocate {} indices: {e}", acc.count()),
        )
    })?;
    for i in 0..acc.count() {
        let b = &bytes[i * stride..];
        out.push(match size {
            1 => u32::from(b[0]),
            2 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        });
    }
    Ok(out)
}

/// A node's own transform in f64.
fn node_matrix(t: Transform) -> DMat4 {
    match t {
        Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
        }
        Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let [x, y, z, w] = rotation.map(f64::from);
            DMat4::from_scale_rotation_translation(
                DVec3::from_array(scale.map(f64::from)),
                DQuat::from_xyzw(x, y, z, w),
                DVec3::from_array(translation.map(f64::from)),
            )
        }
    }
}

/// Adds one primitive's triangles, placed by `world`, to `welder`.
fn add_primitive(
    path: &Path,
    mesh: usize,
    prim: &gltf::Primitive<'_>,
    world: &DMat4,
    buffers: &Buffers,
    welder: &mut Welder,
) -> Result<bool, MeshError> {
    let what = format!("mesh {mesh} primitive {}", prim.index());
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(false);
    }
    let Some(pos_acc) = prim.get(&Semantic::Positions) else {
        return Err(element(path, what, "has no POSITION attribute"));
    };
    let mut positions = read_positions(path, &pos_acc, buffers)?;
    let n = positions.len();
    let indices = match prim.indices() {
        Some(acc) => read_indices(path, &acc, buffers)?,
        None => (0..n as u32).collect(),
    };
    if let Some((k, &i)) = indices.iter().enumerate().find(|(_, i)| **i as usize >= n) {
        return Err(element(
            path,
            what,
            format!(
                "index {k}: vertex {i} out of range (POSITION has {n} vertices, indices 0..={})",
                n.saturating_sub(1)
            ),
        ));
    }
    let m = indices.len();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    match mode {
        Mode::Triangles => {
            if m % 3 != 0 {
                return Err(element(
                    path,
                    what,
                    format!("{m} indices in TRIANGLES mode, not a multiple of 3"),
                ));
            }
            triangles.extend(indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
        }
        Mode::TriangleStrip => {
            for i in 0..m.saturating_sub(2) {
                let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
                triangles.push(if i % 2 == 0 { [a, b, c] } else { [b, a, c] });
            }
        }
        _ => {
            for i in 1..m.saturating_sub(1) {
                triangles.push([indices[i], indices[i + 1], indices[0]]);
            }
        }
    }
    if *world != DMat4::IDENTITY {
        for p in &mut positions {
            let q = world.transform_point3(DVec3::from_array(*p)).to_array();
            if q.iter().any(|c| !c.is_finite()) {
                return Err(element(
                    path,
                    what,
                    format!(
                        "a vertex placed by its node's transform is not finite: {q:?} (expected finite transforms)"
                    ),
                ));
            }
            *p = q;
        }
        if world.determinant() < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
    }
    weld_indexed(welder, path, &positions, &triangles)?;
    Ok(true)
}

/// Loads a glTF 2.0 file (`.gltf` or `.glb`, read whole, at most
/// [`crate::input::MAX_MESH_BYTES`]; see the module's documentation for what is read). Errors
/// name the file and the element: `scene.glb: mesh 0 primitive 1: index 4: vertex 99 out of
/// range (POSITION has 40 vertices, …)`, `accessor 3: …`, `node 5: …`.
pub fn load_gltf(path: &Path) -> Result<TriMesh, MeshError> {
    let format = format_of(path);
    let bytes = read_file(path, format)?;
    let gltf = parse(path, &bytes)?;
    drop(bytes);
    let buffers = read_buffers(path, &gltf)?;
    let doc = &gltf.document;
    let mut welder = Welder::new();
    let mut skipped = 0usize;
    let mut add_mesh = |mesh: gltf::Mesh<'_>, world: &DMat4, welder: &mut Welder| {
        for prim in mesh.primitives() {
            if !add_primitive(path, mesh.index(), &prim, world, &buffers, welder)? {
                skipped += 1;
            }
        }
        Ok::<(), MeshError>(())
    };
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            let mut visited = vec![false; doc.nodes().len()];
            // Depth first, in the file's order (the stack holds siblings reversed).
            let mut stack: Vec<(gltf::Node<'_>, DMat4)> =
                scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
            stack.reverse();
            while let Some((node, parent)) = stack.pop() {
                let what = format!("node {}", node.index());
                if std::mem::replace(&mut visited[node.index()], true) {
                    return Err(element(
                        path,
                        what,
                        "is reached twice from the scene (glTF nodes must form disjoint trees)",
                    ));
                }
                let own = node_matrix(node.transform());
                if !own.is_finite() {
                    return Err(element(path, what, "has a non-finite transform"));
                }
                let world = parent * own;
                if let Some(mesh) = node.mesh() {
                    add_mesh(mesh, &world, &mut welder)?;
                }
                let first = stack.len();
                stack.extend(node.children().map(|c| (c, world)));
                stack[first..].reverse();
            }
        }
        None => {
            for mesh in doc.meshes() {
                add_mesh(mesh, &DMat4::IDENTITY, &mut welder)?;
            }
        }
    }
    welder.finish().ok_or_else(|| MeshError::Format {
        path: path.to_path_buf(),
        format,
        message: format!(
            "no triangles in the scene shown (expected a node with a mesh whose primitives are \
             TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN; {skipped} point or line primitive(s) \
             skipped)"
        ),
    })
}
