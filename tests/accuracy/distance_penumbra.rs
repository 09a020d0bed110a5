//! The distance penumbra (`sweep.penumbra = "distance"`) against independent references: the
//! closed-form edge shadow, the numerically convolved disk shadow, and the shadow-ray reference
//! (Monte Carlo over the Gaussian light's directions) for scenes with occluders at several depths
//! and media. The iterated mode's figures are computed beside them: they show what the distance
//! mode removes, and that each check can fail. Numbers: docs/accuracy.md.

use std::path::Path;

use convshadow::common::model::scene::{Penumbra, Scene, SlabSpec};
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::cpu::sweep::{CpuOptions, SweepOptions, sweep_with};
use convshadow::io::metrics::rmse;
use convshadow::pipeline::{CpuPath, RenderRequest, image_fingerprint, render};
use convshadow::reference::disk::DiskSetup;
use convshadow::reference::edge::{
    EdgeSetup, half_crossing, light_at, model_profile, run_light, width_10_90,
};
use convshadow::reference::{Reference, ReferenceOptions};

/// The edge at distance d = k·d1 (d1 = 1) with the issue's frame: tilt 30°, pixels of d/64, 256
/// px across 4d (so the correct penumbra is 64·σ px wide at every distance), `slabs` slabs between
/// occluder and receiver. `rotated`: an anisotropic light (σ² 0.02 and 0.005, axes rotated 30°),
/// else σ² = 0.01.
fn edge_at(k: f64, slabs: u32, penumbra: Penumbra, rotated: bool) -> EdgeSetup {
    EdgeSetup {
        slabs,
        slab_distance: k / f64::from(slabs),
        optimal_distance: 1.0,
        pixel_size: k / 64.0,
        width: 256,
        height: 48,
        tilt_deg: 30.0,
        variance: if rotated { 0.02 } else { 0.01 },
        variance_y: rotated.then_some(0.005),
        rotation_deg: if rotated { 30.0 } else { 0.0 },
        penumbra,
        kernel: "ellipse2".into(),
        compensation: true,
        seed: 0,
    }
}

/// An edge's errors against the correct shadow (a Gaussian penumbra of std d·σ across the edge):
/// RMSE over the trusted columns, isoline offset (px), 10–90 % width relative error (`None` when
/// the profile does not reach 0.1 or 0.9 inside the image: far too wide).
fn edge_errors(s: &EdgeSetup) -> (f64, f64, Option<f64>) {
    let (profile, _) = s.profile();
    let from = s.first_trusted_column();
    let std = s.distance() * s.variance_across().sqrt() / s.pixel_size;
    let correct = model_profile(profile.len(), s.expected_isoline(), std);
    let to = profile.len() - 8;
    let err = rmse((from..to).map(|x| (profile[x], correct[x])));
    let iso = half_crossing(&profile, from).map_or(f64::INFINITY, |x| x - s.expected_isoline());
    let want = width_10_90(&correct, from).expect("the correct profile spans 0.1–0.9");
    let width = width_10_90(&profile, from).map(|w| w / want - 1.0);
    (err, iso, width)
}

