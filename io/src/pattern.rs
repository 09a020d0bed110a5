//! Reads a light's pattern image (a gobo; the model is in `convshadow_common::plan::pattern`):
//! linear values per channel (an 8-bit PNG's 0–255 as 0–1, no sRGB decoding; 16-bit PNG and EXR
//! likewise), alpha ignored.

use std::path::Path;

use convshadow_common::pixel::texture3d::TextureError;
use convshadow_common::plan::pattern::{MAX_PATTERN_SIDE, Pattern};

/// The decoder's limits for a pattern: the documented [`MAX_PATTERN_SIDE`] a side, and room for
/// the largest decoded buffer at that size (RGBA f32, 16 bytes a texel: 4 GiB). The `image`
/// crate's default (512 MiB) refused the documented maximum, a 16384² RGB image (768 MiB).
fn pattern_limits() -> image::Limits {
    let side = u64::from(MAX_PATTERN_SIDE);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_PATTERN_SIDE);
    limits.max_image_height = Some(MAX_PATTERN_SIDE);
    limits.max_alloc = Some(side * side * 16);
    limits
}

/// Reads a pattern image (PNG, EXR, or any format the `image` crate decodes).
pub fn load_pattern(path: &Path) -> Result<Pattern, TextureError> {
    let err = |message: String| TextureError::Pattern {
        path: path.to_path_buf(),
        message,
    };
    crate::input::check_regular(path).map_err(|e| err(format!("cannot read pattern: {e}")))?;
    let reader = image::ImageReader::open(path)
        .map_err(|e| err(format!("cannot read pattern: {e}")))?
        .with_guessed_format()
        .map_err(|e| err(format!("cannot read pattern: {e}")))?;
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| err(format!("not a readable image: {e}")))?;
    if w == 0 || h == 0 || w > MAX_PATTERN_SIDE || h > MAX_PATTERN_SIDE {
        return Err(err(format!(
            "pattern is {w}x{h} texels, expected 1 to {MAX_PATTERN_SIDE} per side"
        )));
    }
    let mut reader = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| err(format!("cannot read pattern: {e}")))?;
    reader.limits(pattern_limits());
    let img = reader
        .decode()
        .map_err(|e| err(format!("not a readable image: {e}")))?;
    let rgb = img.to_rgb32f();
    let texels = rgb.into_raw();
    if let Some(i) = texels.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        let t = i / 3;
        return Err(err(format!(
            "texel ({}, {}) channel {} is {}, expected a finite value >= 0",
            t % w as usize,
            t / w as usize,
            i % 3,
            texels[i]
        )));
    }
    Ok(Pattern {
        width: w,
        height: h,
        texels,
    })
}

/// Bytes loading the pattern at `path` holds at its peak, from its header: the decoded image as
/// stored and its linear f32 RGB texels. `None` when the header cannot be read (the load then
/// reports why).
pub fn memory_need(path: &Path) -> Option<u64> {
    let (decoded, texels) = header_sizes(path)?;
    Some(decoded.saturating_add(texels.saturating_mul(TEXEL_BYTES)))
}

/// Bytes of the pattern's linear f32 RGB texels alone (what a device copy of it holds), from its
/// header; `None` when the header cannot be read.
pub fn texel_bytes(path: &Path) -> Option<u64> {
    header_sizes(path).map(|(_, texels)| texels.saturating_mul(TEXEL_BYTES))
}

/// Bytes of one loaded texel: linear RGB as f32.
const TEXEL_BYTES: u64 = 12;

/// The decoded image's size in bytes as stored and its texel count, from the file's header.
fn header_sizes(path: &Path) -> Option<(u64, u64)> {
    use image::ImageDecoder;
    crate::input::check_regular(path).ok()?;
    let decoder = image::ImageReader::open(path)
        .ok()?
        .with_guessed_format()
        .ok()?
        .into_decoder()
        .ok()?;
    let (w, h) = decoder.dimensions();
    Some((decoder.total_bytes(), u64::from(w) * u64::from(h)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn the_memory_need_counts_the_decoded_image_and_its_f32_texels() {
        let dir = std::env::temp_dir().join(format!("cs-pattern-need-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.png");
        image::RgbImage::new(300, 200).save(&path).unwrap();
        // 300 × 200 RGB8 decoded (3 bytes a texel) and as f32 RGB (12 bytes a texel).
        assert_eq!(memory_need(&path), Some(300 * 200 * (3 + 12)));
        let gray = dir.join("g.png");
        image::GrayImage::new(10, 10).save(&gray).unwrap();
        assert_eq!(memory_need(&gray), Some(10 * 10 * (1 + 12)));
        assert_eq!(memory_need(&dir.join("missing.png")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Writes an 8-bit RGB PNG of `side`² texels, every channel `value`, a row at a time (the
    /// image crate's encoder would need the whole 768 MiB buffer at 16384²).
    fn write_grey_rgb_png(path: &Path, side: u32, value: u8) {
        let chunk = |out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]| {
            out.extend((data.len() as u32).to_be_bytes());
            let mut crc = flate2::Crc::new();
            crc.update(kind);
            crc.update(data);
            out.extend(kind);
            out.extend(data);
            out.extend(crc.sum().to_be_bytes());
        };
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        let mut row = vec![value; 1 + 3 * side as usize];
        row[0] = 0; // filter: none
        for _ in 0..side {
            z.write_all(&row).unwrap();
        }
        let data = z.finish().unwrap();
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        let mut ihdr = Vec::new();
        ihdr.extend(side.to_be_bytes());
        ihdr.extend(side.to_be_bytes());
        ihdr.extend([8, 2, 0, 0, 0]); // 8 bits, RGB, deflate, no filter, no interlace
        chunk(&mut png, b"IHDR", &ihdr);
        chunk(&mut png, b"IDAT", &data);
        chunk(&mut png, b"IEND", &[]);
        std::fs::write(path, png).unwrap();
    }

    /// Issue 43, class 6: the documented largest pattern, 16384² (an RGB PNG: 768 MiB decoded),
    /// loads; the image crate's default 512 MiB limit refused it. One texel more is refused by
    /// the documented limit, before decoding.
    #[test]
    fn a_pattern_of_the_documented_largest_side_loads() {
        let dir = std::env::temp_dir().join(format!("cs-pattern-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("max.png");
        write_grey_rgb_png(&p, MAX_PATTERN_SIDE, 51);
        let pattern = load_pattern(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((pattern.width, pattern.height), (16384, 16384));
        assert_eq!(pattern.texels.len(), 3 << 28);
        assert_eq!(pattern.texels[0], 0.2);
        drop(pattern);
        write_grey_rgb_png(&p, MAX_PATTERN_SIDE + 1, 51);
        let e = load_pattern(&p).unwrap_err().to_string();
        assert!(e.contains("16385x16385") && e.contains("1 to 16384"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
