//! Scene files (TOML) into the model: the raw (serde) form holds exactly the file's keys,
//! strictly typed; [`validate`] turns it into a [`Scene`], naming the file, the key and what was
//! expected for every unknown key, wrong type, missing key or invalid value.

mod camera;
mod lights;
mod overrides;
mod tables;
mod validate;

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

use crate::model::display::Tonemap;
use crate::model::scene::*;
use validate::Validator;

impl Scene {
    /// The embedded default scene.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE_TOML, DEFAULT_SCENE_NAME, Path::new("."))
            .expect("the embedded default scene is valid (tested)")
    }

    /// Parses and validates scene text; `source` names it in messages, `base_dir` resolves paths.
    pub fn parse(text: &str, source: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        // Through `Tables`: a table-typed key given an array is an error, not read in order.
        let validator = Validator { file: source };
        let raw = toml::Deserializer::parse(text)
            .and_then(|d| RawScene::deserialize(tables::Tables(d)))
            .map_err(|e| {
                // A light of an unknown kind may have keys of its own: name the kind, not them.
                unsupported_light_kind(&validator, text)
                    .unwrap_or_else(|| toml_error(source, text, &e))
            })?;
        validator.scene(raw, base_dir)
    }
}

/// The error for the first `[[light]]` whose `kind` is not one the renderer sweeps, if the text
/// is TOML with such a light.
fn unsupported_light_kind(validator: &Validator<'_>, text: &str) -> Option<SceneError> {
    let table: toml::Table = text.parse().ok()?;
    let lights = table.get("light")?.as_array()?;
    lights.iter().enumerate().find_map(|(i, light)| {
        let kind = light.get("kind")?.as_str()?;
        validator.light_kind(i, Some(kind)).err()
    })
}

// ---------------------------------------------------------------------------------------------
// Raw (serde) form: exactly the file's keys, strictly typed.

/// An array of exactly `N` elements (serde's fixed-size arrays would ignore extra ones).
fn exact<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v = Vec::<T>::deserialize(d)?;
    let len = v.len();
    <[T; N]>::try_from(v)
        .map(Some)
        .map_err(|_| D::Error::custom(format!("expected an array of {N} numbers, got {len}")))
}

