//! The ground-truth shadow-ray reference: the light arriving at
//! every shading point, integrated by Monte Carlo over the Gaussian light's directions with
//! transmittance marched along each shadow ray through the continuous scene.
//!
//! What it shares with the sweep, and what it does not:
//! - **View samples** are the sweep's: per pixel and slab the same shading point (the crossing
//!   point, else the slab centre plus the same hashed jitter), the same material, detail value,
//!   transfer function, specular term and front-to-back compositing. Only the light term `Iin`
//!   differs, so the image difference is the shadow error and nothing else. With second-order
//!   media (`sweep.media`) the sweep lights a medium's sample with the light in the middle of the
//!   slab's part inside the medium, and composites the entry and exit slabs by that part: the
//!   reference does the same (its light traced to the middle of the slab where no surface was
//!   crossed; at a crossing, to the surface).
//! - **Light directions**: per shading point and light, `M = k²` multi-jittered directions
//!   (Chiu, Shirley and Wang 1994): one per cell of a k×k stratification of the unit square and
//!   at the same time one per each of the M fine strata of either axis, the fine strata assigned
//!   by hashed permutations (`light_samples::permute`, Kensler 2013) and jittered by the integer hash (no
//!   `rand`), mapped through the inverse normal CDF to the light's Gaussian
//!   `N(μl, R diag(σ²) Rᵀ)` per unit depth. The fine strata make a shadow edge along a principal
//!   axis of the light converge like 1/M instead of the plain k×k grid's M^-3/4; any other edge
//!   converges like M^-3/4 (docs/accuracy.md, "The ground-truth reference").
//! - **Inside test**: exact. Each shadow ray is intersected (Möller–Trumbore, f64) with the
//!   world triangles whose screen bounding box it passes (a 2D bin grid), and the crossings are
//!   counted even-odd from the light side, where every point is outside. The LDI's fragments are
//!   only exact at pixel centres and a shadow ray crosses pixels between them, so they are not
//!   used for shadow rays (a nearest-pixel inside test would quantize every shadow edge to the
//!   pixel grid, an error of the size being measured).
//! - **Materials** at continuous positions: the gradient's opacity α(v) per reference length
//!   becomes an extinction `κ = −ln(1 − α)/e_ref` per unit depth and the light is attenuated by
//!   `exp(−(1 − τ)·∫κ)` (the limit of the sweep's `1 − α_slab(1 − τ)` per slab as the slab
//!   thickness goes to 0). Like the sweep it attenuates per unit *depth*, not per unit path
//!   length: it integrates the method's model, so it measures numerical error, not the gap
//!   between the model and physically based transport. Detail media are marched with a step
//!   given to [`Reference::new`] (by default an eighth of the slab thickness),
//!   constant media are integrated in closed form. Opacity 1 is an infinite extinction: any
//!   positive length blocks the light.
//! - **Surface crossings**: the model reads the light *arriving at* a crossed surface, which the
//!   surface itself does not occlude. A crossing's shadow rays start on the exact surface under
//!   the pixel centre (the mesh's triangle there, intersected in f64: the LDI's f32 depth is off
//!   the surface by rounding and by the vertices' fixed-point snapping, by up to ~1e-4 of depth
//!   on a surface at 60° to the view, which made whole rows of such a plate shadow themselves)
//!   and do not count that triangle as crossed; a ray heading into the mesh then meets its far
//!   side and is attenuated by the inside (an opaque sphere's surface point is lit by the
//!   directions of its tangent half-space), a ray heading out meets nothing of it. Crossings
//!   within 2^-30 (relative) of the start are the start met again through rounding (a
//!   neighbouring triangle at a shared edge, a coincident face) and are ignored. See `geometry::Start`.
//!
//! - **Open meshes** are thin shells (docs/scene-format.md, "Open meshes"): their crossings
//!   toggle no inside bit, and a shadow ray crossing one is attenuated there by one reference
//!   length of its material, `1 − α·(1 − τ)` at the crossing's detail value.
//!
//! - **Patterned lights**: a ray's transmittance is multiplied by the light's initial light
//!   (its pattern, as the plan sampled it at pixel centres; bilinear between them, 1 outside the
//!   grid like the sweep's reads) where the ray leaves the scene through the first slab plane.
//!
//! - **A perspective camera** (`camera.projection`): the tracer works in slab-grid coordinates
//!   (`Camera::to_grid`: camera x/y over the pixel size at the `look_at` distance, depth along
//!   the view), an affine image of world space in which a directional light's rays keep one
//!   slope; only the view samples move: pixel (i, j)'s sample at depth z is where its ray from
//!   the eye is at that depth (`Camera::pixel_to_grid`), a crossing's surface point is the ray's
//!   f64 intersection with the crossed mesh, and the detail is read there. The LDI is the
//!   perspective one (view depths along each pixel's ray). Highlights keep the view direction
//!   of the image centre.
//!
//! - **Point and spot lights** (`shadow_ray/point.rs`): shadow rays of finite length to `M`
//!   points of the light's 3D Gaussian, the falloff `1/|X − P|²` and the spot's cone of the
//!   light's centre, and the shading's light direction per shading point (`shade_with`).
//!
//! It is slow — every shading point marches `lights × M` rays — and meant for small images.

