//! PLY reading (the Stanford polygon format; ASCII, binary little- and big-endian) through the
//! `ply-rs-bw` crate, then the shared welding (`weld::Welder`).
//!
//! What is read: the `vertex` element's `x`, `y`, `z` (any scalar type) and the `face`
//! element's vertex index list (`vertex_indices` or `vertex_index`, any integer type); faces
//! with more than 3 vertices are triangulated as fans (0, i, i + 1), as OBJ polygons are. Every
//! other element and property (normals, colours, `tristrips`, `edge`, …) is parsed and ignored.

use std::io::Cursor;
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    BeginList, ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType,
    ScalarType,
};

use convshadow_common::prepare::mesh::{MeshError, MeshFormat, TriMesh};

use crate::weld::{Welder, read_file, weld_indexed};

/// Names the face element's index list may have.
const FACE_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// One `vertex`: its coordinates as f64 (every PLY scalar type converts exactly).
struct PlyVertex([f64; 3]);

impl PlyVertex {
    /// Stores coordinate `name` when it is x, y or z.
    fn set(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        let k = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return PropertyAccessResult::Ignored,
        };
        self.0[k] = v;
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex([0.0; 3])
    }
    fn set_char(&mut self, n: &str, v: i8) -> PropertyAccessResult {
        self.set(n, f64::from(v))
    }
    fn set_uchar(&mut self, n: &str, v: u8) -> PropertyAccessResult {
        self.set(n, f64::from(v))
    }
    fn set_short(&mut self, n: &str, v: i16) -> PropertyAccessResult {
        self.set(n, f64::from(v))
    }
    fn set_ushort(&mut self, n: &str, v: u16) -> PropertyAccessResult {
        self.set(n, f64::from(v))
    }
    fn set_int(&mut self, n: &str, v: i32) -> PropertyAccessResult {
        self.set(n, f64::from(v))
    }
    fn set_uint(&mut self, n: &str, v: u32) -> PropertyAccessResult {
        self.set(n, f64::from(v))
    }
    fn set_float(&mut self, n: &str, v: f32) -> PropertyAccessResult {
        self.set(n, f64::from(v))
    }
    fn set_double(&mut self, n: &str, v: f64) -> PropertyAccessResult {
        self.set(n, v)
    }
}

/// One `face`: its vertex indices as written (i64 holds every PLY integer type, so a negative
/// index is seen as such).
#[derive(Default)]
struct PlyFace(Vec<i64>);

impl PlyFace {
    /// Stores the list when `name` is the index list.
    fn set<T: Copy + Into<i64>>(&mut self, name: &str, v: &[T]) -> PropertyAccessResult {
        if !FACE_LISTS.contains(&name) {
            return PropertyAccessResult::Ignored;
        }
        self.0 = v.iter().map(|&x| x.into()).collect();
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace(Vec::new())
    }
    fn set_list_char(&mut self, n: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.set(n, &v)
    }
    fn set_list_uchar(&mut self, n: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.set(n, &v)
    }
    fn set_list_short(&mut self, n: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.set(n, &v)
    }
    fn set_list_ushort(&mut self, n: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.set(n, &v)
    }
    fn set_list_int(&mut self, n: &str, v: Vec<i32>) -> PropertyAccessResult {
        self.set(n, &v)
    }
    fn set_list_uint(&mut self, n: &str, v: Vec<u32>) -> PropertyAccessResult {
        self.set(n, &v)
    }
    fn set_list_float(&mut self, n: &str, _: Vec<f32>) -> PropertyAccessResult {
        self.refuse(n)
    }
    fn set_list_double(&mut self, n: &str, _: Vec<f64>) -> PropertyAccessResult {
        self.refuse(n)
    }
    fn begin_list_float(&mut self, n: &str, _: usize) -> BeginList<'_, f32> {
        match self.refuse(n) {
            PropertyAccessResult::UnsupportedType => BeginList::UnsupportedType,
            _ => BeginList::UseSetter,
        }
    }
    fn begin_list_double(&mut self, n: &str, _: usize) -> BeginList<'_, f64> {
        match self.refuse(n) {
            PropertyAccessResult::UnsupportedType => BeginList::UnsupportedType,
            _ => BeginList::UseSetter,
        }
    }
}

