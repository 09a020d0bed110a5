//! Analytic accuracy of the slab sweep. Every expected value is derived from the scene
//! parameters (μκ = −e·μl, Σκ = d1·e·R Σl Rᵀ, the Gaussian CDF), never from a render.

use crate::support;

use std::path::Path;

use convshadow::common::model::kernel::{KERNEL_NAMES as KERNELS, KernelKind, KernelSpec};
use convshadow::common::model::scene::{Penumbra, Scene};
use convshadow::common::plan::RenderPlan;
use convshadow::cpu::sweep::SweepOutput;
use convshadow::reference::edge::{self, EdgeSetup, InitialLight, phi, run_light};
use convshadow::reference::impulse::{self, moments};

/// Runs the sweep of a scene, optionally from a given initial light buffer.
fn run(scene: &Scene, initial: Option<InitialLight<'_>>) -> (RenderPlan, SweepOutput) {
    let (plan, out, _) = run_light(scene, initial);
    (plan, out)
}

/// The kernel moments in pixel units with e = d1 = pixel size = 1: μκ = −tan ω, Σκ = R diag(σ²) Rᵀ.
fn design_moments(tilt: [f64; 2], variance: [f64; 2], rotation: f64) -> ([f64; 2], [[f64; 2]; 2]) {
    let mean = [-tilt[0].to_radians().tan(), -tilt[1].to_radians().tan()];
    let (s, c) = rotation.to_radians().sin_cos();
    let (a, b) = (variance[0], variance[1]);
    let cov = [
        [c * c * a + s * s * b, c * s * (a - b)],
        [c * s * (a - b), s * s * a + c * c * b],
    ];
    (mean, cov)
}

/// Whether the kernel draws its phase per pixel: a single impulse's mass is then only conserved in
/// expectation (each output pixel's weights sum to 1, not each input pixel's), so their response
/// is averaged over seeds. The others are shift-invariant per slab and conserve it exactly.
fn per_pixel_random(kernel: &str) -> bool {
    let spec: KernelSpec = kernel.parse().unwrap();
    match spec.kind {
        KernelKind::Ellipse(_) => !spec.per_slab_phase,
        KernelKind::Poisson(_) => true,
        _ => false,
    }
}
const SEEDS: u32 = 12;
/// Slabs of the impulse-response scenes.
const IMPULSE_SLABS: u32 = 24;
/// Grid edge of the impulse-response scenes (the impulse is at its centre).
const IMPULSE_GRID: u32 = 256;

/// One impulse-response case: the light's (tilt, variance, rotation), the kernel and whether its
/// variance is compensated.
struct ImpulseCase<'a> {
    tilt: [f64; 2],
    variance: [f64; 2],
    rotation: f64,
    kernel: &'a str,
    compensate: bool,
}

/// How many seeds a kernel's response is averaged over: 12 for per-pixel random phases, 64 for
/// `:slab` (exact mass, but its covariance is right only in expectation over the slab phases),
/// else 1.
fn seed_count(random: bool, per_slab: bool) -> u32 {
    if random {
        SEEDS
    } else if per_slab {
        64
    } else {
        1
    }
}

