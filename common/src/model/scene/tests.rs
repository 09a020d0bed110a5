//! Scene parsing and validation tests.

use super::*;

const MINIMAL: &str = r#"
[image]
width = 64
height = 32
[camera]
view_width = 2.0
[sweep]
slabs = 16
optimal_distance = 0.5
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
material = "m"
[material.m]
"#;

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, "test.toml", Path::new("."))
}

#[test]
fn defaults_are_the_documented_ones() {
    let s = parse(MINIMAL).unwrap();
    assert_eq!(s.camera.direction, [0.0, 0.0, 1.0]);
    assert_eq!(s.camera.up, [0.0, 1.0, 0.0]);
    assert_eq!(s.camera.center, [0.0; 3]);
    assert_eq!(s.image.background, [0.0; 3]);
    assert_eq!(s.sweep.kernel, KernelSpec::default());
    assert!(s.sweep.jitter);
    assert_eq!(s.sweep.seed, 0);
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.lights[0].color, [1.0; 3]);
    assert_eq!(s.meshes[0].scale, 1.0);
    assert_eq!(s.materials[0].transport, [0.0; 3]);
    assert_eq!(s.materials[0].reference_length, None);
    assert_eq!(s.sweep.media, Media::SecondOrder);
    assert!(s.is_monochrome());
}

#[test]
fn the_embedded_default_scene_parses() {
    let s = Scene::default_scene();
    assert!(s.lights.len() >= 2);
    assert!(
        s.meshes
            .iter()
            .all(|m| !matches!(m.shape, ShapeSpec::Obj { .. }))
    );
}

fn expect_err(text: &str, key: &str, words: &str) {
    let e = parse(text).expect_err("must be rejected");
    let msg = e.to_string();
    assert!(msg.contains("test.toml"), "{msg}");
    assert!(msg.contains(key), "message should name key {key}: {msg}");
    assert!(msg.contains(words), "message should say {words}: {msg}");
}

#[test]
fn invalid_values_name_file_key_and_expectation() {
    expect_err(
        &MINIMAL.replace("width = 64", "width = 0"),
        "image.width",
        "1 to 16384",
    );
    expect_err(
        &MINIMAL.replace("width = 64", "width = 100000"),
        "image.width",
        "16384",
    );
    expect_err(
        &MINIMAL.replace("slabs = 16", "slabs = 16\nmedia = \"exact\""),
        "sweep.media",
        "expected \"second-order\" or \"first-order\"",
    );
    let first = parse(&MINIMAL.replace("slabs = 16", "slabs = 16\nmedia = \"first-order\""));
    assert_eq!(first.unwrap().sweep.media, Media::FirstOrder);
    expect_err(
        &MINIMAL.replace("slabs = 16", "slabs = 0"),
        "sweep.slabs",
        "1 to",
    );
    expect_err(
        &MINIMAL.replace("slabs = 16", "slab_distance = 0.0"),
        "sweep.slab_distance",
        "> 0",
    );
    expect_err(
        &MINIMAL.replace("slabs = 16", ""),
        "sweep.slabs",
        "expected one of",
    );
    expect_err(
        &format!("{MINIMAL}\n[[light]]\ntilt_deg = [90.0, 0.0]\n"),
        "light[0].tilt_deg[0]",
        "< 90",
    );
    expect_err(
        &format!("{MINIMAL}\n[[light]]\nvariance = [-1.0, 0.0]\n"),
        "light[0].variance[0]",
        ">= 0",
    );
    expect_err(
        &MINIMAL.replace("size = [1.0, 1.0, 1.0]", "size = [1.0, 0.0, 1.0]"),
        "mesh[0].size[1]",
        "> 0",
    );
    expect_err(
        &MINIMAL.replace("material = \"m\"", "material = \"x\""),
        "mesh[0].material",
        "no material named",
    );
    expect_err(
        &MINIMAL.replace("view_width = 2.0", "view_width = nan"),
        "camera.view_width",
        "finite",
    );
    expect_err(
        &MINIMAL.replace("view_width = 2.0", "view_width = inf"),
        "camera.view_width",
        "finite",
    );
    expect_err(
        &MINIMAL.replace("shape = \"box\"", "shape = \"cone\""),
        "mesh[0].shape",
        "expected one of",
    );
    expect_err(
        &MINIMAL.replace("slabs = 16", "slabs = 16\nkernel = \"blur\""),
        "sweep.kernel",
        "ellipse",
    );
}

