//! Mesh files for tests, written here from the formats' specifications and independent of the
//! loaders in `convshadow_io` (which they test): a small OBJ reader for triangle meshes, and
//! writers of PLY (ASCII, binary little- and big-endian), STL (ASCII, binary) and glTF 2.0
//! (`.gltf` with a `.bin` file or a data URI, `.glb`).
//!
//! Coordinates are f32, as the OBJ loader (tobj) reads them; ASCII writers print each value in
//! Rust's shortest form that reads back to the same f32, so every format holds the same bits.

use std::fmt::Write as _;

/// A triangle mesh as a file holds it: f32 positions and 0-based triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SoupMesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangles, 0-based indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

/// Reads the `v` and `f` lines of a triangle-only OBJ (`f a b c`, `a/t/n` forms, 1-based
/// indices): a reader for test fixtures, not for arbitrary OBJ files. Panics on anything else.
pub fn read_obj_triangles(text: &str) -> SoupMesh {
    let mut m = SoupMesh::default();
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let p: Vec<f32> = w.take(3).map(|x| x.parse().expect("a number")).collect();
                m.positions.push([p[0], p[1], p[2]]);
            }
            Some("f") => {
                let idx: Vec<u32> = w
                    .map(|t| {
                        let v: u32 = t.split('/').next().unwrap().parse().expect("an index");
                        v - 1
                    })
                    .collect();
                assert_eq!(idx.len(), 3, "triangles only: {line}");
                m.triangles.push([idx[0], idx[1], idx[2]]);
            }
            _ => {}
        }
    }
    m
}

/// The PLY encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlyEncoding {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0`.
    LittleEndian,
    /// `format binary_big_endian 1.0`.
    BigEndian,
}

/// A PLY file of `m`: `float` x, y, z (`double` when `double` is set), a `uchar` normal-less
/// colour-less vertex, and `list uchar int vertex_indices` faces; an extra `comment` line.
pub fn ply(m: &SoupMesh, encoding: PlyEncoding, double: bool) -> Vec<u8> {
    let fmt = match encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::LittleEndian => "binary_little_endian",
        PlyEncoding::BigEndian => "binary_big_endian",
    };
    let ty = if double { "double" } else { "float" };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\ncomment written by convshadow-testkit\nelement vertex {}\n\
         property {ty} x\nproperty {ty} y\nproperty {ty} z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    )
    .into_bytes();
    let be = encoding == PlyEncoding::BigEndian;
    let f32b = |x: f32| if be { x.to_be_bytes() } else { x.to_le_bytes() };
    let f64b = |x: f64| if be { x.to_be_bytes() } else { x.to_le_bytes() };
    let i32b = |x: i32| if be { x.to_be_bytes() } else { x.to_le_bytes() };
    for p in &m.positions {
        if encoding == PlyEncoding::Ascii {
            let line = if double {
                format!(
                    "{} {} {}\n",
                    f64::from(p[0]),
                    f64::from(p[1]),
                    f64::from(p[2])
                )
            } else {
                format!("{} {} {}\n", p[0], p[1], p[2])
            };
            out.extend_from_slice(line.as_bytes());
        } else {
            for &c in p {
                if double {
                    out.extend_from_slice(&f64b(f64::from(c)));
                } else {
                    out.extend_from_slice(&f32b(c));
                }
            }
        }
    }
    for t in &m.triangles {
        if encoding == PlyEncoding::Ascii {
            out.extend_from_slice(format!("3 {} {} {}\n", t[0], t[1], t[2]).as_bytes());
        } else {
            out.push(3);
            for &i in t {
                out.extend_from_slice(&i32b(i as i32));
            }
        }
    }
    out
}

/// The corners of triangle `t` of `m`.
fn corners(m: &SoupMesh, t: &[u32; 3]) -> [[f32; 3]; 3] {
    t.map(|i| m.positions[i as usize])
}

