//! Property tests on meshes: random closed meshes (convex hulls of random point clouds, unions
//! of procedural boxes, spheres and tori under random transforms) keep even fragment counts in
//! the LDI, and the fuzzer's mesh files load (docs/errors.md).

use crate::support;

use std::path::Path;

use convshadow::common::model::scene::{CameraSpec, ImageSpec};
use convshadow::common::prepare::camera::Camera;
use convshadow::common::prepare::guard::GuardBand;
use convshadow::common::prepare::mesh::TriMesh;
use convshadow::common::prepare::raster::RasterSetup;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use glam::DVec3;
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// Convex hulls.

/// The convex hull of `points` as outward-wound triangles (incremental algorithm, O(n²)), or
/// `None` when the points are (nearly) coplanar.
fn convex_hull(points: &[DVec3]) -> Option<Vec<[u32; 3]>> {
    let n = points.len();
    let scale = points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(1e-300, f64::max);
    let eps = 1e-9 * scale * scale * scale;
    // An initial tetrahedron of non-coplanar points.
    let i0 = 0;
    let i1 = (1..n).max_by(|&a, &b| {
        (points[a] - points[i0])
            .length_squared()
            .total_cmp(&(points[b] - points[i0]).length_squared())
    })?;
    let i2 = (1..n).filter(|&k| k != i1).max_by(|&a, &b| {
        let area = |k: usize| {
            (points[i1] - points[i0])
                .cross(points[k] - points[i0])
                .length_squared()
        };
        area(a).total_cmp(&area(b))
    })?;
    let volume = |a: usize, b: usize, c: usize, p: DVec3| {
        (points[b] - points[a])
            .cross(points[c] - points[a])
            .dot(p - points[a])
    };
    let i3 = (1..n).filter(|&k| k != i1 && k != i2).max_by(|&a, &b| {
        volume(i0, i1, i2, points[a])
            .abs()
            .total_cmp(&volume(i0, i1, i2, points[b]).abs())
    })?;
    if volume(i0, i1, i2, points[i3]).abs() <= eps {
        return None;
    }
    let mut faces: Vec<[usize; 3]> = if volume(i0, i1, i2, points[i3]) < 0.0 {
        // i3 is behind (i0, i1, i2): that face points away from it.
        vec![[i0, i1, i2], [i0, i3, i1], [i1, i3, i2], [i2, i3, i0]]
    } else {
        vec![[i0, i2, i1], [i0, i1, i3], [i1, i2, i3], [i2, i0, i3]]
    };
    for (p, &point) in points.iter().enumerate() {
        if [i0, i1, i2, i3].contains(&p) {
            continue;
        }
        let visible: Vec<bool> = faces
            .iter()
            .map(|f| volume(f[0], f[1], f[2], point) > eps)
            .collect();
        if !visible.contains(&true) {
            continue;
        }
        // Horizon: directed edges of visible faces whose twin belongs to a hidden face.
        let mut horizon = Vec::new();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, v)| **v) {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let twin_hidden = faces
                    .iter()
                    .zip(&visible)
                    .any(|(g, v)| !*v && (0..3).any(|m| g[m] == b && g[(m + 1) % 3] == a));
                if twin_hidden {
                    horizon.push((a, b));
                }
            }
        }
        let mut kept: Vec<[usize; 3]> = faces
            .iter()
            .zip(&visible)
            .filter(|(_, v)| !**v)
            .map(|(f, _)| *f)
            .collect();
        kept.extend(horizon.iter().map(|&(a, b)| [a, b, p]));
        faces = kept;
    }
    Some(faces.iter().map(|f| f.map(|i| i as u32)).collect())
}