#[test]
fn syntax_unknown_keys_and_wrong_types_are_errors() {
    expect_err(
        &MINIMAL.replace("height = 32", "height = 32\ncolour = 3"),
        "",
        "unknown field `colour`",
    );
    expect_err(
        &MINIMAL.replace("height = 32", "height = \"tall\""),
        "height",
        "line 4",
    );
    // Without the [camera] header its key lands in [image]: an unknown field there.
    let e = parse(&MINIMAL.replace("[camera]\n", "")).unwrap_err();
    assert!(e.to_string().contains("unknown field `view_width`"), "{e}");
    // Without the whole table: a missing required table.
    let e = parse(&MINIMAL.replace("[camera]\nview_width = 2.0\n", "")).unwrap_err();
    assert!(e.to_string().contains("missing field `camera`"), "{e}");
}

/// Issue 43, class 6: every table-typed key, at any depth (a section, an array of tables, a
/// map of tables, an inline table), refuses an array instead of reading it in field order.
#[test]
fn table_keys_refuse_arrays_at_every_depth() {
    let tail = MINIMAL.split_once("[[mesh]]").unwrap().1;
    // Top-level keys go before the first section; the others inside their table.
    let top = |key: &str, section: &str, value: &str| {
        format!("{key} = {value}\n{}", MINIMAL.replace(section, ""))
    };
    for (what, text) in [
        (
            "camera",
            top(
                "camera",
                "[camera]\nview_width = 2.0",
                "[[0, 0, 1], [0, 1, 0], [0, 0, 0], 2.0]",
            ),
        ),
        (
            "sweep",
            top(
                "sweep",
                "[sweep]\nslabs = 16\noptimal_distance = 0.5",
                "[16]",
            ),
        ),
        (
            "light",
            top("light", "", "[[[1, 1, 1], [10, 10], [0.01, 0.01]]]"),
        ),
        (
            "mesh",
            top("mesh", &format!("[[mesh]]{tail}"), "[[\"box\", [1, 1, 1]]]") + "[material.m]\n",
        ),
        (
            "material",
            MINIMAL.replace("[material.m]\n", "[material]\nm = [[1, 1, 1], 0.5]\n"),
        ),
        (
            "texture",
            format!("{MINIMAL}texture = [\"t.raw\", [2, 2, 2], \"u8\"]\n"),
        ),
    ] {
        let e = parse(&text)
            .err()
            .unwrap_or_else(|| panic!("{what}: accepted"));
        assert!(e.message.contains("expected a table"), "{what}: {e}");
        assert!(e.message.contains("line "), "{what}: {e}");
    }
    // The same keys as tables still parse; a wrong field inside one is still named.
    let ok = format!("{MINIMAL}specular = {{ exponent = 8 }}\nphase = {{ g = 0.3 }}\n");
    assert!(parse(&ok).is_ok());
    let e = parse(&format!("{MINIMAL}phase = {{ h = 0.3 }}\n")).unwrap_err();
    assert!(e.message.contains("unknown field `h`"), "{e}");
}

/// An unknown key is named with its table (`light[1].colr`, `material.m.opacty`) and the
/// closest known key.
#[test]
fn unknown_keys_name_their_table_and_the_nearest_key() {
    let two_lights =
        format!("{MINIMAL}[[light]]\ncolor = [1, 1, 1]\n[[light]]\ncolr = [1, 1, 1]\n");
    let e = parse(&two_lights).unwrap_err();
    assert_eq!(e.key, "light[1].colr", "{e}");
    assert!(e.message.contains("did you mean `color`?"), "{e}");
    let e = parse(&format!("{MINIMAL}opacty = 0.5\n")).unwrap_err();
    assert_eq!(e.key, "material.m.opacty", "{e}");
    assert!(e.message.contains("did you mean `opacity`?"), "{e}");
    // Nothing near: no suggestion.
    let e = parse(&format!("{MINIMAL}zzzzzz = 1\n")).unwrap_err();
    assert!(!e.message.contains("did you mean"), "{e}");
}

