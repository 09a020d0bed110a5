//! The shadow-ray reference (`--backend reference`, `reference/src/shadow_ray.rs`) converges to
//! closed forms as its light samples M grow, at surface crossings as well as in free space
//! (issue 46): two opaque half-planes whose penumbrae overlap, an opaque (polyhedral) sphere's
//! receiver shadow and its own lit surface, and a plate turned 60° to the view under a
//! half-plane. Every expected value is written here from the geometry and the light
//! (a Gaussian direction per unit depth, `u ~ N(tan ω, σ²)` per camera axis: a shadow ray from
//! a point at depth z towards the light meets depth z − s at an offset s·u), never taken from a
//! render. Each case renders the same scene at M = 16, 64, 256, 1024 and asks the RMSE against
//! the closed form to fall at least 3× from 16 to 256, never to rise, and to reach ≤ 2e-3.

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::reference::edge::phi;
use convshadow::reference::{Reference, ReferenceOptions};

use crate::support;

/// The light samples the cases render with.
const SAMPLES: [u32; 4] = [16, 64, 256, 1024];
/// Asked at the largest M.
const MAX_RMSE: f64 = 2e-3;
/// Asked between M = 16 and M = 256.
const MIN_GAIN: f64 = 3.0;

/// The reference's images of `scene` (red channel, row-major) at each of [`SAMPLES`].
fn reference_images(scene: &Scene) -> Vec<Vec<f64>> {
    let g = convshadow_io::build_geometry(scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, 1 << 30).unwrap_or_else(|e| panic!("{e}"));
    let plan = convshadow_io::build_plan(scene, &g).unwrap_or_else(|e| panic!("{e}"));
    let reference = Reference::new(scene, &g, &plan, 0.0);
    SAMPLES
        .iter()
        .map(|&samples| {
            let options = ReferenceOptions {
                samples,
                ..ReferenceOptions::default()
            };
            let image = reference.render(&ldi, &options);
            image.chunks(3).map(|c| f64::from(c[0])).collect()
        })
        .collect()
}

/// Camera coordinates (x right, y down; world units) of pixel (i, j)'s centre in a `w`×`h`
/// image of pixel size `px` centred on the camera axis.
fn pixel_centre(i: usize, j: usize, w: usize, h: usize, px: f64) -> (f64, f64) {
    (
        (i as f64 + 0.5 - 0.5 * w as f64) * px,
        (j as f64 + 0.5 - 0.5 * h as f64) * px,
    )
}

/// RMSE of each image against `expected` over the pixels where it is `Some`; returns the RMSEs
/// (one per M) and the number of pixels compared.
pub(crate) fn rmse_per_m(images: &[Vec<f64>], expected: &[Option<f64>]) -> (Vec<f64>, usize) {
    let n = expected.iter().flatten().count();
    let rmse = images
        .iter()
        .map(|img| {
            let sq: f64 = img
                .iter()
                .zip(expected)
                .filter_map(|(v, e)| e.map(|e| (v - e) * (v - e)))
                .sum();
            (sq / n as f64).sqrt()
        })
        .collect();
    (rmse, n)
}

/// The convergence asked of every case: prints the errors, asserts the gain from M = 16 to 256,
/// no rise as M grows (10 % slack for noise) and the final error.
fn assert_converges(name: &str, rmse: &[f64], pixels: usize, min_pixels: usize) {
    let line = SAMPLES
        .iter()
        .zip(rmse)
        .map(|(m, e)| format!("M = {m}: {e:.2e}"))
        .collect::<Vec<_>>()
        .join(", ");
    eprintln!("{name} ({pixels} px): {line}");
    assert!(
        pixels >= min_pixels,
        "{name}: only {pixels} pixels compared"
    );
    let gain = rmse[0] / rmse[2];
    assert!(
        gain >= MIN_GAIN,
        "{name}: M 16 → 256 lowered the RMSE only {gain:.2}× ({line})"
    );
    for w in rmse.windows(2) {
        assert!(w[1] <= 1.1 * w[0], "{name}: the RMSE rose with M ({line})");
    }
    let last = rmse[rmse.len() - 1];
    assert!(
        last <= MAX_RMSE,
        "{name}: RMSE {last:.2e} > {MAX_RMSE:e} ({line})"
    );
}