/// An orthographic camera looking along `direction` at the origin, `width`² pixels over `view`.
fn camera(direction: [f64; 3], width: u32, view: f64) -> Camera {
    let up = if direction[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let spec = CameraSpec {
        direction: DVec3::from(direction).normalize().to_array(),
        up,
        center: [0.0; 3],
        view_width: view,
        projection: Default::default(),
    };
    let image = ImageSpec {
        width,
        height: width,
        background: [0.0; 3],
        exposure: 0.0,
        tonemap: Default::default(),
    };
    Camera::new(&spec, &image)
}

/// Odd pixels of the LDI of `meshes` seen through `cam`.
fn odd_pixels(cam: &Camera, meshes: &[(&[DVec3], &[[u32; 3]])]) -> (u64, u64) {
    let z0 = meshes
        .iter()
        .flat_map(|m| m.0.iter())
        .map(|p| cam.to_camera(*p).z)
        .fold(f64::INFINITY, f64::min);
    let setup = RasterSetup::new(cam, GuardBand::uniform(1), meshes, z0).unwrap();
    let ldi = Ldi::build(&setup, 1 << 30).unwrap();
    let stats = ldi.stats();
    (stats.odd_pixels, stats.fragments)
}

fn point() -> impl Strategy<Value = DVec3> {
    (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn direction() -> impl Strategy<Value = [f64; 3]> {
    (-1.0f64..1.0, -1.0f64..1.0, 0.2f64..1.0).prop_map(|(x, y, z)| [x, y, z])
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    /// The hull of a random point cloud is a closed, consistently wound mesh, and every pixel
    /// of its LDI has an even fragment count, from any direction and at any scale.
    #[test]
    fn random_convex_hulls_are_closed_and_even(
        points in prop::collection::vec(point(), 4..48),
        dir in direction(),
        log_scale in -3.0f64..3.0,
        offset in point(),
        width in 16u32..96,
        // Snapping some points to a grid puts vertices and edges exactly on pixel centres.
        snap in any::<bool>(),
    ) {
        let s = 10f64.powf(log_scale);
        let points: Vec<DVec3> = points
            .iter()
            .map(|p| {
                let p = if snap { (*p * 8.0).round() / 8.0 } else { *p };
                (p + offset * 0.5) * s
            })
            .collect();
        let hull = convex_hull(&points);
        prop_assume!(hull.is_some());
        let hull = hull.unwrap();
        let mesh = TriMesh { positions: points.clone(), triangles: hull };
        let (clean, report) = mesh.analyze();
        prop_assert!(report.is_closed(), "hull not closed: {report:?}");
        prop_assert!(clean.signed_volume() > 0.0, "hull wound inward");
        let cam = camera(dir, width, 3.5 * s);
        let (odd, fragments) = odd_pixels(&cam, &[(&clean.positions, &clean.triangles)]);
        prop_assert_eq!(odd, 0, "{} fragments", fragments);
        prop_assert!(fragments > 0);
    }

    /// Unions of boxes, spheres and tori under random transforms, as separate (overlapping)
    /// meshes of one scene: every mesh keeps an even count at every pixel.
    #[test]
    fn unions_of_procedural_shapes_are_even(
        shapes in prop::collection::vec(
            (0u8..3, point(), point(), 0.2f64..1.5, (0.2f64..1.0, 0.2f64..1.0, 0.2f64..1.0)),
            1..6,
        ),
        dir in direction(),
        width in 16u32..80,
    ) {
        let mut text = format!(
            "[image]\nwidth = {width}\nheight = {width}\n[camera]\ndirection = [{}, {}, {}]\n\
             view_width = 5.0\n[sweep]\nslabs = 8\noptimal_distance = 0.5\nguard_band = 2\n\
             [material.m]\n",
            dir[0], dir[1], dir[2]
        );
        for (kind, t, r, scale, (a, b, c)) in &shapes {
            let size = match kind {
                0 => format!("shape = \"box\"\nsize = [{a}, {b}, {c}]"),
                1 => format!("shape = \"sphere\"\nsize = [{a}, {}]", (b * 4.0) as u32),
                _ => format!("shape = \"torus\"\nsize = [{}, {}, {}]", a + 0.3, a * b * 0.9, 3 + (c * 20.0) as u32),
            };
            text += &format!(
                "[[mesh]]\n{size}\ntranslate = [{}, {}, {}]\nrotate_deg = [{}, {}, {}]\n\
                 scale = {scale}\nmaterial = \"m\"\n",
                t.x, t.y, t.z, r.x * 180.0, r.y * 180.0, r.z * 180.0
            );
        }
        let scene = support::scene(&text, Path::new("."));
        let geometry = convshadow_io::build_geometry(&scene).unwrap();
        prop_assert_eq!(geometry.defect_edges(), 0);
        let ldi = Ldi::build(&geometry.raster, 1 << 30).unwrap();
        prop_assert_eq!(ldi.stats().odd_pixels, 0, "{}", text);
    }
}

#[test]
fn the_hull_helper_builds_closed_hulls_of_a_cube_with_inner_points() {
    // The corners of a cube plus its centre: 12 triangles, the centre unused.
    let mut points: Vec<DVec3> = (0..8)
        .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    points.push(DVec3::splat(0.5));
    let tris = convex_hull(&points).unwrap();
    let (_, report) = TriMesh {
        positions: points,
        triangles: tris.clone(),
    }
    .analyze();
    assert!(report.is_closed(), "{report:?}");
    assert!(
        tris.iter().flatten().all(|&i| i != 8),
        "the centre is inside"
    );
    let flat: Vec<DVec3> = (0..5).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
    assert!(convex_hull(&flat).is_none());
}

// ---------------------------------------------------------------------------------------------
// Fuzz regressions (inputs found by `scripts/fuzz.sh`; see docs/errors.md).

/// obj_load crash 1 (a bug of the fuzz harness, not of the loader): an OBJ whose first two
/// vertices coincide loads, and welding makes two triangles degenerate. `analyze` must account for
/// every triangle as kept or degenerate, with a comment holding NUL bytes and an unknown `fd`
/// statement ignored.
#[test]
fn fuzz_obj_with_welded_vertices_and_nul_bytes_loads_and_counts_degenerate_triangles() {
    let bytes: &[u8] =
        b"# Valid syn\0\0\x004tax, bad topology\nv 1 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n\
        f 1 3 2\nf 1 2 4\nfd topo\nf 2 4 3\n";
    let dir = support::temp_dir("fuzz-obj-1");
    let path = dir.join("crash.obj");
    std::fs::write(&path, bytes).unwrap();
    let mesh = convshadow::io::obj::load_obj(&path).unwrap();
    assert_eq!(mesh.triangles.len(), 3);
    let (clean, report) = mesh.analyze();
    assert_eq!(report.degenerate_triangles, 2, "{report:?}");
    assert_eq!(clean.triangles.len(), report.triangles);
    assert_eq!(report.triangles + report.degenerate_triangles, 3);
    assert!(!report.is_closed());
    std::fs::remove_dir_all(&dir).unwrap();
}
