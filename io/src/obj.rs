//! OBJ reading: a validating scan that names the line, then tobj, then the shared welding
//! (`weld::Welder`).

use std::ops::Div;
use std::path::Path;
use std::str::FromStr;

use convshadow_common::prepare::mesh::{MeshError, MeshFormat, TriMesh};

use crate::weld::{Welder, read_file, too_many_vertices};

/// Longest line excerpt quoted in an error message.
pub(crate) const MAX_QUOTE: usize = 120;

/// The line trimmed and shortened for quoting in a message.
pub(crate) fn quote(line: &str) -> String {
    let t = line.trim();
    if t.chars().count() <= MAX_QUOTE {
        t.to_string()
    } else {
        let mut s: String = t.chars().take(MAX_QUOTE).collect();
        s.push('…');
        s
    }
}

/// What the validating scan learned about a file that tobj needs to be told.
pub(crate) struct ScanSummary {
    /// Number of face lines.
    faces: usize,
    /// Whether the file has `l` (polyline) elements, which tobj would turn into triangles.
    has_polylines: bool,
}

/// The float type tobj parses into (f32, or f64 with tobj's `use_f64` feature), as used by the scan.
pub(crate) trait ObjFloat: FromStr + Copy + Into<f64> + Div<Output = Self> {}
impl<T: FromStr + Copy + Into<f64> + Div<Output = T>> ObjFloat for T {}

/// One line under the scan: where it is, for the errors it words.
struct ObjLine<'a> {
    /// The file.
    path: &'a Path,
    /// 1-based line number.
    line_no: usize,
    /// The line's text (without `\r`).
    text: &'a str,
}

impl ObjLine<'_> {
    /// A syntax error on this line.
    fn syntax(&self, expected: String) -> MeshError {
        MeshError::Syntax {
            path: self.path.to_path_buf(),
            line: self.line_no,
            expected,
            text: quote(self.text),
        }
    }
}

/// Line-by-line validation with tobj's acceptance rules plus ours; errors carry the line number.
///
/// `_like` only fixes `T` to tobj's float type, so finiteness is judged on the values tobj keeps.
pub(crate) fn scan_obj<T: ObjFloat>(
    path: &Path,
    bytes: &[u8],
    _like: &[T],
) -> Result<ScanSummary, MeshError> {
    // Elements defined so far: vertices, texture coordinates, normals.
    let mut defined = [0usize; 3];
    let mut summary = ScanSummary {
        faces: 0,
        has_polylines: false,
    };
    let mut lines = bytes.split(|&b| b == b'\n').enumerate().peekable();
    while let Some((i, raw)) = lines.next() {
        let line_no = i + 1;
        if raw.is_empty() && lines.peek().is_none() {
            break; // trailing newline
        }
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                line: line_no,
                expected: "UTF-8 text".to_string(),
                text: quote(&String::from_utf8_lossy(raw)),
            });
        };
        let line = ObjLine {
            path,
            line_no,
            text,
        };
        let mut words = text.split_whitespace();
        match words.next() {
            Some("v") => {
                let coords = scan_vertex::<T>(&line, words)?;
                defined[0] += 1;
                if coords.iter().any(|c| !c.is_finite()) {
                    return Err(MeshError::NonFinite {
                        path: path.to_path_buf(),
                        line: line_no,
                        vertex: defined[0],
                        text: quote(text),
                    });
                }
            }
            Some(kw @ ("vt" | "vn")) => {
                scan_attribute::<T>(&line, kw == "vt", words)?;
                defined[if kw == "vt" { 1 } else { 2 }] += 1;
            }
            Some("f") => {
                scan_face(&line, defined, words)?;
                summary.faces += 1;
            }
            Some("l") => summary.has_polylines = true,
            Some("usemtl") => {
                // tobj takes the name after the first space and rejects an empty one.
                let name = text.split_once(' ').map(|(_, n)| n.trim()).unwrap_or("");
                if name.is_empty() {
                    return Err(line.syntax("a material name after \"usemtl\"".to_string()));
                }
            }
            _ => {}
        }
    }
    Ok(summary)
}

