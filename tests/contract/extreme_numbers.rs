//! Every scene number drawn from the whole f64 range gives a clear error naming the key or a
//! finite image, and the adversarial pass's one-value regressions stay refused (docs/errors.md).

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{RenderRequest, render};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// Extreme numbers: every scene number drawn from the whole f64 range.

/// The scene numbers the extreme-value property varies: (table, key, number of components).
const NUMERIC_KEYS: &[(&str, &str, usize)] = &[
    ("image", "background", 3),
    ("image", "exposure", 1),
    ("camera", "direction", 3),
    ("camera", "center", 3),
    ("camera", "view_width", 1),
    ("sweep", "slab_distance", 1),
    ("sweep", "optimal_distance", 1),
    ("light", "color", 3),
    ("light", "tilt_deg", 2),
    ("light", "variance", 2),
    ("light", "rotation_deg", 1),
    ("mesh", "translate", 3),
    ("mesh", "rotate_deg", 3),
    ("mesh", "scale", 1),
    ("mesh", "size", 3),
    ("material.m", "color", 3),
    ("material.m", "opacity", 1),
    ("material.m", "reference_length", 1),
    ("material.m", "specular.strength", 1),
    ("material.d", "detail.frequency", 1),
    ("material.d", "detail.lacunarity", 1),
    ("material.d", "detail.gain", 1),
    ("material.d", "detail.time", 1),
    ("material.d", "gradient[0]", 5),
];

/// A small valid scene with key `key` of table `table` set to `value` (TOML text).
fn extreme_scene(table: &str, key: &str, value: &str) -> String {
    let mut lines: Vec<(&str, String, String)> = vec![
        ("image", "width".into(), "8".into()),
        ("image", "height".into(), "8".into()),
        ("image", "background".into(), "[0.1, 0.2, 0.3]".into()),
        ("image", "exposure".into(), "0.0".into()),
        ("camera", "direction".into(), "[0.3, -0.2, 1.0]".into()),
        ("camera", "center".into(), "[0.0, 0.0, 0.0]".into()),
        ("camera", "view_width".into(), "3.0".into()),
        ("sweep", "slabs".into(), "6".into()),
        ("sweep", "optimal_distance".into(), "0.5".into()),
        ("light", "color".into(), "[1.0, 0.9, 0.8]".into()),
        ("light", "tilt_deg".into(), "[20.0, 10.0]".into()),
        ("light", "variance".into(), "[0.01, 0.02]".into()),
        ("light", "rotation_deg".into(), "10.0".into()),
        ("mesh", "shape".into(), "\"box\"".into()),
        ("mesh", "size".into(), "[1.0, 1.0, 1.0]".into()),
        ("mesh", "translate".into(), "[0.0, 0.0, 0.0]".into()),
        ("mesh", "rotate_deg".into(), "[10.0, 20.0, 30.0]".into()),
        ("mesh", "scale".into(), "1.0".into()),
        ("mesh", "material".into(), "\"m\"".into()),
        ("mesh2", "shape".into(), "\"sphere\"".into()),
        ("mesh2", "size".into(), "[0.4, 1.0]".into()),
        ("mesh2", "translate".into(), "[0.5, 0.5, -0.5]".into()),
        ("mesh2", "material".into(), "\"d\"".into()),
        ("material.m", "color".into(), "[0.9, 0.8, 0.7]".into()),
        ("material.m", "opacity".into(), "0.5".into()),
        ("material.m", "reference_length".into(), "0.5".into()),
        (
            "material.m",
            "specular".into(),
            "{ strength = 0.4, exponent = 8 }".into(),
        ),
        (
            "material.d",
            "detail".into(),
            "{ kind = \"fbm\", frequency = 3.0, lacunarity = 2.0, gain = 0.5, time = 0.5 }".into(),
        ),
        (
            "material.d",
            "gradient".into(),
            "[[0.0, 1.0, 0.5, 0.2, 0.0], [1.0, 0.2, 0.4, 1.0, 0.8]]".into(),
        ),
    ];
    for line in &mut lines {
        if line.0 != table {
            continue;
        }
        if key == "slab_distance" && line.1 == "slabs" {
            *line = (line.0, key.into(), value.into());
        } else if line.1 == key {
            line.2 = value.into();
        } else if let Some((inline, field)) = key.split_once('.')
            && line.1 == inline
        {
            // A field of an inline table: replace `field = …` up to the next comma or brace.
            let start = line.2.find(&format!("{field} = ")).unwrap() + field.len() + 3;
            let end = start + line.2[start..].find([',', ' ']).unwrap();
            line.2.replace_range(start..end, value);
        } else if let Some(inner) = key.strip_prefix("gradient[0]")
            && line.1 == "gradient"
        {
            assert!(inner.is_empty());
            line.2 = format!("[{value}, [1.0, 0.2, 0.4, 1.0, 0.8]]");
        }
    }
    let mut text = String::new();
    let mut current = "";
    for (table, key, value) in &lines {
        if *table != current {
            text += &match *table {
                "light" | "mesh" | "mesh2" => "[[mesh]]\n".replace("mesh", &table.replace('2', "")),
                t => format!("[{t}]\n"),
            };
            current = table;
        }
        text += &format!("{key} = {value}\n");
    }
    text
}