#[test]
fn a_world_direction_light_gets_the_tilt_of_its_direction_seen_by_the_camera() {
    let with = |light: &str| parse(&format!("{MINIMAL}\n[[light]]\n{light}\n"));
    // Along the view: no tilt, the bits of `tilt_deg = [0, 0]`.
    let s = with("direction = [0.0, 0.0, 2.0]").unwrap();
    assert_eq!(s.lights[0].tilt_deg, [0.0, 0.0]);
    assert!(s.lights[0].tilt_deg[0].is_sign_positive());
    assert_eq!(
        s.lights[0].world.map(|w| w.direction),
        Some([0.0, 0.0, 1.0])
    );
    // World +x is the image's left and world +y its top: travelling along (tan 30°, −tan 20°, 1)
    // moves left and down, which is a tilt of (30°, −20°) by the camera-space convention (travel
    // ∝ (−tan ωx, −tan ωy, 1), x right, y down).
    let (a, b) = (30f64.to_radians().tan(), 20f64.to_radians().tan());
    let s = with(&format!("direction = [{a}, {}, 1.0]", -b)).unwrap();
    let [wx, wy] = s.lights[0].tilt_deg;
    assert!(
        (wx - 30.0).abs() < 1e-9 && (wy + 20.0).abs() < 1e-9,
        "{wx} {wy}"
    );
}

#[test]
fn a_world_direction_light_stays_put_when_the_camera_turns() {
    let text = format!("{MINIMAL}\n[[light]]\ndirection = [1.0, 0.0, 1.0]\n");
    let mut s = parse(&text).unwrap();
    assert!((s.lights[0].tilt_deg[0] - 45.0).abs() < 1e-9);
    // Looking along +x, camera right is world +z: the light now travels to the image's right.
    s.override_camera(Some([1.0, 0.0, 0.0]), None, None)
        .unwrap();
    assert!(
        (s.lights[0].tilt_deg[0] + 45.0).abs() < 1e-9,
        "{:?}",
        s.lights[0].tilt_deg
    );
    // Looking along −z the light comes from in front of the viewer (135°): the camera turned
    // round (along +z, its x axis world −x) sees it travel +x, to its image's left: tilt +45°.
    s.override_camera(Some([0.0, 0.0, -1.0]), None, None)
        .unwrap();
    assert!(s.lights[0].toward_viewer);
    assert!(
        (s.lights[0].tilt_deg[0] - 45.0).abs() < 1e-9 && s.lights[0].tilt_deg[1] == 0.0,
        "{:?}",
        s.lights[0].tilt_deg
    );
    // Along the slab planes (90°): refused, by name.
    let e = s
        .override_camera(Some([1.0, 0.0, -1.0]), None, None)
        .expect_err("a light along the slab planes");
    let msg = e.to_string();
    assert!(
        msg.contains("light[0].direction") && msg.contains("90.0°"),
        "{msg}"
    );
    assert!(msg.contains("after --camera-direction"), "{msg}");
}