/// The words of a `v` line after the keyword: the vertex as tobj keeps it (x, y, z divided by w
/// when a w is given; colours ignored).
fn scan_vertex<'a, T: ObjFloat>(
    line: &ObjLine<'_>,
    mut words: impl Iterator<Item = &'a str>,
) -> Result<Vec<f64>, MeshError> {
    let mut xyz = [None::<T>; 3];
    for (k, slot) in xyz.iter_mut().enumerate() {
        let axis = ["x", "y", "z"][k];
        let Some(w) = words.next() else {
            return Err(line.syntax(format!(
                "3 coordinates \"v x y z\" in a vertex line, found {k}"
            )));
        };
        match w.parse::<T>() {
            Ok(x) => *slot = Some(x),
            Err(_) => {
                return Err(line.syntax(format!(
                    "a number for the {axis} coordinate of a vertex, found \"{w}\","
                )));
            }
        }
    }
    let rest: Vec<&str> = words.collect();
    let mut coords: Vec<f64> = Vec::with_capacity(3);
    match rest.len() {
        0 | 3 => coords.extend(xyz.iter().flatten().map(|&x| x.into())),
        1 => {
            let w = rest[0].parse::<T>().map_err(|_| {
                line.syntax(format!(
                    "a number for the w coordinate of a vertex, found \"{}\",",
                    rest[0]
                ))
            })?;
            if w.into() == 0.0 {
                return Err(line.syntax("a nonzero w coordinate".to_string()));
            }
            coords.extend(xyz.iter().flatten().map(|&x| (x / w).into()));
        }
        k => {
            return Err(line.syntax(format!(
                "\"v x y z\", \"v x y z w\" or \"v x y z r g b\", found {} numbers",
                3 + k
            )));
        }
    }
    Ok(coords)
}

/// The words of a `vt` (`texture`) or `vn` line after the keyword: enough numbers.
fn scan_attribute<'a, T: ObjFloat>(
    line: &ObjLine<'_>,
    texture: bool,
    mut words: impl Iterator<Item = &'a str>,
) -> Result<(), MeshError> {
    let (need, what) = if texture {
        (2, "texture coordinate \"vt u v\"")
    } else {
        (3, "normal \"vn x y z\"")
    };
    for k in 0..need {
        match words.next() {
            None => {
                return Err(line.syntax(format!("{need} numbers in a {what}, found {k}")));
            }
            Some(w) if w.parse::<T>().is_err() => {
                return Err(line.syntax(format!("a number in a {what}, found \"{w}\",")));
            }
            Some(_) => {}
        }
    }
    Ok(())
}

/// The words of an `f` line after the keyword: at least 3 vertices, each index defined before
/// the line (`defined`: vertices, texture coordinates, normals so far).
fn scan_face<'a>(
    line: &ObjLine<'_>,
    defined: [usize; 3],
    words: impl Iterator<Item = &'a str>,
) -> Result<(), MeshError> {
    let mut count = 0usize;
    for token in words {
        count += 1;
        let parts: Vec<&str> = token.split('/').collect();
        if parts.len() > 3 {
            return Err(line.syntax(format!(
                "a face vertex \"v\", \"v/vt\", \"v//vn\" or \"v/vt/vn\", found \"{token}\","
            )));
        }
        if parts[0].is_empty() {
            return Err(line.syntax(format!("a vertex index, found \"{token}\",")));
        }
        let names = ["vertex", "texture coordinate", "normal"];
        for (k, part) in parts.iter().enumerate() {
            if part.is_empty() {
                continue;
            }
            let Ok(index) = part.parse::<i64>() else {
                return Err(
                    line.syntax(format!("an integer {} index, found \"{part}\",", names[k]))
                );
            };
            let n = defined[k] as i64;
            let ok = (index > 0 && index <= n) || (index < 0 && index >= -n);
            if !ok {
                return Err(MeshError::BadIndex {
                    path: line.path.to_path_buf(),
                    line: line.line_no,
                    element: names[k],
                    index,
                    defined: defined[k],
                    text: quote(line.text),
                });
            }
        }
    }
    if count < 3 {
        return Err(MeshError::FaceTooShort {
            path: line.path.to_path_buf(),
            line: line.line_no,
            count,
            text: quote(line.text),
        });
    }
    Ok(())
}

/// `bytes` with every `l` (polyline) line blanked, keeping line numbers.
pub(crate) fn without_polylines(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        if i > 0 {
            out.push(b'\n');
        }
        let is_polyline = std::str::from_utf8(raw)
            .map(|s| s.split_whitespace().next() == Some("l"))
            .unwrap_or(false);
        if !is_polyline {
            out.extend_from_slice(raw);
        }
    }
    out
}

