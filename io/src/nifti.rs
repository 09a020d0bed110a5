//! NIfTI-1 volumes (`.nii`, `.nii.gz`) as 3D textures, read through the `nifti` crate: dims,
//! voxel spacing, datatype, byte order and the scaling slope/intercept come from the header; the
//! values are mapped to [0, 1] through a window (default: the data's min–max).

use std::collections::HashSet;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use std::sync::atomic::{AtomicBool, Ordering};

use nifti::{InMemNiftiVolume, NiftiHeader, NiftiType, RandomAccessNiftiVolume};

use convshadow_common::pixel::texture3d::{MAX_DIM, MAX_VOXELS, Texture3d, TextureError};

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
    let gz = is_gz(path);
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
    check_dims(path, &head, size_le == 348)
}

/// Checks the header's `dim` field (eight i16 at byte 40) in the byte order `sizeof_hdr` gives,
/// before the `nifti` crate reads it: the crate guesses the byte order from `dim[0]` alone (so
/// a `dim[0]` above 7 had every value printed byte-swapped) and names the field before the one
/// that is 0. `dim[0]` is the number of dimensions, 1 to 7; `dim[1..=dim[0]]` are the sizes.
fn check_dims(path: &Path, head: &[u8], little_endian: bool) -> Result<(), TextureError> {
    let dim: [i16; 8] = std::array::from_fn(|i| {
        let b = [head[40 + 2 * i], head[41 + 2 * i]];
        if little_endian {
            i16::from_le_bytes(b)
        } else {
            i16::from_be_bytes(b)
        }
    });
    if !(1..=7).contains(&dim[0]) {
        return Err(nifti_err(
            path,
            format!(
                "NIfTI header field dim[0] (the number of dimensions) is {}, expected 1 to 7",
                dim[0]
            ),
        ));
    }
    let rank = dim[0] as usize;
    if let Some(i) = (1..=rank).find(|&i| dim[i] < 1) {
        return Err(nifti_err(
            path,
            format!(
                "NIfTI header field dim[{i}] is {}, expected a size from 1 to 32767 (dim = {:?}, \
                 {rank} dimensions)",
                dim[i],
                &dim[..=rank]
            ),
        ));
    }
    Ok(())
}

/// Reads up to 348 decompressed bytes of a gzip stream.
fn flate_prefix(file: std::fs::File, out: &mut Vec<u8>) -> std::io::Result<()> {
    let mut dec = flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file));
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

/// Bytes read and converted between two looks at the cancel flag.
const CHUNK: usize = 4 << 20;

/// Whether `path`'s name ends in `.gz` (any case): the stream is gzip-compressed.
fn is_gz(path: &Path) -> bool {
    path.file_name()
        .is_some_and(|n| n.to_string_lossy().to_ascii_lowercase().ends_with(".gz"))
}

