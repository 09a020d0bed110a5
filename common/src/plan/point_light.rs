//! Point and spot lights as the shading sees them (`[[light]] kind = "point" | "spot"`,
//! docs/how-it-works.md "Point and spot lights"): where the light's centre is on a slab grid, the
//! factor its centre gives the light arriving at a point (`cone·pattern / |X − P|²`) and the
//! shading's terms of the direction to it — one implementation for the shadow-ray reference and
//! the sweep's eye pass.

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
        }
    }
}

/// A point or spot light where a slab grid sees it (slab-grid coordinates: x, y in grid pixels,
/// z in world depth relative to the first slab plane): the shadow-ray reference's tracer and the
/// eye pass of the sweep's point lights.
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
        LightTerms {
            light_color,
            color,
            to_light: f32x3(to_light),
            half_vector: f32x3(h),
            fresnel: fresnel_terms(h, to_light),
        }
    }
}