/// A number from the whole f64 range: the extremes, subnormals, ±0, overflow-to-f32 values, and
/// arbitrary finite values.
fn extreme_number() -> impl Strategy<Value = f64> {
    prop_oneof![
        prop::sample::select(vec![
            f64::MAX,
            -f64::MAX,
            1.7e308,
            1e308,
            -1e308,
            1e307,
            1e39,
            3.5e38,
            1e30,
            1e-30,
            1e-39,
            1e-300,
            -1e-300,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            0.0,
            -0.0,
            1.0,
            89.999999,
            -89.999999,
        ]),
        any::<f64>().prop_filter("finite", |v| v.is_finite()),
        -1e3f64..1e3,
    ]
}

/// Renders scene text: `Err(message)` for a refused scene, else checks every value is finite.
fn render_extreme(text: &str) -> Result<(), String> {
    let scene = Scene::parse(text, "extreme.toml", Path::new(".")).map_err(|e| e.to_string())?;
    let req = RenderRequest {
        threads: 1,
        memory_budget: 256 << 20,
        ..RenderRequest::default()
    };
    let r = render(&scene, &req).map_err(|e| e.to_string())?;
    assert!(
        r.image.data.iter().all(|v| v.is_finite()),
        "non-finite pixel\n{text}"
    );
    assert!(r.light.iter().all(|v| v.is_finite()), "light\n{text}");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1024, .. ProptestConfig::default() })]

    /// One scene number (or one component of an array) set to any finite f64: never a panic;
    /// either a clear error naming the key or a render whose pixels are all finite.
    #[test]
    fn extreme_numbers_give_a_clear_error_or_a_finite_image(
        which in any::<prop::sample::Index>(),
        component in any::<prop::sample::Index>(),
        v in extreme_number(),
    ) {
        let (table, key, n) = NUMERIC_KEYS[which.index(NUMERIC_KEYS.len())];
        let c = component.index(n);
        let value = if n == 1 {
            format!("{v:?}")
        } else {
            let base: Vec<String> = (0..n)
                .map(|i| if i == c { format!("{v:?}") } else if key == "gradient[0]" && i == 0 { "0.0".into() } else { "0.5".into() })
                .collect();
            format!("[{}]", base.join(", "))
        };
        let text = extreme_scene(table, key, &value);
        let outcome = std::panic::catch_unwind(|| render_extreme(&text));
        match outcome {
            Err(_) => prop_assert!(false, "panicked on {}.{} = {}\n{}", table, key, value, text),
            Ok(Err(msg)) => {
                prop_assert!(msg.starts_with("extreme.toml") || !msg.is_empty(), "{}", msg);
                prop_assert!(!msg.contains("NaN") || msg.contains(key), "{}", msg);
            }
            Ok(Ok(())) => {}
        }
    }
}

#[test]
fn the_extreme_value_base_scene_renders() {
    render_extreme(&extreme_scene("", "", "")).unwrap();
}

// ---------------------------------------------------------------------------------------------
// Hardening regressions: one scene value each, found by an adversarial pass.

