//! The SIMD path's quiet-chunk skipping against the scalar path where it is easiest to get wrong:
//! single pixels of light that differ from their surroundings, at every position relative to
//! the 8-pixel chunks, next to unoccluded space (skipped when everything read is exactly 1) and
//! next to opaque space in the dark (skipped when everything read is exactly 0).

use std::path::Path;

use convshadow::common::model::scene::{Penumbra, Scene};
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::cpu::sweep::{ChunkCounts, CpuOptions, SweepOptions, SweepPath, sweep_with};
use convshadow::pipeline::image_fingerprint;

use crate::support;

/// A thin opaque wall over the image's left half at the front, and a small box far behind it so
/// the sweep goes on for slabs after the wall.
fn scene(kernel: &str, penumbra: Penumbra) -> Scene {
    let text = format!(
        "[image]\nwidth = 75\nheight = 36\n[camera]\nview_width = 4.0\n[sweep]\nguard_band = 0\nslabs = 20\n\
         optimal_distance = 0.5\npenumbra = \"{penumbra}\"\nkernel = \"{kernel}\"\n[[light]]\ntilt_deg = [20.0, 10.0]\n\
         variance = [0.04, 0.02]\nrotation_deg = 25.0\n\
         [[mesh]]\nshape = \"box\"\nsize = [2.0, 5.0, 0.05]\ntranslate = [1.0, 0.0, 0.0]\n\
         material = \"wall\"\n\
         [[mesh]]\nshape = \"box\"\nsize = [0.1, 0.1, 0.1]\ntranslate = [-1.8, 1.6, 2.0]\n\
         material = \"wall\"\n[material.wall]\nopacity = 1.0\n"
    );
    Scene::parse(&text, "simd_quiet", Path::new(".")).expect("scene")
}

/// Runs both paths from `initial` light and compares image and light bits; returns the SIMD
/// path's chunk counts.
fn compare(
    kernel: &str,
    penumbra: Penumbra,
    what: &str,
    initial_of: &dyn Fn(usize, usize, usize) -> f32,
) -> [u64; 3] {
    let scene = scene(kernel, penumbra);
    let g = convshadow_io::build_geometry(&scene).expect("geometry");
    let ldi = Ldi::build(&g.raster, u64::MAX).expect("ldi");
    let plan = convshadow_io::build_plan(&scene, &g).expect("plan");
    let (w, h, row_len) = (
        plan.grid_width as usize,
        plan.grid_height as usize,
        plan.light_row_len(),
    );
    let planes = row_len / w;
    let mut initial = vec![0.0f32; row_len * h];
    for y in 0..h {
        for p in 0..planes {
            for x in 0..w {
                // A depth plane starts at 0: no occluder yet.
                initial[y * row_len + p * w + x] = if plan.is_depth_plane(p) {
                    0.0
                } else {
                    initial_of(x, y, w)
                };
            }
        }
    }
    let counts = ChunkCounts::default();
    let run = |path: SweepPath, counts: Option<&ChunkCounts>| {
        let options = SweepOptions {
            initial_light: Some(&initial),
            // The light of every slab is compared, not only up to an early finish.
            every_slab: true,
            ..SweepOptions::default()
        };
        let cpu = CpuOptions {
            path,
            chunk_counts: counts,
            ..CpuOptions::default()
        };
        sweep_with(&plan, &g.raster, &ldi, &options, &cpu).expect("sweep")
    };
    let scalar = run(SweepPath::Scalar, None);
    let simd = run(SweepPath::Simd, Some(&counts));
    assert_eq!(
        (
            image_fingerprint(&simd.image),
            image_fingerprint(&simd.light)
        ),
        (
            image_fingerprint(&scalar.image),
            image_fingerprint(&scalar.light)
        ),
        "{kernel}, {what}: SIMD path with skipping differs from the scalar path"
    );
    counts.snapshot()
}

/// A dot every 9 pixels along x (so dots fall on every position within a chunk), shifted by 4
/// every 5 rows.
fn dot(x: usize, y: usize) -> bool {
    y % 5 == 2 && (x + 4 * (y / 5)).is_multiple_of(9)
}

#[test]
fn single_dots_of_shadow_in_unoccluded_light() {
    for kernel in support::kernels() {
        for penumbra in [Penumbra::Iterated, Penumbra::Distance] {
            let counts = compare(kernel, penumbra, "shadow dots in light", &|x, y, _| {
                if dot(x, y) { 0.5 } else { 1.0 }
            });
            // The distance penumbra grows the dots' kernels with the slab count (their
            // occluders are at depth 0), so they soon reach every chunk: the bits are compared,
            // the skips counted for the iterated penumbra only.
            assert!(
                counts[1] > 0 || penumbra == Penumbra::Distance,
                "{kernel} {penumbra}: no unoccluded chunk was skipped: {counts:?}"
            );
        }
    }
}

#[test]
fn single_dots_of_light_beside_opaque_darkness() {
    // Dark everywhere but for dots of light in the unoccluded right half (grid x > w/2): the dots
    // spread under the wall's opaque left half, whose chunks are skipped while all they read is 0.
    // The wall is in slab 0, so the distance penumbra's depth plane stays 0 under it (0 · the
    // light removed) and its dark chunks are skipped too.
    for kernel in support::kernels() {
        for penumbra in [Penumbra::Iterated, Penumbra::Distance] {
            let counts = compare(kernel, penumbra, "light dots in the dark", &|x, y, w| {
                if x > w / 2 && dot(x, y) { 0.5 } else { 0.0 }
            });
            assert!(
                counts[2] > 0,
                "{kernel} {penumbra}: no dark chunk was skipped: {counts:?}"
            );
        }
    }
}
