// The front-to-back slab sweep: mirrors cpu/src/sweep.rs. One dispatch per slab, one invocation
// per grid pixel, light buffers ping-pong between dispatches. Per pixel, in the CPU's order:
// 1. convolve every light buffer (kernels.wgsl), 2. advance the layer cursor (parity.wgsl),
// 3. shade one point (shading.wgsl), 4. composite and 5. attenuate with the flush
// (composite.wgsl). `finish_image` adds the background and crops the guard band.
//
// This file is concatenated after hash, noise, texture3d, kernels, parity, shading and composite
// (WGSL module-scope declarations may appear in any order).

// Per-render constants; `off_*` are word offsets into `tables` (see gpu/src/sweep.rs).
struct Globals {
    grid_w: u32,
    grid_h: u32,
    guard: u32,
    width: u32,
    height: u32,
    slabs: u32,
    lights: u32,
    channels: u32,
    jitter: u32,
    slab_distance: f32,
    flush_below: f32,
    perlin4_scale: f32,
    bg_r: f32,
    bg_g: f32,
    bg_b: f32,
    row_len: u32,
    off_slab_front: u32,
    off_slab_back: u32,
    off_jitter_hash: u32,
    off_lights: u32,
    off_materials: u32,
    off_mesh_material: u32,
    off_mesh_to_detail: u32,
    off_normals: u32,
}

struct SlabParams {
    slab: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> slab_params: SlabParams;
@group(0) @binding(1) var<uniform> globals: Globals;
@group(0) @binding(2) var<storage, read> light_prev: array<f32>;
@group(0) @binding(3) var<storage, read_write> light_cur: array<f32>;
@group(0) @binding(4) var<storage, read_write> cursors: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> offsets: array<u32>;
@group(0) @binding(7) var<storage, read> frag_depth: array<f32>;
@group(0) @binding(8) var<storage, read> frag_meta: array<u32>;
@group(0) @binding(9) var<storage, read> tables: array<u32>;
@group(0) @binding(10) var<storage, read_write> image: array<f32>;

// Largest lights × channels (the CPU's MAX_LIGHT_CHANNELS).
const MAX_LIGHT_CHANNELS: u32 = 48u;
var<private> iin: array<f32, 48>;

fn tu(i: u32) -> u32 {
    return tables[i];
}

fn tf(i: u32) -> f32 {
    return bitcast<f32>(tables[i]);
}

@compute @workgroup_size(8, 8)
fn sweep_slab(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    if x >= globals.grid_w || y >= globals.grid_h {
        return;
    }
    let slab = slab_params.slab;
    let w = globals.grid_w;
    let ch = globals.channels;
    let back = tf(globals.off_slab_back + slab);
    let front = tf(globals.off_slab_front + slab);

    // 1. Convolution of every light buffer.
    for (var l = 0u; l < globals.lights; l++) {
        let lh = light_header(l);
        let slab_hash = tu(tu(lh + 4u) + slab);
        let row = row_hash(slab_hash, y);
        let phase = phase_at(lh, slab, slab_hash, row, x);
        let per_phase = tu(lh + 1u);
        let taps = tu(lh) + 6u * per_phase * phase;
        let so = tu(lh + 6u) + 2u * slab;
        let shift = vec2<i32>(bitcast<i32>(tu(so)), bitcast<i32>(tu(so + 1u)));
        for (var c = 0u; c < ch; c++) {
            iin[l * ch + c] = gather((l * ch + c) * w, taps, per_phase, shift, i32(x), i32(y));
        }
    }

    // 2. Intersection: advance the layer cursor to the slab's back face.
    let p = y * w + x;
    let state = cursors[p];
    let adv = advance(state.x, offsets[p + 1u], state.y, back);
    cursors[p] = vec2<u32>(adv.next, adv.inside);
    let crossed = adv.first != NO_CROSSING;
    var mesh = first_mesh(adv.inside);
    if crossed {
        mesh = frag_meta[adv.first] & 31u;
    }

    // 3. Shading at one point, if inside a mesh or a surface was crossed; 4. composite.
    var attenuation = vec3<f32>(1.0, 1.0, 1.0);
    if mesh != NO_CROSSING {
        var z: f32;
        if crossed {
            z = frag_depth[adv.first];
        } else if globals.jitter != 0u {
            let jitter_row = row_hash(tu(globals.off_jitter_hash + slab), y);
            z = front + unit_float(pixel_hash(jitter_row, x)) * globals.slab_distance;
        } else {
            z = front + 0.5 * globals.slab_distance;
        }
        let m = globals.off_materials + 16u * tu(globals.off_mesh_material + mesh);
        var value = 0.0;
        if tu(m + 1u) > 1u {
            let q = to_detail(globals.off_mesh_to_detail + 12u * mesh, f32(x) + 0.5, f32(y) + 0.5, z);
            value = detail_value(m, q);
        }
        let e = transfer(m, value);
        let has_spec = crossed && tu(m + 13u) != 0u;
        var n = vec3<f32>(0.0, 0.0, 0.0);
        if has_spec {
            let o = globals.off_normals + 3u * (frag_meta[adv.first] >> 5u);
            n = vec3<f32>(tf(o), tf(o + 1u), tf(o + 2u));
        }
        let shaded = shade(e.color, has_spec, tf(m + 14u), tu(m + 15u), n);
        accum[p] = composite(accum[p], shaded, e.alpha);
        attenuation = e.attenuation;
    }

    // 5. Attenuate (and flush) into this slab's outgoing light buffer.
    let row_base = y * globals.row_len;
    for (var l = 0u; l < globals.lights; l++) {
        for (var c = 0u; c < ch; c++) {
            let k = l * ch + c;
            light_cur[row_base + k * w + x] = attenuate(iin[k], attenuation[c]);
        }
    }
}

// After the last slab: C += (1 − A)·background, guard band cropped, RGB f32 out.
@compute @workgroup_size(8, 8)
fn finish_image(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    if x >= globals.width || y >= globals.height {
        return;
    }
    let p = (y + globals.guard) * globals.grid_w + x + globals.guard;
    let c = finish(accum[p]);
    let o = 3u * (y * globals.width + x);
    image[o] = c.x;
    image[o + 1u] = c.y;
    image[o + 2u] = c.z;
}
