//! Open meshes render as thin shells (docs/scene-format.md, "Open meshes"): a crossing of an
//! open mesh is one slab of its material at the crossing, with no inside. Checked on a single
//! square (two triangles, no volume: every one of its edges is a boundary edge) over a closed
//! receiver, opaque and translucent, against the closed form of its shadow written here from the
//! geometry and the light (a Gaussian direction per unit depth, `u ~ N(tan ω, σ²)` per camera
//! axis: a shadow ray from the receiver meets the square's plane, `D` nearer, at an offset D·u),
//! for the sweep and for the shadow-ray reference.

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::pipeline::{CpuPath, RenderRequest, render};
use convshadow::reference::edge::phi;
use convshadow::reference::{Reference, ReferenceOptions};

use crate::support;

const SIZE: usize = 64;
const VIEW: f64 = 3.0;
/// Half the square's side (world units).
const HALF: f64 = 0.5;
/// The square's distance in front of the receiver's front face (world z = 0).
const D: f64 = 1.0;
const TILT: f64 = 12.0;
const VAR: f64 = 0.02;

/// The square (an OBJ of two triangles written into `dir`) over a closed receiver box, in
/// material `square` of opacity `opacity`; the receiver is white and flat-shaded, so its image
/// is the light it receives, swept in `slabs` slabs. `closed`: a closed box 0.001 thick in the square's place instead.
fn square_scene(dir: &Path, opacity: f64, closed: bool, slabs: u32) -> Scene {
    let occluder = if closed {
        format!(
            "shape = \"box\"\nsize = [{s}, {s}, 0.001]\ntranslate = [0.0, 0.0, {z}]",
            s = 2.0 * HALF,
            z = -D + 0.0005
        )
    } else {
        format!(
            "shape = \"obj\"\npath = \"{}\"\ntranslate = [0.0, 0.0, {}]",
            dir.join("square.obj").display(),
            -D
        )
    };
    let obj = dir.join("square.obj");
    std::fs::write(
        &obj,
        format!(
            "v {n} {n} 0\nv {p} {n} 0\nv {p} {p} 0\nv {n} {p} 0\nf 1 2 3\nf 1 3 4\n",
            n = -HALF,
            p = HALF
        ),
    )
    .unwrap();
    let text = format!(
        r#"
[image]
width = {SIZE}
height = {SIZE}
[camera]
view_width = {VIEW}
[sweep]
slabs = {slabs}
[[light]]
tilt_deg = [{TILT}, 0.0]
variance = [{VAR}, {VAR}]
[[mesh]]
{occluder}
material = "square"
[[mesh]]
shape = "box"
size = [40.0, 40.0, 0.1]
translate = [0.0, 0.0, 0.05]
material = "white"
[material.square]
opacity = {opacity}
surface = "flat"
[material.white]
opacity = 1.0
surface = "flat"
"#,
    );
    support::scene(&text, dir)
}

/// The closed form: the light reaching receiver point (x, y) (camera coordinates) through a
/// square shell that keeps `1 − alpha` of what crosses it. The ray crosses the square iff
/// `|x + D·u| < HALF` and `|y + D·v| < HALF`, u and v independent Gaussians.
fn square_light(x: f64, y: f64, alpha: f64) -> f64 {
    let p = |c: f64, mu: f64| {
        let s = VAR.sqrt();
        phi(((HALF - c) / D - mu) / s) - phi(((-HALF - c) / D - mu) / s)
    };
    1.0 - alpha * p(x, TILT.to_radians().tan()) * p(y, 0.0)
}

/// Expected values at the receiver pixels outside the square's outline (a pixel's margin).
fn expected(alpha: f64) -> Vec<Option<f64>> {
    let px = VIEW / SIZE as f64;
    let mut e = Vec::with_capacity(SIZE * SIZE);
    for j in 0..SIZE {
        for i in 0..SIZE {
            let x = (i as f64 + 0.5 - 0.5 * SIZE as f64) * px;
            let y = (j as f64 + 0.5 - 0.5 * SIZE as f64) * px;
            let covered = x.abs() < HALF + px && y.abs() < HALF + px;
            e.push((!covered).then(|| square_light(x, y, alpha)));
        }
    }
    e
}

/// `scene` by the shadow-ray reference at `samples` directions per pixel.
fn reference_image(scene: &Scene, samples: u32) -> Vec<f32> {
    let g = convshadow_io::build_geometry(scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, 1 << 30).unwrap_or_else(|e| panic!("{e}"));
    let plan = convshadow_io::build_plan(scene, &g).unwrap_or_else(|e| panic!("{e}"));
    let options = ReferenceOptions {
        samples,
        ..ReferenceOptions::default()
    };
    Reference::new(scene, &g, &plan, 0.0).render(&ldi, &options)
}

