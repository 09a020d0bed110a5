//! Stage 3, shading: material lookup at one point per slab, detail function, transfer function,
//! light sum, horizon and Lambert cosine at opaque crossings and specular highlight (step 3 of the per-pixel sweep, paper §4.2). Mirrors
//! `gpu/src/shaders/shading.wgsl`.
//!
//! Written once over [`Lane`]: the per-pixel stage (`crate::sweep::pixel`) calls the 1-lane
//! instance, the SIMD path's chunks the 8-lane one. Table look-ups are per
//! lane, arithmetic is on lanes in one fixed order.

use convshadow_common::model::scene::SpecularModel;
use convshadow_common::pixel::hash::{pixel_hash, unit_float};
use convshadow_common::pixel::lane::{Lane, MAX_LANES};
use convshadow_common::plan::horizon::{HORIZON_PER_UNIT, HORIZON_REACH, HORIZON_STEPS};
pub use convshadow_common::plan::point_light::LightTerms;
use convshadow_common::plan::{MaterialPlan, PI_SIZE, RenderPlan, SpecularPlan, TF_SIZE, TfEntry};

use crate::ldi::Ldi;
use crate::parity::NO_CROSSING;

/// Evaluates a material's detail value in [0, 1] at detail coordinates `p` (0 for constant ones).
#[inline]
pub fn detail_value<L: Lane>(material: &MaterialPlan, p: [L; 3]) -> L {
    if let Some(d) = &material.detail {
        d.eval(p)
    } else if let Some(t) = &material.texture {
        t.sample(p)
    } else {
        L::splat(0.0)
    }
}

/// The depth of the one point a slab shades in a pixel: the first surface crossed in the slab
/// (`crossed`, an LDI fragment), else the slab's front plus a hashed jitter (`jitter_row` is the
/// row's jitter hash), else the slab's centre.
#[inline(always)]
pub fn shading_depth(
    plan: &RenderPlan,
    ldi: &Ldi,
    crossed: u32,
    front: f32,
    jitter_row: u32,
    x: usize,
) -> f32 {
    if crossed != NO_CROSSING {
        ldi.depth[crossed as usize]
    } else if plan.jitter {
        front + unit_float(pixel_hash(jitter_row, plan.hash_x(x as u32))) * plan.slab_distance
    } else {
        front + 0.5 * plan.slab_distance
    }
}

/// A transfer-function entry per lane (see [`TfEntry`]).
#[derive(Clone, Copy)]
pub struct TfLanes<L> {
    /// Linear RGB colour.
    pub color: [L; 3],
    /// Opacity of one slab.
    pub alpha: L,
    /// Light attenuation per channel.
    pub attenuation: [L; 3],
}

/// The transfer-function entry of mesh `mesh`'s material at image pixels (x, y) (per lane, see
/// [`RenderPlan::image_xy`]) and
/// relative depth `z`: detail value (0 for constant materials), then the table look-up.
#[inline(always)]
pub fn material_at<L: Lane>(plan: &RenderPlan, mesh: u32, x: L, y: L, z: L) -> TfLanes<L> {
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    let value = if material.tf.len() > 1 {
        detail_at(plan, mesh, x, y, z)
    } else {
        L::splat(0.0)
    };
    transfer(&material.tf, value)
}

/// The detail value of mesh `mesh`'s material at image pixels (x, y) (per lane) and relative
/// depth `z`: a pure function of its inputs, so a value kept from one slab to the next has the
/// bits of a fresh evaluation.
#[inline(always)]
pub fn detail_at<L: Lane>(plan: &RenderPlan, mesh: u32, x: L, y: L, z: L) -> L {
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    let half = L::splat(0.5);
    let (x, y) = (x + half, y + half);
    // A point light's grid: its cell's slab-grid point at this depth.
    let (x, y) = match &plan.projective {
        None => (x, y),
        Some(p) => {
            let s = (L::splat(p.depth_origin) + z) * L::splat(p.per_depth);
            let (cx, cy) = (L::splat(p.centre[0]), L::splat(p.centre[1]));
            (cx + (x - cx) * s, cy + (y - cy) * s)
        }
    };
    let q = to_detail(&plan.mesh_to_detail[mesh as usize], x, y, z);
    detail_value(material, q)
}

