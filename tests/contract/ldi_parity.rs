//! The LDI and its parity test. Closed meshes must give an even fragment count at every pixel,
//! including the hard cases (vertices and edges exactly on pixel centres, shared edges, sliver and
//! sub-pixel triangles, coplanar touching meshes); the inside test must agree with the analytic
//! shapes away from a derived band around their surfaces; the build must not depend
//! on the thread count.

use crate::support;

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::common::prepare::geometry::SceneGeometry;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::cpu::parity::inside;
use convshadow::io::obj::load_obj;
use glam::DVec3;
use proptest::prelude::*;

const BUDGET: u64 = 8 << 30;

fn build(scene: &Scene) -> (SceneGeometry, Ldi) {
    let g = convshadow_io::build_geometry(scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, BUDGET).unwrap();
    (g, ldi)
}

/// A scene with one procedural mesh and a camera.
fn shape_scene(
    shape: &str,
    size: &str,
    transform: (f64, [f64; 3], [f64; 3]),
    camera: (&str, f64, [f64; 3]),
    width: u32,
) -> Scene {
    let (scale, rot, tr) = transform;
    let (direction, view_width, center) = camera;
    support::scene(
        &format!(
            r#"
[image]
width = {width}
height = {width}
[camera]
direction = {direction}
center = [{}, {}, {}]
view_width = {view_width:e}
[sweep]
slabs = 32
optimal_distance = 0.5
[[mesh]]
shape = "{shape}"
size = {size}
scale = {scale:e}
rotate_deg = [{}, {}, {}]
translate = [{:e}, {:e}, {:e}]
material = "m"
[material.m]
"#,
            center[0], center[1], center[2], rot[0], rot[1], rot[2], tr[0], tr[1], tr[2]
        ),
        Path::new("."),
    )
}

fn assert_even(scene: &Scene, what: &str) -> Ldi {
    let (g, ldi) = build(scene);
    let stats = ldi.stats();
    assert_eq!(g.defect_edges(), 0, "{what}: mesh not closed");
    assert_eq!(
        stats.odd_pixels, 0,
        "{what}: {} odd pixels",
        stats.odd_pixels
    );
    assert!(stats.fragments > 0, "{what}: nothing rasterized");
    assert_eq!(
        ldi.parity_meshes,
        u32::MAX,
        "{what}: every closed mesh is in the parity test"
    );
    ldi
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    /// Procedural closed shapes under random transforms and cameras: even counts everywhere.
    #[test]
    fn procedural_shapes_are_even_under_random_transforms(
        shape in 0usize..3,
        scale in 0.2f64..2.0,
        rot in prop::array::uniform3(-180.0f64..180.0),
        tr in prop::array::uniform3(-1.0f64..1.0),
        dir in prop::array::uniform3(-1.0f64..1.0),
        view in 1.5f64..6.0,
        width in 16u32..80,
    ) {
        prop_assume!(dir.iter().map(|d| d * d).sum::<f64>() > 0.01);
        prop_assume!((dir[0] * dir[0] + dir[2] * dir[2]) > 1e-3 * (dir[1] * dir[1]));
        let (name, size) = [("box", "[1.0, 0.7, 0.4]"), ("sphere", "[0.8, 3]"), ("torus", "[0.8, 0.3, 24]")][shape];
        let dir = format!("[{}, {}, {}]", dir[0], dir[1], dir[2]);
        let s = shape_scene(name, size, (scale, rot, tr), (&dir, view * scale, tr), width);
        assert_even(&s, name);
    }
}

