//! Property tests: random closed meshes (convex hulls of random point clouds, unions
//! of procedural boxes, spheres and tori under random transforms) keep even fragment counts;
//! random valid scenes render without NaN; random invalid scenes are rejected naming the key.

use crate::support;

use std::path::Path;

use convshadow::common::model::scene::{CameraSpec, ImageSpec, Scene};
use convshadow::common::prepare::camera::Camera;
use convshadow::common::prepare::guard::GuardBand;
use convshadow::common::prepare::mesh::TriMesh;
use convshadow::common::prepare::raster::RasterSetup;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::pipeline::{RenderRequest, render};
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
// Random scenes, valid and invalid.

/// A random scene as (key path, TOML value) entries grouped in tables, so one key can be swapped.
#[derive(Debug, Clone)]
struct GenScene {
    width: u32,
    height: u32,
    view_width: f64,
    direction: [f64; 3],
    slabs: u32,
    kernel: &'static str,
    seed: u32,
    guard: u32,
    compensation: bool,
    jitter: bool,
    lights: Vec<GenLight>,
    meshes: Vec<GenMesh>,
    materials: Vec<(f64, [f64; 3], bool)>,
}

/// A light: colour, tilt, variance, rotation.
type GenLight = ([f64; 3], [f64; 2], [f64; 2], f64);
/// A mesh: shape (box, sphere, torus), translation, rotation, scale, material index.
type GenMesh = (u8, [f64; 3], [f64; 3], f64, usize);

/// One (table header, key, value) line of the generated TOML.
type Entry = (String, String, String);

