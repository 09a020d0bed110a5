//! Property tests on scenes: random valid scenes render without NaN, random invalid scenes are
//! rejected naming the key.

use crate::support;

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{RenderRequest, render};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// Random scenes, valid and invalid.

/// A random scene as (key path, TOML value) entries grouped in tables, so one key can be swapped.
#[derive(Debug, Clone)]
struct GenScene {
    width: u32,
    height: u32,
    view_width: f64,
    direction: [f64; 3],
    slabs: u32,
    kernel: &'static str,
    seed: u32,
    guard: u32,
    compensation: bool,
    jitter: bool,
    lights: Vec<GenLight>,
    meshes: Vec<GenMesh>,
    materials: Vec<(f64, [f64; 3], bool)>,
}

/// A light: colour, tilt, variance, rotation.
type GenLight = ([f64; 3], [f64; 2], [f64; 2], f64);
/// A mesh: shape (box, sphere, torus), translation, rotation, scale, material index.
type GenMesh = (u8, [f64; 3], [f64; 3], f64, usize);

/// One (table header, key, value) line of the generated TOML.
type Entry = (String, String, String);

impl GenScene {
    fn entries(&self) -> Vec<Entry> {
        let mut v: Vec<Entry> = Vec::new();
        let mut put = |table: &str, key: &str, value: String| {
            v.push((table.to_string(), key.to_string(), value));
        };
        let arr = |a: &[f64]| {
            format!(
                "[{}]",
                a.iter()
                    .map(|x| format!("{x:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        put("image", "width", self.width.to_string());
        put("image", "height", self.height.to_string());
        put("camera", "direction", arr(&self.direction));
        put("camera", "view_width", format!("{:?}", self.view_width));
        put("sweep", "slabs", self.slabs.to_string());
        put("sweep", "optimal_distance", "0.5".into());
        put("sweep", "kernel", format!("{:?}", self.kernel));
        put("sweep", "seed", self.seed.to_string());
        put("sweep", "guard_band", self.guard.to_string());
        put(
            "sweep",
            "variance_compensation",
            self.compensation.to_string(),
        );
        put("sweep", "jitter", self.jitter.to_string());
        for (i, (color, tilt, variance, rot)) in self.lights.iter().enumerate() {
            let t = format!("light[{i}]");
            put(&t, "color", arr(color));
            put(&t, "tilt_deg", arr(tilt));
            put(&t, "variance", arr(variance));
            put(&t, "rotation_deg", format!("{rot:?}"));
        }
        for (i, (kind, translate, rotate, scale, material)) in self.meshes.iter().enumerate() {
            let t = format!("mesh[{i}]");
            let (shape, size) = match kind {
                0 => ("box", "[0.8, 0.6, 0.7]"),
                1 => ("sphere", "[0.5, 2.0]"),
                _ => ("torus", "[0.5, 0.2, 12.0]"),
            };
            put(&t, "shape", format!("{shape:?}"));
            put(&t, "size", size.into());
            put(&t, "translate", arr(translate));
            put(&t, "rotate_deg", arr(rotate));
            put(&t, "scale", format!("{scale:?}"));
            put(&t, "material", format!("\"m{material}\""));
        }
        for (i, (opacity, transport, detail)) in self.materials.iter().enumerate() {
            let t = format!("material.m{i}");
            put(&t, "transport", arr(transport));
            if *detail {
                put(&t, "detail", "{ kind = \"fbm\", frequency = 3.0 }".into());
                put(
                    &t,
                    "gradient",
                    format!("[[0.0, 1.0, 0.5, 0.2, 0.0], [1.0, 0.2, 0.4, 1.0, {opacity:?}]]"),
                );
            } else {
                put(&t, "opacity", format!("{opacity:?}"));
                put(&t, "color", "[0.9, 0.8, 0.7]".into());
            }
        }
        v
    }

    /// The TOML text, with `key` (a full path like `light[0].tilt_deg`) replaced by `value`.
    fn toml(&self, replace: Option<(&str, &str)>) -> String {
        let mut text = String::new();
        let mut current = String::new();
        for (table, key, value) in self.entries() {
            if table != current {
                let header = match table.split_once('[') {
                    Some((name, _)) => format!("[[{name}]]"),
                    None => format!("[{table}]"),
                };
                text += &format!("{header}\n");
                current = table.clone();
            }
            let path = format!("{table}.{key}");
            let value = match replace {
                Some((k, v)) if k == path => v.to_string(),
                _ => value,
            };
            text += &format!("{key} = {value}\n");
        }
        text
    }
}

fn gen_scene() -> impl Strategy<Value = GenScene> {
    let light = (
        prop::array::uniform3(0.0f64..2.0),
        prop::array::uniform2(-85.0f64..85.0),
        prop::array::uniform2(prop_oneof![Just(0.0), 0.0f64..0.5, 0.5f64..50.0]),
        -180.0f64..180.0,
    );
    let mesh = (
        0u8..3,
        prop::array::uniform3(-0.8f64..0.8),
        prop::array::uniform3(-180.0f64..180.0),
        0.5f64..1.5,
        0usize..2,
    );
    let material = (
        0.0f64..1.0,
        prop::array::uniform3(prop_oneof![Just(0.0), Just(1.0), 0.0f64..1.0]),
        any::<bool>(),
    );
    (
        (
            8u32..=24,
            8u32..=24,
            1.5f64..4.0,
            prop::array::uniform3(-1.0f64..1.0),
        ),
        (
            1u32..=16,
            prop::sample::select(support::kernels()),
            any::<u32>(),
            0u32..4,
            any::<bool>(),
            any::<bool>(),
        ),
        prop::collection::vec(light, 1..4),
        prop::collection::vec(mesh, 1..4),
        prop::collection::vec(material, 2..=2),
    )
        .prop_filter("a view direction", |((_, _, _, d), ..)| {
            d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 0.05
        })
        .prop_map(
            |(
                (width, height, view_width, mut direction),
                (slabs, kernel, seed, guard, compensation, jitter),
                lights,
                meshes,
                materials,
            )| {
                // Keep the default up vector (+y) away from the view direction.
                if direction[0].abs() + direction[2].abs() < 0.2 {
                    direction[2] = 1.0;
                }
                GenScene {
                    width,
                    height,
                    view_width,
                    direction,
                    slabs,
                    kernel,
                    seed,
                    guard,
                    compensation,
                    jitter,
                    lights,
                    meshes,
                    materials,
                }
            },
        )
}

/// A mutation of one key to an invalid value; `names` must appear in the error message.
fn mutation(s: &GenScene, pick: usize, which: usize) -> (String, String, String) {
    let l = pick % s.lights.len();
    let m = pick % s.meshes.len();
    let list: Vec<(String, &str, String)> = vec![
        ("image.width".into(), "0", "image.width".into()),
        ("image.width".into(), "100000", "image.width".into()),
        ("image.height".into(), "-4", "height".into()),
        ("image.height".into(), "\"tall\"", "height".into()),
        (
            "camera.view_width".into(),
            "0.0",
            "camera.view_width".into(),
        ),
        (
            "camera.view_width".into(),
            "nan",
            "camera.view_width".into(),
        ),
        (
            "camera.direction".into(),
            "[0.0, 0.0, 0.0]",
            "camera.direction".into(),
        ),
        (
            "camera.direction".into(),
            "[0.0, 1.0, 0.0]",
            "camera.up".into(),
        ),
        ("sweep.slabs".into(), "0", "sweep.slabs".into()),
        ("sweep.slabs".into(), "70000", "sweep.slabs".into()),
        (
            "sweep.optimal_distance".into(),
            "-0.5",
            "sweep.optimal_distance".into(),
        ),
        ("sweep.kernel".into(), "\"blur\"", "sweep.kernel".into()),
        ("sweep.guard_band".into(), "5000", "sweep.guard_band".into()),
        ("sweep.jitter".into(), "3", "jitter".into()),
        (
            format!("light[{l}].tilt_deg"),
            "[90.0, 0.0]",
            format!("light[{l}].tilt_deg[0]"),
        ),
        (
            format!("light[{l}].tilt_deg"),
            "[0.0, -90.0]",
            format!("light[{l}].tilt_deg[1]"),
        ),
        (
            format!("light[{l}].tilt_deg"),
            "[0.0, 135.0]",
            format!("light[{l}].tilt_deg[1]"),
        ),
        (
            format!("light[{l}].variance"),
            "[-0.1, 0.0]",
            format!("light[{l}].variance[0]"),
        ),
        (
            format!("light[{l}].variance"),
            "[0.1, -1e-9]",
            format!("light[{l}].variance[1]"),
        ),
        (
            format!("light[{l}].color"),
            "[1.0, -1.0, 1.0]",
            format!("light[{l}].color[1]"),
        ),
        (
            format!("light[{l}].rotation_deg"),
            "inf",
            format!("light[{l}].rotation_deg"),
        ),
        (
            format!("mesh[{m}].shape"),
            "\"cone\"",
            format!("mesh[{m}].shape"),
        ),
        (
            format!("mesh[{m}].scale"),
            "0.0",
            format!("mesh[{m}].scale"),
        ),
        (
            format!("mesh[{m}].material"),
            "\"nope\"",
            format!("mesh[{m}].material"),
        ),
        (
            format!("mesh[{m}].translate"),
            "[0.0, nan, 0.0]",
            format!("mesh[{m}].translate[1]"),
        ),
        (
            "material.m0.transport".into(),
            "[0.5, 2.0, 0.5]",
            "material.m0.transport[1]".into(),
        ),
    ];
    let (key, value, names) = &list[which % list.len()];
    (key.clone(), value.to_string(), names.clone())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    /// Small random valid scenes (≤ 24×24 px, ≤ 16 slabs, 1–3 lights, 1–3 meshes, every kernel)
    /// render through the library pipeline with finite, non-negative pixels and light.
    #[test]
    fn random_valid_scenes_render_without_nan(s in gen_scene()) {
        let text = s.toml(None);
        let scene = Scene::parse(&text, "random.toml", Path::new("."))
            .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        let req = RenderRequest { threads: 1, ..RenderRequest::default() };
        let r = render(&scene, &req)
            .map_err(|e| TestCaseError::fail(format!("{}\n{text}", e)))?;
        prop_assert_eq!(r.image.data.len(), (s.width * s.height * 3) as usize);
        prop_assert!(
            r.image.data.iter().all(|v| v.is_finite() && *v >= 0.0),
            "non-finite or negative pixel\n{}", text
        );
        // The light buffers: `[row][light][plane][x]`; a light's channels are ≥ 0, its depth
        // plane (distance penumbra, sub-pixel shadows) is D, negative where light was removed
        // before slab 0's middle (`deepen`): finite only.
        let (w, planes) = (r.plan.grid_width as usize, r.plan.planes_per_light());
        let channels = r.plan.channels as usize;
        let bad = r.light.iter().enumerate().find(|&(i, v)| {
            !v.is_finite() || (((i / w) % planes) < channels && *v < 0.0)
        });
        prop_assert!(bad.is_none(), "light value {:?}\n{}", bad, text);
    }

    /// One key of a valid scene set to an invalid value: rejected by the parser with a message
    /// naming the file and the key (so it can never reach the renderer), while the unmutated
    /// scene is accepted.
    #[test]
    fn random_invalid_scenes_are_rejected_naming_the_key(
        s in gen_scene(),
        pick in any::<usize>(),
        which in any::<usize>(),
    ) {
        prop_assert!(Scene::parse(&s.toml(None), "random.toml", Path::new(".")).is_ok());
        let (key, value, names) = mutation(&s, pick, which);
        let text = s.toml(Some((&key, &value)));
        prop_assert!(text.contains(&format!("= {value}\n")), "mutation applied:\n{}", text);
        match Scene::parse(&text, "random.toml", Path::new(".")) {
            Ok(_) => prop_assert!(false, "{} = {} was accepted\n{}", key, value, text),
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.starts_with("random.toml: "), "{}", msg);
                prop_assert!(msg.contains(&names), "{} = {}: message must name {}: {}", key, value, names, msg);
            }
        }
    }
}
