//! PNG display mapping (exposure, tone curves), NIfTI volumes as textures, `diff` thresholds and
//! the command line's frame, size and camera options.

use crate::support;

use std::path::Path;

use convshadow::common::model::display::DisplayMap;
use convshadow::common::model::display::Tonemap;
use convshadow::common::model::scene::Scene;
use convshadow::io::image::RgbImage;
use convshadow::io::nifti::load_nifti;
use convshadow::pipeline::{RenderRequest, render};

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn default_scene_png_does_not_clip_and_its_float_image_is_unchanged() {
    let mut scene = Scene::default_scene();
    scene.image.width = 96;
    scene.image.height = 96;
    let r = render(&scene, &RenderRequest::default()).unwrap();
    let peak = r.image.data.iter().cloned().fold(0.0f32, f32::max);
    assert!(peak > 1.0, "the linear image peaks above 1 ({peak})");
    // The plain clamp would clip the brightest wall and the highlights (1.4 % of the values
    // since the wall is shaded with the cosine, lambert; 20 % and more when it was flat); the
    // scene's own mapping clips nothing.
    let clamp = DisplayMap::CLAMP.clipped_fraction(&r.image.data);
    let mapped = scene.image.display_map().clipped_fraction(&r.image.data);
    assert!(clamp > 0.01, "clamp clips {clamp}");
    assert!(mapped < 1e-3, "the default mapping clips {mapped}");
    assert_eq!(scene.image.tonemap, Tonemap::Aces);
}

#[test]
fn exr_stays_linear_and_png_follows_the_curve() {
    let dir = support::temp_dir("display-exr");
    let common = [
        "render",
        "--size",
        "40x32",
        "--slabs",
        "24",
        "--threads",
        "2",
        "--quiet",
    ];
    let mut runs = Vec::new();
    for (name, extra) in [
        ("clamp", vec!["--tonemap", "clamp", "--exposure", "0"]),
        (
            "reinhard",
            vec!["--tonemap", "reinhard", "--exposure", "1.5"],
        ),
        ("aces", vec![]),
    ] {
        let mut args: Vec<String> = common.iter().map(|s| s.to_string()).collect();
        args.extend(extra.iter().map(|s| s.to_string()));
        for o in ["-o", &format!("{name}.png"), "-o", &format!("{name}.exr")] {
            args.push(o.to_string());
        }
        args.extend(["--stats-json".to_string(), format!("{name}.json")]);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, out, err) = support::run_cli(&refs, &dir);
        assert_eq!(code, 0, "{out}{err}");
        runs.push((name, extra));
    }
    let exr = |n: &str| RgbImage::load(&dir.join(format!("{n}.exr"))).unwrap();
    // The EXR is the same float image whatever the PNG mapping.
    assert_eq!(exr("clamp"), exr("aces"));
    assert_eq!(exr("clamp"), exr("reinhard"));
    let hash = |n: &str| json(&dir.join(format!("{n}.json")))["image_hash"].clone();
    assert_eq!(hash("clamp"), hash("aces"));
    let png8 = |n: &str| {
        image::open(dir.join(format!("{n}.png")))
            .unwrap()
            .to_rgb8()
            .into_raw()
    };
    let linear = exr("clamp").data;
    assert!(png8("clamp") == DisplayMap::CLAMP.to_srgb8(&linear));
    let reinhard = DisplayMap {
        exposure: 1.5,
        tonemap: Tonemap::Reinhard,
    };
    assert!(png8("reinhard") == reinhard.to_srgb8(&linear));
    // The default scene's own mapping (exposure −1, aces).
    let own = Scene::default_scene().image.display_map();
    assert_eq!(own.tonemap, Tonemap::Aces);
    assert!(
        png8("aces") == own.to_srgb8(&linear),
        "PNG = the scene's mapping of the EXR"
    );
    assert!(png8("aces") != png8("clamp"));
    let (code, _, err) = support::run_cli(&["render", "--tonemap", "filmic"], &dir);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("clamp, reinhard or aces"), "{err}");
}