/// Looks up a pre-integration table ([`MaterialPlan::pre`]) at detail values `front` and
/// `back`: bilinear between the four nearest entries, first along the back value, then along
/// the front value. Indices are found per lane (truncation clamped to [0, PI_SIZE − 2], as in
/// [`transfer`]), the interpolation runs on lanes.
#[inline(always)]
pub fn pre_transfer<L: Lane>(table: &[TfEntry], front: L, back: L) -> TfLanes<L> {
    let scale = L::splat((PI_SIZE - 1) as f32);
    let (pf, pb) = (front * scale, back * scale);
    let mut index = [0usize; MAX_LANES];
    let (mut if_, mut ib) = ([0.0f32; MAX_LANES], [0.0f32; MAX_LANES]);
    for i in 0..L::LANES {
        let kf = (pf.lane(i) as i32).clamp(0, PI_SIZE as i32 - 2) as usize;
        let kb = (pb.lane(i) as i32).clamp(0, PI_SIZE as i32 - 2) as usize;
        index[i] = kf * PI_SIZE + kb;
        if_[i] = kf as f32;
        ib[i] = kb as f32;
    }
    let ff = pf - L::load(&if_, 0);
    let fb = pb - L::load(&ib, 0);
    // Per-lane entries as 7 planes, for the corners (f, b), (f, b + 1), (f + 1, b), (f + 1, b + 1).
    let mut e = [[[0.0f32; MAX_LANES]; 7]; 4];
    for i in 0..L::LANES {
        let k = index[i];
        for (corner, off) in [0, 1, PI_SIZE, PI_SIZE + 1].into_iter().enumerate() {
            let t = table[k + off];
            let dst = &mut e[corner];
            dst[0][i] = t.color[0];
            dst[1][i] = t.color[1];
            dst[2][i] = t.color[2];
            dst[3][i] = t.alpha;
            dst[4][i] = t.attenuation[0];
            dst[5][i] = t.attenuation[1];
            dst[6][i] = t.attenuation[2];
        }
    }
    let field = |j: usize| {
        let (u00, u01) = (L::load(&e[0][j], 0), L::load(&e[1][j], 0));
        let (u10, u11) = (L::load(&e[2][j], 0), L::load(&e[3][j], 0));
        let lo = u00 + fb * (u01 - u00);
        let hi = u10 + fb * (u11 - u10);
        lo + ff * (hi - lo)
    };
    TfLanes {
        color: [field(0), field(1), field(2)],
        alpha: field(3),
        attenuation: [field(4), field(5), field(6)],
    }
}

/// Maps pixel-grid coordinates and relative depth to a mesh's detail coordinates
/// (row-major 3×4 affine, summed in a fixed order).
#[inline(always)]
pub fn to_detail<L: Lane>(m: &[f32; 12], x: L, y: L, z: L) -> [L; 3] {
    let row = |r: usize| {
        let a = L::splat(m[4 * r]) * x;
        let b = L::splat(m[4 * r + 1]) * y;
        let c = L::splat(m[4 * r + 2]) * z;
        ((a + b) + c) + L::splat(m[4 * r + 3])
    };
    [row(0), row(1), row(2)]
}

