//! Accuracy against independent references: the analytic edge, disk and impulse, the
//! shadow-ray reference, and expected values computed from the scene's parameters (never from a
//! render of the code under test); the guard band against a wider frame; pre-integration
//! against many slabs.
//!
//! One test binary of several (docs/ARCHITECTURE.md, Tests): `cargo test --release --test
//! accuracy [NAME::]`.

#[path = "../support/mod.rs"]
mod support;

mod distance_penumbra;
mod fixed_pixel_edge;
mod guard_band;
mod hard_cases;
mod light_resolution;
mod lights_from_any_direction;
mod oblique_receiver;
mod open_meshes;
mod patterned_light;
mod perspective;
mod phase_function;
mod point_lights;
mod point_sweep;
mod preintegration;
mod reference_convergence;
mod several_depths;
mod slab_convergence;
mod sphere_over_receiver;
mod surface_shading;
mod sweep_accuracy;
mod translucent_strip;
