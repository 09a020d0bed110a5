//! Integer hashing: the only source of randomness, identical on CPU and GPU.
//!
//! Random numbers are hashes of (seed, stream, slab, row, column), chained so that the per-slab
//! and per-row parts are computed once and each pixel costs a single `mix32`.

use wide::u32x8;

/// The "lowbias32" integer finalizer (Chris Wellons): a bijection of u32 with good avalanche.
#[inline(always)]
pub const fn mix32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// [`mix32`] on 8 lanes (`wide` u32x8, wrapping multiplies): the SIMD sweep's phase hash.
#[inline(always)]
pub fn mix32x8(x: u32x8) -> u32x8 {
    let x = x ^ (x >> 16);
    let x = x * u32x8::splat(0x7feb_352d);
    let x = x ^ (x >> 15);
    let x = x * u32x8::splat(0x846c_a68b);
    x ^ (x >> 16)
}

/// Stream id of the shading-point jitter (light streams are 0, 1, 2, ...).
pub const JITTER_STREAM: u32 = 0xffff_ffff;

/// Hash of (seed, stream, slab): the per-slab part, computed once per slab on the host.
#[inline]
pub const fn slab_hash(seed: u32, stream: u32, slab: u32) -> u32 {
    mix32(mix32(mix32(seed) ^ stream) ^ slab)
}

/// Hash of a row given the slab hash.
#[inline(always)]
pub const fn row_hash(slab_hash: u32, y: u32) -> u32 {
    mix32(slab_hash ^ y)
}

/// Hash of a pixel given the row hash.
#[inline(always)]
pub const fn pixel_hash(row_hash: u32, x: u32) -> u32 {
    mix32(row_hash ^ x.wrapping_mul(0x9e37_79b9))
}

/// Converts a hash to a float in [0, 1) exactly: the top 24 bits times 2^-24.
#[inline(always)]
pub fn unit_float(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Picks one of `2^bits` phases from a hash (its top bits).
#[inline(always)]
pub const fn phase_index(h: u32, bits: u32) -> u32 {
    if bits == 0 { 0 } else { h >> (32 - bits) }
}

/// A 64-bit FNV-1a style hash over 32-bit words, for image and LDI fingerprints.
#[derive(Clone, Copy, Debug)]
pub struct Fingerprint(u64);

impl Default for Fingerprint {
    fn default() -> Self {
        Fingerprint(0xcbf2_9ce4_8422_2325)
    }
}

impl Fingerprint {
    /// Mixes in one word.
    #[inline(always)]
    pub fn word(&mut self, w: u32) {
        self.0 = (self.0 ^ u64::from(w)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    /// Mixes in a slice of words.
    pub fn words(&mut self, ws: &[u32]) {
        for &w in ws {
            self.word(w);
        }
    }
    /// Mixes in the bit patterns of floats.
    pub fn floats(&mut self, fs: &[f32]) {
        for &f in fs {
            self.word(f.to_bits());
        }
    }
    /// The final 64-bit value.
    pub fn finish(self) -> u64 {
        // One more avalanche round so that short inputs still spread over all bits.
        let mut x = self.0;
        x ^= x >> 33;
        x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
        x ^= x >> 33;
        x
    }
    /// The final value as 16 hex digits.
    pub fn hex(self) -> String {
        format!("{:016x}", self.finish())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mix32x8_is_mix32_in_every_lane() {
        for base in (0..1_000_000u32).step_by(8 * 997).chain([u32::MAX - 7]) {
            let lanes: [u32; 8] =
                std::array::from_fn(|i| base.wrapping_add(i as u32 * 0x9e37_79b9));
            let got = mix32x8(u32x8::new(lanes)).to_array();
            assert_eq!(got, lanes.map(mix32), "{base}");
        }
    }

    #[test]
    fn mix32_is_a_bijection_on_a_sample_and_avalanches() {
        let mut seen = std::collections::HashSet::new();
        for i in 0..100_000u32 {
            assert!(seen.insert(mix32(i)));
        }
        // Flipping one input bit flips about half the output bits on average.
        let mut total = 0u32;
        for i in 0..1000u32 {
            for b in 0..32 {
                total += (mix32(i) ^ mix32(i ^ (1 << b))).count_ones();
            }
        }
        let mean = f64::from(total) / 32_000.0;
        assert!((mean - 16.0).abs() < 0.5, "mean flipped bits {mean}");
    }

    #[test]
    fn unit_float_is_exact_and_in_range() {
        assert_eq!(unit_float(0), 0.0);
        assert_eq!(unit_float(u32::MAX), 1.0 - 1.0 / 16_777_216.0);
        assert_eq!(unit_float(0x8000_0000), 0.5);
    }

    #[test]
    fn phases_are_uniform() {
        let mut counts = [0u32; 64];
        let s = slab_hash(7, 0, 3);
        for y in 0..128 {
            let r = row_hash(s, y);
            for x in 0..128 {
                counts[phase_index(pixel_hash(r, x), 6) as usize] += 1;
            }
        }
        // 16384 draws into 64 bins: expected 256 each, std 16; allow 6 sigma.
        assert!(
            counts.iter().all(|&c| (c as i32 - 256).abs() < 96),
            "{counts:?}"
        );
    }

    #[test]
    fn fingerprint_sees_every_word_and_order() {
        let mut a = Fingerprint::default();
        a.words(&[1, 2, 3]);
        let mut b = Fingerprint::default();
        b.words(&[1, 3, 2]);
        assert_ne!(a.finish(), b.finish());
        let mut c = Fingerprint::default();
        c.floats(&[0.0]);
        let mut d = Fingerprint::default();
        d.floats(&[-0.0]);
        assert_ne!(c.finish(), d.finish());
    }
}
