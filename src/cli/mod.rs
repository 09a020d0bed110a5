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
    refuse_named_collisions(paths.into_iter().map(|p| (p, p.as_path())), |p| {
        p.display().to_string()
    })
}

/// [`refuse_collisions`] over (tag, path) pairs, in linear time (a frame sequence checks every
/// frame's names), `name` saying how the message names a tag's file: `x.png` and `./x.png`
/// are the same file, as their folders are compared resolved where they exist. Tags, not
/// names, are kept per file, so a million frames hold no message text.
pub fn refuse_named_collisions<'a, T: Copy>(
    items: impl IntoIterator<Item = (T, &'a Path)>,
    name: impl Fn(T) -> String,
) -> Result<(), Failure> {
    use std::collections::HashMap;
    use std::path::PathBuf;
    let mut folders: HashMap<PathBuf, PathBuf> = HashMap::new();
    let mut seen: HashMap<PathBuf, T> = HashMap::new();
    for (tag, p) in items {
        let dir = convshadow_io::image::folder_of(p).to_path_buf();
        let resolved = folders
            .entry(dir.clone())
            .or_insert_with(|| std::fs::canonicalize(&dir).unwrap_or(dir));
        let key = resolved.join(p.file_name().unwrap_or_default());
        if let Some(&first) = seen.get(&key) {
            return Err(Failure::new(
                crate::cli::exit::BAD_ARGUMENTS,
                format!(
                    "{} and {} are the same file: give each output its own path",
                    name(first),
                    name(tag)
                ),
            ));
        }
        seen.insert(key, tag);
    }
    Ok(())
}

/// The identity of an existing file (device and inode, through symbolic links), or `None`.
fn file_identity(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
}

/// Refuses an output that is one of the run's inputs (`--stats-json scene.toml`, `diff a.png
/// b.png --heatmap a.png`, also through another spelling, a symbolic or a hard link): the same
/// file by identity (device and inode). `inputs` are (what names it, path).
pub fn refuse_outputs_over_inputs<'a>(
    outputs: impl IntoIterator<Item = &'a std::path::PathBuf>,
    inputs: &[(String, &Path)],
) -> Result<(), Failure> {
    let inputs: Vec<(&String, &Path, (u64, u64))> = inputs
        .iter()
        .filter_map(|(what, p)| file_identity(p).map(|id| (what, *p, id)))
        .collect();
    for out in outputs {
        let Some(id) = file_identity(out) else {
            continue;
        };
        if let Some((what, p, _)) = inputs.iter().find(|(_, _, i)| *i == id) {
            return Err(Failure::new(
                crate::cli::exit::BAD_ARGUMENTS,
                format!(
                    "{} is the same file as the input {} ({what}): writing it would replace the \
                     input; give the output its own path",
                    out.display(),
                    p.display()
                ),
            ));
        }
    }
    Ok(())
}

/// The files a render or LDI run reads: the scene file (when one is given) and the files it
/// names (meshes, textures, patterns), each with what names it.
pub fn scene_inputs<'a>(scene_file: Option<&'a Path>, scene: &'a Scene) -> Vec<(String, &'a Path)> {
    let mut inputs: Vec<(String, &Path)> = scene_file
        .map(|p| ("the scene".to_string(), p))
        .into_iter()
        .collect();
    inputs.extend(scene.input_files());
    inputs
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

/// `--media second-order|first-order`.
pub fn parse_media(s: &str) -> Result<convshadow_common::model::scene::Media, String> {
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