/// Opens `path` as a byte stream, decompressed when its name ends in `.gz`.
fn open_stream(path: &Path) -> Result<Box<dyn Read>, TextureError> {
    let file = std::fs::File::open(path).map_err(|source| TextureError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let file = std::io::BufReader::new(file);
    Ok(if is_gz(path) {
        // Every member of the stream: gzip files may be concatenated (`cat a.gz b.gz`, bgzip,
        // pigz), and GzDecoder stops after the first, which made a valid file "truncated".
        Box::new(flate2::read::MultiGzDecoder::new(file))
    } else {
        Box::new(file)
    })
}

/// Whether the cancel flag is raised.
fn cancelled(cancel: Option<&AtomicBool>) -> bool {
    cancel.is_some_and(|c| c.load(Ordering::Relaxed))
}

/// Reads exactly `len` bytes of `src` (or, with `keep = false`, skips them) in chunks of
/// [`CHUNK`], looking at `cancel` before each: a multi-GB volume (or its gzip decompression)
/// stops within a chunk of a signal. Errors name the file: interrupted, truncated, unreadable,
/// or more bytes than the machine can allocate.
fn read_chunked(
    path: &Path,
    src: &mut dyn Read,
    len: u64,
    keep: bool,
    what: &str,
    cancel: Option<&AtomicBool>,
) -> Result<Vec<u8>, TextureError> {
    let mut out: Vec<u8> = Vec::new();
    if keep {
        usize::try_from(len)
            .ok()
            .and_then(|n| out.try_reserve_exact(n).ok())
            .ok_or_else(|| {
                nifti_err(
                    path,
                    format!("cannot allocate {len} bytes of voxel data on this machine"),
                )
            })?;
    }
    let mut scratch = vec![0u8; if keep { 0 } else { CHUNK.min(len as usize) }];
    let mut done: u64 = 0;
    while done < len {
        if cancelled(cancel) {
            return Err(TextureError::Interrupted {
                path: path.to_path_buf(),
            });
        }
        let step = (len - done).min(CHUNK as u64) as usize;
        let buf = if keep {
            let at = out.len();
            out.resize(at + step, 0);
            &mut out[at..]
        } else {
            &mut scratch[..step]
        };
        src.read_exact(buf).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                nifti_err(
                    path,
                    format!(
                        "truncated NIfTI file: it ends within the {len} bytes of {what} the \
                         header announces"
                    ),
                )
            } else {
                nifti_err(path, format!("cannot read the {what}: {e}"))
            }
        })?;
        done += step as u64;
    }
    Ok(out)
}

/// Reads the 348-byte header from `src` (after [`check_header`] checked size and magic).
fn read_header(path: &Path, src: &mut dyn Read) -> Result<NiftiHeader, TextureError> {
    NiftiHeader::from_reader(src).map_err(|e| match e {
        nifti::NiftiError::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            nifti_err(path, format!("truncated NIfTI file: {io}"))
        }
        other => nifti_err(path, format!("cannot read the NIfTI header: {other}")),
    })
}

/// The header's shape and type, checked before any voxel is read: its dims (1 to 7 of them), the
/// first 3D volume's dims (a 1D or 2D file is one voxel thick) within the texture limits, the
/// number of volumes along the 4th dimension and beyond, and the datatype.
struct Shape {
    dims: Vec<u16>,
    d3: [u32; 3],
    volumes: u64,
    datatype: NiftiType,
}

impl Shape {
    fn of(path: &Path, header: &NiftiHeader) -> Result<Shape, TextureError> {
        let dims = header
            .dim()
            .map_err(|e| nifti_err(path, format!("bad NIfTI dims {:?}: {e}", header.dim)))?
            .to_vec();
        let d3: [u32; 3] = [0, 1, 2].map(|a| dims.get(a).map_or(1, |&d| u32::from(d)));
        let volumes: u64 = dims.iter().skip(3).map(|&d| u64::from(d)).product();
        let n: u64 = d3.iter().map(|&d| u64::from(d)).product();
        if d3.contains(&0) || d3.iter().any(|&d| d > MAX_DIM) || n > MAX_VOXELS {
            return Err(TextureError::Dims {
                path: path.to_path_buf(),
                dims: d3,
            });
        }
        let datatype = header.data_type().map_err(|_| {
            nifti_err(
                path,
                format!("unknown NIfTI datatype code {}", header.datatype),
            )
        })?;
        // NIfTI-1 requires `bitpix` to agree with the datatype. (The crate's own file reader
        // sizes the data by `bitpix` but indexes it by the datatype: such a file panicked there.)
        let bits = 8 * datatype.size_of() as i64;
        if i64::from(header.bitpix) != bits {
            return Err(nifti_err(
                path,
                format!(
                    "NIfTI bitpix {} does not match datatype {} ({bits} bits per voxel)",
                    header.bitpix, header.datatype
                ),
            ));
        }
        Ok(Shape {
            dims,
            d3,
            volumes,
            datatype,
        })
    }

    /// Voxels of the first 3D volume.
    fn voxels(&self) -> u64 {
        self.d3.iter().map(|&d| u64::from(d)).product()
    }

    /// Bytes of the first 3D volume as stored.
    fn stored_bytes(&self) -> u64 {
        self.voxels() * self.datatype.size_of() as u64
    }
}

