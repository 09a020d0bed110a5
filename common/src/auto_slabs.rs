//! `sweep.slabs = "auto"`: the slab count from the detail the slabs must sample (Patel et al.
//! 2013, §7: "for sampled function representations we use the dimensions of the 3D texture as a
//! basis for automatically setting the number of slabs … the chosen frequency scale is taken into
//! account and an additional modulation factor can be specified by the user").
//!
//! Every mesh whose material has detail contributes a *finest period* in world units along the
//! view direction `d`:
//! - procedural detail: one lattice cell of its highest octave, `1 / (f_max · |M d|)` with
//!   `f_max = frequency · max(1, lacunarity)^(octaves − 1)` (one octave for `perlin`) per
//!   object-space unit and `M` the world → object map (`|M d| = 1 / scale`);
//! - a 3D texture: one voxel, `1 / |V M d|` with `V = diag(dims / size)` mapping object units to
//!   voxels (`size` is the object-space box the texture is mapped onto, the NIfTI extent fitted
//!   into it like the plan does).
//!
//! The count is `⌈depth · 2 · slab_factor / p_min⌉` over the scene's depth range (2 slabs per
//! finest period p_min), and at least `⌈AUTO_MIN_SLABS · slab_factor⌉` (a scene without detail,
//! or with very coarse detail, still gets enough slabs for its shadows to iterate smoothly).

use glam::DVec3;

use crate::geometry::{GeometryError, WorldMesh};
use crate::plan::fit_extent;
use crate::scene::{MAX_SLABS, Scene, TextureFormat};

/// Slabs per finest period of the detail (Nyquist: two samples per period).
pub const SLABS_PER_PERIOD: f64 = 2.0;
/// The fewest slabs `"auto"` chooses (times `slab_factor`), also for scenes without detail.
pub const AUTO_MIN_SLABS: f64 = 64.0;

/// What `slabs = "auto"` chose, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct AutoSlabs {
    /// The slab count.
    pub count: u32,
    /// The finest period along the view direction, world units (`None`: no detail; the minimum
    /// count applies).
    pub finest_period: Option<f64>,
    /// The scene key of the detail that sets it (`material.NAME.detail` or `.texture`).
    pub limited_by: Option<String>,
    /// `sweep.slab_factor`.
    pub factor: f64,
}

/// The finest period (world units along `forward`) of the detail of every mesh, and the key of
/// the one that sets it. NIfTI headers are read for their dims and spacing.
pub fn finest_period(
    scene: &Scene,
    forward: DVec3,
    meshes: &[WorldMesh],
) -> Result<Option<(f64, String)>, GeometryError> {
    let mut best: Option<(f64, String)> = None;
    for (spec, wm) in scene.meshes.iter().zip(meshes) {
        let material = &scene.materials[spec.material];
        // The world → object image of one world unit along the view direction.
        let step = wm.world_to_object.matrix3 * forward;
        let mut candidates = Vec::new();
        if let Some(d) = &material.detail {
            let octaves = if d.kind == crate::noise::DetailKind::Perlin {
                1
            } else {
                d.octaves.max(1)
            };
            let mut f_max = d.frequency;
            for _ in 1..octaves {
                f_max *= d.lacunarity.max(1.0);
            }
            let rate = f_max * step.length();
            candidates.push((rate, format!("material.{}.detail", material.name)));
        }
        if let Some(t) = &material.texture {
            let (mut lo, mut hi) = wm.object_bounds;
            let dims = match &t.format {
                TextureFormat::Raw { dims, .. } => *dims,
                TextureFormat::Nifti { .. } => {
                    let (dims, spacing) = crate::nifti::header_grid(&t.path).map_err(|source| {
                        GeometryError::Texture {
                            scene: scene.source.clone(),
                            material: material.name.clone(),
                            source,
                        }
                    })?;
                    let extent = DVec3::new(
                        f64::from(dims[0]) * spacing[0],
                        f64::from(dims[1]) * spacing[1],
                        f64::from(dims[2]) * spacing[2],
                    );
                    (lo, hi) = fit_extent(lo, hi, extent);
                    dims
                }
            };
            let size = (hi - lo).max(DVec3::splat(1e-30));
            let voxels =
                DVec3::new(f64::from(dims[0]), f64::from(dims[1]), f64::from(dims[2])) / size;
            let rate = (voxels * step).length();
            candidates.push((rate, format!("material.{}.texture", material.name)));
        }
        for (rate, key) in candidates {
            if rate > 0.0 && rate.is_finite() {
                let period = 1.0 / rate;
                if best.as_ref().is_none_or(|(p, _)| period < *p) {
                    best = Some((period, key));
                }
            }
        }
    }
    Ok(best)
}

