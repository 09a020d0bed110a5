//! Issue 43, classes 4–7 (docs/errors.md, "Hardening"): outputs checked before the work and
//! never written in place or over an input, gates that can fail, bad input refused, and messages
//! that name the right culprit. Each test failed on the code before its fix.

use crate::support;

use std::path::Path;

use convshadow::io::image::RgbImage;

/// Exit codes (docs/errors.md).
const BAD_ARGUMENTS: i32 = 2;
const BAD_INPUT: i32 = 3;
const OUTPUT_FAILED: i32 = 7;

/// Runs `convshadow ARGS` in `dir`.
fn cli(dir: &Path, args: &[&str]) -> (i32, String, String) {
    support::run_cli(args, dir)
}

/// Asserts a refusal: the code, one error line, no panic, and the words.
fn refused(what: &str, (code, _, err): &(i32, String, String), expected: i32, words: &[&str]) {
    assert!(!err.contains("panicked"), "{what}: panicked:\n{err}");
    assert_eq!(*code, expected, "{what}: exit code; stderr:\n{err}");
    for w in words {
        assert!(err.contains(w), "{what}: message must name {w:?}: {err}");
    }
}

// ---------------------------------------------------------------------------------------------
// Class 5: gates that cannot fail, or fail wrongly.

#[test]
fn diff_limits_that_no_gate_can_use_are_bad_arguments() {
    let dir = support::temp_dir("h43-diff-limits");
    support::exr_with(&dir, "a.exr", 0.25);
    support::exr_with(&dir, "b.exr", 9.0);
    // NaN made `value > limit` false for every image: the gate always passed (exit 0).
    for (flag, value) in [
        ("--max-abs", "NaN"),
        ("--max-rmse", "nan"),
        ("--max-flip", "NaN"),
        ("--max-abs", "-1"),
        ("--max-rmse", "-0.5"),
        ("--max-abs", "inf"),
    ] {
        let arg = format!("{flag}={value}");
        let r = cli(&dir, &["diff", "a.exr", "b.exr", &arg]);
        refused(&arg, &r, BAD_ARGUMENTS, &[flag, "finite", ">= 0"]);
    }
    // Valid limits still gate: 0 passes identical images, fails different ones.
    assert_eq!(
        cli(&dir, &["diff", "a.exr", "a.exr", "--max-abs", "0"]).0,
        0
    );
    assert_eq!(
        cli(&dir, &["diff", "a.exr", "b.exr", "--max-abs", "0"]).0,
        1
    );
}

#[test]
fn identical_images_holding_infinities_differ_by_nothing() {
    let dir = support::temp_dir("h43-diff-inf");
    support::exr_with(&dir, "a.exr", f32::INFINITY);
    support::exr_with(&dir, "b.exr", f32::INFINITY);
    support::exr_with(&dir, "m.exr", f32::NEG_INFINITY);
    // inf − inf is NaN: bit-identical images failed `--max-rmse 0`.
    let r = cli(
        &dir,
        &[
            "diff",
            "a.exr",
            "b.exr",
            "--max-rmse",
            "0",
            "--max-abs",
            "0",
            "--json",
            "d.json",
        ],
    );
    assert_eq!(r.0, 0, "{}{}", r.1, r.2);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("d.json")).unwrap()).unwrap();
    assert_eq!(j["rmse"], 0.0, "{j}");
    assert_eq!(j["max_abs_error"], 0.0, "{j}");
    assert_eq!(j["bit_identical"], true, "{j}");
    // Different infinities still differ, infinitely.
    let r = cli(&dir, &["diff", "a.exr", "m.exr", "--max-abs", "1e30"]);
    assert_eq!(r.0, 1, "{}{}", r.1, r.2);
    // Counts are printed as integers.
    let r = cli(
        &dir,
        &["diff", "a.exr", "m.exr", "--max-differing-pixels", "0"],
    );
    assert!(
        r.2.contains("8-bit differing pixels 1 (limit 0)"),
        "{}",
        r.2
    );
}

// ---------------------------------------------------------------------------------------------
// Class 4: outputs checked after the work, or written in place.