/// Bytes that loading the NIfTI file `path` holds at its peak: the first volume as stored plus
/// its f32 voxels. Read from the header alone (decompressed for `.nii.gz`), so the memory budget
/// counts a gzip file or a 4D series by what it holds, not by its size on disk; `None` when the
/// header cannot be read (loading then reports why).
pub fn memory_need(path: &Path) -> Option<u64> {
    check_header(path).ok()?;
    let mut src = open_stream(path).ok()?;
    let header = read_header(path, &mut src).ok()?;
    let shape = Shape::of(path, &header).ok()?;
    Some(shape.stored_bytes() + 4 * shape.voxels())
}

/// The stream positioned at the first voxel: after the header and its extensions in a `n+1`
/// file (the data starts at `vox_offset`, at least byte 352), or the companion `.img.gz`/`.img`
/// of a header-only `ni1` file.
fn voxel_stream(
    path: &Path,
    header: &NiftiHeader,
    mut src: Box<dyn Read>,
    cancel: Option<&AtomicBool>,
) -> Result<Box<dyn Read>, TextureError> {
    if header.magic != *b"ni1\0" {
        // What the nifti crate skips: the 4 extender bytes and the extensions up to vox_offset.
        // `as` saturates: a negative or NaN offset reads from 352, like the crate.
        let skip = (header.vox_offset as u64).max(352) - 348;
        read_chunked(path, &mut src, skip, false, "header extensions", cancel)?;
        return Ok(src);
    }
    let base = if is_gz(path) {
        path.with_extension("")
    } else {
        path.to_path_buf()
    };
    let gz = base.with_extension("img.gz");
    let img = if gz.is_file() {
        gz
    } else {
        base.with_extension("img")
    };
    crate::input::check_regular(&img).map_err(|e| {
        nifti_err(
            path,
            format!(
                "header-only NIfTI (magic \"ni1\"): its volume file {}: {e}",
                img.display()
            ),
        )
    })?;
    open_stream(&img)
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
    load_nifti_cancellable(path, window, None)
}