#[test]
fn vertices_and_edges_exactly_on_pixel_centres() {
    // View width 16 over 16 px: pixel size 1, pixel centres at half-integers. A box with
    // half-integer corners has its vertices and edges on pixel centres, axis-aligned...
    let axis = shape_scene(
        "box",
        "[6.0, 4.0, 2.0]",
        (1.0, [0.0; 3], [0.5, 0.5, 0.0]),
        ("[0.0, 0.0, 1.0]", 16.0, [0.0; 3]),
        16,
    );
    let ldi = assert_even(&axis, "axis-aligned box on pixel centres");
    // ...and every centre inside or on the box's silhouette is covered by exactly one front and
    // one back face: columns -2.5..=3.5 → pixels whose centres are in [x0, x1] with top-left ownership.
    let inside_pixels = (0..16 * 16)
        .filter(|&p| ldi.offsets[p + 1] - ldi.offsets[p] == 2)
        .count();
    // 6 px wide x 4 px tall: centres on the left/top edges count, right/bottom ones do not.
    assert_eq!(inside_pixels, 6 * 4);
    // Rotated by 45° about the view axis: diagonal edges through pixel centres.
    let diag = shape_scene(
        "box",
        "[4.242640687119285, 4.242640687119285, 2.0]",
        (1.0, [0.0, 0.0, 45.0], [0.5, 0.5, 0.0]),
        ("[0.0, 0.0, 1.0]", 16.0, [0.0; 3]),
        16,
    );
    assert_even(&diag, "diagonal box edges");
    // A sphere whose vertices are snapped onto pixel centres by its size and a coarse grid.
    let sphere = shape_scene(
        "sphere",
        "[4.0, 1]",
        (1.0, [0.0; 3], [0.5, 0.5, 0.0]),
        ("[0.0, 0.0, 1.0]", 16.0, [0.0; 3]),
        16,
    );
    assert_even(&sphere, "icosahedron vertex on pixel centres");
}

#[test]
fn slivers_sub_pixel_triangles_and_extreme_scales() {
    // Sub-pixel triangles: a finely tessellated sphere a few pixels across.
    let tiny = shape_scene(
        "sphere",
        "[1.0, 5]",
        (1.0, [10.0, 20.0, 30.0], [0.0; 3]),
        ("[0.0, 0.0, 1.0]", 12.0, [0.0; 3]),
        32,
    );
    assert_even(&tiny, "sub-pixel triangles");
    // Slivers: a torus with many segments seen edge-on.
    let sliver = shape_scene(
        "torus",
        "[1.0, 0.05, 512]",
        (1.0, [89.9, 0.0, 0.0], [0.0; 3]),
        ("[0.0, 0.0, 1.0]", 3.0, [0.0; 3]),
        64,
    );
    assert_even(&sliver, "slivers");
    for (scale, view) in [(1e-6, 3e-6), (1e6, 3e6)] {
        let s = shape_scene(
            "torus",
            "[0.8, 0.3, 32]",
            (
                scale,
                [30.0, 40.0, 50.0],
                [0.1 * scale, 0.2 * scale, 0.3 * scale],
            ),
            (
                "[0.2, 0.3, 1.0]",
                view,
                [0.1 * scale, 0.2 * scale, 0.3 * scale],
            ),
            48,
        );
        assert_even(&s, &format!("scale {scale}"));
    }
    // Coordinates far from the origin at ordinary size.
    let far = shape_scene(
        "sphere",
        "[1.0, 3]",
        (1.0, [0.0; 3], [1e6, -1e6, 1e6]),
        ("[0.0, 0.0, 1.0]", 3.0, [1e6, -1e6, 1e6]),
        48,
    );
    assert_even(&far, "far from the origin");
}

#[test]
fn meshes_partly_outside_the_view_stay_even() {
    for tr in [[1.2, 0.0, 0.0], [0.0, -1.3, 0.0], [1.1, 1.1, 0.0]] {
        let s = shape_scene(
            "torus",
            "[0.8, 0.3, 24]",
            (1.0, [40.0, 10.0, 0.0], tr),
            ("[0.0, 0.0, 1.0]", 2.0, [0.0; 3]),
            64,
        );
        assert_even(&s, &format!("partly outside at {tr:?}"));
    }
}