#[test]
fn a_light_towards_the_viewer_is_a_second_pass_with_the_camera_turned_round() {
    let text = format!(
        "{MINIMAL}\n[[light]]\ndirection = [0.0, 0.0, 1.0]\n[[light]]\ncolor = [0.5, 0.5, 0.5]\n\
         direction = [0.0, -1.0, -1.0]\n[[light]]\ndirection = [1.0, 0.0, -3.0]\n"
    );
    let s = parse(&text).unwrap();
    assert_eq!(
        s.lights.iter().map(|l| l.toward_viewer).collect::<Vec<_>>(),
        [false, true, true]
    );
    let passes = s.passes();
    let front = passes
        .front
        .as_ref()
        .expect("a light from behind the viewer");
    let back = passes.back.as_ref().expect("lights from in front of it");
    assert_eq!((front.lights.len(), back.lights.len()), (1, 2));
    assert!(!front.turned_round && back.turned_round);
    assert_eq!(back.camera.direction, [0.0, 0.0, -1.0]);
    // The background is composited once, in the front pass.
    assert_eq!(back.image.background, [0.0; 3]);
    assert_eq!(front.image.background, s.image.background);
    // Light 1 travels down and towards the camera: the turned-round camera (x = world −x,
    // y = world −y) sees it travel towards its image's bottom, tilt ωy = atan(−y/z) = −45°.
    let l1 = &back.lights[0];
    assert_eq!(l1.color, [0.5; 3]);
    assert!(
        l1.tilt_deg[0].abs() < 1e-12 && (l1.tilt_deg[1] + 45.0).abs() < 1e-9,
        "{l1:?}"
    );
    // Light 2 travels +x: the turned camera's image right (its x axis is world +x, the
    // image's is world −x), ωx = −atan(1/3).
    let wx = back.lights[1].tilt_deg[0];
    assert!(
        (wx + (1.0f64 / 3.0).atan().to_degrees()).abs() < 1e-9,
        "{wx}"
    );
    assert_eq!(passes.light(&s, 0), (0, 0));
    assert_eq!(passes.light(&s, 1), (1, 0));
    assert_eq!(passes.light(&s, 2), (1, 1));
    // Only lights towards the viewer: one pass, which keeps the background.
    let text = format!("{MINIMAL}\n[[light]]\ndirection = [0.0, 0.0, -1.0]\n");
    let passes = parse(&text).unwrap().passes();
    assert!(passes.front.is_none());
    assert_eq!(
        passes.back.expect("the back pass").image.background,
        parse(&text).unwrap().image.background
    );
}

#[test]
fn bad_light_kinds_and_directions_name_the_key() {
    let light = |l: &str| format!("{MINIMAL}\n[[light]]\n{l}\n");
    expect_err(
        &light("direction = [0.0, 0.0, 0.0]"),
        "light[0].direction",
        "non-zero",
    );
    expect_err(
        &light("direction = [nan, 0.0, 1.0]"),
        "light[0].direction",
        "finite",
    );
    expect_err(
        &light("direction = [0.0, 0.0, 1.0]\ntilt_deg = [10.0, 0.0]"),
        "light[0]",
        "not both",
    );
    expect_err(
        &light("direction = [1.0, 0.0, 0.0]"),
        "light[0].direction",
        "90.0° to the view direction",
    );
    // A point light's key on a directional light is named as such.
    expect_err(
        &light("position = [0.0, 1.0, -2.0]"),
        "light[0].position",
        "only applies to point and spot lights",
    );
    expect_err(
        &light("kind = \"laser\""),
        "light[0].kind",
        "expected \"directional\"",
    );
    assert!(parse(&light("kind = \"directional\"")).is_ok());
}

#[test]
fn light_resolution_is_in_range() {
    let with = |camera: &str, r: &str| {
        format!(
            "[image]\nwidth = 8\nheight = 8\n[camera]\n{camera}\n[sweep]\nslabs = 4\n{r}\n[[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n[material.m]\n"
        )
    };
    let persp = "projection = \"perspective\"\neye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = 40.0";
    assert_eq!(
        parse(&with(persp, "light_resolution = 2.5"))
            .unwrap()
            .sweep
            .light_resolution,
        2.5
    );
    assert_eq!(parse(&with(persp, "")).unwrap().sweep.light_resolution, 1.0);
    assert_eq!(
        parse(&with("view_width = 2.0", "light_resolution = 1.0"))
            .unwrap()
            .sweep
            .light_resolution,
        1.0
    );
    expect_err(
        &with(persp, "light_resolution = 17.0"),
        "sweep.light_resolution",
        "1.6e1",
    );
    expect_err(
        &with(persp, "light_resolution = 0.0"),
        "sweep.light_resolution",
        "",
    );
    expect_err(
        &with(persp, "light_resolution = nan"),
        "sweep.light_resolution",
        "finite",
    );
    // An orthographic camera takes one too (its eye then reads a grid of its own).
    assert_eq!(
        parse(&with("view_width = 2.0", "light_resolution = 0.5"))
            .unwrap()
            .sweep
            .light_resolution,
        0.5
    );
}

