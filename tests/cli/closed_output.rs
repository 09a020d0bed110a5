//! Every command with its stdout a closed pipe, its stdout a full device, or its stderr a closed
//! pipe (issue 43, class 2: these panicked with "failed printing to stdout", exit 101). The
//! documented codes (docs/errors.md, "Standard output and error"): a closed pipe is not an error
//! (the command keeps its exit code), a full device lost output (7 where the command would exit
//! 0), a broken stderr changes nothing.

use crate::support;

use std::fs::File;
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// Where the command's stdout goes.
#[derive(Clone, Copy, Debug)]
enum Sink {
    /// A pipe whose reading end is already closed: every write fails with EPIPE.
    ClosedPipe,
    /// `/dev/full`: every write fails with ENOSPC.
    Full,
}

/// Runs the binary in `dir` with stdout into `sink` and stderr captured (or, with
/// `stderr_closed`, stderr into a closed pipe too).
fn run(args: &[&str], dir: &Path, sink: Sink, stderr_closed: bool) -> Output {
    let stdout: Stdio = match sink {
        Sink::ClosedPipe => {
            let (reader, writer) = std::io::pipe().expect("a pipe");
            drop(reader);
            writer.into()
        }
        Sink::Full => File::options()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full")
            .into(),
    };
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_convshadow"));
    cmd.args(args).current_dir(dir).stdout(stdout);
    if stderr_closed {
        let (reader, writer) = std::io::pipe().expect("a pipe");
        drop(reader);
        cmd.stderr(writer);
    } else {
        cmd.stderr(Stdio::piped());
    }
    cmd.output().expect("the binary runs")
}

#[test]
fn every_command_survives_a_closed_or_full_stdout() {
    let dir = support::temp_dir("closed-output");
    for (name, slabs) in [("a.exr", "4"), ("b.exr", "5")] {
        let args = [
            "render", "--size", "8x8", "--slabs", slabs, "-o", name, "--quiet",
        ];
        let (code, out, err) = support::run_cli(&args, &dir);
        assert_eq!(code, 0, "{out}{err}");
    }
    let commands: [&[&str]; 7] = [
        &["--help"],
        &["render", "--help"],
        &["diff", "a.exr", "b.exr"],
        &["render", "--size", "8x8", "--slabs", "4", "-o", "x.png"],
        &["ldi", "--width", "8", "--height", "8"],
        &["report", "--help"],
        &["ldi", "--help"],
    ];
    for args in commands {
        for sink in [Sink::ClosedPipe, Sink::Full] {
            let out = run(args, &dir, sink, false);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(!stderr.contains("panicked"), "{args:?} {sink:?}: {stderr}");
            let want = match sink {
                Sink::ClosedPipe => 0,
                Sink::Full => 7,
            };
            assert_eq!(out.status.code(), Some(want), "{args:?} {sink:?}: {stderr}");
            if let Sink::Full = sink {
                assert!(
                    stderr.contains("error: standard output: "),
                    "{args:?}: {stderr}"
                );
            }
        }
    }
    // A failing command keeps its own code whatever stdout and stderr do.
    let thresholds = ["diff", "a.exr", "b.exr", "--max-rmse", "0"];
    for sink in [Sink::ClosedPipe, Sink::Full] {
        for stderr_closed in [false, true] {
            let out = run(&thresholds, &dir, sink, stderr_closed);
            assert_eq!(
                out.status.code(),
                Some(1),
                "{sink:?}, stderr closed {stderr_closed}"
            );
            let bad = run(&["render", "missing.toml"], &dir, sink, stderr_closed);
            assert_eq!(
                bad.status.code(),
                Some(3),
                "{sink:?}, stderr closed {stderr_closed}"
            );
        }
    }
}

#[test]
fn an_absurd_frame_pattern_width_is_a_bad_argument_not_a_panic() {
    // `%070000d` made `format!` panic (a width beyond u16::MAX); an overflowing width too.
    let dir = support::temp_dir("frame-width");
    for pattern in ["f_%070000d.png", "f_%099999999999d.png", "f_%021d.png"] {
        let args = [
            "render", "--size", "8x8", "--slabs", "4", "--frames", "0..2", "-o", pattern,
        ];
        let (code, out, err) = support::run_cli(&args, &dir);
        assert_eq!(code, 2, "{pattern}: {out}{err}");
        assert!(!err.contains("panicked"), "{pattern}: {err}");
        assert!(err.contains("at most 20 digits"), "{pattern}: {err}");
    }
    // The widest allowed pads to 20 digits.
    let args = [
        "render",
        "--size",
        "8x8",
        "--slabs",
        "4",
        "--frames",
        "0..2",
        "-o",
        "f_%020d.png",
        "--quiet",
    ];
    let (code, out, err) = support::run_cli(&args, &dir);
    assert_eq!(code, 0, "{out}{err}");
    assert!(dir.join("f_00000000000000000001.png").is_file());
}
