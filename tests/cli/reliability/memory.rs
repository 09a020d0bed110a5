//! Memory limits of the `convshadow` binary: a scene over `--max-memory` (or over the machine) is
//! refused before allocating, allocations sized by a scene value stay within the budget
//! (measured as the child's peak RSS), and textures count before they are read.

use super::*;

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