#[test]
fn shared_edges_of_touching_coplanar_meshes() {
    // Two boxes sharing a face: each mesh is closed on its own, so each pixel is even per mesh.
    let text = r#"
[image]
width = 40
height = 40
[camera]
direction = [0.3, 0.2, 1.0]
view_width = 4.0
[sweep]
slabs = 16
optimal_distance = 0.5
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
translate = [-0.5, 0.0, 0.0]
material = "m"
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
translate = [0.5, 0.0, 0.0]
material = "m"
[material.m]
"#;
    assert_even(&support::scene(text, Path::new(".")), "touching boxes");
}

/// The analytic shapes and their signed distance functions (negative inside).
/// Signed distance to the analytic shape `shape` ("box", "sphere" or a torus) of the
/// inside-classification tests (here and in `ldi_perspective.rs`).
pub(crate) fn sdf(shape: &str, p: DVec3) -> f64 {
    match shape {
        "box" => {
            let h = DVec3::new(0.6, 0.45, 0.35);
            let q = p.abs() - h;
            q.max(DVec3::ZERO).length() + q.x.max(q.y).max(q.z).min(0.0)
        }
        "sphere" => p.length() - 0.7,
        _ => {
            let q = (p.x * p.x + p.y * p.y).sqrt() - 0.6;
            (q * q + p.z * p.z).sqrt() - 0.25
        }
    }
}

/// The largest |sdf| of `shape` over points sampled densely on every face of the scene's first
/// mesh (vertices lie on the analytic surface; face interiors deviate by the sagitta).
pub(crate) fn tessellation_error(g: &SceneGeometry, shape: &str) -> f64 {
    let mesh = &g.meshes[0];
    let to_obj = mesh.world_to_object;
    let mut tess: f64 = 0.0;
    for t in &mesh.mesh.triangles {
        let v = t.map(|i| to_obj.transform_point3(mesh.mesh.positions[i as usize]));
        for a in 0..=6 {
            for b in 0..=(6 - a) {
                let (u, w) = (f64::from(a) / 6.0, f64::from(b) / 6.0);
                let p = v[0] + (v[1] - v[0]) * u + (v[2] - v[0]) * w;
                tess = tess.max(sdf(shape, p).abs());
            }
        }
    }
    tess
}

/// The inside test of `ldi` at 40 depths along every pixel's ray of `g`'s camera (orthographic
/// or perspective) against `shape`'s signed distance, skipping the points within `band(z)` of
/// the surface (z the view depth); asserts each point and that more than 10× as many points were
/// checked as skipped, naming `what`. Returns (checked, skipped).
pub(crate) fn check_inside_along_rays(
    g: &SceneGeometry,
    ldi: &Ldi,
    shape: &str,
    band: impl Fn(f64) -> f64,
    what: &str,
) -> (u32, u32) {
    let to_obj = g.meshes[0].world_to_object;
    let depth_range = f64::from(g.slabs) * g.slab_distance;
    let (mut checked, mut skipped) = (0u32, 0u32);
    for j in 0..ldi.height {
        for i in 0..ldi.width {
            for k in 0..40 {
                let z_rel = depth_range * (f64::from(k) + 0.37) / 40.0;
                let z_f32 = z_rel as f32;
                let z = g.z_origin + f64::from(z_f32);
                let world = g
                    .camera
                    .pixel_to_world(f64::from(i) + 0.5, f64::from(j) + 0.5, z);
                let d = sdf(shape, to_obj.transform_point3(world));
                let band = band(z);
                if d.abs() <= band {
                    skipped += 1;
                    continue;
                }
                let got = inside(ldi, i, j, z_f32) & 1 == 1;
                assert_eq!(
                    got,
                    d < 0.0,
                    "{what}: pixel ({i},{j}) depth {z}: sdf {d}, band {band}"
                );
                checked += 1;
            }
        }
    }
    assert!(
        checked > 10 * skipped.max(1),
        "{what}: too few points checked ({checked} vs {skipped})"
    );
    (checked, skipped)
}

