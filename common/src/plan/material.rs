//! A material's per-render tables: the transfer function (colour, slab opacity and attenuation
//! over detail values), the pre-integration table, the specular plan, built once on the host
//! for a slab thickness.

use std::sync::Arc;

use crate::contract::files::TextureFile;
use crate::model::scene::{MaterialSpec, SpecularModel, SpecularSpec, SurfaceModel};
use crate::pixel::noise::Detail;
use crate::pixel::{texture3d::TextureError, volume::Volume};

/// Entries of a material's transfer-function table over detail values [0, 1].
pub const TF_SIZE: usize = 256;
/// Entries per axis of a pre-integration table: detail values [0, 1] at a slab's front face
/// × at its back face (see [`MaterialPlan::pre`]).
pub const PI_SIZE: usize = 128;
/// Sub-steps per unit of detail value when a pre-integration entry is integrated on the host:
/// a segment from front value `f` to back value `b` is cut into ⌈|b − f| · 512⌉ (at least
/// [`PI_MIN_STEPS`]) thin slabs of constant value, so a gradient feature 0.05 wide gets at least
/// 25.
pub const PI_STEPS_PER_UNIT: f64 = 512.0;
/// The fewest thin slabs a pre-integration entry is integrated over, also for a constant value
/// (`front == back`): the slab's self-shadowing is integrated alike everywhere in the table.
pub const PI_MIN_STEPS: f64 = 16.0;
/// The length a material's opacity is given for when it sets no `reference_length`: one world
/// unit, so that opacity is per unit length (as extinction is in Mitsuba or pbrt) and a material
/// looks the same at any slab count. (It was the slab distance, which made the same material
/// more opaque the fewer the slabs.)
pub const DEFAULT_REFERENCE_LENGTH: f64 = 1.0;

/// One transfer-function entry: colour, slab opacity, and per-channel attenuation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TfEntry {
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Opacity of one slab, `1 − (1 − α)^(e/e_ref)`.
    pub alpha: f32,
    /// Light attenuation per channel, `1 − α_slab·(1 − τ)`.
    pub attenuation: [f32; 3],
}

/// A material's per-render tables.
#[derive(Clone, Debug)]
pub struct MaterialPlan {
    /// Transfer function: `TF_SIZE` entries for detail materials, 1 for constant ones.
    pub tf: Vec<TfEntry>,
    /// With `sweep.preintegration`, for detail materials: the pre-integrated table, `PI_SIZE ×
    /// PI_SIZE` entries at `front · PI_SIZE + back` (front and back the detail values at the
    /// slab's faces, `i / (PI_SIZE − 1)`): the colour, opacity and attenuation of one slab whose
    /// detail varies linearly from front to back ([`preintegrated_entry`]). `None`: one sample.
    pub pre: Option<Vec<TfEntry>>,
    /// Procedural detail, if any.
    pub detail: Option<Detail>,
    /// 3D texture, if any (dense, or bricked: OpenVDB; sampled at normalised object coordinates).
    pub texture: Option<Arc<Volume>>,
    /// The texture's physical extent (NIfTI: dims · spacing, OpenVDB: dims · voxel size), whose
    /// aspect its mapping keeps; `None` (raw textures): stretched to the mesh's bounds.
    pub texture_extent: Option<[f64; 3]>,
    /// The specular highlight at crossed surfaces, if any.
    pub specular: Option<SpecularPlan>,
    /// Whether crossed opaque surfaces are shaded with the Lambert cosine (`surface =
    /// "lambert"`); false: flat (the medium's model everywhere).
    pub lambert: bool,
    /// Per light: the light's colour times this material's phase function at the light's
    /// scattering angle ([`crate::plan::phase_factor`]); exactly the light's colour for an isotropic medium
    /// (g = 0). Shading sums `Iin ⊙ light_color`; the specular term uses the bare colour.
    pub light_color: Vec<[f32; 3]>,
}