/// Gaussian light `u ~ N(mu, sigma²)` along one axis: P(lo < u < hi).
fn p_between(lo: f64, hi: f64, mu: f64, sigma: f64) -> f64 {
    if hi <= lo {
        0.0
    } else {
        phi((hi - mu) / sigma) - phi((lo - mu) / sigma)
    }
}

/// Composite Simpson's rule of `f` on [a, b] with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for k in 1..n {
        s += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// The standard normal density.
fn gauss(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

// ---------------------------------------------------------------------------------------------
// Two half-planes at distances 4 and 1 over a receiver, penumbrae overlapping.

/// Two-plane scene: image size, view width, light.
const PLANES_W: usize = 96;
const PLANES_H: usize = 24;
const PLANES_VIEW: f64 = 1.0;
const PLANES_TILT: f64 = -3.0;
const PLANES_VAR: f64 = 0.02;
/// Half-plane A (distance 4, covers camera x ≤ A_EDGE), B (distance 1, covers x ≥ B_EDGE); both
/// boxes `PLANE_T` thick, their back faces at the distances named.
const A_DIST: f64 = 4.0;
const B_DIST: f64 = 1.0;
const A_EDGE: f64 = -0.4;
const B_EDGE: f64 = 0.4;
const PLANE_T: f64 = 0.01;

fn two_planes_scene() -> Scene {
    // Camera x = −world x (camera along +z, up +y): A covers world x ≥ 0.4, B world x ≤ −0.4.
    // The receiver's front face is at world z = 0.
    let text = format!(
        r#"
[image]
width = {PLANES_W}
height = {PLANES_H}
[camera]
view_width = {PLANES_VIEW}
[sweep]
slabs = 16
[[light]]
tilt_deg = [{PLANES_TILT}, 0.0]
variance = [{PLANES_VAR}, {PLANES_VAR}]
[[mesh]]
shape = "box"
size = [20.0, 40.0, {PLANE_T}]
translate = [{ax}, 0.0, {az}]
material = "white"
[[mesh]]
shape = "box"
size = [20.0, 40.0, {PLANE_T}]
translate = [{bx}, 0.0, {bz}]
material = "white"
[[mesh]]
shape = "box"
size = [40.0, 40.0, 0.1]
translate = [0.0, 0.0, 0.05]
material = "white"
[material.white]
opacity = 1.0
surface = "flat"
"#,
        ax = -A_EDGE + 10.0,
        az = -A_DIST - 0.5 * PLANE_T,
        bx = -B_EDGE - 10.0,
        bz = -B_DIST - 0.5 * PLANE_T,
    );
    support::scene(&text, Path::new("."))
}

/// The light at receiver point x (camera x) under the two half-planes: the ray of slope u
/// passes A iff x + s·u > A_EDGE at both of A's faces (s = A_DIST, A_DIST + PLANE_T) and B iff
/// x + s·u < B_EDGE at both of B's: u in an interval, whose Gaussian measure is a difference of
/// Φ. The y slope does not matter (edges along y, boxes far longer than any ray's y offset).
fn two_planes_light(x: f64) -> f64 {
    let lo = [A_DIST, A_DIST + PLANE_T]
        .iter()
        .map(|s| (A_EDGE - x) / s)
        .fold(f64::NEG_INFINITY, f64::max);
    let hi = [B_DIST, B_DIST + PLANE_T]
        .iter()
        .map(|s| (B_EDGE - x) / s)
        .fold(f64::INFINITY, f64::min);
    p_between(lo, hi, PLANES_TILT.to_radians().tan(), PLANES_VAR.sqrt())
}

#[test]
fn the_closed_form_of_two_half_planes_is_the_integral_over_directions() {
    // The same probability as a 1-D integral of the density over the light's slopes u, by
    // Simpson on ±8σ (the visibility as an indicator of u, made smooth by integrating the
    // density between the indicator's ends found by bisection on the two conditions).
    let mu = PLANES_TILT.to_radians().tan();
    let sigma = PLANES_VAR.sqrt();
    let passes = |x: f64, u: f64| {
        [A_DIST, A_DIST + PLANE_T]
            .iter()
            .all(|s| x + s * u > A_EDGE)
            && [B_DIST, B_DIST + PLANE_T]
                .iter()
                .all(|s| x + s * u < B_EDGE)
    };
    for x in [-0.35, -0.2, 0.0, 0.2, 0.3, 0.38] {
        // Riemann-free: integrate the density times the indicator on a fine grid of cells,
        // Simpson inside each cell the indicator holds on at both ends.
        let (a, b) = (mu - 8.0 * sigma, mu + 8.0 * sigma);
        let cells = 20_000;
        let h = (b - a) / f64::from(cells);
        let mut p = 0.0;
        for c in 0..cells {
            let (u0, u1) = (a + f64::from(c) * h, a + f64::from(c + 1) * h);
            if passes(x, u0) && passes(x, u1) {
                p += simpson(|u| gauss((u - mu) / sigma) / sigma, u0, u1, 2);
            }
        }
        let closed = two_planes_light(x);
        // The cells cut by an end lose at most one cell's mass each: 2·h·max density.
        let bound = 2.0 * h * gauss(0.0) / sigma + 1e-12;
        assert!(
            (p - closed).abs() <= bound,
            "x = {x}: integral {p} vs closed form {closed}"
        );
        assert!(
            closed > 0.05 && closed < 0.999,
            "x = {x}: {closed} is not in a penumbra"
        );
    }
}

#[test]
fn the_reference_converges_on_two_overlapping_half_plane_penumbrae() {
    let images = reference_images(&two_planes_scene());
    let px = PLANES_VIEW / PLANES_W as f64;
    let mut expected = Vec::new();
    for j in 0..PLANES_H {
        for i in 0..PLANES_W {
            let (x, _) = pixel_centre(i, j, PLANES_W, PLANES_H, px);
            // The receiver is seen between the two edges (one pixel's margin).
            let seen = x > A_EDGE + px && x < B_EDGE - px;
            expected.push(seen.then(|| two_planes_light(x)));
        }
    }
    let (rmse, n) = rmse_per_m(&images, &expected);
    assert_converges("two half-planes (d = 4, 1)", &rmse, n, 1500);
}

// ---------------------------------------------------------------------------------------------
// An opaque icosphere over a receiver: the receiver's shadow and the sphere's own lit surface.

const SPHERE_SIZE: usize = 64;
const SPHERE_VIEW: f64 = 3.0;
const SPHERE_R: f64 = 0.5;
/// Subdivisions of the icosphere: the expected values are the polyhedron's, so any will do.
const SPHERE_SUBDIV: u32 = 3;
/// Distance from the sphere's centre to the receiver's front face (world z = 0).
pub(crate) const SPHERE_D: f64 = 1.2;
const SPHERE_TILT: [f64; 2] = [35.0, -10.0];
const SPHERE_VAR: [f64; 2] = [0.03, 0.015];

pub(crate) fn sphere_scene() -> Scene {
    let text = format!(
        r#"
[image]
width = {SPHERE_SIZE}
height = {SPHERE_SIZE}
[camera]
view_width = {SPHERE_VIEW}
[sweep]
slabs = 16
[[light]]
tilt_deg = [{tx}, {ty}]
variance = [{vx}, {vy}]
[[mesh]]
shape = "sphere"
size = [{SPHERE_R}, {SPHERE_SUBDIV}]
translate = [0.0, 0.0, {zc}]
material = "white"
[[mesh]]
shape = "box"
size = [40.0, 40.0, 0.1]
translate = [0.0, 0.0, 0.05]
material = "white"
[material.white]
opacity = 1.0
surface = "flat"
"#,
        tx = SPHERE_TILT[0],
        ty = SPHERE_TILT[1],
        vx = SPHERE_VAR[0],
        vy = SPHERE_VAR[1],
        zc = -SPHERE_D,
    );
    support::scene(&text, Path::new("."))
}

/// The light's slope distribution per camera axis: (mean, standard deviation).
fn sphere_light() -> [(f64, f64); 2] {
    [0, 1].map(|a| (SPHERE_TILT[a].to_radians().tan(), SPHERE_VAR[a].sqrt()))
}

/// The icosphere as the scene places it (vertices in camera coordinates: x = −world x,
/// y = −world y, z = world z for a camera along +z with up +y) and its facets as vertex index
/// triples with their outward unit normals.
struct Polyhedron {
    vertices: Vec<[f64; 3]>,
    facets: Vec<([usize; 3], [f64; 3])>,
}

fn sphere_polyhedron(scene: &Scene) -> Polyhedron {
    let g = convshadow_io::build_geometry(scene).unwrap_or_else(|e| panic!("{e}"));
    let mesh = &g.meshes[0].mesh;
    let vertices: Vec<[f64; 3]> = mesh.positions.iter().map(|p| [-p.x, -p.y, p.z]).collect();
    let centre = [0.0, 0.0, -SPHERE_D];
    let facets = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            let n = cross(sub(b, a), sub(c, a));
            let len = dot(n, n).sqrt();
            let mut n = [n[0] / len, n[1] / len, n[2] / len];
            // Outward: away from the centre (the polyhedron is convex around it).
            if dot(n, sub(a, centre)) < 0.0 {
                n = [-n[0], -n[1], -n[2]];
            }
            (t.map(|i| i as usize), n)
        })
        .collect();
    for v in &vertices {
        let r = dot(sub(*v, centre), sub(*v, centre)).sqrt();
        assert!((r - SPHERE_R).abs() < 1e-9, "vertex off the sphere: {r}");
    }
    Polyhedron { vertices, facets }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Convex hull of 2-D points (Andrew's monotone chain): (lower chain, upper chain), each from
/// the smallest x to the largest.
fn hull(mut pts: Vec<[f64; 2]>) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let chain = |pts: &mut dyn Iterator<Item = [f64; 2]>, keep: &dyn Fn(f64) -> bool| {
        let mut h: Vec<[f64; 2]> = Vec::new();
        for p in pts {
            while h.len() >= 2 && !keep(turn(h[h.len() - 2], h[h.len() - 1], p)) {
                h.pop();
            }
            h.push(p);
        }
        h
    };
    let lower = chain(&mut pts.iter().copied(), &|t| t > 0.0);
    let upper = chain(&mut pts.iter().copied(), &|t| t < 0.0);
    (lower, upper)
}