#[test]
fn nifti_big_endian_and_gzip_4d_match_the_readme() {
    let Some(dir) = support::volumes_dir() else {
        return;
    };
    let a = load_nifti(&dir.join("anatomical.nii"), Some([-610.0, 30393.0])).unwrap();
    assert_eq!(a.texture.dims, [33, 41, 25]);
    assert_eq!(a.spacing, [2.0, 2.0, 2.0]);
    assert!(a.big_endian);
    assert_eq!(a.datatype, 4);
    assert_eq!(a.volumes, 1);
    assert_eq!((a.min, a.max), (-610.0, 30393.0));
    // Undo the window to compare voxel values with the README.
    let value = |t: &convshadow::io::nifti::NiftiTexture, x: usize, y: usize, z: usize| {
        let d = t.texture.dims.map(|d| d as usize);
        let v = f64::from(t.texture.voxels[x + d[0] * (y + d[1] * z)]);
        t.window[0] + v * (t.window[1] - t.window[0])
    };
    assert!((value(&a, 1, 2, 3) - 9798.0).abs() < 0.02);
    assert!((value(&a, 10, 20, 5) - 8577.0).abs() < 0.02);
    let sum: f64 = (0..25)
        .flat_map(|z| (0..41).flat_map(move |y| (0..33).map(move |x| (x, y, z))))
        .map(|(x, y, z)| value(&a, x, y, z))
        .sum();
    assert!((sum - 284_166_082.0).abs() < 50.0, "sum {sum}");

    let g = load_nifti(&dir.join("example4d.nii.gz"), None).unwrap();
    assert_eq!(g.texture.dims, [128, 96, 24]);
    assert!(!g.big_endian);
    assert_eq!(g.volumes, 2, "4D: two time points, the first used");
    assert_eq!((g.min, g.max), (0.0, 1162.0));
    assert_eq!(g.spacing[0], 2.0);
    assert!((g.spacing[2] - 2.2).abs() < 1e-5);
    let mean = g.texture.voxels.iter().map(|&v| f64::from(v)).sum::<f64>() * 1162.0
        / g.texture.voxels.len() as f64;
    assert!((mean - 172.9139).abs() < 1e-3, "mean {mean}");
    // Default window = min–max: the values span [0, 1].
    assert_eq!(g.texture.voxels.iter().cloned().fold(0.0f32, f32::max), 1.0);
}

#[test]
fn truncated_and_foreign_files_get_a_clear_error_naming_the_file() {
    let Some(dir) = support::volumes_dir() else {
        return;
    };
    let tmp = support::temp_dir("nifti-bad");
    let full = std::fs::read(dir.join("anatomical.nii")).unwrap();
    let cases = [
        ("cut.nii", full[..full.len() / 2].to_vec(), "truncated"),
        ("header.nii", full[..200].to_vec(), "not a NIfTI-1 file"),
        (
            "text.nii",
            b"hello, not a volume\n".repeat(40),
            "not a NIfTI-1 file",
        ),
    ];
    for (name, bytes, want) in cases {
        let p = tmp.join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = load_nifti(&p, None).unwrap_err().to_string();
        assert!(e.contains(want) && e.contains(name), "{name}: {e}");
    }
    let gz = std::fs::read(dir.join("example4d.nii.gz")).unwrap();
    let p = tmp.join("cut.nii.gz");
    std::fs::write(&p, &gz[..gz.len() / 3]).unwrap();
    let e = load_nifti(&p, None).unwrap_err().to_string();
    assert!(e.contains("cut.nii.gz"), "{e}");
    // Through a scene: the render fails with exit code 3 and names the file.
    let scene = String::from(
        "[image]\nwidth = 16\nheight = 16\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 8\n\
         optimal_distance = 1.0\n[[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\n\
         material = \"v\"\n[material.v]\ntexture = { path = \"cut.nii\" }\n\
         gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 0.5]]\n",
    );
    std::fs::write(tmp.join("s.toml"), scene).unwrap();
    let (code, _, err) = support::run_cli(&["render", "s.toml", "-q"], &tmp);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("cut.nii") && err.contains("truncated"),
        "{err}"
    );
}

