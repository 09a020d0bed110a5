//! Patterned lights (gobos): `[[light]] pattern = { path, size, center }` makes the image the
//! light's initial light buffer. A half-black pattern is the opaque edge of the analytic
//! references moved to the first slab plane: its shadow on a receiver must follow the light
//! (moved by d·tan ω) and have the iterated model's penumbra (paper eq. 8). Bad pattern files are
//! refused naming the key and the file.

mod support;

use std::path::Path;

use convshadow::common::image_io::save_gray_png;
use convshadow::common::plan::RenderPlan;
use convshadow::common::scene::Scene;
use convshadow::cpu::reference::edge::{self, EdgeSetup, phi, run_light};

/// The edge set-up with its occluder made transparent (it only keeps the depth range) and a
/// pattern, black left of the image centre and white right of it, one texel per pixel aligned
/// with the pixel grid, on the light.
fn patterned_edge(m: u32, tilt: f64, variance: f64, dir: &Path) -> (EdgeSetup, Scene) {
    let s = EdgeSetup::classic(m, tilt, variance, "ellipse2");
    let (w, h) = (s.width, 2u32);
    let texels: Vec<u8> = (0..h)
        .flat_map(|_| (0..w).map(move |x| if x < w / 2 { 0 } else { 255 }))
        .collect();
    save_gray_png(&dir.join("half.png"), w, h, texels).unwrap();
    let view = f64::from(s.width) * s.pixel_size;
    let text = s
        .toml()
        .replace(
            "[[light]]\n",
            &format!(
                "[[light]]\npattern = {{ path = \"half.png\", size = [{view:e}, 1.0], center = [0.0, 0.0] }}\n"
            ),
        )
        .replace(
            "[material.occluder]\n",
            "[material.occluder]\ntransport = [1.0, 1.0, 1.0]\n",
        );
    assert!(text.contains("pattern = "), "the light's table was found");
    (s, support::scene(&text, dir))
}

/// The receiver's light profile (light 0, channel 0) after the last slab, swept from the plan's
/// initial light.
fn profile(scene: &Scene) -> (RenderPlan, Vec<f64>) {
    let init = |plan: &RenderPlan| plan.initial_light.clone().expect("a patterned light");
    let (plan, out, _) = run_light(scene, Some(&init));
    let p = edge::edge_profile(&plan, &out);
    (plan, p)
}

#[test]
fn a_half_black_pattern_casts_the_edge_shadow_moved_by_d_tan_omega() {
    let dir = support::temp_dir("pattern-edge");
    let variance = 0.05f64;
    for tilt in [0.0f64, 30.0, 60.0] {
        for m in [4u32, 16, 48] {
            let (s, scene) = patterned_edge(m, tilt, variance, &dir);
            let (plan, p) = profile(&scene);
            // The pattern lies on the front of slab 0 and the receiver is crossed in slab m:
            // m + 1 convolutions, so the pattern travels d = (m + 1)·e.
            assert_eq!(plan.slabs, m + 1);
            let d = f64::from(m + 1) * s.slab_distance;
            let center = f64::from(s.width) / 2.0 - d * tilt.to_radians().tan() / s.pixel_size;
            let got = edge::half_crossing(&p, 64).expect("the profile crosses 0.5");
            // The iterated model's penumbra: std √(d·d1)·σ (paper eq. 8).
            let std = (d * s.optimal_distance).sqrt() * variance.sqrt() / s.pixel_size;
            let (mut se, mut n) = (0.0, 0);
            for (x, v) in p.iter().enumerate() {
                let u = x as f64 + 0.5 - center;
                if u.abs() <= 4.0 * std {
                    se += (v - phi(u / std)).powi(2);
                    n += 1;
                }
            }
            let rmse = (se / f64::from(n)).sqrt();
            eprintln!(
                "tilt {tilt}°, d = {d:.2}: isoline {got:.3} px (expected {center:.3}), penumbra \
                 std {std:.2} px, RMSE vs Φ {rmse:.4}"
            );
            assert!(
                (got - center).abs() <= 0.5,
                "tilt {tilt}, d {d}: isoline at {got}, expected {center}"
            );
            assert!(rmse < 0.02, "tilt {tilt}, d {d}: RMSE {rmse}");
        }
    }
}

#[test]
fn the_pattern_is_the_initial_light_buffer() {
    let dir = support::temp_dir("pattern-initial");
    let (s, scene) = patterned_edge(4, 0.0, 0.0, &dir);
    let g = convshadow::common::geometry::SceneGeometry::build(&scene).unwrap();
    let plan = RenderPlan::new(&scene, &g).unwrap();
    let init = plan.initial_light.as_ref().unwrap();
    let row_len = plan.light_row_len();
    let w = s.width as usize;
    // Every channel of every row: 0 left of the centre, 1 right of it (texel centres on pixel
    // centres, so bilinear sampling gives the texels themselves).
    for y in 0..plan.grid_height as usize {
        for c in 0..plan.channels as usize {
            let row = &init[y * row_len + c * w..][..w];
            assert!(
                row[..w / 2].iter().all(|&v| v == 0.0),
                "row {y} channel {c}"
            );
            assert!(
                row[w / 2..].iter().all(|&v| v == 1.0),
                "row {y} channel {c}"
            );
        }
    }
}