/// y of the chain (sorted by x) at `x`, linear between its points.
fn chain_at(chain: &[[f64; 2]], x: f64) -> f64 {
    for w in chain.windows(2) {
        if x <= w[1][0] {
            let span = w[1][0] - w[0][0];
            let t = if span > 0.0 {
                (x - w[0][0]) / span
            } else {
                1.0
            };
            return w[0][1] + t * (w[1][1] - w[0][1]);
        }
    }
    chain[chain.len() - 1][1]
}

/// The light at receiver point (x, y, 0) under the polyhedron: 1 − P(the ray's slopes u fall in
/// the polyhedron's central projection from the point), the projection being the convex hull
/// of the vertices' slopes ((V − p)_xy / (p − V)_z); the Gaussian measure of the polygon is
/// ∫ φx(ux)·[Φy(upper(ux)) − Φy(lower(ux))] dux, by Simpson on each piece between the hull's
/// vertices (where the integrand is smooth), 32 intervals a piece.
fn sphere_receiver_light(poly: &Polyhedron, x: f64, y: f64) -> f64 {
    let [(mx, sx), (my, sy)] = sphere_light();
    let slopes: Vec<[f64; 2]> = poly
        .vertices
        .iter()
        .map(|v| [(v[0] - x) / -v[2], (v[1] - y) / -v[2]])
        .collect();
    let (lower, upper) = hull(slopes);
    let mut xs: Vec<f64> = lower.iter().chain(&upper).map(|p| p[0]).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let f = |u: f64| {
        let (lo, hi) = (chain_at(&lower, u), chain_at(&upper, u));
        gauss((u - mx) / sx) / sx * (phi((hi - my) / sy) - phi((lo - my) / sy)).max(0.0)
    };
    let blocked: f64 = xs.windows(2).map(|w| simpson(f, w[0], w[1], 32)).sum();
    1.0 - blocked
}

