use std::f64::consts::PI;

use super::*;
use crate::model::kernel::{KERNEL_NAMES, KERNEL_SYNTAX};

#[test]
fn the_kernel_list_parses_round_trips_and_covers_every_family() {
    let mut families = Vec::new();
    for name in KERNEL_NAMES {
        let spec: KernelSpec = name.parse().unwrap();
        assert_eq!(spec.to_string(), name);
        families.push(std::mem::discriminant(&spec.kind));
    }
    for kind in [
        KernelKind::Ellipse(2),
        KernelKind::Dirac,
        KernelKind::Poisson(8),
        KernelKind::Gaussian(3),
        KernelKind::Box,
    ] {
        assert!(
            families.contains(&std::mem::discriminant(&kind)),
            "{kind:?}"
        );
    }
    for name in [
        "ellipse",
        "dirac",
        "poisson8",
        "poisson16",
        "gaussian:K",
        "box",
    ] {
        assert!(KERNEL_SYNTAX.contains(name), "{name}");
    }
}

#[test]
fn kernel_names_round_trip_and_bad_names_are_rejected() {
    for name in [
        "ellipse2",
        "ellipse3",
        "ellipse7:slab",
        "dirac",
        "poisson8",
        "poisson16",
        "gaussian:19",
        "box",
    ] {
        assert_eq!(name.parse::<KernelSpec>().unwrap().to_string(), name);
    }
    for bad in [
        "ellipse1",
        "ellipse",
        "gaussian:4",
        "gaussian:x",
        "box:slab",
        "blur",
        "",
    ] {
        assert!(bad.parse::<KernelSpec>().is_err(), "{bad}");
    }
}

#[test]
fn moments_follow_design_formulas() {
    // Tilt 45° → μl = 1; e = 0.1, px = 0.05 → mean −2 px. Variance 0.5·d1·e/px² = 0.5·0.5·0.1/0.0025.
    let m = KernelMoments::for_light([45.0, 0.0], [0.5, 0.5], 0.0, 0.1, 0.5, 0.05);
    assert!((m.mean[0] + 2.0).abs() < 1e-12 && m.mean[1] == 0.0);
    assert!((m.cov[0][0] - 10.0).abs() < 1e-9 && (m.cov[1][1] - 10.0).abs() < 1e-9);
    // Rotation by 90° swaps the axes.
    let r = KernelMoments::for_light([0.0, 0.0], [1.0, 0.0], 90.0, 1.0, 1.0, 1.0);
    assert!(r.cov[0][0].abs() < 1e-12 && (r.cov[1][1] - 1.0).abs() < 1e-12);
}

#[test]
fn ellipse_variance_ratio_matches_closed_form_limits() {
    // Circle: a uniform point on a circle of radius 1 has Var x = 1/2.
    let (vx, vy, len) = ellipse_second_moments(1.0);
    assert!((vx - 0.5).abs() < 1e-12 && (vy - 0.5).abs() < 1e-12);
    assert!((len - 2.0 * PI).abs() < 1e-9);
    // Segment [-1, 1] traversed uniformly: Var x = 1/3.
    let (vx, vy, _) = ellipse_second_moments(0.0);
    assert!((vx - 1.0 / 3.0).abs() < 1e-6 && vy == 0.0, "{vx}");
    for ratio in [1e-6, 0.01, 0.3, 0.9] {
        let r = ellipse_ratio_for_variance_ratio(ratio);
        let (vx, vy, _) = ellipse_second_moments(r);
        assert!((vy / vx - ratio).abs() < 1e-9 * ratio.max(1e-3), "{ratio}");
    }
}