use convshadow_common::model::scene::{MaterialSpec, Scene};
use convshadow_common::pixel::hash::{mix32, row_hash};

mod geometry;
mod point;
mod transmittance;
mod turned_eye;

use geometry::{Start, Tri, add, intersect, sub};

/// How a light's shadow rays are drawn.
#[derive(Clone, Debug)]
enum LightSource {
    /// A directional light: its mean direction offset per unit depth (grid px per world depth)
    /// and the Cholesky-like factor (R·diag(σ)) in grid px per world depth.
    Directional([f64; 2], [[f64; 2]; 2]),
    /// A point or spot light.
    Point(PointSource),
}
use convshadow_common::plan::point_light::PointSource;
pub use point::closed_mesh_holding;
pub use turned_eye::TurnedEye;

use crate::light_samples::{gaussian_pair, samples_side};
use convshadow_common::plan::{DEFAULT_REFERENCE_LENGTH, RenderPlan};
use convshadow_common::prepare::geometry::SceneGeometry;
use rayon::prelude::*;

use convshadow_cpu::composite::{composite, finish, part_of_slab};
use convshadow_cpu::ldi::Ldi;
use convshadow_cpu::parity::{NO_CROSSING, advance, first_mesh, slab_part};
use convshadow_cpu::shading::{LightTerms, Surface, material_at, shade_with, shading_depth};

/// Optical depth beyond which a shadow ray is treated as fully blocked (e^-40 ≈ 4e-18).
const OPAQUE_DEPTH: f64 = 40.0;
/// Side of a bin of the triangle grid, in grid pixels.
const BIN: f64 = 4.0;
/// Stop compositing a pixel once `1 − A` falls below this (changes the image by less).
const TRANSPARENCY_CUTOFF: f32 = 1e-7;

/// How the reference integrates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceOptions {
    /// Light directions per shading point and light; rounded up to a square `k²`.
    pub samples: u32,
    /// Seed of the direction jitter (independent of the sweep's seed).
    pub seed: u32,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions {
            samples: 64,
            seed: 0x5eed,
        }
    }
}

/// A material as the reference sees it: extinction per unit depth as a function of the detail
/// value, and transport.
#[derive(Clone, Debug)]
struct Medium {
    /// Opacity of a constant material (per reference length).
    opacity: f64,
    /// Gradient stops (value, opacity) of a detail material; empty for constant ones.
    stops: Vec<(f64, f64)>,
    /// The length the opacities are given for.
    reference_length: f64,
    /// Transport colour τ.
    transport: [f64; 3],
}

/// Extinction per unit depth of opacity `alpha` per `reference_length` (infinite for opacity 1:
/// any positive length of an opaque medium blocks the light, as the sweep's `α_slab = 1` does).
fn extinction(alpha: f64, reference_length: f64) -> f64 {
    if alpha >= 1.0 {
        f64::INFINITY
    } else {
        -(1.0 - alpha.max(0.0)).ln() / reference_length
    }
}