impl MaterialPlan {
    /// Whether every slab of this material takes out all light: attenuation exactly 0 in every
    /// channel of every transfer-function entry (and pre-integrated entry). Such a material's
    /// surfaces are held ([`crate::plan::RenderPlan::surface_hold`]).
    pub fn blocks_light(&self) -> bool {
        let blocks = |t: &TfEntry| t.attenuation == [0.0; 3];
        self.tf.iter().all(blocks) && self.pre.iter().flatten().all(blocks)
    }
}

/// A material's specular highlight, as the shading stage evaluates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularPlan {
    /// Which model.
    pub model: SpecularModel,
    /// The factor in front of the lobe: Blinn–Phong's strength; for Ashikmin–Shirley the
    /// strength times the normalisation (e + 1)/(8π), computed in f64.
    pub scale: f32,
    /// The lobe's exponent (repeated squaring).
    pub exponent: u32,
    /// Ashikmin–Shirley: reflectance at normal incidence (Schlick's Fresnel term); 0 for
    /// Blinn–Phong.
    pub f0: f32,
}

impl SpecularPlan {
    /// The plan of a material's `specular` table.
    pub fn new(s: &SpecularSpec) -> SpecularPlan {
        match s.model {
            SpecularModel::BlinnPhong => SpecularPlan {
                model: s.model,
                scale: s.strength,
                exponent: s.exponent,
                f0: 0.0,
            },
            SpecularModel::AshikminShirley { f0 } => SpecularPlan {
                model: s.model,
                scale: (f64::from(s.strength) * (f64::from(s.exponent) + 1.0)
                    / (8.0 * std::f64::consts::PI)) as f32,
                exponent: s.exponent,
                f0,
            },
        }
    }
}

/// Colours below 2^-24 become 0, so products in shading never approach the subnormal range.
pub(crate) fn flush_tiny(c: f32) -> f32 {
    if c < 1.0 / 16_777_216.0 { 0.0 } else { c }
}

/// The light a slab of opacity `alpha` (< 1) and transport `tau` lets through, per channel:
/// `(1 − α)^(1 − τ)`, the medium's transmittance `e^(−(1 − τ)·κ·e)` over the slab (κ its
/// extinction), so that slabs compose exactly: two half slabs let through what one whole slab
/// does, whatever τ (the first-order `1 − α·(1 − τ)` did not: its error grew with the slab
/// thickness). Opacity 1 (a surface, not a medium) and a thin shell keep `1 − α·(1 − τ)`.
pub(crate) fn medium_transmittance(alpha: f64, tau: f64) -> f64 {
    (1.0 - alpha).powf(1.0 - tau)
}

/// How a material's slab lets the light through: as a medium (`(1 − α)^(1 − τ)`, see
/// `medium_transmittance`) or as a filter (`1 − α·(1 − τ)`: opacity 1, a thin shell's
/// crossing, and every slab with `sweep.media = "first-order"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Passes {
    /// A slab of a closed mesh's medium (`sweep.media = "second-order"`).
    Medium,
    /// A filter: a thin shell's crossing (one reference length of the material), or the paper's
    /// first-order slab.
    Filter,
}

impl Passes {
    /// `(1 − α)^(1 − τ)` for a medium of opacity below 1, else `1 − α·(1 − τ)`.
    fn attenuation(self, alpha: f64, tau: f64) -> f64 {
        if self == Passes::Medium && alpha < 1.0 {
            medium_transmittance(alpha, tau)
        } else {
            1.0 - alpha * (1.0 - tau)
        }
    }
}

/// The transfer-function entry for colour `c`, opacity `a`, transport `tau`, thickness ratio.
pub(crate) fn tf_entry(c: [f64; 3], a: f64, tau: [f64; 3], ratio: f64, passes: Passes) -> TfEntry {
    let alpha = 1.0 - (1.0 - a).powf(ratio);
    let alpha = if alpha < 1.0 / 16_777_216.0 {
        0.0
    } else {
        alpha.min(1.0)
    };
    TfEntry {
        color: c.map(|v| flush_tiny(v as f32)),
        alpha: alpha as f32,
        attenuation: tau.map(|t| passes.attenuation(alpha, t) as f32),
    }
}

