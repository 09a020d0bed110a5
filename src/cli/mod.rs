//! The command line, private to the `convshadow` binary: the subcommands, their failures with
//! exit codes ([`exit`]) and the processor check that runs before `main`. The library
//! (`convshadow::pipeline`, `convshadow::report`) returns typed errors; this module turns them
//! into exit codes and messages (docs/errors.md) with the library's `convshadow::exit_code`,
//! which the Python module shares.

mod cpu_check;
pub mod diff;
pub mod exit;
pub mod frames;
pub mod ldi;
pub mod render;
pub mod report;

use std::path::Path;

use convshadow_common::model::scene::Scene;

use crate::cli::exit::Failure;

/// The value parsers of the scene flags (shared with the Python module).
pub use convshadow::overrides::{parse_side, parse_slabs, parse_surface, parse_threads};

/// Loads the scene file, or the embedded default scene when none is given.
pub fn load_scene(path: Option<&Path>) -> Result<Scene, Failure> {
    Ok(match path {
        Some(p) => convshadow_io::load_scene(p)?,
        None => Scene::default_scene(),
    })
}

/// Applies `--width`/`--height` overrides and re-validates
/// ([`convshadow::overrides::override_size`]).
pub fn override_size(
    scene: &mut Scene,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<(), Failure> {
    Ok(convshadow::overrides::override_size(scene, width, height)?)
}

/// Refuses two outputs of one run that name the same file (the later write would silently
/// replace the earlier one: `-o x.png --stats-json x.png`).
pub fn refuse_collisions<'a>(
    paths: impl IntoIterator<Item = &'a std::path::PathBuf>,
) -> Result<(), Failure> {
    // The folder resolved where it exists, so `x.png` and `./x.png` are the same file.
    let key = |p: &Path| {
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
        let dir = dir.map_or_else(|| Path::new(".").to_path_buf(), Path::to_path_buf);
        let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
        dir.join(p.file_name().unwrap_or_default())
    };
    let mut seen: Vec<(std::path::PathBuf, &Path)> = Vec::new();
    for p in paths {
        let k = key(p);
        if let Some((_, first)) = seen.iter().find(|(s, _)| *s == k) {
            return Err(Failure::new(
                crate::cli::exit::BAD_ARGUMENTS,
                format!(
                    "{} and {} are the same file: give each output its own path",
                    first.display(),
                    p.display()
                ),
            ));
        }
        seen.push((k, p));
    }
    Ok(())
}

/// Refuses a PNG-only output (`flag`) whose name ends in another extension: the file would hold
/// PNG data under a misleading name.
pub fn require_png(flag: &str, path: Option<&std::path::PathBuf>) -> Result<(), Failure> {
    if let Some(p) = path {
        let ext = p
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if ext.as_deref() != Some("png") {
            return Err(Failure::new(
                crate::cli::exit::BAD_ARGUMENTS,
                format!("{flag} {}: writes PNG; expected a .png name", p.display()),
            ));
        }
    }
    Ok(())
}

/// `--penumbra iterated|distance` (clap reports a bad value with the option's name).
pub fn parse_penumbra(s: &str) -> Result<convshadow_common::model::scene::Penumbra, String> {
    s.parse()
}

/// The pipeline's thread pool with `threads` workers (0 = one per core), its error as a failure.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, Failure> {
    Ok(convshadow::pipeline::thread_pool(threads)?)
}

/// Writes a JSON value atomically.
pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Failure::new(crate::cli::exit::INTERNAL, e.to_string()))?;
    convshadow_io::image::write_atomically(path, |w| {
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })?;
    Ok(())
}
