//! The release build targets x86-64-v3 (`.cargo/config.toml`), and `common/src/lane.rs` has an
//! AVX2 branch and a portable branch for several 8-lane operations. The portable branches are what
//! a build for an older processor runs (`RUSTFLAGS="-C target-cpu=native"`, as the config file
//! advises there): this test builds the lane module's tests for baseline x86-64 (a target folder
//! of its own, `target/baseline-x86-64`) and runs them, so a portable branch that disagrees with
//! the 1-lane path fails here as the AVX2 branches fail in the normal build. It builds with the
//! unoptimised `baseline-lanes` profile (Cargo.toml; optimisation changes no float result): about
//! a minute on a fresh machine, seconds once built.

use std::path::Path;
use std::process::Command;

/// Flags of a build for baseline x86-64 (they replace the config file's, as `RUSTFLAGS` does).
const BASELINE: &str = "-C target-cpu=x86-64";

#[test]
fn the_lane_tests_pass_in_a_build_for_baseline_x86_64() {
    if !cfg!(target_feature = "avx2") {
        eprintln!("SKIP: this build is not for x86-64-v3; its own lane tests ran its branches");
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());

    // The flags really leave AVX2 out (else the portable branches would not be compiled).
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let cfg = Command::new(&rustc)
        .args(["--print", "cfg"])
        .args(BASELINE.split(' '))
        .output()
        .expect("run rustc --print cfg");
    let cfg = String::from_utf8_lossy(&cfg.stdout);
    assert!(
        cfg.contains("target_feature=\"sse2\"") && !cfg.contains("target_feature=\"avx2\""),
        "{BASELINE} should give SSE2 and no AVX2:\n{cfg}"
    );

    let out = Command::new(cargo)
        .current_dir(root)
        .env("RUSTFLAGS", BASELINE)
        // Either would take precedence over RUSTFLAGS.
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("CARGO_BUILD_RUSTFLAGS")
        .env("CARGO_TARGET_DIR", root.join("target/baseline-x86-64"))
        .args([
            "test",
            "--profile",
            "baseline-lanes",
            "-p",
            "convshadow-common",
            "--lib",
            "lane::",
        ])
        .output()
        .expect("run cargo test for baseline x86-64");
    let text = format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.status.success(),
        "lane tests in the baseline build:\n{text}"
    );
    // Every lane test ran (a filter that matched nothing would pass with 0).
    let passed: usize = text
        .lines()
        .filter_map(|l| l.strip_prefix("test result: ok. "))
        .filter_map(|l| l.split(' ').next()?.parse::<usize>().ok())
        .sum();
    assert!(
        passed >= 5,
        "expected the lane module's tests to run, got {passed}:\n{text}"
    );
}
