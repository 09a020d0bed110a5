// Stage 3, shading: mirrors cpu/src/shading.rs (detail value, transfer function, light sum with
// the horizon and the Lambert cosine at opaque crossings, specular by repeated squaring).

#import shared/constants
#import shared/bindings
#import noise
#import texture3d

struct TfEntry {
    color: vec3<f32>,
    alpha: f32,
    attenuation: vec3<f32>,
}

fn tf_entry(i: u32) -> TfEntry {
    let e = tf_entries[i];
    return TfEntry(
        vec3<f32>(e.color[0], e.color[1], e.color[2]),
        e.alpha,
        vec3<f32>(e.attenuation[0], e.attenuation[1], e.attenuation[2]),
    );
}

// `shading_depth`: the depth of a slab's one shading point in pixel (hx, hy) (image pixels, the
// hashes' keys): the crossing `first` where one was crossed, else the slab's front plus the
// hashed jitter, else the slab's centre.
fn shading_depth(crossed: bool, first: u32, faces: Slab, hx: u32, hy: u32) -> f32 {
    if crossed {
        return frag_depth[first];
    }
    if globals.jitter != 0u {
        let jitter_row = row_hash(faces.jitter_hash, hy);
        return faces.front + unit_float(pixel_hash(jitter_row, hx)) * globals.slab_distance;
    }
    return faces.front + 0.5 * globals.slab_distance;
}

// `detail_value`: procedural detail, else the 3D texture, else 0.
fn detail_value(m: MaterialHeader, p: vec3<f32>) -> f32 {
    if m.detail_kind != DETAIL_NONE {
        return detail_eval(m, p.x, p.y, p.z);
    }
    if m.has_texture != TEXTURE_NONE {
        return texture_sample(m, p.x, p.y, p.z);
    }
    return 0.0;
}

// `to_detail`: the row-major 3×4 affine of `mesh`, each row `((a + b) + c) + t`.
fn to_detail(mesh: u32, x: f32, y: f32, z: f32) -> vec3<f32> {
    let t = meshes[mesh].to_detail;
    var out: vec3<f32>;
    for (var r = 0u; r < 3u; r++) {
        let a = t[4u * r] * x;
        let b = t[4u * r + 1u] * y;
        let c = t[4u * r + 2u] * z;
        out[r] = ((a + b) + c) + t[4u * r + 3u];
    }
    return out;
}

// `detail_at` (cpu/src/shading.rs): the detail of mesh `mesh` (material `m`) at image pixels
// (x, y) (+ 0.5 already) and relative depth z — on a point light's grid (`projective`) at the
// cell's own 3D point, `centre + (xy − centre)·(depth_origin + z)·per_depth`.
fn detail_at(mesh: u32, m: MaterialHeader, x: f32, y: f32, z: f32) -> f32 {
    var q = vec2<f32>(x, y);
    if globals.projective != 0u {
        let s = (globals.projective_depth_origin + z) * globals.projective_per_depth;
        let c = globals.projective_centre;
        q = vec2<f32>(c.x + (x - c.x) * s, c.y + (y - c.y) * s);
    }
    return detail_value(m, to_detail(mesh, q.x, q.y, z));
}

fn lerp3(f: f32, u: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(u.x + f * (v.x - u.x), u.y + f * (v.y - u.y), u.z + f * (v.z - u.z));
}

// `transfer`: linear interpolation between the two nearest entries (index clamped to
// [0, TF_SIZE − 2] with Rust's saturating float → int conversion).
fn transfer(m: MaterialHeader, value: f32) -> TfEntry {
    let base = m.tf;
    if m.tf_len == 1u {
        return tf_entry(base);
    }
    let pos = value * f32(TF_SIZE - 1u);
    let fl = floor(pos);
    var i = 0u;
    if fl >= f32(TF_SIZE - 2u) {
        i = TF_SIZE - 2u;
    } else if fl > 0.0 {
        i = u32(fl);
    }
    let f = pos - f32(i);
    let a = tf_entry(base + i);
    let b = tf_entry(base + i + 1u);
    return TfEntry(
        lerp3(f, a.color, b.color),
        a.alpha + f * (b.alpha - a.alpha),
        lerp3(f, a.attenuation, b.attenuation),
    );
}

// `pre_transfer`: bilinear look-up of the pre-integration table at `base` (PI_SIZE × PI_SIZE,
// front-major): first along the back value, then along the front value; indices clamped to
// [0, PI_SIZE − 2] as in `transfer`.
fn pre_index(pos: f32) -> u32 {
    let fl = floor(pos);
    if fl >= f32(PI_SIZE - 2u) {
        return PI_SIZE - 2u;
    } else if fl > 0.0 {
        return u32(fl);
    }
    return 0u;
}

