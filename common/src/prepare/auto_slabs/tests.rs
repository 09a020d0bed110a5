use std::path::Path;

use crate::contract::files::GeometryFiles;
use crate::model::scene::Scene;
use crate::prepare::error::GeometryError;
use crate::prepare::geometry::SceneGeometry;

/// A 2×2×2 box (or `box_size`) at the origin seen along `direction`, with `sweep` and the
/// material table `material` (its `[material.m]` header included).
fn scene(direction: &str, sweep: &str, mesh_extra: &str, material: &str) -> Scene {
    let text = format!(
        r#"
[image]
width = 16
height = 16
[camera]
direction = {direction}
view_width = 4.0
[sweep]
optimal_distance = 1.0
{sweep}
[[mesh]]
shape = "box"
size = [2.0, 2.0, 2.0]
material = "m"
{mesh_extra}
{material}
"#
    );
    Scene::parse(&text, "auto.toml", Path::new(".")).unwrap()
}

fn fbm(frequency: f64) -> String {
    format!(
        "[material.m]\ndetail = {{ kind = \"fbm\", frequency = {frequency}, octaves = 3, \
         lacunarity = 2.0 }}\ngradient = [[0.0, 1.0, 1.0, 1.0, 0.5]]\n"
    )
}

fn count(s: &Scene) -> u32 {
    let g = SceneGeometry::build(s, &GeometryFiles::default()).unwrap();
    assert_eq!(g.slabs, g.auto_slabs.as_ref().unwrap().count);
    g.slabs
}

#[test]
fn doubling_a_details_frequency_doubles_the_count() {
    const AUTO: &str = "slabs = \"auto\"";
    // f_max = 5 · 2² = 20 per unit; the box is 2 deep: at least 2 · 20 · 2 = 80 slabs, at
    // most one more (the ceiling of a depth widened by one part in 10⁶).
    let n1 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(5.0)));
    assert!((80..=81).contains(&n1), "{n1}");
    let n2 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(10.0)));
    assert!(n2 == 2 * n1 || n2 == 2 * n1 - 1, "{n1} → {n2}");
    let n4 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(20.0)));
    assert!(n4 == 2 * n2 || n4 == 2 * n2 - 1, "{n2} → {n4}");
    // slab_factor multiplies the count the same way.
    let f2 = count(&scene(
        "[0.0, 0.0, 1.0]",
        "slabs = \"auto\"\nslab_factor = 2.0",
        "",
        &fbm(5.0),
    ));
    assert!(f2 == 2 * n1 || f2 == 2 * n1 - 1, "{n1} → {f2}");
    // Perlin noise has one octave: its finest frequency is its frequency.
    let perlin = "[material.m]\ndetail = { kind = \"perlin\", frequency = 40.0, octaves = 3 }\n\
                  gradient = [[0.0, 1.0, 1.0, 1.0, 0.5]]\n";
    let np = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", perlin));
    // 2 · 40 · 2 = 160 (octaves ignored), not 2 · 40 · 4² · 2.
    assert!((160..=161).contains(&np), "{np}");
}

#[test]
fn periods_are_measured_in_world_units_along_the_view() {
    const AUTO: &str = "slabs = \"auto\"";
    let n1 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(5.0)));
    // Scaled by 2 the box is 4 deep and its detail twice as coarse in world units: the
    // same number of periods over the depth, the same count.
    let scaled = count(&scene("[0.0, 0.0, 1.0]", AUTO, "scale = 2.0", &fbm(5.0)));
    assert_eq!(scaled, n1);
    // A second, constant box behind it doubles the depth range: twice the slabs.
    let two = format!(
        "{}\n[[mesh]]\nshape = \"box\"\nsize = [2.0, 2.0, 2.0]\ntranslate = [0.0, 0.0, 2.0]\n\
         material = \"wall\"\n[material.wall]\n",
        fbm(5.0)
    );
    let deep = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &two));
    assert!(deep == 2 * n1 || deep == 2 * n1 - 1, "{n1} → {deep}");
}