/// `extreme_scene` with one key replaced must be refused naming `names` (file and key).
fn assert_scene_refused(table: &str, key: &str, value: &str, names: &str) {
    let text = extreme_scene(table, key, value);
    match Scene::parse(&text, "extreme.toml", Path::new(".")) {
        Ok(_) => panic!("{table}.{key} = {value} was accepted\n{text}"),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("extreme.toml"), "{msg}");
            assert!(
                msg.contains(names),
                "{key} = {value}: must name {names}: {msg}"
            );
        }
    }
}

#[test]
fn huge_finite_distances_and_variances_are_refused_not_panics() {
    assert_scene_refused(
        "sweep",
        "optimal_distance",
        "1.7e308",
        "sweep.optimal_distance",
    );
    assert_scene_refused("sweep", "slab_distance", "1e307", "sweep.slab_distance");
    assert_scene_refused(
        "light",
        "variance",
        "[1e308, 1e308]",
        "light[0].variance[0]",
    );
    // And the planner itself is total: no scene value makes it panic.
    assert!(render_extreme(&extreme_scene("light", "variance", "[1e8, 1e8]")).is_ok());
}

#[test]
fn colours_beyond_f32_are_refused_with_the_representable_range() {
    for (table, key, value, names) in [
        (
            "material.m",
            "color",
            "[1e308, 1.0, 1.0]",
            "material.m.color[0]",
        ),
        (
            "material.m",
            "specular.strength",
            "1e308",
            "material.m.specular.strength",
        ),
        ("light", "color", "[1e39, 1.0, 1.0]", "light[0].color[0]"),
        (
            "image",
            "background",
            "[1e39, 0.0, 0.0]",
            "image.background[0]",
        ),
    ] {
        assert_scene_refused(table, key, value, names);
        let msg = Scene::parse(&extreme_scene(table, key, value), "x.toml", Path::new("."))
            .unwrap_err()
            .to_string();
        assert!(msg.contains("1e4"), "the range is given: {msg}");
    }
    // The largest accepted values still give a finite image.
    render_extreme(&extreme_scene("material.m", "color", "[1e4, 1e4, 1e4]")).unwrap();
    render_extreme(&extreme_scene("light", "color", "[1e4, 1e4, 1e4]")).unwrap();
    render_extreme(&extreme_scene("material.m", "specular.strength", "1e4")).unwrap();
}

#[test]
fn arrays_of_the_wrong_length_and_gradient_indices_are_exact() {
    assert_scene_refused("material.m", "color", "[1.0, 1.0, 1.0, 1.0]", "4");
    assert_scene_refused("light", "tilt_deg", "[1.0, 2.0, 3.0]", "3");
    assert_scene_refused(
        "material.d",
        "gradient[0]",
        "[0.0, 1.0, 0.5, 0.2, 0.0, 1.0]",
        "gradient stop 0",
    );
    // A bad colour at [0][1] is reported at [0][1], not [0][0].
    assert_scene_refused(
        "material.d",
        "gradient[0]",
        "[0.0, -1.0, 0.5, 0.2, 0.0]",
        "material.d.gradient[0][1]",
    );
    assert_scene_refused(
        "material.d",
        "gradient[0]",
        "[0.0, 1.0, 0.5, 1e9, 0.0]",
        "material.d.gradient[0][3]",
    );
}

#[test]
fn kernel_names_are_canonical() {
    use convshadow::common::model::kernel::KernelSpec;
    for bad in [
        "gaussian:+3",
        "ellipse02",
        "ellipse+4",
        "gaussian:03",
        "ellipse",
        "gaussian:",
    ] {
        assert!(bad.parse::<KernelSpec>().is_err(), "{bad} accepted");
    }
    for good in ["gaussian:3", "ellipse2", "ellipse16", "ellipse4:slab"] {
        assert!(good.parse::<KernelSpec>().is_ok(), "{good} refused");
    }
}

#[test]
fn a_huge_direction_is_normalised_and_tiny_slab_distances_print_short() {
    let text = extreme_scene("camera", "direction", "[1e308, 1e308, 1e308]");
    Scene::parse(&text, "x.toml", Path::new(".")).unwrap();
    let msg = Scene::parse(
        &extreme_scene("sweep", "slab_distance", "1e-300"),
        "x.toml",
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(
        msg.contains("sweep.slab_distance") && msg.len() < 200,
        "{msg}"
    );
}
