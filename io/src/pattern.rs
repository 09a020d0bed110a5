//! Reads a light's pattern image (a gobo; the model is in `convshadow_common::plan::pattern`):
//! linear values per channel (an 8-bit PNG's 0–255 as 0–1, no sRGB decoding; 16-bit PNG and EXR
//! likewise), alpha ignored.

use std::path::Path;

use convshadow_common::pixel::texture3d::TextureError;
use convshadow_common::plan::pattern::{MAX_PATTERN_SIDE, Pattern};

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
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| err(format!("cannot read pattern: {e}")))?
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
    use image::ImageDecoder;
    crate::input::check_regular(path).ok()?;
    let decoder = image::ImageReader::open(path)
        .ok()?
        .with_guessed_format()
        .ok()?
        .into_decoder()
        .ok()?;
    let (w, h) = decoder.dimensions();
    let texels = u64::from(w) * u64::from(h);
    Some(
        decoder
            .total_bytes()
            .saturating_add(texels.saturating_mul(12)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