/// The `"auto"` slab count over a depth range of `depth` world units (see the module
/// documentation); more than [`MAX_SLABS`] is an error naming `sweep.slabs`.
pub fn auto_slabs(
    scene: &Scene,
    forward: DVec3,
    meshes: &[WorldMesh],
    depth: f64,
) -> Result<AutoSlabs, GeometryError> {
    let factor = scene.sweep.slab_factor;
    let found = finest_period(scene, forward, meshes)?;
    let floor = (AUTO_MIN_SLABS * factor).ceil().max(1.0);
    let needed = match &found {
        Some((period, _)) => (depth * SLABS_PER_PERIOD * factor / period).ceil(),
        None => floor,
    };
    let count = needed.max(floor);
    if count.is_nan() || count > f64::from(MAX_SLABS) {
        let (period, key) = found.clone().unwrap_or((f64::NAN, String::new()));
        return Err(GeometryError::TooManyAutoSlabs {
            scene: scene.source.clone(),
            count,
            depth,
            period,
            limited_by: key,
            factor,
        });
    }
    Ok(AutoSlabs {
        count: count as u32,
        finest_period: found.as_ref().map(|f| f.0),
        limited_by: found.map(|f| f.1),
        factor,
    })
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::geometry::{GeometryError, SceneGeometry};
    use crate::scene::Scene;

    /// A 2×2×2 box (or `box_size`) at the origin seen along `direction`, with `sweep` and the
    /// material table `material` (its `[material.m]` header included).
    fn scene(direction: &str, sweep: &str, mesh_extra: &str, material: &str) -> Scene {
        let text = format!(
            r#"
[image]
width = 16
height = 16
[camera]
direction = {direction}
view_width = 4.0
[sweep]
optimal_distance = 1.0
{sweep}
[[mesh]]
shape = "box"
size = [2.0, 2.0, 2.0]
material = "m"
{mesh_extra}
{material}
"#
        );
        Scene::parse(&text, "auto.toml", Path::new(".")).unwrap()
    }

    fn fbm(frequency: f64) -> String {
        format!(
            "[material.m]\ndetail = {{ kind = \"fbm\", frequency = {frequency}, octaves = 3, \
             lacunarity = 2.0 }}\ngradient = [[0.0, 1.0, 1.0, 1.0, 0.5]]\n"
        )
    }

    fn count(s: &Scene) -> u32 {
        let g = SceneGeometry::build(s).unwrap();
        assert_eq!(g.slabs, g.auto_slabs.as_ref().unwrap().count);
        g.slabs
    }

    #[test]
    fn doubling_a_details_frequency_doubles_the_count() {
        const AUTO: &str = "slabs = \"auto\"";
        // f_max = 5 · 2² = 20 per unit; the box is 2 deep: at least 2 · 20 · 2 = 80 slabs, at
        // most one more (the ceiling of a depth widened by one part in 10⁶).
        let n1 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(5.0)));
        assert!((80..=81).contains(&n1), "{n1}");
        let n2 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(10.0)));
        assert!(n2 == 2 * n1 || n2 == 2 * n1 - 1, "{n1} → {n2}");
        let n4 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(20.0)));
        assert!(n4 == 2 * n2 || n4 == 2 * n2 - 1, "{n2} → {n4}");
        // slab_factor multiplies the count the same way.
        let f2 = count(&scene(
            "[0.0, 0.0, 1.0]",
            "slabs = \"auto\"\nslab_factor = 2.0",
            "",
            &fbm(5.0),
        ));
        assert!(f2 == 2 * n1 || f2 == 2 * n1 - 1, "{n1} → {f2}");
        // Perlin noise has one octave: its finest frequency is its frequency.
        let perlin = "[material.m]\ndetail = { kind = \"perlin\", frequency = 40.0, octaves = 3 }\n\
                      gradient = [[0.0, 1.0, 1.0, 1.0, 0.5]]\n";
        let np = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", perlin));
        // 2 · 40 · 2 = 160 (octaves ignored), not 2 · 40 · 4² · 2.
        assert!((160..=161).contains(&np), "{np}");
    }

    #[test]
    fn periods_are_measured_in_world_units_along_the_view() {
        const AUTO: &str = "slabs = \"auto\"";
        let n1 = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &fbm(5.0)));
        // Scaled by 2 the box is 4 deep and its detail twice as coarse in world units: the
        // same number of periods over the depth, the same count.
        let scaled = count(&scene("[0.0, 0.0, 1.0]", AUTO, "scale = 2.0", &fbm(5.0)));
        assert_eq!(scaled, n1);
        // A second, constant box behind it doubles the depth range: twice the slabs.
        let two = format!(
            "{}\n[[mesh]]\nshape = \"box\"\nsize = [2.0, 2.0, 2.0]\ntranslate = [0.0, 0.0, 2.0]\n\
             material = \"wall\"\n[material.wall]\n",
            fbm(5.0)
        );
        let deep = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &two));
        assert!(deep == 2 * n1 || deep == 2 * n1 - 1, "{n1} → {deep}");
    }

    #[test]
    fn a_texture_of_64_voxels_along_the_view_gets_at_least_128_slabs_over_it() {
        let texture = |dims: &str| {
            format!(
                "[material.m]\ntexture = {{ path = \"never-read.raw\", dims = {dims}, type = \"u8\" }}\n\
                 gradient = [[0.0, 1.0, 1.0, 1.0, 0.5]]\n"
            )
        };
        const AUTO: &str = "slabs = \"auto\"";
        // The box spans the whole depth, so "over it" is the whole count.
        let along_z = count(&scene("[0.0, 0.0, 1.0]", AUTO, "", &texture("[4, 4, 64]")));
        assert!((128..=129).contains(&along_z), "{along_z}");
        // Seen along x, the x dimension counts.
        let along_x = count(&scene("[1.0, 0.0, 0.0]", AUTO, "", &texture("[64, 4, 4]")));
        assert!((128..=129).contains(&along_x), "{along_x}");
        // The 4 voxels along x of a [4, 4, 64] texture need 8 slabs: the minimum of 64 applies.
        let coarse = count(&scene("[1.0, 0.0, 0.0]", AUTO, "", &texture("[4, 4, 64]")));
        assert_eq!(coarse, super::AUTO_MIN_SLABS as u32);
        // Along the diagonal of x and z, one world unit crosses (1/√2)·(4/2) voxels in x and
        // (1/√2)·(64/2) in z: √(2² + 32²)/√2 voxels per world unit, one voxel the period.
        let rate = (2.0f64 * 2.0 + 32.0 * 32.0).sqrt() / 2f64.sqrt();
        let g = SceneGeometry::build(&scene("[1.0, 0.0, 1.0]", AUTO, "", &texture("[4, 4, 64]")))
            .unwrap();
        let period = g.auto_slabs.unwrap().finest_period.unwrap();
        assert!((period - 1.0 / rate).abs() < 1e-12 * rate, "{period}");
    }

    #[test]
    fn a_scene_without_detail_gets_the_minimum() {
        let s = scene("[0.0, 0.0, 1.0]", "slabs = \"auto\"", "", "[material.m]\n");
        assert_eq!(count(&s), super::AUTO_MIN_SLABS as u32);
        let a = SceneGeometry::build(&s).unwrap().auto_slabs.unwrap();
        assert_eq!((a.finest_period, a.limited_by), (None, None));
    }

    #[test]
    fn too_many_auto_slabs_is_an_error_naming_the_key() {
        let s = scene("[0.0, 0.0, 1.0]", "slabs = \"auto\"", "", &fbm(1e5));
        let e = SceneGeometry::build(&s).unwrap_err();
        assert!(matches!(e, GeometryError::TooManyAutoSlabs { .. }), "{e}");
        let msg = e.to_string();
        for words in ["auto.toml", "sweep.slabs", "material.m.detail", "65536"] {
            assert!(msg.contains(words), "{words}: {msg}");
        }
    }

    #[test]
    fn bad_auto_keys_are_refused_by_name() {
        let text = |sweep: &str| {
            format!(
                "[image]\nwidth = 8\nheight = 8\n[camera]\nview_width = 2.0\n[sweep]\n\
                 optimal_distance = 1.0\n{sweep}\n[[mesh]]\nshape = \"box\"\n\
                 size = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n[material.m]\n"
            )
        };
        for (sweep, key, words) in [
            ("slabs = \"many\"", "sweep.slabs", "\"auto\""),
            ("slabs = -3", "sweep.slabs", "got -3"),
            ("slabs = 16\nslab_factor = 2.0", "sweep.slab_factor", "auto"),
            (
                "slabs = \"auto\"\nslab_factor = 0.0",
                "sweep.slab_factor",
                "expected a number",
            ),
            (
                "slabs = \"auto\"\nslab_factor = 1e9",
                "sweep.slab_factor",
                "1.024e3",
            ),
        ] {
            let e = Scene::parse(&text(sweep), "bad.toml", Path::new(".")).unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains(key) && msg.contains(words), "{sweep}: {msg}");
        }
    }
}