#[test]
fn a_texture_of_64_voxels_along_the_view_gets_at_least_128_slabs_over_it() {
    let texture = |dims: &str| {
        format!(
            "[material.m]\ntexture = {{ path = \"never-read.raw\", dims = {dims}, type = \"u8\" }}\n\
             gradient = [[0.0, 1.0, 1.0, 1.0, 0.5]]\n"
        )
    };
    const AUTO: &str = "slabs = \"auto\"";
    // The box spans the whole depth, so "over it" is the whole count.
    let along_z = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &texture("[4, 4, 64]")));
    assert!((128..=129).contains(&along_z), "{along_z}");
    // Seen along x, the x dimension counts.
    let along_x = count(&scene("[1.0, 0.0, 0.0]", AUTO, "", &texture("[64, 4, 4]")));
    assert!((128..=129).contains(&along_x), "{along_x}");
    // The 4 voxels along x of a [4, 4, 64] texture need 8 slabs: the minimum of 64 applies.
    let coarse = count(&scene("[1.0, 0.0, 0.0]", AUTO, "", &texture("[4, 4, 64]")));
    assert_eq!(coarse, super::AUTO_MIN_SLABS as u32);
    // Along the diagonal of x and z, one world unit crosses (1/√2)·(4/2) voxels in x and
    // (1/√2)·(64/2) in z: √(2² + 32²)/√2 voxels per world unit, one voxel the period.
    let rate = (2.0f64 * 2.0 + 32.0 * 32.0).sqrt() / 2f64.sqrt();
    let g = SceneGeometry::build(
        &scene("[1.0, 0.0, 1.0]", AUTO, "", &texture("[4, 4, 64]")),
        &GeometryFiles::default(),
    )
    .unwrap();
    let period = g.auto_slabs.unwrap().finest_period.unwrap();
    assert!((period - 1.0 / rate).abs() < 1e-12 * rate, "{period}");
}

#[test]
fn a_scene_without_detail_gets_the_minimum() {
    let s = scene("[0.0, 0.0, 1.0]", "slabs = \"auto\"", "", "[material.m]\n");
    assert_eq!(count(&s), super::AUTO_MIN_SLABS as u32);
    let a = SceneGeometry::build(&s, &GeometryFiles::default())
        .unwrap()
        .auto_slabs
        .unwrap();
    // The 2-deep box is the only feature: 2 slabs across it need 1 · 2 slabs over its 2 units of
    // depth, fewer than the minimum.
    assert!(a.minimum);
    assert_eq!(a.limited_by.as_deref(), Some("mesh[0] thickness"));
    let t = a.finest_period.unwrap();
    assert!((t - 2.0).abs() < 1e-6, "{t}");
}

/// A scene 3 units deep: a `size` box (its thickness along z) at the origin, in front of a
/// 1×1×1 box whose back is 3 units behind the plate's front, seen along z (or `direction`).
fn plate_scene(size: [f64; 3], rotate: [f64; 3], sweep: &str, material: &str) -> Scene {
    let [sx, sy, sz] = size;
    let [rx, ry, rz] = rotate;
    let text = format!(
        r#"
[image]
width = 128
height = 128
[camera]
direction = [0.0, 0.0, 1.0]
view_width = 6.0
[sweep]
optimal_distance = 1.0
{sweep}
[[mesh]]
shape = "box"
size = [{sx}, {sy}, {sz}]
rotate_deg = [{rx}, {ry}, {rz}]
material = "m"
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
translate = [0.0, 0.0, 2.5]
material = "wall"
[material.wall]
{material}
"#
    );
    Scene::parse(&text, "plate.toml", Path::new(".")).unwrap()
}

fn depth(s: &Scene) -> f64 {
    let g = SceneGeometry::build(s, &GeometryFiles::default()).unwrap();
    g.slab_distance * f64::from(g.slabs)
}

