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
    assert_eq!((a.finest_period, a.limited_by), (None, None));
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
