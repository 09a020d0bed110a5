//! Why a mesh file was refused: every message names the file, the line or element, and what
//! was expected.

use std::path::{Path, PathBuf};

/// The mesh file formats a scene's `path` may name, chosen by the file's extension
/// ([`MeshFormat::from_path`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`, and any extension not listed below).
    Obj,
    /// PLY, the Stanford polygon format (`.ply`): ASCII or binary, either byte order.
    Ply,
    /// glTF 2.0 as JSON (`.gltf`, buffers embedded as data URIs or in files beside it).
    Gltf,
    /// glTF 2.0 binary (`.glb`).
    Glb,
    /// STL (`.stl`): ASCII or binary.
    Stl,
}

impl MeshFormat {
    /// The format a path names by its extension (case-insensitive); an unknown or missing
    /// extension is OBJ, as every mesh file was before the other formats were read.
    pub fn from_path(path: &Path) -> MeshFormat {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("ply") => MeshFormat::Ply,
            Some("gltf") => MeshFormat::Gltf,
            Some("glb") => MeshFormat::Glb,
            Some("stl") => MeshFormat::Stl,
            _ => MeshFormat::Obj,
        }
    }

    /// The format's short name in messages ("OBJ", "PLY", "glTF", "STL").
    pub fn name(self) -> &'static str {
        match self {
            MeshFormat::Obj => "OBJ",
            MeshFormat::Ply => "PLY",
            MeshFormat::Gltf | MeshFormat::Glb => "glTF",
            MeshFormat::Stl => "STL",
        }
    }

    /// What a readable file of the format is, in messages ("a readable Wavefront OBJ file").
    pub fn expected(self) -> &'static str {
        match self {
            MeshFormat::Obj => "a readable Wavefront OBJ file",
            MeshFormat::Ply => "a readable PLY file",
            MeshFormat::Gltf => "a readable glTF 2.0 file",
            MeshFormat::Glb => "a readable binary glTF 2.0 file",
            MeshFormat::Stl => "a readable STL file",
        }
    }
}

impl std::fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Errors of reading a mesh file (`convshadow_io::mesh`); every message names the file, the
/// line or element where known, and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The scene names the file but the host did not read it before the geometry was built (a
    /// caller's mistake: `convshadow_io::read_geometry_files` reads every mesh file).
    #[error("{}: not read (the scene's files are read before its geometry is built)", .path.display())]
    NotRead {
        /// File path.
        path: PathBuf,
    },
    /// The file (or a file it names, such as a glTF buffer) could not be opened or read.
    #[error("{}: cannot read {format} file (expected {}): {source}", .path.display(), .format.expected())]
    Io {
        /// File path.
        path: PathBuf,
        /// The format the file was read as.
        format: MeshFormat,
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
    /// A PLY, glTF or STL file that its format's parser refused, or whose header or structure
    /// is wrong, where no single element is to blame (a bad header, a truncated file).
    #[error("{}: not a valid {format} file: {message}", .path.display())]
    Format {
        /// File path.
        path: PathBuf,
        /// The format the file was read as.
        format: MeshFormat,
        /// What is wrong and what was expected.
        message: String,
    },
    /// One element of a PLY, glTF or STL file is wrong: `element` names it the way the format
    /// counts (`face 12`, `mesh 0 primitive 1`, `facet 7`; numbers from 0, as the formats' own
    /// indices are).
    #[error("{}: {element}: {message}", .path.display())]
    Element {
        /// File path.
        path: PathBuf,
        /// The element, e.g. `face 12` or `vertex 3`.
        element: String,
        /// What is wrong and what was expected.
        message: String,
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