#[test]
fn the_texture_keeps_the_voxel_spacings_aspect() {
    let Some(dir) = support::volumes_dir() else {
        return;
    };
    let scene_text = |size: &str| {
        format!(
            "[image]\nwidth = 24\nheight = 24\n[camera]\nview_width = 3.0\n[sweep]\nslabs = 8\n\
             optimal_distance = 1.0\n[[mesh]]\nshape = \"box\"\nsize = {size}\nmaterial = \"v\"\n\
             [material.v]\ntexture = {{ path = \"{}\" }}\n\
             gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 0.5]]\n",
            dir.join("example4d.nii.gz").display()
        )
    };
    // A cube: the 256 × 192 × 52.8 mm volume fits by its x side, centred in y and z.
    let cube = Scene::parse(&scene_text("[2.0, 2.0, 2.0]"), "t.toml", &dir).unwrap();
    let geometry = convshadow_io::build_geometry(&cube).unwrap();
    let plan = convshadow_io::build_plan(&cube, &geometry).unwrap();
    let extent = plan.materials[0].texture_extent.unwrap();
    assert_eq!(extent[0], 256.0);
    assert_eq!(extent[1], 192.0);
    assert!((extent[2] - 24.0 * 2.2).abs() < 1e-3);
    // Texture coordinates per image pixel (x) and per depth unit (z): the scale along x is
    // 1/2 per world unit, along z 256/52.8 times that (the box is 2 wide).
    let m = plan.mesh_to_detail[0];
    let du_dx = f64::from(m[0])
        .hypot(f64::from(m[4]))
        .hypot(f64::from(m[8]));
    let dw_dz = f64::from(m[2])
        .hypot(f64::from(m[6]))
        .hypot(f64::from(m[10]));
    let px = geometry.camera.pixel_size;
    assert!((du_dx / px - 0.5).abs() < 1e-4, "{}", du_dx / px);
    assert!((dw_dz - 0.5 * 256.0 / 52.8).abs() < 1e-3, "{dw_dz}");
    // Rendered through the CLI, the 4D file says that only its first volume is used.
    let tmp = support::temp_dir("nifti-4d");
    std::fs::write(tmp.join("s.toml"), scene_text("[2.0, 2.0, 2.0]")).unwrap();
    let (code, _, err) = support::run_cli(&["render", "s.toml", "-o", "s.png"], &tmp);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning:") && err.contains("128x96x24x2") && err.contains("first 3D volume"),
        "{err}"
    );
}