/// Looks up the transfer function: linear interpolation between the two nearest entries. The
/// entry index is found per lane, the interpolation runs on lanes.
#[inline(always)]
pub fn transfer<L: Lane>(tf: &[TfEntry], value: L) -> TfLanes<L> {
    if tf.len() == 1 {
        let e = tf[0];
        return TfLanes {
            color: [
                L::splat(e.color[0]),
                L::splat(e.color[1]),
                L::splat(e.color[2]),
            ],
            alpha: L::splat(e.alpha),
            attenuation: [
                L::splat(e.attenuation[0]),
                L::splat(e.attenuation[1]),
                L::splat(e.attenuation[2]),
            ],
        };
    }
    let pos = value * L::splat((TF_SIZE - 1) as f32);
    // Truncation instead of floor: they differ only for negative `pos`, where the clamp to 0
    // makes them agree again (NaN → 0 and ±∞ saturate alike), and SSE2 has no vector floor.
    let mut index = [0usize; MAX_LANES];
    let mut index_f = [0.0f32; MAX_LANES];
    for i in 0..L::LANES {
        let k = (pos.lane(i) as i32).clamp(0, TF_SIZE as i32 - 2) as usize;
        index[i] = k;
        index_f[i] = k as f32;
    }
    let f = pos - L::load(&index_f, 0);
    // Per-lane entries as 7 planes: colour, alpha, attenuation of entry i, then of entry i + 1.
    let mut a = [[0.0f32; MAX_LANES]; 7];
    let mut b = [[0.0f32; MAX_LANES]; 7];
    for i in 0..L::LANES {
        let k = index[i];
        for (dst, e) in [(&mut a, tf[k]), (&mut b, tf[k + 1])] {
            dst[0][i] = e.color[0];
            dst[1][i] = e.color[1];
            dst[2][i] = e.color[2];
            dst[3][i] = e.alpha;
            dst[4][i] = e.attenuation[0];
            dst[5][i] = e.attenuation[1];
            dst[6][i] = e.attenuation[2];
        }
    }
    let field = |j: usize| {
        let (u, v) = (L::load(&a[j], 0), L::load(&b[j], 0));
        u + f * (v - u)
    };
    TfLanes {
        color: [field(0), field(1), field(2)],
        alpha: field(3),
        attenuation: [field(4), field(5), field(6)],
    }
}

/// `x^n` by repeated squaring (multiplications only: no `pow` per pixel; same exponent in every
/// lane).
#[inline(always)]
pub fn powi_by_squaring<L: Lane>(mut x: L, mut n: u32) -> L {
    let mut r = L::splat(1.0);
    while n > 0 {
        if n & 1 == 1 {
            r = r * x;
        }
        x = x * x;
        n >>= 1;
    }
    r
}

/// The normal `n` flipped to face the viewer (who looks along +z: a facing normal has z ≤ 0).
#[inline(always)]
pub fn facing<L: Lane>(n: [L; 3]) -> [L; 3] {
    let s = L::select(n[2].gt(L::splat(0.0)), L::splat(-1.0), L::splat(1.0));
    [s * n[0], s * n[1], s * n[2]]
}

/// `(f₀·v₀ + f₁·v₁) + f₂·v₂`, in that order.
#[inline(always)]
fn dot<L: Lane>(f: [L; 3], v: [f32; 3]) -> L {
    (f[0] * L::splat(v[0]) + f[1] * L::splat(v[1])) + f[2] * L::splat(v[2])
}

/// `max(0, d)` (`d` when d > 0, else 0; NaN gives 0).
#[inline(always)]
fn positive<L: Lane>(d: L) -> L {
    let zero = L::splat(0.0);
    L::select(d.gt(zero), d, zero)
}

/// The Blinn–Phong weight of one light at a facing normal `f` ([`facing`]):
/// `strength · max(0, f·h)^exponent`.
#[inline(always)]
pub fn blinn_phong<L: Lane>(f: [L; 3], h: [f32; 3], strength: f32, exponent: u32) -> L {
    L::splat(strength) * powi_by_squaring(positive(dot(f, h)), exponent)
}

/// The Lambert cosine `max(0, f·l)` of a facing normal `f` and the direction towards a light.
#[inline(always)]
pub fn lambert<L: Lane>(f: [L; 3], to_light: [f32; 3]) -> L {
    positive(dot(f, to_light))
}

/// Whether a crossing of `material`'s surface needs its triangle's normal: for a highlight, the
/// Lambert cosine or the horizon.
#[inline(always)]
pub fn uses_normals(plan: &RenderPlan, material: &MaterialPlan) -> bool {
    material.specular.is_some() || material.lambert || !plan.horizon.is_empty()
}

