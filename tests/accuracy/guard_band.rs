//! The automatic guard band (`sweep.guard_band = "auto"`, the default): occluders outside the
//! view cast the shadows they would cast if the frame were cut wider, and a scene whose meshes
//! all lie inside the view gets no band and the same bits as with the band off.
//!
//! The reference for "cut wider" is the same scene with a fixed band far larger than any shadow
//! reach: the image pixels keep their size and their random pattern (per-pixel hashes are keyed
//! by image coordinates), so the two images differ only where the automatic band is too narrow.
//! Each case also renders with the band off and requires a clear difference, so the scene does
//! test what it claims (its out-of-view occluder darkens the view).

use crate::support;

use std::path::Path;

use convshadow::common::model::scene::GuardBandSpec;
use convshadow::common::model::scene::{Scene, ShapeSpec};
use convshadow::common::prepare::guard::GuardBand;
use convshadow::pipeline::{RenderRequest, Rendered, render};

/// A band wider than any shadow reach in these scenes (the auto bands below are ≤ 140 px).
const WIDE: u32 = 320;

fn run(scene: &Scene, guard: GuardBandSpec) -> Rendered {
    let mut scene = scene.clone();
    scene.sweep.guard_band = guard;
    render(&scene, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn rmse(a: &Rendered, b: &Rendered) -> f64 {
    let (x, y) = (&a.image.data, &b.image.data);
    assert_eq!(x.len(), y.len());
    let sum: f64 = x
        .iter()
        .zip(y)
        .map(|(p, q)| (f64::from(*p) - f64::from(*q)).powi(2))
        .sum();
    (sum / x.len() as f64).sqrt()
}

/// Renders with `auto`, off and [`WIDE`]; checks auto ≈ wide and off ≠ wide; returns the band.
fn check_against_wide(scene: &Scene, what: &str) -> GuardBand {
    let auto = run(scene, GuardBandSpec::Auto);
    let off = run(scene, GuardBandSpec::Pixels(0));
    let wide = run(scene, GuardBandSpec::Pixels(WIDE));
    let band = auto.plan.guard;
    assert_eq!(wide.plan.guard, GuardBand::uniform(WIDE));
    assert!(
        band.sides().iter().all(|&s| s < WIDE / 2),
        "{what}: the wide band must be far larger than auto's {band}"
    );
    let (e_auto, e_off) = (rmse(&auto, &wide), rmse(&off, &wide));
    eprintln!("{what}: auto band {band}: RMSE against wide {e_auto:.2e}, band off {e_off:.2e}");
    assert!(e_auto <= 1e-4, "{what}: auto band {band}: RMSE {e_auto:e}");
    assert!(
        e_off > 1e-2,
        "{what}: the out-of-view occluder must matter (RMSE {e_off:e} without a band)"
    );
    band
}

/// The issue's half-plane: an opaque half-plane over a receiver 1.0 behind it, the light tilted
/// 30° in x with σ² = 0.01, a 2.0-wide view centred on the shadow edge. Shadows move by
/// −d·tan ω (docs/scene-format.md): towards image left by tan 30° ≈ 0.577 over the gap. The
/// camera looks along +z with +y up, so camera x is world −x: the half-plane covers world
/// x ≤ −0.577 (image right of camera x = 0.577) and reaches far beyond the right, top and bottom
/// image edges.
fn half_plane_scene(size: u32) -> Scene {
    let text = format!(
        r#"
[image]
width = {size}
height = {size}
[camera]
direction = [0.0, 0.0, 1.0]
view_width = 2.0
[sweep]
slabs = 48
optimal_distance = 1.0
[[light]]
tilt_deg = [30.0, 0.0]
variance = [0.01, 0.01]
[[mesh]]
shape = "box"          # the half-plane: world x from −6.57735 to −0.57735, y ±3
size = [6.0, 6.0, 0.02]
translate = [-3.57735, 0.0, 0.0]
material = "dark"
[[mesh]]
shape = "box"          # the receiver, 1.0 behind
size = [8.0, 8.0, 0.1]
translate = [0.0, 0.0, 1.0]
material = "white"
[material.dark]
color = [0.1, 0.1, 0.1]
[material.white]
color = [1.0, 1.0, 1.0]
"#
    );
    support::scene(&text, Path::new("."))
}

#[test]
fn half_plane_outside_the_view_casts_its_shadow_with_auto() {
    let scene = half_plane_scene(256);
    let band = check_against_wide(&scene, "half-plane");
    // Shadows move towards image left: the right band holds the mean shift (≈ 74 px at
    // 2/256 world units per pixel), the others only the spread.
    assert!(band.right > band.left, "{band}");
    assert!(band.right as f64 > 0.577 / (2.0 / 256.0), "{band}");
    assert_eq!(band.top, band.bottom, "{band}");
}

/// A sphere just outside one image edge (its nearest point 0.05 beyond it) over a receiver 1.0
/// behind, with the light tilted 40° towards the image, so its shadow falls inside.
fn sphere_scene(edge: &str) -> Scene {
    // Camera x = −world x, camera y = −world y (looking along +z, +y up). Shadows move by
    // −d·tan ω: along camera +x (image right) for a negative x tilt, along camera +y (image
    // down) for a negative y tilt.
    let (pos, tilt) = match edge {
        "left" => ([1.35, 0.0], [-40.0, 0.0]),
        "right" => ([-1.35, 0.0], [40.0, 0.0]),
        "top" => ([0.0, 1.35], [0.0, -40.0]),
        "bottom" => ([0.0, -1.35], [0.0, 40.0]),
        _ => unreachable!(),
    };
    let text = format!(
        r#"
[image]
width = 128
height = 128
[camera]
direction = [0.0, 0.0, 1.0]
view_width = 2.0
[sweep]
slabs = 40
optimal_distance = 1.0
[[light]]
tilt_deg = [{}, {}]
variance = [0.005, 0.005]
[[mesh]]
shape = "sphere"
size = [0.3, 3]
translate = [{}, {}, 0.0]
material = "dark"
[[mesh]]
shape = "box"          # the receiver: just inside the view, so only the sphere reaches out
size = [1.96, 1.96, 0.1]
translate = [0.0, 0.0, 1.0]
material = "white"
[material.dark]
color = [0.1, 0.1, 0.1]
[material.white]
color = [1.0, 1.0, 1.0]
"#,
        tilt[0], tilt[1], pos[0], pos[1]
    );
    support::scene(&text, Path::new("."))
}

#[test]
fn a_sphere_beyond_each_edge_casts_into_the_view_with_auto() {
    for edge in ["left", "right", "top", "bottom"] {
        let band = check_against_wide(&sphere_scene(edge), &format!("sphere beyond the {edge}"));
        // Only the sphere's side gets a band: the receiver lies just inside the view.
        let sides = ["left", "right", "top", "bottom"];
        for (s, px) in sides.iter().zip(band.sides()) {
            if *s == edge {
                assert!(px > 0, "{edge}: {band}");
            } else {
                assert_eq!(px, 0, "{edge}: {band}");
            }
        }
    }
}

#[test]
fn meshes_inside_the_view_get_no_band_and_the_same_bits() {
    // The default scene (detail materials, two lights) with its wall shrunk from 5 to 3.8 units,
    // inside the 4-unit view: every mesh lies inside.
    let mut scene = Scene::default_scene();
    scene.image.width = 96;
    scene.image.height = 96;
    let wall = scene.meshes.len() - 1;
    match &mut scene.meshes[wall].shape {
        ShapeSpec::Box { size } => *size = [3.8, 3.8, 0.2],
        other => panic!("the default scene's last mesh is its wall, got {other:?}"),
    }
    let auto = run(&scene, GuardBandSpec::Auto);
    let off = run(&scene, GuardBandSpec::Pixels(0));
    assert_eq!(auto.plan.guard, GuardBand::default());
    assert_eq!(auto.image_hash, off.image_hash);
    assert_eq!(auto.ldi_hash, off.ldi_hash);
    // The same scene with the view narrowed: the meshes reach out, and get a band.
    let mut narrow = scene.clone();
    narrow.camera.view_width *= 0.5;
    assert_ne!(
        run(&narrow, GuardBandSpec::Auto).plan.guard,
        GuardBand::default()
    );
}

#[test]
fn the_band_is_reported_and_set_from_the_command_line() {
    let dir = support::temp_dir("guard-cli");
    std::fs::write(
        dir.join("s.toml"),
        support::lone_box_scene(24, 8).replace("[sweep]", "[sweep]\nguard_band = \"auto\""),
    )
    .unwrap();
    let stats = |args: &[&str]| {
        let mut all = vec!["render", "s.toml", "-o", "o.exr", "--stats-json", "s.json"];
        all.extend_from_slice(args);
        let (code, out, err) = support::run_cli(&all, &dir);
        assert_eq!(code, 0, "{args:?}: {err}");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
        (out, json)
    };
    // The box (6 units in a 4-unit view) reaches beyond every edge: an automatic band.
    let (out, json) = stats(&[]);
    assert_eq!(json["guard_band"], "auto");
    let px = &json["guard_band_px"];
    let sides: Vec<u64> = ["left", "right", "top", "bottom"]
        .iter()
        .map(|k| px[k].as_u64().unwrap())
        .collect();
    assert!(sides.iter().all(|&s| s > 0), "{px}");
    assert_eq!(
        json["grid_width"].as_u64().unwrap(),
        24 + sides[0] + sides[1]
    );
    assert!(out.contains("guard band "), "{out}");
    // A fixed band from the command line, the same on every side.
    let (out, json) = stats(&["--guard-band", "7"]);
    assert_eq!(json["guard_band"], "7");
    for k in ["left", "right", "top", "bottom"] {
        assert_eq!(json["guard_band_px"][k], 7);
    }
    assert!(out.contains("guard band 7 px"), "{out}");
    // Bad values: a clear error naming the option or the key, no output.
    let (code, _, err) = support::run_cli(
        &["render", "s.toml", "-o", "bad.exr", "--guard-band", "wide"],
        &dir,
    );
    assert_ne!(code, 0);
    assert!(
        err.contains("--guard-band") && err.contains("auto"),
        "{err}"
    );
    assert!(!dir.join("bad.exr").exists());
    for bad in ["\"wide\"", "-1", "4097", "1.5"] {
        std::fs::write(
            dir.join("b.toml"),
            support::lone_box_scene(24, 8)
                .replace("[sweep]", &format!("[sweep]\nguard_band = {bad}")),
        )
        .unwrap();
        let (code, _, err) = support::run_cli(&["render", "b.toml", "-o", "bad.exr"], &dir);
        assert_ne!(code, 0, "{bad}");
        assert!(err.contains("sweep.guard_band"), "{bad}: {err}");
        assert!(!dir.join("bad.exr").exists());
    }
}
