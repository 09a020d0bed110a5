//! A directional light from any direction (issue 41): an opaque thin half-plane and a
//! translucent thin receiver sheet, both perpendicular to a Gaussian light's mean direction,
//! seen by a camera at any angle from that direction, with the exact profile of the sheet.
//!
//! World: the light travels along +z; the half-plane is the box x ∈ [0, 3], z ∈ [−h, h]; the
//! sheet the box x ∈ [−1.5, 1.5], z ∈ [W − t/2, W + t/2], translucent (extinction κ per unit
//! depth for the eye) with transport 1 (it takes no light out), white; both are 8 long in y.
//! A light ray of slope δ (x per unit z, N(0, Σxx) with Σxx = cos²α·σx² + sin²α·σy² for a light
//! whose own frame is rotated by α) reaching (x, z) passed depth z' at x − δ·(z − z'); it misses
//! the half-plane iff δ > x/(z − h) for x ≥ 0 and δ > x/(z + h) for x < 0 (the corner it grazes),
//! so V(x, z) = Φ(−x/((z ∓ h)·√Σxx)). A pixel sees the sheet's light scattered along its view
//! ray, `∫ κ·e^(−κs)·V ds / ∫ κ·e^(−κs) ds` over the part of the ray inside the sheet
//! (Gauss–Legendre), divided by the sheet's lit level (the render's mean where V = 1 on the same
//! rows). Behind the sheet nothing is lit: the background is black and the half-plane's faces
//! seen through the sheet are in its own shadow (for a camera at more than 90° they face away
//! from the light; below 90° pixels whose ray meets the half-plane first are left out).
//!
//! Used by `tests/accuracy/lights_from_any_direction.rs` and the report's `direction` family.

use crate::edge::phi;
use crate::quadrature::gauss_legendre;

/// Image width and height in pixels (the profile runs along x; rows are alike).
pub const WIDTH: u32 = 128;
/// Image height in pixels.
pub const HEIGHT: u32 = 8;
/// The view's width in world units.
pub const VIEW: f64 = 2.0;
/// Half the half-plane's thickness.
pub const H: f64 = 0.01;
/// The sheet's middle depth (its distance from the half-plane).
pub const W: f64 = 1.0;
/// The sheet's thickness.
pub const T: f64 = 0.02;
/// The sheet's opacity per unit depth: κ = −ln(1 − 0.9).
pub const OPACITY: f64 = 0.9;
/// The slab distance: at 80° the light moves tan 80° ≈ 5.7 slab distances across the view per
/// slab, and must not step over the half-plane (0.02 thick, 0.02/sin 80° across a slab).
pub const SLAB_DISTANCE: f64 = 0.002;

/// A Gaussian light along +z: variances along its own axes, rotation of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SheetLight {
    /// σ² along the light's own x and y axes.
    pub variance: [f64; 2],
    /// Rotation of those axes (degrees).
    pub rotation_deg: f64,
}

impl SheetLight {
    /// An isotropic light, σ² = 0.01.
    pub const ISOTROPIC: SheetLight = SheetLight {
        variance: [0.01, 0.01],
        rotation_deg: 0.0,
    };
    /// An anisotropic light, σ² = (0.02, 0.005), its axes rotated 30°.
    pub const ROTATED: SheetLight = SheetLight {
        variance: [0.02, 0.005],
        rotation_deg: 30.0,
    };

    /// Σxx: the variance of its slopes along world x (its own x axis is world −x: `frame` of +z
    /// with `up` = +y), a marginal that the axis's sign does not change.
    pub fn var_x(&self) -> f64 {
        let r = self.rotation_deg.to_radians();
        r.cos().powi(2) * self.variance[0] + r.sin().powi(2) * self.variance[1]
    }
}

/// The camera's view direction at `theta` degrees from the light's travel (+z), turned about y.
pub fn view_direction(theta: f64) -> [f64; 3] {
    let t = theta.to_radians();
    [t.sin(), 0.0, t.cos()]
}