#[test]
fn diff_writes_its_heatmap_by_rename_not_in_place() {
    let dir = support::temp_dir("h43-heatmap");
    support::exr_with(&dir, "a.exr", 0.25);
    support::exr_with(&dir, "b.exr", 0.5);
    // heat.png is a second name of keep.png: writing in place changed keep.png too.
    std::fs::write(dir.join("keep.png"), b"keep").unwrap();
    std::fs::hard_link(dir.join("keep.png"), dir.join("heat.png")).unwrap();
    let r = cli(&dir, &["diff", "a.exr", "b.exr", "--heatmap", "heat.png"]);
    assert_eq!(r.0, 0, "{}{}", r.1, r.2);
    assert_eq!(std::fs::read(dir.join("keep.png")).unwrap(), b"keep");
    assert!(image::open(dir.join("heat.png")).is_ok());
    // An output naming an input (here through a symbolic link) is refused before any work.
    std::os::unix::fs::symlink("a.exr", dir.join("link.png")).unwrap();
    let before = std::fs::read(dir.join("a.exr")).unwrap();
    let r = cli(&dir, &["diff", "a.exr", "b.exr", "--heatmap", "link.png"]);
    refused("heatmap over A", &r, BAD_ARGUMENTS, &["link.png", "a.exr"]);
    let r = cli(&dir, &["diff", "a.exr", "b.exr", "--json", "b.exr"]);
    refused("json over B", &r, BAD_ARGUMENTS, &["b.exr", "input"]);
    assert_eq!(std::fs::read(dir.join("a.exr")).unwrap(), before);
}

#[test]
fn render_refuses_outputs_over_its_inputs_and_checks_every_frame_before_rendering() {
    let dir = support::temp_dir("h43-render-outputs");
    let scene = support::lone_box_scene(16, 8).replace(
        "[[light]]",
        "[[light]]\npattern = { path = \"gobo.png\", size = [4.0, 4.0] }",
    );
    std::fs::write(dir.join("s.toml"), &scene).unwrap();
    support::exr_with(&dir, "gobo.exr", 0.5);
    RgbImage::load(&dir.join("gobo.exr"))
        .unwrap()
        .save(&dir.join("gobo.png"))
        .unwrap();
    std::fs::remove_file(dir.join("gobo.exr")).unwrap();
    let gobo = std::fs::read(dir.join("gobo.png")).unwrap();
    let before = support::files_in(&dir);
    // `--stats-json s.toml` replaced the scene with JSON (exit 0).
    let r = cli(
        &dir,
        &["render", "s.toml", "-o", "a.png", "--stats-json", "s.toml"],
    );
    refused(
        "stats over scene",
        &r,
        BAD_ARGUMENTS,
        &["s.toml", "the scene"],
    );
    assert_eq!(std::fs::read_to_string(dir.join("s.toml")).unwrap(), scene);
    // An output over the light's pattern, spelled another way.
    let r = cli(&dir, &["render", "s.toml", "-o", "./gobo.png", "-q"]);
    refused(
        "png over pattern",
        &r,
        BAD_ARGUMENTS,
        &["light[0].pattern.path"],
    );
    assert_eq!(std::fs::read(dir.join("gobo.png")).unwrap(), gobo);
    // A later frame's missing folder failed after frame 0 was written.
    std::fs::create_dir(dir.join("o0")).unwrap();
    let r = cli(
        &dir,
        &[
            "render",
            "s.toml",
            "-o",
            "o%d/a.png",
            "--frames",
            "0..2",
            "-q",
        ],
    );
    refused(
        "frame 1's folder",
        &r,
        OUTPUT_FAILED,
        &["o1", "does not exist"],
    );
    assert!(
        support::files_in(&dir.join("o0")).is_empty(),
        "frame 0 was written"
    );
    std::fs::remove_dir(dir.join("o0")).unwrap();
    // Two patterns that meet on frame 10 overwrote each other silently.
    let r = cli(
        &dir,
        &[
            "render",
            "s.toml",
            "-o",
            "a_%d.png",
            "-o",
            "a_%02d.png",
            "--frames",
            "9..11",
            "-q",
        ],
    );
    refused(
        "colliding patterns",
        &r,
        BAD_ARGUMENTS,
        &["same file", "frame 10"],
    );
    // A name too long for the file system failed after the render.
    let long = format!("{}.png", "x".repeat(300));
    let r = cli(&dir, &["render", "s.toml", "-o", &long, "-q"]);
    refused("long name", &r, OUTPUT_FAILED, &["at most 255"]);
    let r = cli(&dir, &["render", "s.toml", "-o", "a.png/", "-q"]);
    refused("trailing slash", &r, OUTPUT_FAILED, &["names a folder"]);
    assert_eq!(support::files_in(&dir), before, "nothing was written");
    // A frame range too long to check (and to render) is a bad argument, before the outputs
    // (`0..4000000000` collected 16 GB of frame numbers).
    let r = cli(
        &dir,
        &[
            "render",
            "s.toml",
            "-o",
            "no/f_%d.png",
            "--frames",
            "0..2000000",
        ],
    );
    refused(
        "huge range",
        &r,
        BAD_ARGUMENTS,
        &["--frames", "at most 1000000"],
    );
}