/// RMSE and largest error of the red channel against `expected`, over the pixels it names.
fn errors(image: &[f32], expected: &[Option<f64>]) -> (f64, f64, usize) {
    let (mut sq, mut worst, mut n) = (0.0, 0.0f64, 0);
    for (c, e) in image.chunks(3).zip(expected) {
        if let Some(e) = e {
            let d = f64::from(c[0]) - e;
            sq += d * d;
            worst = worst.max(d.abs());
            n += 1;
        }
    }
    ((sq / n as f64).sqrt(), worst, n)
}

#[test]
fn an_open_square_is_a_shell_that_casts_the_closed_form_shadow() {
    let dir = support::temp_dir("open-square");
    // A shell is one reference length of its material: opacity 0.5 takes out half of the
    // light crossing it, whatever the slab count (16, 64 and 256 slabs).
    for (opacity, alpha, slabs) in [
        (1.0, 1.0, 64),
        (0.5, 0.5, 64),
        (0.5, 0.5, 16),
        (0.5, 0.5, 256),
    ] {
        let scene = square_scene(&dir, opacity, false, slabs);
        let g = convshadow_io::build_geometry(&scene).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(g.shell_meshes(), vec![0], "the square is the one open mesh");
        let expected = expected(alpha);

        let r = render(&scene, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            r.mesh_warnings.iter().any(|w| w.contains("thin shell")),
            "{:?}",
            r.mesh_warnings
        );
        assert_eq!(r.ldi.odd_pixels, 0, "a shell is not a parity defect");
        let (rmse, worst, n) = errors(&r.image.data, &expected);
        eprintln!(
            "opacity {opacity}, {slabs} slabs, sweep: RMSE {rmse:.2e}, max {worst:.2e} over {n} px"
        );
        assert!(n > 3000, "{n} pixels compared");
        // The sweep's own error on this shadow, the same as a closed plate's (below): measured
        // 2.0e-2 (max 0.11), the half-shadow line about 0.8 px towards the light's mean, the
        // whole-pixel carry of a tilted light's mean (docs/accuracy.md §2b).
        assert!(
            rmse <= 3e-2 && worst <= 0.15,
            "sweep: RMSE {rmse:e}, max {worst:e}"
        );
        if opacity == 1.0 {
            // An opaque shell takes out the light where it is crossed, as the front face of a
            // closed plate in the same slab does: the same image, bit for bit.
            let plate = render(
                &square_scene(&dir, opacity, true, slabs),
                &RenderRequest::default(),
            )
            .unwrap_or_else(|e| panic!("{e}"));
            assert!(
                plate.mesh_warnings.is_empty(),
                "the plate is closed: {:?}",
                plate.mesh_warnings
            );
            assert_eq!(plate.image_hash, r.image_hash, "shell vs closed plate");
        }

        let image = reference_image(&scene, 1024);
        let (rmse, worst, _) = errors(&image, &expected);
        eprintln!(
            "opacity {opacity}, {slabs} slabs, reference (M = 1024): RMSE {rmse:.2e}, max {worst:.2e}"
        );
        assert!(rmse <= 2e-3, "reference: RMSE {rmse:e}, max {worst:e}");
    }
}

/// The light reaching receiver point (x, y) past the opaque square turned `turn` degrees about
/// the y axis (`rotate_deg = [0, turn, 0]`), whose point (s, r, 0) lies at (s·cos θ, r, s·sin θ)
/// in camera coordinates (z away from the eye), D nearer than the receiver. A shadow ray
/// (x + t·u, y + t·v, −t) meets its plane where t = D − s·sin θ, s = (x + D·u) / (cos θ +
/// u·sin θ); the square is crossed iff |s| < HALF and |y + t·v| < HALF. Integrated over u
/// numerically (the Gaussian's ±8σ in steps of σ/100), over v in closed form. (The shadow-ray
/// reference agrees: RMSE ≤ 2e-3 at M = 256, asserted below.)
fn turned_square_light(x: f64, y: f64, turn: f64) -> f64 {
    let (sin, cos) = turn.to_radians().sin_cos();
    let (mu, s) = (TILT.to_radians().tan(), VAR.sqrt());
    let steps = 1600;
    let mut blocked = 0.0;
    for k in 0..=steps {
        let z = -8.0 + 16.0 * k as f64 / steps as f64;
        let u = mu + s * z;
        let weight = if k == 0 || k == steps { 0.5 } else { 1.0 } * 16.0 / steps as f64;
        let density = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let along = (x + D * u) / (cos + u * sin);
        if along.abs() >= HALF {
            continue;
        }
        let t = D - along * sin;
        let across = phi(((HALF - y) / t) / s) - phi(((-HALF - y) / t) / s);
        blocked += weight * density * across;
    }
    1.0 - blocked
}