/// Gradient stops, each exactly `[value, r, g, b, opacity]`.
fn exact_stops<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<[f64; 5]>>, D::Error> {
    let stops = Vec::<Vec<f64>>::deserialize(d)?;
    let mut out = Vec::with_capacity(stops.len());
    for (j, s) in stops.into_iter().enumerate() {
        let len = s.len();
        out.push(<[f64; 5]>::try_from(s).map_err(|_| {
            D::Error::custom(format!(
                "gradient stop {j}: expected 5 numbers [value, r, g, b, opacity], got {len}"
            ))
        })?);
    }
    Ok(Some(out))
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawScene {
    image: RawImage,
    camera: RawCamera,
    sweep: RawSweep,
    #[serde(default)]
    light: Vec<RawLight>,
    #[serde(default)]
    mesh: Vec<RawMesh>,
    #[serde(default)]
    material: BTreeMap<String, RawMaterial>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawImage {
    width: u32,
    height: u32,
    #[serde(default, deserialize_with = "exact")]
    background: Option<[f64; 3]>,
    exposure: Option<f64>,
    tonemap: Option<Tonemap>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    #[serde(default, deserialize_with = "exact")]
    direction: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    up: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    center: Option<[f64; 3]>,
    view_width: Option<f64>,
    projection: Option<String>,
    #[serde(default, deserialize_with = "exact")]
    eye: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    look_at: Option<[f64; 3]>,
    fov_deg: Option<f64>,
    near: Option<f64>,
}

/// `sweep.slabs` as written: an integer or a word (only `"auto"` is valid; checked with the key).
#[derive(Debug)]
enum RawSlabs {
    Count(i64),
    Word(String),
}

impl<'de> Deserialize<'de> for RawSlabs {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = RawSlabs;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an integer slab count or \"auto\"")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<RawSlabs, E> {
                Ok(RawSlabs::Count(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<RawSlabs, E> {
                Ok(RawSlabs::Count(i64::try_from(v).unwrap_or(i64::MAX)))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawSlabs, E> {
                Ok(RawSlabs::Word(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawSweep {
    slabs: Option<RawSlabs>,
    slab_factor: Option<f64>,
    slab_distance: Option<f64>,
    optimal_distance: Option<f64>,
    penumbra: Option<String>,
    kernel: Option<String>,
    jitter: Option<bool>,
    seed: Option<u32>,
    variance_compensation: Option<bool>,
    guard_band: Option<toml::Value>,
    preintegration: Option<bool>,
    media: Option<String>,
    subpixel_shadows: Option<bool>,
    held_lit_side: Option<bool>,
    served_releases: Option<bool>,
    horizon: Option<bool>,
    light_resolution: Option<f64>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawLight {
    kind: Option<String>,
    #[serde(default, deserialize_with = "exact")]
    direction: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    up: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    color: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    tilt_deg: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "exact")]
    variance: Option<[f64; 2]>,
    rotation_deg: Option<f64>,
    pattern: Option<RawPattern>,
    #[serde(default, deserialize_with = "exact")]
    position: Option<[f64; 3]>,
    radius: Option<f64>,
    cone_deg: Option<f64>,
    falloff_deg: Option<f64>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawPattern {
    path: String,
    #[serde(default, deserialize_with = "exact")]
    size: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "exact")]
    center: Option<[f64; 2]>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    shape: String,
    size: Option<Vec<f64>>,
    path: Option<String>,
    #[serde(default, deserialize_with = "exact")]
    translate: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact")]
    rotate_deg: Option<[f64; 3]>,
    scale: Option<f64>,
    material: String,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    #[serde(default, deserialize_with = "exact")]
    color: Option<[f64; 3]>,
    opacity: Option<f64>,
    #[serde(default, deserialize_with = "exact")]
    transport: Option<[f64; 3]>,
    reference_length: Option<f64>,
    detail: Option<RawDetail>,
    texture: Option<RawTexture>,
    #[serde(default, deserialize_with = "exact_stops")]
    gradient: Option<Vec<[f64; 5]>>,
    specular: Option<RawSpecular>,
    phase: Option<RawPhase>,
    surface: Option<String>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawPhase {
    g: f64,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawDetail {
    kind: DetailKind,
    frequency: Option<f64>,
    octaves: Option<u32>,
    lacunarity: Option<f64>,
    gain: Option<f64>,
    time: Option<f64>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawTexture {
    path: String,
    #[serde(default, deserialize_with = "exact")]
    dims: Option<[u32; 3]>,
    #[serde(rename = "type")]
    voxel: Option<VoxelType>,
    #[serde(default, deserialize_with = "exact")]
    window: Option<[f64; 2]>,
    grid: Option<String>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct RawSpecular {
    model: Option<String>,
    strength: Option<f64>,
    exponent: u32,
    f0: Option<f64>,
}

fn toml_error(source: &str, text: &str, e: &toml::de::Error) -> SceneError {
    let (line, col) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
    let line_text = text
        .lines()
        .nth(line.saturating_sub(1))
        .unwrap_or("")
        .trim();
    let key = if line_text.starts_with('[') {
        // A section header: its own name.
        line_text.trim_matches(['[', ']', ' ']).to_string()
    } else {
        line_text
            .split('=')
            .next()
            .filter(|_| line_text.contains('='))
            .map(|k| format!("{}{}", table_prefix(text, line), k.trim()))
            .unwrap_or_default()
    };
    let mut message = e.message().to_string();
    if let Some(near) = did_you_mean(&message) {
        message = format!("{message}; did you mean `{near}`?");
    }
    if line > 0 {
        message = format!("line {line}, column {col}: {message} (in `{line_text}`)");
    }
    SceneError {
        file: source.to_string(),
        key,
        message,
    }
}

/// The table that line `line` (1-based) of `text` is in, as a key prefix: `light[1].` in the
/// second `[[light]]`, `material.m.` under `[material.m]`, nothing before the first header.
fn table_prefix(text: &str, line: usize) -> String {
    let mut prefix = String::new();
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for l in text.lines().take(line.saturating_sub(1)) {
        let l = l.split('#').next().unwrap_or("").trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|r| r.strip_suffix("]]")) {
            let name = name.trim().to_string();
            let n = counts.entry(name.clone()).or_insert(0);
            prefix = format!("{name}[{n}].");
            *n += 1;
        } else if let Some(name) = l.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            prefix = format!("{}.", name.trim());
        }
    }
    prefix
}

/// For serde's `unknown field `X`, expected one of `a`, `b`, …` (or `expected `a` or `b``):
/// the expected name closest to `X`, when at most two edits away (`colr` → `color`).
fn did_you_mean(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    let (unknown, rest) = rest.split_once('`')?;
    let (_, expected) = rest.split_once("expected")?;
    let candidates = expected.split('`').skip(1).step_by(2);
    candidates
        .map(|c| (edit_distance(unknown, c), c))
        .filter(|&(d, c)| d > 0 && d <= 2 && d < c.chars().count())
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c.to_string())
}

/// Levenshtein distance between `a` and `b`, in characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1)
                .min(row[j] + 1)
                .min(diagonal + usize::from(ca != cb));
            diagonal = above;
        }
    }
    row[b.len()]
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}