/// The horizon: the part of a light above the tangent plane of facing normal `f`, Φ(μ/σ) with
/// μ = f·`to_light` and σ² = ((a·fx² + b·fx·fy) + c·fy²) + iso from the light's `spread`
/// ([`convshadow_common::plan::horizon`]), Φ read from `table` by linear interpolation: 1 where
/// μ/σ ≥ its reach, 0 where ≤ −reach; without spread (σ = 0) 1 where μ > 0, else 0. Mirrors
/// `shading.wgsl` `horizon` operation for operation.
#[inline(always)]
pub fn horizon<L: Lane>(table: &[f32], f: [L; 3], to_light: [f32; 3], spread: [f32; 4]) -> L {
    let (zero, one) = (L::splat(0.0), L::splat(1.0));
    let mu = dot(f, to_light);
    let var = ((L::splat(spread[0]) * (f[0] * f[0]) + L::splat(spread[1]) * (f[0] * f[1]))
        + L::splat(spread[2]) * (f[1] * f[1]))
        + L::splat(spread[3]);
    let sharp = L::select(mu.gt(zero), one, zero);
    let soft = var.gt(zero);
    let t = mu / L::select(soft, var, one).sqrt();
    let steps = HORIZON_STEPS as f32;
    let u = (t + L::splat(HORIZON_REACH)) * L::splat(HORIZON_PER_UNIT);
    let below_top = u.lt(L::splat(steps));
    let above_bottom = u.gt(zero);
    let clamped = L::select(below_top, u, L::splat(steps - 1.0));
    let clamped = L::select(above_bottom, clamped, zero);
    let knot = clamped.floor();
    let w = clamped - knot;
    let i = knot.trunc_u32();
    let a = L::gather(table, i);
    let b = L::gather(table, L::u_add(i, L::u_splat(1)));
    let phi = a + (b - a) * w;
    let phi = L::select(below_top, phi, one);
    let phi = L::select(above_bottom, phi, zero);
    L::select(soft, phi, sharp)
}

/// The Ashikmin–Shirley weight of one light (isotropic lobe, Schlick Fresnel) at a facing normal
/// `f`, the cosine included: `a · (f·h)^e · (f·l) / max(f·l, f·v)` with v = (0, 0, −1), so
/// f·v = −f_z, and `a = scale · (b + f0·c)` the light's Fresnel-over-(h·k) constants
/// ([`convshadow_common::plan::fresnel_terms`]) times the normalised strength. Every dot product
/// is clamped at 0; where both cosines are 0 the quotient's denominator is taken as 1 (the
/// numerator is 0 then, so the weight is 0 instead of NaN).
#[inline(always)]
pub fn ashikmin_shirley<L: Lane>(
    f: [L; 3],
    h: [f32; 3],
    to_light: [f32; 3],
    fresnel: [f32; 2],
    sp: &SpecularPlan,
) -> L {
    let zero = L::splat(0.0);
    let nh = positive(dot(f, h));
    let nl = positive(dot(f, to_light));
    let nv = positive(zero - f[2]);
    let den = L::select(nl.gt(nv), nl, nv);
    let den = L::select(den.gt(zero), den, L::splat(1.0));
    let a = sp.scale * (fresnel[0] + sp.f0 * fresnel[1]);
    L::splat(a) * (powi_by_squaring(nh, sp.exponent) * (nl / den))
}

/// The crossed-surface input of [`shade`]: per-lane normals, the lanes that crossed a surface
/// in this slab (the only ones that get a highlight or the Lambert cosine), and the slab
/// opacity at the shading point (the Lambert cosine applies only where it is exactly 1: an
/// opaque crossing).
pub struct Surface<L: Lane> {
    /// Camera-space normal per lane (the crossed fragment's triangle normal, either facing).
    pub normal: [L; 3],
    /// The lanes that crossed a surface.
    pub lanes: L::M,
    /// Slab opacity at the shading point (the transfer-function entry's).
    pub alpha: L,
}