impl PlyFace {
    /// A float list is refused when it is the index list (the header check reports it first).
    fn refuse(&self, name: &str) -> PropertyAccessResult {
        if FACE_LISTS.contains(&name) {
            PropertyAccessResult::UnsupportedType
        } else {
            PropertyAccessResult::Ignored
        }
    }
}

/// Any other element: parsed (the payload must be consumed) and dropped.
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Skipped
    }
}

/// Bytes of one value of a scalar type in a binary file.
fn scalar_bytes(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The fewest bytes one element of `e` takes in the payload: binary, every scalar's size and
/// every list's count (an empty list); ASCII, a digit and a separator per value.
fn min_element_bytes(e: &ElementDef, encoding: Encoding) -> u64 {
    e.properties
        .values()
        .map(|p| match (&p.data_type, encoding) {
            (_, Encoding::Ascii) => 2,
            (PropertyType::Scalar(t), _) => scalar_bytes(t),
            (PropertyType::List(count, _), _) => scalar_bytes(count),
        })
        .sum()
}

/// Checks the header before any payload is read: a vertex element with x, y, z scalars, a face
/// element with an integer index list, vertex indices addressable with u32, and counts the
/// bytes after the header can hold (so no count from a corrupt header sizes an allocation).
fn check_header(
    path: &Path,
    header: &Header,
    payload_bytes: u64,
) -> Result<(usize, usize), MeshError> {
    let format = |message: String| MeshError::Format {
        path: path.to_path_buf(),
        format: MeshFormat::Ply,
        message,
    };
    let vertex = header.elements.get("vertex").ok_or_else(|| {
        format(
            "no \"vertex\" element (expected \"element vertex N\" with properties x, y, z)".into(),
        )
    })?;
    for axis in ["x", "y", "z"] {
        match vertex.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(PropertyType::List(..)) => {
                return Err(format(format!(
                    "vertex property \"{axis}\" is a list (expected a number)"
                )));
            }
            None => {
                return Err(format(format!(
                    "the vertex element has no property \"{axis}\" (expected x, y and z)"
                )));
            }
        }
    }
    let face = header.elements.get("face").ok_or_else(|| {
        format("no \"face\" element (expected \"element face N\" with a \"property list … vertex_indices\"; a point cloud has no surface)".into())
    })?;
    let list = FACE_LISTS
        .iter()
        .find_map(|n| face.properties.get(*n))
        .ok_or_else(|| {
            format(
                "the face element has no \"vertex_indices\" (or \"vertex_index\") list property"
                    .into(),
            )
        })?;
    match &list.data_type {
        PropertyType::List(_, ScalarType::Float | ScalarType::Double) | PropertyType::Scalar(_) => {
            return Err(format(format!(
                "face property \"{}\" is {:?} (expected a list of integer vertex indices)",
                list.name, list.data_type
            )));
        }
        PropertyType::List(..) => {}
    }
    if u32::try_from(vertex.count).is_err() {
        return Err(format(format!(
            "{} vertices declared, more than u32 indices address",
            vertex.count
        )));
    }
    let mut need: u64 = 0;
    for e in header.elements.values() {
        let bytes = (e.count as u64).saturating_mul(min_element_bytes(e, header.encoding));
        need = need.saturating_add(bytes);
        if need > payload_bytes {
            return Err(format(format!(
                "the header declares {} \"{}\" elements, but the {payload_bytes} bytes after the \
                 header cannot hold the elements declared up to them (at least {need} bytes): a \
                 truncated file or a wrong count",
                e.count, e.name
            )));
        }
    }
    Ok((vertex.count, face.count))
}