/// The scene (TOML) of the camera at `theta` degrees from the light `light`, with `[sweep]`
/// lines `sweep` added after the slab distance (e.g. `penumbra = "iterated"`).
pub fn scene_toml(theta: f64, light: SheetLight, sweep: &str) -> String {
    let [dx, dy, dz] = view_direction(theta);
    format!(
        "[image]\nwidth = {WIDTH}\nheight = {HEIGHT}\nbackground = [0.0, 0.0, 0.0]\n\
         [camera]\ndirection = [{dx}, {dy}, {dz}]\ncenter = [0.0, 0.0, {W}]\nview_width = {VIEW}\n\
         [sweep]\nslab_distance = {SLAB_DISTANCE}\n{sweep}\n\
         [[light]]\ndirection = [0.0, 0.0, 1.0]\nvariance = [{}, {}]\nrotation_deg = {}\n\
         [[mesh]]\nshape = \"box\"\nsize = [3.0, 8.0, {}]\ntranslate = [1.5, 0.0, 0.0]\n\
         material = \"plane\"\n\
         [[mesh]]\nshape = \"box\"\nsize = [3.0, 8.0, {T}]\ntranslate = [0.0, 0.0, {W}]\n\
         material = \"sheet\"\n\
         [material.plane]\ncolor = [1.0, 1.0, 1.0]\n\
         [material.sheet]\ncolor = [1.0, 1.0, 1.0]\nopacity = {OPACITY}\ntransport = [1.0, 1.0, 1.0]\n",
        light.variance[0],
        light.variance[1],
        light.rotation_deg,
        2.0 * H,
    )
}

/// The ray parameters (entry, exit) of `p + s·f` in the box x ∈ `x`, z ∈ `z`, if it meets it.
fn slab_hit(p: [f64; 3], f: [f64; 3], x: (f64, f64), z: (f64, f64)) -> Option<(f64, f64)> {
    let mut lo = f64::NEG_INFINITY;
    let mut hi = f64::INFINITY;
    for (o, d, (a, b)) in [(p[0], f[0], x), (p[2], f[2], z)] {
        if d.abs() < 1e-15 {
            if o < a || o > b {
                return None;
            }
            continue;
        }
        let (s0, s1) = ((a - o) / d, (b - o) / d);
        lo = lo.max(s0.min(s1));
        hi = hi.min(s0.max(s1));
    }
    (lo < hi).then_some((lo, hi))
}

/// The visibility of the light at (x, z) behind the half-plane.
fn visibility(x: f64, z: f64, sigma: f64) -> f64 {
    let d = if x >= 0.0 { z - H } else { z + H };
    phi(-x / (d * sigma))
}

/// 16-point Gauss–Legendre on [0, 1]: (node, weight).
fn gauss_legendre_16() -> Vec<(f64, f64)> {
    gauss_legendre(16)
        .iter()
        .map(|&(x, w)| (0.5 * (x + 1.0), 0.5 * w))
        .collect()
}

/// Per pixel of a middle row: the expected normalised value, or `None` where the pixel does not
/// see the sheet first (or the sheet's penumbra lies off the measured range).
pub fn expected_row(theta: f64, light: SheetLight) -> Vec<Option<f64>> {
    let f = view_direction(theta);
    let right = right_of(f);
    let down = [0.0, -1.0, 0.0];
    let px = VIEW / f64::from(WIDTH);
    (0..WIDTH)
        .map(|i| {
            let cx = (f64::from(i) + 0.5 - f64::from(WIDTH) / 2.0) * px;
            let cy = 0.5 * px; // the row just below the centre
            let p = [
                right[0] * cx,
                right[1] * cx + down[1] * cy,
                W + right[2] * cx,
            ];
            expected_on_ray(p, f, 1.0, light)
        })
        .collect()
}

/// A perspective camera (`camera.projection = "perspective"`) at `eye` looking at `look_at`
/// (up = +y), horizontal field of view `fov_x_deg` across [`WIDTH`] pixels: its scene (TOML), as
/// [`scene_toml`]'s with the camera replaced, and its vertical `fov_deg` for [`HEIGHT`] pixels.
pub fn perspective_scene_toml(
    eye: [f64; 3],
    look_at: [f64; 3],
    fov_x_deg: f64,
    light: SheetLight,
    sweep: &str,
) -> String {
    let fov_y = perspective_fov_y(fov_x_deg);
    let ortho = scene_toml(0.0, light, sweep);
    let camera_start = ortho.find("[camera]").expect("a camera table");
    let camera_end = ortho.find("[sweep]").expect("a sweep table");
    format!(
        "{}[camera]\nprojection = \"perspective\"\neye = {eye:?}\nlook_at = {look_at:?}\n\
         fov_deg = {fov_y:?}\n{}",
        &ortho[..camera_start],
        &ortho[camera_end..]
    )
}

