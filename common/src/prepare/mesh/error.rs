//! Why an OBJ file was refused: every message names the file, the line and what was expected.

use std::path::PathBuf;

/// Errors of reading a mesh file (`convshadow_io::obj`); every message names the file, the line where known, and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The scene names the file but the host did not read it before the geometry was built (a
    /// caller's mistake: `convshadow_io::read_geometry_files` reads every mesh file).
    #[error("{}: not read (the scene's files are read before its geometry is built)", .path.display())]
    NotRead {
        /// File path.
        path: PathBuf,
    },
    /// The file could not be opened or read.
    #[error("{}: cannot read OBJ file (expected a readable Wavefront OBJ file): {source}", .path.display())]
    Io {
        /// File path.
        path: PathBuf,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// A line does not follow the OBJ syntax.
    #[error("{}:{line}: expected {expected} in \"{text}\"", .path.display())]
    Syntax {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What was expected there.
        expected: String,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// A face line with fewer than 3 vertices.
    #[error("{}:{line}: face has {count} vertex indices, expected at least 3, in \"{text}\"", .path.display())]
    FaceTooShort {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// Number of vertex references on the line.
        count: usize,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// A face refers to an element (vertex, texture coordinate, normal) that is not defined.
    #[error(
        "{}:{line}: {element} index {index} is out of range (expected {expected}) in \"{text}\"",
        .path.display(),
        expected = index_range_hint(.defined)
    )]
    BadIndex {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// "vertex", "texture coordinate" or "normal".
        element: &'static str,
        /// The index as written in the file (0, too large, or too negative).
        index: i64,
        /// How many such elements were defined before this line.
        defined: usize,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// A vertex with a NaN or infinite coordinate.
    #[error(
        "{}:{line}: vertex {vertex} has a non-finite coordinate (expected finite numbers) in \"{text}\"",
        .path.display()
    )]
    NonFinite {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// 1-based vertex index, as faces in the file refer to it.
        vertex: usize,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// tobj rejected the file and the line could not be located.
    #[error("{}: line unknown: tobj could not parse the file ({reason}); expected a valid Wavefront OBJ file", .path.display())]
    Obj {
        /// File path.
        path: PathBuf,
        /// tobj's error, in words.
        reason: String,
    },
    /// The file has no faces.
    #[error("{}: no triangles (expected at least one face line \"f a b c\")", .path.display())]
    NoTriangles {
        /// File path.
        path: PathBuf,
    },
    /// A whole-file inconsistency that has no single line (e.g. too many vertices for u32 indices).
    #[error("{}: {message}", .path.display())]
    Invalid {
        /// File path.
        path: PathBuf,
        /// What is wrong and what was expected.
        message: String,
    },
}

/// Text for the accepted index range when `defined` elements exist.
pub(crate) fn index_range_hint(defined: &usize) -> String {
    let defined = *defined;
    if defined == 0 {
        "an element defined on an earlier line; none is defined yet".to_string()
    } else {
        format!(
            "1..={defined} or -{defined}..=-1, as {defined} are defined before this line; OBJ indices start at 1"
        )
    }
}