/// The parser's error, with the element being read and the line (ASCII files).
fn parse_error(path: &Path, what: &str, e: ply_rs_bw::parser::ParseError) -> MeshError {
    let element = match e.line() {
        Some(line) => format!("line {line} ({what})"),
        None => what.to_string(),
    };
    // The crate's message repeats the line ("Line 12: …"): drop that prefix.
    let text = e.to_string();
    let message = match e.line() {
        Some(line) => text
            .strip_prefix(&format!("Line {line}: "))
            .unwrap_or(&text)
            .to_string(),
        None => text,
    };
    MeshError::Element {
        path: path.to_path_buf(),
        element,
        message: message.replace('\n', " ").replace('\t', ""),
    }
}

/// Loads a PLY file (ASCII or binary, read whole, at most [`crate::input::MAX_MESH_BYTES`]).
///
/// The header is checked first (`check_header`: elements, property types, counts against
/// the bytes that follow); then every element is read in file order; then each vertex must be
/// finite and each face have 3 or more indices, all in range. Errors name the file and the
/// element: `bunny.ply: face 12: index 99 out of range (the file has 40 vertices)` (vertices
/// and faces count from 0, as PLY's indices do).
pub fn load_ply(path: &Path) -> Result<TriMesh, MeshError> {
    let bytes = read_file(path, MeshFormat::Ply)?;
    let mut reader = Reader::new(Cursor::new(bytes.as_slice()));
    let header = Parser::<Skipped>::new()
        .read_header(&mut reader)
        .map_err(|e| MeshError::Format {
            path: path.to_path_buf(),
            format: MeshFormat::Ply,
            message: format!("bad header: {}", e.to_string().replace('\n', " ")),
        })?;
    let payload_bytes = bytes.len() as u64 - reader.get_ref().position();
    let (vertex_count, face_count) = check_header(path, &header, payload_bytes)?;

    let mut vertices: Vec<PlyVertex> = Vec::new();
    let mut faces: Vec<PlyFace> = Vec::new();
    for e in header.elements.values() {
        let what = format!("{} elements ({} declared)", e.name, e.count);
        match e.name.as_str() {
            "vertex" => {
                vertices = Parser::<PlyVertex>::new()
                    .read_payload_for_element(&mut reader, e, &header)
                    .map_err(|err| parse_error(path, &what, err))?;
            }
            "face" => {
                faces = Parser::<PlyFace>::new()
                    .read_payload_for_element(&mut reader, e, &header)
                    .map_err(|err| parse_error(path, &what, err))?;
            }
            _ => {
                Parser::<Skipped>::new()
                    .read_payload_for_element(&mut reader, e, &header)
                    .map_err(|err| parse_error(path, &what, err))?;
            }
        }
    }
    debug_assert_eq!((vertices.len(), faces.len()), (vertex_count, face_count));
    let element = |element: String, message: String| MeshError::Element {
        path: path.to_path_buf(),
        element,
        message,
    };

    let positions: Vec<[f64; 3]> = vertices.into_iter().map(|v| v.0).collect();
    if let Some((i, p)) = positions
        .iter()
        .enumerate()
        .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
    {
        return Err(element(
            format!("vertex {i}"),
            format!("non-finite coordinate {p:?} (expected finite numbers)"),
        ));
    }
    let n = positions.len();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let idx = &face.0;
        if idx.len() < 3 {
            return Err(element(
                format!("face {f}"),
                format!("{} vertex indices, expected at least 3", idx.len()),
            ));
        }
        let mut ids = [0u32; 3];
        let map = |k: usize| -> Result<u32, MeshError> {
            let i = idx[k];
            match u32::try_from(i) {
                Ok(v) if (v as usize) < n => Ok(v),
                _ => Err(element(
                    format!("face {f}"),
                    format!(
                        "index {i} out of range (the file has {n} vertices, indices 0..={})",
                        n.saturating_sub(1)
                    ),
                )),
            }
        };
        ids[0] = map(0)?;
        for k in 1..idx.len() - 1 {
            ids[1] = map(k)?;
            ids[2] = map(k + 1)?;
            triangles.push(ids);
        }
    }
    let mut welder = Welder::new();
    weld_indexed(&mut welder, path, &positions, &triangles)?;
    welder.finish().ok_or_else(|| MeshError::Format {
        path: path.to_path_buf(),
        format: MeshFormat::Ply,
        message: "no triangles (expected at least one face)".into(),
    })
}
