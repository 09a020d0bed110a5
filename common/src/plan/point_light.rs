//! Point and spot lights as the shading sees them (`[[light]] kind = "point" | "spot"`,
//! docs/how-it-works.md "Point and spot lights"): where the light's centre is on a slab grid, the
//! factor its centre gives the light arriving at a point (`cone·pattern / |X − P|²`) and the
//! shading's terms of the direction to it: in f64 for the shadow-ray reference ([`PointSource`]),
//! in f32 with a fixed operation order for the sweep's eye pass on the CPU and the GPU
//! ([`PointShading`], built from the same [`PointSource`]).

use std::sync::Arc;

use glam::DVec3;

use crate::model::scene::{PatternSpec, PointLight, SpotCone, frame};
use crate::plan::material::MaterialPlan;
use crate::plan::pattern::Pattern;
use crate::plan::{RenderPlan, fresnel_terms, henyey_greenstein};
use crate::prepare::camera::Camera;

/// What the shading takes of light `l` at a shading point: for a directional light its plan's
/// constants (`convshadow_cpu::shading::shade`); for a point light, those of the direction to
/// it from the point (the shadow-ray reference and the sweep's eye pass).
#[derive(Clone, Copy, Debug)]
pub struct LightTerms {
    /// The light's colour times the material's phase function (`MaterialPlan::light_color`).
    pub light_color: [f32; 3],
    /// The bare colour, for the specular term.
    pub color: [f32; 3],
    /// Unit direction towards the light, as `LightPlan::to_light`.
    pub to_light: [f32; 3],
    /// Blinn–Phong half vector, as `LightPlan::half_vector`.
    pub half_vector: [f32; 3],
    /// Ashikmin–Shirley's Fresnel constants, as `LightPlan::fresnel`.
    pub fresnel: [f32; 2],
    /// The light's spread as the horizon reads it, as `LightPlan::spread` (a point light:
    /// `[0, 0, 0, radius²/|X − P|²]`).
    pub spread: [f32; 4],
    /// The light's buffer holds the visible part of it, as `LightPlan::plain` (every point
    /// light's: its cone and pattern are in its colour).
    pub plain: bool,
}

impl LightTerms {
    /// The plan's terms of directional light `l` for `material`.
    #[inline(always)]
    pub fn of(plan: &RenderPlan, material: &MaterialPlan, l: usize) -> LightTerms {
        let light = &plan.lights[l];
        LightTerms {
            light_color: material.light_color[l],
            color: light.color,
            to_light: light.to_light,
            half_vector: light.half_vector,
            fresnel: light.fresnel,
            spread: light.spread,
            plain: light.plain,
        }
    }
}

/// A point or spot light where a slab grid sees it (slab-grid coordinates: x, y in grid pixels,
/// z in world depth relative to the first slab plane): the shadow-ray reference's tracer, and
/// what the sweep's f32 [`PointShading`] is made from.
#[derive(Clone, Debug)]
pub struct PointSource {
    /// The light's centre, grid coordinates.
    pub center: [f64; 3],
    /// The light's standard deviation per grid axis: `radius / pixel_size` across, `radius` in
    /// depth.
    pub sigma: [f64; 3],
    /// World units per grid pixel across the view.
    pixel_size: f64,
    /// The spot's cone with its axis in camera space (x right, y down, z along the view).
    spot: Option<SpotCone>,
    /// A spot's pattern and where it lies on the plane at unit distance along the axis.
    pattern: Option<SpotPattern>,
}

/// A spot light's pattern (gobo): the image on the plane at unit distance along the spot's axis,
/// in the spot's own frame, `size` and `center` in units of that plane (tangents of the angle
/// from the axis).
#[derive(Clone, Debug)]
struct SpotPattern {
    /// The spot's own right and down axes, camera space.
    right: DVec3,
    /// See `right`.
    down: DVec3,
    /// The image's extent on the unit plane.
    size: [f64; 2],
    /// The image's centre on the unit plane, along right and down.
    center: [f64; 2],
    /// The image.
    image: Arc<Pattern>,
}