/// The final light of a unit impulse at pixel (`c`, `c`), averaged over `seeds` seeds.
fn averaged_impulse_response(
    case: &ImpulseCase<'_>,
    seeds: u32,
    c: usize,
) -> (RenderPlan, SweepOutput) {
    let mut scene = impulse::empty_scene(
        IMPULSE_SLABS,
        IMPULSE_GRID,
        case.tilt,
        case.variance,
        case.rotation,
        case.kernel,
        case.compensate,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let impulse = |plan: &RenderPlan| {
        let mut v = vec![0.0f32; plan.light_row_len() * plan.grid_height as usize];
        v[c * plan.light_row_len() + c] = 1.0;
        v
    };
    let mut avg: Option<(RenderPlan, SweepOutput)> = None;
    for seed in 0..seeds {
        scene.sweep.seed = seed;
        let (plan, out) = run(&scene, Some(&impulse));
        match &mut avg {
            None => avg = Some((plan, out)),
            Some((_, acc)) => {
                for (a, b) in acc.light.iter_mut().zip(&out.light) {
                    *a += *b;
                }
            }
        }
    }
    let (plan, mut out) = avg.unwrap();
    for v in &mut out.light {
        *v /= seeds as f32;
    }
    (plan, out)
}

/// Stated (mass, mean, relative covariance) tolerances: deterministic kernels are exact up to
/// rounding and the 1/4 px² bilinear bound; per-pixel random ones carry the sampling noise of
/// 12 seeds.
fn tolerances(random: bool, per_slab: bool) -> (f64, f64, f64) {
    if random {
        (0.15, 0.5, 0.08)
    } else if per_slab {
        (2e-4, 0.02, 0.08)
    } else {
        (2e-4, 0.02, 0.02)
    }
}

/// Checks the measured covariance `cov` against `target` = n·Σκ for the case's compensation.
fn check_covariance(
    case: &ImpulseCase<'_>,
    what: &str,
    cov: [[f64; 2]; 2],
    target: [[f64; 2]; 2],
    slack: f64,
    trace: f64,
    n: f64,
) {
    let (compensate, kernel, variance) = (case.compensate, case.kernel, case.variance);
    let min_axis = variance[0].min(variance[1]);
    if compensate && kernel != "box" && min_axis > 0.25 {
        // Compensated: pattern + bilinear = Σκ.
        for a in 0..2 {
            for b in 0..2 {
                assert!(
                    (cov[a][b] - target[a][b]).abs() < slack,
                    "{what}: {cov:?} vs {target:?}"
                );
            }
        }
    } else if compensate && kernel == "box" {
        // The box's width carry keeps each axis within 10 % (stated bound for `box`).
        for a in 0..2 {
            assert!(
                (cov[a][a] - target[a][a]).abs() < 0.10 * trace + 0.25 * n,
                "{what}: {cov:?} vs {target:?}"
            );
        }
    } else {
        // Uncompensated (or a zero-variance principal axis that no pattern can undo):
        // bilinear reads add f(1−f) ≤ 1/4 px² per axis and slab on top of n·Σκ.
        for a in 0..2 {
            let extra = cov[a][a] - target[a][a];
            assert!(
                extra > -slack && extra < 0.25 * n + slack,
                "{what}: {cov:?} vs {target:?}"
            );
        }
        assert!(
            (cov[0][1] - target[0][1]).abs() < 0.25 * n + slack,
            "{what}: {cov:?} vs {target:?}"
        );
    }
}

/// Checks one case's impulse response: mass 1, mean c + n·μκ, covariance n·Σκ (`mu`, `sigma`).
fn check_impulse_case(case: &ImpulseCase<'_>, mu: [f64; 2], sigma: [[f64; 2]; 2]) {
    let (kernel, compensate) = (case.kernel, case.compensate);
    let (tilt, variance, rotation) = (case.tilt, case.variance, case.rotation);
    let n = f64::from(IMPULSE_SLABS);
    let random = per_pixel_random(kernel);
    let c = (IMPULSE_GRID / 2) as usize;
    let per_slab = kernel.ends_with(":slab");
    let (plan, out) = averaged_impulse_response(case, seed_count(random, per_slab), c);
    let expect_mean = [c as f64 + n * mu[0], c as f64 + n * mu[1]];
    let (mass, mean, cov) = moments(&plan, &out, expect_mean, 75.0);
    let what =
        format!("{kernel} compensate={compensate} tilt {tilt:?} var {variance:?} rot {rotation}");
    let target = [
        [n * sigma[0][0], n * sigma[0][1]],
        [n * sigma[1][0], n * sigma[1][1]],
    ];
    let trace = target[0][0] + target[1][1];
    eprintln!(
        "{what}: mass {mass:.4}, mean {mean:.3?} vs {expect_mean:.3?}, covariance {cov:.3?} vs n·Σκ {target:.3?}"
    );
    let (mass_tol, mean_tol, rel) = tolerances(random, per_slab);
    assert!((mass - 1.0).abs() < mass_tol, "{what}: mass {mass}");
    for a in 0..2 {
        assert!(
            (mean[a] - expect_mean[a]).abs() < mean_tol,
            "{what}: mean {mean:?} vs {expect_mean:?}"
        );
    }
    let slack = rel * trace;
    check_covariance(case, &what, cov, target, slack, trace, n);
}

#[test]
fn impulse_response_has_the_kernel_moments_for_every_kernel() {
    let cases = [
        // (tilt, variance, rotation): a rotated anisotropic light, ratio 0, ratio 1e6.
        ([20.0, -10.0], [4.0, 1.0], 30.0),
        ([-15.0, 25.0], [3.0, 0.0], 60.0),
        ([10.0, 5.0], [3e-6, 3.0], 20.0),
    ];
    for (tilt, variance, rotation) in cases {
        let (mu, sigma) = design_moments(tilt, variance, rotation);
        for kernel in KERNELS {
            for compensate in [false, true] {
                let case = ImpulseCase {
                    tilt,
                    variance,
                    rotation,
                    kernel,
                    compensate,
                };
                check_impulse_case(&case, mu, sigma);
            }
        }
    }
}

/// The light profile across the edge of `tests/accuracy/sweep_accuracy.rs`'s set-up
/// ([`EdgeSetup::classic`]: e = 0.01, d1 = 0.16, 512 × 96 pixels of 0.01).
fn edge_profile(m: u32, tilt: f64, variance: f64, kernel: &str) -> Vec<f64> {
    EdgeSetup::classic(m, tilt, variance, kernel).profile().0
}

/// Where the profile first rises through 0.5, from column 64 (the left border reads unoccluded
/// light outside the grid).
fn half_crossing(profile: &[f64]) -> f64 {
    edge::half_crossing(profile, 64).expect("profile never crosses 0.5")
}

#[test]
fn half_shadow_isoline_follows_the_light_at_every_distance() {
    let variance = 0.05;
    for tilt in [0.0f64, 30.0, 60.0] {
        for m in [4u32, 16, 64] {
            let s = EdgeSetup::classic(m, tilt, variance, "ellipse2");
            let d = f64::from(m) * s.slab_distance;
            // The edge projects to the image centre; the isoline moves by −d·tan ω.
            let expected = f64::from(s.width) / 2.0 - d * tilt.to_radians().tan() / s.pixel_size;
            let got = half_crossing(&edge_profile(m, tilt, variance, "ellipse2"));
            assert!(
                (got - expected).abs() <= 0.5,
                "tilt {tilt}°, d = {d} ({m} slabs): isoline at {got:.3} px, expected {expected:.3}"
            );
        }
    }
}

#[test]
fn penumbra_matches_the_correct_shadow_at_d1_and_the_iterated_model_elsewhere() {
    let variance = 0.05f64;
    let sigma = variance.sqrt();
    for (m, tilt) in [(16u32, 30.0f64), (4, 0.0), (64, 30.0)] {
        let s = EdgeSetup::classic(m, tilt, variance, "ellipse2");
        let d = f64::from(m) * s.slab_distance;
        // Correct shadow: std d·σ; iterated model (paper eq. 8): std √(d·d1)·σ. Equal at d = d1.
        let s_iter = (d * s.optimal_distance).sqrt() * sigma / s.pixel_size;
        let profile = edge_profile(m, tilt, variance, "ellipse2");
        let center = f64::from(s.width) / 2.0 - d * tilt.to_radians().tan() / s.pixel_size;
        let (mut se, mut count) = (0.0, 0);
        for (x, v) in profile.iter().enumerate() {
            let u = x as f64 + 0.5 - center;
            if u.abs() <= 4.0 * s_iter {
                se += (v - phi(u / s_iter)).powi(2);
                count += 1;
            }
        }
        let rmse = (se / f64::from(count)).sqrt();
        eprintln!(
            "d = {d} ({m} slabs), tilt {tilt}: penumbra std {s_iter:.2} px, RMSE vs Gaussian CDF {rmse:.4}"
        );
        assert!(
            rmse < 0.02,
            "d = {d}: RMSE {rmse} against the Gaussian CDF of std {s_iter} px"
        );
    }
}

#[test]
fn a_constant_unoccluded_light_stays_exactly_one_over_4096_slabs() {
    for kernel in KERNELS {
        for penumbra in [Penumbra::Iterated, Penumbra::Distance] {
            let mut scene =
                impulse::empty_scene(4096, 24, [30.0, -20.0], [0.3, 0.1], 25.0, kernel, true)
                    .unwrap_or_else(|e| panic!("{e}"));
            scene.sweep.penumbra = penumbra;
            let (plan, out) = run(&scene, None);
            assert_eq!(plan.slabs, 4096);
            // Exact: each phase's f32 weights sum to exactly 1 in the gather's order, and reads
            // outside the buffer see 1 (and 0 in a depth plane: no occluder).
            let w = plan.grid_width as usize;
            let planes = out.light.chunks(w).enumerate();
            let per_row = plan.light_row_len() / w;
            assert!(
                planes.clone().all(|(i, p)| {
                    let want = if plan.is_depth_plane(i % per_row) {
                        0.0
                    } else {
                        1.0
                    };
                    p.iter().all(|&v| v == want)
                }),
                "{kernel} {penumbra}: the light drifted"
            );
        }
    }
}

fn extreme_scene(tilt: [f64; 2], variance: [f64; 2], kernel: &str) -> Scene {
    support::scene(
        &format!(
            r#"
[image]
width = 40
height = 32
[camera]
view_width = 4.0
[sweep]
guard_band = 0
slabs = 24
optimal_distance = 0.5
kernel = "{kernel}"
[[light]]
tilt_deg = [{}, {}]
variance = [{:e}, {:e}]
rotation_deg = 33.0
[[mesh]]
shape = "sphere"
size = [0.8, 2]
material = "m"
[[mesh]]
shape = "box"
size = [3.0, 3.0, 0.3]
translate = [0.0, 0.0, 1.5]
material = "m"
[material.m]
transport = [0.2, 0.5, 0.9]
"#,
            tilt[0], tilt[1], variance[0], variance[1]
        ),
        Path::new("."),
    )
}

#[test]
fn no_nan_or_infinity_at_grazing_tilts_zero_or_huge_variance() {
    // Pixel size 0.1, slab ≈ 0.1, d1 = 0.5: variance 2e6 gives Σκ ≈ 1e6 px² per slab.
    for kernel in KERNELS {
        for (tilt, variance) in [
            ([89.0, 0.0], [0.01, 0.01]),
            ([85.0, -80.0], [0.0, 0.0]),
            ([0.0, 89.0], [0.0, 0.0]),
            ([30.0, 10.0], [2e6, 2e6]),
            ([10.0, 0.0], [2e6, 0.0]),
        ] {
            let (plan, out) = run(&extreme_scene(tilt, variance, kernel), None);
            assert!(
                out.image.iter().all(|v| v.is_finite()),
                "{kernel} {tilt:?} {variance:?}: image"
            );
            // The buffer is `[row][light][x][plane]`: a light's channels are ≥ 0; its depth plane
            // (distance penumbra) may be negative, where an opaque surface was crossed before
            // slab 0's middle (sub-pixel shadows' `removal_depth`).
            let planes = plan.planes_per_light();
            let channels = plan.channels as usize;
            assert!(
                out.light
                    .iter()
                    .enumerate()
                    .all(|(i, v)| v.is_finite() && (i % planes >= channels || *v >= 0.0)),
                "{kernel} {tilt:?} {variance:?}: light"
            );
            assert!(
                plan.lights[0].table.taps_per_phase as usize
                    <= convshadow::common::plan::kernel::MAX_TAPS_PER_PHASE
            );
        }
    }
}

#[test]
fn dense_media_flush_light_to_exact_zeros_not_subnormals() {
    let text = r#"
[image]
width = 48
height = 48
[camera]
view_width = 4.0
[sweep]
guard_band = 0
slabs = 400
optimal_distance = 0.5
[[light]]
tilt_deg = [10.0, 0.0]
variance = [0.01, 0.01]
[[mesh]]
shape = "box"
size = [3.0, 3.0, 4.0]
material = "fog"
[material.fog]
opacity = 0.5
transport = [0.3, 0.3, 0.3]
reference_length = 0.01  # one slab: opacity 0.5 per slab
"#;
    let (_, out) = run(&support::scene(text, Path::new(".")), None);
    // 400 slabs of attenuation 1 − 0.5·0.7 = 0.65 would reach 1e-75: far below f32's range.
    assert!(
        out.light.contains(&0.0),
        "the light should have been flushed to zero"
    );
    assert!(
        out.light.iter().all(|&v| v == 0.0 || v.is_normal()),
        "a subnormal light value survived"
    );
    assert!(
        out.image.iter().all(|&v| v == 0.0 || v.is_normal()),
        "a subnormal image value"
    );
}