fn pre_transfer(base: u32, front: f32, back: f32) -> TfEntry {
    let scale = f32(PI_SIZE - 1u);
    let pf = front * scale;
    let pb = back * scale;
    let kf = pre_index(pf);
    let kb = pre_index(pb);
    let ff = pf - f32(kf);
    let fb = pb - f32(kb);
    let i = base + kf * PI_SIZE + kb;
    let e00 = tf_entry(i);
    let e01 = tf_entry(i + 1u);
    let e10 = tf_entry(i + PI_SIZE);
    let e11 = tf_entry(i + PI_SIZE + 1u);
    let lo = TfEntry(
        lerp3(fb, e00.color, e01.color),
        e00.alpha + fb * (e01.alpha - e00.alpha),
        lerp3(fb, e00.attenuation, e01.attenuation),
    );
    let hi = TfEntry(
        lerp3(fb, e10.color, e11.color),
        e10.alpha + fb * (e11.alpha - e10.alpha),
        lerp3(fb, e10.attenuation, e11.attenuation),
    );
    return TfEntry(
        lerp3(ff, lo.color, hi.color),
        lo.alpha + ff * (hi.alpha - lo.alpha),
        lerp3(ff, lo.attenuation, hi.attenuation),
    );
}

// `preintegrated` (cpu/src/sweep/pixel.rs): the pre-integration entry of mesh `mesh` (material
// `m`) at pixel `p` (image coordinates + 0.5: `x`, `y`) for the detail values at the slab's
// faces. The front value is the one kept in `pre_front` unless the pixel crossed a surface (then
// at the crossing depth `zc`) or none is kept (then at `front`); the back value is kept for the
// next slab when `keep` (the pixel is still in `mesh` at the back face). A kept value has the
// bits of a fresh one, so keeping it only saves an evaluation.
fn preintegrated(p: u32, mesh: u32, m: MaterialHeader, crossed: bool, zc: f32, front: f32, back: f32, x: f32, y: f32, keep: bool) -> TfEntry {
    let kept = pre_front[p];
    var vf: f32;
    if !crossed && kept != PRE_NONE {
        vf = bitcast<f32>(kept);
    } else {
        var z = front;
        if crossed {
            z = zc;
        }
        vf = detail_at(mesh, m, x, y, z);
    }
    let vb = detail_at(mesh, m, x, y, back);
    var next = PRE_NONE;
    if keep {
        next = bitcast<u32>(vb);
    }
    pre_front[p] = next;
    return pre_transfer(m.pre, vf, vb);
}

// `powi_by_squaring`.
fn powi_by_squaring(x0: f32, n0: u32) -> f32 {
    var x = x0;
    var n = n0;
    var r = 1.0;
    loop {
        if n == 0u {
            break;
        }
        if (n & 1u) == 1u {
            r = r * x;
        }
        x = x * x;
        n = n >> 1u;
    }
    return r;
}

// The normal flipped to face the viewer (shading.rs `facing`).
fn facing(n: vec3<f32>) -> vec3<f32> {
    let s = select(1.0, -1.0, n.z > 0.0);
    return vec3<f32>(s * n.x, s * n.y, s * n.z);
}

// (f.x·v0 + f.y·v1) + f.z·v2, in that order (shading.rs `dot`).
fn dot_fixed(f: vec3<f32>, v: array<f32, 3>) -> f32 {
    return (f.x * v[0] + f.y * v[1]) + f.z * v[2];
}

// max(0, d) (NaN gives 0).
fn positive(d: f32) -> f32 {
    return select(0.0, d, d > 0.0);
}

// `LightTerms`: what the shading takes of a light. The grid's sweep takes every light's from its
// header and `light_colors`; the eye pass of a point light's grid sets `terms` per sample
// (eye.wgsl `point_terms`) and `terms_on`, and the shading takes them for its one light.
struct LightTerms {
    light_color: vec3<f32>, // the colour times the material's phase function
    color: vec3<f32>,       // the bare colour (specular)
    to_light: array<f32, 3>,
    half_vector: array<f32, 3>,
    fresnel: array<f32, 2>,
    spread: array<f32, 4>, // the horizon's spread (`LightPlan::spread`)
    plain: bool,           // the light buffer holds the visible part (`LightPlan::plain`)
}

var<private> terms_on: bool = false;
var<private> terms: LightTerms;

fn half_vector_of(l: u32) -> array<f32, 3> {
    if terms_on {
        return terms.half_vector;
    }
    return lights[l].half_vector;
}

fn to_light_of(l: u32) -> array<f32, 3> {
    if terms_on {
        return terms.to_light;
    }
    return lights[l].to_light;
}

fn spread_of(l: u32) -> array<f32, 4> {
    if terms_on {
        return terms.spread;
    }
    return lights[l].spread;
}

fn plain_of(l: u32) -> bool {
    if terms_on {
        return terms.plain;
    }
    return lights[l].plain != 0u;
}

