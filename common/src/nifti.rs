//! NIfTI-1 volumes (`.nii`, `.nii.gz`) as 3D textures, read through the `nifti` crate: dims,
//! voxel spacing, datatype, byte order and the scaling slope/intercept come from the header; the
//! values are mapped to [0, 1] through a window (default: the data's min–max).

use std::collections::HashSet;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use nifti::{NiftiObject, NiftiVolume, RandomAccessNiftiVolume, ReaderOptions};

use crate::texture3d::{MAX_DIM, MAX_VOXELS, Texture3d, TextureError};

/// Whether `path` names a NIfTI file (`.nii` or `.nii.gz`, any case).
pub fn is_nifti_path(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    name.ends_with(".nii") || name.ends_with(".nii.gz")
}

/// A NIfTI volume loaded as a texture, with what its header said.
#[derive(Clone, Debug)]
pub struct NiftiTexture {
    /// The windowed voxels in [0, 1], x fastest (the file's order).
    pub texture: Texture3d,
    /// Voxel spacing along x, y, z (header `pixdim[1..4]`, absolute; 1 where the header has 0).
    pub spacing: [f64; 3],
    /// Header `datatype` code (2 u8, 4 i16, 8 i32, 16 f32, 64 f64, 256 i8, 512 u16, 768 u32, …).
    pub datatype: i16,
    /// Whether the file is big-endian.
    pub big_endian: bool,
    /// Volumes along the 4th dimension and beyond (1 for a 3D file); only the first is used.
    pub volumes: u64,
    /// Smallest scaled value of the (first) volume.
    pub min: f64,
    /// Largest scaled value.
    pub max: f64,
    /// The window mapped to [0, 1].
    pub window: [f64; 2],
}

impl NiftiTexture {
    /// The physical extent `dims · spacing`, which the texture's mapping keeps the aspect of.
    pub fn extent(&self) -> [f64; 3] {
        [0, 1, 2].map(|a| f64::from(self.texture.dims[a]) * self.spacing[a])
    }
}