#[test]
fn a_thin_plate_gets_two_slabs_across_its_thickness() {
    const AUTO: &str = "slabs = \"auto\"";
    // A 0.03 thick plate from z = −0.015 to a box whose back is at 3.0: 3.015 deep (plus one
    // part in 10⁶), 2 · 3.015 / 0.03 = 201 slabs.
    let s = plate_scene([4.0, 4.0, 0.03], [0.0; 3], AUTO, "[material.m]\n");
    let n = count(&s);
    assert!((201..=202).contains(&n), "{n}");
    let a = SceneGeometry::build(&s, &GeometryFiles::default())
        .unwrap()
        .auto_slabs
        .unwrap();
    assert_eq!(a.limited_by.as_deref(), Some("mesh[0] thickness"));
    assert!(!a.minimum);
    assert_eq!(a.thinnest.unwrap().mesh, 0);
    assert!((a.finest_period.unwrap() - 0.03).abs() < 1e-6, "{a:?}");
    // slab_factor multiplies it.
    let f = count(&plate_scene(
        [4.0, 4.0, 0.03],
        [0.0; 3],
        "slabs = \"auto\"\nslab_factor = 1.5",
        "[material.m]\n",
    ));
    assert!((301..=303).contains(&f), "{f}");
    // A thick plate (0.5): 2 · 3.25 / 0.5 = 13 < 64, the minimum.
    let thick = plate_scene([4.0, 4.0, 0.5], [0.0; 3], AUTO, "[material.m]\n");
    assert_eq!(count(&thick), super::AUTO_MIN_SLABS as u32);
}

#[test]
fn a_tilted_plate_is_as_thick_as_its_thickness_over_the_cosine() {
    const AUTO: &str = "slabs = \"auto\"";
    for deg in [30.0f64, 60.0] {
        let s = plate_scene([3.0, 3.0, 0.03], [deg, 0.0, 0.0], AUTO, "[material.m]\n");
        let g = SceneGeometry::build(&s, &GeometryFiles::default()).unwrap();
        let a = g.auto_slabs.clone().unwrap();
        let along = 0.03 / deg.to_radians().cos();
        let t = a.finest_period.unwrap();
        // The faces are planes: every sampled pixel inside the plate sees the same gap, up to
        // the f32 depth plane and the fixed-point vertices (1/256 px of slope tan θ).
        assert!((t - along).abs() < 1e-4, "{deg}°: {t} vs {along}");
        let expect = (2.0 * depth(&s) / along).ceil() as u32;
        assert!(
            g.slabs.abs_diff(expect) <= 1,
            "{deg}°: {} vs {expect}",
            g.slabs
        );
        assert_eq!(a.limited_by.as_deref(), Some("mesh[0] thickness"));
    }
}

#[test]
fn detail_and_a_thin_plate_take_the_larger_count() {
    const AUTO: &str = "slabs = \"auto\"";
    let fbm = |f: f64| {
        format!(
            "detail = {{ kind = \"fbm\", frequency = {f}, octaves = 1 }}\n\
             gradient = [[0.0, 1.0, 1.0, 1.0, 0.5]]\n[material.m]\n"
        )
    };
    // Detail on the back box with period 1/100 (< the plate's 0.03): the detail sets the count,
    // 2 · 3.015 · 100 = 603.
    let s = plate_scene([4.0, 4.0, 0.03], [0.0; 3], AUTO, &fbm(100.0));
    let n = count(&s);
    assert!((603..=604).contains(&n), "{n}");
    let a = SceneGeometry::build(&s, &GeometryFiles::default())
        .unwrap()
        .auto_slabs
        .unwrap();
    assert_eq!(a.limited_by.as_deref(), Some("material.wall.detail"));
    assert!((a.thinnest.unwrap().thickness - 0.03).abs() < 1e-6);
    // Period 1/10 (> 0.03): the plate sets it, 201.
    let s = plate_scene([4.0, 4.0, 0.03], [0.0; 3], AUTO, &fbm(10.0));
    let n = count(&s);
    assert!((201..=202).contains(&n), "{n}");
}

