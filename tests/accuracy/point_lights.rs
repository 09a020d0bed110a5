//! Point and spot lights (issue 41) in the shadow-ray reference, against visibilities integrated
//! in `convshadow_reference::point_edge`: the light of a point light of radius r reaching a point X past an opaque thin half-plane
//! is `V(X) / |X − P|²`, V the probability that the segment from X to a point `P + δ` of the
//! light's Gaussian (`δ ~ N(0, r²·I)`) misses the half-plane. Across the edge only δ's two
//! components in the plane of the edge's normal and the depth matter; for a given depth offset
//! the segment is blocked iff δ's component across the edge passes a threshold, so
//! `V = ∫ Φ(threshold(δ_z)/r) N(δ_z; 0, r²) dδ_z`, integrated by Gauss–Legendre over ±8 r. A
//! spot's cone edge is placed by its angle, `tan(cone)` times the distance; a hard spot's cone,
//! falloff and gobo are checked on the sweep too (`point_sweep.rs` has its shadows).

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::render_reference;
use convshadow::reference::Reference;
use convshadow::reference::point_edge::{H, visibility};
use glam::DVec3;

/// A scene with the opaque half-plane x ≥ 0 around z = 0 and `light` (TOML lines), seen by
/// `camera` (TOML lines).
fn half_plane_scene(camera: &str, light: &str) -> Scene {
    let text = format!(
        r#"
[image]
width = 64
height = 8
[camera]
{camera}
[sweep]
slabs = 8
[[light]]
{light}
[[mesh]]
shape = "box"
size = [3.0, 8.0, {t}]
translate = [1.5, 0.0, 0.0]
material = "plate"
[material.plate]
color = [1.0, 1.0, 1.0]
"#,
        t = 2.0 * H
    );
    Scene::parse(&text, "point_lights", Path::new(".")).unwrap()
}

/// The reference's light (channel 0) at each world point, `k²` samples, and the expected
/// `V / |X − P|²`, both divided by the unshadowed `1/|X − P|²`.
fn light_profile(scene: &Scene, points: &[DVec3], k: u32) -> (Vec<f64>, Vec<f64>) {
    let geometry = convshadow::io::build_geometry(scene).unwrap();
    let plan = convshadow::io::build_plan(scene, &geometry).unwrap();
    let reference = Reference::new(scene, &geometry, &plan, 0.0);
    let light = scene.lights[0].point.unwrap();
    let p = DVec3::from(light.position);
    let (mut got, mut want) = (Vec::new(), Vec::new());
    for (i, x) in points.iter().enumerate() {
        let g = geometry.camera.to_grid(*x);
        let at = [g.x, g.y, g.z - geometry.z_origin];
        let d2 = (*x - p).length_squared();
        got.push(reference.light_at(0, at, k, 0x5eed, i as u32)[0] * d2);
        want.push(visibility(*x, p, light.radius));
    }
    (got, want)
}