impl GenScene {
    fn entries(&self) -> Vec<Entry> {
        let mut v: Vec<Entry> = Vec::new();
        let mut put = |table: &str, key: &str, value: String| {
            v.push((table.to_string(), key.to_string(), value));
        };
        let arr = |a: &[f64]| {
            format!(
                "[{}]",
                a.iter()
                    .map(|x| format!("{x:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        put("image", "width", self.width.to_string());
        put("image", "height", self.height.to_string());
        put("camera", "direction", arr(&self.direction));
        put("camera", "view_width", format!("{:?}", self.view_width));
        put("sweep", "slabs", self.slabs.to_string());
        put("sweep", "optimal_distance", "0.5".into());
        put("sweep", "kernel", format!("{:?}", self.kernel));
        put("sweep", "seed", self.seed.to_string());
        put("sweep", "guard_band", self.guard.to_string());
        put(
            "sweep",
            "variance_compensation",
            self.compensation.to_string(),
        );
        put("sweep", "jitter", self.jitter.to_string());
        for (i, (color, tilt, variance, rot)) in self.lights.iter().enumerate() {
            let t = format!("light[{i}]");
            put(&t, "color", arr(color));
            put(&t, "tilt_deg", arr(tilt));
            put(&t, "variance", arr(variance));
            put(&t, "rotation_deg", format!("{rot:?}"));
        }
        for (i, (kind, translate, rotate, scale, material)) in self.meshes.iter().enumerate() {
            let t = format!("mesh[{i}]");
            let (shape, size) = match kind {
                0 => ("box", "[0.8, 0.6, 0.7]"),
                1 => ("sphere", "[0.5, 2.0]"),
                _ => ("torus", "[0.5, 0.2, 12.0]"),
            };
            put(&t, "shape", format!("{shape:?}"));
            put(&t, "size", size.into());
            put(&t, "translate", arr(translate));
            put(&t, "rotate_deg", arr(rotate));
            put(&t, "scale", format!("{scale:?}"));
            put(&t, "material", format!("\"m{material}\""));
        }
        for (i, (opacity, transport, detail)) in self.materials.iter().enumerate() {
            let t = format!("material.m{i}");
            put(&t, "transport", arr(transport));
            if *detail {
                put(&t, "detail", "{ kind = \"fbm\", frequency = 3.0 }".into());
                put(
                    &t,
                    "gradient",
                    format!("[[0.0, 1.0, 0.5, 0.2, 0.0], [1.0, 0.2, 0.4, 1.0, {opacity:?}]]"),
                );
            } else {
                put(&t, "opacity", format!("{opacity:?}"));
                put(&t, "color", "[0.9, 0.8, 0.7]".into());
            }
        }
        v
    }

    /// The TOML text, with `key` (a full path like `light[0].tilt_deg`) replaced by `value`.
    fn toml(&self, replace: Option<(&str, &str)>) -> String {
        let mut text = String::new();
        let mut current = String::new();
        for (table, key, value) in self.entries() {
            if table != current {
                let header = match table.split_once('[') {
                    Some((name, _)) => format!("[[{name}]]"),
                    None => format!("[{table}]"),
                };
                text += &format!("{header}\n");
                current = table.clone();
            }
            let path = format!("{table}.{key}");
            let value = match replace {
                Some((k, v)) if k == path => v.to_string(),
                _ => value,
            };
            text += &format!("{key} = {value}\n");
        }
        text
    }
}

fn gen_scene() -> impl Strategy<Value = GenScene> {
    let light = (
        prop::array::uniform3(0.0f64..2.0),
        prop::array::uniform2(-85.0f64..85.0),
        prop::array::uniform2(prop_oneof![Just(0.0), 0.0f64..0.5, 0.5f64..50.0]),
        -180.0f64..180.0,
    );
    let mesh = (
        0u8..3,
        prop::array::uniform3(-0.8f64..0.8),
        prop::array::uniform3(-180.0f64..180.0),
        0.5f64..1.5,
        0usize..2,
    );
    let material = (
        0.0f64..1.0,
        prop::array::uniform3(prop_oneof![Just(0.0), Just(1.0), 0.0f64..1.0]),
        any::<bool>(),
    );
    (
        (
            8u32..=24,
            8u32..=24,
            1.5f64..4.0,
            prop::array::uniform3(-1.0f64..1.0),
        ),
        (
            1u32..=16,
            prop::sample::select(support::kernels()),
            any::<u32>(),
            0u32..4,
            any::<bool>(),
            any::<bool>(),
        ),
        prop::collection::vec(light, 1..4),
        prop::collection::vec(mesh, 1..4),
        prop::collection::vec(material, 2..=2),
    )
        .prop_filter("a view direction", |((_, _, _, d), ..)| {
            d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 0.05
        })
        .prop_map(
            |(
                (width, height, view_width, mut direction),
                (slabs, kernel, seed, guard, compensation, jitter),
                lights,
                meshes,
                materials,
            )| {
                // Keep the default up vector (+y) away from the view direction.
                if direction[0].abs() + direction[2].abs() < 0.2 {
                    direction[2] = 1.0;
                }
                GenScene {
                    width,
                    height,
                    view_width,
                    direction,
                    slabs,
                    kernel,
                    seed,
                    guard,
                    compensation,
                    jitter,
                    lights,
                    meshes,
                    materials,
                }
            },
        )
}

/// A mutation of one key to an invalid value; `names` must appear in the error message.
fn mutation(s: &GenScene, pick: usize, which: usize) -> (String, String, String) {
    let l = pick % s.lights.len();
    let m = pick % s.meshes.len();
    let list: Vec<(String, &str, String)> = vec![
        ("image.width".into(), "0", "image.width".into()),
        ("image.width".into(), "100000", "image.width".into()),
        ("image.height".into(), "-4", "height".into()),
        ("image.height".into(), "\"tall\"", "height".into()),
        (
            "camera.view_width".into(),
            "0.0",
            "camera.view_width".into(),
        ),
        (
            "camera.view_width".into(),
            "nan",
            "camera.view_width".into(),
        ),
        (
            "camera.direction".into(),
            "[0.0, 0.0, 0.0]",
            "camera.direction".into(),
        ),
        (
            "camera.direction".into(),
            "[0.0, 1.0, 0.0]",
            "camera.up".into(),
        ),
        ("sweep.slabs".into(), "0", "sweep.slabs".into()),
        ("sweep.slabs".into(), "70000", "sweep.slabs".into()),
        (
            "sweep.optimal_distance".into(),
            "-0.5",
            "sweep.optimal_distance".into(),
        ),
        ("sweep.kernel".into(), "\"blur\"", "sweep.kernel".into()),
        ("sweep.guard_band".into(), "5000", "sweep.guard_band".into()),
        ("sweep.jitter".into(), "3", "jitter".into()),
        (
            format!("light[{l}].tilt_deg"),
            "[90.0, 0.0]",
            format!("light[{l}].tilt_deg[0]"),
        ),
        (
            format!("light[{l}].tilt_deg"),
            "[0.0, -90.0]",
            format!("light[{l}].tilt_deg[1]"),
        ),
        (
            format!("light[{l}].tilt_deg"),
            "[0.0, 135.0]",
            format!("light[{l}].tilt_deg[1]"),
        ),
        (
            format!("light[{l}].variance"),
            "[-0.1, 0.0]",
            format!("light[{l}].variance[0]"),
        ),
        (
            format!("light[{l}].variance"),
            "[0.1, -1e-9]",
            format!("light[{l}].variance[1]"),
        ),
        (
            format!("light[{l}].color"),
            "[1.0, -1.0, 1.0]",
            format!("light[{l}].color[1]"),
        ),
        (
            format!("light[{l}].rotation_deg"),
            "inf",
            format!("light[{l}].rotation_deg"),
        ),
        (
            format!("mesh[{m}].shape"),
            "\"cone\"",
            format!("mesh[{m}].shape"),
        ),
        (
            format!("mesh[{m}].scale"),
            "0.0",
            format!("mesh[{m}].scale"),
        ),
        (
            format!("mesh[{m}].material"),
            "\"nope\"",
            format!("mesh[{m}].material"),
        ),
        (
            format!("mesh[{m}].translate"),
            "[0.0, nan, 0.0]",
            format!("mesh[{m}].translate[1]"),
        ),
        (
            "material.m0.transport".into(),
            "[0.5, 2.0, 0.5]",
            "material.m0.transport[1]".into(),
        ),
    ];
    let (key, value, names) = &list[which % list.len()];
    (key.clone(), value.to_string(), names.clone())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    /// Small random valid scenes (≤ 24×24 px, ≤ 16 slabs, 1–3 lights, 1–3 meshes, every kernel)
    /// render through the library pipeline with finite, non-negative pixels and light.
    #[test]
    fn random_valid_scenes_render_without_nan(s in gen_scene()) {
        let text = s.toml(None);
        let scene = Scene::parse(&text, "random.toml", Path::new("."))
            .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        let req = RenderRequest { threads: 1, ..RenderRequest::default() };
        let r = render(&scene, &req)
            .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e)))?;
        prop_assert_eq!(r.image.data.len(), (s.width * s.height * 3) as usize);
        prop_assert!(
            r.image.data.iter().all(|v| v.is_finite() && *v >= 0.0),
            "non-finite or negative pixel\n{}", text
        );
        // The light buffers: `[row][light][plane][x]`; a light's channels are ≥ 0, its depth
        // plane (distance penumbra, sub-pixel shadows) is D, negative where light was removed
        // before slab 0's middle (`deepen`): finite only.
        let (w, planes) = (r.plan.grid_width as usize, r.plan.planes_per_light());
        let channels = r.plan.channels as usize;
        let bad = r.light.iter().enumerate().find(|&(i, v)| {
            !v.is_finite() || (((i / w) % planes) < channels && *v < 0.0)
        });
        prop_assert!(bad.is_none(), "light value {:?}\n{}", bad, text);
    }

    /// One key of a valid scene set to an invalid value: rejected by the parser with a message
    /// naming the file and the key (so it can never reach the renderer), while the unmutated
    /// scene is accepted.
    #[test]
    fn random_invalid_scenes_are_rejected_naming_the_key(
        s in gen_scene(),
        pick in any::<usize>(),
        which in any::<usize>(),
    ) {
        prop_assert!(Scene::parse(&s.toml(None), "random.toml", Path::new(".")).is_ok());
        let (key, value, names) = mutation(&s, pick, which);
        let text = s.toml(Some((&key, &value)));
        prop_assert!(text.contains(&format!("= {value}\n")), "mutation applied:\n{}", text);
        match Scene::parse(&text, "random.toml", Path::new(".")) {
            Ok(_) => prop_assert!(false, "{} = {} was accepted\n{}", key, value, text),
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.starts_with("random.toml: "), "{}", msg);
                prop_assert!(msg.contains(&names), "{} = {}: message must name {}: {}", key, value, names, msg);
            }
        }
    }
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

