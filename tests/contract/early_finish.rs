//! The CPU sweep stops after the first slab after which every image pixel is opaque (alpha
//! exactly 1), since no later slab can change the image (`SweepOptions::every_slab`). Held to it
//! here: the same image bits as a sweep of every slab on both paths and any thread count, the same
//! stopping slab for all of them, every slab swept while one image pixel can still change, and a
//! progress callback that still reaches the last slab. (`tests/contract/golden_hashes.rs` holds
//! the early finish to the `image_hash` values of the commit before it, for every example scene.)

use std::sync::atomic::{AtomicU32, Ordering};

use convshadow::common::model::scene::{Scene, SlabSpec};
use convshadow::pipeline::{CpuPath, RenderRequest, Rendered, render};

/// The default scene, small, seen `view_width` wide: its wall (5 × 5) fills a view up to 5 wide.
fn default_scene_seen(view_width: f64) -> Scene {
    let mut scene = Scene::default_scene();
    scene.image.width = 53; // not a multiple of 8: the rows' tails take the 1-lane stage
    scene.image.height = 40;
    scene.sweep.slabs = SlabSpec::Count(48);
    scene.camera.view_width = view_width;
    scene
}

fn run(scene: &Scene, path: CpuPath, threads: usize, every_slab: bool) -> Rendered {
    let req = RenderRequest {
        path,
        threads,
        every_slab,
        ..RenderRequest::default()
    };
    render(scene, &req).unwrap_or_else(|e| panic!("{e}"))
}

fn bits(r: &Rendered) -> Vec<u32> {
    r.image.data.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn an_early_finish_keeps_every_image_bit_on_every_path() {
    let scene = default_scene_seen(4.0);
    let mut stops = Vec::new();
    for path in [CpuPath::Scalar, CpuPath::Simd] {
        for threads in [1, 2] {
            let every = run(&scene, path, threads, true);
            let early = run(&scene, path, threads, false);
            assert_eq!(
                every.slabs_swept, every.plan.slabs,
                "{path:?}, {threads} threads"
            );
            assert!(
                early.slabs_swept < early.plan.slabs,
                "{path:?}, {threads} threads: the wall makes every image pixel opaque before the \
                 last slab, yet {} of {} slabs were swept",
                early.slabs_swept,
                early.plan.slabs
            );
            assert!(bits(&every) == bits(&early), "{path:?}, {threads} threads");
            assert_eq!(every.image_hash, early.image_hash);
            stops.push(early.slabs_swept);
        }
    }
    assert!(stops.iter().all(|&s| s == stops[0]), "stops {stops:?}");
}

#[test]
fn an_image_pixel_past_the_wall_keeps_every_slab() {
    // Wider than the wall: the image's corners see nothing opaque.
    let r = run(&default_scene_seen(6.0), CpuPath::Simd, 2, false);
    assert_eq!(r.slabs_swept, r.plan.slabs);
}

#[test]
fn after_an_early_finish_progress_reports_the_last_slab() {
    let scene = default_scene_seen(4.0);
    let (calls, last) = (AtomicU32::new(0), AtomicU32::new(0));
    let progress = |slab: u32| {
        calls.fetch_add(1, Ordering::Relaxed);
        last.store(slab, Ordering::Relaxed);
    };
    let req = RenderRequest {
        progress: &progress,
        ..RenderRequest::default()
    };
    let r = render(&scene, &req).unwrap_or_else(|e| panic!("{e}"));
    assert!(r.slabs_swept < r.plan.slabs);
    assert_eq!(last.load(Ordering::Relaxed), r.plan.slabs - 1);
    assert_eq!(calls.load(Ordering::Relaxed), r.slabs_swept + 1);
}
