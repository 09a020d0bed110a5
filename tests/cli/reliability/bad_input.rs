//! Bad input to the `convshadow` binary: every bad scene file, unreadable model, bad output
//! path, out-of-range argument, device or FIFO given as input and control character is refused
//! with a message naming the problem and its documented exit code (docs/errors.md), no panic and
//! no file left behind.

use super::*;

fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad")
}

#[test]
fn the_base_scene_of_the_bad_files_renders() {
    // The control: without its one change, every bad scene would render.
    let dir = support::temp_dir("rel-base");
    std::fs::write(dir.join("base.toml"), BASE_SCENE).unwrap();
    let (code, out, err) = support::run_cli(
        &[
            "render",
            "base.toml",
            "-o",
            "out.png",
            "--stats-json",
            "s.json",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(files_in(&dir), ["base.toml", "out.png", "s.json"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_bad_scene_file_is_refused_naming_file_and_key_and_writes_nothing() {
    let out_dir = support::temp_dir("rel-bad-scenes");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(bad_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(&path).unwrap();
        // Each file says what it breaks and what the message must name.
        let expect = text
            .lines()
            .find_map(|l| l.strip_prefix("# expect: "))
            .unwrap_or_else(|| panic!("{name}: no `# expect:` line"));
        let out = out_dir.join("out.png");
        let json = out_dir.join("stats.json");
        for cmd in ["render", "ldi"] {
            let mut args = vec![cmd, path.to_str().unwrap(), "--stats-json"];
            args.push(json.to_str().unwrap());
            if cmd == "render" {
                args.extend(["-o", out.to_str().unwrap()]);
            }
            let (code, _, err) = support::run_cli(&args, &out_dir);
            assert_refused(
                &format!("{cmd} {name}"),
                code,
                BAD_INPUT,
                &err,
                &[&name, expect],
            );
            assert!(
                files_in(&out_dir).is_empty(),
                "{cmd} {name}: left {:?}",
                files_in(&out_dir)
            );
        }
        names.push(name);
    }
    // The required bad inputs, each present.
    for required in [
        "unknown_key.toml",
        "wrong_type.toml",
        "tilt_90.toml",
        "tilt_minus_90.toml",
        "negative_variance.toml",
        "zero_slabs.toml",
        "huge_width.toml",
        "missing_obj_file.toml",
        "obj_without_path.toml",
    ] {
        assert!(names.iter().any(|n| n == required), "missing {required}");
    }
    std::fs::remove_dir_all(&out_dir).unwrap();
}

/// A scene framing an OBJ file (a fixed view when it does not load).
fn obj_scene_file(dir: &Path, obj: &Path) -> PathBuf {
    let scene = dir.join(format!(
        "{}.toml",
        obj.file_stem().unwrap().to_string_lossy()
    ));
    let text = support::framed_obj_scene(obj, 32, 1.5).replace("slabs = 64", "slabs = 8");
    std::fs::write(&scene, text).unwrap();
    scene
}

#[test]
fn render_refuses_every_unreadable_model_writing_nothing_and_renders_open_ones_as_shells() {
    let Some(models) = support::models_dir() else {
        return;
    };
    let scenes = support::temp_dir("rel-bad-models-scenes");
    let out_dir = support::temp_dir("rel-bad-models-out");
    let (mut refused, mut shells) = (0, 0);
    let mut files: Vec<PathBuf> = std::fs::read_dir(models.join("bad"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.push(models.join("cube_no_bottom.obj")); // an open mesh
    for path in files {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let scene = obj_scene_file(&scenes, &path);
        let out = out_dir.join("out.png");
        let (code, _, err) = support::run_cli(
            &[
                "render",
                scene.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "-q",
            ],
            &out_dir,
        );
        assert!(!err.contains("panicked"), "{name}: {err}");
        match code {
            // The control of models/bad renders, and so does a mesh that is not closed: a thin
            // shell, with a warning naming the mesh and its edges.
            0 => {
                assert!(out.is_file(), "{name}");
                std::fs::remove_file(&out).unwrap();
                if name != "tetra_ok.obj" {
                    assert!(
                        err.contains("mesh[0] is not closed")
                            && err.contains("edges")
                            && err.contains("thin shell"),
                        "{name}: {err}"
                    );
                    shells += 1;
                }
            }
            // A parse error names the OBJ file and its line (`file.obj:LINE:`), and nothing is
            // written.
            BAD_INPUT => {
                assert!(err.contains(&format!("{name}:")), "{name}: {err}");
                assert!(
                    files_in(&out_dir).is_empty(),
                    "{name}: left {:?}",
                    files_in(&out_dir)
                );
                refused += 1;
            }
            _ => panic!("{name}: exit code {code}, expected 0 or {BAD_INPUT}: {err}"),
        }
        if name == "cube_no_bottom.obj" {
            assert_eq!(code, 0, "{err}");
            assert!(err.contains("boundary"), "{err}");
        }
    }
    // Six unreadable files; the flipped face, the non-manifold edge and the open cube are shells.
    assert_eq!((refused, shells), (6, 3), "refused, shells");
}

#[test]
fn bad_output_paths_are_refused_before_rendering_and_leave_nothing() {
    let dir = support::temp_dir("rel-outputs");
    std::fs::write(dir.join("scene.toml"), BASE_SCENE).unwrap();
    std::fs::create_dir(dir.join("a_folder")).unwrap();
    std::fs::write(dir.join("some_file.txt"), "not a folder").unwrap();
    // Tests run as root here, so a folder without write permission would still be writable.
    // Unwritable for root too: a path under a regular file (ENOTDIR), and /proc (no regular files
    // can be created there).
    let cases: [(&str, &[&str]); 5] = [
        ("a_folder", &["a_folder", "is a folder"]),
        (
            "some_file.txt/out.png",
            &["some_file.txt", "is not a folder"],
        ),
        ("missing/out.png", &["missing", "does not exist"]),
        ("/proc/convshadow-out.png", &["/proc", "cannot create"]),
        ("out.tiff", &["out.tiff", "expected .png or .exr"]),
    ];
    for (target, what) in cases {
        let (code, _, err) = support::run_cli(&["render", "scene.toml", "-o", target], &dir);
        let expected = if target.ends_with(".tiff") {
            2
        } else {
            OUTPUT_FAILED
        };
        assert_refused(target, code, expected, &err, what);
        assert_eq!(
            files_in(&dir),
            ["a_folder", "scene.toml", "some_file.txt"],
            "{target}"
        );
        assert!(files_in(&dir.join("a_folder")).is_empty());
        // Refused up front: no render ran (the summary line never printed).
    }
    // The stats JSON goes through the same checks.
    let (code, _, err) = support::run_cli(
        &[
            "render",
            "scene.toml",
            "-o",
            "ok.png",
            "--stats-json",
            "some_file.txt/s.json",
        ],
        &dir,
    );
    assert_refused("stats json", code, OUTPUT_FAILED, &err, &["some_file.txt"]);
    assert_eq!(files_in(&dir), ["a_folder", "scene.toml", "some_file.txt"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("some_file.txt")).unwrap(),
        "not a folder"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------------
// Hardening: arguments and input files that used to hang, grow without bound or blame the scene.

/// Exit code of bad command-line arguments (docs/errors.md).
const BAD_ARGUMENTS: i32 = 2;

/// Runs `args` in `dir`, asserting it finishes within `limit` seconds.
fn run_quickly(args: &[&str], dir: &Path, limit: f64) -> (i32, String, String) {
    let start = std::time::Instant::now();
    let r = support::run_cli(args, dir);
    let took = start.elapsed().as_secs_f64();
    assert!(took < limit, "{args:?} took {took:.1} s");
    r
}

#[test]
fn huge_thread_counts_image_sides_and_sample_counts_are_bad_arguments() {
    let dir = support::temp_dir("rel-args");
    std::fs::write(dir.join("base.toml"), BASE_SCENE).unwrap();
    for (args, names) in [
        (
            &["render", "base.toml", "-o", "o.png", "--threads", "100000"][..],
            "--threads",
        ),
        (
            &["render", "base.toml", "-o", "o.png", "--threads", "5000"][..],
            "--threads",
        ),
        (
            &["ldi", "base.toml", "--threads", "100000"][..],
            "--threads",
        ),
        (
            &["render", "base.toml", "-o", "o.png", "--width", "0"][..],
            "--width",
        ),
        (
            &["render", "base.toml", "-o", "o.png", "--width", "16385"][..],
            "--width",
        ),
        (&["ldi", "base.toml", "--height", "0"][..], "--height"),
        (
            &[
                "render",
                "base.toml",
                "-o",
                "o.png",
                "--backend",
                "reference",
                "--width",
                "1",
                "--height",
                "1",
                "--reference-samples",
                "4294967295",
            ][..],
            "--reference-samples",
        ),
    ] {
        let (code, _, err) = run_quickly(args, &dir, 10.0);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(code, BAD_ARGUMENTS, "{args:?}: {err}");
        assert!(err.contains(names), "{args:?}: must name {names}: {err}");
        assert_eq!(files_in(&dir), ["base.toml"], "{args:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn devices_fifos_and_folders_are_refused_as_inputs_without_reading_them() {
    let dir = support::temp_dir("rel-nonregular");
    let fifo = dir.join("pipe.obj");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo only creates a file system node.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let obj_scene = |path: &str| {
        BASE_SCENE.replace(
            "shape = \"box\"\nsize = [1.0, 1.0, 1.0]",
            &format!("shape = \"obj\"\npath = {path:?}"),
        )
    };
    std::fs::write(dir.join("zero.toml"), obj_scene("/dev/zero")).unwrap();
    std::fs::write(dir.join("fifo.toml"), obj_scene("pipe.obj")).unwrap();
    std::fs::write(dir.join("dir.toml"), obj_scene(".")).unwrap();
    for (scene, names) in [
        ("zero.toml", "not a regular file"),
        ("fifo.toml", "not a regular file"),
        ("dir.toml", "folder"),
        ("/dev/zero", "not a regular file"),
        ("pipe.obj", "not a regular file"),
    ] {
        for cmd in ["render", "ldi"] {
            let (code, _, err) = run_quickly(
                &[cmd, scene, "-o", "o.png"][..if cmd == "ldi" { 2 } else { 4 }],
                &dir,
                10.0,
            );
            assert_refused(&format!("{cmd} {scene}"), code, BAD_INPUT, &err, &[names]);
        }
    }
    // A raw texture path that is a folder is named as a folder, not by its size.
    let tex = BASE_SCENE.replace(
        "[material.m]\nopacity = 0.5",
        "[material.m]\ntexture = { path = \".\", dims = [2, 2, 2], type = \"u8\" }\n\
         gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 1.0]]",
    );
    std::fs::write(dir.join("tex.toml"), tex).unwrap();
    let (code, _, err) = run_quickly(&["render", "tex.toml", "-o", "o.png"], &dir, 10.0);
    assert_refused("texture folder", code, BAD_INPUT, &err, &["folder"]);
    assert!(!err.contains("4096"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn output_paths_long_names_collisions_misnamed_formats_and_devices() {
    let dir = support::temp_dir("rel-outpaths");
    std::fs::write(dir.join("base.toml"), BASE_SCENE).unwrap();
    // A 250-character name: the temporary name must stay within 255 bytes.
    let long = format!("{}.png", "n".repeat(246));
    let (code, _, err) = support::run_cli(&["render", "base.toml", "-o", &long], &dir);
    assert_eq!(code, 0, "{err}");
    assert!(dir.join(&long).is_file());
    std::fs::remove_file(dir.join(&long)).unwrap();
    for (args, names) in [
        (
            &[
                "render",
                "base.toml",
                "-o",
                "x.png",
                "--stats-json",
                "x.png",
            ][..],
            "same file",
        ),
        (
            &[
                "render",
                "base.toml",
                "-o",
                "x.png",
                "--stats-json",
                "./x.png",
            ][..],
            "same file",
        ),
        (
            &["ldi", "base.toml", "--layers-png", "l.jpg"][..],
            "--layers-png",
        ),
        (
            &["diff", "a.exr", "b.exr", "--heatmap", "h.exr"][..],
            "--heatmap",
        ),
    ] {
        let (code, _, err) = support::run_cli(args, &dir);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(names), "{args:?}: must name {names}: {err}");
        assert_eq!(files_in(&dir), ["base.toml"], "{args:?}");
    }
    // A FIFO named like an output is not replaced.
    let fifo = dir.join("dev.png");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo only creates a file system node.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let (code, _, err) = support::run_cli(&["render", "base.toml", "-o", "dev.png"], &dir);
    assert_refused(
        "fifo output",
        code,
        OUTPUT_FAILED,
        &err,
        &["not a regular file"],
    );
    assert!(!std::fs::metadata(&fifo).unwrap().is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn control_characters_in_messages_are_escaped() {
    let dir = support::temp_dir("rel-escape");
    std::fs::write(
        dir.join("evil.obj"),
        b"v 0 0 0\nv 1 0 0\x1b[31m\x07\nf 1 2 3\n",
    )
    .unwrap();
    let scene = BASE_SCENE.replace(
        "shape = \"box\"\nsize = [1.0, 1.0, 1.0]",
        "shape = \"obj\"\npath = \"evil.obj\"",
    );
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    std::fs::write(dir.join("t.toml"), "[image]\nwidth = \"\u{1b}[31m\u{7}\"\n").unwrap();
    for scene in ["s.toml", "t.toml"] {
        let (code, _, err) = support::run_cli(&["ldi", scene], &dir);
        assert_eq!(code, BAD_INPUT, "{err}");
        assert!(
            !err.chars().any(|c| c.is_control() && c != '\n'),
            "{scene}: raw control characters: {err:?}"
        );
    }
    let (code, _, err) = support::run_cli(&["render", "s.toml", "--threads", "\u{1b}[31m"], &dir);
    assert_eq!(code, 2);
    assert!(!err.contains('\u{1b}'), "{err:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// OBJ text of unit cubes translated by `offsets` (outward winding); `flip` reverses the first
/// triangle of the last cube.
fn cubes_obj(offsets: &[[f64; 3]], flip: bool) -> String {
    use convshadow::common::prepare::mesh::TriMesh;
    let mut text = String::new();
    let mut base = 0;
    for (k, o) in offsets.iter().enumerate() {
        let cube = TriMesh::unit_box(glam::DVec3::ONE);
        for p in &cube.positions {
            text += &format!("v {} {} {}\n", p.x + o[0], p.y + o[1], p.z + o[2]);
        }
        for (j, t) in cube.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|i| i + 1 + base);
            if flip && k + 1 == offsets.len() && j == 0 {
                text += &format!("f {a} {c} {b}\n");
            } else {
                text += &format!("f {a} {b} {c}\n");
            }
        }
        base += cube.positions.len() as u32;
    }
    text
}

#[test]
fn two_cubes_sharing_one_edge_are_closed_with_a_warning_and_broken_pairs_are_shells() {
    let dir = support::temp_dir("rel-two-cubes");
    let scene = BASE_SCENE.replace(
        "shape = \"box\"\nsize = [1.0, 1.0, 1.0]",
        "shape = \"obj\"\npath = \"m.obj\"",
    );
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    // The cubes [-0.5, 0.5]³ and [0.5, 1.5]² × [-0.5, 0.5] share the edge x = y = 0.5.
    std::fs::write(
        dir.join("m.obj"),
        cubes_obj(&[[0.0; 3], [1.0, 1.0, 0.0]], false),
    )
    .unwrap();
    let (code, out, err) = support::run_cli(&["ldi", "s.toml"], &dir);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains(" 0 odd pixels"), "{out}");
    assert!(
        err.contains(
            "warning: mesh[0] has 1 non-manifold edges, each used as often in each direction"
        ),
        "{err}"
    );
    let (code, _, err) = support::run_cli(&["render", "s.toml", "-o", "o.png"], &dir);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("1 non-manifold edges"), "{err}");
    // One triangle of the second cube flipped: inconsistent winding, not closed: a thin shell.
    std::fs::write(
        dir.join("m.obj"),
        cubes_obj(&[[0.0; 3], [1.0, 1.0, 0.0]], true),
    )
    .unwrap();
    let shell = "warning: mesh[0] is not closed";
    let (code, _, err) = support::run_cli(&["ldi", "s.toml"], &dir);
    assert!(code == 0 && err.contains(shell), "{code}: {err}");
    assert!(err.contains("flipped edges"), "{err}");
    let (code, _, err) = support::run_cli(&["render", "s.toml", "-o", "o2.png"], &dir);
    assert!(code == 0 && err.contains(shell), "{code}: {err}");
    // A lone extra triangle on the shared edge: odd incidence (5), not closed: a thin shell.
    let mut text = cubes_obj(&[[0.0; 3], [1.0, 1.0, 0.0]], false);
    text += "v 0.5 0.5 -0.5\nv 0.5 0.5 0.5\nv 3 3 0\nf 17 18 19\n";
    std::fs::write(dir.join("m.obj"), text).unwrap();
    let (code, _, err) = support::run_cli(&["ldi", "s.toml"], &dir);
    assert!(code == 0 && err.contains(shell), "{code}: {err}");
    assert!(err.contains("1 non-manifold"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
