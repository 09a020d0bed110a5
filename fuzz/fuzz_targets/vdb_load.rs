//! Fuzz target: the OpenVDB path (`vdb::load_vdb`: magic and version checks, vdb-rs with its
//! panics caught, the tree walk into bricks). The bytes are loaded as a `.vdb` file's grid
//! `density`; a loaded texture is held to the bricked layout's contract. Any panic is a bug: a
//! bad file must come back as a `TextureError`. Seeds: scenes/cloud.vdb (scripts/fuzz.sh).
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use convshadow_common::pixel::volume::BRICK_VOXELS;
use convshadow_io::vdb::load_vdb;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    let path = PATH.get_or_init(|| {
        std::env::temp_dir().join(format!("convshadow-fuzz-{}.vdb", std::process::id()))
    });
    if std::fs::write(path, data).is_err() {
        return;
    }
    let Ok(v) = load_vdb(path, "density") else {
        return;
    };
    let t = &v.texture;
    // Every table entry names a slot of the pool, every value is finite, and a sample is too.
    let slots = t.pool.len() / BRICK_VOXELS;
    assert_eq!(t.pool.len() % BRICK_VOXELS, 0);
    assert!(t.table.iter().all(|&s| (s as usize) < slots));
    assert!(t.pool.iter().all(|v| v.is_finite()));
    assert!(t.sample([0.5f32, 0.5, 0.5]).is_finite());
});
