//! The `convshadow` command line.

use clap::{Parser, Subcommand};

mod cli;

use cli::exit;

/// Iterative convolution shadows for closed meshes filled with volumetric detail.
#[derive(Parser, Debug)]
#[command(name = "convshadow", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Compare two images (EXR or PNG; A is the reference): errors, PSNR, FLIP, 8-bit sRGB
    /// differences, optional JSON and heat-map.
    Diff(cli::diff::DiffArgs),
    /// Build the layered depth image and report fragments, layers and mesh defects.
    Ldi(cli::ldi::LdiArgs),
    /// Render a scene (the embedded default scene without SCENE) to PNG and/or EXR.
    Render(Box<cli::render::RenderArgs>),
    /// Speed against error: render a grid of cases (kernels × slab counts × lights) and write
    /// report.csv, report.md and speed_vs_error.png.
    Report(cli::report::ReportArgs),
}

/// Gives the process a private runtime folder when `XDG_RUNTIME_DIR` is unset or unusable (not
/// a folder, or open to others), so the Vulkan loader and Mesa do not print "XDG_RUNTIME_DIR is
/// invalid" on a successful GPU run (docs/gpu.md).
fn ensure_runtime_dir() {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let valid = std::env::var_os("XDG_RUNTIME_DIR")
        .is_some_and(|d| std::fs::metadata(&d).is_ok_and(|m| m.is_dir() && m.mode() & 0o077 == 0));
    if valid {
        return;
    }
    let uid = std::fs::metadata("/proc/self").map_or(0, |m| m.uid());
    let dir = std::env::temp_dir().join(format!("convshadow-runtime-{uid}"));
    let ok = std::fs::create_dir_all(&dir).is_ok()
        && std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)).is_ok()
        && std::fs::metadata(&dir).is_ok_and(|m| m.uid() == uid);
    if ok {
        // SAFETY: called first thing in main, before any other thread exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

/// Ends the process with `code`, first writing its peak resident set (`VmHWM` of
/// `/proc/self/status`, KiB) to the file `CONVSHADOW_PEAK_RSS_FILE` names, if set: the memory
/// tests' measure of this process alone (a parent's `wait4` counts the parent's own peak in a
/// child started by `vfork`, docs/errors.md, "Measuring a run's memory").
fn finish(code: i32) -> ! {
    if let Some(path) = std::env::var_os("CONVSHADOW_PEAK_RSS_FILE") {
        let peak = std::fs::read_to_string("/proc/self/status")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find_map(|l| l.strip_prefix("VmHWM:"))
                    .map(|v| v.trim().trim_end_matches("kB").trim().to_string())
            })
            .unwrap_or_default();
        let _ = std::fs::write(path, peak);
    }
    std::process::exit(code)
}

fn main() {
    ensure_runtime_dir();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() {
                exit::BAD_ARGUMENTS
            } else {
                exit::OK
            };
            // Arguments may hold control characters: print them escaped.
            let text = exit::escape_controls(&e.render().to_string());
            if e.use_stderr() {
                convshadow::err!("{text}");
            } else {
                convshadow::out!("{text}");
            }
            finish(convshadow::console::final_code(code));
        }
    };
    let result = match &cli.command {
        Command::Diff(a) => cli::diff::run(a),
        Command::Ldi(a) => cli::ldi::run(a),
        Command::Render(a) => cli::render::run(a),
        Command::Report(a) => cli::report::run(a),
    };
    match result {
        Ok(code) => finish(convshadow::console::final_code(code)),
        Err(f) => {
            convshadow::errln!("error: {}", exit::escape_line(&f.message));
            finish(f.code);
        }
    }
}