/// The shaded colour `c ⊙ Σ_l (Iin_l ⊙ colour_l · cos_l)` plus specular terms, summed light by
/// light. `colour_l` is `material.light_color[l]`: the light's colour times the material's phase
/// function for that light (the bare colour for isotropic media); the specular term, a surface
/// reflection, uses the bare colour. `cos_l` is the Lambert cosine `max(0, n·l)` in lanes that
/// crossed an opaque surface (slab opacity exactly 1) of a `lambert` material, else exactly 1
/// (so a flat material, a volume sample or a translucent crossing keeps the bits it had
/// without the factor: `x·1 = x`).
///
/// With a `horizon` table (`sweep.horizon`), the light at an opaque crossing is first limited to
/// the part above the surface's tangent plane ([`horizon`]): the smaller of the two for a plain
/// light (its buffer holds the visible part), their product for a pattern's.
///
/// `iin` holds `lights × channels` values; with one channel the light is grey.
#[inline(always)]
pub fn shade<L: Lane>(
    plan: &RenderPlan,
    material: &MaterialPlan,
    color: [L; 3],
    iin: &[L],
    surface: Option<&Surface<L>>,
) -> [L; 3] {
    let terms = |l: usize| LightTerms::of(plan, material, l);
    let lights = material.light_color.len();
    shade_with(
        plan.channels as usize,
        lights,
        terms,
        material,
        color,
        iin,
        surface,
        &plan.horizon,
    )
}