#[test]
fn report_checks_its_outputs_before_any_case_and_writes_by_rename() {
    let dir = support::temp_dir("h43-report");
    // `--case` past the grid left an empty folder behind.
    let r = cli(
        &dir,
        &["report", "--quick", "--case", "99999", "--out", "new"],
    );
    refused("case out of range", &r, BAD_ARGUMENTS, &["--case 99999"]);
    assert!(!dir.join("new").exists(), "a folder was created");
    // report.csv as a folder: refused before the case runs (`-v` prints a line per case run).
    std::fs::create_dir_all(dir.join("r/report.csv")).unwrap();
    let r = cli(
        &dir,
        &["report", "--quick", "--case", "0", "--out", "r", "-v"],
    );
    refused(
        "report.csv a folder",
        &r,
        OUTPUT_FAILED,
        &["report.csv", "is a folder"],
    );
    assert!(
        !r.2.contains(" n="),
        "a case ran before the check:\n{}",
        r.2
    );
    // report.csv is a second name of keep.csv: writing in place changed keep.csv too.
    std::fs::create_dir(dir.join("s")).unwrap();
    std::fs::write(dir.join("keep.csv"), "keep").unwrap();
    std::fs::hard_link(dir.join("keep.csv"), dir.join("s/report.csv")).unwrap();
    let r = cli(&dir, &["report", "--quick", "--case", "0", "--out", "s"]);
    assert_eq!(r.0, 0, "{}{}", r.1, r.2);
    assert_eq!(
        std::fs::read_to_string(dir.join("keep.csv")).unwrap(),
        "keep"
    );
    let csv = std::fs::read_to_string(dir.join("s/report.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
    assert_eq!(
        support::files_in(&dir.join("s")),
        ["report.csv"],
        "no temporary file left"
    );
}

// ---------------------------------------------------------------------------------------------
// Class 6: bad input accepted.

#[test]
fn table_keys_refuse_arrays_read_in_field_order() {
    let dir = support::temp_dir("h43-tables");
    let base = support::lone_box_scene(16, 8);
    // Each was read positionally into the table's fields (exit 0, or a message about a field
    // the file never names).
    for (name, from, to) in [
        (
            "specular",
            "[material.m]",
            "[material.m]\nspecular = [\"blinn-phong\", 0.5, 8, 0.04]",
        ),
        ("phase", "[material.m]", "[material.m]\nphase = [0.3]"),
        (
            "image",
            "[image]\nwidth = 16\nheight = 16",
            "image = [16, 16]",
        ),
        (
            "pattern",
            "[[light]]",
            "[[light]]\npattern = [\"gobo.png\", [1.0, 1.0], [0.0, 0.0]]",
        ),
        (
            "detail",
            "[material.m]",
            "[material.m]\ndetail = [\"fbm\", 2.0]\ngradient = [[0, 1, 1, 1, 1], [1, 1, 1, 1, 1]]",
        ),
    ] {
        let text = base.replacen(from, to, 1);
        assert_ne!(text, base, "{name}: the edit applies");
        std::fs::write(dir.join("t.toml"), text).unwrap();
        let r = cli(&dir, &["render", "t.toml", "-o", "a.png", "-q"]);
        refused(
            name,
            &r,
            BAD_INPUT,
            &["t.toml", name, "expected a table", "line "],
        );
    }
    // Tables still read, and their own errors keep naming the key inside them.
    let text = base.replacen(
        "[material.m]",
        "[material.m]\nspecular = { exponent = 8 }",
        1,
    );
    std::fs::write(dir.join("t.toml"), text).unwrap();
    assert_eq!(cli(&dir, &["render", "t.toml", "-o", "a.png", "-q"]).0, 0);
    assert!(!dir.join("t.toml").with_file_name(".a.png.partial").exists());
}

/// The lone box with a 4D-able fBm detail.
fn detail_scene() -> String {
    support::lone_box_scene(16, 8).replacen(
        "[material.m]",
        "[material.m]\ndetail = { kind = \"fbm\", frequency = 2.0 }\n\
         gradient = [[0, 1, 1, 1, 0.5], [1, 1, 1, 1, 0.5]]",
        1,
    )
}

#[test]
fn time_steps_that_push_the_detail_time_past_its_limit_are_refused_before_rendering() {
    let dir = support::temp_dir("h43-time-step");
    std::fs::write(dir.join("d.toml"), detail_scene()).unwrap();
    // Frame 2 at 2e9: past |detail.time| <= 1e9 (rendered flat, exit 0).
    for args in [
        &["--frames", "0..3", "--time-step", "1e9"][..],
        &["--frame", "2", "--time-step", "6e8"],
        &["--frames", "0..3", "--time-step", "-6e8"],
    ] {
        let mut argv = vec!["render", "d.toml", "-o", "f_%d.png", "-q"];
        argv.extend(args);
        let r = cli(&dir, &argv);
        refused(
            &format!("{args:?}"),
            &r,
            BAD_ARGUMENTS,
            &["--time-step", "frame 2", "material.m.detail.time", "1e9"],
        );
    }
    assert_eq!(support::files_in(&dir), ["d.toml"]);
    // Within the limit: rendered, and times print as decimals (3 × 0.1 is not 0.3 in binary).
    let r = cli(
        &dir,
        &[
            "render",
            "d.toml",
            "-o",
            "f_%d.png",
            "--frames",
            "0..4",
            "--time-step",
            "0.1",
        ],
    );
    assert_eq!(r.0, 0, "{}{}", r.1, r.2);
    assert!(r.1.contains("frame 3 (time 0.3)"), "{}", r.1);
}

// ---------------------------------------------------------------------------------------------
// Class 7: messages that name the wrong culprit.

#[test]
fn raw_texture_dims_beyond_the_limits_are_bad_dims_not_memory() {
    let dir = support::temp_dir("h43-raw-dims");
    for dims in [
        "[4294967295, 1, 1]",
        "[16777217, 1, 1]",
        "[65536, 65536, 1]",
    ] {
        let text = support::lone_box_scene(16, 8).replacen(
            "[material.m]",
            &format!(
                "[material.m]\ntexture = {{ path = \"t.raw\", dims = {dims}, type = \"u8\" }}\n\
                 gradient = [[0, 1, 1, 1, 0.5], [1, 1, 1, 1, 0.5]]"
            ),
            1,
        );
        std::fs::write(dir.join("t.toml"), text).unwrap();
        let r = cli(&dir, &["render", "t.toml", "-o", "a.png", "-q"]);
        refused(
            dims,
            &r,
            BAD_INPUT,
            &["texture.dims", "16777216", "268435456"],
        );
        assert!(!r.2.contains("MiB"), "{dims}: {}", r.2);
    }
}

#[test]
fn an_obj_with_a_byte_order_mark_keeps_its_first_vertex() {
    let dir = support::temp_dir("h43-bom");
    let mut obj = String::from("\u{feff}");
    for z in [-0.5, 0.5] {
        for y in [-0.5, 0.5] {
            for x in [-0.5, 0.5] {
                obj.push_str(&format!("v {x} {y} {z}\n"));
            }
        }
    }
    // The 12 outward triangles of the cube (vertex i = x + 2y + 4z, 1-based).
    for f in [
        [1, 3, 4],
        [1, 4, 2],
        [5, 6, 8],
        [5, 8, 7],
        [1, 2, 6],
        [1, 6, 5],
        [3, 7, 8],
        [3, 8, 4],
        [1, 5, 7],
        [1, 7, 3],
        [2, 4, 8],
        [2, 8, 6],
    ] {
        obj.push_str(&format!("f {} {} {}\n", f[0], f[1], f[2]));
    }
    std::fs::write(dir.join("cube.obj"), &obj).unwrap();
    std::fs::write(dir.join("plain.obj"), &obj[3..]).unwrap();
    let scene = |name: &str| support::obj_scene(&dir.join(name), 16, 3.0);
    std::fs::write(dir.join("bom.toml"), scene("cube.obj")).unwrap();
    std::fs::write(dir.join("plain.toml"), scene("plain.obj")).unwrap();
    let r = cli(&dir, &["ldi", "plain.toml"]);
    assert_eq!(r.0, 0, "control: {}{}", r.1, r.2);
    // With the mark, the first `v` was an unknown keyword and a face named a missing vertex.
    let b = cli(&dir, &["ldi", "bom.toml"]);
    assert_eq!(b.0, 0, "{}{}", b.1, b.2);
    let hash = |out: &str| {
        out.lines()
            .find(|l| l.contains("ldi_hash"))
            .map(str::to_string)
    };
    assert!(hash(&r.1).is_some(), "{}", r.1);
    assert_eq!(hash(&b.1), hash(&r.1), "the same LDI as without the mark");
}

// ---------------------------------------------------------------------------------------------
// Also: `--size` with the scene's own aspect keeps view_width.

#[test]
fn size_with_the_same_aspect_keeps_the_view_width_exactly() {
    let dir = support::temp_dir("h43-size");
    // 1×7 px, 1.1 wide: 1.1 · 7/1 · 5/35 is 1.1000000000000003 in floats.
    let scene = support::lone_box_scene(16, 8)
        .replace("width = 16\nheight = 16", "width = 1\nheight = 7")
        .replace("view_width = 4.0", "view_width = 1.1");
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let r = cli(&dir, &["render", "s.toml", "--size", "5x35", "-o", "a.png"]);
    assert_eq!(r.0, 0, "{}{}", r.1, r.2);
    assert!(!r.2.contains("view_width"), "view_width changed: {}", r.2);
    assert!(r.1.contains("rendered 5x35 px"), "{}", r.1);
}

#[test]
fn stats_carry_the_version_that_wrote_them() {
    let dir = support::temp_dir("h43-version");
    std::fs::write(dir.join("s.toml"), support::lone_box_scene(16, 8)).unwrap();
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(name)).unwrap()).unwrap()
    };
    let r = cli(
        &dir,
        &[
            "render",
            "s.toml",
            "-o",
            "a.png",
            "-q",
            "--stats-json",
            "r.json",
        ],
    );
    assert_eq!(r.0, 0, "{}", r.2);
    let r = cli(&dir, &["ldi", "s.toml", "--stats-json", "l.json"]);
    assert_eq!(r.0, 0, "{}", r.2);
    for name in ["r.json", "l.json"] {
        assert_eq!(read(name)["version"], env!("CARGO_PKG_VERSION"), "{name}");
    }
}