// `horizon`: the part of light `l` above the tangent plane of facing normal f, Φ(μ/σ) with
// μ = f·l and σ² = ((a·fx² + b·fx·fy) + c·fy²) + iso, Φ interpolated in the table at
// `globals.horizon_at`; 1 / 0 beyond its reach; without spread 1 where μ > 0, else 0.
fn horizon(f: vec3<f32>, l: u32) -> f32 {
    let mu = dot_fixed(f, to_light_of(l));
    let s = spread_of(l);
    let v = ((s[0] * (f.x * f.x) + s[1] * (f.x * f.y)) + s[2] * (f.y * f.y)) + s[3];
    let sharp = select(0.0, 1.0, mu > 0.0);
    let soft = v > 0.0;
    let t = mu / sqrt(select(1.0, v, soft));
    let steps = f32(HORIZON_STEPS);
    let u = (t + HORIZON_REACH) * HORIZON_PER_UNIT;
    let below_top = u < steps;
    let above_bottom = u > 0.0;
    var clamped = select(steps - 1.0, u, below_top);
    clamped = select(0.0, clamped, above_bottom);
    let knot = floor(clamped);
    let w = clamped - knot;
    let i = globals.horizon_at + u32(knot);
    let a = bitcast<f32>(level_table[i]);
    let b = bitcast<f32>(level_table[i + 1u]);
    var phi = a + (b - a) * w;
    phi = select(1.0, phi, below_top);
    phi = select(0.0, phi, above_bottom);
    return select(sharp, phi, soft);
}

fn fresnel_of(l: u32) -> array<f32, 2> {
    if terms_on {
        return terms.fresnel;
    }
    return lights[l].fresnel;
}

// `blinn_phong`: strength · max(0, f·h)^exponent at a facing normal f.
fn blinn_phong(f: vec3<f32>, l: u32, m: MaterialHeader) -> f32 {
    let d = positive(dot_fixed(f, half_vector_of(l)));
    return m.spec_strength * powi_by_squaring(d, m.spec_exponent);
}

// `ashikmin_shirley`: a · (f·h)^e · (f·l) / max(f·l, f·v), v = (0, 0, −1), a = the material's
// normalised strength · (b + f0·c) with the light's Fresnel constants; a zero denominator is 1.
fn ashikmin_shirley(f: vec3<f32>, l: u32, m: MaterialHeader) -> f32 {
    let nh = positive(dot_fixed(f, half_vector_of(l)));
    let nl = positive(dot_fixed(f, to_light_of(l)));
    let nv = positive(0.0 - f.z);
    var den = select(nv, nl, nl > nv);
    den = select(1.0, den, den > 0.0);
    let fr = fresnel_of(l);
    let a = m.spec_strength * (fr[0] + m.spec_f0 * fr[1]);
    return a * (powi_by_squaring(nh, m.spec_exponent) * (nl / den));
}

fn light_color(l: u32) -> vec3<f32> {
    if terms_on {
        return terms.color;
    }
    let c = lights[l].color;
    return vec3<f32>(c[0], c[1], c[2]);
}

fn iin_at(l: u32, c: u32) -> f32 {
    let ch = globals.channels;
    return iin[l * ch + select(c, 0u, ch == 1u)];
}

// Material `material`'s colour of light `l`: the light's colour times its phase function.
fn phase_light_color(material: u32, l: u32) -> vec3<f32> {
    if terms_on {
        return terms.light_color;
    }
    let c = light_colors[material * globals.lights + l];
    return vec3<f32>(c[0], c[1], c[2]);
}

// `shade`: c ⊙ Σ_l (Iin_l ⊙ colour_l · cos_l) with the material's phase-weighted light colours
// (Iin_l limited by the horizon at an opaque crossing: the smaller for a plain light, else the
// product),
// then the specular terms light by light with the bare light colours. `surface`: the pixel
// crossed a surface of normal `n` in this slab (and the material uses it); cos_l is the Lambert
// cosine where the material is `lambert` and the crossing opaque (alpha exactly 1), else 1.
fn shade(material: u32, color: vec3<f32>, alpha: f32, surface: bool, n: vec3<f32>) -> vec3<f32> {
    let m = materials[material];
    let f = facing(n);
    let diffuse = surface && m.lambert != 0u && !(alpha < 1.0);
    // The horizon limits the light at an opaque crossing (`sweep.horizon`).
    let limited = surface && globals.horizon_at != HORIZON_NONE && !(alpha < 1.0);
    var sum = vec3<f32>(0.0, 0.0, 0.0);
    for (var l = 0u; l < globals.lights; l++) {
        let lc = phase_light_color(material, l);
        var k = 1.0;
        if diffuse {
            k = positive(dot_fixed(f, to_light_of(l)));
        }
        var h = 1.0;
        if limited {
            h = horizon(f, l);
        }
        let plain = plain_of(l);
        for (var c = 0u; c < 3u; c++) {
            var i = iin_at(l, c);
            if limited {
                if plain {
                    i = select(h, i, i < h);
                } else {
                    i = i * h;
                }
            }
            sum[c] = sum[c] + (i * lc[c]) * k;
        }
    }
    var out = vec3<f32>(color.x * sum.x, color.y * sum.y, color.z * sum.z);
    if surface && m.has_specular != SPEC_NONE {
        for (var l = 0u; l < globals.lights; l++) {
            var w: f32;
            if m.has_specular == SPEC_BLINN_PHONG {
                w = blinn_phong(f, l, m);
            } else {
                w = ashikmin_shirley(f, l, m);
            }
            let lc = light_color(l);
            for (var c = 0u; c < 3u; c++) {
                out[c] = out[c] + w * (iin_at(l, c) * lc[c]);
            }
        }
    }
    return out;
}