#[test]
fn point_and_spot_lights_keep_their_place_size_and_cone() {
    let light = |l: &str| parse(&format!("{MINIMAL}\n[[light]]\n{l}\n")).unwrap();
    let s = light("kind = \"point\"\nposition = [0.0, 1.0, -2.0]\nradius = 0.1");
    let p = s.lights[0].point.expect("a point light");
    assert_eq!(
        (p.position, p.radius, p.spot),
        ([0.0, 1.0, -2.0], 0.1, None)
    );
    // Tilt and spread are a directional light's: 0 on a point light.
    assert_eq!(
        (s.lights[0].tilt_deg, s.lights[0].variance),
        ([0.0; 2], [0.0; 2])
    );
    assert_eq!(
        light("kind = \"point\"\nposition = [1.0, 2.0, 3.0]").lights[0]
            .point
            .unwrap()
            .radius,
        0.0
    );
    let s = light(
        "kind = \"spot\"\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, -2.0, 0.0]\ncone_deg = 20.0\nfalloff_deg = 5.0",
    );
    let spot = s.lights[0].point.unwrap().spot.expect("a spot");
    assert_eq!(
        (spot.direction, spot.cone_deg, spot.falloff_deg),
        ([0.0, -1.0, 0.0], 20.0, 5.0)
    );
}

#[test]
fn bad_point_and_spot_lights_name_the_key() {
    let light = |l: &str| format!("{MINIMAL}\n[[light]]\n{l}\n");
    let point = |l: &str| {
        light(&format!(
            "kind = \"point\"\nposition = [0.0, 1.0, -2.0]\n{l}"
        ))
    };
    let spot = |l: &str| {
        light(&format!(
            "kind = \"spot\"\nposition = [0.0, 1.0, -2.0]\ndirection = [0.0, 0.0, 1.0]\n{l}"
        ))
    };
    expect_err(
        &light("kind = \"point\""),
        "light[0].position",
        "expected `position",
    );
    expect_err(
        &light("kind = \"point\"\nposition = [0.0, nan, 1.0]"),
        "light[0].position[1]",
        "finite",
    );
    expect_err(&point("radius = -0.5"), "light[0].radius", "from 0");
    expect_err(&point("radius = inf"), "light[0].radius", "finite");
    expect_err(
        &point("tilt_deg = [10.0, 0.0]"),
        "light[0].tilt_deg",
        "only applies to directional",
    );
    expect_err(
        &point("variance = [0.1, 0.1]"),
        "light[0].variance",
        "only applies to directional",
    );
    expect_err(
        &point("direction = [0.0, 0.0, 1.0]"),
        "light[0].direction",
        "only applies to directional",
    );
    expect_err(
        &point("cone_deg = 20.0"),
        "light[0].cone_deg",
        "only applies to spot lights",
    );
    expect_err(
        &point("pattern = { path = \"g.png\", size = [1.0, 1.0] }"),
        "light[0].pattern",
        "only applies to directional and spot lights",
    );
    expect_err(&spot(""), "light[0].cone_deg", "expected `cone_deg`");
    expect_err(
        &spot("cone_deg = 20.0\nup = [0.0, 0.0, 2.0]"),
        "light[0].up",
        "not parallel",
    );
    expect_err(
        &point("up = [0.0, 1.0, 0.0]"),
        "light[0].up",
        "only applies to directional",
    );
    expect_err(
        &spot("cone_deg = 90.0"),
        "light[0].cone_deg",
        "from 0 to 89",
    );
    expect_err(
        &spot("cone_deg = -1.0"),
        "light[0].cone_deg",
        "from 0 to 89",
    );
    expect_err(
        &spot("cone_deg = 20.0\nfalloff_deg = 91.0"),
        "light[0].falloff_deg",
        "from 0 to 90",
    );
    expect_err(
        &light("kind = \"spot\"\nposition = [0.0, 1.0, -2.0]\ncone_deg = 20.0"),
        "light[0].direction",
        "expected `direction",
    );
    expect_err(
        &light(
            "kind = \"spot\"\nposition = [0.0, 1.0, -2.0]\ndirection = [0.0, 0.0, 0.0]\ncone_deg = 20.0",
        ),
        "light[0].direction",
        "",
    );
}