/// The vertical field of view (degrees) of [`HEIGHT`] pixels whose [`WIDTH`] pixels span
/// `fov_x_deg`.
pub fn perspective_fov_y(fov_x_deg: f64) -> f64 {
    let focal = 0.5 * f64::from(WIDTH) / (0.5 * fov_x_deg.to_radians()).tan();
    2.0 * (0.5 * f64::from(HEIGHT) / focal).atan().to_degrees()
}

/// [`expected_row`] for the perspective camera of [`perspective_scene_toml`]: each pixel's ray
/// from the eye through its centre, the sheet's opacity per unit of view depth (along the axis).
pub fn expected_row_perspective(
    eye: [f64; 3],
    look_at: [f64; 3],
    fov_x_deg: f64,
    light: SheetLight,
) -> Vec<Option<f64>> {
    let d = [
        look_at[0] - eye[0],
        look_at[1] - eye[1],
        look_at[2] - eye[2],
    ];
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let f = [d[0] / n, d[1] / n, d[2] / n];
    let right = right_of(f);
    let down = [0.0, -1.0, 0.0];
    let focal = 0.5 * f64::from(WIDTH) / (0.5 * fov_x_deg.to_radians()).tan();
    (0..WIDTH)
        .map(|i| {
            let u = (f64::from(i) + 0.5 - f64::from(WIDTH) / 2.0) / focal;
            let v = 0.5 / focal; // the row just below the centre
            let r = [
                f[0] + right[0] * u + down[0] * v,
                f[1] + right[1] * u + down[1] * v,
                f[2] + right[2] * u + down[2] * v,
            ];
            let len = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            let r = [r[0] / len, r[1] / len, r[2] / len];
            // View depth per unit of path along this ray.
            let depth_rate = r[0] * f[0] + r[1] * f[1] + r[2] * f[2];
            expected_on_ray(eye, r, depth_rate, light)
        })
        .collect()
}

/// The camera's right axis for view direction `f` and up = +y: down × f (`frame`).
fn right_of(f: [f64; 3]) -> [f64; 3] {
    let down = [0.0, -1.0, 0.0];
    [
        down[1] * f[2] - down[2] * f[1],
        down[2] * f[0] - down[0] * f[2],
        down[0] * f[1] - down[1] * f[0],
    ]
}

/// The expected normalised value of the view ray `p + s·f` (unit `f`; the sheet's opacity is
/// per unit of view depth, `depth_rate` of it per unit of s), or `None` where the ray does not
/// see the sheet first or meets it within 2 pixels of its ends.
fn expected_on_ray(p: [f64; 3], f: [f64; 3], depth_rate: f64, light: SheetLight) -> Option<f64> {
    let sigma = light.var_x().sqrt();
    let (v, _) = integrate_on_ray(p, f, depth_rate, |x, z| (visibility(x, z, sigma), 1.0))?;
    Some(v)
}

/// Along the view ray `p + s·f` through the sheet (see [`expected_on_ray`]): the mean over the
/// sheet's scattering of `light(x, z) = (visibility, unshadowed irradiance)` weighted by the
/// irradiance, and the mean irradiance: `(∫ w·V·E / ∫ w·E, ∫ w·E / ∫ w)` with `w = κ·e^(−κs)`.
fn integrate_on_ray(
    p: [f64; 3],
    f: [f64; 3],
    depth_rate: f64,
    light: impl Fn(f64, f64) -> (f64, f64),
) -> Option<(f64, f64)> {
    let px = VIEW / f64::from(WIDTH);
    let kappa = -(1.0 - OPACITY).ln() * depth_rate;
    let (s0, s1) = slab_hit(p, f, (-1.5, 1.5), (W - T / 2.0, W + T / 2.0))?;
    if let Some((h0, _)) = slab_hit(p, f, (0.0, 3.0), (-H, H))
        && h0 < s0
    {
        return None; // the half-plane hides the sheet
    }
    // Away from the sheet's ends (their own edges, 2 pixels) only.
    let x_at = |s: f64| p[0] + s * f[0];
    if x_at(s0).abs().max(x_at(s1).abs()) > 1.5 - 2.0 * px {
        return None;
    }
    // ∫ κ e^{−κ(s − s0)} V ds over [s0, s1], in pieces of at most 0.005.
    let nodes = gauss_legendre_16();
    let pieces = ((s1 - s0) / 0.005).ceil().max(1.0) as usize;
    let step = (s1 - s0) / pieces as f64;
    let (mut num, mut lit, mut den) = (0.0, 0.0, 0.0);
    for k in 0..pieces {
        for &(u, w) in &nodes {
            let s = s0 + step * (k as f64 + u);
            let weight = w * step * kappa * (-kappa * (s - s0)).exp();
            let (v, e) = light(x_at(s), p[2] + s * f[2]);
            num += weight * v * e;
            lit += weight * e;
            den += weight;
        }
    }
    Some((num / lit, lit / den))
}