/// The pre-integrated entry of a slab of thickness ratio `ratio` (= e / reference length) whose
/// detail value runs linearly from `front` to `back` (Engel, Kraus & Ertl 2001; Patel et al.
/// 2013 §7). The slab is cut into `n` = max(16, ⌈|back − front| · [`PI_STEPS_PER_UNIT`]⌉) thin
/// slabs of constant value (their midpoints' gradient colour `c_i` and opacity), each of
/// opacity `a_i = 1 − (1 − α)^(ratio / n)` and light attenuation `(1 − a_i)^(1 − τ)` (`passes`:
/// [`Passes::Filter`] has the first-order `1 − a_i·(1 − τ)`), and
/// composited front to back as the sweep would composite `n` slabs: opacity `A = 1 − Π(1 − a_i)`,
/// colour `Σ T_i·a_i·c_i·L_i` with `T_i` the view's and `L_i` the light's transmittance through
/// the thin slabs before i (the light entering the slab at its front, attenuated in the pixel's
/// column: the slab shadows itself as thin slabs would), attenuation `Π(1 − a_i·(1 − τ))`. The
/// entry keeps the sweep's single-sample form: colour = that sum / A (the sweep composites
/// `A·colour` times the entering light).
pub fn preintegrated_entry(
    m: &MaterialSpec,
    ratio: f64,
    front: f64,
    back: f64,
    passes: Passes,
) -> TfEntry {
    let n = ((back - front).abs() * PI_STEPS_PER_UNIT)
        .ceil()
        .max(PI_MIN_STEPS) as usize;
    let mut view = 1.0f64;
    let mut light = [1.0f64; 3];
    let mut sum = [0.0f64; 3];
    let mut mean = [0.0f64; 3];
    for i in 0..n {
        let v = front + (back - front) * ((i as f64 + 0.5) / n as f64);
        let (c, a) = gradient_at(m, v);
        let a_i = if a >= 1.0 {
            1.0
        } else {
            1.0 - (1.0 - a).powf(ratio / n as f64)
        };
        for k in 0..3 {
            sum[k] += view * a_i * c[k] * light[k];
            mean[k] += c[k] / n as f64;
            light[k] *= passes.attenuation(a_i, m.transport[k]);
        }
        view *= 1.0 - a_i;
    }
    let alpha = 1.0 - view;
    let alpha = if alpha < 1.0 / 16_777_216.0 {
        0.0
    } else {
        alpha.min(1.0)
    };
    let color = if alpha > 0.0 {
        sum.map(|p| p / alpha)
    } else {
        mean
    };
    TfEntry {
        color: color.map(|v| flush_tiny(v as f32)),
        alpha: alpha as f32,
        attenuation: light.map(|t| t as f32),
    }
}

/// The pre-integration table of a detail material ([`MaterialPlan::pre`]).
pub(crate) fn preintegration_table(m: &MaterialSpec, ratio: f64, passes: Passes) -> Vec<TfEntry> {
    let step = 1.0 / (PI_SIZE - 1) as f64;
    let mut table = Vec::with_capacity(PI_SIZE * PI_SIZE);
    for f in 0..PI_SIZE {
        for b in 0..PI_SIZE {
            table.push(preintegrated_entry(
                m,
                ratio,
                f as f64 * step,
                b as f64 * step,
                passes,
            ));
        }
    }
    table
}