/// Load an OBJ with tobj (single_index = false, triangulate = true; all models/objects in the file merged into one TriMesh).
///
/// Vertices are welded by exact position (−0.0 = 0.0) so closure is judged by position.
/// Each line is validated first so that errors name the line: syntax tobj would reject,
/// non-finite vertices, faces with fewer than 3 vertices, and indices that are 0 or refer to an
/// element not defined before the line (negative indices are relative, as in the OBJ format).
/// Polylines (`l`) are ignored; materials are not read. Degenerate triangles are kept here and
/// dropped by [`TriMesh::analyze`]. Polygons are triangulated by tobj as fans.
pub fn load_obj(path: &Path) -> Result<TriMesh, MeshError> {
    let mut bytes = read_file(path, MeshFormat::Obj)?;
    // A UTF-8 byte-order mark (editors on Windows write one) is not part of the first line:
    // left in, the first `v` was an unknown keyword and its vertex was lost.
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    // The empty Vec only tells the scan which float type tobj parses into.
    let summary = scan_obj(path, &bytes, &tobj::Mesh::default().positions)?;
    if summary.faces == 0 {
        return Err(MeshError::NoTriangles {
            path: path.to_path_buf(),
        });
    }
    let filtered;
    let input: &[u8] = if summary.has_polylines {
        filtered = without_polylines(&bytes);
        &filtered
    } else {
        &bytes
    };
    // `..Default::default()` keeps this compiling when tobj's `merging`/`reordering` features add fields.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(input), &options, |_| {
            Err(tobj::LoadError::GenericFailure)
        })
        .map_err(|source| MeshError::Obj {
            path: path.to_path_buf(),
            reason: source.to_string(),
        })?;

    let mut welder = Welder::new();
    let mut local: Vec<u32> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        local.clear();
        for p in m.positions.chunks_exact(3) {
            let q: [f64; 3] = [p[0].into(), p[1].into(), p[2].into()];
            if q.iter().any(|c| !c.is_finite()) {
                return Err(MeshError::Invalid {
                    path: path.to_path_buf(),
                    message: format!(
                        "a vertex of object \"{}\" has a non-finite coordinate {q:?} (expected finite numbers)",
                        model.name
                    ),
                });
            }
            local.push(welder.vertex(q).ok_or_else(|| too_many_vertices(path))?);
        }
        for t in m.indices.chunks_exact(3) {
            let map = |i: u32| local.get(i as usize).copied();
            match (map(t[0]), map(t[1]), map(t[2])) {
                (Some(a), Some(b), Some(c)) => welder.triangle([a, b, c]),
                _ => {
                    return Err(MeshError::Invalid {
                        path: path.to_path_buf(),
                        message: format!(
                            "tobj produced a vertex index out of range in object \"{}\" (expected valid face indices)",
                            model.name
                        ),
                    });
                }
            }
        }
    }
    welder.finish().ok_or_else(|| MeshError::NoTriangles {
        path: path.to_path_buf(),
    })
}

/// Bytes loading and placing the OBJ file at `path` holds at its peak, counted from its lines
/// without parsing them (one streaming pass, 64 KiB at a time), so that the memory budget is
/// checked before the file is parsed: its text twice (the bytes and the copy without polylines),
/// per vertex line [`OBJ_BYTES_PER_VERTEX`], per triangle of the fans its faces make
/// [`OBJ_BYTES_PER_TRIANGLE`], and [`OBJ_BYTES_PER_FACE_INDEX`] per index of its widest face
/// (parsed one face at a time). Measured peaks lie below (`armadillo_100k.obj`: 21 MB of 28
/// counted). `None` when the file cannot be read (the load then reports why). Faces continued
/// over lines with `\` count as the line they start on.
pub fn memory_need(path: &Path) -> Option<u64> {
    use std::io::Read;
    let size = crate::input::check_regular(path).ok()?;
    let mut file = std::fs::File::open(path).ok()?;
    let mut buf = vec![0u8; 1 << 16];
    let (mut vertices, mut triangles, mut widest) = (0u64, 0u64, 0u64);
    // The line so far: its column, its keyword's first byte (0 once it is longer than one
    // byte), and the tokens begun on it.
    let (mut column, mut keyword, mut tokens, mut in_token) = (0u64, 0u8, 0u64, false);
    let mut end_line = |keyword: u8, tokens: u64| match keyword {
        b'v' => vertices += 1,
        b'f' => {
            let indices = tokens.saturating_sub(1);
            triangles += indices.saturating_sub(2);
            widest = widest.max(indices);
        }
        _ => {}
    };
    let mut read = 0u64;
    loop {
        let n = file.read(&mut buf).ok()?;
        read += n as u64;
        if n == 0 || read > size.saturating_add(1 << 16) {
            break;
        }
        for &b in &buf[..n] {
            if b == b'\n' {
                end_line(keyword, tokens);
                (column, keyword, tokens, in_token) = (0, 0, 0, false);
                continue;
            }
            let space = b.is_ascii_whitespace();
            match column {
                0 => keyword = b,
                1 if !space => keyword = 0,
                _ => {}
            }
            if !space && !in_token {
                tokens += 1;
            }
            in_token = !space;
            column += 1;
        }
    }
    end_line(keyword, tokens);
    Some(
        size.saturating_mul(2)
            .saturating_add(vertices.saturating_mul(OBJ_BYTES_PER_VERTEX))
            .saturating_add(triangles.saturating_mul(OBJ_BYTES_PER_TRIANGLE))
            .saturating_add(widest.saturating_mul(OBJ_BYTES_PER_FACE_INDEX)),
    )
}

