//! `convshadow render` from the command line: the default scene, outputs, stats, refusals.

use crate::support;

#[test]
fn render_without_arguments_writes_render_png_of_the_default_scene() {
    let dir = support::temp_dir("render-default");
    let (code, out, err) = support::run_cli(
        &["render", "--width", "96", "--height", "96", "--slabs", "64"],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(!err.contains("panicked"));
    let png = dir.join("render.png");
    assert!(png.is_file(), "render.png not written: {out}");
    assert!(
        out.contains("render.png"),
        "the summary names the output: {out}"
    );
    let img = convshadow::io::image::RgbImage::load(&png).unwrap();
    assert_eq!((img.width, img.height), (96, 96));
    // Not a flat image: the default scene has coloured objects, shadows and a background.
    let (lo, hi) = img
        .data
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert!(hi - lo > 0.3, "image looks flat: {lo}..{hi}");
}

#[test]
fn repeated_outputs_png_and_exr_and_stats_json() {
    let dir = support::temp_dir("render-outputs");
    let (code, out, err) = support::run_cli(
        &[
            "render",
            "--width",
            "40",
            "--height",
            "32",
            "--slabs",
            "32",
            "-o",
            "a.png",
            "-o",
            "b.exr",
            "--stats-json",
            "s.json",
            "--kernel",
            "poisson8",
            "--threads",
            "3",
            "--quiet",
            // The plain encoding (the default scene maps its PNG with exposure −1 and aces).
            "--tonemap",
            "clamp",
            "--exposure",
            "0",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.is_empty(), "--quiet prints nothing: {out}");
    let exr = convshadow::io::image::RgbImage::load(&dir.join("b.exr")).unwrap();
    let png = convshadow::io::image::RgbImage::load(&dir.join("a.png")).unwrap();
    assert_eq!(
        exr.to_srgb8(),
        png.to_srgb8(),
        "with clamp and no exposure, the PNG is the sRGB encoding of the EXR"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    for key in [
        "width",
        "height",
        "slabs",
        "slab_distance",
        "kernel",
        "lights",
        "fragments",
        "odd_pixels",
        "threads",
        "path",
        "backend",
        "seconds_ldi",
        "seconds_sweep",
        "seconds_total",
        "pixel_slab_lights_per_second",
        "image_hash",
    ] {
        assert!(!v[key].is_null(), "missing {key}: {v}");
    }
    assert_eq!(v["kernel"], "poisson8");
    assert_eq!(v["media"], "second-order");
    assert!(v["subpixel_shadows"].is_boolean(), "{v}");
    assert_eq!(v["threads"], 3);
    // The EXR holds exactly the hashed float image.
    assert_eq!(
        format!(
            "{:016x}",
            convshadow::pipeline::image_fingerprint(&exr.data)
        ),
        v["image_hash"].as_str().unwrap()
    );
}

#[test]
fn open_meshes_render_as_thin_shells_with_a_warning() {
    // The teapot (160 boundary edges) and the cube without a bottom are not closed: they render
    // as thin shells (exit 0), each with a warning naming the mesh, where they were refused with
    // exit code 6 before.
    let Some(models) = support::models_dir() else {
        return;
    };
    let dir = support::temp_dir("render-open");
    for name in ["teapot.obj", "cube_no_bottom.obj"] {
        let scene = dir.join("open.toml");
        std::fs::write(&scene, support::obj_scene(&models.join(name), 48, 8.0)).unwrap();
        let s = scene.to_str().unwrap();
        let (code, _, err) = support::run_cli(&["render", s, "-o", "x.png"], &dir);
        assert_eq!(code, 0, "{name}: {err}");
        assert!(
            err.contains("warning: mesh[0] is not closed") && err.contains("thin shell"),
            "{name}: {err}"
        );
        assert!(dir.join("x.png").is_file(), "{name}");
        std::fs::remove_file(dir.join("x.png")).unwrap();
    }
}

#[test]
fn backend_reference_renders_the_sweeps_view_samples_with_reference_light() {
    // One opaque box and nothing between it and the light: the reference's light is exactly 1
    // (every shadow ray leaves the scene unblocked), so its image is the sweep's up to f32
    // rounding of 1·colour (the images differ only by the shadow error).
    let dir = support::temp_dir("render-reference");
    std::fs::write(dir.join("lone.toml"), support::lone_box_scene(16, 8)).unwrap();
    let (code, out, err) = support::run_cli(&["render", "lone.toml", "-o", "cpu.exr"], &dir);
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = support::run_cli(
        &[
            "render",
            "lone.toml",
            "--backend",
            "reference",
            "--reference-samples",
            "16",
            "-o",
            "ref.exr",
            "--stats-json",
            "s.json",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("reference: 16 light directions"),
        "the summary names the backend: {out}"
    );
    let load = |n: &str| convshadow::io::image::RgbImage::load(&dir.join(n)).unwrap();
    let (cpu, reference) = (load("cpu.exr"), load("ref.exr"));
    assert_eq!(cpu.data.len(), reference.data.len());
    for (a, b) in cpu.data.iter().zip(&reference.data) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(v["backend"], "reference");
    assert_eq!(v["reference_samples"], 16);
}

#[test]
fn reference_samples_are_checked() {
    let dir = support::temp_dir("render-reference-args");
    let (code, _, err) = support::run_cli(
        &[
            "render",
            "--backend",
            "reference",
            "--reference-samples",
            "0",
        ],
        &dir,
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--reference-samples"), "{err}");
    let (code, _, err) = support::run_cli(&["render", "--reference-samples", "4"], &dir);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("only applies to --backend reference"), "{err}");
    assert!(!dir.join("render.png").exists(), "nothing is written");
}

#[test]
fn slabs_auto_is_printed_and_written_to_the_stats() {
    let dir = support::temp_dir("render-auto-slabs");
    // A 2-deep box of fBm at frequency 5, 3 octaves of lacunarity 2: finest period 1/20, so
    // 2 · 20 · 2 = 80 slabs (81 with the depth's widening by one part in 10⁶).
    let scene = r#"
[image]
width = 16
height = 16
[camera]
view_width = 4.0
[sweep]
slabs = 8
optimal_distance = 1.0
[[mesh]]
shape = "box"
size = [2.0, 2.0, 2.0]
material = "m"
[material.m]
detail = { kind = "fbm", frequency = 5.0, octaves = 3, lacunarity = 2.0 }
gradient = [[0.0, 1.0, 1.0, 1.0, 0.2]]
"#;
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let (code, out, err) = support::run_cli(
        &[
            "render",
            "s.toml",
            "--slabs",
            "auto",
            "-o",
            "a.exr",
            "--stats-json",
            "s.json",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("81 slabs (auto: 2 per finest period 5.000e-2 of material.m.detail"),
        "{out}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(v["slabs"], 81, "{v}");
    assert_eq!(v["slabs_auto"]["limited_by"], "material.m.detail", "{v}");
    assert_eq!(v["slabs_auto"]["slab_factor"], 1.0, "{v}");
    // A count on the command line: no auto note, `slabs_auto` null.
    let (code, out, err) = support::run_cli(
        &[
            "render",
            "s.toml",
            "--slabs",
            "12",
            "-o",
            "b.exr",
            "--stats-json",
            "t.json",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("12 slabs,") && !out.contains("auto"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("t.json")).unwrap()).unwrap();
    assert!(v["slabs_auto"].is_null(), "{v}");
    // A word other than auto is a bad argument naming the flag.
    let (code, _, err) = support::run_cli(&["render", "s.toml", "--slabs", "many"], &dir);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--slabs") && err.contains("auto"), "{err}");
}

#[test]
fn slabs_auto_names_the_thinnest_mesh_in_the_summary_and_the_stats() {
    let dir = support::temp_dir("render-auto-thin");
    // A 0.03 plate at z = 0 in front of a unit box reaching z = 3: 3.015 deep, 2 slabs across
    // 0.03: 2 · 3.015 / 0.03 = 201, 202 with the depth's widening by one part in 10⁶.
    let scene = r#"
[image]
width = 32
height = 32
[camera]
view_width = 6.0
[sweep]
slabs = "auto"
optimal_distance = 1.0
[[mesh]]
shape = "box"
size = [4.0, 4.0, 0.03]
material = "m"
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
translate = [0.0, 0.0, 2.5]
material = "m"
[material.m]
"#;
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let (code, out, err) = support::run_cli(
        &["render", "s.toml", "-o", "a.exr", "--stats-json", "s.json"],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains(
            "202 slabs (auto: 2 across the thinnest feature 3.000e-2 of mesh[0] thickness"
        ),
        "{out}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(v["slabs"], 202, "{v}");
    let a = &v["slabs_auto"];
    assert_eq!(a["limited_by"], "mesh[0] thickness", "{v}");
    assert_eq!(a["minimum"], false, "{v}");
    assert_eq!(a["thinnest"]["mesh"], 0, "{v}");
    let t = a["thinnest"]["thickness"].as_f64().unwrap();
    assert!((t - 0.03).abs() < 1e-6, "{v}");
    // A plate too thin for 65536 slabs: exit code 4 naming the key and the mesh.
    std::fs::write(dir.join("t.toml"), scene.replace("0.03]", "0.00001]")).unwrap();
    let (code, out, err) = support::run_cli(&["render", "t.toml", "-o", "b.exr"], &dir);
    assert_eq!(code, 4, "{out}{err}");
    assert!(
        err.contains("sweep.slabs") && err.contains("mesh[0] thickness"),
        "{err}"
    );
}

#[test]
fn a_world_direction_light_renders_like_its_tilt_and_bad_ones_exit_3() {
    // A box over a wall, shadowed by one light given as a camera-space tilt or as the world
    // direction it travels (the default camera looks along +z with +y up).
    let dir = support::temp_dir("render-direction");
    let scene = |light: &str| {
        format!(
            "[image]\nwidth = 48\nheight = 48\n[camera]\nview_width = 4.0\n[sweep]\nslabs = 48\n\
             [[light]]\n{light}\n\
             [[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 0.4]\nmaterial = \"m\"\n\
             [[mesh]]\nshape = \"box\"\nsize = [8.0, 8.0, 0.2]\ntranslate = [0.0, 0.0, 1.5]\n\
             material = \"m\"\n[material.m]\ncolor = [0.8, 0.6, 0.4]\n"
        )
    };
    let hash = |name: &str, light: &str| {
        std::fs::write(dir.join(name), scene(light)).unwrap();
        let (code, out, err) = support::run_cli(
            &[
                "render",
                name,
                "-o",
                "x.exr",
                "--quiet",
                "--stats-json",
                "s.json",
            ],
            &dir,
        );
        assert_eq!(code, 0, "{name}: {out}{err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
        v["image_hash"].as_str().unwrap().to_string()
    };
    assert_eq!(
        hash(
            "tilt.toml",
            "tilt_deg = [0.0, 0.0]\nvariance = [0.02, 0.01]"
        ),
        hash(
            "dir.toml",
            "direction = [0.0, 0.0, 1.0]\nvariance = [0.02, 0.01]"
        ),
        "a light along the view"
    );
    // Tilted 30° (world +x is the image's left). A world light's variances are those of its
    // own directions: on the slab plane its slopes vary σx²/cos⁴ω along the tilt and σy²/cos²ω
    // across it (scene-format.md), which the tilt light is given here: the same image up to
    // the last bits.
    let (a, c) = (30f64.to_radians().tan(), 30f64.to_radians().cos());
    let render_exr = |name: &str, light: &str| {
        std::fs::write(dir.join(name), scene(light)).unwrap();
        let (code, _, err) = support::run_cli(&["render", name, "-o", "x.exr", "--quiet"], &dir);
        assert_eq!(code, 0, "{name}: {err}");
        convshadow::io::image::RgbImage::load(&dir.join("x.exr"))
            .unwrap()
            .data
    };
    let slab_plane = format!(
        "tilt_deg = [30.0, 0.0]\nvariance = [{}, {}]",
        0.02 / c.powi(4),
        0.01 / c.powi(2)
    );
    let ia = render_exr("tilt30.toml", &slab_plane);
    let ib = render_exr(
        "dir30.toml",
        &format!("direction = [{a}, 0.0, 1.0]\nvariance = [0.02, 0.01]"),
    );
    let worst = ia
        .iter()
        .zip(&ib)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "largest difference {worst}");
    // Bad lights: exit code 3, the key named, no output file.
    for (light, words) in [
        ("direction = [1.0, 0.0, 0.0]", "light[0].direction"),
        ("direction = [0.0, 0.0, 0.0]", "light[0].direction"),
        (
            "direction = [0.0, 0.0, 1.0]\ntilt_deg = [5.0, 0.0]",
            "not both",
        ),
        // A spot light is valid, but the sweep needs every mesh wholly on one side of it: one
        // beside the box, within its depth range, is refused naming the position and the box.
        (
            "kind = \"spot\"\nposition = [2.0, 0.0, 0.1]\nradius = 0.1\ndirection = [0.0, 0.0, -1.0]\ncone_deg = 20.0",
            "light[0].position`: the light's centre lies at view depth 0.100000, within mesh[0]",
        ),
        ("kind = \"spot\"", "light[0].position"),
    ] {
        std::fs::write(dir.join("bad.toml"), scene(light)).unwrap();
        let (code, _, err) =
            support::run_cli(&["render", "bad.toml", "-o", "bad.png", "--quiet"], &dir);
        assert_eq!(code, 3, "{light}: {err}");
        assert!(
            err.contains("bad.toml") && err.contains(words),
            "{light}: {err}"
        );
        assert!(
            !dir.join("bad.png").exists(),
            "{light}: an output was written"
        );
    }
    // Between the box and the wall it is amid the meshes: two passes, rendered.
    std::fs::write(
        dir.join("amid.toml"),
        scene("kind = \"spot\"\nposition = [2.0, 0.0, 0.8]\nradius = 0.1\ndirection = [-1.0, 0.0, -1.0]\ncone_deg = 40.0"),
    )
    .unwrap();
    let (code, _, err) =
        support::run_cli(&["render", "amid.toml", "-o", "amid.png", "--quiet"], &dir);
    assert_eq!(code, 0, "amid: {err}");
    assert!(dir.join("amid.png").exists());
}