#[test]
fn bad_point_and_spot_lights_exit_3_without_an_output_file() {
    let dir = support::temp_dir("h-point-lights");
    let base = support::lone_box_scene(16, 8);
    // The lone box's directional light, replaced whole.
    const LIGHT: &str = "[[light]]\ntilt_deg = [20.0, 10.0]\nvariance = [0.02, 0.02]";
    let point =
        |rest: &str| format!("[[light]]\nkind = \"point\"\nposition = [0.0, 0.0, -2.0]\n{rest}");
    for (name, light, backend, words) in [
        ("negative radius", point("radius = -1.0"), "cpu", vec!["light[0].radius", "from 0"]),
        (
            "cone of 90°",
            "[[light]]\nkind = \"spot\"\nposition = [0.0, 0.0, -2.0]\ndirection = [0.0, 0.0, 1.0]\ncone_deg = 90.0".to_string(),
            "cpu",
            vec!["light[0].cone_deg", "0 to 89"],
        ),
        ("zero spot axis", "[[light]]\nkind = \"spot\"\nposition = [0.0, 0.0, -2.0]\ndirection = [0.0, 0.0, 0.0]\ncone_deg = 20.0".to_string(), "cpu", vec!["light[0].direction"]),
        ("tilt on a point light", point("tilt_deg = [10.0, 0.0]"), "reference", vec!["light[0].tilt_deg", "directional"]),
        (
            // Beside the box, at a view depth within its depth range: it cannot be split there.
            "within a mesh's depth range in the sweep",
            "[[light]]\nkind = \"point\"\nposition = [5.0, 0.0, 0.0]".to_string(),
            "cpu",
            vec!["light[0].position", "mesh[0]'s depth range", "--backend reference"],
        ),
        (
            "inside the box",
            "[[light]]\nkind = \"point\"\nposition = [0.0, 0.0, 0.0]".to_string(),
            "reference",
            vec!["light[0].position", "inside closed mesh[0]"],
        ),
    ] {
        let text = base.replacen(LIGHT, &light, 1);
        assert_ne!(text, base, "{name}: the edit applies");
        std::fs::write(dir.join("t.toml"), text).unwrap();
        let r = cli(&dir, &["render", "t.toml", "--backend", backend, "-o", "a.png", "-q"]);
        refused(name, &r, BAD_INPUT, &words);
        assert!(!dir.join("a.png").exists(), "{name}: no output file");
    }
    // A point light outside the box renders with the reference.
    let text = base.replacen(LIGHT, &point("radius = 0.05"), 1);
    std::fs::write(dir.join("t.toml"), text).unwrap();
    let r = cli(
        &dir,
        &[
            "render",
            "t.toml",
            "--backend",
            "reference",
            "--reference-samples",
            "4",
            "-o",
            "a.png",
            "-q",
        ],
    );
    assert_eq!(r.0, 0, "{}", r.2);
    assert!(dir.join("a.png").exists());
    // Before the box it renders with the sweep, hard and soft; soft with the iterated penumbra
    // it is refused, naming the key and the backend that renders it.
    for light in [point(""), point("radius = 0.05")] {
        std::fs::remove_file(dir.join("a.png")).unwrap();
        std::fs::write(dir.join("t.toml"), base.replacen(LIGHT, &light, 1)).unwrap();
        let r = cli(&dir, &["render", "t.toml", "-o", "a.png", "-q"]);
        assert_eq!(r.0, 0, "{light}: {}", r.2);
        assert!(dir.join("a.png").exists());
    }
    std::fs::remove_file(dir.join("a.png")).unwrap();
    let r = cli(
        &dir,
        &[
            "render",
            "t.toml",
            "--penumbra",
            "iterated",
            "-o",
            "a.png",
            "-q",
        ],
    );
    refused(
        "soft, iterated",
        &r,
        BAD_INPUT,
        &["sweep.penumbra", "--backend reference"],
    );
    assert!(!dir.join("a.png").exists(), "no output file");
}

#[test]
fn a_light_grid_beyond_the_largest_side_is_a_resource_limit_without_an_output() {
    let dir = support::temp_dir("h-light-grid");
    std::fs::write(dir.join("t.toml"), support::lone_box_scene(16, 8)).unwrap();
    // 4096 px at 16 cells a pixel: a 65536-cell grid, beyond the 16384 a side of any image.
    let r = cli(
        &dir,
        &[
            "render",
            "t.toml",
            "--size",
            "4096x4096",
            "--light-resolution",
            "16",
            "-o",
            "a.png",
            "-q",
        ],
    );
    refused(
        "a huge light grid",
        &r,
        4,
        &["light grid", "65536", "sweep.light_resolution"],
    );
    assert!(!dir.join("a.png").exists());
    // Out of its range it is a bad argument, naming the key.
    let r = cli(
        &dir,
        &[
            "render",
            "t.toml",
            "--light-resolution",
            "17",
            "-o",
            "a.png",
            "-q",
        ],
    );
    refused(
        "light resolution 17",
        &r,
        BAD_ARGUMENTS,
        &["light_resolution"],
    );
    assert!(!dir.join("a.png").exists());
}
