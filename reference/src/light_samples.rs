//! The light samples of the shadow-ray reference: multi-jittered strata on the unit square
//! (integer-only, so the same everywhere), mapped to Gaussian directions through the normal
//! quantile.

use convshadow_common::pixel::hash::mix32;

/// The multi-jittered sample of coarse cell (a, b) of a k×k grid (Chiu, Shirley and Wang 1994):
/// its fine stratum (1/k² wide) on each axis, x from column a's permutation at row b, y from row
/// b's permutation at column a, the permutations hashed from `base`. Every fine stratum of
/// either axis holds exactly one of the k² samples (N-rooks) and every coarse cell one.
pub(crate) fn fine_strata(base: u32, k: u32, a: u32, b: u32) -> (u32, u32) {
    let col = mix32(base ^ a.wrapping_mul(0x68bc_21eb) ^ 0x0a11_ce55);
    let row = mix32(base ^ b.wrapping_mul(0x02e5_be93) ^ 0x0b0b_cafe);
    (a * k + permute(b, k, col), b * k + permute(a, k, row))
}

/// The multi-jittered Gaussian sample of coarse cell (a, b) of a k×k grid seeded by `base`: a
/// standard normal deviate per axis, through the inverse normal CDF of the cell's fine strata
/// ([`fine_strata`]) jittered by the integer hash; and that hash, for more jitter.
pub(crate) fn gaussian_pair(base: u32, k: u32, a: u32, b: u32) -> ([f64; 2], u32) {
    let inv_m = 1.0 / f64::from(k * k);
    let h = mix32(base ^ (a * k + b).wrapping_mul(0x9e37_79b9));
    let j1 = (f64::from(h >> 8) + 0.5) / 16_777_216.0;
    let j2 = (f64::from(mix32(h) >> 8) + 0.5) / 16_777_216.0;
    let (fx, fy) = fine_strata(base, k, a, b);
    (
        [
            inverse_normal_cdf((f64::from(fx) + j1) * inv_m),
            inverse_normal_cdf((f64::from(fy) + j2) * inv_m),
        ],
        h,
    )
}

/// Kensler's hashed permutation of `0..l` (A. Kensler, "Correlated Multi-Jittered Sampling",
/// Pixar technical memo 13-01, 2013): a bijection of the next power of two, cycle-walked into
/// `0..l`; `p` selects the permutation. Integer-only, so the samples are the same everywhere.
pub(crate) fn permute(i: u32, l: u32, p: u32) -> u32 {
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let mut i = i;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            return (i + p % l) % l;
        }
    }
}

/// `ceil(√samples)`, at least 1: the side of the stratification.
pub fn samples_side(samples: u32) -> u32 {
    let mut k = 1u32;
    while k * k < samples {
        k += 1;
    }
    k
}

/// The standard normal quantile (Acklam's rational approximation refined by one Halley step
/// on the complementary error function: relative error below 1e-12 on (0, 1)).
pub fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let p = p.clamp(1e-300, 1.0 - 1e-16);
    let x = if p < 0.024_25 {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - 0.024_25 {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (1.0 - p).ln()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    // One Halley step: e = Φ(x) − p.
    let e = normal_cdf(x) - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (0.5 * x * x).exp();
    x - u / (1.0 + 0.5 * x * u)
}

/// The standard normal CDF Φ(x) = erfc(−x/√2)/2, by `libm`'s `erfc` (musl's, within about an
/// ulp): the complementary function keeps the lower tail's relative precision.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_and_quantile_agree_with_known_values() {
        // Φ(0) = 1/2, Φ(1) = 0.841344746068543, Φ(−3) = 0.00134989803163009,
        // Φ(−5) = 1 − Φ(5) = 2.866515718791939e-7 (tabulated values).
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-16);
        assert!((normal_cdf(1.0) - 0.841_344_746_068_543).abs() < 1e-14);
        assert!((normal_cdf(-3.0) - 0.001_349_898_031_630_09).abs() < 1e-16);
        // The upper tail: Φ(5) is within f64's rounding of 1 − 2.87e-7 (ulp(1) = 2.2e-16, so
        // 1 − Φ(5) cannot be checked closer than that); the lower tail Φ(−5) is computed directly
        // by the continued fraction and must be good to 1e-14 relative.
        assert!((normal_cdf(5.0) - (1.0 - 2.866_515_718_791_939e-7)).abs() <= 2.0 * f64::EPSILON);
        assert!((normal_cdf(-5.0) / 2.866_515_718_791_939e-7 - 1.0).abs() < 1e-14);
        for p in [1e-9, 0.001, 0.02, 0.3, 0.5, 0.77, 0.999] {
            let x = inverse_normal_cdf(p);
            assert!((normal_cdf(x) - p).abs() < 1e-13 * p.max(1e-3), "{p}");
        }
    }

    #[test]
    fn permute_is_a_permutation_and_the_samples_are_multi_jittered() {
        for l in [1u32, 2, 3, 7, 16, 31, 32, 64] {
            for p in [0u32, 1, 0xdead_beef, 0xffff_ffff, 12345] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permute(i, l, p);
                    assert!(j < l && !seen[j as usize], "l {l}, p {p}: {i} → {j}");
                    seen[j as usize] = true;
                }
            }
        }
        // The fine strata of both axes are each hit once, the coarse cells once (k = 8, a few
        // seeds).
        let k = 8u32;
        for base in [0u32, 7, 0x1234_5678] {
            let (mut fx_seen, mut fy_seen) = (vec![0; 64], vec![0; 64]);
            for a in 0..k {
                for b in 0..k {
                    let (fx, fy) = fine_strata(base, k, a, b);
                    assert_eq!((fx / k, fy / k), (a, b));
                    fx_seen[fx as usize] += 1;
                    fy_seen[fy as usize] += 1;
                }
            }
            assert!(fx_seen.iter().chain(&fy_seen).all(|&c| c == 1));
        }
    }
}