/// Builds a material's tables for slab thickness `e` (with the pre-integration table when
/// `preintegration` is on and the material has detail).
pub(crate) fn material_plan(
    m: &MaterialSpec,
    e: f64,
    passes: Passes,
    preintegration: bool,
    texture: Option<TextureFile>,
) -> Result<MaterialPlan, TextureError> {
    let ratio = e / m.reference_length.unwrap_or(DEFAULT_REFERENCE_LENGTH);
    let tf = if m.gradient.is_empty() {
        vec![tf_entry(m.color, m.opacity, m.transport, ratio, passes)]
    } else {
        (0..TF_SIZE)
            .map(|i| {
                let v = i as f64 / (TF_SIZE - 1) as f64;
                let (c, a) = gradient_at(m, v);
                tf_entry(c, a, m.transport, ratio, passes)
            })
            .collect()
    };
    let detail = m.detail.as_ref().map(|d| {
        Detail::new(
            d.kind,
            d.frequency as f32,
            d.octaves,
            d.lacunarity as f32,
            d.gain as f32,
            d.time.map(|t| t as f32),
        )
    });
    let (texture, texture_extent) = match (&m.texture, texture) {
        (Some(_), Some(t)) => (Some(t.texture), t.extent),
        (Some(t), None) => {
            return Err(TextureError::NotRead {
                path: t.path.clone(),
            });
        }
        (None, _) => (None, None),
    };
    let pre =
        (preintegration && !m.gradient.is_empty()).then(|| preintegration_table(m, ratio, passes));
    Ok(MaterialPlan {
        tf,
        pre,
        detail,
        texture,
        texture_extent,
        specular: m.specular.as_ref().map(SpecularPlan::new),
        lambert: m.surface == SurfaceModel::Lambert,
        light_color: Vec::new(),
    })
}

