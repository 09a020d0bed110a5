//! The LDI along perspective rays (issue 42): closed meshes seen in perspective give an even
//! fragment count at every pixel (procedural shapes under random cameras, and the real models of
//! `../shared/models`), the inside test agrees with analytic shapes at points along each pixel's
//! ray (which checks the fragments' perspective depths against geometry computed here in f64),
//! and the build is independent of the thread count.

use crate::ldi_parity::{check_inside_along_rays, tessellation_error};
use crate::support;

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::common::prepare::geometry::SceneGeometry;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use glam::DVec3;
use proptest::prelude::*;

const BUDGET: u64 = 8 << 30;

/// A perspective camera at `eye` looking at `look_at` with vertical field of view `fov_deg`.
struct View {
    eye: DVec3,
    look_at: DVec3,
    fov_deg: f64,
}

/// A `width × height` scene seen through `view` whose meshes are `meshes` (TOML `[[mesh]]`
/// tables, each naming material `m`).
fn perspective_scene(meshes: &str, view: &View, width: u32, height: u32) -> Scene {
    let camera = (view.eye, view.look_at);
    let text = support::perspective_scene_text((width, height), camera, view.fov_deg, "", meshes);
    support::scene(&text, Path::new("."))
}

fn build(scene: &Scene) -> (SceneGeometry, Ldi) {
    let g = convshadow_io::build_geometry(scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, BUDGET).unwrap();
    (g, ldi)
}

/// The LDI of `scene`, asserted even at every pixel (and built the same with 3 threads).
fn assert_even(scene: &Scene, what: &str) -> Ldi {
    let (g, ldi) = build(scene);
    assert!(g.camera.focal_px.is_some(), "{what}: a perspective camera");
    assert_eq!(g.defect_edges(), 0, "{what}: mesh not closed");
    let stats = ldi.stats();
    assert_eq!(
        stats.odd_pixels, 0,
        "{what}: {} odd pixels",
        stats.odd_pixels
    );
    assert!(stats.fragments > 0, "{what}: nothing rasterized");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let h3 = pool.install(|| Ldi::build(&g.raster, BUDGET).unwrap().fingerprint());
    assert_eq!(
        h3,
        ldi.fingerprint(),
        "{what}: ldi_hash differs with 3 threads"
    );
    ldi
}

