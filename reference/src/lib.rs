//! The references the sweep is measured against, in one place for the report and the tests:
//!
//! - [`shadow_ray`]: the ground truth of any scene, the light at every shading point integrated
//!   by Monte Carlo over shadow rays (`--backend reference`);
//! - [`edge`]: a straight shadow edge, whose exact profile is a normal CDF;
//! - [`disk`]: a polygonal occluder over a plane, whose exact shadow is a Gaussian integral over
//!   the polygon;
//! - [`half_plane_sheet`]: an opaque half-plane's shadow on a translucent sheet, both
//!   perpendicular to a directional light seen from any angle, integrated along each view ray;
//! - [`perspective_edge`]: a half-plane's shadow on a receiver seen through a perspective camera,
//!   evaluated where each pixel's ray meets the receiver;
//! - [`point_edge`]: a point light's shadow of a half-plane on a wall, integrated over the
//!   light's Gaussian;
//! - [`impulse`]: a single lit pixel through an empty scene, whose exact spread is n·Σκ;
//! - [`quadrature`]: the Gauss–Legendre nodes of the disk's and the sheet's integrals.
//!
//! Library code only: no exit codes, no printing.

pub mod disk;
pub mod edge;
pub mod half_plane_sheet;
pub mod impulse;
pub mod light_samples;
pub mod perspective_edge;
pub mod point_edge;
pub mod quadrature;
pub mod shadow_ray;

pub use light_samples::{inverse_normal_cdf, normal_cdf, samples_side};
pub use shadow_ray::{Reference, ReferenceOptions};