/// Bytes a vertex line costs once loaded (see [`memory_need`]): tobj's position, the welded
/// position and its entry in the weld map.
pub const OBJ_BYTES_PER_VERTEX: u64 = 96;
/// Bytes a triangle costs once loaded and placed (see [`memory_need`]): tobj's indices, the
/// mesh's triangle, its closure-check edges and its rasterizer set-up.
pub const OBJ_BYTES_PER_TRIANGLE: u64 = 160;
/// Bytes an index of a face costs while tobj parses that face (see [`memory_need`]).
pub const OBJ_BYTES_PER_FACE_INDEX: u64 = 48;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn load_obj_welds_seams_and_resolves_relative_indices() {
        let dir = std::env::temp_dir().join(format!("convshadow-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("seam.obj");
        // A tetrahedron whose vertex 1 is duplicated (as -0.0) and whose faces use v/vt/vn,
        // v//vn, negative indices, and a polyline that must be ignored (tobj would make it a triangle).
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv -0.0 0 -0\nvt 0 0\nvn 0 0 1\n\
                    f 1/1/1 3/1/1 2/1/1\nf 5//1 2//1 4//1\nf -5 -2 -3\nf 2 3 4\nl 1 2 3\n";
        std::fs::write(&path, text).expect("write");
        let m = load_obj(&path).expect("loads");
        let (_, r) = m.analyze();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(r.triangles, 4);
        assert!(r.is_closed(), "{r}");
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-15);

        let cases: [(&str, &str, &str); 9] = [
            (
                "v 0 0 0\nv 1 0 0\nf 1 2 0\n",
                "seam.obj:3:",
                "vertex index 0",
            ),
            (
                "v 0 0 0\nv 1 0 0\nf 1 2 -3\n",
                "seam.obj:3:",
                "vertex index -3",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3 4\n",
                "seam.obj:4:",
                "vertex index 4",
            ),
            ("v 0 0 0\nv 1 0\n", "seam.obj:2:", "3 coordinates"),
            ("v 0 0 0\nv 1 inf 0\n", "seam.obj:2:", "vertex 2"),
            ("v 0 0 0\n\nv 1 0 0\nf 1 2\n", "seam.obj:4:", "at least 3"),
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/2 2 3\n",
                "seam.obj:4:",
                "texture coordinate index 2",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3/x\n",
                "seam.obj:4:",
                "\"x\"",
            ),
            ("v 0 0 0\nv 1 0 0\n", "seam.obj", "no triangles"),
        ];
        for (text, location, what) in cases {
            std::fs::write(&path, text).expect("write");
            let msg = load_obj(&path).expect_err(text).to_string();
            assert!(
                msg.contains(location) && msg.contains(what),
                "{text:?} -> {msg}"
            );
        }
        let missing = load_obj(&dir.join("missing.obj"))
            .expect_err("missing")
            .to_string();
        assert!(missing.contains("missing.obj"), "{missing}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_memory_need_counts_vertices_fan_triangles_and_the_widest_face() {
        let dir = std::env::temp_dir().join(format!("cs-obj-need-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.obj");
        // 4 vertices, a triangle, a quad (2 fan triangles) and a hexagon (4), a comment with
        // words, a vertex normal and a face line without a newline at the end.
        let text = "# f 1 2 3 4\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nf 1 2 3\n\
                    f  1/1 2/2  3/3 4/4\nf 1 2 3 4 1 2";
        std::fs::write(&path, text).unwrap();
        let want = 2 * text.len() as u64
            + 4 * OBJ_BYTES_PER_VERTEX
            + (1 + 2 + 4) * OBJ_BYTES_PER_TRIANGLE
            + 6 * OBJ_BYTES_PER_FACE_INDEX;
        assert_eq!(memory_need(&path), Some(want));
        assert_eq!(memory_need(&dir.join("missing.obj")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