/// An ASCII STL of `m` (facet normals written as 0 0 0, which readers may ignore).
pub fn stl_ascii(m: &SoupMesh) -> Vec<u8> {
    let mut s = String::from("solid test\n");
    for t in &m.triangles {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for c in corners(m, t) {
            writeln!(s, "      vertex {} {} {}", c[0], c[1], c[2]).unwrap();
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str("endsolid test\n");
    s.into_bytes()
}

/// A binary STL of `m`; the 80-byte header starts with `header` (e.g. "solid exported", which
/// readers must not take for ASCII).
pub fn stl_binary(m: &SoupMesh, header: &str) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    let h = header.as_bytes();
    out[..h.len().min(80)].copy_from_slice(&h[..h.len().min(80)]);
    out.extend_from_slice(&(m.triangles.len() as u32).to_le_bytes());
    for t in &m.triangles {
        out.extend_from_slice(&[0u8; 12]);
        for c in corners(m, t) {
            for x in c {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    out
}

/// One glTF node: a mesh (index into the meshes written) and a column-major matrix, with child
/// nodes by index.
#[derive(Clone, Debug)]
pub struct GltfNode {
    /// The mesh it holds, if any.
    pub mesh: Option<usize>,
    /// Its transform, column-major (`None`: no `matrix` key).
    pub matrix: Option<[f64; 16]>,
    /// Child node indices.
    pub children: Vec<usize>,
}

/// The binary buffer and JSON of a glTF holding `meshes` (each one primitive of TRIANGLES,
/// POSITION f32 VEC3 and u32 indices, in one buffer) and `nodes` (scene 0's roots: `roots`).
/// `uri` is the buffer's `uri` (`None` for a GLB's binary chunk).
fn gltf_parts(
    meshes: &[SoupMesh],
    nodes: &[GltfNode],
    roots: &[usize],
    uri: Option<&str>,
) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    let (mut views, mut accessors, mut mesh_json) = (Vec::new(), Vec::new(), Vec::new());
    for m in meshes {
        let (lo, hi) = m.positions.iter().fold(
            ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
            |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                    [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
                )
            },
        );
        let pos_off = bin.len();
        for p in &m.positions {
            for x in p {
                bin.extend_from_slice(&x.to_le_bytes());
            }
        }
        let idx_off = bin.len();
        for t in &m.triangles {
            for i in t {
                bin.extend_from_slice(&i.to_le_bytes());
            }
        }
        let (pv, iv) = (views.len(), views.len() + 1);
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{pos_off},"byteLength":{},"target":34962}}"#,
            idx_off - pos_off
        ));
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{idx_off},"byteLength":{},"target":34963}}"#,
            bin.len() - idx_off
        ));
        let (pa, ia) = (accessors.len(), accessors.len() + 1);
        accessors.push(format!(
            r#"{{"bufferView":{pv},"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}}"#,
            m.positions.len(),
            lo[0],
            lo[1],
            lo[2],
            hi[0],
            hi[1],
            hi[2]
        ));
        accessors.push(format!(
            r#"{{"bufferView":{iv},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
            3 * m.triangles.len()
        ));
        mesh_json.push(format!(
            r#"{{"primitives":[{{"attributes":{{"POSITION":{pa}}},"indices":{ia},"mode":4}}]}}"#
        ));
    }
    let node_json: Vec<String> = nodes
        .iter()
        .map(|n| {
            let mut parts = Vec::new();
            if let Some(m) = n.mesh {
                parts.push(format!(r#""mesh":{m}"#));
            }
            if let Some(mat) = n.matrix {
                let v: Vec<String> = mat.iter().map(|x| format!("{x:?}")).collect();
                parts.push(format!(r#""matrix":[{}]"#, v.join(",")));
            }
            if !n.children.is_empty() {
                let c: Vec<String> = n.children.iter().map(|c| c.to_string()).collect();
                parts.push(format!(r#""children":[{}]"#, c.join(",")));
            }
            format!("{{{}}}", parts.join(","))
        })
        .collect();
    let roots: Vec<String> = roots.iter().map(|r| r.to_string()).collect();
    let uri = uri.map_or(String::new(), |u| format!(r#""uri":"{u}","#));
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"convshadow-testkit"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],"meshes":[{}],"accessors":[{}],"bufferViews":[{}],"buffers":[{{{uri}"byteLength":{}}}]}}"#,
        roots.join(","),
        node_json.join(","),
        mesh_json.join(","),
        accessors.join(","),
        views.join(","),
        bin.len()
    );
    (json, bin)
}

/// A `.gltf` JSON whose buffer is the file `bin_name` (returned as the second value).
pub fn gltf_with_bin(
    meshes: &[SoupMesh],
    nodes: &[GltfNode],
    roots: &[usize],
    bin_name: &str,
) -> (String, Vec<u8>) {
    gltf_parts(meshes, nodes, roots, Some(bin_name))
}

/// A `.gltf` JSON with its buffer inline as a base64 data URI.
pub fn gltf_embedded(meshes: &[SoupMesh], nodes: &[GltfNode], roots: &[usize]) -> String {
    let (_, bin) = gltf_parts(meshes, nodes, roots, Some("x"));
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    gltf_parts(meshes, nodes, roots, Some(&uri)).0
}

/// A `.glb`: 12-byte header, the JSON chunk (padded with spaces) and the BIN chunk (padded
/// with zeros), each 4-byte aligned.
pub fn glb(meshes: &[SoupMesh], nodes: &[GltfNode], roots: &[usize]) -> Vec<u8> {
    let (json, mut bin) = gltf_parts(meshes, nodes, roots, None);
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// The simplest scene: one root node holding mesh 0, no transform.
pub fn one_node() -> (Vec<GltfNode>, Vec<usize>) {
    (
        vec![GltfNode {
            mesh: Some(0),
            matrix: None,
            children: Vec::new(),
        }],
        vec![0],
    )
}

/// Standard base64 (RFC 4648, with padding).
fn base64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }

    #[test]
    fn binary_stl_has_the_size_its_count_says() {
        let m = read_obj_triangles("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let b = stl_binary(&m, "solid x");
        assert_eq!(b.len(), 84 + 50);
        assert_eq!(&b[80..84], &1u32.to_le_bytes());
    }
}