/// A view of a ball of radius `radius` around `c` from `direction` (towards `c`), the ball
/// filling `fill` of the vertical field of view.
fn framing(c: DVec3, radius: f64, direction: DVec3, fov_deg: f64, fill: f64) -> View {
    let distance = radius / ((0.5 * fov_deg).to_radians().sin() * fill);
    View {
        eye: c - direction.normalize() * distance,
        look_at: c,
        fov_deg,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    /// Procedural closed shapes under random transforms and perspective cameras (fields of
    /// view 10°–150°, the shape filling from a third of the view to beyond it, at least 32 px
    /// wide so that it covers pixels): even counts everywhere.
    #[test]
    fn procedural_shapes_are_even_in_perspective(
        shape in 0usize..3,
        rot in prop::array::uniform3(-180.0f64..180.0),
        dir in prop::array::uniform3(-1.0f64..1.0),
        fov in 10.0f64..150.0,
        fill in 0.35f64..1.6,
        width in 32u32..80,
    ) {
        let dir = DVec3::from(dir);
        prop_assume!(dir.length() > 0.1);
        prop_assume!(dir.normalize().y.abs() < 0.95);
        let (name, size) = [("box", "[1.0, 0.7, 0.4]"), ("sphere", "[0.8, 3]"), ("torus", "[0.8, 0.3, 24]")][shape];
        let mesh = format!(
            "[[mesh]]\nshape = \"{name}\"\nsize = {size}\nrotate_deg = [{}, {}, {}]\nmaterial = \"m\"",
            rot[0], rot[1], rot[2]
        );
        // Every shape lies within 1.25 of the origin: the eye stays outside.
        let view = framing(DVec3::ZERO, 1.25, dir, fov, fill.min(0.95));
        let s = perspective_scene(&mesh, &view, width, width * 3 / 4 + 1);
        assert_even(&s, name);
    }
}

#[test]
fn inside_classification_matches_analytic_shapes_in_perspective() {
    for fov in [30.0, 90.0] {
        for (shape, size) in [
            ("box", "[1.2, 0.9, 0.7]"),
            ("sphere", "[0.7, 4]"),
            ("torus", "[0.6, 0.25, 96]"),
        ] {
            let rot = [20.0, -35.0, 10.0];
            let mesh = format!(
                "[[mesh]]\nshape = \"{shape}\"\nsize = {size}\nrotate_deg = [{}, {}, {}]\nmaterial = \"m\"",
                rot[0], rot[1], rot[2]
            );
            let view = framing(DVec3::ZERO, 0.8, DVec3::new(0.2, -0.3, 1.0), fov, 0.9);
            let s = perspective_scene(&mesh, &view, 96, 80);
            let (g, ldi) = build(&s);
            let tess = tessellation_error(&g, shape);
            let focal = g.camera.focal_px.unwrap();
            // Snapping moves a vertex by ≤ √2·2^-9 px, a pixel spanning z / focal at depth z;
            // the f32 inverse-depth plane and `1/plane − origin` err by a few ulps of z; a depth
            // error moves the point along the ray by up to its length per unit depth (≤ 1/cos of
            // the half diagonal view, < 1.8 at 90°).
            let band = |z: f64| {
                let snap = 2f64.sqrt() / 512.0 * z / focal;
                1.05 * tess + 1.8 * (snap + 16.0 * f64::from(f32::EPSILON) * (z + g.z_origin))
            };
            let what = format!("{shape} fov {fov}");
            let (checked, skipped) = check_inside_along_rays(&g, &ldi, shape, band, &what);
            eprintln!(
                "{shape} fov {fov}: tessellation {tess:.2e}, {checked} points checked, {skipped} in the band"
            );
        }
    }
}

#[test]
fn every_closed_model_is_even_in_perspective() {
    let Some(dir) = support::models_dir() else {
        return;
    };
    for name in support::CLOSED_MODELS {
        let path = dir.join(name);
        let m = convshadow::io::obj::load_obj(&path).unwrap_or_else(|e| panic!("{e}"));
        let (lo, hi) = m.bounds();
        let (c, radius) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
        for fov in [30.0, 90.0] {
            let view = framing(c, radius, DVec3::new(0.3, -0.2, 1.0), fov, 0.95);
            let mesh = format!(
                "[[mesh]]\nshape = \"obj\"\npath = \"{}\"\nmaterial = \"m\"",
                path.display()
            );
            let s = perspective_scene(&mesh, &view, 256, 192);
            assert_even(&s, &format!("{name} fov {fov}"));
        }
    }
}

#[test]
fn near_sets_the_sweeps_origin_and_depths_are_view_depths_from_the_eye() {
    // A unit ball 5 in front of the eye: the central ray meets it at view depth 4 (less the
    // tessellation's sagitta), and off-axis rays where the analytic sphere says.
    let ball = "[[mesh]]\nshape = \"sphere\"\nsize = [1.0, 6]\nmaterial = \"m\"";
    let view = View {
        eye: DVec3::new(0.0, 0.0, -5.0),
        look_at: DVec3::ZERO,
        fov_deg: 40.0,
    };
    for near in [None, Some(2.0)] {
        let mut s = perspective_scene(ball, &view, 64, 64);
        if let convshadow::common::model::scene::Projection::Perspective { near: n, .. } =
            &mut s.camera.projection
        {
            *n = near;
        }
        let (g, ldi) = build(&s);
        let origin = near.unwrap_or(g.z_origin);
        assert_eq!(g.z_origin, origin, "near {near:?}: the sweep starts there");
        let f = g.camera.focal_px.unwrap();
        let (mut worst, mut hits) = (0.0f64, 0);
        for j in 0..ldi.height {
            for i in 0..ldi.width {
                let p = (j * ldi.width + i) as usize;
                let a = ldi.offsets[p] as usize;
                if a == ldi.offsets[p + 1] as usize {
                    continue;
                }
                // The ray (u, v, 1) per unit view depth meets |eye + z·(u, v, 1)| = 1 at the
                // smaller root z of (u² + v² + 1)z² − 10z + 24 = 0.
                let u = (f64::from(i) + 0.5 - 32.0) / f;
                let v = (f64::from(j) + 0.5 - 32.0) / f;
                let q = u * u + v * v + 1.0;
                let disc = 100.0 - 96.0 * q;
                if disc < 0.05 {
                    continue; // grazing rays: the tessellation decides
                }
                let z = (10.0 - disc.sqrt()) / (2.0 * q);
                worst = worst.max((origin + f64::from(ldi.depth[a]) - z).abs());
                hits += 1;
            }
        }
        // Subdivision 6 keeps the sagitta below 1e-3; f32 depths add a few ulps of 5.
        assert!(hits > 500, "near {near:?}: {hits} pixels hit");
        assert!(
            worst < 2e-3,
            "near {near:?}: first fragment off by {worst:.2e}"
        );
    }
}