impl PointSource {
    /// `light` (with its pattern's placement `spec` and image, a spot's) seen by `camera`,
    /// with grid depths relative to `z_origin`.
    pub fn new(
        light: &PointLight,
        pattern: Option<(&PatternSpec, &Arc<Pattern>)>,
        camera: &Camera,
        z_origin: f64,
    ) -> PointSource {
        let c = camera.to_grid(DVec3::from(light.position));
        let px = camera.pixel_size;
        let to_camera = |d: DVec3| {
            DVec3::new(
                d.dot(camera.right),
                d.dot(camera.down),
                d.dot(camera.forward),
            )
        };
        let spot = light.spot.map(|s| SpotCone {
            direction: to_camera(DVec3::from(s.direction)).to_array(),
            ..s
        });
        let pattern = light.spot.zip(pattern).map(|(s, (spec, image))| {
            let [right, down, _] = frame(DVec3::from(s.direction), DVec3::from(s.up));
            SpotPattern {
                right: to_camera(right),
                down: to_camera(down),
                size: spec.size,
                center: spec.center,
                image: Arc::clone(image),
            }
        });
        PointSource {
            center: [c.x, c.y, c.z - z_origin],
            sigma: [light.radius / px, light.radius / px, light.radius],
            pixel_size: px,
            spot,
            pattern,
        }
    }

    /// World units per grid pixel across the view.
    pub fn pixel_size(&self) -> f64 {
        self.pixel_size
    }

    /// The camera-space world vector from grid point `p` to the light's centre.
    pub fn toward_center(&self, p: [f64; 3]) -> DVec3 {
        let d = [0, 1, 2].map(|i| self.center[i] - p[i]);
        DVec3::new(d[0] * self.pixel_size, d[1] * self.pixel_size, d[2])
    }

    /// The factor the light's centre gives the light arriving at `p`, per channel: the cone
    /// (1 for a point light) times a spot's pattern over the squared distance,
    /// `cone(X − P)·pattern(X − P) / |X − P|²` (0 at the centre itself).
    pub fn falloff(&self, p: [f64; 3]) -> [f64; 3] {
        let d = self.toward_center(p);
        let d2 = d.length_squared();
        if d2 == 0.0 {
            return [0.0; 3];
        }
        let cone = self.spot.map_or(1.0, |s| s.factor(-d)) / d2;
        let Some(pattern) = &self.pattern else {
            return [cone; 3];
        };
        // Where the ray from the centre through X meets the unit plane along the axis: none at
        // 90° or more from the axis.
        let out = -d;
        let along = out.dot(DVec3::from(
            self.spot.map_or([0.0, 0.0, 1.0], |s| s.direction),
        ));
        if along <= 0.0 {
            return [0.0; 3];
        }
        let (a, b) = (
            out.dot(pattern.right) / along,
            out.dot(pattern.down) / along,
        );
        let img = &pattern.image;
        let tx = ((a - pattern.center[0]) / pattern.size[0] + 0.5) * f64::from(img.width);
        let ty = ((b - pattern.center[1]) / pattern.size[1] + 0.5) * f64::from(img.height);
        std::array::from_fn(|c| cone * img.sample(tx, ty, c))
    }

    /// The shading's terms of this light at grid point `p` (a front-to-back pass: the viewer
    /// along −z): the direction to the centre, its half vector with the view, the Fresnel
    /// constants, and the colour times the phase function `g` for the angle between the light's
    /// travel and the view (the bare colour where g = 0, as the plan's).
    pub fn terms(&self, p: [f64; 3], color: [f32; 3], g: f64) -> LightTerms {
        let d = self.toward_center(p);
        let to_light = if d.length_squared() > 0.0 {
            d.normalize()
        } else {
            DVec3::NEG_Z
        };
        let h = (to_light + DVec3::NEG_Z).normalize_or(DVec3::NEG_Z);
        let f32x3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        // cos θ between the travel (−to_light) and the direction to the viewer (−z).
        let phase = henyey_greenstein(g, to_light.z);
        let light_color = if g == 0.0 {
            color
        } else {
            color.map(|c| (f64::from(c) * phase) as f32)
        };
        let d2 = d.length_squared();
        let iso = if d2 > 0.0 {
            self.sigma[2] * self.sigma[2] / d2
        } else {
            0.0
        };
        LightTerms {
            light_color,
            color,
            to_light: f32x3(to_light),
            half_vector: f32x3(h),
            fresnel: fresnel_terms(h, to_light),
            spread: [0.0, 0.0, 0.0, iso as f32],
            plain: true,
        }
    }
}