impl Medium {
    fn new(m: &MaterialSpec) -> Medium {
        Medium {
            opacity: m.opacity,
            stops: m.gradient.iter().map(|s| (s.value, s.opacity)).collect(),
            reference_length: m.reference_length.unwrap_or(DEFAULT_REFERENCE_LENGTH),
            transport: m.transport,
        }
    }

    /// Extinction at detail value `v`: the gradient's opacity interpolated linearly (piecewise
    /// linear, constant beyond the ends, as the scene format defines it), then converted.
    fn kappa(&self, v: f64) -> f64 {
        let g = &self.stops;
        if g.is_empty() {
            return extinction(self.opacity, self.reference_length);
        }
        let mut a = g[g.len() - 1].1;
        if v <= g[0].0 {
            a = g[0].1;
        } else {
            for w in g.windows(2) {
                if v <= w[1].0 {
                    let span = w[1].0 - w[0].0;
                    let t = if span > 0.0 { (v - w[0].0) / span } else { 1.0 };
                    a = w[0].1 + t * (w[1].1 - w[0].1);
                    break;
                }
            }
        }
        extinction(a, self.reference_length)
    }
}

/// The reference renderer for one scene (triangles binned once, materials converted once).
pub struct Reference<'a> {
    plan: &'a RenderPlan,
    geometry: &'a SceneGeometry,
    tris: Vec<Tri>,
    bins: Vec<Vec<u32>>,
    bin_origin: [f64; 2],
    bin_dims: [usize; 2],
    media: Vec<Medium>,
    mesh_material: Vec<usize>,
    /// Per light, how its shadow rays are drawn.
    lights: Vec<LightSource>,
    /// Per material, its phase function's asymmetry g (a point light's phase is per point).
    phase_g: Vec<f64>,
    step: f64,
    /// A perspective eye's rays, where the tracer works on its turned-round slab grid.
    eye: Option<TurnedEye<'a>>,
}

