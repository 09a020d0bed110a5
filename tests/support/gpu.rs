//! Shared helpers of the GPU tests: the adapter (required under CI, a loud skip otherwise) and
//! small scenes.
#![allow(dead_code)]

use std::path::Path;
use std::sync::Arc;

use convshadow::common::model::scene::{Scene, SlabSpec};
use convshadow_gpu::GpuContext;

/// The process's shared GPU context (the one the renders use), or `None` with a loud `SKIP`
/// message. Under CI (env `CI` set) a missing adapter is a failure: the GPU tests are required
/// there.
pub fn gpu() -> Option<Arc<GpuContext>> {
    match GpuContext::shared() {
        Ok(ctx) => {
            eprintln!("GPU tests on adapter {}", ctx.adapter_name());
            Some(ctx)
        }
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("GPU tests are required in CI but there is no adapter: {e}")
        }
        Err(e) => {
            eprintln!("SKIP: no Vulkan adapter ({e}); GPU test skipped");
            None
        }
    }
}

/// Every example scene in `scenes/`, sorted by name; those reading a missing `../shared`
/// folder skipped (loudly; a failure under CI).
pub fn example_scenes() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut v: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .filter(|p| super::example_scene_inputs_present(p))
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no example scene in {}", dir.display());
    v
}

/// Loads a scene and makes it small: `size`×`size` pixels and `slabs` slabs.
pub fn small(path: &Path, size: u32, slabs: u32) -> Scene {
    let mut scene = convshadow_io::load_scene(path).unwrap_or_else(|e| panic!("{e}"));
    shrink(&mut scene, size, slabs);
    scene
}

/// Sets the size and slab count (and re-validates).
pub fn shrink(scene: &mut Scene, size: u32, slabs: u32) {
    scene.image.width = size;
    scene.image.height = size;
    scene.sweep.slabs = SlabSpec::Count(slabs);
    scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
}

/// Writes a coloured `w × h` pattern (gobo) image `gobo.png` into `dir`, value `((i·a + b) mod m)
/// / (m − 1)` at float i, texels that align with no pixel grid; returns its path.
pub fn write_gobo(
    dir: &Path,
    (w, h): (u32, u32),
    (a, b, m): (u32, u32, u32),
) -> std::path::PathBuf {
    let data: Vec<f32> = (0..w * h * 3)
        .map(|i| ((i * a + b) % m) as f32 / (m - 1) as f32)
        .collect();
    let path = dir.join("gobo.png");
    convshadow::io::image::RgbImage {
        width: w,
        height: h,
        data,
    }
    .save(&path)
    .unwrap();
    path
}