/// A point or spot light's shading constants in f32 for the sweep's eye pass: the direction to
/// its centre, its falloff, cone and pattern at each eye sample, evaluated by
/// [`PointShading::terms`] — which `gpu/src/shaders/eye.wgsl` `point_terms` mirrors operation
/// for operation, so the CPU and the GPU port shade a point light with the same bits. (The
/// shadow-ray reference evaluates the same model in f64: [`PointSource`].)
#[derive(Clone, Debug)]
pub struct PointShading {
    /// The light's centre, the eye's slab-grid coordinates (x, y grid pixels, z relative depth).
    pub center: [f32; 3],
    /// World units per grid pixel across the view.
    pub pixel_size: f32,
    /// The light's colour.
    pub color: [f32; 3],
    /// A spot's cone: its axis (camera space) and the cosines of its half-angle and outer edge.
    pub cone: Option<ConeCosines>,
    /// A spot's pattern (gobo), placed as [`PointSource`]'s.
    pub pattern: Option<PatternPlacement>,
    /// A turned-round pass (a light behind every mesh): the frame is the turned camera's, the
    /// viewer towards its +z, and the shading's direction to the light and half vector are
    /// negated as a turned pass's `LightPlan` has them (the shading faces normals towards −z).
    pub turned: bool,
    /// The light's radius squared (world units²): its spread for the horizon, over |X − P|².
    pub radius2: f32,
}

/// A spot's cone in f32 ([`SpotCone::factor`]'s smoothstep in the cosine).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeCosines {
    /// The unit axis, camera space (x right, y down, z along the view).
    pub axis: [f32; 3],
    /// cos(`cone_deg`): full intensity at or above it.
    pub inner: f32,
    /// cos(`cone_deg + falloff_deg`): nothing at or below it.
    pub outer: f32,
}

/// A spot's pattern in f32: its image on the plane at unit distance along the axis, the spot's
/// right and down axes (camera space), the image's size and centre on that plane.
#[derive(Clone, Debug)]
pub struct PatternPlacement {
    /// The spot's right axis, camera space.
    pub right: [f32; 3],
    /// The spot's down axis, camera space.
    pub down: [f32; 3],
    /// The image's extent on the unit plane.
    pub size: [f32; 2],
    /// The image's centre on the unit plane.
    pub center: [f32; 2],
    /// The image.
    pub image: Arc<Pattern>,
}

/// A medium's Henyey–Greenstein constants in f32, `[1 − g², 1 + g², 2g]` (`2g` = 0: isotropic,
/// the bare colour): the phase for `cos θ` is `(1 − g²) / (x·√x)`, `x = 1 + g² − 2g·cos θ`.
pub fn phase_constants(g: f64) -> [f32; 3] {
    [(1.0 - g * g) as f32, (1.0 + g * g) as f32, (2.0 * g) as f32]
}

impl PointShading {
    /// The f32 constants of `source` (the same light, the same frame) with colour `color`, in
    /// a turned-round pass where `turned`.
    pub fn new(source: &PointSource, color: [f32; 3], turned: bool) -> PointShading {
        let f32x3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        PointShading {
            center: source.center.map(|c| c as f32),
            pixel_size: source.pixel_size as f32,
            color,
            cone: source.spot.map(|s| {
                let [inner, outer] = s.cosines();
                ConeCosines {
                    axis: s.direction.map(|c| c as f32),
                    inner: inner as f32,
                    outer: outer as f32,
                }
            }),
            pattern: source.pattern.as_ref().map(|p| PatternPlacement {
                right: f32x3(p.right),
                down: f32x3(p.down),
                size: p.size.map(|c| c as f32),
                center: p.center.map(|c| c as f32),
                image: Arc::clone(&p.image),
            }),
            turned,
            radius2: (source.sigma[2] * source.sigma[2]) as f32,
        }
    }

