//! Stage 3, shading: material lookup at one point per slab, detail function, transfer function,
//! light sum and specular highlight (DESIGN §2 step 3, paper §4.2). Mirrors
//! `gpu/src/shaders/shading.wgsl`.

use convshadow_common::hash::{pixel_hash, unit_float};
use convshadow_common::plan::{MaterialPlan, RenderPlan, TF_SIZE, TfEntry};
use wide::f32x8;

use crate::ldi::Ldi;
use crate::parity::NO_CROSSING;

/// Evaluates a material's detail value in [0, 1] at detail coordinates `p` (0 for constant ones).
#[inline]
pub fn detail_value(material: &MaterialPlan, p: [f32; 3]) -> f32 {
    if let Some(d) = &material.detail {
        d.eval(p)
    } else if let Some(t) = &material.texture {
        t.sample(p)
    } else {
        0.0
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
        front + unit_float(pixel_hash(jitter_row, x as u32)) * plan.slab_distance
    } else {
        front + 0.5 * plan.slab_distance
    }
}

/// The transfer-function entry of mesh `mesh`'s material at grid pixel (x, y) and relative depth
/// `z`: detail value (0 for constant materials), then the table look-up.
#[inline(always)]
pub fn material_at(plan: &RenderPlan, mesh: u32, x: usize, y: usize, z: f32) -> TfEntry {
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    let value = if material.tf.len() > 1 {
        let q = to_detail(
            &plan.mesh_to_detail[mesh as usize],
            x as f32 + 0.5,
            y as f32 + 0.5,
            z,
        );
        detail_value(material, q)
    } else {
        0.0
    };
    transfer(&material.tf, value)
}

/// Maps pixel-grid coordinates and relative depth to a mesh's detail coordinates
/// (row-major 3×4 affine, summed in a fixed order).
#[inline(always)]
pub fn to_detail(m: &[f32; 12], x: f32, y: f32, z: f32) -> [f32; 3] {
    let row = |r: usize| {
        let a = m[4 * r] * x;
        let b = m[4 * r + 1] * y;
        let c = m[4 * r + 2] * z;
        ((a + b) + c) + m[4 * r + 3]
    };
    [row(0), row(1), row(2)]
}

/// Looks up the transfer function: linear interpolation between the two nearest entries.
#[inline(always)]
pub fn transfer(tf: &[TfEntry], value: f32) -> TfEntry {
    if tf.len() == 1 {
        return tf[0];
    }
    let pos = value * (TF_SIZE - 1) as f32;
    let i = (pos.floor() as i32).clamp(0, TF_SIZE as i32 - 2) as usize;
    let f = pos - i as f32;
    let (a, b) = (tf[i], tf[i + 1]);
    let lerp = |u: f32, v: f32| u + f * (v - u);
    TfEntry {
        color: [
            lerp(a.color[0], b.color[0]),
            lerp(a.color[1], b.color[1]),
            lerp(a.color[2], b.color[2]),
        ],
        alpha: lerp(a.alpha, b.alpha),
        attenuation: [
            lerp(a.attenuation[0], b.attenuation[0]),
            lerp(a.attenuation[1], b.attenuation[1]),
            lerp(a.attenuation[2], b.attenuation[2]),
        ],
    }
}

/// `x^n` by repeated squaring (multiplications only: no `pow` per pixel).
#[inline(always)]
pub fn powi_by_squaring(mut x: f32, mut n: u32) -> f32 {
    let mut r = 1.0f32;
    while n > 0 {
        if n & 1 == 1 {
            r *= x;
        }
        x *= x;
        n >>= 1;
    }
    r
}

/// Specular weight of one light at a surface with camera-space normal `n` (flipped to face the
/// viewer): `strength · max(0, n·h)^exponent`.
#[inline(always)]
pub fn specular(n: [f32; 3], h: [f32; 3], strength: f32, exponent: u32) -> f32 {
    let s = if n[2] > 0.0 { -1.0f32 } else { 1.0 };
    let d = ((s * n[0]) * h[0] + (s * n[1]) * h[1]) + (s * n[2]) * h[2];
    let d = if d > 0.0 { d } else { 0.0 };
    strength * powi_by_squaring(d, exponent)
}

/// The shaded colour `c ⊙ Σ_l (Iin_l ⊙ colour_l)` plus specular terms, summed light by light.
///
/// `iin` holds `lights × channels` values; with one channel the light is grey.
#[inline(always)]
pub fn shade(
    plan: &RenderPlan,
    color: [f32; 3],
    iin: &[f32],
    spec: Option<(f32, u32, [f32; 3])>,
) -> [f32; 3] {
    let ch = plan.channels as usize;
    let mut sum = [0.0f32; 3];
    for (l, light) in plan.lights.iter().enumerate() {
        for c in 0..3 {
            let i = iin[l * ch + if ch == 1 { 0 } else { c }];
            sum[c] += i * light.color[c];
        }
    }
    let mut out = [color[0] * sum[0], color[1] * sum[1], color[2] * sum[2]];
    if let Some((strength, exponent, n)) = spec {
        for (l, light) in plan.lights.iter().enumerate() {
            let w = specular(n, light.half_vector, strength, exponent);
            for (c, o) in out.iter_mut().enumerate() {
                let i = iin[l * ch + if ch == 1 { 0 } else { c }];
                *o += w * (i * light.color[c]);
            }
        }
    }
    out
}