#[test]
fn frames_in_one_run_and_one_at_a_time_give_the_same_hashes() {
    let dir = support::temp_dir("frames");
    let base = [
        "render",
        "--size",
        "32x24",
        "--slabs",
        "16",
        "--threads",
        "2",
        "--quiet",
    ];
    let run = |extra: &[&str]| {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        let (code, out, err) = support::run_cli(&args, &dir);
        assert_eq!(code, 0, "{out}{err}");
    };
    run(&[
        "--frames",
        "0..3",
        "--time-step",
        "0.25",
        "-o",
        "seq_%03d.png",
        "--stats-json",
        "seq.json",
    ]);
    let seq = json(&dir.join("seq.json"));
    let frames = seq["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    let mut hashes = Vec::new();
    for k in 0..3u32 {
        let f = &frames[k as usize];
        assert_eq!(f["frame"], k);
        assert!(dir.join(format!("seq_{k:03}.png")).is_file());
        let name = format!("one_{k}.json");
        run(&[
            "--frame",
            &k.to_string(),
            "--time-step",
            "0.25",
            "-o",
            "one_%d.exr",
            "--stats-json",
            &name,
        ]);
        let one = json(&dir.join(&name));
        assert_eq!(one["frames"][0]["image_hash"], f["image_hash"], "frame {k}");
        assert!(dir.join(format!("one_{k}.exr")).is_file());
        hashes.push(f["image_hash"].clone());
    }
    assert_ne!(hashes[0], hashes[1], "the noise moves between frames");
    // Without a frame pattern a sequence would overwrite one file: refused.
    let args: Vec<&str> = base
        .iter()
        .chain(&["--frames", "0..2", "-o", "same.png"])
        .copied()
        .collect();
    let (code, _, err) = support::run_cli(&args, &dir);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn size_and_camera_overrides() {
    let dir = support::temp_dir("size-camera");
    let (code, out, err) = support::run_cli(
        &[
            "render",
            "--size",
            "48x24",
            "--slabs",
            "8",
            "--camera-center",
            "0.1,-0.2,0",
            "--camera-direction",
            "0,0.1,1",
            "-o",
            "a.exr",
            "--threads",
            "2",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(err.contains("camera.view_width 4 → 8"), "{err}");
    assert!(out.contains("2 lights"), "{out}");
    let img = RgbImage::load(&dir.join("a.exr")).unwrap();
    assert_eq!((img.width, img.height), (48, 24));
    let (code, _, err) = support::run_cli(
        &[
            "render",
            "--view-width",
            "-1",
            "-o",
            "b.png",
            "--slabs",
            "4",
        ],
        &dir,
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--view-width"), "{err}");
    let (code, _, err) = support::run_cli(&["render", "--size", "12"], &dir);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn diff_thresholds_gate_and_nans_fail_every_threshold() {
    let dir = support::temp_dir("diff-gate");
    support::exr_with(&dir, "a.exr", 0.25);
    support::exr_with(&dir, "b.exr", 0.35);
    support::exr_with(&dir, "n.exr", f32::NAN);
    let diff = |args: &[&str]| {
        let mut all = vec!["diff"];
        all.extend(args);
        support::run_cli(&all, &dir)
    };
    // No threshold: 0 whatever the difference.
    assert_eq!(diff(&["a.exr", "b.exr"]).0, 0);
    assert_eq!(diff(&["a.exr", "b.exr", "--max-abs", "0.2"]).0, 0);
    let (code, _, err) = diff(&["a.exr", "b.exr", "--max-abs", "0.05"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("max abs error"), "{err}");
    assert_eq!(diff(&["a.exr", "b.exr", "--max-rmse", "0.01"]).0, 1);
    assert_eq!(
        diff(&["a.exr", "b.exr", "--max-differing-pixels", "0"]).0,
        1
    );
    assert_eq!(
        diff(&["a.exr", "b.exr", "--max-differing-pixels", "1"]).0,
        0
    );
    assert_eq!(diff(&["a.exr", "b.exr", "--max-flip", "1"]).0, 0);
    // Identical finite images: PSNR inf.
    let (code, out, _) = diff(&["a.exr", "a.exr", "--max-abs", "0"]);
    assert_eq!(code, 0);
    assert!(out.contains("PSNR inf"), "{out}");
    // A NaN: reported with its count and position, and it fails any threshold.
    let (code, out, _) = diff(&["a.exr", "n.exr", "--json", "d.json"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("B has 1 NaN value (first at (1, 2, channel 0))"),
        "{out}"
    );
    assert!(!out.contains("PSNR inf"), "{out}");
    let j = json(&dir.join("d.json"));
    assert_eq!(j["nan_b"]["count"], 1);
    assert_eq!(j["psnr_db"], "nan");
    let (code, _, err) = diff(&["n.exr", "n.exr", "--max-flip", "1"]);
    assert_eq!(code, 1, "{err}");
    // Unreadable input: 3.
    assert_eq!(diff(&["a.exr", "missing.exr"]).0, 3);
}

/// The README's usage block names every option `--help` lists, for every subcommand.
#[test]
fn readme_usage_lists_every_help_option() {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let dir = support::temp_dir("help");
    for cmd in ["render", "ldi", "diff", "report"] {
        let (code, out, _) = support::run_cli(&[cmd, "--help"], &dir);
        assert_eq!(code, 0);
        let usage: String = readme
            .lines()
            .skip_while(|l| !l.starts_with(&format!("convshadow {cmd}")))
            .take_while(|l| l.starts_with(&format!("convshadow {cmd}")) || l.starts_with("   "))
            .collect::<Vec<_>>()
            .join("\n");
        assert!(
            !usage.is_empty(),
            "README has no `convshadow {cmd}` usage line"
        );
        let mut missing = Vec::new();
        for line in out.lines() {
            let t = line.trim_start();
            if !t.starts_with('-') {
                continue;
            }
            let long = t
                .split([' ', ','])
                .find(|w| w.starts_with("--"))
                .map(|w| w.split(['=', '<']).next().unwrap_or(w).to_string());
            if let Some(l) = long
                && l != "--help"
                && l != "--version"
                && !usage.match_indices(&l).any(|(i, _)| {
                    !usage[i + l.len()..]
                        .starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-')
                })
            {
                missing.push(l);
            }
        }
        assert!(
            missing.is_empty(),
            "README usage of `{cmd}` lacks {missing:?}"
        );
    }
}

#[test]
fn messages_say_1_light_and_label_the_triangle_counts() {
    let dir = support::temp_dir("messages");
    let scene = "[image]\nwidth = 16\nheight = 16\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 4\n\
                 optimal_distance = 1.0\n[[light]]\n[[mesh]]\nshape = \"sphere\"\nsize = [0.5, 1]\n\
                 material = \"m\"\n[material.m]\ncolor = [1.0, 1.0, 1.0]\nopacity = 0.5\n";
    std::fs::write(dir.join("one.toml"), scene).unwrap();
    let (code, out, err) = support::run_cli(&["render", "one.toml", "-o", "one.png"], &dir);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(" 1 light,"), "{out}");
    let (code, out, err) = support::run_cli(&["ldi", "--width", "24", "--height", "24"], &dir);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("triangles rasterized of"), "{out}");
}

#[test]
fn no_xdg_runtime_dir_noise_without_the_variable() {
    let dir = support::temp_dir("xdg");
    // `auto`: the GPU where Vulkan has an adapter (lavapipe here), else the CPU; either way the
    // loader must not complain about XDG_RUNTIME_DIR.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_convshadow"))
        .args([
            "render",
            "--backend",
            "auto",
            "--size",
            "16x16",
            "--slabs",
            "4",
        ])
        .args(["-o", "x.png"])
        .env_remove("XDG_RUNTIME_DIR")
        .current_dir(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
}