fn nifti_err(path: &Path, message: impl Into<String>) -> TextureError {
    TextureError::Nifti {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Checks the 348-byte header's size field and magic before the crate parses it, so a file that
/// is not NIfTI-1 gets that message rather than a parse error.
fn check_header(path: &Path) -> Result<(), TextureError> {
    crate::input::check_regular(path).map_err(|source| TextureError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let file = std::fs::File::open(path).map_err(|source| TextureError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let gz = path
        .file_name()
        .is_some_and(|n| n.to_string_lossy().to_ascii_lowercase().ends_with(".gz"));
    let mut head = Vec::with_capacity(348);
    let read = if gz {
        flate_prefix(file, &mut head)
    } else {
        file.take(348).read_to_end(&mut head).map(|_| ())
    };
    if let Err(e) = read {
        return Err(nifti_err(
            path,
            format!(
                "cannot read the NIfTI header{}: {e}",
                if gz { " (gzip)" } else { "" }
            ),
        ));
    }
    if head.len() < 348 {
        return Err(nifti_err(
            path,
            format!(
                "not a NIfTI-1 file: {} bytes, shorter than the 348-byte header (truncated?)",
                head.len()
            ),
        ));
    }
    let size_le = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
    let size_be = i32::from_be_bytes([head[0], head[1], head[2], head[3]]);
    let magic = &head[344..348];
    if (size_le != 348 && size_be != 348) || (magic != b"n+1\0" && magic != b"ni1\0") {
        return Err(nifti_err(
            path,
            "not a NIfTI-1 file: expected sizeof_hdr 348 and magic \"n+1\" or \"ni1\"",
        ));
    }
    Ok(())
}

/// Reads up to 348 decompressed bytes of a gzip stream.
fn flate_prefix(file: std::fs::File, out: &mut Vec<u8>) -> std::io::Result<()> {
    let mut dec = flate2::read::GzDecoder::new(std::io::BufReader::new(file));
    let mut buf = [0u8; 348];
    let mut n = 0;
    while n < buf.len() {
        match dec.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    out.extend_from_slice(&buf[..n]);
    Ok(())
}

/// Prints "only the first volume is used" once per file and process (animations re-plan).
fn warn_4d(path: &Path, dims: &[u16]) {
    static WARNED: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);
    let mut w = WARNED.lock().unwrap_or_else(|e| e.into_inner());
    if w.get_or_insert_with(HashSet::new)
        .insert(path.to_path_buf())
    {
        let shape: Vec<String> = dims.iter().map(u16::to_string).collect();
        eprintln!(
            "warning: {}: NIfTI volume is {} ({}D); using the first 3D volume only",
            path.display(),
            shape.join("x"),
            dims.len()
        );
    }
}

/// The voxel counts and spacing of a NIfTI-1 file, from its header alone (no voxel data is
/// read): what `sweep.slabs = "auto"` needs before the texture is loaded. Dimensions beyond the
/// file's count are 1, spacing follows [`load_nifti`] (absolute, 1 where the header has 0).
pub fn header_grid(path: &Path) -> Result<([u32; 3], [f64; 3]), TextureError> {
    check_header(path)?;
    let header = nifti::NiftiHeader::from_file(path)
        .map_err(|e| nifti_err(path, format!("cannot read the NIfTI header: {e}")))?;
    let ndim = usize::from(header.dim[0].min(7));
    let dims = [1, 2, 3].map(|i| {
        if i <= ndim {
            u32::from(header.dim[i])
        } else {
            1
        }
    });
    if dims.contains(&0) {
        return Err(TextureError::Dims {
            path: path.to_path_buf(),
            dims,
        });
    }
    let spacing = [1, 2, 3].map(|i| {
        let s = f64::from(header.pixdim[i]).abs();
        if s.is_finite() && s > 0.0 { s } else { 1.0 }
    });
    Ok((dims, spacing))
}

/// Loads a NIfTI-1 file as a texture: the first 3D volume, scaled by `scl_slope`/`scl_inter`
/// (when the slope is non-zero), mapped to [0, 1] through `window` (default: min–max; values
/// outside clamp). Errors name the file: unreadable, not NIfTI-1, truncated, unsupported type.
pub fn load_nifti(path: &Path, window: Option<[f64; 2]>) -> Result<NiftiTexture, TextureError> {
    check_header(path)?;
    let obj = ReaderOptions::new().read_file(path).map_err(|e| {
        let why = match &e {
            nifti::NiftiError::IncompatibleLength(got, want) => {
                format!("truncated NIfTI file: {got} bytes of voxel data, the header needs {want}")
            }
            nifti::NiftiError::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
                format!("truncated NIfTI file: {io}")
            }
            other => format!("cannot read NIfTI volume: {other}"),
        };
        nifti_err(path, why)
    })?;
    let header = obj.header().clone();
    let volume = obj.volume();
    let dims = volume.dim().to_vec();
    if dims.is_empty() {
        return Err(nifti_err(path, "NIfTI header has no dimensions"));
    }
    // 1D and 2D files are volumes one voxel thick.
    let d3: [u32; 3] = [0, 1, 2].map(|a| dims.get(a).map_or(1, |&d| u32::from(d)));
    let volumes: u64 = dims.iter().skip(3).map(|&d| u64::from(d)).product();
    let n: u64 = d3.iter().map(|&d| u64::from(d)).product();
    if d3.contains(&0) || d3.iter().any(|&d| d > MAX_DIM) || n > MAX_VOXELS {
        return Err(TextureError::Dims {
            path: path.to_path_buf(),
            dims: d3,
        });
    }
    if volumes > 1 {
        warn_4d(path, &dims);
    }
    let mut raw = Vec::with_capacity(n as usize);
    let mut coords = vec![0u16; dims.len().max(3)];
    for z in 0..d3[2] {
        for y in 0..d3[1] {
            for x in 0..d3[0] {
                coords[0] = x as u16;
                if dims.len() > 1 {
                    coords[1] = y as u16;
                }
                if dims.len() > 2 {
                    coords[2] = z as u16;
                }
                let c = &coords[..dims.len()];
                let v = volume
                    .get_f64(c)
                    .map_err(|e| nifti_err(path, format!("cannot read voxel {c:?}: {e}")))?;
                if !v.is_finite() {
                    return Err(nifti_err(
                        path,
                        format!("voxel [{x}, {y}, {z}] is {v}, expected a finite value"),
                    ));
                }
                raw.push(v);
            }
        }
    }
    let (min, max) = raw
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if let Some([lo, hi]) = window
        && !(lo.is_finite() && hi.is_finite() && lo < hi)
    {
        return Err(nifti_err(
            path,
            format!("window [{lo}, {hi}]: expected finite lo < hi"),
        ));
    }
    let window = window.unwrap_or([min, max]);
    // A constant volume (min == max) maps to 0 everywhere.
    let span = window[1] - window[0];
    let voxels = raw
        .iter()
        .map(|&v| {
            if span > 0.0 {
                ((v - window[0]) / span).clamp(0.0, 1.0) as f32
            } else {
                0.0
            }
        })
        .collect();
    let spacing = [1, 2, 3].map(|i| {
        let s = f64::from(header.pixdim[i]).abs();
        if s.is_finite() && s > 0.0 { s } else { 1.0 }
    });
    let texture = Texture3d::from_voxels(d3, voxels).map_err(|e| nifti_err(path, e.to_string()))?;
    Ok(NiftiTexture {
        texture,
        spacing,
        datatype: header.datatype,
        big_endian: header.endianness == nifti::Endianness::Big,
        volumes,
        min,
        max,
        window,
    })
}