#[test]
fn inside_classification_matches_analytic_shapes() {
    for (shape, size) in [
        ("box", "[1.2, 0.9, 0.7]"),
        ("sphere", "[0.7, 4]"),
        ("torus", "[0.6, 0.25, 96]"),
    ] {
        let rot = [20.0, -35.0, 10.0];
        let s = shape_scene(
            shape,
            size,
            (1.0, rot, [0.0; 3]),
            ("[0.0, 0.0, 1.0]", 2.0, [0.0; 3]),
            96,
        );
        let (g, ldi) = build(&s);
        let tess = tessellation_error(&g, shape);
        // Snapping moves vertices by at most √2·2^-9 px laterally; f32 depths err by a few ulps
        // of the depth range. Points farther than this band from the surface must be exact.
        let px = g.camera.pixel_size;
        let snap = 2f64.sqrt() * (1.0 / 512.0) * px;
        let depth_range = f64::from(g.slabs) * g.slab_distance;
        let band = 1.05 * tess + snap + 8.0 * f64::from(f32::EPSILON) * (depth_range + 2.0);
        let (checked, skipped) = check_inside_along_rays(&g, &ldi, shape, |_| band, shape);
        eprintln!(
            "{shape}: band {band:.2e} (tessellation {tess:.2e}), {checked} points checked, {skipped} in the band"
        );
    }
}

#[test]
fn ldi_hash_is_independent_of_thread_count() {
    let scene = Scene::default_scene();
    let g = convshadow_io::build_geometry(&scene).unwrap();
    let hashes: Vec<u64> = [1, 2, 3, 8]
        .iter()
        .map(|&n| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap();
            pool.install(|| Ldi::build(&g.raster, BUDGET).unwrap().fingerprint())
        })
        .collect();
    assert!(hashes.windows(2).all(|w| w[0] == w[1]), "{hashes:x?}");
}

/// A scene framing an OBJ model with a 10 % margin (the loader's errors are the test's).
fn model_scene(path: &Path, width: u32) -> Scene {
    load_obj(path).unwrap_or_else(|e| panic!("{e}"));
    support::scene(&support::framed_obj_scene(path, width, 1.1), Path::new("."))
}

#[test]
fn every_closed_model_is_even_and_thread_independent() {
    let Some(dir) = support::models_dir() else {
        return;
    };
    for name in support::CLOSED_MODELS {
        let s = model_scene(&dir.join(name), 256);
        let ldi = assert_even(&s, name);
        let g = convshadow_io::build_geometry(&s).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let h3 = pool.install(|| Ldi::build(&g.raster, BUDGET).unwrap().fingerprint());
        assert_eq!(
            h3,
            ldi.fingerprint(),
            "{name}: ldi_hash differs with 3 threads"
        );
    }
}

#[test]
fn open_models_are_thin_shells_out_of_the_parity_test() {
    let Some(dir) = support::models_dir() else {
        return;
    };
    for name in [
        "teapot.obj",
        "cube_no_bottom.obj",
        "stanford_bunny_original.obj",
    ] {
        let s = model_scene(&dir.join(name), 128);
        let (g, ldi) = build(&s);
        let stats = ldi.stats();
        assert!(g.meshes[0].report.boundary_edges > 0, "{name}");
        assert_eq!(g.raster.parity_meshes & 1, 0, "{name}: a shell");
        assert_eq!(ldi.parity_meshes & 1, 0, "{name}: the LDI knows it");
        // Counted here over every fragment: the open mesh crosses some pixel an odd number of
        // times (it is open), which the statistics, over the closed meshes only, do not count.
        let odd = (0..ldi.height)
            .flat_map(|j| (0..ldi.width).map(move |i| (i, j)))
            .filter(|&(i, j)| ldi.range(i, j).len() % 2 == 1)
            .count();
        assert!(odd > 0, "{name}: an open mesh shows odd pixels");
        assert_eq!(stats.odd_pixels, 0, "{name}: a shell is no parity defect");
    }
}
