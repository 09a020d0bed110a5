// Stages 4 and 5: mirrors cpu/src/composite.rs (front-to-back compositing, attenuation with the
// explicit flush, the final background).

#import shared/bindings

// `composite`: t = (1 − A)·α; C += t·c; A += t. `acc` is (C.rgb, A).
fn composite(acc: vec4<f32>, c: vec3<f32>, a: f32) -> vec4<f32> {
    let t = (1.0 - acc.w) * a;
    return vec4<f32>(acc.x + t * c.x, acc.y + t * c.y, acc.z + t * c.z, acc.w + t);
}

// `attenuate`: Iin·attenuation, flushed to zero below FLUSH_BELOW.
fn attenuate(v_in: f32, attenuation: f32) -> f32 {
    let v = v_in * attenuation;
    return select(v, 0.0, v < globals.flush_below);
}

// `deepen` (distance penumbra): the occluder-depth plane after a slab, D + slab · removed
// (`removed`: the light the slab took out, summed over channels), flushed like the light.
fn deepen(depth: f32, slab: u32, removed: f32) -> f32 {
    let v = depth + f32(slab) * removed;
    return select(v, 0.0, v < globals.flush_below);
}

// `finish`: C += (1 − A)·background.
fn finish(acc: vec4<f32>) -> vec3<f32> {
    let t = 1.0 - acc.w;
    return vec3<f32>(acc.x + t * globals.bg_r, acc.y + t * globals.bg_g, acc.z + t * globals.bg_b);
}