fn rmse(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

#[test]
fn a_point_lights_penumbra_matches_the_integrated_visibility_for_any_camera() {
    // The light 2 before the plate, off its edge's line; the receiver points 1 behind the plate
    // across the shadow line (x = −0.1 for the centre) and its penumbra (σ ≈ r/2 = 0.05).
    let points: Vec<DVec3> = (0..81)
        .map(|i| DVec3::new(-0.5 + 0.01 * f64::from(i), 0.05, 1.0))
        .collect();
    let cameras = [
        (
            "along +z, orthographic",
            "direction = [0.0, 0.0, 1.0]\nview_width = 2.0",
        ),
        (
            "45° off, orthographic",
            "direction = [0.7071067811865476, 0.0, 0.7071067811865476]\nview_width = 3.0",
        ),
        (
            "perspective, fov 60°",
            "projection = \"perspective\"\neye = [0.3, 0.2, -3.0]\nlook_at = [0.0, 0.0, 0.5]\nfov_deg = 60.0",
        ),
    ];
    for radius in [0.1, 0.03] {
        let light = format!("kind = \"point\"\nposition = [0.2, 0.1, -2.0]\nradius = {radius}");
        for (name, camera) in cameras {
            let scene = half_plane_scene(camera, &light);
            let (got, want) = light_profile(&scene, &points, 32);
            let e = rmse(&got, &want);
            let worst = got
                .iter()
                .zip(&want)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            eprintln!("point light r = {radius}, camera {name}: RMSE {e:.2e}, worst {worst:.2e}");
            // The profile does cross the shadow: lit at one end, dark at the other.
            assert!(want[0] > 1.0 - 1e-6 && want[80] < 1e-6, "{want:?}");
            assert!(
                e <= 5e-3,
                "r = {radius}, {name}: RMSE {e:e}\n{got:?}\n{want:?}"
            );
            if radius == 0.1 {
                // Monte Carlo error, not a bias: it falls with 9× the samples.
                let (finer, _) = light_profile(&scene, &points, 96);
                let e_finer = rmse(&finer, &want);
                eprintln!("  with 96² samples: RMSE {e_finer:.2e}");
                assert!(e_finer < 0.6 * e, "{name}: {e_finer:e} against {e:e}");
            }
        }
    }
}

#[test]
fn a_hard_point_lights_shadow_line_is_where_the_edge_projects() {
    // r = 0: the light is all or nothing; the line from the light through the plate's edge
    // corner (x = 0, z = −H) meets z = 1 at x = P_x + (0 − P_x)·(1 − P_z)/(−H − P_z).
    let scene = half_plane_scene(
        "direction = [0.0, 0.0, 1.0]\nview_width = 2.0",
        "kind = \"point\"\nposition = [0.2, 0.1, -2.0]",
    );
    let line = 0.2 - 0.2 * 3.0 / (2.0 - H);
    let points: Vec<DVec3> = [-0.003, 0.003]
        .iter()
        .map(|dx| DVec3::new(line + dx, 0.0, 1.0))
        .collect();
    let (got, _) = light_profile(&scene, &points, 4);
    assert!((got[0] - 1.0).abs() < 1e-9 && got[1] < 1e-12, "{got:?}");
}

/// A white wall (a Lambert surface, its front face at z = 1) filling a 128 × 4 view 4 wide,
/// under a spot 3 before it at (0, 0, −2) pointing along +z whose other keys are `spot`.
fn spot_wall_scene(spot: &str) -> String {
    format!(
        r#"
[image]
width = 128
height = 4
background = [0.0, 0.0, 0.0]
[camera]
direction = [0.0, 0.0, 1.0]
view_width = 4.0
[sweep]
slabs = 8
[[light]]
kind = "spot"
position = [0.0, 0.0, -2.0]
direction = [0.0, 0.0, 1.0]
{spot}
[[mesh]]
shape = "box"
size = [8.0, 8.0, 0.02]
translate = [0.0, 0.0, 1.01]
material = "wall"
[material.wall]
color = [1.0, 1.0, 1.0]
"#
    )
}

#[test]
fn a_spot_lights_cone_edge_lands_where_its_angle_projects() {
    // A spot 2 before a wall (its front face at z = 1), pointing along +z: lit within
    // tan(cone)·3 of the axis, at 1/d² there; nothing beyond. The wall is white, a Lambert
    // surface (the default), the background black, so a pixel is the light reaching its
    // centre times the cosine of the direction to the light.
    for (cone, falloff) in [(10.0f64, 0.0f64), (12.0, 6.0)] {
        let text = spot_wall_scene(&format!("cone_deg = {cone}\nfalloff_deg = {falloff}"));
        let scene = Scene::parse(&text, "spot", Path::new(".")).unwrap();
        for r in reference_and_sweep(&scene) {
            let px = 4.0 / 128.0;
            // Pixel i's centre is at world |x| = |i + 0.5 − 64|·px (the row is symmetric).
            let row = 1usize;
            let mut lit_edge: Option<f64> = None;
            for i in 64..128usize {
                let x = (i as f64 + 0.5 - 64.0) * px;
                let v = f64::from(r.image.data[3 * (row * 128 + i)]);
                let y = (row as f64 + 0.5 - 2.0) * px;
                let d2 = x * x + y * y + 9.0;
                // The falloff is a smoothstep in the cosine of the angle from the axis, from
                // cos(cone + falloff) (0) to cos(cone) (1), as pbrt-v4's spot.
                let cos = 3.0 / d2.sqrt();
                let (inner, outer) = (cone.to_radians().cos(), (cone + falloff).to_radians().cos());
                let want = if cos >= inner {
                    1.0
                } else if cos <= outer {
                    0.0
                } else {
                    let s = (cos - outer) / (inner - outer);
                    s * s * (3.0 - 2.0 * s)
                };
                // The wall is a Lambert surface facing the light's axis: cos = 3/d, per point.
                let lit = v * d2 / (3.0 / d2.sqrt());
                assert!(
                    (lit - want).abs() < 1e-5,
                    "cone {cone}: pixel {i}: {lit} vs {want}"
                );
                if v > 0.0 {
                    lit_edge = Some(x);
                }
            }
            // The last lit pixel centre lies within half a pixel before the projected edge.
            let edge = 3.0 * (cone + falloff).to_radians().tan();
            let last = lit_edge.unwrap();
            assert!(
                last <= edge && edge - last <= px,
                "cone {cone}: last lit {last}, edge {edge}"
            );
        }
    }
}

#[test]
fn a_point_light_inside_a_closed_mesh_is_refused_and_the_sweep_names_the_backend() {
    let scene = half_plane_scene(
        "direction = [0.0, 0.0, 1.0]\nview_width = 2.0",
        "kind = \"point\"\nposition = [1.0, 0.0, 0.0]",
    );
    let e = render_reference(&scene, 1, 4, 1 << 30, false, &[], None)
        .err()
        .expect("refused");
    let msg = e.to_string();
    assert!(
        msg.contains("light[0].position") && msg.contains("mesh[0]"),
        "{msg}"
    );
    let scene = half_plane_scene(
        "direction = [0.0, 0.0, 1.0]\nview_width = 2.0",
        "kind = \"point\"\nposition = [1.0, 0.0, -1.0]",
    );
    // The same light outside the mesh renders with the reference, and with the sweep, hard and
    // soft; a soft one with the iterated penumbra only with the reference, and the sweep says so.
    render_reference(&scene, 1, 4, 1 << 30, false, &[], None).unwrap();
    convshadow::pipeline::render(&scene, &Default::default()).unwrap();
    let mut soft = scene.clone();
    soft.lights[0].point.as_mut().unwrap().radius = 0.05;
    convshadow::pipeline::render(&soft, &Default::default()).unwrap();
    soft.sweep.penumbra = convshadow::common::model::scene::Penumbra::Iterated;
    soft.sweep.optimal_distance = Some(0.5);
    let e = convshadow::pipeline::render(&soft, &Default::default())
        .err()
        .expect("refused");
    assert!(
        e.to_string().contains("sweep.penumbra") && e.to_string().contains("--backend reference"),
        "{e}"
    );
}

#[test]
fn a_spot_lights_gobo_lands_where_it_projects_through_the_cone() {
    // A 2 × 1 gobo, black then white along the spot's right axis (world −x, as the camera's),
    // 0.4 wide on the plane at unit distance, centred 0.1 right of the axis: on that plane it is
    // black up to a = 0 (the black texel's centre, clamped beyond), rises linearly to the white
    // texel's centre at a = 0.2 and stays white beyond; on the wall 3 from the spot, at 3·a.
    let dir = crate::support::temp_dir("spot_gobo");
    convshadow::io::image::save_gray_png(&dir.join("gobo.png"), 2, 1, vec![0, 255]).unwrap();
    let text = spot_wall_scene(
        "up = [0.0, 1.0, 0.0]\ncone_deg = 60.0\n\
         pattern = { path = \"gobo.png\", size = [0.4, 0.4], center = [0.1, 0.0] }",
    );
    let scene = Scene::parse(&text, "gobo", &dir).unwrap();
    for r in reference_and_sweep(&scene) {
        let px = 4.0 / 128.0;
        let row = 1usize;
        let y = (row as f64 + 0.5 - 2.0) * px;
        let mut half: Option<f64> = None;
        let mut before = (f64::NAN, f64::NAN);
        for i in 0..128usize {
            // The image's right is world −x, as the spot's right: `a` is the image x over 3.
            let x = (i as f64 + 0.5 - 64.0) * px;
            let d2 = x * x + y * y + 9.0;
            let lit = f64::from(r.image.data[3 * (row * 128 + i)]) * d2 / (3.0 / d2.sqrt());
            let a = x / 3.0;
            let want = (a / 0.2).clamp(0.0, 1.0);
            assert!((lit - want).abs() < 1e-4, "pixel {i}: {lit} vs {want}");
            if before.1 < 0.5 && lit >= 0.5 {
                // The half-way crossing, linearly between the two pixel centres.
                half = Some(before.0 + (0.5 - before.1) / (lit - before.1) * (x - before.0));
            }
            before = (x, lit);
        }
        // The gobo's half-way line projects to 3·0.1 = 0.3 from the axis: within half a pixel.
        let half = half.expect("a crossing");
        assert!(
            (half - 0.3).abs() <= 0.5 * px,
            "crossing at {half}, projected 0.3"
        );
    }
}

/// `scene` rendered by the shadow-ray reference and by the sweep (a hard light: both render it).
fn reference_and_sweep(scene: &Scene) -> [convshadow::pipeline::Rendered; 2] {
    [
        render_reference(scene, 1, 4, 1 << 30, false, &[], None).unwrap(),
        convshadow::pipeline::render(scene, &Default::default()).unwrap(),
    ]
}
