//! Stage 3, shading: material lookup at one point per slab, detail function, transfer function,
//! light sum and specular highlight (DESIGN §2 step 3, paper §4.2). Mirrors
//! `gpu/src/shaders/shading.wgsl`.

use convshadow_common::plan::{MaterialPlan, RenderPlan, TF_SIZE, TfEntry};

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
