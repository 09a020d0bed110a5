//! Reliability of the `convshadow` binary: every bad input is refused with a message
//! naming the problem and a documented exit code (docs/errors.md), nothing panics, no output or
//! temporary file is left behind, memory limits are enforced before allocating, and SIGINT/SIGTERM
//! stop a render cleanly with exit code 130.

use crate::support;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Exit codes (docs/errors.md).
const BAD_INPUT: i32 = 3;
const RESOURCE_LIMIT: i32 = 4;
const OUTPUT_FAILED: i32 = 7;
const INTERRUPTED: i32 = 130;

/// The valid scene every file of tests/data/bad/ is derived from (one change each).
const BASE_SCENE: &str = r#"
[image]
width = 32
height = 32
[camera]
direction = [0.3, -0.2, 1.0]
view_width = 3.0
[sweep]
slabs = 16
optimal_distance = 0.5
[[light]]
tilt_deg = [20.0, 10.0]
variance = [0.01, 0.02]
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
material = "m"
[material.m]
opacity = 0.5
"#;

fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad")
}

/// The names of the files in `dir` (outputs, temporary `.partial` files, anything).
fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Asserts a refused run: the exit code, no panic, the message names `what`.
fn assert_refused(name: &str, code: i32, expected_code: i32, err: &str, what: &[&str]) {
    assert!(!err.contains("panicked"), "{name}: must not panic:\n{err}");
    assert_eq!(code, expected_code, "{name}: exit code; stderr:\n{err}");
    assert!(err.starts_with("error: "), "{name}: one error line: {err}");
    assert!(
        !err.contains("  "),
        "{name}: a broken line continuation: {err}"
    );
    for w in what {
        assert!(err.contains(w), "{name}: message must name {w:?}: {err}");
    }
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

/// Starts the binary in `cwd` with stdout discarded and stderr piped.
fn spawn_cli(args: &[&str], cwd: &Path) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_convshadow"))
        .args(args)
        .current_dir(cwd)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Runs the binary in `cwd` (stdout discarded): (exit code, stderr, peak RSS in KiB of that
/// process alone), the peak as the binary writes it at exit to `CONVSHADOW_PEAK_RSS_FILE` (its
/// `VmHWM`, which starts afresh at `exec`). Not the child's `ru_maxrss` from `wait4`: std
/// starts children by `vfork`, and Linux then counts this test process's own peak RSS ever (any
/// test's, in any thread) in the child's (measured: a 300 MiB peak of a parent showed as a
/// 314 MiB `/bin/true`).
pub(crate) fn run_measured(args: &[&str], cwd: &Path) -> (i32, String, u64) {
    static RUNS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let peak_file = std::env::temp_dir().join(format!(
        "convshadow-peak-rss-{}-{n}.txt",
        std::process::id()
    ));
    let _ = std::fs::remove_file(&peak_file);
    let out = Command::new(env!("CARGO_BIN_EXE_convshadow"))
        .args(args)
        .current_dir(cwd)
        .env("CONVSHADOW_PEAK_RSS_FILE", &peak_file)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let code = out
        .status
        .code()
        .unwrap_or_else(|| panic!("the child was killed: {:?}: {err}", out.status));
    let peak = std::fs::read_to_string(&peak_file)
        .unwrap_or_else(|e| panic!("no peak RSS from the child ({e}): {err}"));
    let _ = std::fs::remove_file(&peak_file);
    let kib = peak
        .trim()
        .parse()
        .unwrap_or_else(|e| panic!("peak RSS {peak:?}: {e}"));
    (code, err, kib)
}

/// The first number after `word` in `text`.
fn number_after(text: &str, word: &str) -> u64 {
    let rest = &text[text
        .find(word)
        .unwrap_or_else(|| panic!("{word:?} in {text}"))
        + word.len()..];
    rest.trim_start()
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("a number after {word:?} in {text}"))
}

#[test]
fn a_scene_over_the_memory_budget_is_refused_before_allocating() {
    let dir = support::temp_dir("rel-budget");
    // A baseline: the same binary refusing a scene file that does not exist (its own footprint).
    let (code, _, base_kib) = run_measured(&["render", "missing.toml", "-o", "x.png"], &dir);
    assert_eq!(code, BAD_INPUT);

    // 1. The per-pixel buffers: 16384² pixels of the default scene need many GiB (light buffers,
    //    sweep state, LDI arrays); a 256 MiB budget refuses it before any of them exists.
    let (code, err, kib) = run_measured(
        &[
            "render",
            "--width",
            "16384",
            "--height",
            "16384",
            "--max-memory",
            "256",
            "-o",
            "big.png",
        ],
        &dir,
    );
    assert_refused(
        "16384²",
        code,
        RESOURCE_LIMIT,
        &err,
        &["needs", "MiB", "256 MiB"],
    );
    let need_mib = number_after(&err, "needs");
    assert!(need_mib > 8 * 1024, "{err}");
    let peak_mib = kib / 1024;
    assert!(
        peak_mib * 100 < need_mib && peak_mib < 256,
        "peak RSS {peak_mib} MiB (baseline {} MiB) must stay far below the need {need_mib} MiB",
        base_kib / 1024
    );

    // 2. The fragments: 32 nested boxes at 2048² put 64 layers on most pixels: ~250 M fragments
    //    (over 4 GiB). The per-pixel arrays fit in 512 MiB; the fragment arrays are refused after
    //    the counting pass, before they are allocated.
    let mut text = String::from(
        "[image]\nwidth = 2048\nheight = 2048\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 8\n\
         optimal_distance = 0.5\n[material.m]\n",
    );
    for i in 0..32 {
        let s = 4.0 - 0.1 * f64::from(i);
        text += &format!("[[mesh]]\nshape = \"box\"\nsize = [{s}, {s}, {s}]\nmaterial = \"m\"\n");
    }
    std::fs::write(dir.join("layers.toml"), text).unwrap();
    for cmd in ["render", "ldi"] {
        let (code, err, kib) = run_measured(
            &[
                cmd,
                "layers.toml",
                "--max-memory",
                "512",
                "--stats-json",
                "s.json",
            ],
            &dir,
        );
        assert_refused(cmd, code, RESOURCE_LIMIT, &err, &["fragments", "MiB"]);
        let fragments = number_after(&err, "needs");
        assert!(fragments > 200_000_000, "{err}");
        let need_mib = (fragments * convshadow::cpu::ldi::BYTES_PER_FRAGMENT) >> 20;
        let peak_mib = kib / 1024;
        assert!(
            peak_mib * 10 < need_mib && peak_mib < 512,
            "{cmd}: peak RSS {peak_mib} MiB must stay far below the fragments' {need_mib} MiB"
        );
    }
    assert_eq!(files_in(&dir), ["layers.toml"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 43, class 1: allocations sized by a scene value, each once not seen by the budget.
/// Every case runs under a small `--max-memory` and must end (rendered or refused with exit code
/// 4, or a usage error) with a peak RSS within that budget plus the binary's own footprint.
/// Before the fixes: a far mesh aborted on a 48 GiB allocation, 16 lights × 65536 slabs peaked
/// at 198 MB under 8 MiB, a 6-million-index face (12 MB of text, counted 24 MB) took ~200 MB under 32 MiB, a 4096² pattern
/// ~230 MB under 64 MiB, and `--frames 0..4000000000` aborted on a 16 GB list.
#[test]
fn allocations_sized_by_a_scene_value_stay_within_the_budget() {
    let dir = support::temp_dir("rel-class1");
    let (code, _, base_kib) = run_measured(&["render", "missing.toml", "-o", "x.png"], &dir);
    assert_eq!(code, BAD_INPUT);
    let head = "[image]\nwidth = 32\nheight = 32\n[camera]\nview_width = 2.0\n";
    let boxed = "[[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n\
                 [material.m]\nopacity = 0.5\n";
    // 1. The quiet chunks' row windows, sized by the kernel's vertical reach: a wide light
    //    over slabs at the documented maximum thickness.
    let far =
        format!("{head}[sweep]\nslab_distance = 1e9\n[[light]]\nvariance = [1.0, 1.0]\n{boxed}");
    // 2. Kernel tables: 16 lights × 65536 slabs, about 20 MiB of tables.
    let mut lights = format!("{head}[sweep]\nslabs = 65536\n");
    for i in 0..16 {
        lights += &format!("[[light]]\ntilt_deg = [{i}.0, 0.0]\nvariance = [0.02, 0.01]\n");
    }
    lights += boxed;
    // 3. An OBJ face of 6 million indices (12 MB of text; a fan of as many triangles).
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nf");
    for _ in 0..2_000_000 {
        obj += " 1 2 3";
    }
    obj.push('\n');
    std::fs::write(dir.join("wide_face.obj"), obj).unwrap();
    let face = format!(
        "{head}[sweep]\nslabs = 4\n[[light]]\n[[mesh]]\nshape = \"obj\"\npath = \"wide_face.obj\"\n\
         material = \"m\"\n[material.m]\nopacity = 0.5\n"
    );
    // 4. A light pattern: a 4096² grey PNG of a few kB decodes to 16 MiB and 201 MiB of f32
    //    texels.
    image::GrayImage::new(4096, 4096)
        .save(dir.join("gobo.png"))
        .unwrap();
    let pattern = format!(
        "{head}[sweep]\nslabs = 4\n[[light]]\npattern = {{ path = \"gobo.png\", size = [2.0, 2.0] }}\n\
         {boxed}"
    );
    for (name, text, budget, refused) in [
        ("far", far, 64, None),
        ("lights", lights, 8, Some(&["kernel tables", "MiB"][..])),
        (
            "face",
            face,
            32,
            Some(&["needs", "MiB", "textures and meshes"][..]),
        ),
        (
            "pattern",
            pattern,
            64,
            Some(&["needs", "MiB", "textures and meshes"][..]),
        ),
    ] {
        let file = format!("{name}.toml");
        std::fs::write(dir.join(&file), text).unwrap();
        let out = format!("{name}.png");
        let mib = budget.to_string();
        let args = ["render", &file, "-o", &out, "--max-memory", &mib];
        let (code, err, kib) = run_measured(&args, &dir);
        match refused {
            None => assert_eq!(code, 0, "{name}: {err}"),
            Some(what) => assert_refused(name, code, RESOURCE_LIMIT, &err, what),
        }
        let over = kib.saturating_sub(base_kib) / 1024;
        assert!(
            over <= budget + 4,
            "{name}: peak RSS {} MiB, {over} MiB over the binary's own {} MiB, under \
             --max-memory {budget}",
            kib / 1024,
            base_kib / 1024
        );
    }
    // 5. A frame range is refused before any list of its frames exists.
    let args = [
        "render",
        "far.toml",
        "-o",
        "f_%010d.png",
        "--frames",
        "0..4000000000",
    ];
    let (code, err, kib) = run_measured(&args, &dir);
    assert_refused("frames", code, 2, &err, &["--frames", "at most 1000000"]);
    assert!(
        kib.saturating_sub(base_kib) < 64 << 10,
        "frames: peak RSS {kib} KiB"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A slow scene: 1024² px, 16 coloured lights (3 channels), 2048 slabs. Its first light buffer
/// alone is 16·3·1024²·4 B = 192 MiB, the second as much once the first slab has written it.
const SLOW_SCENE: &str = r#"
[image]
width = 1024
height = 1024
[camera]
view_width = 3.0
[sweep]
slabs = 2048
optimal_distance = 0.5
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
material = "m"
[material.m]
opacity = 0.2
transport = [0.9, 0.5, 0.1]
"#;

/// Resident set size of a running process in KiB, or `None` once it has exited.
fn rss_kib(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Starts the slow render, waits until it is in the sweep, sends `signal`, and checks the exit
/// code, the message, and that neither the output nor a temporary file exists.
fn interrupt_mid_sweep(signal: libc::c_int, name: &str) {
    let dir = support::temp_dir(name);
    let lights = "[[light]]\ntilt_deg = [30.0, 10.0]\nvariance = [0.02, 0.01]\n".repeat(16);
    std::fs::write(dir.join("slow.toml"), format!("{SLOW_SCENE}{lights}")).unwrap();
    let mut child = spawn_cli(
        &[
            "render",
            "slow.toml",
            "-o",
            "out.png",
            "-o",
            "out.exr",
            "--stats-json",
            "s.json",
        ],
        &dir,
    );
    let pid = child.id();
    // In the sweep: both light buffers are resident (the second is written by the first slab).
    // Geometry and LDI of one box take a few MiB, so 300 MiB is only reached inside the sweep.
    loop {
        let rss = rss_kib(pid);
        if rss.is_some_and(|k| k > 300 * 1024) {
            break;
        }
        assert!(
            rss.is_some() && child.try_wait().unwrap().is_none(),
            "{name}: the render ended before its sweep was interrupted"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let (code, err, _) = signal_and_wait(&mut child, signal);
    assert_eq!(code, Some(INTERRUPTED), "{name}: {code:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    let left = files_in(&dir);
    assert_eq!(
        left,
        ["slow.toml"],
        "{name}: no output and no .partial file"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sigterm_mid_sweep_exits_130_and_leaves_no_file() {
    interrupt_mid_sweep(libc::SIGTERM, "rel-sigterm");
}

#[test]
fn sigint_mid_sweep_exits_130_and_leaves_no_file() {
    interrupt_mid_sweep(libc::SIGINT, "rel-sigint");
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

/// MiB of physical memory (`MemTotal`), and whether the kernel refuses allocations beyond it
/// (overcommit mode 0 or 2).
fn machine_memory() -> Option<(u64, bool)> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib = number_after(&info, "MemTotal:");
    let mode = std::fs::read_to_string("/proc/sys/vm/overcommit_memory").ok()?;
    Some((kib / 1024, mode.trim() != "1"))
}

#[test]
fn a_budget_above_the_machine_is_an_error_not_an_allocation_abort() {
    let dir = support::temp_dir("rel-budget-huge");
    let args = |mem: &'static str| {
        [
            "render",
            "--width",
            "16384",
            "--height",
            "16384",
            "--max-memory",
            mem,
            "-o",
            "big.png",
        ]
    };
    let (code, err, _) = run_measured(&args("256"), &dir);
    assert_eq!(code, RESOURCE_LIMIT, "{err}");
    let need_mib = number_after(&err, "needs");
    let Some((total_mib, refuses)) = machine_memory() else {
        return;
    };
    if need_mib <= total_mib || !refuses {
        // This machine could really allocate the render: running it here would be no test.
        eprintln!("skipped: the need ({need_mib} MiB) fits this machine ({total_mib} MiB)");
        return;
    }
    let (code, err, kib) = run_measured(&args("100000000"), &dir);
    assert_refused(
        "over the machine",
        code,
        RESOURCE_LIMIT,
        &err,
        &["cannot allocate"],
    );
    assert!(kib / 1024 < 256, "peak RSS {} MiB", kib / 1024);
    assert_eq!(files_in(&dir), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Spawns `args` in `dir`, sends `signal` after `delay_ms`, and returns (exit code, stderr,
/// seconds from the signal to the exit).
fn signal_after(
    args: &[&str],
    dir: &Path,
    delay_ms: u64,
    signal: i32,
) -> (Option<i32>, String, f64) {
    let mut child = spawn_cli(args, dir);
    std::thread::sleep(std::time::Duration::from_millis(delay_ms));
    assert!(
        child.try_wait().unwrap().is_none(),
        "{args:?} ended before the signal"
    );
    signal_and_wait(&mut child, signal)
}

/// Sends `signal` to a running child and waits: (exit code, stderr, seconds from the signal to
/// the exit).
fn signal_and_wait(child: &mut std::process::Child, signal: i32) -> (Option<i32>, String, f64) {
    let sent = std::time::Instant::now();
    // SAFETY: sending a signal to our own child.
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let status = child.wait().unwrap();
    (status.code(), err, sent.elapsed().as_secs_f64())
}

#[test]
fn signals_stop_the_reference_and_report_with_130_and_leave_nothing() {
    let dir = support::temp_dir("rel-signals-more");
    std::fs::write(dir.join("base.toml"), BASE_SCENE).unwrap();
    let reference = [
        "render",
        "base.toml",
        "-o",
        "o.png",
        "--backend",
        "reference",
        "--reference-samples",
        "65536",
    ];
    for signal in [libc::SIGTERM, libc::SIGINT] {
        let (code, err, took) = signal_after(&reference, &dir, 300, signal);
        assert_eq!(code, Some(INTERRUPTED), "reference: {err}");
        assert!(err.contains("interrupted"), "{err}");
        assert!(took < 2.0, "reference took {took:.1} s to stop");
        assert_eq!(files_in(&dir), ["base.toml"]);
    }
    let (code, err, took) = signal_after(
        &["report", "--quick", "--out", "rep"],
        &dir,
        300,
        libc::SIGTERM,
    );
    assert_eq!(code, Some(INTERRUPTED), "report: {err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(took < 2.0, "report took {took:.1} s to stop");
    assert_eq!(files_in(&dir), ["base.toml"], "no empty report folder");
    // A file as --out is named as such, not "File exists (os error 17)".
    let (code, _, err) = support::run_cli(&["report", "--quick", "--out", "base.toml"], &dir);
    assert_refused(
        "report --out FILE",
        code,
        OUTPUT_FAILED,
        &err,
        &["expected a folder"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn textures_count_in_the_memory_budget_before_they_are_read() {
    let dir = support::temp_dir("rel-texture-budget");
    // Two sparse 1 GiB f32 textures (nothing on disk, 1 GiB each if read).
    let mut scene = BASE_SCENE.replace("[material.m]\nopacity = 0.5", "");
    for (i, name) in ["a.raw", "b.raw"].iter().enumerate() {
        let f = std::fs::File::create(dir.join(name)).unwrap();
        f.set_len(1 << 30).unwrap();
        scene += &format!(
            "[material.t{i}]\ntexture = {{ path = \"{name}\", dims = [1024, 1024, 256], type = \"f32\" }}\n\
             gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 0.5]]\n"
        );
    }
    scene = scene.replace("material = \"m\"", "material = \"t0\"");
    scene += "[[mesh]]\nshape = \"box\"\nsize = [0.5, 0.5, 0.5]\nmaterial = \"t1\"\n";
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let start = std::time::Instant::now();
    let (code, err, kib) = run_measured(
        &["render", "s.toml", "-o", "o.png", "--max-memory", "64"],
        &dir,
    );
    assert_refused(
        "two 1 GiB textures",
        code,
        RESOURCE_LIMIT,
        &err,
        &["textures and meshes 4096 MiB", "64 MiB"],
    );
    assert!(start.elapsed().as_secs_f64() < 5.0);
    assert!(kib / 1024 < 64, "peak RSS {} MiB", kib / 1024);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn texture_loading_is_timed_apart_from_the_ldi() {
    let dir = support::temp_dir("rel-texture-time");
    // A 32 MiB f32 texture: its loading dominates the plan time.
    std::fs::write(dir.join("t.raw"), vec![0u8; 32 << 20]).unwrap();
    let scene = BASE_SCENE.replace(
        "[material.m]\nopacity = 0.5",
        "[material.m]\ntexture = { path = \"t.raw\", dims = [256, 256, 128], type = \"f32\" }\n\
         gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 0.5]]",
    );
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let (code, _, err) = support::run_cli(
        &["render", "s.toml", "-o", "o.png", "--stats-json", "s.json"],
        &dir,
    );
    assert_eq!(code, 0, "{err}");
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    let secs = |k: &str| {
        stats[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k} in {stats}"))
    };
    assert!(secs("seconds_plan") > 0.0);
    assert!(
        secs("seconds_ldi") + secs("seconds_plan") + secs("seconds_sweep")
            <= secs("seconds_total") + 1e-3
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sigterm_stops_ldi_with_130_and_leaves_no_stats() {
    let dir = support::temp_dir("rel-signals-ldi");
    // The default scene at 8192² takes seconds to build: still running when signalled.
    let args = [
        "ldi",
        "--width",
        "8192",
        "--height",
        "8192",
        "--stats-json",
        "l.json",
    ];
    let (code, err, took) = signal_after(&args, &dir, 300, libc::SIGTERM);
    assert_eq!(code, Some(INTERRUPTED), "ldi: {err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(took < 2.0, "ldi took {took:.1} s to stop");
    assert_eq!(files_in(&dir), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_signal_during_texture_loading_stops_the_render_promptly() {
    let dir = support::temp_dir("rel-texture-signal");
    // A sparse 256 MiB u8 texture: seconds to read and convert, nothing on disk.
    let f = std::fs::File::create(dir.join("t.raw")).unwrap();
    f.set_len(256 << 20).unwrap();
    drop(f);
    interrupt_while_loading(
        &dir,
        "texture = { path = \"t.raw\", dims = [1024, 1024, 256], type = \"u8\" }",
        "t.raw",
    );
}

/// Renders a scene whose material reads `texture` (the file `name` in `dir`), sends SIGINT
/// after 0.3 s, and checks that the render stopped within 1 s with exit 130 and wrote nothing.
fn interrupt_while_loading(dir: &Path, texture: &str, name: &str) {
    let scene = BASE_SCENE.replace(
        "[material.m]\nopacity = 0.5",
        &format!(
            "[material.m]\n{texture}\n\
             gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 0.5]]"
        ),
    );
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let args = ["render", "s.toml", "-o", "o.png", "--max-memory", "16384"];
    let (code, err, took) = signal_after(&args, dir, 300, libc::SIGINT);
    assert_eq!(code, Some(INTERRUPTED), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(took < 1.0, "the render took {took:.1} s to stop");
    assert_eq!(files_in(dir), ["s.toml", name]);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_signal_during_nifti_loading_stops_the_render_promptly() {
    let dir = support::temp_dir("rel-nifti-signal");
    // A sparse NIfTI-1 file of 1024×1024×256 u8 voxels (256 MiB of zeros after the 352-byte
    // header: NIfTI-1 layout, dim at byte 40, datatype 70, bitpix 72, pixdim 76, vox_offset 108,
    // magic 344): seconds to read and convert, nothing on disk.
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (i, d) in [3i16, 1024, 1024, 256, 1, 1, 1, 1].iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&2i16.to_le_bytes());
    h[72..74].copy_from_slice(&8i16.to_le_bytes());
    for i in 0..8 {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&1f32.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    std::fs::write(dir.join("t.nii"), &h).unwrap();
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(dir.join("t.nii"))
        .unwrap();
    f.set_len(352 + (256 << 20)).unwrap();
    drop(f);
    interrupt_while_loading(&dir, "texture = { path = \"t.nii\" }", "t.nii");
}

#[test]
fn a_signal_between_frames_names_the_complete_frames_written() {
    // Issue 43, class 3: a signal after some frames said "no output written" while the frames
    // were on disk (and one during the outputs' writing was swallowed: exit 0). Now every output
    // is written after a check of the signal flag, and the message names what is on disk.
    for (signal, name) in [
        (libc::SIGINT, "rel-frames-int"),
        (libc::SIGTERM, "rel-frames-term"),
    ] {
        let dir = support::temp_dir(name);
        let args = [
            "render",
            "--size",
            "8x8",
            "--slabs",
            "4",
            "--frames",
            "0..1000000",
            "-o",
            "f_%07d.png",
            "--quiet",
        ];
        let mut child = spawn_cli(&args, &dir);
        let start = std::time::Instant::now();
        while files_in(&dir)
            .iter()
            .filter(|n| n.ends_with(".png"))
            .count()
            < 3
        {
            assert!(start.elapsed().as_secs() < 120, "no frames written");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let (code, err, _) = signal_and_wait(&mut child, signal);
        assert_eq!(code, Some(130), "{name}: {err}");
        let on_disk = files_in(&dir);
        assert!(
            on_disk
                .iter()
                .all(|n| n.starts_with("f_") && n.ends_with(".png")),
            "{name}: only complete frames, no temporary file: {on_disk:?}"
        );
        let first = on_disk.first().unwrap();
        let last = on_disk.last().unwrap();
        assert_eq!(first, "f_0000000.png");
        // Up to 8 files by name, else the count, the first and the last.
        let listed = if on_disk.len() <= 8 {
            on_disk.join(", ")
        } else {
            format!("{} files, {first} … {last}", on_disk.len())
        };
        let want = format!("error: interrupted; written before the signal, complete: {listed}");
        assert!(err.contains(&want), "{name}: {err}\nwanted: {want}");
        for n in &on_disk {
            let img = image::open(dir.join(n)).unwrap_or_else(|e| panic!("{n}: {e}"));
            assert_eq!((img.width(), img.height()), (8, 8), "{n}");
        }
    }
}
