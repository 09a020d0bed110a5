//! Patterned lights (gobos): `[[light]] pattern = { path, size, center }` makes the image the
//! light's initial light buffer. A half-black pattern is the opaque edge of the analytic
//! references moved to the first slab plane: its shadow on a receiver must follow the light
//! (moved by d·tan ω) and have the iterated model's penumbra (paper eq. 8); a checkerboard's
//! contrast must fall as the Gaussian transfer function of that model predicts. Bad pattern files
//! are refused naming the key and the file.

use crate::support;

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::common::plan::RenderPlan;
use convshadow::io::image::save_gray_png;
use convshadow::reference::edge::{self, EdgeSetup, phi, run_light};

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
    let g = convshadow_io::build_geometry(&scene).unwrap();
    let plan = convshadow_io::build_plan(&scene, &g).unwrap();
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
# The isoline of the projected pattern is measured at 0.5 of the unshaded light: no Lambert
# cosine (cos 30° would move the 0.5 crossing into the penumbra).
surface = "flat"
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
    let g = convshadow_io::build_geometry(&scene).unwrap();
    let ldi = <convshadow::common::contract::ldi::Ldi as convshadow::cpu::ldi::BuildLdi>::build(
        &g.raster,
        1 << 30,
    )
    .unwrap();
    let plan = convshadow_io::build_plan(&scene, &g).unwrap();
    let reference = convshadow::reference::Reference::new(&scene, &g, &plan, 0.0)
        .render(&ldi, &convshadow::reference::ReferenceOptions::default());
    let ref_iso = image_isoline(&reference, 64);
    eprintln!(
        "isoline: sweep {sweep_iso:.3} px, reference {ref_iso:.3} px, expected {expected:.3}"
    );
    assert!((sweep_iso - expected).abs() <= 0.5, "sweep {sweep_iso}");
    assert!((ref_iso - expected).abs() <= 0.1, "reference {ref_iso}");
}

/// The edge set-up (transparent occluder, `m + 1` slabs, 512 × 160 px of 0.01, d1 = 0.16,
/// e = 0.01, no guard band) with a checkerboard of `period`-pixel period (squares of period/2
/// texels, one texel per pixel, aligned with the grid) on the light.
fn patterned_checkerboard(
    m: u32,
    tilt: f64,
    variance: f64,
    period: u32,
    dir: &Path,
) -> (EdgeSetup, Scene) {
    let mut s = EdgeSetup::classic(m, tilt, variance, "ellipse2");
    s.height = 160;
    let (w, h) = (s.width, s.height);
    let half = period / 2;
    let texels: Vec<u8> = (0..h)
        .flat_map(|y| {
            (0..w).map(move |x| {
                if (x / half + y / half).is_multiple_of(2) {
                    0
                } else {
                    255
                }
            })
        })
        .collect();
    save_gray_png(&dir.join("checker.png"), w, h, texels).unwrap();
    let (vw, vh) = (f64::from(w) * s.pixel_size, f64::from(h) * s.pixel_size);
    let text = s
        .toml()
        .replace(
            "[[light]]\n",
            &format!(
                "[[light]]\npattern = {{ path = \"checker.png\", size = [{vw:e}, {vh:e}] }}\n"
            ),
        )
        .replace(
            "[material.occluder]\n",
            "[material.occluder]\ntransport = [1.0, 1.0, 1.0]\n",
        );
    (s, support::scene(&text, dir))
}

