//! Patterned (projective textured) lights — a gobo (Zhang & Crawfis 2003 §4): an image that
//! becomes a light's initial light buffer, so the pattern is projected through the scene along the
//! light's direction and blurs with distance like any shadow.
//!
//! The image is read as linear values per channel (an 8-bit PNG's 0–255 as 0–1, no sRGB
//! decoding; 16-bit PNG and EXR likewise), alpha ignored. It is placed on the first slab plane
//! (the scene's nearest depth) as a `size` = [w, h] world-unit rectangle centred at `center`
//! (camera-space x right, y down, from the view's centre), its first row at the top, and sampled
//! bilinearly at every light-buffer pixel centre, clamped to its edge texels beyond the rectangle.

/// Largest pattern side in texels.
pub const MAX_PATTERN_SIDE: u32 = 16384;

/// A loaded pattern: linear RGB per texel, row-major from the top row.
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    /// Texels across.
    pub width: u32,
    /// Texels down.
    pub height: u32,
    /// `width · height · 3` linear values, each finite and ≥ 0.
    pub texels: Vec<f32>,
}

impl Pattern {
    /// Whether every texel is grey (its three channels equal).
    pub fn is_grey(&self) -> bool {
        self.texels
            .chunks_exact(3)
            .all(|t| t[0] == t[1] && t[1] == t[2])
    }

    /// The bilinear sample at texel coordinates (tx, ty) (texel centres at i + 0.5), clamped to
    /// the edge texels, channel `c`.
    pub fn sample(&self, tx: f64, ty: f64, c: usize) -> f64 {
        let (w, h) = (self.width as i64, self.height as i64);
        let fx = tx - 0.5;
        let fy = ty - 0.5;
        let x0 = fx.floor();
        let y0 = fy.floor();
        let (ax, ay) = (fx - x0, fy - y0);
        let at = |x: i64, y: i64| {
            let x = x.clamp(0, w - 1) as usize;
            let y = y.clamp(0, h - 1) as usize;
            f64::from(self.texels[(y * self.width as usize + x) * 3 + c])
        };
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = at(x0, y0) * (1.0 - ax) + at(x0 + 1, y0) * ax;
        let bottom = at(x0, y0 + 1) * (1.0 - ax) + at(x0 + 1, y0 + 1) * ax;
        top * (1.0 - ay) + bottom * ay
    }

    /// [`Pattern::sample`] in f32 (the sweep's spot patterns; `eye.wgsl` `pattern_sample` is
    /// the same operations): the texel indices clamped in float before they become integers,
    /// so no conversion saturates.
    pub fn sample_f32(&self, tx: f32, ty: f32, c: usize) -> f32 {
        let (w, h) = (self.width as f32, self.height as f32);
        let (fx, fy) = (tx - 0.5, ty - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (ax, ay) = (fx - x0, fy - y0);
        let (x0, y0) = (x0.clamp(-1.0, w) as i32, y0.clamp(-1.0, h) as i32);
        let at = |x: i32, y: i32| {
            let x = x.clamp(0, self.width as i32 - 1) as usize;
            let y = y.clamp(0, self.height as i32 - 1) as usize;
            self.texels[(y * self.width as usize + x) * 3 + c]
        };
        let top = at(x0, y0) * (1.0 - ax) + at(x0 + 1, y0) * ax;
        let bottom = at(x0, y0 + 1) * (1.0 - ax) + at(x0 + 1, y0 + 1) * ax;
        top * (1.0 - ay) + bottom * ay
    }
}
