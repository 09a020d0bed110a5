//! Extra output layers ("arbitrary output variables", `render --aov`): the first-hit depth from
//! the LDI, and each light's own contribution to the image.
//!
//! The image is linear in the lights' colours: a light's colour enters only the shading
//! (`RenderPlan::lights[l].color`, the specular term, and every material's
//! `light_color[l]`, the colour times the phase function), and no opacity, attenuation, light
//! buffer, kernel table, hash or guard band depends on it. So light `l`'s contribution is the
//! sweep of the same plan with every other light's colour and the background set to 0: the same
//! grid, tables, per-light hashes and light indices (removing the other lights would change the
//! light indices the hashes use and the automatic guard band). Each light layer costs one more
//! sweep. The layers sum to the image's composited colour `C`; the image is
//! `C + (1 − A)·background`, so `Σ_l layer_l + (1 − A)·background` is the image up to float
//! rounding (the sum over lights is taken in a different order).

use std::sync::atomic::AtomicBool;

use convshadow_common::contract::ldi::Ldi;
use convshadow_common::plan::RenderPlan;

use super::{RenderError, check_cancel};

/// One extra output layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    /// The first-hit camera depth per pixel: the camera-space z (world units along the view
    /// direction, from the plane through `camera.center`) of the LDI's first fragment — the
    /// nearest surface of any mesh, opaque or not — at the pixel centre; `+∞` where no mesh
    /// covers the pixel centre. Written as the EXR channel `Z`.
    Depth,
    /// Light N's contribution to the image's RGB (the background excluded). Written as the EXR
    /// channels `lightN.R`, `lightN.G`, `lightN.B`.
    Light(usize),
}

impl Aov {
    /// The layer's name on the command line: `depth`, `light0`, …
    pub fn name(self) -> String {
        match self {
            Aov::Depth => "depth".to_string(),
            Aov::Light(l) => format!("light{l}"),
        }
    }
}

impl std::str::FromStr for Aov {
    type Err = String;

    /// `depth` or `lightN` (N a light index written without sign or leading zero).
    fn from_str(s: &str) -> Result<Aov, String> {
        if s == "depth" {
            return Ok(Aov::Depth);
        }
        if let Some(n) = s.strip_prefix("light")
            && !n.is_empty()
            && n.bytes().all(|b| b.is_ascii_digit())
            && (n == "0" || !n.starts_with('0'))
            && let Ok(l) = n.parse::<usize>()
        {
            return Ok(Aov::Light(l));
        }
        Err(format!(
            "unknown layer {s:?}; expected depth or lightN (N a light index: light0, light1, …)"
        ))
    }
}

/// The first-hit depth of every image pixel ([`Aov::Depth`]), row-major, `width·height`: the
/// LDI's first fragment at the pixel (its grid pixel, the guard band skipped), whose depth is
/// relative to `z_origin`, made camera depth again.
pub fn first_hit_depth(plan: &RenderPlan, ldi: &Ldi, z_origin: f64) -> Vec<f32> {
    let origin = (plan.guard.left as usize, plan.guard.top as usize);
    let image = (plan.width as usize, plan.height as usize);
    first_hit_depth_in(ldi, origin, image, z_origin)
}

/// [`first_hit_depth`] of the `image` = (width, height) pixels at grid pixel `origin` = (left,
/// top) of an LDI (a perspective camera's eye LDI: its image, at (0, 0)).
pub fn first_hit_depth_in(
    ldi: &Ldi,
    (left, top): (usize, usize),
    (iw, ih): (usize, usize),
    z_origin: f64,
) -> Vec<f32> {
    let w = ldi.width as usize;
    let mut out = Vec::with_capacity(iw * ih);
    for y in 0..ih {
        for x in 0..iw {
            let p = (y + top) * w + x + left;
            let (first, end) = (ldi.offsets[p] as usize, ldi.offsets[p + 1] as usize);
            out.push(if first < end {
                (z_origin + f64::from(ldi.depth[first])) as f32
            } else {
                f32::INFINITY
            });
        }
    }
    out
}

/// The light layers of `aovs`, in their order: light l's image is `sweep` of `plan` with every
/// other light's colour and the background 0 ([`LightColors::isolate`]; the plan's colours are
/// given back after each), with a cancel point before each.
pub fn light_layers(
    plan: &mut RenderPlan,
    aovs: &[Aov],
    cancel: Option<&AtomicBool>,
    mut sweep: impl FnMut(&RenderPlan) -> Result<Vec<f32>, RenderError>,
) -> Result<Vec<(usize, Vec<f32>)>, RenderError> {
    let colors = LightColors::of(plan);
    let mut layers = Vec::new();
    for aov in aovs {
        if let Aov::Light(l) = *aov {
            check_cancel(cancel)?;
            colors.isolate(plan, l);
            let layer = sweep(plan);
            colors.restore(plan);
            layers.push((l, layer?));
        }
    }
    Ok(layers)
}

/// The lights' colours and the background of a plan, kept so that the plan can be turned into
/// one light's plan ([`LightColors::isolate`]) and back ([`LightColors::restore`]).
pub struct LightColors {
    lights: Vec<[f32; 3]>,
    materials: Vec<Vec<[f32; 3]>>,
    background: [f32; 3],
}

impl LightColors {
    /// The colours of `plan` as they are.
    pub fn of(plan: &RenderPlan) -> LightColors {
        LightColors {
            lights: plan.lights.iter().map(|l| l.color).collect(),
            materials: plan
                .materials
                .iter()
                .map(|m| m.light_color.clone())
                .collect(),
            background: plan.background,
        }
    }

    /// Sets every light's colour but light `keep`'s, and the background, to 0 in `plan` (whose
    /// colours were taken by [`LightColors::of`]); light `keep` gets its own colour back.
    pub fn isolate(&self, plan: &mut RenderPlan, keep: usize) {
        self.set(plan, Some(keep));
        plan.background = [0.0; 3];
    }

    /// Gives `plan` its colours back.
    pub fn restore(&self, plan: &mut RenderPlan) {
        self.set(plan, None);
        plan.background = self.background;
    }

    /// Every light's colour from `self`, or with `keep`, every other light's 0.
    fn set(&self, plan: &mut RenderPlan, keep: Option<usize>) {
        let pick = |l: usize, c: [f32; 3]| match keep {
            Some(k) if k != l => [0.0; 3],
            _ => c,
        };
        for (l, (light, &c)) in plan.lights.iter_mut().zip(&self.lights).enumerate() {
            light.color = pick(l, c);
        }
        for (m, colors) in plan.materials.iter_mut().zip(&self.materials) {
            for (l, (dst, &c)) in m.light_color.iter_mut().zip(colors).enumerate() {
                *dst = pick(l, c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layer_names_parse_and_print_the_same() {
        for (s, aov) in [
            ("depth", Aov::Depth),
            ("light0", Aov::Light(0)),
            ("light12", Aov::Light(12)),
        ] {
            assert_eq!(s.parse::<Aov>(), Ok(aov));
            assert_eq!(aov.name(), s);
        }
        for bad in [
            "", "Depth", "light", "light-1", "light01", "light+1", "lights", "z",
        ] {
            let e = bad.parse::<Aov>().unwrap_err();
            assert!(e.contains("expected depth or lightN"), "{bad}: {e}");
        }
    }
}