    /// The shading's terms of this light at grid point `p` for a medium of
    /// [`phase_constants`] `phase`, with both colours times the light its centre gives there
    /// (`cone·pattern / |X − P|²`; 0 at the centre itself). Every operation in f32 in a fixed
    /// order, no fused multiply-add (DESIGN §3): eye.wgsl's `point_terms` is the same.
    pub fn terms(&self, p: [f32; 3], phase: [f32; 3]) -> LightTerms {
        let ps = self.pixel_size;
        let d = [
            (self.center[0] - p[0]) * ps,
            (self.center[1] - p[1]) * ps,
            self.center[2] - p[2],
        ];
        let d2 = (d[0] * d[0] + d[1] * d[1]) + d[2] * d[2];
        // The direction to the viewer is (0, 0, view_z).
        let view_z = if self.turned { 1.0 } else { -1.0 };
        // The horizon's spread: the light's variance over the squared distance, towards it.
        let iso = if d2 > 0.0 { self.radius2 / d2 } else { 0.0 };
        let (to_light, falloff) = if d2 > 0.0 {
            let len = d2.sqrt();
            let t = [d[0] / len, d[1] / len, d[2] / len];
            let cone = self.cone.map_or(1.0, |c| cone_factor(&c, t));
            let pattern = self
                .pattern
                .as_ref()
                .map(|pt| pattern_at(pt, &self.cone, d));
            let falloff: [f32; 3] =
                std::array::from_fn(|c| pattern.map_or(cone, |v| cone * v[c]) / d2);
            (t, falloff)
        } else {
            ([0.0, 0.0, view_z], [0.0; 3])
        };
        let t = to_light;
        let hv = [t[0], t[1], t[2] + view_z];
        let hl2 = (hv[0] * hv[0] + hv[1] * hv[1]) + hv[2] * hv[2];
        let h = if hl2 > 0.0 {
            let len = hl2.sqrt();
            [hv[0] / len, hv[1] / len, hv[2] / len]
        } else {
            [0.0, 0.0, view_z]
        };
        let hk = (h[0] * t[0] + h[1] * t[1]) + h[2] * t[2];
        let q = 1.0 - hk;
        let q2 = q * q;
        let fresnel_p = (q2 * q2) * q;
        // cos θ between the travel (−to_light) and the direction to the viewer: ∓t.z.
        let cos = if self.turned { -t[2] } else { t[2] };
        let light_color = if phase[2] == 0.0 {
            self.color
        } else {
            let x = phase[1] - phase[2] * cos;
            let factor = phase[0] / (x * x.sqrt());
            self.color.map(|c| c * factor)
        };
        LightTerms {
            light_color: std::array::from_fn(|c| light_color[c] * falloff[c]),
            color: std::array::from_fn(|c| self.color[c] * falloff[c]),
            to_light: if self.turned { t.map(|v| -v) } else { t },
            half_vector: if self.turned { h.map(|v| -v) } else { h },
            fresnel: [fresnel_p / hk, (1.0 - fresnel_p) / hk],
            spread: [0.0, 0.0, 0.0, iso],
            plain: true,
        }
    }
}

/// [`SpotCone::factor`] in f32 for unit direction `t` towards the light (the emission is −t).
fn cone_factor(c: &ConeCosines, t: [f32; 3]) -> f32 {
    let cos = 0.0 - ((t[0] * c.axis[0] + t[1] * c.axis[1]) + t[2] * c.axis[2]);
    if cos >= c.inner {
        1.0
    } else if cos > c.outer {
        let s = (cos - c.outer) / (c.inner - c.outer);
        s * s * (3.0 - 2.0 * s)
    } else {
        0.0
    }
}

/// A spot pattern's value per channel for emission along `−d` (`d` towards the light): where
/// the ray from the centre meets the unit plane along the axis, bilinear; 0 at 90° or more.
fn pattern_at(p: &PatternPlacement, cone: &Option<ConeCosines>, d: [f32; 3]) -> [f32; 3] {
    let out = [0.0 - d[0], 0.0 - d[1], 0.0 - d[2]];
    let dot = |a: [f32; 3], b: [f32; 3]| (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
    let along = dot(out, cone.map_or([0.0, 0.0, 1.0], |c| c.axis));
    if along.is_nan() || along <= 0.0 {
        return [0.0; 3];
    }
    let a = dot(out, p.right) / along;
    let b = dot(out, p.down) / along;
    let img = &p.image;
    let tx = ((a - p.center[0]) / p.size[0] + 0.5) * img.width as f32;
    let ty = ((b - p.center[1]) / p.size[1] + 0.5) * img.height as f32;
    std::array::from_fn(|c| img.sample_f32(tx, ty, c))
}