#[test]
fn moments_by_lanes_are_the_bits_of_one_step_at_a_time() {
    // The moment integral and the arc-length table by lanes give the plain loops' bits for
    // dyadic ratios, the ends and ratios spread over [0, 1] (a reassociated sum or a fused
    // product fails here).
    let mut rs = vec![0.0, 1.0, 0.5, 0.25, 0.75, 1e-9, 1.0 - 1e-12];
    rs.extend((1..200).map(|i| (f64::from(i) * 0.618_033_988_75).fract()));
    for r in rs {
        let (lanes, steps) = (
            ellipse_second_moments(r),
            ellipse_second_moments_by_steps(r),
        );
        let bits = |m: (f64, f64, f64)| [m.0.to_bits(), m.1.to_bits(), m.2.to_bits()];
        assert_eq!(bits(lanes), bits(steps), "r = {r}");
        // The arc-length table of the pattern's points, for the unit ellipse and a scaled one.
        for (a, b) in [(1.0, r), (2.5, 0.7 * r)] {
            let (lanes, steps) = (cumulative_arc(a, b), cumulative_arc_by_steps(a, b));
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&lanes), bits(&steps), "a = {a}, b = {b}");
        }
    }
}

#[test]
fn remembered_moments_give_the_bits_of_the_integral() {
    // The bisection written out with the integral itself: nearby ratios share their first steps,
    // so the later ones read remembered moments, which must be the integral's bits.
    let plain = |ratio: f64| {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            let (vx, vy, _) = ellipse_second_moments(mid);
            if vy / vx < ratio {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    for ratio in [0.25, 0.25 + 1e-12, 0.2500001, 0.7, 1e-5, 0.25] {
        let remembered = ellipse_ratio_for_variance_ratio(ratio);
        assert_eq!(remembered.to_bits(), plain(ratio).to_bits(), "{ratio}");
    }
}

#[test]
fn ellipse_points_are_equally_spaced_in_arc_length() {
    let pts = ellipse_points(2.0, 0.5, 0.1, 16);
    let mut d: Vec<f64> = Vec::new();
    for i in 0..16 {
        // Chord lengths of equal arcs on this smooth curve differ only by curvature; compare
        // neighbouring arcs via a fine polyline instead: the arc between points i and i+1.
        let a = pts[i];
        let b = pts[(i + 1) % 16];
        let ta = a[1].atan2(a[0] / 4.0);
        let mut tb = b[1].atan2(b[0] / 4.0);
        if tb < ta {
            tb += 2.0 * PI;
        }
        let mut s = 0.0;
        let steps = 2000;
        for j in 0..steps {
            let t = ta + (tb - ta) * (j as f64 + 0.5) / steps as f64;
            s += (4.0 * t.sin().powi(2) + 0.25 * t.cos().powi(2)).sqrt() * (tb - ta) / steps as f64;
        }
        d.push(s);
    }
    let mean = d.iter().sum::<f64>() / 16.0;
    assert!(d.iter().all(|x| (x - mean).abs() < 1e-3 * mean), "{d:?}");
}

fn check_table(spec: &str, m: KernelMoments, tol: f64) {
    let t = build_table(spec.parse().unwrap(), &m, 8, false);
    for p in 0..t.phase_count {
        assert_eq!(sequential_weight_sum(t.phase(p)), 1.0, "{spec} phase {p}");
    }
    let r = t.response_moments();
    // Without compensation the response has the pattern's covariance plus bilinear variance,
    // which is at most 1/4 per axis; the mean is exact.
    assert!((r.mean[0] - m.mean[0]).abs() < 1e-6, "{spec} {r:?}");
    assert!((r.mean[1] - m.mean[1]).abs() < 1e-6, "{spec} {r:?}");
    for i in 0..2 {
        let extra = r.cov[i][i] - m.cov[i][i];
        assert!(
            (-tol..=0.25 + tol).contains(&extra),
            "{spec} axis {i}: {r:?} vs {m:?}"
        );
    }
}

#[test]
fn tables_have_exact_unit_weight_and_target_moments() {
    let cases = [
        KernelMoments::for_light([20.0, -10.0], [0.02, 0.005], 30.0, 0.01, 0.5, 0.005),
        KernelMoments::for_light([0.0, 0.0], [0.0, 0.0], 0.0, 0.01, 0.5, 0.005),
        KernelMoments::for_light([60.0, 0.0], [0.01, 0.0], 10.0, 0.01, 0.5, 0.005),
    ];
    for m in cases {
        for spec in COMPENSATED {
            check_table(spec, m, 1e-3 * (1.0 + m.cov[0][0] + m.cov[1][1]));
        }
    }
}

#[test]
fn poisson_pattern_is_white() {
    for n in [8, 16] {
        let p = poisson_disk_whitened(n);
        let (mut m, mut c) = ([0.0; 2], [0.0; 3]);
        for q in &p {
            m[0] += q[0];
            m[1] += q[1];
            c[0] += q[0] * q[0];
            c[1] += q[0] * q[1];
            c[2] += q[1] * q[1];
        }
        let k = f64::from(n);
        assert!(m[0].abs() < 1e-9 && m[1].abs() < 1e-9);
        assert!(
            (c[0] / k - 1.0).abs() < 1e-9
                && (c[1] / k).abs() < 1e-9
                && (c[2] / k - 1.0).abs() < 1e-9
        );
    }
}

/// Kernels whose compensated response must hit Σκ exactly (`box` has its own schedule).
const COMPENSATED: [&str; 7] = [
    "ellipse2",
    "ellipse3",
    "ellipse5:slab",
    "dirac",
    "poisson8",
    "poisson16",
    "gaussian:19",
];

/// The bound on a response moment's error that rounding the weights to f32 allows: each of a
/// phase's N corner weights is off by at most ε/2 relative, and the last one absorbs the f32
/// sum's rounding (at most N·ε/2 absolute), so the weight misplaced is ≤ N·ε and it sits at
/// most R px from the mean: the variance moves by ≤ N·ε·R².
fn rounding_bound(t: &KernelTable, mean: [f64; 2]) -> f64 {
    let shift = t.slab_shift.first().copied().unwrap_or([0, 0]);
    let mut r2: f64 = 1.0;
    for tap in &t.taps {
        for (c, w) in tap.w.iter().enumerate() {
            if *w != 0.0 {
                let x = -f64::from(tap.dx + shift[0] + (c as i32 & 1));
                let y = -f64::from(tap.dy + shift[1] + (c as i32 >> 1));
                // Carried tables: the slab's mean is within 1 px of μκ.
                let d = (x - mean[0]).abs().max((y - mean[1]).abs()) + 1.0;
                r2 = r2.max(2.0 * d * d);
            }
        }
    }
    4.0 * f64::from(t.taps_per_phase) * f64::from(f32::EPSILON) * r2
}

/// Σκ = R(α) diag(a, b) R(α)ᵀ.
fn rotated(a: f64, b: f64, deg: f64) -> [[f64; 2]; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [
        [c * c * a + s * s * b, c * s * (a - b)],
        [c * s * (a - b), s * s * a + c * c * b],
    ]
}

/// Builds a compensated table and checks the iterated moments: after n slabs the variance is
/// n·Σκ per axis (within the rounding bound) and the mean n·μκ (carried: within ½ px, the
/// rounding of n·μκ). Returns the table and its per-slab response.
fn compensated(spec: &str, m: KernelMoments) -> (KernelTable, KernelMoments, f64) {
    const SLABS: u32 = 8;
    let t = build_table(spec.parse().unwrap(), &m, SLABS, true);
    for p in 0..t.phase_count {
        assert_eq!(sequential_weight_sum(t.phase(p)), 1.0, "{spec} phase {p}");
    }
    let r = t.response_moments();
    let tol = rounding_bound(&t, m.mean);
    let carried = t.slab_shift.iter().any(|s| *s != [0, 0]);
    let n = f64::from(SLABS);
    for ax in 0..2 {
        let (got, want) = (n * r.mean[ax], n * m.mean[ax]);
        let bound = if carried { 0.5 + 1e-9 } else { n * tol };
        assert!(
            (got - want).abs() <= bound,
            "{spec} {m:?}: iterated mean {got} vs {want} (carried {carried})"
        );
        assert!(
            (r.cov[ax][ax] - m.cov[ax][ax]).abs() <= tol,
            "{spec} {m:?}: axis {ax} variance {} vs {} (bound {tol:e}, carried {carried})",
            r.cov[ax][ax],
            m.cov[ax][ax]
        );
    }
    (t, r, tol)
}

#[test]
fn compensated_response_variance_is_sigma_kappa_from_a_thousandth_to_a_hundred_px2() {
    // Means with a fractional part (μκ at tilts 20° and −10°, a half pixel, 2.37 px) and an
    // integer one; Σκ below f(1−f) of the fraction carries the mean, above it does not.
    let means = [[-0.364, 0.176], [0.5, -0.5], [-2.373, 0.0], [-1.0, 2.0]];
    let variances = [
        0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.25, 0.5, 1.0, 3.0, 10.0, 30.0, 100.0,
    ];
    let mut carried = 0;
    for spec in COMPENSATED {
        for mean in means {
            for v in variances {
                for cov in [[[v, 0.0], [0.0, v]], [[v, 0.0], [0.0, 4.0 * v]]] {
                    let (t, _, _) = compensated(spec, KernelMoments { mean, cov });
                    carried += usize::from(t.slab_shift.iter().any(|s| *s != [0, 0]));
                }
            }
        }
    }
    assert!(carried > 0, "some cases must carry the mean");
}

#[test]
fn compensated_response_keeps_the_correlation_when_sigma_kappa_allows_it() {
    // Σκ − I/4 positive semi-definite: P = Σκ − diag(bilinear) ⪰ 0 exists (reads add at most
    // 1/4 px² per axis), so the whole covariance is reached.
    let mean = [-0.364, 0.176];
    for (a, b, deg) in [
        (0.25, 2.0, 65.0),
        (0.3, 2.0, 30.0),
        (1.0, 10.0, 45.0),
        (5.0, 50.0, 20.0),
    ] {
        let cov = rotated(a, b, deg);
        for spec in COMPENSATED {
            let (_, r, tol) = compensated(spec, KernelMoments { mean, cov });
            assert!(
                (r.cov[0][1] - cov[0][1]).abs() <= tol,
                "{spec} ({a}, {b}, {deg}°): covariance {} vs {}",
                r.cov[0][1],
                cov[0][1]
            );
        }
    }
    // Narrower rotated lights: the diagonal is still exact (checked in `compensated`) and
    // the correlation is never exaggerated or flipped.
    for (a, b, deg) in [(0.01, 0.2, 45.0), (0.001, 1.0, 30.0), (0.05, 0.1, 60.0)] {
        let cov = rotated(a, b, deg);
        for spec in COMPENSATED {
            let (_, r, tol) = compensated(spec, KernelMoments { mean, cov });
            assert!(
                r.cov[0][1] * cov[0][1] >= -tol && r.cov[0][1].abs() <= cov[0][1].abs() + tol,
                "{spec} ({a}, {b}, {deg}°): covariance {} vs {}",
                r.cov[0][1],
                cov[0][1]
            );
        }
    }
}

#[test]
fn carried_mean_compensates_the_pattern_around_zero() {
    // Σκ = 0.05 px² < f(1−f) = 0.24 of μκ = −0.6: the mean is carried. The pattern is read
    // around 0, where its own taps add bilinear variance: uncompensated, ellipse2's two points
    // at ±√(2·0.05)·(cos, sin) add E|x|·(1 − |x|) ≈ 0.18 px² per axis (+360 %).
    let m = KernelMoments {
        mean: [-0.6, 0.3],
        cov: [[0.05, 0.0], [0.0, 0.05]],
    };
    let (t, _, _) = compensated("ellipse2", m);
    assert!(
        t.slab_shift.iter().any(|s| *s != [0, 0]),
        "the mean is carried"
    );
    // Over 8 slabs the shifts add up to round(8·μκ) = (−5, 2) (read offsets are −moves).
    let total = t
        .slab_shift
        .iter()
        .fold([0, 0], |a, s| [a[0] - s[0], a[1] - s[1]]);
    assert_eq!(total, [-5, 2]);
}

#[test]
fn gaussian_taps_of_small_variance_are_three_points() {
    let var_x = |taps: &[([f64; 2], f64)]| taps.iter().map(|(o, w)| w * o[0] * o[0]).sum::<f64>();
    for v in [1e-9, 1e-3, 0.05, 0.25, 0.5] {
        // Axis-aligned, y variance 0: one row of (v/2, 1 − v, v/2) at −1, 0, 1.
        let taps = gaussian_taps(19, v, 0.0, [1.0, 0.0]);
        let mut xs: Vec<(f64, f64)> = taps.iter().map(|(o, w)| (o[0], *w)).collect();
        xs.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(
            xs,
            vec![(-1.0, 0.5 * v), (0.0, 1.0 - v), (1.0, 0.5 * v)],
            "{v}"
        );
        assert!(taps.iter().all(|(o, _)| o[1] == 0.0));
        assert!((var_x(&taps) - v).abs() <= 1e-15, "{v}");
    }
    // Above 1/2 the sampled Gaussian: variance exact, positions i·√(v/got). By Poisson
    // summation the integer-sampled Gaussian's variance is v·(1 − O(e^(−2π²v))): got is
    // within 1e-4 of v for v ≥ 1/2 (and the ±9 truncation is > 4 std away for v ≤ 4), so
    // the stretch stays within 1 %.
    for v in [0.5001, 1.0, 4.0] {
        let taps = gaussian_taps(19, v, 0.0, [1.0, 0.0]);
        assert!((var_x(&taps) - v).abs() <= 1e-12 * v, "{v}");
        let stretch = taps
            .iter()
            .map(|(o, _)| o[0])
            .filter(|x| *x > 0.0)
            .fold(f64::INFINITY, f64::min);
        assert!((stretch - 1.0).abs() <= 0.01, "{v}: stretch {stretch}");
    }
    // The case the old stretch broke: Σκ = 0.25 px², μκ = −0.364 (pattern variance ≈ 0.02):
    // every read stays within |μκ| + 1 px (scale ≤ 1 of taps at ≤ 1 px, plus the bilinear
    // neighbour).
    let m = KernelMoments {
        mean: [-0.364, 0.176],
        cov: [[0.25, 0.0], [0.0, 0.25]],
    };
    let (t, _, _) = compensated("gaussian:19", m);
    for tap in t.taps.iter().filter(|t| t.w != [0.0; 4]) {
        assert!(
            (-2..=1).contains(&tap.dx) && (-2..=1).contains(&tap.dy),
            "{tap:?}"
        );
    }
}

#[test]
fn distance_levels_of_one_kernel_repeat_its_rows_and_map_distances_as_the_distance_table() {
    // The iterated kernel at every level (sub-pixel shadows with the iterated penumbra): every
    // level's rows and schedule are the kernel's own, and `level_of` is the distance table's.
    let m = KernelMoments {
        mean: [0.3, -0.2],
        cov: [[0.8, 0.1], [0.1, 0.5]],
    };
    let slabs = 300;
    for spec in ["ellipse2", "ellipse2:slab", "gaussian:7", "poisson8"] {
        let kernel: KernelSpec = spec.parse().unwrap();
        let one = build_table(kernel, &m, slabs, true);
        let t = one.clone().with_distance_levels(slabs);
        let ranges = distance_levels(slabs);
        assert_eq!(t.levels as usize, ranges.len(), "{spec}");
        assert!(t.levels > 16, "{spec}: {} levels", t.levels);
        for level in 0..t.levels {
            for p in 0..t.phase_count {
                assert_eq!(t.phase(level * t.phase_count + p), one.phase(p), "{spec}");
            }
        }
        if t.phase_mode == PhaseMode::Schedule {
            assert_eq!(t.slab_phase.len(), ranges.len() * slabs as usize, "{spec}");
            assert!(
                t.slab_phase
                    .chunks(slabs as usize)
                    .all(|c| c == one.slab_phase)
            );
        }
        let scale = |f: f64| KernelMoments {
            mean: m.mean,
            cov: [
                [m.cov[0][0] * f, m.cov[0][1] * f],
                [m.cov[1][0] * f, m.cov[1][1] * f],
            ],
        };
        let distance = build_distance_table(kernel, &scale, slabs, true, &TableGuard::unlimited())
            .expect("an unlimited guard never stops");
        assert_eq!(t.level_of, distance.level_of, "{spec}");
        assert_eq!(
            (t.slab_shift, t.taps_per_phase),
            (one.slab_shift, one.taps_per_phase)
        );
    }
}