#[test]
fn bad_pattern_files_are_refused_naming_the_key_and_the_file() {
    let dir = support::temp_dir("pattern-bad");
    std::fs::write(dir.join("notes.png"), "not an image").unwrap();
    std::fs::create_dir_all(dir.join("folder.png")).unwrap();
    let scene = |path: &str| {
        format!(
            "[image]\nwidth = 16\nheight = 16\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 4\n\
             optimal_distance = 0.5\n[[light]]\npattern = {{ path = \"{path}\", size = [2.0, 2.0] }}\n\
             [[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n[material.m]\n"
        )
    };
    for (file, words) in [
        ("missing.png", "cannot read pattern"),
        ("notes.png", "not a readable image"),
        ("folder.png", "folder"),
    ] {
        std::fs::write(dir.join("s.toml"), scene(file)).unwrap();
        let (code, out, err) = support::run_cli(&["render", "s.toml", "-o", "o.png"], &dir);
        assert_eq!(code, 3, "{file}: {out}{err}");
        for w in ["s.toml", "light[0].pattern.path", file, words] {
            assert!(err.contains(w), "{file}: expected {w:?} in {err}");
        }
        assert!(!dir.join("o.png").exists(), "no output on error");
    }
    // Scene keys: size is required, lengths positive.
    std::fs::write(
        dir.join("s.toml"),
        scene("half.png").replace(", size = [2.0, 2.0]", ""),
    )
    .unwrap();
    let (code, _, err) = support::run_cli(&["render", "s.toml", "-o", "o.png"], &dir);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("light[0].pattern.size"), "{err}");
    std::fs::write(
        dir.join("s.toml"),
        scene("half.png").replace("[2.0, 2.0]", "[2.0, 0.0]"),
    )
    .unwrap();
    let (code, _, err) = support::run_cli(&["render", "s.toml", "-o", "o.png"], &dir);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("light[0].pattern.size[1]"), "{err}");
}

/// A half-black pattern (black for camera x < 0, texels on pixel centres) over an opaque white
/// receiver whose front is `d` = 1 world unit behind the first slab plane (set by an invisible,
/// opacity-0 box), lit by a hard light tilted 30°: 64 × 16 pixels of 0.05.
fn pattern_over_receiver(dir: &Path) -> Scene {
    let (w, h) = (64u32, 2u32);
    let texels: Vec<u8> = (0..h)
        .flat_map(|_| (0..w).map(move |x| if x < w / 2 { 0 } else { 255 }))
        .collect();
    save_gray_png(&dir.join("half.png"), w, h, texels).unwrap();
    support::scene(
        r#"
[image]
width = 64
height = 16
[camera]
view_width = 3.2
[sweep]
slabs = 40
optimal_distance = 1.0
[[light]]
tilt_deg = [30.0, 0.0]
pattern = { path = "half.png", size = [3.2, 1.0] }
[[mesh]]
shape = "box"
size = [8.0, 8.0, 0.1]
translate = [0.0, 0.0, 0.05]
material = "air"
[[mesh]]
shape = "box"
size = [8.0, 8.0, 0.2]
translate = [0.0, 0.0, 1.1]
material = "receiver"
[material.air]
opacity = 0.0
[material.receiver]
"#,
        dir,
    )
}

/// Where row 8 of an RGB image (red channel) first rises through 0.5.
fn image_isoline(data: &[f32], width: usize) -> f64 {
    let row: Vec<f64> = (0..width)
        .map(|x| f64::from(data[(8 * width + x) * 3]))
        .collect();
    edge::half_crossing(&row, 1).expect("the row crosses 0.5")
}

#[test]
fn sweep_paths_and_the_reference_project_the_pattern_alike() {
    use convshadow::pipeline::{CpuPath, RenderRequest, render};
    let dir = support::temp_dir("pattern-receiver");
    let scene = pattern_over_receiver(&dir);
    // The edge at the image centre (32 px) moves by d·tan ω / px = tan 30° / 0.05 = 11.547 px.
    let expected = 32.0 - 30f64.to_radians().tan() / 0.05;
    let run = |path| {
        render(
            &scene,
            &RenderRequest {
                path,
                ..RenderRequest::default()
            },
        )
        .unwrap()
    };
    let simd = run(CpuPath::Simd);
    let scalar = run(CpuPath::Scalar);
    assert_eq!(simd.image_hash, scalar.image_hash, "scalar and SIMD bits");
    let sweep_iso = image_isoline(&simd.image.data, 64);
    let g = convshadow::common::geometry::SceneGeometry::build(&scene).unwrap();
    let ldi =
        <convshadow::common::ldi::Ldi as convshadow::cpu::ldi::BuildLdi>::build(&g.raster, 1 << 30)
            .unwrap();
    let plan = RenderPlan::new(&scene, &g).unwrap();
    let reference = convshadow::cpu::reference::Reference::new(&scene, &g, &plan, 0.0).render(
        &ldi,
        &convshadow::cpu::reference::ReferenceOptions::default(),
    );
    let ref_iso = image_isoline(&reference, 64);
    eprintln!(
        "isoline: sweep {sweep_iso:.3} px, reference {ref_iso:.3} px, expected {expected:.3}"
    );
    assert!((sweep_iso - expected).abs() <= 0.5, "sweep {sweep_iso}");
    assert!((ref_iso - expected).abs() <= 0.1, "reference {ref_iso}");
}