#[test]
fn a_world_lights_spread_is_turned_onto_the_slab_plane() {
    let with = |light: &str| parse(&format!("{MINIMAL}\n[[light]]\n{light}\n")).unwrap();
    // Along the view, its axes the camera's: the slab plane's own numbers, bit for bit.
    let s = with("direction = [0.0, 0.0, 1.0]\nvariance = [0.02, 0.01]\nrotation_deg = 20.0");
    let t = with("tilt_deg = [0.0, 0.0]\nvariance = [0.02, 0.01]\nrotation_deg = 20.0");
    let (a, b) = (&s.lights[0], &t.lights[0]);
    assert_eq!(
        (a.tilt_deg, a.variance, a.rotation_deg),
        (b.tilt_deg, b.variance, b.rotation_deg)
    );
    // Its up along world +x turns its frame a quarter turn on the view: its x axis is the
    // camera's −y, so its variances swap on the slab plane.
    let s = with("direction = [0.0, 0.0, 1.0]\nup = [1.0, 0.0, 0.0]\nvariance = [0.02, 0.01]");
    assert_eq!(
        (s.lights[0].variance, s.lights[0].rotation_deg),
        ([0.01, 0.02], 0.0)
    );
    // Tilted ω = 40° about the camera's y axis, isotropic σ² = 0.01: a turn θ of its direction in
    // the tilt's plane moves the slope tan(ω + θ) by θ/cos²ω, a turn across it by θ/cos ω, so the
    // slope variances are σ²/cos⁴ω and σ²/cos²ω, unrotated.
    let w = 40f64.to_radians();
    let s = with(&format!(
        "direction = [{}, 0.0, {}]\nvariance = [0.01, 0.01]",
        w.sin(),
        w.cos()
    ));
    let l = &s.lights[0];
    let expected = [0.01 / w.cos().powi(4), 0.01 / w.cos().powi(2)];
    assert!((l.tilt_deg[0] - 40.0).abs() < 1e-9, "{:?}", l.tilt_deg);
    for (got, want) in l.variance.iter().zip(expected) {
        assert!((got - want).abs() < 1e-12, "{:?}", l.variance);
    }
    assert!(l.rotation_deg.abs() < 1e-9, "{}", l.rotation_deg);
    // Straight down (a light from above a floor the camera looks at from the side would be at
    // 90°; seen from above it is along the view): the default up turns to +z.
    let top = parse(&format!(
        "{}\n[[light]]\ndirection = [0.0, -1.0, 0.0]\nvariance = [0.01, 0.03]\n",
        MINIMAL.replace(
            "view_width = 2.0",
            "view_width = 2.0\ndirection = [0.0, -1.0, 0.0]\nup = [0.0, 0.0, 1.0]"
        )
    ))
    .unwrap();
    assert_eq!(top.lights[0].world.unwrap().up, [0.0, 0.0, 1.0]);
    assert_eq!(top.lights[0].tilt_deg, [0.0, 0.0]);
    assert!((top.lights[0].variance[0] - 0.01).abs() < 1e-12);
    expect_err(
        &format!("{MINIMAL}\n[[light]]\ndirection = [0.0, 0.0, 1.0]\nup = [0.0, 0.0, 2.0]\n"),
        "light[0].up",
        "not parallel",
    );
    expect_err(
        &format!("{MINIMAL}\n[[light]]\nup = [0.0, 1.0, 0.0]\n"),
        "light[0].up",
        "only applies with `direction`",
    );
}

/// [`MINIMAL`] with its camera replaced by `camera` (the `[camera]` table's lines).
fn with_camera(camera: &str) -> String {
    MINIMAL.replace("[camera]\nview_width = 2.0", &format!("[camera]\n{camera}"))
}

#[test]
fn a_perspective_camera_looks_from_its_eye_at_its_target() {
    let s = parse(&with_camera(
        "projection = \"perspective\"\neye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, 4.0]\nfov_deg = 60",
    ))
    .unwrap();
    assert_eq!(s.camera.direction, [0.0, 0.0, 1.0]);
    assert_eq!(s.camera.center, [0.0, 0.0, -4.0]);
    assert!(s.camera.is_perspective());
    let Projection::Perspective { fov_deg, near, .. } = s.camera.projection else {
        unreachable!()
    };
    assert_eq!((fov_deg, near), (60.0, None));
    // 8 units to the target, 2·8·tan 30° high, twice that wide (64 × 32 pixels).
    let expect = 2.0 * 8.0 * (1.0f64 / 3.0).sqrt() * 2.0;
    assert!((s.camera.view_width - expect).abs() < 1e-12 * expect);
    // Orthographic stays the default.
    assert_eq!(
        parse(MINIMAL).unwrap().camera.projection,
        Projection::Orthographic
    );
}

