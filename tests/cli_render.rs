//! `convshadow render` from the command line: the default scene, outputs, stats, refusals.

mod support;

#[test]
fn render_without_arguments_writes_render_png_of_the_default_scene() {
    let dir = support::temp_dir("render-default");
    let (code, out, err) = support::run_cli(&["render", "--width", "96", "--height", "96", "--slabs", "64"], &dir);
    assert_eq!(code, 0, "{out}{err}");
    assert!(!err.contains("panicked"));
    let png = dir.join("render.png");
    assert!(png.is_file(), "render.png not written: {out}");
    assert!(out.contains("render.png"), "the summary names the output: {out}");
    let img = convshadow::common::image_io::RgbImage::load(&png).unwrap();
    assert_eq!((img.width, img.height), (96, 96));
    // Not a flat image: the default scene has coloured objects, shadows and a background.
    let (lo, hi) = img.data.iter().fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert!(hi - lo > 0.3, "image looks flat: {lo}..{hi}");
}

#[test]
fn repeated_outputs_png_and_exr_and_stats_json() {
    let dir = support::temp_dir("render-outputs");
    let (code, out, err) = support::run_cli(
        &[
            "render", "--width", "40", "--height", "32", "--slabs", "32", "-o", "a.png", "-o", "b.exr",
            "--stats-json", "s.json", "--kernel", "poisson8", "--threads", "3", "--quiet",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.is_empty(), "--quiet prints nothing: {out}");
    let exr = convshadow::common::image_io::RgbImage::load(&dir.join("b.exr")).unwrap();
    let png = convshadow::common::image_io::RgbImage::load(&dir.join("a.png")).unwrap();
    assert_eq!(exr.to_srgb8(), png.to_srgb8(), "PNG is the sRGB encoding of the EXR");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    for key in [
        "width", "height", "slabs", "slab_distance", "kernel", "lights", "fragments", "odd_pixels", "threads",
        "path", "backend", "seconds_ldi", "seconds_sweep", "seconds_total", "pixel_slab_lights_per_second",
        "image_hash",
    ] {
        assert!(!v[key].is_null(), "missing {key}: {v}");
    }
    assert_eq!(v["kernel"], "poisson8");
    assert_eq!(v["threads"], 3);
    // The EXR holds exactly the hashed float image.
    assert_eq!(
        format!("{:016x}", convshadow::pipeline::image_fingerprint(&exr.data)),
        v["image_hash"].as_str().unwrap()
    );
}

#[test]
fn open_meshes_are_refused_unless_allowed() {
    let Some(models) = support::models_dir() else { return };
    let dir = support::temp_dir("render-open");
    let scene = dir.join("open.toml");
    std::fs::write(&scene, support::obj_scene(&models.join("cube_no_bottom.obj"), 48, 4.0)).unwrap();
    let s = scene.to_str().unwrap();
    let (code, _, err) = support::run_cli(&["render", s, "-o", "x.png"], &dir);
    assert_eq!(code, 6, "{err}");
    assert!(err.contains("boundary") && err.contains("--allow-open"), "{err}");
    assert!(!dir.join("x.png").exists());
    let (code, _, err) = support::run_cli(&["render", s, "-o", "x.png", "--allow-open"], &dir);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("odd fragment count"), "{err}");
    assert!(dir.join("x.png").is_file());
}
