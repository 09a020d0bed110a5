//! The release build targets x86-64-v3 (`.cargo/config.toml`); on a processor without those
//! instructions the binary must say so in one line and exit with code 8, never die with SIGILL.
//! Checked for real on processors emulated by qemu-user (`qemu-x86_64 -cpu MODEL`): Nehalem and
//! Westmere lack AVX2, Haswell has every v3 extension. `.ci/run` installs qemu-user; on a
//! developer machine without it the test says so and skips.

use std::process::Command;

/// `qemu-x86_64`, if installed (required under CI).
fn qemu() -> Option<&'static str> {
    let found = Command::new("qemu-x86_64").arg("-version").output().is_ok();
    if found {
        Some("qemu-x86_64")
    } else if std::env::var_os("CI").is_some() {
        panic!("qemu-x86_64 not found (CI installs qemu-user in .ci/run)");
    } else {
        eprintln!("SKIP: qemu-x86_64 not found (apt-get install qemu-user); CPU check not run");
        None
    }
}

/// Runs the binary with `args` on an emulated `cpu`: (exit code or signal, stdout, stderr).
fn run_on(cpu: &str, args: &[&str]) -> Option<(Result<i32, i32>, String, String)> {
    use std::os::unix::process::ExitStatusExt;
    let q = qemu()?;
    let out = Command::new(q)
        .args(["-cpu", cpu, env!("CARGO_BIN_EXE_convshadow")])
        .args(args)
        .output()
        .expect("run qemu-x86_64");
    let code = out
        .status
        .code()
        .ok_or_else(|| out.status.signal().unwrap_or(-1));
    let err = String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| !l.contains("TCG doesn't support"))
        .collect::<Vec<_>>()
        .join("\n");
    Some((code, String::from_utf8_lossy(&out.stdout).into(), err))
}

#[test]
fn without_avx2_the_binary_says_so_and_exits_8() {
    // Built for baseline x86-64 (RUSTFLAGS) the binary has no requirement: nothing to check.
    if !cfg!(target_feature = "avx2") {
        eprintln!("SKIP: this build does not target x86-64-v3");
        return;
    }
    for cpu in ["Nehalem", "Westmere"] {
        for args in [
            &["--version"][..],
            &["render", "--size", "8x8", "-o", "never.png"][..],
        ] {
            let Some((code, out, err)) = run_on(cpu, args) else {
                return;
            };
            assert_eq!(code, Ok(8), "{cpu} {args:?}: stderr {err:?}");
            assert_eq!(err.lines().count(), 1, "{cpu}: one line, got {err:?}");
            assert!(
                err.starts_with("error: this convshadow was built for x86-64-v3")
                    && err.contains("AVX2")
                    && err.contains("target-cpu=native"),
                "{cpu}: {err:?}"
            );
            assert!(out.is_empty(), "{cpu}: nothing on stdout, got {out:?}");
        }
    }
    assert!(!std::path::Path::new("never.png").exists());
}

#[test]
fn with_every_v3_extension_the_check_passes() {
    let Some((code, out, err)) = run_on("Haswell", &["--version"]) else {
        return;
    };
    assert_eq!(code, Ok(0), "stderr {err:?}");
    assert!(out.starts_with("convshadow "), "{out:?}");
}
