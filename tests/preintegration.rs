//! Pre-integrated compositing (`sweep.preintegration`, Patel et al. 2013 §7; Engel, Kraus & Ertl
//! 2001): on a transfer function with a narrow opacity band it needs far fewer slabs for the
//! same picture; off (the default) it changes no bit; on, it keeps the bit-exactness contract
//! (scalar = SIMD, any thread count), and it leaves materials without detail alone.
//!
//! The error measurements render `scenes/narrowband.toml` small; run in release mode (the 2048-
//! slab reference is 33 M pixel·slab updates).

mod support;

use std::path::Path;

use convshadow::common::metrics::rmse;
use convshadow::common::scene::{Scene, SlabSpec};
use convshadow::pipeline::{CpuPath, RenderRequest, render};

/// `scenes/narrowband.toml` at `size`² pixels, `slabs` slabs, pre-integration on or off.
fn narrowband(size: u32, slabs: u32, pre: bool) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/narrowband.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut scene = Scene::parse(&text, "narrowband.toml", path.parent().unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    scene.image.width = size;
    scene.image.height = size;
    scene.sweep.slabs = SlabSpec::Count(slabs);
    scene.sweep.preintegration = pre;
    scene.revalidate().unwrap();
    scene
}

/// The float image and its hash.
fn image(scene: &Scene, path: CpuPath, threads: usize) -> (Vec<f32>, u64) {
    let req = RenderRequest {
        path,
        threads,
        ..RenderRequest::default()
    };
    let r = render(scene, &req).unwrap_or_else(|e| panic!("{e}"));
    (r.image.data, r.image_hash)
}

fn image_rmse(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len());
    rmse(a.iter().zip(b).map(|(x, y)| (f64::from(*x), f64::from(*y))))
}

#[test]
fn preintegration_halves_the_error_of_a_narrow_band_at_64_and_128_slabs() {
    let size = 128;
    let (reference, _) = image(&narrowband(size, 2048, false), CpuPath::Simd, 0);
    for slabs in [64, 128] {
        let (with, _) = image(&narrowband(size, slabs, true), CpuPath::Simd, 0);
        let (without, _) = image(&narrowband(size, slabs, false), CpuPath::Simd, 0);
        let (e_with, e_without) = (
            image_rmse(&with, &reference),
            image_rmse(&without, &reference),
        );
        eprintln!(
            "{slabs} slabs: RMSE against 2048 slabs {e_without:.5} without, {e_with:.5} with \
             pre-integration (ratio {:.3})",
            e_with / e_without
        );
        assert!(
            e_with <= 0.5 * e_without,
            "{slabs} slabs: {e_with} with pre-integration, {e_without} without"
        );
    }
}