/// [`load_nifti`] that stops with [`TextureError::Interrupted`] once `cancel` is raised: the
/// file is read (and, for `.nii.gz`, decompressed) here in chunks of 4 MiB that look at the flag,
/// and only the first 3D volume is read; the bytes then go to the `nifti` crate's in-memory
/// volume, whose values are converted a z-slice at a time, again looking at the flag. The
/// header's dims are checked against the texture limits before any voxel is read.
pub fn load_nifti_cancellable(
    path: &Path,
    window: Option<[f64; 2]>,
    cancel: Option<&AtomicBool>,
) -> Result<NiftiTexture, TextureError> {
    check_header(path)?;
    if let Some([lo, hi]) = window
        && !(lo.is_finite() && hi.is_finite() && lo < hi)
    {
        return Err(nifti_err(
            path,
            format!("window [{lo}, {hi}]: expected finite lo < hi"),
        ));
    }
    let mut src = open_stream(path)?;
    let header = read_header(path, &mut src)?;
    let shape = Shape::of(path, &header)?;
    if shape.volumes > 1 {
        warn_4d(path, &shape.dims);
    }
    let mut src = voxel_stream(path, &header, src, cancel)?;
    let bytes = read_chunked(
        path,
        &mut src,
        shape.stored_bytes(),
        true,
        "voxel data",
        cancel,
    )?;
    drop(src);
    // The first 3D volume only: a 4D file's later volumes were never read.
    let mut raw_dim = header.dim;
    raw_dim[0] = raw_dim[0].min(3);
    let volume = InMemNiftiVolume::from_raw_fields(
        raw_dim,
        shape.datatype,
        header.scl_slope,
        header.scl_inter,
        bytes,
        header.endianness,
    )
    .map_err(|e| nifti_err(path, format!("cannot read NIfTI volume: {e}")))?;
    let rank = usize::from(raw_dim[0]);
    let d3 = shape.d3;
    // Every scaled value of the volume, z-slice by z-slice, checking the cancel flag per slice.
    let each = |f: &mut dyn FnMut(f64)| -> Result<(), TextureError> {
        for z in 0..d3[2] {
            if cancelled(cancel) {
                return Err(TextureError::Interrupted {
                    path: path.to_path_buf(),
                });
            }
            for y in 0..d3[1] {
                for x in 0..d3[0] {
                    let coords = [x as u16, y as u16, z as u16];
                    let c = &coords[..rank];
                    let v = volume
                        .get_f64(c)
                        .map_err(|e| nifti_err(path, format!("cannot read voxel {c:?}: {e}")))?;
                    if !v.is_finite() {
                        return Err(nifti_err(
                            path,
                            format!("voxel [{x}, {y}, {z}] is {v}, expected a finite value"),
                        ));
                    }
                    // Texture values are f32: beyond its range a value is not finite once
                    // converted (and the min–max window's width overflowed to NaN voxels).
                    if v.abs() > f64::from(f32::MAX) {
                        return Err(nifti_err(
                            path,
                            format!(
                                "voxel [{x}, {y}, {z}] is {v:e}{}, out of the f32 range of a \
                                 texture (|v| <= {:e}): not finite after conversion",
                                if header.scl_slope != 0.0 {
                                    " after scl_slope/scl_inter scaling"
                                } else {
                                    ""
                                },
                                f32::MAX
                            ),
                        ));
                    }
                    f(v);
                }
            }
        }
        Ok(())
    };
    // No f64 copy of the volume: at most the stored bytes plus 4 bytes per voxel are held, what
    // the memory budget counts. The first pass keeps each value as f32 and its min–max; when
    // every value is an f32 exactly (any 8- or 16-bit type, f32 data), the window is applied to
    // those in place, else a second pass reads the values again.
    let mut voxels: Vec<f32> = Vec::new();
    voxels
        .try_reserve_exact(shape.voxels() as usize)
        .map_err(|_| {
            nifti_err(
                path,
                format!("cannot allocate {} voxels on this machine", shape.voxels()),
            )
        })?;
    let (mut min, mut max, mut exact) = (f64::INFINITY, f64::NEG_INFINITY, true);
    each(&mut |v| {
        min = min.min(v);
        max = max.max(v);
        let f = v as f32;
        exact &= f64::from(f) == v;
        voxels.push(f);
    })?;
    let window = window.unwrap_or([min, max]);
    // A constant volume (min == max) maps to 0 everywhere.
    let span = window[1] - window[0];
    let map = |v: f64| {
        if span > 0.0 {
            ((v - window[0]) / span).clamp(0.0, 1.0) as f32
        } else {
            0.0
        }
    };
    if exact {
        for chunk in voxels.chunks_mut(CHUNK) {
            if cancelled(cancel) {
                return Err(TextureError::Interrupted {
                    path: path.to_path_buf(),
                });
            }
            for x in chunk {
                *x = map(f64::from(*x));
            }
        }
    } else {
        voxels.clear();
        each(&mut |v| voxels.push(map(v)))?;
    }
    drop(volume);
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
        volumes: shape.volumes,
        min,
        max,
        window,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use std::sync::Arc;

    /// A little-endian NIfTI-1 header (magic `n+1`, data at byte 352) for `dims` of `datatype`
    /// with `bitpix`, spacing 1, no scaling; written from the NIfTI-1 layout (dim at byte 40,
    /// datatype 70, bitpix 72, pixdim 76, vox_offset 108, magic 344), not by the crate.
    fn header(dims: &[u16], datatype: i16, bitpix: i16) -> Vec<u8> {
        let mut h = vec![0u8; 352];
        h[0..4].copy_from_slice(&348i32.to_le_bytes());
        let mut dim = [1i16; 8];
        dim[0] = dims.len() as i16;
        for (i, &d) in dims.iter().enumerate() {
            dim[i + 1] = d as i16;
        }
        for (i, d) in dim.iter().enumerate() {
            h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
        }
        h[70..72].copy_from_slice(&datatype.to_le_bytes());
        h[72..74].copy_from_slice(&bitpix.to_le_bytes());
        for i in 0..8 {
            h[76 + 4 * i..80 + 4 * i].copy_from_slice(&1f32.to_le_bytes());
        }
        h[108..112].copy_from_slice(&352f32.to_le_bytes());
        h[344..348].copy_from_slice(b"n+1\0");
        h
    }

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("cs-nifti-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_small_volume_reads_its_values_and_only_the_first_of_four_d() {
        let dir = temp("small");
        // 2×2×1×2 u8: the first volume is 0, 51, 102, 255; the second (never read) 7s.
        let mut f = header(&[2, 2, 1, 2], 2, 8);
        f.extend_from_slice(&[0, 51, 102, 255, 7, 7, 7, 7]);
        let p = dir.join("v.nii");
        std::fs::write(&p, &f).unwrap();
        let t = load_nifti(&p, None).unwrap();
        assert_eq!(t.texture.dims, [2, 2, 1]);
        assert_eq!(t.volumes, 2);
        assert_eq!((t.min, t.max), (0.0, 255.0));
        assert_eq!(t.texture.voxels, [0.0, 0.2, 0.4, 1.0]);
        // Stored bytes plus 4 f32 bytes per voxel of the first volume.
        assert_eq!(memory_need(&p), Some(4 * (1 + 4)));
        // The second volume cut off: nothing of it is read, so the file still loads.
        std::fs::write(&p, &f[..352 + 4]).unwrap();
        assert_eq!(load_nifti(&p, None).unwrap().texture.voxels.len(), 4);
        std::fs::write(&p, &f[..352 + 3]).unwrap();
        let e = load_nifti(&p, None).unwrap_err().to_string();
        assert!(e.contains("truncated") && e.contains("v.nii"), "{e}");
        // i32 values that f32 cannot hold (2^24 + 1) take the second pass, from the f64 values.
        let values = [-5i32, 16_777_217, 1 << 30, 0];
        let mut f = header(&[4], 8, 32);
        for v in values {
            f.extend_from_slice(&v.to_le_bytes());
        }
        std::fs::write(&p, &f).unwrap();
        // A window two units wide around 2^24 + 1: that voxel is 0.5 (as f32 it would be 0).
        let t = load_nifti(&p, Some([16_777_216.0, 16_777_218.0])).unwrap();
        assert_eq!(t.texture.dims, [4, 1, 1]);
        assert_eq!((t.min, t.max), (-5.0, f64::from(1 << 30)));
        assert_eq!(t.texture.voxels, [0.0, 0.5, 1.0, 0.0]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bitpix_and_oversized_dims_are_refused_before_reading() {
        let dir = temp("refuse");
        // f32 data announced with 8 bits per voxel: the crate would index past its buffer.
        let mut f = header(&[4, 1, 1], 16, 8);
        f.extend_from_slice(&[0u8; 16]);
        let p = dir.join("bitpix.nii");
        std::fs::write(&p, &f).unwrap();
        let e = load_nifti(&p, None).unwrap_err().to_string();
        assert!(e.contains("bitpix 8") && e.contains("datatype 16"), "{e}");
        // 2^15-1 cubed voxels in a 352-byte file: the texture limits, not a read or allocation.
        let p = dir.join("huge.nii");
        std::fs::write(&p, header(&[32767, 32767, 32767], 2, 8)).unwrap();
        let e = load_nifti(&p, None).unwrap_err();
        assert!(matches!(e, TextureError::Dims { .. }), "{e}");
        assert_eq!(memory_need(&p), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 43, class 7: a valid gzip of two members is read whole (it was "truncated").
    #[test]
    fn a_multi_member_gzip_volume_is_read_whole() {
        let dir = temp("multigz");
        let mut f = header(&[2, 2, 2], 2, 8);
        f.extend_from_slice(&[0, 1, 2, 3, 4, 5, 6, 255]);
        let p = dir.join("two.nii.gz");
        let mut bytes = Vec::new();
        for part in [&f[..300], &f[300..]] {
            let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
            gz.write_all(part).unwrap();
            bytes.extend(gz.finish().unwrap());
        }
        std::fs::write(&p, &bytes).unwrap();
        let t = load_nifti(&p, None).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(t.texture.dims, [2, 2, 2]);
        assert_eq!((t.min, t.max), (0.0, 255.0));
        assert_eq!(memory_need(&p), Some(8 * 5));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 43, class 7: a bad `dim` is named as its own field with its value in the file's
    /// byte order (a zero dim[3] was called dim[2] with dim[2]'s value; dim[0] = 9 was printed
    /// byte-swapped).
    #[test]
    fn bad_dims_name_their_own_field_and_value() {
        let dir = temp("dims");
        let p = dir.join("d.nii");
        let mut f = header(&[3, 4, 0], 2, 8);
        std::fs::write(&p, &f).unwrap();
        let e = load_nifti(&p, None).unwrap_err().to_string();
        assert!(e.contains("d.nii") && e.contains("dim[3] is 0"), "{e}");
        f[40..42].copy_from_slice(&9i16.to_le_bytes());
        std::fs::write(&p, &f).unwrap();
        let e = load_nifti(&p, None).unwrap_err().to_string();
        assert!(e.contains("dim[0]") && e.contains("is 9,"), "{e}");
        f[40..42].copy_from_slice(&3i16.to_le_bytes());
        f[44..46].copy_from_slice(&(-2i16).to_le_bytes());
        std::fs::write(&p, &f).unwrap();
        let e = load_nifti(&p, None).unwrap_err().to_string();
        assert!(e.contains("dim[2] is -2"), "{e}");
        assert!(header_grid(&p).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 43, class 7: values beyond f32 are named with their value (they were "NaN").
    #[test]
    fn values_beyond_f32_are_out_of_range_with_their_value() {
        let dir = temp("huge");
        let p = dir.join("h.nii");
        let mut f = header(&[4], 64, 64);
        for v in [0.0f64, 1.7e308, -1.7e308, 1.0] {
            f.extend_from_slice(&v.to_le_bytes());
        }
        std::fs::write(&p, &f).unwrap();
        let e = load_nifti(&p, None).unwrap_err().to_string();
        assert!(
            e.contains("voxel [1, 0, 0] is 1.7e308") && e.contains("f32 range"),
            "{e}"
        );
        assert!(!e.contains("NaN"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_raised_cancel_flag_stops_a_gzip_volume_within_a_chunk() {
        let dir = temp("cancel");
        // 1024×1024×256 u8 zeros, gzipped (about 256 KiB): seconds to inflate and convert.
        let p = dir.join("big.nii.gz");
        let mut gz = flate2::write::GzEncoder::new(
            std::fs::File::create(&p).unwrap(),
            flate2::Compression::fast(),
        );
        gz.write_all(&header(&[1024, 1024, 256], 2, 8)).unwrap();
        let zeros = vec![0u8; 1 << 20];
        for _ in 0..256 {
            gz.write_all(&zeros).unwrap();
        }
        gz.finish().unwrap();
        assert_eq!(
            memory_need(&p),
            Some(5 << 28),
            "counted from the header, not the file"
        );
        let cancel = Arc::new(AtomicBool::new(false));
        let raised = Arc::new(std::sync::Mutex::new(None));
        let raiser = {
            let (cancel, raised) = (Arc::clone(&cancel), Arc::clone(&raised));
            std::thread::spawn(move || {
                std::thread::sleep(std::time::Duration::from_millis(200));
                cancel.store(true, Ordering::Relaxed);
                *raised.lock().unwrap() = Some(std::time::Instant::now());
            })
        };
        let r = load_nifti_cancellable(&p, None, Some(&cancel));
        let done = std::time::Instant::now();
        raiser.join().unwrap();
        let raised = raised
            .lock()
            .unwrap()
            .expect("the flag was raised before the load ended");
        assert!(
            matches!(r, Err(TextureError::Interrupted { .. })),
            "{:?}",
            r.map(|t| t.texture.dims)
        );
        let took = done.duration_since(raised).as_secs_f64();
        assert!(took < 0.5, "stopped {took:.2} s after the flag");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
