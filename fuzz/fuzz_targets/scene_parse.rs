//! Fuzz target: the scene parser and validator (`Scene::parse`), then, for scenes small enough
//! to be cheap, the geometry set-up and the render plan built from the validated scene.
//! Any panic is a bug: bad scene text must come back as a `SceneError` (or a geometry/plan error).
#![no_main]

use std::path::Path;

use convshadow_common::model::scene::GuardBandSpec;
use convshadow_common::model::scene::{Scene, ShapeSpec, SlabSpec};
use libfuzzer_sys::fuzz_target;

/// Whether a parsed scene is small enough to build its geometry and plan within a fuzz run.
fn small(scene: &Scene) -> bool {
    let pixels = u64::from(scene.image.width) * u64::from(scene.image.height);
    let slabs_ok = match scene.sweep.slabs {
        SlabSpec::Count(n) => n <= 256,
        SlabSpec::Distance(_) | SlabSpec::Auto => true,
    };
    let meshes_ok = scene.meshes.iter().all(|m| match &m.shape {
        ShapeSpec::Sphere { subdivisions, .. } => *subdivisions <= 3,
        ShapeSpec::Torus { segments, .. } => *segments <= 64,
        ShapeSpec::Cylinder { segments, .. } => *segments <= 256,
        // Boxes are small; the base folder does not exist, so OBJ paths fail to load (the error
        // path is fuzzed); shapes added later are built too.
        _ => true,
    });
    // `auto` is bounded by the scene's meshes (and MAX_GUARD_BAND); a fixed band is kept small.
    let guard_ok = match scene.sweep.guard_band {
        GuardBandSpec::Pixels(g) => g <= 16,
        GuardBandSpec::Auto => true,
    };
    pixels <= 128 * 128 && slabs_ok && meshes_ok && guard_ok
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scene) = Scene::parse(text, "fuzz.toml", Path::new("/nonexistent-fuzz-dir")) else {
        return;
    };
    // A parsed scene must pass its own re-validation.
    scene
        .revalidate()
        .expect("a parsed scene re-validates unchanged");
    if !small(&scene) {
        return;
    }
    let Ok(geometry) = convshadow_io::build_geometry(&scene) else {
        return;
    };
    if geometry.slabs > 4096 {
        return;
    }
    if let Ok(plan) = convshadow_io::build_plan(&scene, &geometry) {
        assert_eq!(plan.slabs, geometry.slabs);
        assert!(plan.slab_distance.is_finite() && plan.slab_distance >= 0.0);
    }
});