/// The point-light variant's set-ups per view angle: (θ in degrees, the light's distance `L`
/// before the half-plane, the light grid's resolution). The light lies at (0.2, 0, −L), its
/// radius 0.05·L (the angular size of the directional light's σ/2 at the half-plane). `L` is
/// the nearest round distance at which the light lies before every mesh along the view (θ < 90°)
/// or behind every mesh (θ > 90°), as the sweep requires (a light amid the meshes is refused);
/// at 80° and 100° the light's grid at the eye's cell size would be wider than 16384 cells
/// (its rays graze the slabs), so it is swept at half the eye's resolution.
pub const POINT_SETUPS: [(f64, f64, f64); 6] = [
    (0.0, 2.0, 1.0),
    (45.0, 2.0, 1.0),
    (80.0, 10.0, 0.5),
    (100.0, 20.0, 0.5),
    (135.0, 4.0, 1.0),
    (180.0, 2.0, 1.0),
];

/// The point light's position and radius at distance `l` ([`POINT_SETUPS`]).
pub fn point_light_at(l: f64) -> ([f64; 3], f64) {
    ([0.2, 0.0, -l], 0.05 * l)
}

/// A point light of radius `r` (an isotropic 3D Gaussian) at `position` (before the
/// half-plane: z < −h) in the same scene, in place of the directional light: the `[[light]]`
/// lines, its colour `l_z²` so that the unshadowed irradiance is about 1 at the half-plane.
pub fn point_light_toml(position: [f64; 3], r: f64) -> String {
    let [x, y, z] = position;
    let c = z * z;
    format!(
        "kind = \"point\"\nposition = [{x:?}, {y:?}, {z:?}]\nradius = {r:?}\n\
         color = [{c:?}, {c:?}, {c:?}]\n"
    )
}

/// [`scene_toml`] with the point light of [`point_light_toml`] instead of the directional one.
pub fn point_scene_toml(theta: f64, position: [f64; 3], r: f64, sweep: &str) -> String {
    let text = scene_toml(theta, SheetLight::ISOTROPIC, sweep);
    let start = text.find("[[light]]\n").expect("a light") + "[[light]]\n".len();
    let end = text.find("[[mesh]]").expect("a mesh");
    format!(
        "{}{}{}",
        &text[..start],
        point_light_toml(position, r),
        &text[end..]
    )
}

/// [`expected_row`] for the point light of [`point_scene_toml`]: per pixel of a middle row, the
/// expected value normalised by the pixel's own unshadowed light (the light falls off as
/// 1/|X − P|² across the sheet), and that unshadowed light (relative: divide the render by it
/// before [`profile_rmse`]). The visibility is integrated over the light's Gaussian
/// (`point_edge::visibility_past`, the half-plane's own thickness).
pub fn expected_row_point(theta: f64, position: [f64; 3], r: f64) -> Vec<Option<(f64, f64)>> {
    let f = view_direction(theta);
    let right = right_of(f);
    let px = VIEW / f64::from(WIDTH);
    let light = glam::DVec3::from(position);
    (0..WIDTH)
        .map(|i| {
            let cx = (f64::from(i) + 0.5 - f64::from(WIDTH) / 2.0) * px;
            let cy = 0.5 * px;
            let p = [right[0] * cx, -cy, W + right[2] * cx];
            integrate_on_ray(p, f, 1.0, |x, z| {
                let at = glam::DVec3::new(x, p[1], z);
                let e = 1.0 / (at - light).length_squared();
                (crate::point_edge::visibility_past(at, light, r, H), e)
            })
        })
        .collect()
}

/// [`profile_rmse`] of a point light's render: each pixel divided by its unshadowed light
/// from [`expected_row_point`] first.
pub fn point_profile_rmse(
    image: &[f32],
    expected: &[Option<(f64, f64)>],
) -> Result<(f64, usize), String> {
    let w = WIDTH as usize;
    let levelled: Vec<f32> = image
        .iter()
        .enumerate()
        .map(|(k, &v)| match expected[(k / 3) % w] {
            Some((_, e)) => (f64::from(v) / e) as f32,
            None => v,
        })
        .collect();
    let visibility: Vec<Option<f64>> = expected.iter().map(|e| e.map(|(v, _)| v)).collect();
    profile_rmse(&levelled, &visibility)
}

