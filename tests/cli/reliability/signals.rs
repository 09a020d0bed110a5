//! Signals: SIGINT and SIGTERM stop a render (mid-sweep, while loading textures or NIfTI, in
//! the LDI, between frames), the reference and the report promptly with exit code 130, and leave
//! no output or temporary file behind.

use super::*;

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