/// The amplitude of the checkerboard's fundamental, the (1, 1) harmonic cos(2πx/P)·cos(2πy/P)
/// at any phase, in the light buffer (light 0, channel 0) over the grid window `xs × ys` (whole
/// periods, so the mean and every other harmonic of the checkerboard project to 0): the norm of
/// the projections on the four products of cos and sin, each normalised by its squared norm.
fn fundamental(
    plan: &RenderPlan,
    light: &[f32],
    xs: std::ops::Range<usize>,
    ys: std::ops::Range<usize>,
    period: f64,
) -> f64 {
    let row_len = plan.light_row_len();
    let k = 2.0 * std::f64::consts::PI / period;
    let mut p = [0.0f64; 4];
    let mut n = 0.0;
    for y in ys {
        let (cy, sy) = ((k * (y as f64 + 0.5)).cos(), (k * (y as f64 + 0.5)).sin());
        for x in xs.clone() {
            let (cx, sx) = ((k * (x as f64 + 0.5)).cos(), (k * (x as f64 + 0.5)).sin());
            let v = f64::from(light[y * row_len + x]);
            p[0] += v * cx * cy;
            p[1] += v * sx * cy;
            p[2] += v * cx * sy;
            p[3] += v * sx * sy;
            n += 1.0;
        }
    }
    // Each product has mean square 1/4 over whole periods: coefficient = 4·Σ/n.
    p.iter().map(|q| (4.0 * q / n).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn a_checkerboard_pattern_loses_contrast_as_the_gaussian_transfer_function_predicts() {
    // A period-P pattern blurred by a Gaussian of std s (px) keeps exp(−2π²s²/P²) of its
    // fundamental along each axis; the checkerboard's fundamental is the (1, 1) harmonic, blurred
    // along x and y, so it keeps exp(−2π²(sx² + sy²)/P²). After the light has travelled
    // d = n·e (n convolutions, see the edge test above), the iterated model's covariance is
    // d·d1·σ² per axis (docs/accuracy.md; common/src/kernel/moments.rs: n slabs of
    // Σκ = d1·e·σ²), in px² divided by px². The measured amplitude is compared as a ratio to
    // the same projection of the initial light buffer (the pattern as the sweep starts from it:
    // the sampled square wave's own fundamental), so the pattern's discretisation cancels out.
    let dir = support::temp_dir("pattern-checker");
    let (variance, period) = (0.05f64, 32u32);
    for tilt in [0.0f64, 30.0] {
        for m in [4u32, 16, 48] {
            let (s, scene) = patterned_checkerboard(m, tilt, variance, period, &dir);
            let init = |plan: &RenderPlan| plan.initial_light.clone().expect("a patterned light");
            let (plan, out, _) = run_light(&scene, Some(&init));
            assert_eq!(
                (plan.grid_width, plan.grid_height),
                (512, 160),
                "no guard band"
            );
            let n = plan.slabs;
            let d = f64::from(n) * s.slab_distance;
            let s2 = d * s.optimal_distance * variance / (s.pixel_size * s.pixel_size);
            let p = f64::from(period);
            let expected = (-2.0 * std::f64::consts::PI.powi(2) * (2.0 * s2) / (p * p)).exp();
            // 10 × 2 periods, at least 48 px (≥ 7 std at n = 49) from every edge of the grid,
            // where reads outside it see unoccluded light; the tilt moves the pattern by at most
            // d·tan 30° / px = 28 px, which the window leaves room for.
            let (xs, ys) = (96..416, 48..112);
            let a0 = fundamental(
                &plan,
                plan.initial_light.as_ref().unwrap(),
                xs.clone(),
                ys.clone(),
                p,
            );
            let a = fundamental(&plan, &out.light, xs, ys, p);
            let ratio = a / a0;
            eprintln!(
                "tilt {tilt}°, {n} slabs: blur std {:.2} px, fundamental {a:.4} of {a0:.4}: \
                 ratio {ratio:.4}, expected {expected:.4}",
                s2.sqrt()
            );
            // Tolerance 0.006 (absolute, on ratios from 0.86 down to 0.22; measured within
            // 0.0022, the sweep blurring a little more than the Gaussian): the iterated ellipse2
            // kernel is Gaussian only in its first two moments (its characteristic function at
            // this frequency differs from the Gaussian's by ~4e-5 per slab), and its per-pixel
            // random phases add noise that the 20 480-pixel projection averages down to ~1e-4.
            // A wrong model misses by far more: one axis instead of two by 0.07 at 5 slabs, d²
            // instead of d·d1 by 0.18 at 49.
            assert!(
                (ratio - expected).abs() <= 0.006,
                "tilt {tilt}, {n} slabs: ratio {ratio}, expected {expected}"
            );
        }
    }
}

/// A pattern on a light travelling towards the viewer (its turned-round pass starts from the
/// scene's far end, whose camera x is the scene camera's reversed): a 64 × 1 pattern, black left
/// of camera x = 0.25 and white right of it, a hard light straight at the camera, seen on a
/// translucent sheet that takes no light out. The sheet's profile is the pattern where `center`
/// puts it, in the scene camera's space: dark left of the line, lit right of it — an orthographic
/// camera (the line between columns 39 and 40) and a perspective eye (the line where its rays
/// meet the sheet at camera x 0.25), on the sweep and on the reference.
#[test]
fn a_pattern_on_a_light_towards_the_viewer_lands_where_its_center_says() {
    let dir = support::temp_dir("pattern-back");
    let texels: Vec<u8> = (0..64u32).map(|x| if x < 32 { 0 } else { 255 }).collect();
    save_gray_png(&dir.join("half.png"), 64, 1, texels).unwrap();
    let light_and_sheet = "[[light]]\ndirection = [0.0, 0.0, -1.0]\nvariance = [0.0, 0.0]\n\
        pattern = { path = \"half.png\", size = [1.0, 4.0], center = [0.25, 0.0] }\n\
        [[mesh]]\nshape = \"box\"\nsize = [4.0, 4.0, 0.05]\nmaterial = \"sheet\"\n\
        [material.sheet]\nopacity = 0.9\ntransport = [1.0, 1.0, 1.0]\n";
    let ortho = format!(
        "[image]\nwidth = 64\nheight = 8\n[camera]\ndirection = [0.0, 0.0, 1.0]\n\
         view_width = 2.0\n[sweep]\nslabs = 8\n{light_and_sheet}"
    );
    // The eye 5 in front of the sheet: camera x 0.25 on it is 0.25·f/5 px right of the centre.
    let (fov, height) = (4.0f64, 8u32);
    let focal = 0.5 * f64::from(height) / (0.5 * fov.to_radians()).tan();
    let perspective = format!(
        "[image]\nwidth = 64\nheight = {height}\n[camera]\nprojection = \"perspective\"\n\
         eye = [0.0, 0.0, -5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = {fov}\n\
         [sweep]\nslabs = 8\n{light_and_sheet}"
    );
    let line_px = |ortho: bool| {
        if ortho {
            0.25 / (2.0 / 64.0) + 32.0
        } else {
            32.0 + 0.25 * focal / 5.0
        }
    };
    for (text, is_ortho) in [(ortho, true), (perspective, false)] {
        let scene = support::scene(&text, &dir);
        assert!(scene.lights[0].toward_viewer);
        let line = line_px(is_ortho);
        let sweep = convshadow::pipeline::render(&scene, &Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let reference =
            convshadow::pipeline::render_reference(&scene, 0, 4, u64::MAX / 4, false, &[], None)
                .unwrap_or_else(|e| panic!("{e}"));
        for (what, image) in [
            ("sweep", &sweep.image.data),
            ("reference", &reference.image.data),
        ] {
            let row = 4usize;
            let value = |i: usize| f64::from(image[3 * (row * 64 + i)]);
            let lit = value(60);
            assert!(
                lit > 0.01,
                "{what}, orthographic {is_ortho}: the sheet is lit ({lit})"
            );
            for i in 0..64usize {
                let centre = i as f64 + 0.5;
                let v = value(i) / lit;
                // Beyond the pattern's bilinear ramp (one texel, 1/64 world) and a pixel.
                if centre < line - 1.5 {
                    assert!(
                        v < 0.02,
                        "{what}, orthographic {is_ortho}: column {i} is {v}"
                    );
                } else if centre > line + 1.5 {
                    assert!(
                        v > 0.98,
                        "{what}, orthographic {is_ortho}: column {i} is {v}"
                    );
                }
            }
        }
    }
}
