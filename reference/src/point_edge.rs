//! A point light's shadow of an opaque thin half-plane on a wall behind it: the visibility of a
//! light of radius r (an isotropic 3D Gaussian around its centre P) at a wall point, integrated
//! over the light, the scene that holds them, and the wall's profile measured from an image
//! against it (the sweep's point lights: `tests/accuracy/point_sweep.rs` and the report's `point`
//! family; the shadow-ray reference's: `tests/accuracy/point_lights.rs`).
//!
//! The plate spans world x ≥ 0 (to 3), every y in view, z ∈ [−H, H]; the wall's front face is
//! z = 1; the light lies before the plate (P_z < −H). The light reaching X is
//! `V(X)·cos/|X − P|²` on a Lambert wall; across the edge only the light's offsets across it and
//! in depth matter: for a depth offset δ_z the segment from X to `P + δ` meets the plate iff
//! `δ_x` passes a threshold, so `V = ∫ Φ(threshold(δ_z)/r) N(δ_z; 0, r²) dδ_z`, by
//! Gauss–Legendre over ±8 r.

use glam::DVec3;

use crate::edge::phi;
use crate::quadrature::gauss_legendre;

/// Half the plate's thickness.
pub const H: f64 = 0.005;

/// The scene's text: a `width × height` image seen by `camera` (TOML lines), `slabs` slabs, a
/// black background, the opaque white plate and the white Lambert wall (its front face at z = 1,
/// 8 × 8), lit by `light` (the lines of one `[[light]]`).
pub fn scene_toml(
    (width, height): (usize, usize),
    camera: &str,
    slabs: u32,
    light: &str,
) -> String {
    format!(
        r#"
[image]
width = {width}
height = {height}
background = [0.0, 0.0, 0.0]
[camera]
{camera}
[sweep]
slabs = {slabs}
[[light]]
{light}
[[mesh]]
shape = "box"
size = [3.0, 8.0, {t}]
translate = [1.5, 0.0, 0.0]
material = "plate"
[[mesh]]
shape = "box"
size = [8.0, 8.0, 0.02]
translate = [0.0, 0.0, 1.01]
material = "wall"
[material.plate]
color = [1.0, 1.0, 1.0]
[material.wall]
color = [1.0, 1.0, 1.0]
"#,
        t = 2.0 * H
    )
}

/// V at world point `x` (z > H, y inside the plate's extent) for a light of radius `r` at `p`
/// (z < −H): the segment from x to `p + δ` meets the plate iff its world x is ≥ 0 at z = H or
/// at z = −H, i.e. iff `δ_x ≥ min over z of x_x·(1 − 1/s(z)) − p_x`, s(z) = (z − x_z)/(l_z − x_z)
/// the fraction of the way to the light's point. A hard light (r = 0): 1 or 0.
pub fn visibility(x: DVec3, p: DVec3, r: f64) -> f64 {
    visibility_past(x, p, r, H)
}

/// [`visibility`] for a plate of half-thickness `h` (z ∈ [−h, h]; x at z > h, p at z < −h).
pub fn visibility_past(x: DVec3, p: DVec3, r: f64, h: f64) -> f64 {
    let threshold = |lz: f64| {
        [h, -h]
            .map(|z| {
                let s = (z - x.z) / (lz - x.z);
                x.x * (1.0 - 1.0 / s)
            })
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    };
    if r == 0.0 {
        return f64::from(u8::from(p.x < threshold(p.z)));
    }
    let mut v = 0.0;
    for &(node, weight) in gauss_legendre(400) {
        let dz = 8.0 * r * node;
        let density = (-0.5 * (dz / r).powi(2)).exp() / (r * (2.0 * std::f64::consts::PI).sqrt());
        v += weight * 8.0 * r * density * phi((threshold(p.z + dz) - p.x) / r);
    }
    v
}

/// Where the ray from `eye` along `dir` meets the wall's face z = 1, if it passes the plate
/// (at z = ±H it is at x < 0) and meets the wall within its 8 × 8 extent.
pub fn wall_point(eye: DVec3, dir: DVec3) -> Option<DVec3> {
    let at = |z: f64| eye + dir * ((z - eye.z) / dir.z);
    let x = at(1.0);
    (at(-H).x < 0.0 && at(H).x < 0.0 && x.x.abs() < 4.0 && x.y.abs() < 4.0).then_some(x)
}

/// How the scene is seen: orthographic along +z from the view's centre (0, 0, −5), `width`
/// world units across; or in perspective from (0, 0, −4) towards +z, `focal` pixels.
#[derive(Clone, Copy, Debug)]
pub enum View {
    /// `view_width` world units across the image.
    Orthographic(f64),
    /// The focal length in pixels.
    Perspective(f64),
}

impl View {
    /// The ray of pixel (i, j) of a `w × h` image: its origin and direction (the image's right
    /// and down are world −x and −y: the default `up`, +y, looking along +z).
    pub fn ray(self, (w, h): (usize, usize), (i, j): (usize, usize)) -> (DVec3, DVec3) {
        let u = 0.5 * w as f64 - (i as f64 + 0.5);
        let v = 0.5 * h as f64 - (j as f64 + 0.5);
        match self {
            View::Orthographic(width) => {
                let px = width / w as f64;
                (DVec3::new(u * px, v * px, -5.0), DVec3::Z)
            }
            View::Perspective(f) => (DVec3::new(0.0, 0.0, -4.0), DVec3::new(u / f, v / f, 1.0)),
        }
    }

    /// World units across one pixel on the wall.
    pub fn pixel_on_wall(self, w: usize) -> f64 {
        match self {
            View::Orthographic(width) => width / w as f64,
            View::Perspective(f) => 5.0 / f,
        }
    }
}

/// The RMSE over the wall's visible pixels of `image` (`w × h` RGB, channel 0) normalised by
/// the unshadowed light `cos/|X − P|²`, against [`visibility`], and how many pixels it took.
pub fn wall_rmse(
    image: &[f32],
    size: (usize, usize),
    view: View,
    p: DVec3,
    r: f64,
) -> (f64, usize) {
    let (w, h) = size;
    let (mut sum, mut n) = (0.0f64, 0usize);
    for j in 0..h {
        for i in 0..w {
            let (eye, dir) = view.ray(size, (i, j));
            let Some(x) = wall_point(eye, dir) else {
                continue;
            };
            let d = (x - p).length();
            let lit = (1.0 - p.z) / (d * d * d);
            let got = f64::from(image[3 * (j * w + i)]) / lit;
            sum += (got - visibility(x, p, r)).powi(2);
            n += 1;
        }
    }
    ((sum / n.max(1) as f64).sqrt(), n)
}