// ---------------------------------------------------------------------------------------------
// Extreme numbers: every scene number drawn from the whole f64 range.

/// The scene numbers the extreme-value property varies: (table, key, number of components).
const NUMERIC_KEYS: &[(&str, &str, usize)] = &[
    ("image", "background", 3),
    ("image", "exposure", 1),
    ("camera", "direction", 3),
    ("camera", "center", 3),
    ("camera", "view_width", 1),
    ("sweep", "slab_distance", 1),
    ("sweep", "optimal_distance", 1),
    ("light", "color", 3),
    ("light", "tilt_deg", 2),
    ("light", "variance", 2),
    ("light", "rotation_deg", 1),
    ("mesh", "translate", 3),
    ("mesh", "rotate_deg", 3),
    ("mesh", "scale", 1),
    ("mesh", "size", 3),
    ("material.m", "color", 3),
    ("material.m", "opacity", 1),
    ("material.m", "reference_length", 1),
    ("material.m", "specular.strength", 1),
    ("material.d", "detail.frequency", 1),
    ("material.d", "detail.lacunarity", 1),
    ("material.d", "detail.gain", 1),
    ("material.d", "detail.time", 1),
    ("material.d", "gradient[0]", 5),
];

/// A small valid scene with key `key` of table `table` set to `value` (TOML text).
fn extreme_scene(table: &str, key: &str, value: &str) -> String {
    let mut lines: Vec<(&str, String, String)> = vec![
        ("image", "width".into(), "8".into()),
        ("image", "height".into(), "8".into()),
        ("image", "background".into(), "[0.1, 0.2, 0.3]".into()),
        ("image", "exposure".into(), "0.0".into()),
        ("camera", "direction".into(), "[0.3, -0.2, 1.0]".into()),
        ("camera", "center".into(), "[0.0, 0.0, 0.0]".into()),
        ("camera", "view_width".into(), "3.0".into()),
        ("sweep", "slabs".into(), "6".into()),
        ("sweep", "optimal_distance".into(), "0.5".into()),
        ("light", "color".into(), "[1.0, 0.9, 0.8]".into()),
        ("light", "tilt_deg".into(), "[20.0, 10.0]".into()),
        ("light", "variance".into(), "[0.01, 0.02]".into()),
        ("light", "rotation_deg".into(), "10.0".into()),
        ("mesh", "shape".into(), "\"box\"".into()),
        ("mesh", "size".into(), "[1.0, 1.0, 1.0]".into()),
        ("mesh", "translate".into(), "[0.0, 0.0, 0.0]".into()),
        ("mesh", "rotate_deg".into(), "[10.0, 20.0, 30.0]".into()),
        ("mesh", "scale".into(), "1.0".into()),
        ("mesh", "material".into(), "\"m\"".into()),
        ("mesh2", "shape".into(), "\"sphere\"".into()),
        ("mesh2", "size".into(), "[0.4, 1.0]".into()),
        ("mesh2", "translate".into(), "[0.5, 0.5, -0.5]".into()),
        ("mesh2", "material".into(), "\"d\"".into()),
        ("material.m", "color".into(), "[0.9, 0.8, 0.7]".into()),
        ("material.m", "opacity".into(), "0.5".into()),
        ("material.m", "reference_length".into(), "0.5".into()),
        (
            "material.m",
            "specular".into(),
            "{ strength = 0.4, exponent = 8 }".into(),
        ),
        (
            "material.d",
            "detail".into(),
            "{ kind = \"fbm\", frequency = 3.0, lacunarity = 2.0, gain = 0.5, time = 0.5 }".into(),
        ),
        (
            "material.d",
            "gradient".into(),
            "[[0.0, 1.0, 0.5, 0.2, 0.0], [1.0, 0.2, 0.4, 1.0, 0.8]]".into(),
        ),
    ];
    for line in &mut lines {
        if line.0 != table {
            continue;
        }
        if key == "slab_distance" && line.1 == "slabs" {
            *line = (line.0, key.into(), value.into());
        } else if line.1 == key {
            line.2 = value.into();
        } else if let Some((inline, field)) = key.split_once('.')
            && line.1 == inline
        {
            // A field of an inline table: replace `field = …` up to the next comma or brace.
            let start = line.2.find(&format!("{field} = ")).unwrap() + field.len() + 3;
            let end = start + line.2[start..].find([',', ' ']).unwrap();
            line.2.replace_range(start..end, value);
        } else if let Some(inner) = key.strip_prefix("gradient[0]")
            && line.1 == "gradient"
        {
            assert!(inner.is_empty());
            line.2 = format!("[{value}, [1.0, 0.2, 0.4, 1.0, 0.8]]");
        }
    }
    let mut text = String::new();
    let mut current = "";
    for (table, key, value) in &lines {
        if *table != current {
            text += &match *table {
                "light" | "mesh" | "mesh2" => "[[mesh]]\n".replace("mesh", &table.replace('2', "")),
                t => format!("[{t}]\n"),
            };
            current = table;
        }
        text += &format!("{key} = {value}\n");
    }
    text
}