/// The light at the polyhedron's surface point on the facet of outward normal n: a ray of
/// slopes u (direction (ux, uy, −1)) leaves the convex polyhedron iff n·(ux, uy, −1) > 0, else it
/// crosses its opaque inside. n·v is Gaussian with mean nx·μx + ny·μy − nz and variance
/// nx²σx² + ny²σy²: the light is Φ(mean / std).
fn facet_light(n: [f64; 3]) -> f64 {
    let [(mx, sx), (my, sy)] = sphere_light();
    let mean = n[0] * mx + n[1] * my - n[2];
    let std = (n[0] * n[0] * sx * sx + n[1] * n[1] * sy * sy).sqrt();
    if std == 0.0 {
        if mean > 0.0 { 1.0 } else { 0.0 }
    } else {
        phi(mean / std)
    }
}

/// The facet the camera sees at (x, y): the front-facing facet (nz < 0) whose projection holds
/// the point.
fn seen_facet(poly: &Polyhedron, x: f64, y: f64) -> Option<[f64; 3]> {
    poly.facets.iter().find_map(|(t, n)| {
        if n[2] >= 0.0 {
            return None;
        }
        let [a, b, c] = t.map(|i| poly.vertices[i]);
        let side =
            |p: [f64; 3], q: [f64; 3]| (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0]);
        let s = [side(a, b), side(b, c), side(c, a)];
        (s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)).then_some(*n)
    })
}