/// Eight [`TfEntry`]s, one per lane.
#[derive(Clone, Copy)]
pub struct TfEntry8 {
    /// Linear RGB colour.
    pub color: [f32x8; 3],
    /// Opacity of one slab.
    pub alpha: f32x8,
    /// Light attenuation per channel.
    pub attenuation: [f32x8; 3],
}

/// 8-lane [`detail_value`]: the material's detail function at 8 points.
#[inline]
pub fn detail_value8(material: &MaterialPlan, p: [f32x8; 3]) -> f32x8 {
    if let Some(d) = &material.detail {
        d.eval8(p[0], p[1], p[2])
    } else if let Some(t) = &material.texture {
        t.sample8(p[0], p[1], p[2])
    } else {
        f32x8::ZERO
    }
}

/// 8-lane [`to_detail`].
#[inline(always)]
pub fn to_detail8(m: &[f32; 12], x: f32x8, y: f32x8, z: f32x8) -> [f32x8; 3] {
    let row = |r: usize| {
        let a = f32x8::splat(m[4 * r]) * x;
        let b = f32x8::splat(m[4 * r + 1]) * y;
        let c = f32x8::splat(m[4 * r + 2]) * z;
        ((a + b) + c) + f32x8::splat(m[4 * r + 3])
    };
    [row(0), row(1), row(2)]
}

/// 8-lane [`transfer`]: the entry index is found per lane exactly as in the scalar path, the
/// interpolation runs on vectors in the same order.
#[inline(always)]
pub fn transfer8(tf: &[TfEntry], value: f32x8) -> TfEntry8 {
    if tf.len() == 1 {
        let e = tf[0];
        return TfEntry8 {
            color: e.color.map(f32x8::splat),
            alpha: f32x8::splat(e.alpha),
            attenuation: e.attenuation.map(f32x8::splat),
        };
    }
    let pos = value * f32x8::splat((TF_SIZE - 1) as f32);
    let pos_lanes = pos.to_array();
    // Truncation instead of the scalar path's floor: they differ only for negative `pos`, where
    // the clamp to 0 makes them agree again (NaN → 0 and ±∞ saturate alike), and SSE2 has no
    // vector floor (a libm call per lane).
    let index: [usize; 8] = pos_lanes.map(|p| (p as i32).clamp(0, TF_SIZE as i32 - 2) as usize);
    let f = pos - f32x8::new(index.map(|i| i as f32));
    let field = |get: &dyn Fn(&TfEntry) -> f32| {
        let a = f32x8::new(index.map(|i| get(&tf[i])));
        let b = f32x8::new(index.map(|i| get(&tf[i + 1])));
        a + f * (b - a)
    };
    TfEntry8 {
        color: [
            field(&|e| e.color[0]),
            field(&|e| e.color[1]),
            field(&|e| e.color[2]),
        ],
        alpha: field(&|e| e.alpha),
        attenuation: [
            field(&|e| e.attenuation[0]),
            field(&|e| e.attenuation[1]),
            field(&|e| e.attenuation[2]),
        ],
    }
}

/// 8-lane [`powi_by_squaring`] (same exponent in every lane, same multiplications).
#[inline(always)]
pub fn powi_by_squaring8(mut x: f32x8, mut n: u32) -> f32x8 {
    let mut r = f32x8::ONE;
    while n > 0 {
        if n & 1 == 1 {
            r *= x;
        }
        x *= x;
        n >>= 1;
    }
    r
}

/// 8-lane [`specular`].
#[inline(always)]
pub fn specular8(n: [f32x8; 3], h: [f32; 3], strength: f32, exponent: u32) -> f32x8 {
    let s = n[2]
        .simd_gt(f32x8::ZERO)
        .select(f32x8::splat(-1.0), f32x8::ONE);
    let h = h.map(f32x8::splat);
    let d = ((s * n[0]) * h[0] + (s * n[1]) * h[1]) + (s * n[2]) * h[2];
    let d = d.simd_gt(f32x8::ZERO).select(d, f32x8::ZERO);
    f32x8::splat(strength) * powi_by_squaring8(d, exponent)
}

/// The specular input of [`shade8`]: strength, exponent, per-lane normals, and the lanes that
/// crossed a surface (the only ones that get a highlight).
pub struct Specular8 {
    /// Strength.
    pub strength: f32,
    /// Exponent.
    pub exponent: u32,
    /// Camera-space normal per lane.
    pub normal: [f32x8; 3],
    /// All-ones lanes get the highlight.
    pub lanes: f32x8,
}

/// 8-lane [`shade`]: the same sums in the same order.
#[inline(always)]
pub fn shade8(
    plan: &RenderPlan,
    color: [f32x8; 3],
    iin: &[f32x8],
    spec: Option<&Specular8>,
) -> [f32x8; 3] {
    let ch = plan.channels as usize;
    let mut sum = [f32x8::ZERO; 3];
    for (l, light) in plan.lights.iter().enumerate() {
        for (c, s) in sum.iter_mut().enumerate() {
            let i = iin[l * ch + if ch == 1 { 0 } else { c }];
            *s += i * f32x8::splat(light.color[c]);
        }
    }
    let mut out = [color[0] * sum[0], color[1] * sum[1], color[2] * sum[2]];
    if let Some(sp) = spec {
        for (l, light) in plan.lights.iter().enumerate() {
            let w = specular8(sp.normal, light.half_vector, sp.strength, sp.exponent);
            for (c, o) in out.iter_mut().enumerate() {
                let i = iin[l * ch + if ch == 1 { 0 } else { c }];
                let lit = *o + w * (i * f32x8::splat(light.color[c]));
                *o = sp.lanes.select(lit, *o);
            }
        }
    }
    out
}