/// A number from the whole f64 range: the extremes, subnormals, ±0, overflow-to-f32 values, and
/// arbitrary finite values.
fn extreme_number() -> impl Strategy<Value = f64> {
    prop_oneof![
        prop::sample::select(vec![
            f64::MAX,
            -f64::MAX,
            1.7e308,
            1e308,
            -1e308,
            1e307,
            1e39,
            3.5e38,
            1e30,
            1e-30,
            1e-39,
            1e-300,
            -1e-300,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            0.0,
            -0.0,
            1.0,
            89.999999,
            -89.999999,
        ]),
        any::<f64>().prop_filter("finite", |v| v.is_finite()),
        -1e3f64..1e3,
    ]
}

/// Renders scene text: `Err(message)` for a refused scene, else checks every value is finite.
fn render_extreme(text: &str) -> Result<(), String> {
    let scene = Scene::parse(text, "extreme.toml", Path::new(".")).map_err(|e| e.to_string())?;
    let req = RenderRequest {
        threads: 1,
        memory_budget: 256 << 20,
        ..RenderRequest::default()
    };
    let r = render(&scene, &req).map_err(|e| e.to_string())?;
    assert!(
        r.image.data.iter().all(|v| v.is_finite()),
        "non-finite pixel\n{text}"
    );
    assert!(r.light.iter().all(|v| v.is_finite()), "light\n{text}");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1024, .. ProptestConfig::default() })]

    /// One scene number (or one component of an array) set to any finite f64: never a panic;
    /// either a clear error naming the key or a render whose pixels are all finite.
    #[test]
    fn extreme_numbers_give_a_clear_error_or_a_finite_image(
        which in any::<prop::sample::Index>(),
        component in any::<prop::sample::Index>(),
        v in extreme_number(),
    ) {
        let (table, key, n) = NUMERIC_KEYS[which.index(NUMERIC_KEYS.len())];
        let c = component.index(n);
        let value = if n == 1 {
            format!("{v:?}")
        } else {
            let base: Vec<String> = (0..n)
                .map(|i| if i == c { format!("{v:?}") } else if key == "gradient[0]" && i == 0 { "0.0".into() } else { "0.5".into() })
                .collect();
            format!("[{}]", base.join(", "))
        };
        let text = extreme_scene(table, key, &value);
        let outcome = std::panic::catch_unwind(|| render_extreme(&text));
        match outcome {
            Err(_) => prop_assert!(false, "panicked on {}.{} = {}\n{}", table, key, value, text),
            Ok(Err(msg)) => {
                prop_assert!(msg.starts_with("extreme.toml") || !msg.is_empty(), "{}", msg);
                prop_assert!(!msg.contains("NaN") || msg.contains(key), "{}", msg);
            }
            Ok(Ok(())) => {}
        }
    }
}