#[test]
fn the_receiver_closed_form_of_the_polyhedron_is_the_spheres_within_its_facets() {
    // A check of the polygon integral: the receiver's light under the polyhedron lies between
    // the light under the sphere through its vertices and under its inscribed sphere, here
    // computed independently (a sphere of radius r at distance D blocks the directions within
    // a cone of half-angle asin(r/|c − p|) around c − p: a 2-D Gaussian integral over the
    // slopes, by Simpson across x and the exact interval along y).
    let scene = sphere_scene();
    let poly = sphere_polyhedron(&scene);
    let [(mx, sx), (my, sy)] = sphere_light();
    let sphere_light_at = |r: f64, x: f64, y: f64| {
        // Slopes u = (a, b): the ray p + s·(a, b, −1) meets the ball iff
        // |w × v|² ≤ r²|v|², w = c − p, v = (a, b, −1): a quadratic in b for each a.
        let w = [-x, -y, -SPHERE_D];
        let k = dot(w, w) - r * r;
        let f = |a: f64| {
            // (w·v)² − k|v|² ≥ 0 with w·v = w0·a + w1·b − w2.
            let c0 = w[0] * a - w[2];
            let qa = w[1] * w[1] - k;
            let qb = 2.0 * w[1] * c0;
            let qc = c0 * c0 - k * (a * a + 1.0);
            let disc = qb * qb - 4.0 * qa * qc;
            if disc <= 0.0 || qa >= 0.0 {
                return 0.0;
            }
            let (r1, r2) = (
                (-qb + disc.sqrt()) / (2.0 * qa),
                (-qb - disc.sqrt()) / (2.0 * qa),
            );
            let (lo, hi) = (r1.min(r2), r1.max(r2));
            gauss((a - mx) / sx) / sx * (phi((hi - my) / sy) - phi((lo - my) / sy))
        };
        1.0 - simpson(f, mx - 9.0 * sx, mx + 9.0 * sx, 4000)
    };
    // The inradius: the smallest distance from the centre to a facet plane.
    let centre = [0.0, 0.0, -SPHERE_D];
    let inradius = poly
        .facets
        .iter()
        .map(|(t, n)| dot(sub(poly.vertices[t[0]], centre), *n))
        .fold(f64::INFINITY, f64::min);
    let mut penumbra = 0;
    for (x, y) in [
        (-0.84, 0.21),
        (-0.6, 0.0),
        (-0.9, 0.5),
        (-1.2, 0.3),
        (-0.7, -0.2),
        (-1.4, 0.0),
    ] {
        let p = sphere_receiver_light(&poly, x, y);
        let (outer, inner) = (
            sphere_light_at(SPHERE_R, x, y),
            sphere_light_at(inradius, x, y),
        );
        assert!(
            outer - 1e-6 <= p && p <= inner + 1e-6,
            "({x}, {y}): polyhedron {p} not within spheres [{outer}, {inner}]"
        );
        penumbra += usize::from(p > 0.01 && p < 0.99);
    }
    assert!(penumbra >= 3, "the points must include penumbra");
}

