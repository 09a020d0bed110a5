//! The sweep on an opaque icosphere over a receiver (issue 46: "the opaque sphere over a
//! receiver: ≤ 5e-3 on the receiver and on the sphere's lit surface"), against the closed forms
//! `tests/accuracy/reference_convergence.rs` writes from the geometry for the shadow-ray
//! reference's convergence: the Gaussian measure of the polyhedron's central projection on the
//! receiver, `Φ(mean/std of n·v)` on each facet the camera sees. Never the renderer's output.
//!
//! The receiver does not meet 5e-3 yet (docs/accuracy.md §1c, "An opaque sphere"); the lit
//! surface does since the horizon (`sweep.horizon`, 2026-12-07) blocks the light below each
//! facet's tangent plane, but for the distance penumbra at 128 px and 256 slabs, where the
//! sweep reads the sphere's own zeros near the terminator (0.027). On a convex body that part
//! of the light is the whole of the self-occlusion, so the surface rows measure what the sweep
//! darkens beyond it. The bounds are today's figures plus 25 % (a guard against getting worse,
//! not the target). Without the horizon the sweep lit the facets fully near the terminator:
//! 0.075–0.089 at 128 px.

use convshadow::common::model::scene::{Penumbra, SlabSpec};
use convshadow::pipeline::{RenderRequest, render};

use crate::reference_convergence::{SPHERE_D, rmse_per_m, sphere_expected, sphere_scene};

/// A penumbra model with its receiver and surface RMSE bounds.
type Bounds = (Penumbra, f64, f64);

/// Per image size, today's RMSE at 64 and 256 slabs plus 25 % as (receiver, surface) bounds per
/// penumbra (distance, iterated) — measured 2026-12-07: 64 px distance 0.027 / 0.0005, iterated
/// 0.025 / 0.0011; 128 px distance 0.018 / 0.027, iterated 0.033 / 0.0031 (the receiver's
/// bounds are those of 2026-12-06, when it measured 0.029–0.048).
const CASES: [(u32, [Bounds; 2]); 2] = [
    (
        64,
        [
            (Penumbra::Distance, 0.044, 0.0007),
            (Penumbra::Iterated, 0.048, 0.0014),
        ],
    ),
    (
        128,
        [
            (Penumbra::Distance, 0.037, 0.034),
            (Penumbra::Iterated, 0.06, 0.0039),
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