#[test]
fn the_extreme_value_base_scene_renders() {
    render_extreme(&extreme_scene("", "", "")).unwrap();
}

// ---------------------------------------------------------------------------------------------
// Hardening regressions: one scene value each, found by an adversarial pass.

/// `extreme_scene` with one key replaced must be refused naming `names` (file and key).
fn assert_scene_refused(table: &str, key: &str, value: &str, names: &str) {
    let text = extreme_scene(table, key, value);
    match Scene::parse(&text, "extreme.toml", Path::new(".")) {
        Ok(_) => panic!("{table}.{key} = {value} was accepted\n{text}"),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("extreme.toml"), "{msg}");
            assert!(
                msg.contains(names),
                "{key} = {value}: must name {names}: {msg}"
            );
        }
    }
}

#[test]
fn huge_finite_distances_and_variances_are_refused_not_panics() {
    assert_scene_refused(
        "sweep",
        "optimal_distance",
        "1.7e308",
        "sweep.optimal_distance",
    );
    assert_scene_refused("sweep", "slab_distance", "1e307", "sweep.slab_distance");
    assert_scene_refused(
        "light",
        "variance",
        "[1e308, 1e308]",
        "light[0].variance[0]",
    );
    // And the planner itself is total: no scene value makes it panic.
    assert!(render_extreme(&extreme_scene("light", "variance", "[1e8, 1e8]")).is_ok());
}