#[test]
fn bad_perspective_cameras_name_the_key() {
    let p = "projection = \"perspective\"\n";
    let aim = "eye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, 0.0]\n";
    let err =
        |camera: String, key: &str, words: &str| expect_err(&with_camera(&camera), key, words);
    err(
        "projection = \"fisheye\"\nview_width = 2.0".to_string(),
        "camera.projection",
        "\"orthographic\" or \"perspective\"",
    );
    err(
        format!("{p}eye = [1.0, 2.0, 3.0]\nlook_at = [1.0, 2.0, 3.0]\nfov_deg = 40"),
        "camera.look_at",
        "other than camera.eye",
    );
    err(
        format!("{p}{aim}up = [0.0, 0.0, 2.0]\nfov_deg = 40"),
        "camera.up",
        "not parallel to the view",
    );
    err(
        format!("{p}{aim}fov_deg = 0.5"),
        "camera.fov_deg",
        "[1, 170]",
    );
    err(
        format!("{p}{aim}fov_deg = 171"),
        "camera.fov_deg",
        "[1, 170]",
    );
    err(format!("{p}{aim}fov_deg = nan"), "camera.fov_deg", "finite");
    err(
        format!("{p}{aim}fov_deg = 40\nnear = -1.0"),
        "camera.near",
        "",
    );
    err(
        format!("{p}look_at = [0.0, 0.0, 0.0]\nfov_deg = 40"),
        "camera.eye",
        "missing",
    );
    err(
        format!("{p}eye = [0.0, 0.0, -4.0]\nfov_deg = 40"),
        "camera.look_at",
        "missing",
    );
    err(format!("{p}{aim}"), "camera.fov_deg", "missing");
    // One projection's keys only.
    err(
        format!("{p}{aim}fov_deg = 40\nview_width = 2.0"),
        "camera.view_width",
        "orthographic camera's key",
    );
    err(
        format!("{p}{aim}fov_deg = 40\ndirection = [0.0, 0.0, 1.0]"),
        "camera.direction",
        "orthographic camera's key",
    );
    err(
        "view_width = 2.0\nfov_deg = 40".to_string(),
        "camera.fov_deg",
        "perspective camera's key",
    );
    err(
        "view_width = 2.0\neye = [0.0, 0.0, 1.0]".to_string(),
        "camera.eye",
        "perspective camera's key",
    );
    err(
        "direction = [0.0, 0.0, 1.0]".to_string(),
        "camera.view_width",
        "missing",
    );
}

#[test]
fn perspective_overrides_aim_the_camera_and_refuse_the_other_projections_flags() {
    let mut s = parse(&with_camera(
        "projection = \"perspective\"\neye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = 60",
    ))
    .unwrap();
    s.override_perspective(Some([4.0, 0.0, 0.0]), None, Some(30.0))
        .unwrap();
    assert_eq!(s.camera.direction, [-1.0, 0.0, 0.0]);
    assert_eq!(s.camera.center, [4.0, 0.0, 0.0]);
    let e = s
        .override_perspective(None, Some([4.0, 0.0, 0.0]), None)
        .unwrap_err();
    assert_eq!(e.key, "--look-at", "{e}");
    let e = s.override_perspective(None, None, Some(200.0)).unwrap_err();
    assert_eq!(e.key, "--fov", "{e}");
    let e = s.override_camera(None, None, Some(3.0)).unwrap_err();
    assert_eq!(e.key, "--view-width", "{e}");
    let mut o = parse(MINIMAL).unwrap();
    let e = o.override_perspective(None, None, Some(30.0)).unwrap_err();
    assert_eq!(e.key, "--fov", "{e}");
    o.override_perspective(None, None, None).unwrap();
}