impl<'a> Reference<'a> {
    /// Prepares the reference for a scene whose geometry and plan are built. `step` is the
    /// marching step through detail media in world depth units (`0` = an eighth of a slab).
    pub fn new(
        scene: &Scene,
        geometry: &'a SceneGeometry,
        plan: &'a RenderPlan,
        step: f64,
    ) -> Reference<'a> {
        let cam = &geometry.camera;
        let mut tris = Vec::new();
        for (m, wm) in geometry.meshes.iter().enumerate() {
            let pts: Vec<[f64; 3]> = wm
                .mesh
                .positions
                .iter()
                .map(|p| {
                    let q = cam.to_grid(*p);
                    // Slab-grid coordinates (an orthographic camera's pixels, as the plan's
                    // detail affine takes them): a directional light's rays are straight lines
                    // of one slope in them, perspective or not.
                    [q.x, q.y, q.z - geometry.z_origin]
                })
                .collect();
            for t in &wm.mesh.triangles {
                let (a, b, c) = (pts[t[0] as usize], pts[t[1] as usize], pts[t[2] as usize]);
                tris.push(Tri {
                    v0: a,
                    e1: sub(b, a),
                    e2: sub(c, a),
                    mesh: m as u32,
                });
            }
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for t in &tris {
            for v in [t.v0, add(t.v0, t.e1), add(t.v0, t.e2)] {
                for a in 0..2 {
                    lo[a] = lo[a].min(v[a]);
                    hi[a] = hi[a].max(v[a]);
                }
            }
        }
        let dims = [
            (((hi[0] - lo[0]) / BIN).floor() as usize + 1).min(4096),
            (((hi[1] - lo[1]) / BIN).floor() as usize + 1).min(4096),
        ];
        let cell =
            |v: f64, a: usize| (((v - lo[a]) / BIN).floor().max(0.0) as usize).min(dims[a] - 1);
        let mut bins = vec![Vec::new(); dims[0] * dims[1]];
        for (i, t) in tris.iter().enumerate() {
            let vs = [t.v0, add(t.v0, t.e1), add(t.v0, t.e2)];
            let bx = vs
                .iter()
                .map(|v| v[0])
                .fold((f64::INFINITY, f64::NEG_INFINITY), |m, x| {
                    (m.0.min(x), m.1.max(x))
                });
            let by = vs
                .iter()
                .map(|v| v[1])
                .fold((f64::INFINITY, f64::NEG_INFINITY), |m, x| {
                    (m.0.min(x), m.1.max(x))
                });
            for cy in cell(by.0, 1)..=cell(by.1, 1) {
                for cx in cell(bx.0, 0)..=cell(bx.1, 0) {
                    bins[cy * dims[0] + cx].push(i as u32);
                }
            }
        }
        let e = geometry.slab_distance;
        let media = scene.materials.iter().map(Medium::new).collect();
        let px = cam.pixel_size;
        let lights = scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                if let Some(point) = &l.point {
                    let pattern = l
                        .pattern
                        .as_ref()
                        .zip(plan.spot_patterns.get(i).and_then(Option::as_ref));
                    return LightSource::Point(PointSource::new(
                        point,
                        pattern,
                        cam,
                        geometry.z_origin,
                    ));
                }
                let mu = l.tilt_deg.map(|t| t.to_radians().tan() / px);
                let (s, c) = l.rotation_deg.to_radians().sin_cos();
                let (sx, sy) = (l.variance[0].sqrt() / px, l.variance[1].sqrt() / px);
                // δ = R·(sx z1, sy z2), R = [[c, −s], [s, c]].
                LightSource::Directional(mu, [[c * sx, -s * sy], [s * sx, c * sy]])
            })
            .collect();
        Reference {
            plan,
            geometry,
            tris,
            bins,
            bin_origin: lo,
            bin_dims: dims,
            media,
            mesh_material: scene.meshes.iter().map(|m| m.material).collect(),
            lights,
            phase_g: scene.materials.iter().map(|m| m.phase_g).collect(),
            step: if step > 0.0 { step } else { e / 8.0 },
            eye: None,
        }
    }

    /// The reference on a turned-round slab grid (the geometry and plan given to
    /// [`Reference::new`]) seen by a perspective eye: the view LDI given to
    /// [`Reference::render`] is then the eye's, each pixel's fragments far to near at the grid's
    /// depths, and the image the eye's.
    pub fn with_turned_eye(mut self, eye: TurnedEye<'a>) -> Reference<'a> {
        self.eye = Some(eye);
        self
    }

    /// Candidate triangles whose bins the screen segment from `a` to `b` passes.
    fn candidates(&self, a: [f64; 2], b: [f64; 2], out: &mut Vec<u32>) {
        out.clear();
        let len = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()) / BIN)
            .ceil()
            .max(1.0) as usize;
        let cell = |v: f64, k: usize| -> i64 { ((v - self.bin_origin[k]) / BIN).floor() as i64 };
        let (mut last_x, mut last_y) = (i64::MIN, i64::MIN);
        for i in 0..len {
            // Piece i of the segment, at most one bin long per axis: its bounding box of bins.
            let t0 = i as f64 / len as f64;
            let t1 = (i + 1) as f64 / len as f64;
            let p0 = [a[0] + t0 * (b[0] - a[0]), a[1] + t0 * (b[1] - a[1])];
            let p1 = [a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1])];
            let (x0, x1) = (cell(p0[0].min(p1[0]), 0), cell(p0[0].max(p1[0]), 0));
            let (y0, y1) = (cell(p0[1].min(p1[1]), 1), cell(p0[1].max(p1[1]), 1));
            for cy in y0.max(0)..=y1.min(self.bin_dims[1] as i64 - 1) {
                for cx in x0.max(0)..=x1.min(self.bin_dims[0] as i64 - 1) {
                    if (cx, cy) == (last_x, last_y) {
                        continue;
                    }
                    last_x = cx;
                    last_y = cy;
                    out.extend_from_slice(&self.bins[cy as usize * self.bin_dims[0] + cx as usize]);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }

    /// The light arriving at `p` (grid px, relative depth) from light `l`, per channel: the mean
    /// transmittance over `k²` multi-jittered directions (see [`Reference::render`]); `stream`
    /// decorrelates the jitter. `p` is taken as exact: crossings within 2^-30 (relative) of it
    /// are ignored, so a point given on a surface is lit through that surface.
    pub fn light_at(&self, l: usize, p: [f64; 3], k: u32, seed: u32, stream: u32) -> [f64; 3] {
        let mut scratch = Scratch::default();
        self.light_at_with(l, p, Start::free(p), k, seed, stream, &mut scratch)
    }

    #[allow(clippy::too_many_arguments)]
    fn light_at_with(
        &self,
        l: usize,
        p: [f64; 3],
        start: Start,
        k: u32,
        seed: u32,
        stream: u32,
        scratch: &mut Scratch,
    ) -> [f64; 3] {
        let base = mix32(mix32(mix32(seed ^ k.wrapping_mul(0x2c1b_3c6d)) ^ stream) ^ l as u32);
        let (mu, f) = match &self.lights[l] {
            LightSource::Directional(mu, f) => (*mu, *f),
            LightSource::Point(light) => {
                return self.point_light_at(light, p, start, (k, base), scratch);
            }
        };
        let m = k * k;
        let mut acc = [0.0f64; 3];
        for a in 0..k {
            for b in 0..k {
                let ([z1, z2], _) = gaussian_pair(base, k, a, b);
                let dir = [
                    mu[0] + f[0][0] * z1 + f[0][1] * z2,
                    mu[1] + f[1][0] * z1 + f[1][1] * z2,
                ];
                let mut t = self.transmittance(p, [dir[0], dir[1], -1.0], p[2], start, scratch);
                if self.plan.initial_light.is_some() {
                    // A patterned light: the ray leaves the scene through the first slab plane
                    // (depth 0) at p + p.z·dir, where the pattern gives the light's value.
                    let i = self.initial_at(l, p[0] + p[2] * dir[0], p[1] + p[2] * dir[1]);
                    for (v, s) in t.iter_mut().zip(i) {
                        *v *= s;
                    }
                }
                for (a, v) in acc.iter_mut().zip(t) {
                    *a += v;
                }
            }
        }
        acc.map(|v| v / f64::from(m))
    }

    /// The exact surface point under the pixel centre (x, y) that the LDI's fragment of mesh
    /// `mesh` at f32 depth `z` stands for: among the mesh's triangles whose projection holds
    /// (x, y) (within 1e-9 in barycentric terms, so that a centre on a shared edge finds both),
    /// the one whose plane at (x, y) is nearest `z`, if within a slab thickness. Returns that
    /// depth, computed in f64 on the unsnapped triangle, and the triangle's index.
    fn surface_point(&self, mesh: u32, x: f64, y: f64, z: f64) -> Option<(f64, u32)> {
        if let Some(eye) = &self.eye {
            let (origin, dir) = eye.line(x, y);
            return self.surface_point_on_line(mesh, origin, dir, z);
        }
        if let Some(focal) = self.geometry.camera.focal_px {
            return self.surface_point_on_ray(mesh, x, y, z, focal);
        }
        let cell = |v: f64, a: usize| {
            (((v - self.bin_origin[a]) / BIN).floor().max(0.0) as usize).min(self.bin_dims[a] - 1)
        };
        let bin = &self.bins[cell(y, 1) * self.bin_dims[0] + cell(x, 0)];
        let mut best: Option<(f64, f64, u32)> = None;
        for &i in bin {
            let t = &self.tris[i as usize];
            if t.mesh != mesh {
                continue;
            }
            let det = t.e1[0] * t.e2[1] - t.e1[1] * t.e2[0];
            if det == 0.0 {
                continue; // edge-on to the view: no pixel centre's fragment
            }
            let (dx, dy) = (x - t.v0[0], y - t.v0[1]);
            let a = (dx * t.e2[1] - dy * t.e2[0]) / det;
            let b = (t.e1[0] * dy - t.e1[1] * dx) / det;
            const EPS: f64 = 1e-9;
            if a < -EPS || b < -EPS || a + b > 1.0 + EPS {
                continue;
            }
            let depth = t.v0[2] + a * t.e1[2] + b * t.e2[2];
            let off = (depth - z).abs();
            if best.is_none_or(|(o, _, _)| off < o) {
                best = Some((off, depth, i));
            }
        }
        best.filter(|&(off, _, _)| off <= self.geometry.slab_distance)
            .map(|(_, depth, i)| (depth, i))
    }

    /// [`Reference::surface_point`] for a perspective camera (focal length `focal` px): the
    /// view ray from the eye through pixel centre (x, y), intersected in f64 with the mesh's
    /// triangles near the slab-grid position it has within a slab of depth `z`; the hit nearest
    /// `z`, if within a slab thickness.
    fn surface_point_on_ray(
        &self,
        mesh: u32,
        x: f64,
        y: f64,
        z: f64,
        focal: f64,
    ) -> Option<(f64, u32)> {
        let cam = &self.geometry.camera;
        let (cx, cy) = (f64::from(cam.width) * 0.5, f64::from(cam.height) * 0.5);
        let s = focal * cam.pixel_size;
        // The eye sits at relative depth −z_origin on the view axis; the ray's depth grows by 1
        // per unit of its parameter.
        let origin = [cx, cy, -self.geometry.z_origin];
        let dir = [(x - cx) / s, (y - cy) / s, 1.0];
        self.surface_point_on_line(mesh, origin, dir, z)
    }

    /// The hit of the line `origin + t·dir` (`dir` of depth component 1) on mesh `mesh` nearest
    /// relative depth `z`, if within a slab thickness: its depth and triangle.
    fn surface_point_on_line(
        &self,
        mesh: u32,
        origin: [f64; 3],
        dir: [f64; 3],
        z: f64,
    ) -> Option<(f64, u32)> {
        let e = self.geometry.slab_distance;
        let at = |zr: f64| {
            let t = zr - origin[2];
            [origin[0] + dir[0] * t, origin[1] + dir[1] * t]
        };
        let mut candidates = Vec::new();
        self.candidates(at(z - e), at(z + e), &mut candidates);
        let mut best: Option<(f64, f64, u32)> = None;
        for i in candidates {
            let t = &self.tris[i as usize];
            if t.mesh != mesh {
                continue;
            }
            if let Some(param) = intersect(origin, dir, t) {
                let depth = origin[2] + param;
                let off = (depth - z).abs();
                if best.is_none_or(|(o, _, _)| off < o) {
                    best = Some((off, depth, i));
                }
            }
        }
        best.filter(|&(off, _, _)| off <= e)
            .map(|(_, depth, i)| (depth, i))
    }

    /// Where pixel centre (x, y)'s view ray is at relative depth `z`, in the tracer's slab-grid
    /// coordinates: (x, y) for an orthographic camera (`Camera::pixel_to_grid`).
    fn view_point(&self, x: f64, y: f64, z: f64) -> [f64; 3] {
        if let Some(eye) = &self.eye {
            return eye.point(x, y, z);
        }
        let g = self.geometry;
        let (gx, gy) = g.camera.pixel_to_grid(x, y, g.z_origin + z);
        [gx, gy, z]
    }

    /// Light `l`'s initial light (its pattern) at image position (x, y) in pixels (the ray
    /// positions' frame; the grid starts `guard.left`, `guard.top` pixels before it), per
    /// channel: bilinear between pixel centres, 1 outside the grid (as the sweep reads it).
    fn initial_at(&self, l: usize, x: f64, y: f64) -> [f64; 3] {
        let plan = self.plan;
        let Some(buf) = &plan.initial_light else {
            return [1.0; 3];
        };
        let (x, y) = (
            x + f64::from(plan.guard.left),
            y + f64::from(plan.guard.top),
        );
        let (w, h) = (plan.grid_width as i64, plan.grid_height as i64);
        let ch = plan.channels as usize;
        let row_len = plan.light_row_len();
        let (fx, fy) = (x - 0.5, y - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (ax, ay) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut out = [1.0f64; 3];
        for (c, o) in out.iter_mut().enumerate().take(ch) {
            let at = |xi: i64, yi: i64| {
                if xi < 0 || yi < 0 || xi >= w || yi >= h {
                    1.0
                } else {
                    let plane = plan.light_plane(l, c);
                    f64::from(buf[yi as usize * row_len + plane * w as usize + xi as usize])
                }
            };
            let top = at(x0, y0) * (1.0 - ax) + at(x0 + 1, y0) * ax;
            let bottom = at(x0, y0 + 1) * (1.0 - ax) + at(x0 + 1, y0 + 1) * ax;
            *o = top * (1.0 - ay) + bottom * ay;
        }
        if ch == 1 {
            out = [out[0]; 3];
        }
        out
    }

    /// Renders the image (linear RGB, `width·height·3`) with the sweep's view samples and
    /// reference light (see the module documentation).
    pub fn render(&self, ldi: &Ldi, options: &ReferenceOptions) -> Vec<f32> {
        self.render_with_alpha(ldi, options).0
    }

    /// [`Reference::render`]'s image and its composited alpha per pixel (`width·height`): the
    /// reference's own front-to-back `A += (1 − A)·α_slab` before the background is added (its
    /// view samples stop once `1 − A` is below its transparency cutoff, so a pixel that is opaque
    /// on the sweep may keep an alpha a little under 1 here).
    pub fn render_with_alpha(&self, ldi: &Ldi, options: &ReferenceOptions) -> (Vec<f32>, Vec<f32>) {
        let plan = self.plan;
        let k = samples_side(options.samples);
        // The image and where its pixels sit in the view LDI (the grid's, or a turned eye's own).
        let (iw, ih, left, top, w) = match &self.eye {
            Some(eye) => (
                eye.width as usize,
                eye.height as usize,
                0,
                0,
                eye.width as usize,
            ),
            None => (
                plan.width as usize,
                plan.height as usize,
                plan.guard.left as usize,
                plan.guard.top as usize,
                plan.grid_width as usize,
            ),
        };
        // Hashes are keyed by image pixel (`RenderPlan::hash_x`), as in the sweep.
        let (hash_left, hash_top) = (plan.guard.left as usize, plan.guard.top as usize);
        let normals = self.eye.map_or(&self.geometry.raster, |eye| eye.raster);
        let ch = plan.channels as usize;
        let lights = plan.lights.len();
        let mut image = vec![0.0f32; iw * ih * 3];
        let mut image_alpha = vec![0.0f32; iw * ih];
        image
            .par_chunks_mut(iw * 3)
            .zip(image_alpha.par_chunks_mut(iw))
            .enumerate()
            .for_each(|(iy, (row, row_alpha))| {
                let mut scratch = Scratch::default();
                let y = iy + top;
                for ix in 0..iw {
                    let x = ix + left;
                    let p = y * w + x;
                    let mut next = ldi.offsets[p];
                    let end = ldi.offsets[p + 1];
                    let mut inside = 0u32;
                    let mut color = [0.0f32; 3];
                    let mut alpha = 0.0f32;
                    let mut iin = [0.0f32; 48];
                    for slab in 0..plan.slabs {
                        let back = plan.slab_back[slab as usize];
                        let front = plan.slab_front[slab as usize];
                        let before = inside;
                        let crossed = advance(ldi, &mut next, end, &mut inside, back);
                        let mesh = if crossed != NO_CROSSING {
                            Some(u32::from(ldi.mesh[crossed as usize]))
                        } else {
                            first_mesh(inside)
                        };
                        let Some(mesh) = mesh else { continue };
                        if !plan.turned_round && 1.0 - alpha < TRANSPARENCY_CUTOFF {
                            break;
                        }
                        let jitter_row = row_hash(
                            plan.jitter_slab_hash[slab as usize],
                            plan.hash_y((iy + hash_top) as u32),
                        );
                        let z =
                            shading_depth(plan, ldi, crossed, front, jitter_row, ix + hash_left);
                        let (cx, cy) = (ix as f64 + 0.5, iy as f64 + 0.5);
                        // The detail where the view ray is (the plan's slab-grid pixel, whose
                        // centre is +0.5: `detail_at`); an orthographic camera's own pixel.
                        let (dx, dy) =
                            if self.geometry.camera.focal_px.is_some() || self.eye.is_some() {
                                let [gx, gy, _] = self.view_point(cx, cy, f64::from(z));
                                ((gx - 0.5) as f32, (gy - 0.5) as f32)
                            } else {
                                (ix as f32, iy as f32)
                            };
                        let mut tf = material_at(plan, mesh, dx, dy, z);
                        // The sweep's view samples: a medium's entry and exit slabs by the part
                        // inside (the light needs no such factor: it is traced).
                        let (part, lit_from) = slab_part(
                            ldi,
                            (mesh, plan.second_order_media),
                            (before, inside),
                            (crossed, next.wrapping_sub(1)),
                            (front, back),
                            plan.inv_slab_distance,
                        );
                        // With second-order media the sweep lights a medium's sample at the
                        // middle of the slab's part inside it (`slab_part`): inside a medium, the
                        // light is traced to there, not to the jittered point.
                        let light_z = if plan.second_order_media && tf.alpha < 1.0 {
                            f64::from(front) + f64::from(lit_from) * f64::from(plan.slab_distance)
                        } else {
                            f64::from(z)
                        };
                        part_of_slab(&mut tf, part, 0.0);
                        let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
                        // A crossing's shadow rays start on the exact surface and do not cross
                        // it (see `Start`); a point inside a medium starts where it is.
                        let (pos, start) = if crossed == NO_CROSSING {
                            let pos = self.view_point(cx, cy, light_z);
                            (pos, Start::free(pos))
                        } else {
                            match self.surface_point(mesh, cx, cy, f64::from(z)) {
                                Some((depth, tri)) => {
                                    let pos = self.view_point(cx, cy, depth);
                                    (pos, Start::on(pos, tri))
                                }
                                None => {
                                    let pos = self.view_point(cx, cy, f64::from(z));
                                    (pos, Start::near(pos))
                                }
                            }
                        };
                        let stream = mix32(mix32(p as u32) ^ slab);
                        for l in 0..lights {
                            let t = self.light_at_with(
                                l,
                                pos,
                                start,
                                k,
                                options.seed,
                                stream,
                                &mut scratch,
                            );
                            for (dst, v) in iin[l * ch..(l + 1) * ch].iter_mut().zip(t) {
                                *dst = v as f32;
                            }
                        }
                        // The sweep's surface model: highlight and Lambert cosine at a
                        // crossing, with the crossed triangle's normal.
                        let has_surface = material.specular.is_some() || material.lambert;
                        let surface = (crossed != NO_CROSSING && has_surface).then(|| Surface {
                            normal: normals.triangles[ldi.triangle[crossed as usize] as usize]
                                .normal,
                            lanes: true,
                            alpha: tf.alpha,
                        });
                        let iin = &iin[..lights * ch];
                        // A point light's shading terms are those of the direction to it from
                        // this sample (found once per sample, read by the diffuse and specular
                        // sums); a directional light's are the plan's.
                        let g = self.phase_g[self.mesh_material[mesh as usize]];
                        scratch.terms.clear();
                        scratch
                            .terms
                            .extend(self.lights.iter().enumerate().map(
                                |(l, source)| match source {
                                    LightSource::Point(light) => {
                                        light.terms(pos, plan.lights[l].color, g)
                                    }
                                    LightSource::Directional(..) => {
                                        LightTerms::of(plan, material, l)
                                    }
                                },
                            ));
                        let terms = &scratch.terms;
                        let shaded = shade_with(
                            ch,
                            lights,
                            |l| terms[l],
                            material,
                            tf.color,
                            iin,
                            surface.as_ref(),
                            // No horizon: the shadow rays find the body below the tangent
                            // plane themselves.
                            &[],
                        );
                        composite(
                            &mut color,
                            &mut alpha,
                            shaded,
                            tf.alpha,
                            true,
                            plan.turned_round,
                        );
                    }
                    finish(&mut color, alpha, plan.background);
                    row[3 * ix..3 * ix + 3].copy_from_slice(&color);
                    row_alpha[ix] = alpha;
                }
            });
        (image, image_alpha)
    }
}

/// Per-thread scratch buffers.
#[derive(Default)]
struct Scratch {
    tris: Vec<u32>,
    hits: Vec<(f64, u32)>,
    /// The shading's terms of each light at the current sample.
    terms: Vec<LightTerms>,
}
