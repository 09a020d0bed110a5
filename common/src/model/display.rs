//! Display mapping of PNG output: exposure (in stops) and a tone curve, then the sRGB encoding.
//! EXR output stays the linear float image; nothing here touches the render or its hashes.

use std::fmt;
use std::str::FromStr;

/// The tone curve applied to linear values (after exposure) before the sRGB encoding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tonemap {
    /// `min(x, 1)`: the linear image as it is; everything above 1 clips to white.
    Clamp,
    /// Reinhard's global operator `x / (1 + x)` (Reinhard et al., "Photographic Tone
    /// Reproduction for Digital Images", SIGGRAPH 2002): never clips, compresses strongly.
    Reinhard,
    /// Krzysztof Narkowicz's fit of the ACES filmic curve ("ACES Filmic Tone Mapping Curve",
    /// 2016): `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)`, clamped to [0, 1]. It rolls the
    /// highlights off smoothly (reaching 1 only at x ≈ 7.2) and slightly lifts the midtones.
    #[default]
    Aces,
}

impl Tonemap {
    /// Every curve, in the order of the docs.
    pub const ALL: [Tonemap; 3] = [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces];

    /// The curve at linear value `x` (negative and NaN values map to 0).
    pub fn apply(self, x: f32) -> f32 {
        // `x > 0` is false for NaN too.
        let x = if x > 0.0 { x } else { 0.0 };
        let y = match self {
            Tonemap::Clamp => x,
            Tonemap::Reinhard => x / (1.0 + x),
            Tonemap::Aces => {
                // Past 1e18 the quadratic overflows nothing but loses meaning: the limit is 1.
                if x > 1e18 {
                    1.0
                } else {
                    (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
                }
            }
        };
        y.min(1.0)
    }

    /// The name used in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Tonemap::Clamp => "clamp",
            Tonemap::Reinhard => "reinhard",
            Tonemap::Aces => "aces",
        }
    }
}

impl fmt::Display for Tonemap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Tonemap {
    type Err = String;

    fn from_str(s: &str) -> Result<Tonemap, String> {
        Tonemap::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| format!("unknown tone curve `{s}`; expected clamp, reinhard or aces"))
    }
}

/// How a linear image becomes 8-bit sRGB for PNG: `curve(value · 2^exposure)`, sRGB-encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayMap {
    /// Exposure in stops (each stop doubles the linear values before the curve).
    pub exposure: f64,
    /// The tone curve.
    pub tonemap: Tonemap,
}

impl Default for DisplayMap {
    fn default() -> Self {
        DisplayMap {
            exposure: 0.0,
            tonemap: Tonemap::default(),
        }
    }
}

impl DisplayMap {
    /// The plain encoding: no exposure change, clamp (what `RgbImage::to_srgb8` does).
    pub const CLAMP: DisplayMap = DisplayMap {
        exposure: 0.0,
        tonemap: Tonemap::Clamp,
    };

    /// The linear multiplier of the exposure, `2^exposure` (computed once per image).
    pub fn gain(&self) -> f32 {
        self.exposure.exp2() as f32
    }

    /// The display value in [0, 1] (before the sRGB encoding) of linear value `v`.
    pub fn display(&self, v: f32) -> f32 {
        self.tonemap.apply(v * self.gain())
    }

    /// Maps linear values to sRGB-encoded 8-bit.
    pub fn to_srgb8(&self, data: &[f32]) -> Vec<u8> {
        let gain = self.gain();
        data.iter()
            .map(|&v| linear_to_srgb8(self.tonemap.apply(v * gain)))
            .collect()
    }

    /// The fraction of values (channels) that reach 255 after the mapping: clipped highlights.
    pub fn clipped_fraction(&self, data: &[f32]) -> f64 {
        if data.is_empty() {
            return 0.0;
        }
        let clipped = self.to_srgb8(data).iter().filter(|&&b| b == 255).count();
        clipped as f64 / data.len() as f64
    }
}

/// Linear to sRGB-encoded 8-bit (clamped), as PNG viewers expect.
pub fn linear_to_srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor() as u8
}

/// sRGB-encoded 8-bit to linear.
pub fn srgb8_to_linear(v: u8) -> f32 {
    let s = f32::from(v) / 255.0;
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_match_their_closed_forms() {
        for x in [0.0f64, 0.05, 0.18, 0.5, 1.0, 1.34, 4.0, 20.0] {
            let xf = x as f32;
            let close = |a: f32, b: f64| assert!((f64::from(a) - b).abs() < 1e-6, "{a} vs {b}");
            close(Tonemap::Clamp.apply(xf), x.min(1.0));
            close(Tonemap::Reinhard.apply(xf), x / (1.0 + x));
            let aces = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
            close(Tonemap::Aces.apply(xf), aces.clamp(0.0, 1.0));
        }
        // Known values: Reinhard halves 1; ACES maps 1 to 2.54/3.16.
        assert_eq!(Tonemap::Reinhard.apply(1.0), 0.5);
        assert!((Tonemap::Aces.apply(1.0) - 2.54 / 3.16).abs() < 1e-6);
        for t in Tonemap::ALL {
            assert_eq!(t.apply(f32::NAN), 0.0);
            assert_eq!(t.apply(-3.0), 0.0);
            assert_eq!(t.apply(f32::INFINITY), 1.0);
        }
    }

    #[test]
    fn curves_are_monotone_and_stay_in_the_unit_interval() {
        for t in Tonemap::ALL {
            let mut last = t.apply(0.0);
            for i in 1..=200_000 {
                let x = i as f32 * 1e-4;
                let y = t.apply(x);
                assert!(y >= last, "{t} decreases at {x}: {last} -> {y}");
                assert!((0.0..=1.0).contains(&y));
                last = y;
            }
        }
    }

    #[test]
    fn exposure_doubles_per_stop() {
        let m = DisplayMap {
            exposure: 1.0,
            tonemap: Tonemap::Clamp,
        };
        assert_eq!(m.display(0.25), 0.5);
        let m = DisplayMap {
            exposure: -2.0,
            tonemap: Tonemap::Reinhard,
        };
        assert_eq!(m.display(4.0), 0.5);
        assert_eq!(
            DisplayMap::CLAMP.to_srgb8(&[0.0, 0.5, 2.0]),
            [0.0f32, 0.5, 2.0].map(linear_to_srgb8)
        );
    }

    #[test]
    fn names_round_trip() {
        for t in Tonemap::ALL {
            assert_eq!(t.name().parse::<Tonemap>(), Ok(t));
        }
        assert!("filmic".parse::<Tonemap>().is_err());
    }
}