/// [`shade`] with each light's terms given by `terms` (`lights` of them, `ch` channels) and the
/// horizon's table `horizon` (empty: none).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn shade_with<L: Lane>(
    ch: usize,
    lights: usize,
    terms: impl Fn(usize) -> LightTerms,
    material: &MaterialPlan,
    color: [L; 3],
    iin: &[L],
    surface: Option<&Surface<L>>,
    horizon_table: &[f32],
) -> [L; 3] {
    let one = L::splat(1.0);
    let f = surface.map(|sf| facing(sf.normal));
    // The horizon limits the light in lanes that crossed an opaque surface (alpha exactly 1), with
    // a table; `kept`: the others (not crossed: alpha taken as 0).
    let horizon_lanes = match (surface, f) {
        (Some(sf), Some(f)) if !horizon_table.is_empty() => {
            Some((L::select(sf.lanes, sf.alpha, L::splat(0.0)).lt(one), f))
        }
        _ => None,
    };
    // The lanes whose Lambert cosine applies: crossed, and opaque (alpha < 1 keeps 1).
    let diffuse = match (surface, f, material.lambert) {
        (Some(sf), Some(f), true) => Some((sf, f, sf.alpha.lt(one))),
        _ => None,
    };
    let mut sum = [L::splat(0.0); 3];
    for l in 0..lights {
        let light = terms(l);
        let lc = light.light_color;
        let cos = diffuse.map(|(sf, f, translucent)| {
            let d = lambert(f, light.to_light);
            L::select(sf.lanes, L::select(translucent, one, d), one)
        });
        let visible = horizon_lanes.map(|(kept, f)| {
            (
                kept,
                horizon(horizon_table, f, light.to_light, light.spread),
            )
        });
        for (c, s) in sum.iter_mut().enumerate() {
            let i = iin[l * ch + if ch == 1 { 0 } else { c }];
            let i = match visible {
                Some((kept, h)) => {
                    let limited = if light.plain {
                        L::select(i.lt(h), i, h)
                    } else {
                        i * h
                    };
                    L::select(kept, i, limited)
                }
                None => i,
            };
            let t = i * L::splat(lc[c]);
            *s = *s + cos.map_or(t, |k| t * k);
        }
    }
    let mut out = [color[0] * sum[0], color[1] * sum[1], color[2] * sum[2]];
    if let (Some(sf), Some(f), Some(sp)) = (surface, f, material.specular.as_ref()) {
        for l in 0..lights {
            let light = terms(l);
            let w = match sp.model {
                SpecularModel::BlinnPhong => {
                    blinn_phong(f, light.half_vector, sp.scale, sp.exponent)
                }
                SpecularModel::AshikminShirley { .. } => {
                    ashikmin_shirley(f, light.half_vector, light.to_light, light.fresnel, sp)
                }
            };
            for (c, o) in out.iter_mut().enumerate() {
                let i = iin[l * ch + if ch == 1 { 0 } else { c }];
                let lit = *o + w * (i * L::splat(light.color[c]));
                *o = L::select(sf.lanes, lit, *o);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use convshadow_common::plan::horizon::horizon_table;
    use wide::f32x8;

    /// Φ(t) by Simpson's rule on the standard normal density from −12 (independent of the
    /// table's erfc).
    fn phi_by_quadrature(t: f64) -> f64 {
        let (a, n) = (-12.0, 20_000);
        let h = (t - a) / f64::from(n);
        let density = |x: f64| (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let inner: f64 = (1..n)
            .map(|i| density(a + f64::from(i) * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        (density(a) + inner + density(t)) * h / 3.0
    }

    #[test]
    fn the_horizon_is_the_part_of_a_gaussian_light_above_the_tangent_plane() {
        let table = horizon_table();
        // A light tilted (20°, −10°) with σ² = (0.03, 0.015) turned 25°: the variance of f·d
        // for d = (s, −1)/‖(s̄, −1)‖ is fᵀΣf/‖(s̄, −1)‖², written out here in f64.
        let (tilt, var, rot) = ([20.0f64, -10.0], [0.03, 0.015], 25.0f64);
        let s = [tilt[0].to_radians().tan(), tilt[1].to_radians().tan()];
        let norm = (s[0] * s[0] + s[1] * s[1] + 1.0).sqrt();
        let to_light = [s[0] / norm, s[1] / norm, -1.0 / norm];
        let spread = convshadow_common::plan::horizon::directional_spread(tilt, var, rot);
        let (sn, cs) = rot.to_radians().sin_cos();
        let cov = [
            [
                cs * cs * var[0] + sn * sn * var[1],
                cs * sn * (var[0] - var[1]),
            ],
            [
                cs * sn * (var[0] - var[1]),
                sn * sn * var[0] + cs * cs * var[1],
            ],
        ];
        let mut worst = 0.0f64;
        for k in 0..400 {
            // Facing normals (z ≤ 0) all round the terminator.
            let (a, b) = (f64::from(k) * 0.157, 0.05 + f64::from(k % 20) * 0.078);
            let n = [b.sin() * a.cos(), b.sin() * a.sin(), -b.cos()];
            let mu = (n[0] * to_light[0] + n[1] * to_light[1]) + n[2] * to_light[2];
            let v =
                (n[0] * n[0] * cov[0][0] + 2.0 * n[0] * n[1] * cov[0][1] + n[1] * n[1] * cov[1][1])
                    / (norm * norm);
            let expected = phi_by_quadrature(mu / v.sqrt());
            let f = n.map(|c| c as f32);
            let got = horizon::<f32>(&table, f, to_light.map(|c| c as f32), spread);
            worst = worst.max((f64::from(got) - expected).abs());
            // The SIMD lanes give the same bits.
            let lanes = horizon::<f32x8>(
                &table,
                f.map(f32x8::splat),
                to_light.map(|c| c as f32),
                spread,
            );
            assert_eq!(lanes.lane(3).to_bits(), got.to_bits());
        }
        assert!(worst < 2e-5, "largest difference from Φ: {worst}");
    }

    #[test]
    fn without_spread_the_horizon_is_the_side_of_the_tangent_plane() {
        let table = horizon_table();
        let to_light = [0.0, 0.6, -0.8];
        let hard = [0.0; 4];
        let facing_light = horizon::<f32>(&table, [0.0, 0.0, -1.0], to_light, hard);
        let away = horizon::<f32>(&table, [0.0, -1.0, -0.01], to_light, hard);
        assert_eq!((facing_light, away), (1.0, 0.0));
        // Far beyond the table's reach either way: exactly 1 and 0.
        let wide = [0.0, 0.0, 0.0, 1e-6];
        assert_eq!(
            horizon::<f32>(&table, [0.0, 0.0, -1.0], to_light, wide),
            1.0
        );
        assert_eq!(
            horizon::<f32>(&table, [0.0, -1.0, 0.0], to_light, wide),
            0.0
        );
    }
}