#[test]
fn colours_beyond_f32_are_refused_with_the_representable_range() {
    for (table, key, value, names) in [
        (
            "material.m",
            "color",
            "[1e308, 1.0, 1.0]",
            "material.m.color[0]",
        ),
        (
            "material.m",
            "specular.strength",
            "1e308",
            "material.m.specular.strength",
        ),
        ("light", "color", "[1e39, 1.0, 1.0]", "light[0].color[0]"),
        (
            "image",
            "background",
            "[1e39, 0.0, 0.0]",
            "image.background[0]",
        ),
    ] {
        assert_scene_refused(table, key, value, names);
        let msg = Scene::parse(&extreme_scene(table, key, value), "x.toml", Path::new("."))
            .unwrap_err()
            .to_string();
        assert!(msg.contains("1e4"), "the range is given: {msg}");
    }
    // The largest accepted values still give a finite image.
    render_extreme(&extreme_scene("material.m", "color", "[1e4, 1e4, 1e4]")).unwrap();
    render_extreme(&extreme_scene("light", "color", "[1e4, 1e4, 1e4]")).unwrap();
    render_extreme(&extreme_scene("material.m", "specular.strength", "1e4")).unwrap();
}

#[test]
fn arrays_of_the_wrong_length_and_gradient_indices_are_exact() {
    assert_scene_refused("material.m", "color", "[1.0, 1.0, 1.0, 1.0]", "4");
    assert_scene_refused("light", "tilt_deg", "[1.0, 2.0, 3.0]", "3");
    assert_scene_refused(
        "material.d",
        "gradient[0]",
        "[0.0, 1.0, 0.5, 0.2, 0.0, 1.0]",
        "gradient stop 0",
    );
    // A bad colour at [0][1] is reported at [0][1], not [0][0].
    assert_scene_refused(
        "material.d",
        "gradient[0]",
        "[0.0, -1.0, 0.5, 0.2, 0.0]",
        "material.d.gradient[0][1]",
    );
    assert_scene_refused(
        "material.d",
        "gradient[0]",
        "[0.0, 1.0, 0.5, 1e9, 0.0]",
        "material.d.gradient[0][3]",
    );
}

#[test]
fn kernel_names_are_canonical() {
    use convshadow::common::model::kernel::KernelSpec;
    for bad in [
        "gaussian:+3",
        "ellipse02",
        "ellipse+4",
        "gaussian:03",
        "ellipse",
        "gaussian:",
    ] {
        assert!(bad.parse::<KernelSpec>().is_err(), "{bad} accepted");
    }
    for good in ["gaussian:3", "ellipse2", "ellipse16", "ellipse4:slab"] {
        assert!(good.parse::<KernelSpec>().is_ok(), "{good} refused");
    }
}

#[test]
fn a_huge_direction_is_normalised_and_tiny_slab_distances_print_short() {
    let text = extreme_scene("camera", "direction", "[1e308, 1e308, 1e308]");
    Scene::parse(&text, "x.toml", Path::new(".")).unwrap();
    let msg = Scene::parse(
        &extreme_scene("sweep", "slab_distance", "1e-300"),
        "x.toml",
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(
        msg.contains("sweep.slab_distance") && msg.len() < 200,
        "{msg}"
    );
}
