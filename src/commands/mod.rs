//! The `convshadow` subcommands.

pub mod diff;
pub mod frames;
pub mod ldi;
pub mod render;
pub mod report;

use std::path::Path;

use convshadow_common::scene::Scene;

use crate::exit::Failure;

/// Loads the scene file, or the embedded default scene when none is given.
pub fn load_scene(path: Option<&Path>) -> Result<Scene, Failure> {
    Ok(match path {
        Some(p) => Scene::load(p)?,
        None => Scene::default_scene(),
    })
}

/// Applies `--width`/`--height` overrides and re-validates.
pub fn override_size(
    scene: &mut Scene,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<(), Failure> {
    if let Some(w) = width {
        scene.image.width = w;
    }
    if let Some(h) = height {
        scene.image.height = h;
    }
    scene.revalidate()?;
    Ok(())
}

/// The pipeline's thread pool with `threads` workers (0 = one per core), its error as a failure.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, Failure> {
    Ok(crate::pipeline::thread_pool(threads)?)
}

/// Writes a JSON value atomically.
pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Failure::new(crate::exit::INTERNAL, e.to_string()))?;
    convshadow_common::image_io::write_atomically(path, |w| {
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })?;
    Ok(())
}
