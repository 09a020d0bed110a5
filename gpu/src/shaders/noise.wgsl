// Volumetric detail functions: mirrors common/src/pixel/noise.rs operation by operation (read its header
// comment). Only f32 add, sub, mul, floor, sign-bit clear/xor, compare + select, saturating
// f32 → i32 of an integral value, and u32 wrapping arithmetic. No fma, mix, min, max or
// transcendentals. Every expression keeps the Rust evaluation order (left to right).

#import shared/constants
#import shared/bindings
#import hash

// `hash`: lowbias32 (the same bijection as `mix32`).
fn noise_hash(k: u32) -> u32 {
    return mix32(k);
}

// Perlin's quintic fade: `((t*t)*t) * ((t*((t*6) - 15)) + 10)`.
fn fade(t: f32) -> f32 {
    let t3 = t * t * t;
    let p = t * (t * 6.0 - 15.0) + 10.0;
    return t3 * p;
}

// `a + t*(b - a)`.
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    return a + t * (b - a);
}

// Sign-bit clear.
fn abs_bits(v: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(v) & 0x7fffffffu);
}

// Sign-bit xor.
fn xor_sign(v: f32, bits: u32) -> f32 {
    return bitcast<f32>(bitcast<u32>(v) ^ bits);
}

// `((floor as i32) & 255) as u32` with Rust's saturating conversion: ≥ 2^31 → i32::MAX (255 after
// the mask); < −2^31, −inf and NaN → i32::MIN or 0 (both 0 after the mask).
fn lattice(fl: f32) -> u32 {
    if fl >= 2147483648.0 {
        return 255u;
    }
    if fl >= -2147483648.0 {
        return bitcast<u32>(i32(fl)) & 255u;
    }
    return 0u;
}

fn next_lattice(i: u32) -> u32 {
    return (i + 1u) & 255u;
}

// Perlin 2002 `grad()`.
fn grad3(hash: u32, x: f32, y: f32, z: f32) -> f32 {
    let h = hash >> 28u;
    let u_is_x = (h & 8u) == 0u;
    let v_is_y = (h & 12u) == 0u;
    let v_is_x = (h & 13u) == 12u;
    let u = select(y, x, u_is_x);
    let v = select(select(z, x, v_is_x), y, v_is_y);
    let su = (h & 1u) << 31u;
    let sv = (h & 2u) << 30u;
    return xor_sign(u, su) + xor_sign(v, sv);
}

// Gustavson's `grad4()`.
fn grad4(hash: u32, x: f32, y: f32, z: f32, t: f32) -> f32 {
    let h = hash >> 27u;
    let h24 = h & 24u;
    let u = select(x, y, h24 == 24u);
    let v = select(z, y, (h & 16u) == 0u);
    let w = select(t, z, h24 == 0u);
    let su = (h & 1u) << 31u;
    let sv = (h & 2u) << 30u;
    let sw = (h & 4u) << 29u;
    return xor_sign(u, su) + xor_sign(v, sv) + xor_sign(w, sw);
}

fn perlin3(x: f32, y: f32, z: f32) -> f32 {
    let flx = floor(x);
    let fly = floor(y);
    let flz = floor(z);
    let xi0 = lattice(flx);
    let yi0 = lattice(fly);
    let zi0 = lattice(flz);
    let x0 = x - flx;
    let y0 = y - fly;
    let z0 = z - flz;
    let xi1 = next_lattice(xi0);
    let yi0s = yi0 << 8u;
    let yi1s = next_lattice(yi0) << 8u;
    let zi0s = zi0 << 16u;
    let zi1s = next_lattice(zi0) << 16u;
    let x1 = x0 - 1.0;
    let y1 = y0 - 1.0;
    let z1 = z0 - 1.0;
    let u = fade(x0);
    let v = fade(y0);
    let w = fade(z0);
    let g000 = grad3(noise_hash(xi0 | yi0s | zi0s), x0, y0, z0);
    let g100 = grad3(noise_hash(xi1 | yi0s | zi0s), x1, y0, z0);
    let g010 = grad3(noise_hash(xi0 | yi1s | zi0s), x0, y1, z0);
    let g110 = grad3(noise_hash(xi1 | yi1s | zi0s), x1, y1, z0);
    let g001 = grad3(noise_hash(xi0 | yi0s | zi1s), x0, y0, z1);
    let g101 = grad3(noise_hash(xi1 | yi0s | zi1s), x1, y0, z1);
    let g011 = grad3(noise_hash(xi0 | yi1s | zi1s), x0, y1, z1);
    let g111 = grad3(noise_hash(xi1 | yi1s | zi1s), x1, y1, z1);
    let a0 = lerp(u, g000, g100);
    let a1 = lerp(u, g010, g110);
    let a2 = lerp(u, g001, g101);
    let a3 = lerp(u, g011, g111);
    let b0 = lerp(v, a0, a1);
    let b1 = lerp(v, a2, a3);
    return lerp(w, b0, b1);
}