/// The profile's error: the RMSE of the two middle rows of `image` (RGB, [`WIDTH`] ×
/// [`HEIGHT`]) normalised by the sheet's lit level, against `expected` ([`expected_row`]) over
/// the sheet's penumbra (expected value within 1e-4 of neither 0 nor 1), and the number of
/// pixels measured. Err when too few pixels are lit or in the penumbra to measure.
pub fn profile_rmse(image: &[f32], expected: &[Option<f64>]) -> Result<(f64, usize), String> {
    let w = WIDTH as usize;
    let rows = [HEIGHT as usize / 2 - 1, HEIGHT as usize / 2];
    let value = |row: usize, i: usize| f64::from(image[3 * (row * w + i)]);
    // The lit level: the render's mean where the sheet sees the whole light.
    let lit: Vec<f64> = rows
        .iter()
        .flat_map(|&r| {
            (0..w)
                .filter(|&i| expected[i].is_some_and(|v| v > 1.0 - 1e-12))
                .map(move |i| value(r, i))
        })
        .collect();
    if lit.len() < 8 {
        return Err(format!("only {} lit pixels", lit.len()));
    }
    let level = lit.iter().sum::<f64>() / lit.len() as f64;
    let (mut sq, mut n) = (0.0, 0usize);
    for &r in &rows {
        for (i, e) in expected.iter().enumerate() {
            let Some(e) = *e else { continue };
            if !(1e-4..=1.0 - 1e-4).contains(&e) {
                continue;
            }
            sq += (value(r, i) / level - e).powi(2);
            n += 1;
        }
    }
    if n < 2 {
        return Err(format!("only {n} penumbra pixels"));
    }
    Ok(((sq / n as f64).sqrt(), n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nodes_on_0_1_integrate_polynomials_to_degree_31() {
        let nodes = gauss_legendre_16();
        let w: f64 = nodes.iter().map(|&(_, w)| w).sum();
        assert!((w - 1.0).abs() < 1e-13);
        for d in [1, 7, 20, 31] {
            let got: f64 = nodes.iter().map(|&(x, w)| w * x.powi(d)).sum();
            assert!((got - 1.0 / f64::from(d + 1)).abs() < 1e-13, "degree {d}");
        }
    }

    #[test]
    fn a_camera_along_the_light_sees_the_edge_profile() {
        // θ = 0: each pixel looks along the light (its right is world −x). Where x > 0
        // (pixels up to 63) the half-plane hides the sheet; beside it, V is Φ(−x/(d·σ)) with
        // d = W + h at the sheet's depth, averaged over its thickness.
        let row = expected_row(0.0, SheetLight::ISOTROPIC);
        let sigma = 0.1;
        for k in 0..8 {
            assert_eq!(row[63 - k], None, "pixel {} sees the half-plane", 63 - k);
            let x = -(k as f64 + 0.5) * VIEW / f64::from(WIDTH);
            let v = row[64 + k].unwrap();
            assert!((v - phi(-x / ((W + H) * sigma))).abs() < 2e-3, "{k}: {v}");
        }
    }

    #[test]
    fn a_camera_along_a_point_light_sees_its_visibility_and_falloff() {
        // θ = 0: beside the half-plane each pixel's ray runs along z through the sheet; the
        // value is the visibility at the sheet's middle (within the thickness's average), the
        // irradiance 1/|X − P|² there.
        let (p, r) = point_light_at(2.0);
        let light = glam::DVec3::from(p);
        let row = expected_row_point(0.0, p, r);
        for k in 0..12 {
            let x = -(k as f64 + 0.5) * VIEW / f64::from(WIDTH);
            let at = glam::DVec3::new(x, -0.5 * VIEW / f64::from(WIDTH), W);
            let (v, e) = row[64 + k].unwrap();
            let want = crate::point_edge::visibility_past(at, light, r, H);
            assert!((v - want).abs() < 2e-3, "{k}: {v} against {want}");
            let falloff = 1.0 / (at - light).length_squared();
            assert!(
                (e / falloff - 1.0).abs() < 1e-3,
                "{k}: {e} against {falloff}"
            );
        }
        // Some of those pixels are in the penumbra: the check is not of a constant.
        assert!(
            row[64..76]
                .iter()
                .any(|v| v.is_some_and(|(v, _)| v > 0.05 && v < 0.95))
        );
    }
}