#[test]
fn an_edge_shadow_is_right_at_every_distance() {
    let mut failures = Vec::new();
    let mut iterated_failures = 0;
    for rotated in [false, true] {
        for k in [0.125, 0.25, 1.0, 4.0, 8.0] {
            let (err, iso, width) = edge_errors(&edge_at(k, 64, Penumbra::Distance, rotated));
            let (i_err, i_iso, i_width) = edge_errors(&edge_at(k, 64, Penumbra::Iterated, rotated));
            let pct =
                |w: Option<f64>| w.map_or("> image".into(), |w| format!("{:+.2} %", 100.0 * w));
            eprintln!(
                "edge d = {k}·d1{}: distance RMSE {err:.5}, isoline {iso:+.3} px, width {}; \
                 iterated RMSE {i_err:.5}, isoline {i_iso:+.3} px, width {}",
                if rotated {
                    " (rotated anisotropic)"
                } else {
                    ""
                },
                pct(width),
                pct(i_width),
            );
            let ok = |e: f64, i: f64, w: Option<f64>| {
                e <= 5e-3 && i.abs() <= 0.5 && w.is_some_and(|w| w.abs() <= 0.05)
            };
            if !ok(err, iso, width) {
                failures.push(format!(
                    "d = {k}·d1, rotated {rotated}: {err}, {iso}, {width:?}"
                ));
            }
            if !ok(i_err, i_iso, i_width) {
                iterated_failures += 1;
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    // The same bounds reject the iterated mode away from d1 (8 of the 10 cases).
    assert_eq!(
        iterated_failures, 8,
        "the bounds must tell the two models apart"
    );
}

#[test]
fn a_disk_shadow_is_right_at_every_distance() {
    const SLABS: u32 = 128;
    let mut failures = Vec::new();
    // Overhead, and tilted by 20°: 17.47 px of shift, which the sweep carries in whole pixels
    // (its smallest levels cannot read between pixels), so its shadow lands 0.53 px too far.
    for tilt in [0.0, 20.0] {
        for k in [0.25, 1.0, 4.0] {
            let setup = DiskSetup {
                slabs: SLABS,
                slab_distance: k / f64::from(SLABS),
                optimal_distance: 1.0,
                pixel_size: k / 48.0,
                width: 160,
                height: 128,
                radius: 0.25 * k,
                tilt_deg: tilt,
                variance: [0.02, 0.01],
                rotation_deg: 30.0,
                kernel: "ellipse2".into(),
                compensation: true,
                penumbra: Penumbra::Distance,
            };
            let scene = setup.scene().expect("scene");
            let g = convshadow_io::build_geometry(&scene).expect("geometry");
            let d = setup.distance();
            let correct = setup.reference_light(&g, d * d);
            // The correct shadow moved by the whole pixels the sweep carries: the occluder's
            // light leaves slab 0 and is gathered in slabs 1..=m, which move it by
            // round((m + 1)·μ) − round(μ) for μ the shift per slab.
            let mu = setup.shift_px() / f64::from(SLABS);
            let moved = (f64::from(SLABS + 1) * mu).round() - mu.round();
            let carried_tilt = (moved * setup.pixel_size / d).atan().to_degrees();
            let carried = DiskSetup {
                tilt_deg: -carried_tilt,
                ..setup.clone()
            }
            .reference_light(&g, d * d);
            let (w, h) = (setup.width as usize, setup.height as usize);
            // The shadow and its penumbra (where the correct light is below 1 − 1e-9), 3 px
            // around, 8 px from the border.
            let shadowed: Vec<usize> = (0..w * h).filter(|&i| correct[i] < 1.0 - 1e-9).collect();
            let (x0, x1) = (
                shadowed.iter().map(|i| i % w).min().expect("a shadow"),
                shadowed.iter().map(|i| i % w).max().expect("a shadow"),
            );
            let (y0, y1) = (shadowed[0] / w, shadowed[shadowed.len() - 1] / w);
            let window: Vec<usize> = (y0.saturating_sub(3).max(8)..(y1 + 4).min(h - 8))
                .flat_map(|y| {
                    (x0.saturating_sub(3).max(8)..(x1 + 4).min(w - 8)).map(move |x| y * w + x)
                })
                .collect();
            let light = |penumbra: Penumbra| {
                let s = DiskSetup {
                    penumbra,
                    ..setup.clone()
                };
                let (plan, out, _) = run_light(&s.scene().expect("scene"), None);
                let gw = plan.grid_width as usize;
                window
                    .iter()
                    .map(|&i| light_at(&plan, &out, i % gw, i / gw))
                    .collect::<Vec<f64>>()
            };
            let error = |v: &[f64], r: &[f64]| rmse(window.iter().zip(v).map(|(&i, &x)| (x, r[i])));
            let (distance, iterated) = (light(Penumbra::Distance), light(Penumbra::Iterated));
            let e = error(&distance, &correct);
            let e_carried = error(&distance, &carried);
            eprintln!(
                "disk tilt {tilt}°, d = {k}·d1: RMSE distance {e:.5} (against the carried shift \
                 {e_carried:.5}), iterated {:.5}",
                error(&iterated, &correct)
            );
            if tilt == 0.0 && e > 5e-3 {
                failures.push(format!("tilt 0°, d = {k}·d1: RMSE {e}"));
            }
            if e_carried > 5e-3 {
                failures.push(format!(
                    "tilt {tilt}°, d = {k}·d1: RMSE {e_carried} (carried)"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Paper fig. 18's set-up: two opaque bars at different depths (0.0 and 1.2) over a wall whose
/// upper half faces the camera (depth 2.0) and whose lower half is angled 45° away from it (depth
/// 2.0 to 4.0), so the occluder-to-receiver distance runs from 0.8 to 4.0 over one image.
fn two_occluders(penumbra: Penumbra, d1: f64) -> Scene {
    let text = format!(
        r#"
[image]
width = 128
height = 128
[camera]
view_width = 4.0
[sweep]
slabs = 256
optimal_distance = {d1:e}
penumbra = "{penumbra}"
[[light]]
tilt_deg = [15.0, 10.0]
variance = [0.02, 0.015]
rotation_deg = 30.0
[[mesh]]
shape = "box"
size = [0.5, 3.4, 0.05]
translate = [-0.9, 0.0, 0.0]
material = "bar"
[[mesh]]
shape = "box"
size = [0.5, 3.4, 0.05]
translate = [0.7, 0.0, 1.2]
material = "bar"
[[mesh]]
shape = "box"
size = [6.0, 3.0, 0.1]
translate = [0.0, 1.5, 2.05]
material = "wall"
[[mesh]]
shape = "box"
size = [6.0, 3.0, 0.1]
rotate_deg = [-45.0, 0.0, 0.0]
translate = [0.0, -1.0, 3.05]
material = "wall"
[material.bar]
color = [0.1, 0.1, 0.1]
[material.wall]
color = [1.0, 1.0, 1.0]
"#
    );
    Scene::parse(&text, "fig18.toml", Path::new(".")).expect("scene")
}

/// The sweep's image and the shadow-ray reference's (`samples` light directions) for `scene`.
fn sweep_and_reference(scene: &Scene, samples: u32) -> (Vec<f32>, Vec<f32>) {
    let g = convshadow_io::build_geometry(scene).expect("geometry");
    let ldi = Ldi::build(&g.raster, u64::MAX).expect("ldi");
    let plan = convshadow_io::build_plan(scene, &g).expect("plan");
    let out = sweep_with(
        &plan,
        &g.raster,
        &ldi,
        &SweepOptions::default(),
        &CpuOptions::default(),
    )
    .expect("sweep");
    let reference = Reference::new(scene, &g, &plan, 0.0).render(
        &ldi,
        &ReferenceOptions {
            samples,
            ..ReferenceOptions::default()
        },
    );
    (out.image, reference)
}

/// RMSE of two images.
fn image_rmse(a: &[f32], b: &[f32]) -> f64 {
    rmse(a.iter().zip(b).map(|(x, y)| (f64::from(*x), f64::from(*y))))
}

#[test]
fn two_occluders_over_an_angled_wall_beat_the_iterated_mode_at_its_best_d1() {
    const SAMPLES: u32 = 64;
    let (image, reference) = sweep_and_reference(&two_occluders(Penumbra::Distance, 1.0), SAMPLES);
    let distance = image_rmse(&image, &reference);
    let mut best = (f64::INFINITY, 0.0);
    for d1 in [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0] {
        let (image, reference) =
            sweep_and_reference(&two_occluders(Penumbra::Iterated, d1), SAMPLES);
        let e = image_rmse(&image, &reference);
        eprintln!("fig. 18: iterated, d1 = {d1}: RMSE {e:.5}");
        if e < best.0 {
            best = (e, d1);
        }
    }
    eprintln!(
        "fig. 18: distance RMSE {distance:.5}; iterated at its best d1 = {}: {:.5}",
        best.1, best.0
    );
    assert!(
        distance < best.0,
        "distance {distance} vs iterated {best:?}"
    );
}

/// A cloud of fBm detail over a wall, one tilted light: shadows cast through a medium.
fn cloud(penumbra: Penumbra) -> Scene {
    let text = format!(
        r#"
[image]
width = 48
height = 48
[camera]
view_width = 3.0
[sweep]
slabs = 96
optimal_distance = 0.8
penumbra = "{penumbra}"
[[light]]
color = [1.0, 0.9, 0.8]
tilt_deg = [25.0, 10.0]
variance = [0.03, 0.02]
[[mesh]]
shape = "sphere"
size = [0.7, 4]
material = "cloud"
[[mesh]]
shape = "box"
size = [5.0, 5.0, 0.1]
translate = [0.0, 0.0, 1.2]
material = "wall"
[material.cloud]
detail = {{ kind = "fbm", frequency = 3.0, octaves = 4, lacunarity = 2.0, gain = 0.5 }}
gradient = [[0.0, 0.9, 0.9, 1.0, 0.0], [0.45, 0.9, 0.9, 1.0, 0.1], [1.0, 1.0, 1.0, 1.0, 0.8]]
transport = [0.6, 0.5, 0.3]
reference_length = 0.05
[material.wall]
color = [0.85, 0.85, 0.8]
opacity = 1.0
"#
    );
    Scene::parse(&text, "cloud.toml", Path::new(".")).expect("scene")
}

/// The default scene at 48² and 96 slabs.
fn small_default(penumbra: Penumbra) -> Scene {
    let mut s = Scene::default_scene();
    s.image.width = 48;
    s.image.height = 48;
    s.sweep.slabs = SlabSpec::Count(96);
    s.sweep.penumbra = penumbra;
    s
}

#[test]
fn the_default_scene_and_a_cloud_are_no_worse_than_the_iterated_mode() {
    const SAMPLES: u32 = 16;
    for (name, make) in [
        ("default scene", small_default as fn(Penumbra) -> Scene),
        ("cloud", cloud),
    ] {
        let distance = make(Penumbra::Distance);
        let (image, reference) = sweep_and_reference(&distance, SAMPLES);
        assert!(
            image.iter().all(|v| v.is_finite()),
            "{name}: a value is not finite"
        );
        // The same bits on both paths and any thread count.
        for (path, threads) in [(CpuPath::Scalar, 1), (CpuPath::Simd, 1), (CpuPath::Simd, 3)] {
            let request = RenderRequest {
                path,
                threads,
                ..RenderRequest::default()
            };
            let other = render(&distance, &request).expect("render");
            assert_eq!(
                other.image_hash,
                image_fingerprint(&image),
                "{name}: {path:?} on {threads} threads differs"
            );
        }
        let (iterated, _) = sweep_and_reference(&make(Penumbra::Iterated), 1);
        let (e_distance, e_iterated) = (
            image_rmse(&image, &reference),
            image_rmse(&iterated, &reference),
        );
        eprintln!(
            "{name}: RMSE against the shadow-ray reference (M = {SAMPLES}): distance {e_distance:.5}, \
             iterated {e_iterated:.5}"
        );
        assert!(
            e_distance <= e_iterated,
            "{name}: {e_distance} > {e_iterated}"
        );
    }
}
