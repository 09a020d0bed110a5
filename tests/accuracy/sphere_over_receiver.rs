//! The sweep on an opaque icosphere over a receiver (issue 46: "the opaque sphere over a
//! receiver: ≤ 5e-3 on the receiver and on the sphere's lit surface"), against the closed forms
//! `tests/accuracy/reference_convergence.rs` writes from the geometry for the shadow-ray
//! reference's convergence: the Gaussian measure of the polyhedron's central projection on the
//! receiver, `Φ(mean/std of n·v)` on each facet the camera sees. Never the renderer's output.
//!
//! Neither meets 5e-3 yet (docs/accuracy.md §1c, "An opaque sphere"): the bounds are today's
//! figures plus 25 %, a guard against getting worse, not the target. At 64 px the surface looks
//! right (4.3e-3) only because its 3-pixel margin leaves out the terminator, where the sweep
//! lights the facets fully (the surface hold passes the light below their tangent planes); at
//! 128 px the margin is half as wide and the surface is at 0.075–0.089.

use convshadow::common::model::scene::{Penumbra, SlabSpec};
use convshadow::pipeline::{RenderRequest, render};

use crate::reference_convergence::{SPHERE_D, rmse_per_m, sphere_expected, sphere_scene};

/// A penumbra model with its receiver and surface RMSE bounds.
type Bounds = (Penumbra, f64, f64);

/// Per image size, today's RMSE at 64 and 256 slabs plus 25 % as (receiver, surface) bounds per
/// penumbra (distance, iterated) — measured 2026-12-06: 64 px distance 0.034–0.035 / 0.0043,
/// iterated 0.038 / 0.0032–0.0039; 128 px distance 0.029 / 0.085–0.089, iterated 0.044–0.048 /
/// 0.075–0.082.
const CASES: [(u32, [Bounds; 2]); 2] = [
    (
        64,
        [
            (Penumbra::Distance, 0.044, 0.0054),
            (Penumbra::Iterated, 0.048, 0.0049),
        ],
    ),
    (
        128,
        [
            (Penumbra::Distance, 0.037, 0.112),
            (Penumbra::Iterated, 0.06, 0.103),
        ],
    ),
];

#[test]
fn an_opaque_sphere_over_a_receiver_against_the_closed_forms() {
    let mut report = Vec::new();
    let mut failed = false;
    for (size, penumbras) in CASES {
        let mut base = sphere_scene();
        (base.image.width, base.image.height) = (size, size);
        // The closed forms once per size (the receiver's is a polygon integral per pixel).
        let (receiver, surface) = sphere_expected(&base);
        for (penumbra, receiver_bound, surface_bound) in penumbras {
            for slabs in [64u32, 256] {
                let mut scene = base.clone();
                scene.sweep.slabs = SlabSpec::Count(slabs);
                scene.sweep.penumbra = penumbra;
                // The iterated model's d1 (required with it): the sphere centre's distance to the
                // receiver, where its shadow's penumbra is right.
                scene.sweep.optimal_distance = Some(SPHERE_D);
                let image = render(&scene, &RenderRequest::default())
                    .unwrap_or_else(|e| panic!("{e}"))
                    .image;
                let images = [image.data.chunks(3).map(|c| f64::from(c[0])).collect()];
                let (on_receiver, n_receiver) = rmse_per_m(&images, &receiver);
                let (on_surface, n_surface) = rmse_per_m(&images, &surface);
                let (on_receiver, on_surface) = (on_receiver[0], on_surface[0]);
                report.push(format!(
                    "{size} px, {penumbra:?}, {slabs} slabs: receiver {on_receiver:.4} over \
                     {n_receiver} px (≤ {receiver_bound}), lit surface {on_surface:.4} over \
                     {n_surface} px (≤ {surface_bound}); issue 46 asks 5e-3"
                ));
                failed |= on_receiver > receiver_bound || on_surface > surface_bound;
                failed |= n_receiver < 300 || n_surface < 150;
            }
        }
    }
    let report = report.join("\n");
    println!("{report}");
    assert!(!failed, "{report}");
}