/// The receiver's light at every pixel centre outside the square turned by `turn`° (its outline
/// as seen, grown by `margin` across it and one pixel along it), from `turned_square_light`.
fn turned_square_expected(turn: f64, margin: f64) -> Vec<Option<f64>> {
    let px = VIEW / SIZE as f64;
    let cos = f64::to_radians(turn).cos();
    (0..SIZE * SIZE)
        .map(|p| {
            let x = ((p % SIZE) as f64 + 0.5 - 0.5 * SIZE as f64) * px;
            let y = ((p / SIZE) as f64 + 0.5 - 0.5 * SIZE as f64) * px;
            let covered = x.abs() < HALF * cos + margin && y.abs() < HALF + px;
            (!covered).then(|| turned_square_light(x, y, turn))
        })
        .collect()
}

#[test]
fn a_turned_opaque_shell_casts_its_whole_shadow() {
    // A shell is one slab thick in its column. Turned so that a gather reads columns the shell
    // crosses later (here +30° and +60°), it read light from in front of the shell into the
    // column behind it: measured before the barrier (surface_hold::barrier) 0.021 and 0.056
    // RMSE, the 60° square's shadow grey (the teapot's on its wall). Turned the other way
    // nothing leaks that way: −30° measured 0.0063 before, 0.0086 with the barrier (it also
    // darkens a little light that passed beside the shell), and −60° 0.059–0.062 before,
    // 0.061–0.067 with it — the shadow beyond the square's far edge is missing, the surface
    // hold's passed light leaving past that edge (docs/accuracy.md §2g), held here to its
    // measured value +25 %.
    let dir = support::temp_dir("turned-square");
    let px = VIEW / SIZE as f64;
    for (turn, slabs, bound) in [
        (30.0, 256, 0.013),
        (60.0, 256, 0.022),
        (60.0, 64, 0.030),
        (-30.0, 256, 0.011),
        (-60.0, 256, 0.077),
        (-60.0, 64, 0.083),
    ] {
        let mut scene = square_scene(&dir, 1.0, false, slabs);
        scene.meshes[0].rotate_deg = [0.0, turn, 0.0];
        let r = render(&scene, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
        let expected = turned_square_expected(turn, px);
        let (rmse, worst, n) = errors(&r.image.data, &expected);
        eprintln!("turned {turn}°, {slabs} slabs: RMSE {rmse:.2e}, max {worst:.2e} over {n} px");
        assert!(n > 3000, "{n} pixels compared");
        assert!(
            rmse <= bound,
            "turned {turn}°, {slabs} slabs: RMSE {rmse:e}"
        );
        if slabs == 256 {
            let (rmse, worst, _) = errors(&reference_image(&scene, 256), &expected);
            eprintln!("   reference (M = 256): RMSE {rmse:.2e}, max {worst:.2e}");
            assert!(rmse <= 3e-3, "reference: RMSE {rmse:e}");
        }
    }
}

#[test]
fn a_thin_plate_turned_towards_the_light_casts_its_whole_shadow_with_held_light_on_its_lit_side() {
    // A closed plate 0.001 thick in the square's place, turned like it: its entry's surface hold
    // passes the light on past its far face, and the held light stepped sideways into the
    // columns behind the plate (docs/accuracy.md §2g). With `sweep.held_lit_side` a gather reads
    // no light from a held pixel behind whose surface it lies (`surface_hold`, "Who reads the
    // held light"). Measured (RMSE against the closed form): 30° 0.0203 → 0.0097, 60° 0.0598 →
    // 0.0091; turned away (−30°, −60°) 0.0060 → 0.0069 and 0.0260 → 0.0237. Bounds: the
    // measured values + 25 %; turned towards the light the plates without it measure above
    // them (asserted: the test fails without the change).
    let dir = support::temp_dir("turned-plate");
    let px = VIEW / SIZE as f64;
    for (turn, bound) in [
        (30.0, 0.0122),
        (60.0, 0.0114),
        (-30.0, 0.0087),
        (-60.0, 0.030),
    ] {
        let rmse_of = |lit_side: bool| {
            let mut scene = square_scene(&dir, 1.0, true, 256);
            scene.meshes[0].rotate_deg = [0.0, turn, 0.0];
            scene.sweep.held_lit_side = lit_side;
            let r = render(&scene, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
            // The plate's thickness seen turned: one more pixel of margin.
            let expected = turned_square_expected(turn, 2.0 * px);
            let scalar = RenderRequest {
                path: CpuPath::Scalar,
                ..RenderRequest::default()
            };
            let s = render(&scene, &scalar).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                s.image.data == r.image.data,
                "turned {turn}°: scalar and SIMD bits differ"
            );
            errors(&r.image.data, &expected)
        };
        let (on, worst, n) = rmse_of(true);
        let (off, _, _) = rmse_of(false);
        eprintln!(
            "plate turned {turn}°: RMSE {on:.2e} (max {worst:.2e}, {n} px); without: {off:.2e}"
        );
        assert!(n > 3000, "{n} pixels compared");
        assert!(on <= bound, "plate turned {turn}°: RMSE {on:e} > {bound}");
        if turn > 0.0 {
            assert!(
                off > bound,
                "plate turned {turn}° without: RMSE {off:e} ≤ {bound}"
            );
        }
    }
}
