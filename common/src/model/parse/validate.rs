//! Validation: the raw form into the model, every value checked against its documented range.

use std::path::Path;

use super::*;
use crate::model::kernel::KernelSpec;

pub(super) struct Validator<'a> {
    /// The scene file, for messages.
    pub(super) file: &'a str,
}

impl Validator<'_> {
    pub(super) fn err(&self, key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            key: key.into(),
            message: message.into(),
        }
    }

    pub(super) fn finite(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(key, format!("expected a finite number, got {v}")))
        }
    }

    fn finite3(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        for (i, c) in v.iter().enumerate() {
            self.finite(&format!("{key}[{i}]"), *c)?;
        }
        Ok(v)
    }

    fn positive(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(key, format!("expected a number > 0, got {v}")))
        }
    }

    /// A finite number with |v| <= `max`.
    fn bounded(&self, key: &str, v: f64, max: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v.abs() <= max {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("expected a number from -{max:e} to {max:e}, got {v:e}"),
            ))
        }
    }

    /// Three numbers, each with |v| <= `max`.
    pub(super) fn bounded3(
        &self,
        key: &str,
        v: [f64; 3],
        max: f64,
    ) -> Result<[f64; 3], SceneError> {
        for (i, c) in v.iter().enumerate() {
            self.bounded(&format!("{key}[{i}]"), *c, max)?;
        }
        Ok(v)
    }

    /// A positive world-space length in [`MIN_WORLD`, `MAX_WORLD`].
    pub(super) fn length(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.positive(key, v)?;
        self.in_range(key, v, MIN_WORLD, MAX_WORLD)
    }

    /// A positive number in [`lo`, `hi`], the message giving the range.
    fn in_range(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("expected a number from {lo:e} to {hi:e}, got {v:e}"),
            ))
        }
    }

    fn unit_interval(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if (0.0..=1.0).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(key, format!("expected a number in [0, 1], got {v}")))
        }
    }

    fn color(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        self.finite3(key, v)?;
        for (i, c) in v.iter().enumerate() {
            if *c < 0.0 {
                return Err(self.err(
                    format!("{key}[{i}]"),
                    format!("expected a colour component >= 0, got {c}"),
                ));
            }
            if *c > MAX_COLOR {
                return Err(self.err(
                    format!("{key}[{i}]"),
                    format!("expected a colour component from 0 to {MAX_COLOR:e}, got {c:e}"),
                ));
            }
        }
        Ok(v)
    }

    /// One colour component in [0, [`MAX_COLOR`]], the key naming its exact index.
    fn color_component(&self, key: &str, c: f64) -> Result<f64, SceneError> {
        self.finite(key, c)?;
        if (0.0..=MAX_COLOR).contains(&c) {
            Ok(c)
        } else {
            Err(self.err(
                key,
                format!("expected a colour component from 0 to {MAX_COLOR:e}, got {c:e}"),
            ))
        }
    }

    pub(super) fn unit_vector(&self, key: &str, v: [f64; 3]) -> Result<[f64; 3], SceneError> {
        self.finite3(key, v)?;
        // Divided by the largest component first, so that 1e308 or 1e-300 do not overflow.
        let big = v[0].abs().max(v[1].abs()).max(v[2].abs());
        if big == 0.0 {
            return Err(self.err(key, "expected a non-zero direction vector, got [0, 0, 0]"));
        }
        let v = v.map(|c| c / big);
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        Ok([v[0] / len, v[1] / len, v[2] / len])
    }

    pub(super) fn image_size(&self, width: u32, height: u32) -> Result<(), SceneError> {
        for (key, v) in [("image.width", width), ("image.height", height)] {
            if v == 0 || v > MAX_IMAGE_SIDE {
                return Err(self.err(
                    key,
                    format!("expected an integer from 1 to {MAX_IMAGE_SIDE}, got {v}"),
                ));
            }
        }
        Ok(())
    }

    pub(super) fn exposure(&self, stops: f64) -> Result<f64, SceneError> {
        let stops = self.finite("image.exposure", stops)?;
        if stops.abs() > MAX_EXPOSURE_STOPS {
            return Err(self.err(
                "image.exposure",
                format!(
                    "expected stops in [-{MAX_EXPOSURE_STOPS}, {MAX_EXPOSURE_STOPS}], got {stops}"
                ),
            ));
        }
        Ok(stops)
    }

    pub(super) fn slab_count(&self, n: u32) -> Result<(), SceneError> {
        if n == 0 || n > MAX_SLABS {
            return Err(self.err(
                "sweep.slabs",
                format!("expected an integer from 1 to {MAX_SLABS}, got {n}"),
            ));
        }
        Ok(())
    }

    pub(super) fn scene(&self, raw: RawScene, base_dir: &Path) -> Result<Scene, SceneError> {
        self.image_size(raw.image.width, raw.image.height)?;
        let background =
            self.color("image.background", raw.image.background.unwrap_or([0.0; 3]))?;
        let image = ImageSpec {
            width: raw.image.width,
            height: raw.image.height,
            background: background.map(|c| c as f32),
            exposure: self.exposure(raw.image.exposure.unwrap_or(0.0))?,
            tonemap: raw.image.tonemap.unwrap_or_default(),
        };

        let aspect = f64::from(image.width) / f64::from(image.height);
        let camera = self.camera(&raw.camera, aspect)?;

        let sweep = self.sweep(raw.sweep)?;
        self.light_resolution(sweep.light_resolution)?;

        if raw.light.len() > MAX_LIGHTS {
            return Err(self.err(
                "light",
                format!(
                    "expected at most {MAX_LIGHTS} lights, got {}",
                    raw.light.len()
                ),
            ));
        }
        let mut lights = Vec::new();
        for (i, l) in raw.light.into_iter().enumerate() {
            lights.push(self.light(i, l, base_dir, &camera)?);
        }
        if lights.is_empty() {
            lights.push(LightSpec {
                color: [1.0; 3],
                tilt_deg: [0.0; 2],
                world: None,
                variance: [0.0; 2],
                rotation_deg: 0.0,
                pattern: None,
                toward_viewer: false,
                point: None,
            });
        }

        let names: Vec<String> = raw.material.keys().cloned().collect();
        let mut materials = Vec::new();
        for (name, m) in raw.material {
            materials.push(self.material(&name, m, base_dir)?);
        }

        if raw.mesh.is_empty() {
            return Err(self.err("mesh", "expected at least one [[mesh]]"));
        }
        if raw.mesh.len() > MAX_MESHES {
            return Err(self.err(
                "mesh",
                format!(
                    "expected at most {MAX_MESHES} meshes, got {}",
                    raw.mesh.len()
                ),
            ));
        }
        let mut meshes = Vec::new();
        for (i, m) in raw.mesh.into_iter().enumerate() {
            meshes.push(self.mesh(i, m, &names, base_dir)?);
        }

        Ok(Scene {
            source: self.file.to_string(),
            base_dir: base_dir.to_path_buf(),
            image,
            camera,
            sweep,
            lights,
            meshes,
            materials,
            turned_round: false,
        })
    }

    fn sweep(&self, raw: RawSweep) -> Result<SweepSpec, SceneError> {
        let slabs = match (raw.slabs, raw.slab_distance) {
            (Some(_), Some(_)) => {
                return Err(self.err(
                    "sweep.slabs",
                    "expected only one of `slabs` and `slab_distance`, got both",
                ));
            }
            (None, None) => {
                return Err(self.err(
                    "sweep.slabs",
                    "expected one of `slabs` (a count) or `slab_distance` (world units)",
                ));
            }
            (Some(RawSlabs::Count(n)), None) => match u32::try_from(n) {
                Ok(n) if (1..=MAX_SLABS).contains(&n) => SlabSpec::Count(n),
                _ => {
                    return Err(self.err(
                        "sweep.slabs",
                        format!("expected an integer from 1 to {MAX_SLABS} or \"auto\", got {n}"),
                    ));
                }
            },
            (Some(RawSlabs::Word(w)), None) => {
                if w != "auto" {
                    return Err(self.err(
                        "sweep.slabs",
                        format!("expected an integer from 1 to {MAX_SLABS} or \"auto\", got {w:?}"),
                    ));
                }
                SlabSpec::Auto
            }
            (None, Some(d)) => SlabSpec::Distance(self.length("sweep.slab_distance", d)?),
        };
        if let Some(f) = raw.slab_factor {
            if slabs != SlabSpec::Auto {
                return Err(self.err(
                    "sweep.slab_factor",
                    "`slab_factor` modulates `slabs = \"auto\"` only; remove it or set \
                     `slabs = \"auto\"`",
                ));
            }
            let (lo, hi) = SLAB_FACTOR_RANGE;
            self.in_range("sweep.slab_factor", f, lo, hi)?;
        }
        let kernel_text = raw.kernel.unwrap_or_else(|| "ellipse2".to_string());
        let kernel = kernel_text
            .parse::<KernelSpec>()
            .map_err(|e| self.err("sweep.kernel", e))?;
        let guard_band = match raw.guard_band {
            None => GuardBandSpec::Auto,
            Some(toml::Value::String(s)) if s == "auto" => GuardBandSpec::Auto,
            Some(toml::Value::Integer(g)) if (0..=i64::from(MAX_GUARD_BAND)).contains(&g) => {
                GuardBandSpec::Pixels(g as u32)
            }
            Some(other) => {
                return Err(self.err(
                    "sweep.guard_band",
                    format!(
                        "expected \"auto\" or a pixel count 0 to {MAX_GUARD_BAND}, got {other}"
                    ),
                ));
            }
        };
        let penumbra = match raw.penumbra.as_deref() {
            None => Penumbra::default(),
            Some(p) => p
                .parse::<Penumbra>()
                .map_err(|e| self.err("sweep.penumbra", e))?,
        };
        let media = match raw.media.as_deref() {
            None => Media::default(),
            Some(m) => m.parse::<Media>().map_err(|e| self.err("sweep.media", e))?,
        };
        let optimal_distance = match raw.optimal_distance {
            Some(d) => Some(self.length("sweep.optimal_distance", d)?),
            None if penumbra == Penumbra::Iterated => {
                return Err(self.err(
                    "sweep.optimal_distance",
                    "missing: the iterated penumbra needs the distance d1 (world units) at which \
                     its shadows are right (or set penumbra = \"distance\", which needs none)",
                ));
            }
            None => None,
        };
        Ok(SweepSpec {
            slabs,
            slab_factor: raw.slab_factor.unwrap_or(1.0),
            optimal_distance,
            penumbra,
            kernel,
            jitter: raw.jitter.unwrap_or(true),
            seed: raw.seed.unwrap_or(0),
            variance_compensation: raw.variance_compensation.unwrap_or(true),
            guard_band,
            preintegration: raw.preintegration.unwrap_or(false),
            media,
            subpixel_shadows: raw.subpixel_shadows.unwrap_or(true),
            held_lit_side: raw.held_lit_side.unwrap_or(false),
            served_releases: raw.served_releases.unwrap_or(true),
            horizon: raw.horizon.unwrap_or(true),
            light_resolution: raw.light_resolution.unwrap_or(1.0),
        })
    }

    /// `sweep.light_resolution`: 1/16 to 16.
    pub(super) fn light_resolution(&self, r: f64) -> Result<(), SceneError> {
        let (lo, hi) = LIGHT_RESOLUTION_RANGE;
        self.in_range("sweep.light_resolution", r, lo, hi)?;
        Ok(())
    }

    fn light(
        &self,
        i: usize,
        raw: RawLight,
        base_dir: &Path,
        camera: &CameraSpec,
    ) -> Result<LightSpec, SceneError> {
        let key = |k: &str| format!("light[{i}].{k}");
        let color = self.color(&key("color"), raw.color.unwrap_or([1.0; 3]))?;
        let kind = self.light_kind(i, raw.kind.as_deref())?;
        let point = self.point_light(i, kind, &raw)?;
        let tilt = self.light_tilt(i, raw.tilt_deg, raw.direction.is_some())?;
        let variance = raw.variance.unwrap_or([0.0; 2]);
        for (j, v) in variance.iter().enumerate() {
            let k = format!("light[{i}].variance[{j}]");
            self.finite(&k, *v)?;
            if *v < 0.0 {
                return Err(self.err(k, format!("expected a variance >= 0, got {v}")));
            }
            if *v > MAX_VARIANCE {
                return Err(self.err(
                    k,
                    format!("expected a variance from 0 to {MAX_VARIANCE:e}, got {v:e}"),
                ));
            }
        }
        let pattern = match raw.pattern {
            None => None,
            Some(p) => {
                let size = p.size.ok_or_else(|| {
                    self.err(
                        key("pattern.size"),
                        "expected `size = [w, h]`: the pattern's world-unit size on the first slab plane",
                    )
                })?;
                for (j, v) in size.iter().enumerate() {
                    self.length(&format!("light[{i}].pattern.size[{j}]"), *v)?;
                }
                let center = p.center.unwrap_or([0.0; 2]);
                for (j, v) in center.iter().enumerate() {
                    self.bounded(&format!("light[{i}].pattern.center[{j}]"), *v, MAX_WORLD)?;
                }
                Some(PatternSpec {
                    path: base_dir.join(p.path),
                    size,
                    center,
                })
            }
        };
        let rotation_deg = self.bounded(
            &key("rotation_deg"),
            raw.rotation_deg.unwrap_or(0.0),
            MAX_ANGLE_DEG,
        )?;
        let mut light = LightSpec {
            pattern,
            color: color.map(|c| c as f32),
            tilt_deg: tilt,
            world: None,
            variance,
            rotation_deg,
            toward_viewer: false,
            point,
        };
        if point.is_some() {
            return Ok(light);
        }
        if let Some(direction) = raw.direction {
            let world = self.world_light(i, direction, raw.up, variance, rotation_deg)?;
            self.place_light(i, &mut light, world, camera, "")?;
        } else if raw.up.is_some() {
            return Err(self.err(
                key("up"),
                "only applies with `direction` (a world-space light)",
            ));
        }
        Ok(light)
    }

    /// The shape of mesh `i`: its `shape`, `size` and `path` keys.
    fn shape(&self, i: usize, raw: &RawMesh, base_dir: &Path) -> Result<ShapeSpec, SceneError> {
        let key = |k: &str| format!("mesh[{i}].{k}");
        let size = |n: usize, what: &str| -> Result<Vec<f64>, SceneError> {
            let s = raw.size.clone().ok_or_else(|| {
                self.err(
                    key("size"),
                    format!("expected `size` = {what} for this shape"),
                )
            })?;
            if s.len() != n {
                return Err(self.err(
                    key("size"),
                    format!("expected {n} numbers ({what}), got {}", s.len()),
                ));
            }
            for (j, v) in s.iter().enumerate() {
                self.bounded(&format!("mesh[{i}].size[{j}]"), *v, MAX_WORLD)?;
            }
            Ok(s)
        };
        let whole = |v: f64, k: &str, min: u32, max: u32| -> Result<u32, SceneError> {
            if v.fract() != 0.0 || v < f64::from(min) || v > f64::from(max) {
                return Err(self.err(
                    key(k),
                    format!("expected a whole number from {min} to {max}, got {v}"),
                ));
            }
            Ok(v as u32)
        };
        if raw.path.is_some() && raw.shape != "obj" && raw.shape != "file" {
            return Err(self.err(
                key("path"),
                "`path` is only for shape = \"obj\" or \"file\"",
            ));
        }
        Ok(match raw.shape.as_str() {
            "box" => {
                let s = size(3, "[x, y, z] full extents")?;
                for (j, v) in s.iter().enumerate() {
                    self.length(&format!("mesh[{i}].size[{j}]"), *v)?;
                }
                ShapeSpec::Box {
                    size: [s[0], s[1], s[2]],
                }
            }
            "sphere" => {
                let s = size(2, "[radius, subdivisions]")?;
                self.length(&format!("mesh[{i}].size[0]"), s[0])?;
                ShapeSpec::Sphere {
                    radius: s[0],
                    subdivisions: whole(s[1], "size[1]", 0, MAX_SPHERE_SUBDIVISIONS)?,
                }
            }
            "torus" => {
                let s = size(3, "[major radius, minor radius, segments]")?;
                self.length(&format!("mesh[{i}].size[0]"), s[0])?;
                self.length(&format!("mesh[{i}].size[1]"), s[1])?;
                if s[1] >= s[0] {
                    return Err(self.err(
                        key("size"),
                        format!(
                            "expected minor radius < major radius, got {} >= {}",
                            s[1], s[0]
                        ),
                    ));
                }
                let segments = whole(s[2], "size[2]", 3, MAX_TORUS_SEGMENTS)?;
                ShapeSpec::Torus {
                    major: s[0],
                    minor: s[1],
                    segments,
                }
            }
            "cylinder" => {
                let s = size(3, "[radius, height, segments]")?;
                self.length(&format!("mesh[{i}].size[0]"), s[0])?;
                self.length(&format!("mesh[{i}].size[1]"), s[1])?;
                let segments = whole(s[2], "size[2]", 3, MAX_TORUS_SEGMENTS)?;
                ShapeSpec::Cylinder {
                    radius: s[0],
                    height: s[1],
                    segments,
                }
            }
            "obj" | "file" => {
                if raw.size.is_some() {
                    return Err(self.err(
                        key("size"),
                        format!("a {:?} mesh takes `path`, not `size`", raw.shape),
                    ));
                }
                let p = raw.path.as_ref().ok_or_else(|| {
                    self.err(
                        key("path"),
                        "expected `path` = the mesh file (.obj, .ply, .gltf, .glb or .stl), relative to the scene",
                    )
                })?;
                ShapeSpec::Obj {
                    path: base_dir.join(p),
                }
            }
            other => {
                return Err(self.err(
                    key("shape"),
                    format!(
                        "expected one of box, sphere, torus, cylinder, obj, file; got {other:?}"
                    ),
                ));
            }
        })
    }

    fn mesh(
        &self,
        i: usize,
        raw: RawMesh,
        materials: &[String],
        base_dir: &Path,
    ) -> Result<MeshSpec, SceneError> {
        let key = |k: &str| format!("mesh[{i}].{k}");
        let shape = self.shape(i, &raw, base_dir)?;
        let material = materials
            .iter()
            .position(|n| *n == raw.material)
            .ok_or_else(|| {
                self.err(
                    key("material"),
                    format!(
                        "no material named {:?}; expected one of [{}]",
                        raw.material,
                        materials.join(", ")
                    ),
                )
            })?;
        let scale = self.bounded(&key("scale"), raw.scale.unwrap_or(1.0), MAX_WORLD)?;
        if scale.abs() < MIN_WORLD {
            return Err(self.err(
                key("scale"),
                format!("expected a non-zero scale with |scale| >= {MIN_WORLD:e}, got {scale:e}"),
            ));
        }
        Ok(MeshSpec {
            shape,
            translate: self.bounded3(
                &key("translate"),
                raw.translate.unwrap_or([0.0; 3]),
                MAX_WORLD,
            )?,
            rotate_deg: self.bounded3(
                &key("rotate_deg"),
                raw.rotate_deg.unwrap_or([0.0; 3]),
                MAX_ANGLE_DEG,
            )?,
            scale,
            material,
        })
    }

    /// The `gradient` of material `name`: stops sorted by value (`needed`: the material has
    /// detail or a texture, which the gradient maps to colour and opacity).
    fn gradient(
        &self,
        name: &str,
        raw: Option<Vec<[f64; 5]>>,
        needed: bool,
    ) -> Result<Vec<GradientStop>, SceneError> {
        let key = |k: &str| format!("material.{name}.{k}");
        let mut gradient = Vec::new();
        if let Some(g) = raw {
            if g.is_empty() {
                return Err(self.err(key("gradient"), "expected at least one stop"));
            }
            for (j, s) in g.iter().enumerate() {
                let k = format!("material.{name}.gradient[{j}]");
                for (c, v) in s.iter().enumerate() {
                    self.finite(&format!("{k}[{c}]"), *v)?;
                }
                self.unit_interval(&format!("{k}[0]"), s[0])?;
                for (c, v) in s.iter().enumerate().take(4).skip(1) {
                    self.color_component(&format!("{k}[{c}]"), *v)?;
                }
                self.unit_interval(&format!("{k}[4]"), s[4])?;
                if let Some(prev) = gradient.last().map(|p: &GradientStop| p.value)
                    && s[0] < prev
                {
                    return Err(self.err(k, "expected stops sorted by value"));
                }
                gradient.push(GradientStop {
                    value: s[0],
                    color: [s[1], s[2], s[3]],
                    opacity: s[4],
                });
            }
        } else if needed {
            return Err(self.err(
                key("gradient"),
                "a material with detail or texture needs `gradient` = [[value, r, g, b, opacity], ...]",
            ));
        }
        Ok(gradient)
    }

    fn material(
        &self,
        name: &str,
        raw: RawMaterial,
        base_dir: &Path,
    ) -> Result<MaterialSpec, SceneError> {
        let key = |k: &str| format!("material.{name}.{k}");
        let color = self.color(&key("color"), raw.color.unwrap_or([1.0; 3]))?;
        let opacity = self.unit_interval(&key("opacity"), raw.opacity.unwrap_or(1.0))?;
        let transport = raw.transport.unwrap_or([0.0; 3]);
        for (j, t) in transport.iter().enumerate() {
            self.unit_interval(&format!("material.{name}.transport[{j}]"), *t)?;
        }
        let reference_length = raw
            .reference_length
            .map(|r| self.length(&key("reference_length"), r))
            .transpose()?;
        let detail = raw.detail.map(|d| self.detail(&key, d)).transpose()?;
        let texture = raw
            .texture
            .map(|t| self.texture(&key, t, base_dir))
            .transpose()?;
        if detail.is_some() && texture.is_some() {
            return Err(self.err(
                key("texture"),
                "expected either `detail` or `texture`, not both",
            ));
        }
        let gradient = self.gradient(name, raw.gradient, detail.is_some() || texture.is_some())?;
        if raw.opacity.is_some() && !gradient.is_empty() {
            return Err(self.err(
                key("opacity"),
                "a gradient material takes its opacity from the gradient; remove `opacity`",
            ));
        }
        let specular = raw.specular.map(|s| self.specular(&key, s)).transpose()?;
        let surface = match raw.surface.as_deref() {
            None | Some("lambert") => SurfaceModel::Lambert,
            Some("flat") => SurfaceModel::Flat,
            Some(other) => {
                return Err(self.err(
                    key("surface"),
                    format!("expected \"flat\" or \"lambert\", got \"{other}\""),
                ));
            }
        };
        let phase_g = match raw.phase {
            None => 0.0,
            Some(p) => {
                let k = key("phase.g");
                self.finite(&k, p.g)?;
                if p.g.abs() > MAX_PHASE_G {
                    return Err(self.err(
                        k,
                        format!(
                            "expected a Henyey-Greenstein asymmetry from -{MAX_PHASE_G} to \
                             {MAX_PHASE_G} (the function needs -1 < g < 1), got {}",
                            p.g
                        ),
                    ));
                }
                p.g
            }
        };
        Ok(MaterialSpec {
            name: name.to_string(),
            color,
            opacity,
            transport,
            reference_length,
            detail,
            texture,
            gradient,
            specular,
            surface,
            phase_g,
        })
    }

    /// A material's procedural detail (`material.NAME.detail`).
    fn detail(&self, key: &dyn Fn(&str) -> String, d: RawDetail) -> Result<DetailSpec, SceneError> {
        let octaves = d.octaves.unwrap_or(4);
        if octaves == 0 || octaves > 16 {
            return Err(self.err(
                key("detail.octaves"),
                format!("expected 1 to 16 octaves, got {octaves}"),
            ));
        }
        Ok(DetailSpec {
            kind: d.kind,
            frequency: self.length(&key("detail.frequency"), d.frequency.unwrap_or(1.0))?,
            octaves,
            lacunarity: self.in_range(
                &key("detail.lacunarity"),
                d.lacunarity.unwrap_or(2.0),
                1.0 / MAX_OCTAVE_RATIO,
                MAX_OCTAVE_RATIO,
            )?,
            gain: self.in_range(
                &key("detail.gain"),
                d.gain.unwrap_or(0.5),
                1.0 / MAX_OCTAVE_RATIO,
                MAX_OCTAVE_RATIO,
            )?,
            time: d
                .time
                .map(|t| self.bounded(&key("detail.time"), t, MAX_WORLD))
                .transpose()?,
        })
    }

    /// A material's 3D texture (`material.NAME.texture`): NIfTI by extension, else raw.
    fn texture(
        &self,
        key: &dyn Fn(&str) -> String,
        t: RawTexture,
        base_dir: &Path,
    ) -> Result<TextureSpec, SceneError> {
        let path = base_dir.join(&t.path);
        if t.grid.is_some() && !is_vdb_path(&path) {
            return Err(self.err(
                key("texture.grid"),
                "`grid` applies to OpenVDB textures (.vdb) only",
            ));
        }
        let format = if is_vdb_path(&path) {
            if t.dims.is_some() || t.voxel.is_some() || t.window.is_some() {
                return Err(self.err(
                    key("texture"),
                    "an OpenVDB texture (.vdb) takes its dims from the grid's active voxels and \
                     uses its values as stored; remove `dims`, `type` and `window`",
                ));
            }
            let Some(grid) = t.grid else {
                return Err(self.err(
                    key("texture.grid"),
                    "an OpenVDB texture (.vdb) needs the name of its float grid, e.g. \
                     `grid = \"density\"`",
                ));
            };
            TextureFormat::Vdb { grid }
        } else if is_nifti_path(&path) {
            if t.dims.is_some() || t.voxel.is_some() {
                return Err(self.err(
                    key("texture"),
                    "a NIfTI texture (.nii, .nii.gz) takes dims and type from its header; \
                     remove `dims` and `type`",
                ));
            }
            if let Some([lo, hi]) = t.window
                && !(lo.is_finite() && hi.is_finite() && lo < hi)
            {
                return Err(self.err(
                    key("texture.window"),
                    format!("expected [lo, hi] with finite lo < hi, got [{lo}, {hi}]"),
                ));
            }
            TextureFormat::Nifti { window: t.window }
        } else {
            let (Some(dims), Some(voxel)) = (t.dims, t.voxel) else {
                return Err(self.err(
                    key("texture"),
                    "a raw texture needs `dims = [x, y, z]` and `type` (u8, u16, f32); \
                     NIfTI files end in .nii or .nii.gz",
                ));
            };
            // The loader's limits, checked here so that dims beyond them are named as the
            // dims (exit code 3), not as a memory need of 2^32 voxels (exit code 4).
            if crate::pixel::texture3d::voxel_count(dims).is_none() {
                use crate::pixel::texture3d::{MAX_DIM, MAX_VOXELS};
                return Err(self.err(
                    key("texture.dims"),
                    format!(
                        "expected three dimensions from 1 to {MAX_DIM} with at most \
                         {MAX_VOXELS} voxels in all, got [{}, {}, {}]",
                        dims[0], dims[1], dims[2]
                    ),
                ));
            }
            if t.window.is_some() {
                return Err(self.err(
                    key("texture.window"),
                    "`window` applies to NIfTI textures only (raw ones are normalised by type)",
                ));
            }
            TextureFormat::Raw { dims, voxel }
        };
        Ok(TextureSpec { path, format })
    }

    /// A material's specular highlight (`material.NAME.specular`).
    fn specular(
        &self,
        key: &dyn Fn(&str) -> String,
        s: RawSpecular,
    ) -> Result<SpecularSpec, SceneError> {
        let model = match s.model.as_deref() {
            None | Some("blinn-phong") => SpecularModel::BlinnPhong,
            Some("ashikmin-shirley") => SpecularModel::AshikminShirley {
                f0: self.unit_interval(&key("specular.f0"), s.f0.unwrap_or(DEFAULT_F0))? as f32,
            },
            Some(other) => {
                return Err(self.err(
                    key("specular.model"),
                    format!("expected \"blinn-phong\" or \"ashikmin-shirley\", got \"{other}\""),
                ));
            }
        };
        if s.f0.is_some() && model == SpecularModel::BlinnPhong {
            return Err(self.err(
                key("specular.f0"),
                "`f0` (Fresnel reflectance at normal incidence) applies to \
                 model = \"ashikmin-shirley\" only",
            ));
        }
        let strength = s.strength.unwrap_or(1.0);
        self.finite(&key("specular.strength"), strength)?;
        if !(0.0..=MAX_COLOR).contains(&strength) {
            return Err(self.err(
                key("specular.strength"),
                format!("expected a strength from 0 to {MAX_COLOR:e}, got {strength:e}"),
            ));
        }
        if s.exponent == 0 || s.exponent > 4096 {
            return Err(self.err(
                key("specular.exponent"),
                format!("expected 1 to 4096, got {}", s.exponent),
            ));
        }
        Ok(SpecularSpec {
            model,
            strength: strength as f32,
            exponent: s.exponent,
        })
    }
}