#[test]
fn a_very_thin_plate_is_an_error_naming_the_key_and_the_mesh() {
    // 1e-5 thick: 2 · 3 / 1e-5 = 6·10⁵ slabs, above the bound (but above the 3·10⁻⁶ epsilon).
    let s = plate_scene(
        [4.0, 4.0, 1e-5],
        [0.0; 3],
        "slabs = \"auto\"",
        "[material.m]\n",
    );
    let e = SceneGeometry::build(&s, &GeometryFiles::default()).unwrap_err();
    assert!(matches!(e, GeometryError::TooManyAutoSlabs { .. }), "{e}");
    let msg = e.to_string();
    for words in ["plate.toml", "sweep.slabs", "mesh[0] thickness", "65536"] {
        assert!(msg.contains(words), "{words}: {msg}");
    }
    // Thinner than the epsilon (1e-6 of the depth): a zero-thickness sheet, ignored.
    let s = plate_scene(
        [4.0, 4.0, 1e-7],
        [0.0; 3],
        "slabs = \"auto\"",
        "[material.m]\n",
    );
    assert_eq!(count(&s), super::AUTO_MIN_SLABS as u32);
    // A count given keeps its count.
    let s = plate_scene([4.0, 4.0, 1e-5], [0.0; 3], "slabs = 16", "[material.m]\n");
    assert_eq!(
        SceneGeometry::build(&s, &GeometryFiles::default())
            .unwrap()
            .slabs,
        16
    );
}

#[test]
fn a_sphere_is_not_thin_at_its_silhouette() {
    // Near a curved silhouette the entry-to-exit chord goes to zero; the antiparallel rule
    // keeps only chords where the two normals are within 20° of opposite: ≥ 2r·cos 10°.
    let text = r#"
[image]
width = 256
height = 256
[camera]
direction = [0.3, 0.2, 1.0]
view_width = 2.5
[sweep]
slabs = "auto"
optimal_distance = 1.0
[[mesh]]
shape = "sphere"
size = [1.0, 5]
material = "m"
[material.m]
"#;
    let s = Scene::parse(text, "sphere.toml", Path::new(".")).unwrap();
    let g = SceneGeometry::build(&s, &GeometryFiles::default()).unwrap();
    let a = g.auto_slabs.unwrap();
    let t = a.thinnest.unwrap().thickness;
    assert!(t >= 2.0 * 0.99 * 10f64.to_radians().cos(), "{t}");
    assert!(a.minimum);
    assert_eq!(g.slabs, super::AUTO_MIN_SLABS as u32);
}

#[test]
fn too_many_auto_slabs_is_an_error_naming_the_key() {
    let s = scene("[0.0, 0.0, 1.0]", "slabs = \"auto\"", "", &fbm(1e5));
    let e = SceneGeometry::build(&s, &GeometryFiles::default()).unwrap_err();
    assert!(matches!(e, GeometryError::TooManyAutoSlabs { .. }), "{e}");
    let msg = e.to_string();
    for words in ["auto.toml", "sweep.slabs", "material.m.detail", "65536"] {
        assert!(msg.contains(words), "{words}: {msg}");
    }
}

#[test]
fn bad_auto_keys_are_refused_by_name() {
    let text = |sweep: &str| {
        format!(
            "[image]\nwidth = 8\nheight = 8\n[camera]\nview_width = 2.0\n[sweep]\n\
             optimal_distance = 1.0\n{sweep}\n[[mesh]]\nshape = \"box\"\n\
             size = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n[material.m]\n"
        )
    };
    for (sweep, key, words) in [
        ("slabs = \"many\"", "sweep.slabs", "\"auto\""),
        ("slabs = -3", "sweep.slabs", "got -3"),
        ("slabs = 16\nslab_factor = 2.0", "sweep.slab_factor", "auto"),
        (
            "slabs = \"auto\"\nslab_factor = 0.0",
            "sweep.slab_factor",
            "expected a number",
        ),
        (
            "slabs = \"auto\"\nslab_factor = 1e9",
            "sweep.slab_factor",
            "1.024e3",
        ),
    ] {
        let e = Scene::parse(&text(sweep), "bad.toml", Path::new(".")).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(key) && msg.contains(words), "{sweep}: {msg}");
    }
}