fn perlin4(x: f32, y: f32, z: f32, t: f32) -> f32 {
    let flx = floor(x);
    let fly = floor(y);
    let flz = floor(z);
    let flt = floor(t);
    let xi0 = lattice(flx);
    let yi0 = lattice(fly);
    let zi0 = lattice(flz);
    let ti0 = lattice(flt);
    let x0 = x - flx;
    let y0 = y - fly;
    let z0 = z - flz;
    let t0 = t - flt;
    let xi = array<u32, 2>(xi0, next_lattice(xi0));
    let yi = array<u32, 2>(yi0 << 8u, next_lattice(yi0) << 8u);
    let zi = array<u32, 2>(zi0 << 16u, next_lattice(zi0) << 16u);
    let ti = array<u32, 2>(ti0 << 24u, next_lattice(ti0) << 24u);
    let xs = array<f32, 2>(x0, x0 - 1.0);
    let ys = array<f32, 2>(y0, y0 - 1.0);
    let zs = array<f32, 2>(z0, z0 - 1.0);
    let ts = array<f32, 2>(t0, t0 - 1.0);
    let fx = fade(x0);
    let fy = fade(y0);
    let fz = fade(z0);
    let ft = fade(t0);
    // Corner c = x | y << 1 | z << 2 | t << 3; interpolate along x, y, z, t, lower corner first.
    var ax: array<f32, 8>;
    for (var j = 0u; j < 8u; j++) {
        var g: array<f32, 2>;
        for (var a = 0u; a < 2u; a++) {
            let c = 2u * j + a;
            let b = (c >> 1u) & 1u;
            let d = (c >> 2u) & 1u;
            let e = (c >> 3u) & 1u;
            let k = xi[a] | yi[b] | zi[d] | ti[e];
            g[a] = grad4(noise_hash(k), xs[a], ys[b], zs[d], ts[e]);
        }
        ax[j] = lerp(fx, g[0], g[1]);
    }
    var ay: array<f32, 4>;
    for (var j = 0u; j < 4u; j++) {
        ay[j] = lerp(fy, ax[2u * j], ax[2u * j + 1u]);
    }
    let az0 = lerp(fz, ay[0], ay[1]);
    let az1 = lerp(fz, ay[2], ay[3]);
    return lerp(ft, az0, az1) * globals.perlin4_scale;
}

// Clamp to [0, 1] with compares and selects (NaN and −0 → +0).
fn clamp01(v: f32) -> f32 {
    let r = select(0.0, v, v > 0.0);
    return select(r, 1.0, r > 1.0);
}

// Noise of octave i of material `m` (the DETAIL_* codes come from gpu/src/layout.rs).
fn octave(m: MaterialHeader, i: u32, x: f32, y: f32, z: f32) -> f32 {
    let f = octaves[m.octaves + i].frequency;
    if m.animated == 0u {
        return perlin3(x * f, y * f, z * f);
    }
    return perlin4(x * f, y * f, z * f, m.time * f);
}

fn amplitude(m: MaterialHeader, i: u32) -> f32 {
    return octaves[m.octaves + i].amplitude;
}

// `Detail::eval`: the detail value in [0, 1] at object-space point (x, y, z).
fn detail_eval(m: MaterialHeader, x: f32, y: f32, z: f32) -> f32 {
    let kind = m.detail_kind;
    let n_oct = m.octave_count;
    if n_oct == 0u {
        return 0.0;
    }
    let inv = m.inv_amplitude_sum;
    var v: f32;
    if kind == DETAIL_TURBULENCE {
        var sum = amplitude(m, 0u) * abs_bits(octave(m, 0u, x, y, z));
        for (var i = 1u; i < n_oct; i++) {
            sum = sum + amplitude(m, i) * abs_bits(octave(m, i, x, y, z));
        }
        v = sum * inv;
    } else if kind == DETAIL_RIDGED {
        let r0 = 1.0 - abs_bits(octave(m, 0u, x, y, z));
        var signal = r0 * r0;
        var sum = amplitude(m, 0u) * signal;
        for (var i = 1u; i < n_oct; i++) {
            let weight = clamp01(signal);
            let r = 1.0 - abs_bits(octave(m, i, x, y, z));
            signal = r * r * weight;
            sum = sum + amplitude(m, i) * signal;
        }
        v = sum * inv;
    } else {
        // Perlin and fBm.
        var sum = amplitude(m, 0u) * octave(m, 0u, x, y, z);
        for (var i = 1u; i < n_oct; i++) {
            sum = sum + amplitude(m, i) * octave(m, i, x, y, z);
        }
        v = 0.5 + 0.5 * (sum * inv);
    }
    return clamp01(v);
}