/// The sphere scene's expected light per pixel (row-major, at the scene's image size, square):
/// (the receiver where the sphere shadows it, 2 px or more outside the outline; the sphere's own
/// surface, 3 px or more inside it), `None` elsewhere.
pub(crate) fn sphere_expected(scene: &Scene) -> (Vec<Option<f64>>, Vec<Option<f64>>) {
    let size = scene.image.width as usize;
    let poly = sphere_polyhedron(scene);
    let px = SPHERE_VIEW / size as f64;
    let (mut receiver, mut surface) = (Vec::new(), Vec::new());
    for j in 0..size {
        for i in 0..size {
            let (x, y) = pixel_centre(i, j, size, size, px);
            let rho = (x * x + y * y).sqrt();
            receiver.push(if rho > SPHERE_R + 2.0 * px {
                let l = sphere_receiver_light(&poly, x, y);
                (l < 1.0 - 1e-6).then_some(l)
            } else {
                None
            });
            surface.push(if rho < SPHERE_R - 3.0 * px {
                let n = seen_facet(&poly, x, y).expect("a facet under every inner pixel");
                Some(facet_light(n))
            } else {
                None
            });
        }
    }
    (receiver, surface)
}

#[test]
fn the_reference_converges_on_a_spheres_receiver_shadow_and_its_lit_surface() {
    let scene = sphere_scene();
    let images = reference_images(&scene);
    let (receiver, surface) = sphere_expected(&scene);
    let (rmse, n) = rmse_per_m(&images, &receiver);
    assert_converges("sphere: receiver in its shadow", &rmse, n, 300);
    let (rmse, n) = rmse_per_m(&images, &surface);
    assert_converges("sphere: its own lit surface", &rmse, n, 150);
}

// ---------------------------------------------------------------------------------------------
// A plate turned 60° to the view under an opaque half-plane (tests/accuracy/oblique_receiver.rs'
// geometry, with the occluder's thickness in the closed form).

/// Image width and height (pixels) and pixel size: 2 world units high, a strip right of the
/// occluder's edge wide (the self-hits of before needed pixels this small: at 64 px over 2 units
/// the rounding of the LDI's depth happened to stay outside the plate).
const PLATE_W: usize = 48;
const PLATE_H: usize = 128;
const PLATE_PX: f64 = 2.0 / 128.0;
const PLATE_TILT_DEG: f64 = 60.0;
const PLATE_THICK: f64 = 0.1;
const PLATE_GAP: f64 = 0.2;
const PLATE_OCC_T: f64 = 0.02;
const PLATE_LIGHT: [f64; 2] = [-25.0, 15.0];
const PLATE_VAR: f64 = 0.0025;

/// Camera depth of the plate's front face at camera y (world y = −camera y).
fn plate_depth(cam_y: f64) -> f64 {
    let t = PLATE_TILT_DEG.to_radians();
    -0.5 * PLATE_THICK / t.cos() - cam_y * t.tan()
}

/// Depth of the occluder's back face: `PLATE_GAP` in front of the plate's nearest point seen.
fn plate_occluder_back() -> f64 {
    let half = 0.5 * PLATE_H as f64 * PLATE_PX;
    plate_depth(-half).min(plate_depth(half)) - PLATE_GAP
}

fn plate_scene() -> Scene {
    let text = format!(
        r#"
[image]
width = {PLATE_W}
height = {PLATE_H}
[camera]
view_width = {view}
[sweep]
slabs = 64
[[light]]
tilt_deg = [{lx}, {ly}]
variance = [{PLATE_VAR}, {PLATE_VAR}]
[[mesh]]
shape = "box"
size = [8.0, 16.0, {PLATE_OCC_T}]
translate = [4.0, 0.0, {zo}]
material = "white"
[[mesh]]
shape = "box"
size = [8.0, 8.0, {PLATE_THICK}]
rotate_deg = [{PLATE_TILT_DEG}, 0.0, 0.0]
material = "white"
[material.white]
opacity = 1.0
surface = "flat"
"#,
        lx = PLATE_LIGHT[0],
        ly = PLATE_LIGHT[1],
        zo = plate_occluder_back() - 0.5 * PLATE_OCC_T,
        view = PLATE_W as f64 * PLATE_PX,
    );
    support::scene(&text, Path::new("."))
}

