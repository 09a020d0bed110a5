// Stage 3, shading: mirrors cpu/src/shading.rs (detail value, transfer function, light sum,
// specular by repeated squaring). Transfer-function entries are 7 words: colour rgb, alpha,
// attenuation rgb.

const TF_SIZE: u32 = 256u;

struct TfEntry {
    color: vec3<f32>,
    alpha: f32,
    attenuation: vec3<f32>,
}

fn tf_entry(at: u32) -> TfEntry {
    return TfEntry(
        vec3<f32>(tf(at), tf(at + 1u), tf(at + 2u)),
        tf(at + 3u),
        vec3<f32>(tf(at + 4u), tf(at + 5u), tf(at + 6u)),
    );
}

// `detail_value`: procedural detail, else the 3D texture, else 0.
fn detail_value(m: u32, p: vec3<f32>) -> f32 {
    if tu(m + 2u) != 0u {
        return detail_eval(m, p.x, p.y, p.z);
    }
    if tu(m + 12u) != 0u {
        return texture_sample(m, p.x, p.y, p.z);
    }
    return 0.0;
}

// `to_detail`: row-major 3×4 affine at word `at`, each row `((a + b) + c) + t`.
fn to_detail(at: u32, x: f32, y: f32, z: f32) -> vec3<f32> {
    var out: vec3<f32>;
    for (var r = 0u; r < 3u; r++) {
        let a = tf(at + 4u * r) * x;
        let b = tf(at + 4u * r + 1u) * y;
        let c = tf(at + 4u * r + 2u) * z;
        out[r] = ((a + b) + c) + tf(at + 4u * r + 3u);
    }
    return out;
}

fn lerp3(f: f32, u: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(u.x + f * (v.x - u.x), u.y + f * (v.y - u.y), u.z + f * (v.z - u.z));
}

// `transfer`: linear interpolation between the two nearest entries (index clamped to
// [0, TF_SIZE − 2] with Rust's saturating float → int conversion).
fn transfer(m: u32, value: f32) -> TfEntry {
    let base = tu(m);
    if tu(m + 1u) == 1u {
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
    let a = tf_entry(base + 7u * i);
    let b = tf_entry(base + 7u * (i + 1u));
    return TfEntry(
        lerp3(f, a.color, b.color),
        a.alpha + f * (b.alpha - a.alpha),
        lerp3(f, a.attenuation, b.attenuation),
    );
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

// `specular`: strength · max(0, n·h)^exponent with n flipped to face the viewer.
fn specular(n: vec3<f32>, h: vec3<f32>, strength: f32, exponent: u32) -> f32 {
    let s = select(1.0, -1.0, n.z > 0.0);
    var d = ((s * n.x) * h.x + (s * n.y) * h.y) + (s * n.z) * h.z;
    d = select(0.0, d, d > 0.0);
    return strength * powi_by_squaring(d, exponent);
}

fn light_header(l: u32) -> u32 {
    return globals.off_lights + 16u * l;
}

fn light_color(l: u32) -> vec3<f32> {
    let lh = light_header(l);
    return vec3<f32>(tf(lh + 7u), tf(lh + 8u), tf(lh + 9u));
}

fn iin_at(l: u32, c: u32) -> f32 {
    let ch = globals.channels;
    return iin[l * ch + select(c, 0u, ch == 1u)];
}

// `shade`: c ⊙ Σ_l (Iin_l ⊙ colour_l), then the specular terms light by light.
fn shade(color: vec3<f32>, has_spec: bool, strength: f32, exponent: u32, n: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0, 0.0, 0.0);
    for (var l = 0u; l < globals.lights; l++) {
        let lc = light_color(l);
        for (var c = 0u; c < 3u; c++) {
            sum[c] = sum[c] + iin_at(l, c) * lc[c];
        }
    }
    var out = vec3<f32>(color.x * sum.x, color.y * sum.y, color.z * sum.z);
    if has_spec {
        for (var l = 0u; l < globals.lights; l++) {
            let lh = light_header(l);
            let h = vec3<f32>(tf(lh + 10u), tf(lh + 11u), tf(lh + 12u));
            let w = specular(n, h, strength, exponent);
            let lc = light_color(l);
            for (var c = 0u; c < 3u; c++) {
                out[c] = out[c] + w * (iin_at(l, c) * lc[c]);
            }
        }
    }
    return out;
}