/// The gradient's colour and opacity at value `v` (piecewise linear, constant beyond the ends).
pub(crate) fn gradient_at(m: &MaterialSpec, v: f64) -> ([f64; 3], f64) {
    let g = &m.gradient;
    if v <= g[0].value {
        return (g[0].color, g[0].opacity);
    }
    for w in g.windows(2) {
        if v <= w[1].value {
            let span = w[1].value - w[0].value;
            let t = if span > 0.0 {
                (v - w[0].value) / span
            } else {
                1.0
            };
            let lerp = |a: f64, b: f64| a + t * (b - a);
            return (
                [
                    lerp(w[0].color[0], w[1].color[0]),
                    lerp(w[0].color[1], w[1].color[1]),
                    lerp(w[0].color[2], w[1].color[2]),
                ],
                lerp(w[0].opacity, w[1].opacity),
            );
        }
    }
    let last = g[g.len() - 1];
    (last.color, last.opacity)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_opacity_correction_composes() {
        // Two slabs of half the reference length let through what one reference slab does.
        let half = tf_entry([1.0; 3], 0.6, [0.0; 3], 0.5, Passes::Medium);
        let full = tf_entry([1.0; 3], 0.6, [0.0; 3], 1.0, Passes::Medium);
        let through_two = (1.0 - f64::from(half.alpha)).powi(2);
        assert!((through_two - (1.0 - f64::from(full.alpha))).abs() < 1e-6);
        // Transport 1 lets the light through untouched; a shell is a filter, 1 − α·(1 − τ).
        let clear = tf_entry([1.0; 3], 0.9, [1.0, 0.0, 0.5], 1.0, Passes::Filter);
        assert_eq!(clear.attenuation[0], 1.0);
        assert!((clear.attenuation[1] - 0.1).abs() < 1e-6);
        assert!((clear.attenuation[2] - 0.55).abs() < 1e-6);
        // A medium's slab: (1 − α)^(1 − τ), so that its halves compose exactly for any τ.
        let tau = [1.0, 0.0, 0.5];
        let half = tf_entry([1.0; 3], 0.9, tau, 0.5, Passes::Medium);
        let full = tf_entry([1.0; 3], 0.9, tau, 1.0, Passes::Medium);
        for (k, t) in tau.iter().enumerate() {
            let expected = 0.1f64.powf(1.0 - t);
            assert!((f64::from(full.attenuation[k]) - expected).abs() < 1e-6);
            let two = f64::from(half.attenuation[k]).powi(2);
            assert!((two - expected).abs() < 1e-6, "channel {k}");
        }
    }

    /// A detail material whose gradient is the given stops (value, grey colour, opacity).
    fn graded(stops: &[(f64, f64, f64)], transport: [f64; 3]) -> MaterialSpec {
        MaterialSpec {
            name: "m".into(),
            color: [1.0; 3],
            opacity: 1.0,
            transport,
            reference_length: None,
            detail: None,
            texture: None,
            gradient: stops
                .iter()
                .map(|&(value, c, opacity)| crate::model::scene::GradientStop {
                    value,
                    color: [c; 3],
                    opacity,
                })
                .collect(),
            specular: None,
            surface: crate::model::scene::SurfaceModel::Lambert,
            phase_g: 0.0,
        }
    }

    #[test]
    fn a_constant_preintegrated_slab_matches_the_closed_form_of_its_thin_slabs() {
        // Constant value: 16 thin slabs of opacity a = 1 − (1 − α)^(r/16); the slab passes
        // T = (1 − α)^r of the view. With τ = 0 the light passes the same, so thin slab i is
        // seen through (1 − a)^i and lit through (1 − a)^i: Σ a·(1 − a)^{2i}·c
        // = c·a·(1 − T²)/(1 − (1 − a)²), i.e. colour = c·(1 + T)/(2 − a) after dividing by
        // A = 1 − T. With τ = 1 the light is not attenuated and the colour is c itself.
        let (alpha, r, c) = (0.6, 0.5, 0.8);
        let m = graded(&[(0.0, c, alpha), (1.0, c, alpha)], [0.0; 3]);
        let e = preintegrated_entry(&m, r, 0.3, 0.3, Passes::Filter);
        let t = (1.0f64 - alpha).powf(r);
        let a = 1.0 - (1.0f64 - alpha).powf(r / 16.0);
        assert!((f64::from(e.alpha) - (1.0 - t)).abs() < 1e-6, "{e:?}");
        assert!((f64::from(e.color[0]) - c * (1.0 + t) / (2.0 - a)).abs() < 1e-6);
        assert!((f64::from(e.attenuation[1]) - t).abs() < 1e-6);
        let clear = preintegrated_entry(
            &graded(&[(0.0, c, alpha)], [1.0; 3]),
            r,
            0.3,
            0.3,
            Passes::Filter,
        );
        assert!((f64::from(clear.color[2]) - c).abs() < 1e-6);
        assert_eq!(clear.attenuation, [1.0; 3]);
        assert!((f64::from(clear.alpha) - (1.0 - t)).abs() < 1e-6);
    }

    #[test]
    fn a_preintegrated_slab_is_its_two_halves_composited() {
        // Front 0.2 → back 0.8 over a gradient with a narrow band: 308 thin slabs; each half
        // (0.2 → 0.5, 0.5 → 0.8, half the thickness) is 154 of the same thin slabs. Compositing
        // the halves as the sweep composites slabs — the second seen through the first's opacity
        // and lit through its attenuation — must give the whole slab.
        let m = graded(
            &[
                (0.0, 0.2, 0.0),
                (0.45, 0.9, 0.0),
                (0.5, 0.5, 0.9),
                (0.55, 0.1, 0.0),
            ],
            [0.3, 0.6, 0.9],
        );
        let r = 2.0;
        let whole = preintegrated_entry(&m, r, 0.2, 0.8, Passes::Medium);
        let (h1, h2) = (
            preintegrated_entry(&m, r / 2.0, 0.2, 0.5, Passes::Medium),
            preintegrated_entry(&m, r / 2.0, 0.5, 0.8, Passes::Medium),
        );
        let (a1, a2) = (f64::from(h1.alpha), f64::from(h2.alpha));
        let alpha = 1.0 - (1.0 - a1) * (1.0 - a2);
        assert!(whole.alpha > 0.2, "the band is crossed: {whole:?}");
        assert!((f64::from(whole.alpha) - alpha).abs() < 1e-6);
        for k in 0..3 {
            let l1 = f64::from(h1.attenuation[k]);
            let color = a1 * f64::from(h1.color[k]) + (1.0 - a1) * l1 * a2 * f64::from(h2.color[k]);
            assert!(
                (f64::from(whole.color[k]) * alpha - color).abs() < 1e-6,
                "channel {k}: {whole:?} vs {h1:?} + {h2:?}"
            );
            let att = l1 * f64::from(h2.attenuation[k]);
            assert!((f64::from(whole.attenuation[k]) - att).abs() < 1e-6);
        }
        // The band is inside the slab, not at its faces: one sample at either face misses it.
        assert_eq!(gradient_at(&m, 0.2).1, 0.0);
        assert_eq!(gradient_at(&m, 0.8).1, 0.0);
    }
}