/// The light on the plate at camera (x, y), x > 0 (the occluder covers camera x ≤ 0): the ray
/// passes the occluder iff x + s·ux > 0 at both its faces (s = d, d + thickness), and leaves the
/// plate's front face (outward normal (0, −sin t, −cos t) in camera space) iff
/// −sin t·uy + cos t > 0, i.e. uy < cot t. The two conditions are on independent axes.
fn plate_light(x: f64, y: f64) -> f64 {
    let d = plate_depth(y) - plate_occluder_back();
    let lo = [d, d + PLATE_OCC_T]
        .iter()
        .map(|s| -x / s)
        .fold(f64::NEG_INFINITY, f64::max);
    let sigma = PLATE_VAR.sqrt();
    let (mx, my) = (
        PLATE_LIGHT[0].to_radians().tan(),
        PLATE_LIGHT[1].to_radians().tan(),
    );
    let t = PLATE_TILT_DEG.to_radians();
    p_between(lo, f64::INFINITY, mx, sigma) * phi((t.cos() / t.sin() - my) / sigma)
}

#[test]
fn the_reference_converges_on_a_plate_at_60_degrees_without_shadowing_itself() {
    let images = reference_images(&plate_scene());
    let px = PLATE_PX;
    let mut expected = Vec::new();
    let mut lit = Vec::new();
    for j in 0..PLATE_H {
        for i in 0..PLATE_W {
            let (x, y) = pixel_centre(i, j, PLATE_W, PLATE_H, px);
            let e = (x > px).then(|| plate_light(x, y));
            if e.is_some_and(|e| e > 0.999) {
                lit.push(j * PLATE_W + i);
            }
            expected.push(e);
        }
    }
    // No dark rows: every pixel the closed form lights (≥ 0.999) is lit (≥ 0.98) in every render.
    let mut dark_rows = Vec::new();
    for (img, m) in images.iter().zip(SAMPLES) {
        let rows: std::collections::BTreeSet<usize> = lit
            .iter()
            .filter(|&&k| img[k] < 0.98)
            .map(|k| k / PLATE_W)
            .collect();
        let mean = lit.iter().map(|&k| img[k]).sum::<f64>() / lit.len() as f64;
        eprintln!("plate, M = {m}: lit region mean {mean:.6}, rows with dark lit pixels {rows:?}");
        dark_rows.push(rows.len());
    }
    assert!(
        dark_rows.iter().all(|&r| r == 0),
        "rows with dark lit pixels: {dark_rows:?}"
    );
    eprintln!("plate: {} lit pixels", lit.len());
    assert!(lit.len() >= 100, "{} lit pixels", lit.len());
    let (rmse, n) = rmse_per_m(&images, &expected);
    assert_converges("plate at 60° under a half-plane", &rmse, n, 1500);
}

#[test]
fn the_reference_gives_the_same_bits_on_any_thread_count() {
    // Hashes for every random number and a fixed summation order per pixel: the image of a
    // scene with crossings (the icosphere over its receiver) does not depend on the threads.
    let scene = sphere_scene();
    let g = convshadow_io::build_geometry(&scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, 1 << 30).unwrap_or_else(|e| panic!("{e}"));
    let plan = convshadow_io::build_plan(&scene, &g).unwrap_or_else(|e| panic!("{e}"));
    let reference = Reference::new(&scene, &g, &plan, 0.0);
    let options = ReferenceOptions {
        samples: 16,
        ..ReferenceOptions::default()
    };
    let render = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let image = pool.install(|| reference.render(&ldi, &options));
        image.iter().map(|v| v.to_bits()).collect::<Vec<u32>>()
    };
    let one = render(1);
    assert!(
        one.iter()
            .any(|&b| f32::from_bits(b) > 0.0 && f32::from_bits(b) < 1.0)
    );
    assert_eq!(one, render(3));
    assert_eq!(one, render(8));
}
