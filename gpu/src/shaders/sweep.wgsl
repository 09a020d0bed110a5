// The front-to-back slab sweep: mirrors cpu/src/sweep/pixel.rs. One dispatch per slab, one invocation
// per grid pixel, light buffers ping-pong between dispatches. Per pixel, in the CPU's order:
// 1. convolve every light buffer (kernels.wgsl; with the distance penumbra through each pixel's
// level, depth plane included), 2. advance the layer cursor (parity.wgsl),
// 3. shade one point (shading.wgsl), 4. composite and 5. attenuate with the flush
// (composite.wgsl). `finish_image` adds the background and crops the guard band.

#import shared/constants
#import shared/bindings
#import hash
#import noise
#import texture3d
#import kernels
#import subpixel
#import parity
#import shading
#import composite

// Light-buffer values read by every stage of one pixel (`MAX_LIGHT_CHANNELS` from the Rust side).
var<private> iin: array<f32, MAX_LIGHT_CHANNELS>;
// Distance penumbra: each light's gathered occluder-depth plane.
var<private> depth_in: array<f32, MAX_LIGHTS>;
// Each light's tap row (sub-pixel shadows gather through it again).
var<private> tap_rows: array<u32, MAX_LIGHTS>;

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
    let faces = slabs[slab];
    let back = faces.back;
    let front = faces.front;

    // Per-pixel hashes are keyed by image coordinates (wrapping below 0 in the guard band), as
    // on the CPU (`RenderPlan::hash_x`): the noise of an image pixel does not depend on the band.
    let hx = x - globals.guard_left;
    let hy = y - globals.guard_top;

    // 1. Convolution of every light buffer (and, distance penumbra, its depth plane); where a
    // surface holds, through `gather_held` (the same bits where it reads no corner otherwise):
    // with `held_lit_side` a pixel not held itself reads no light from held pixels behind whose
    // surface it lies, and a pixel on a surface (its held crossing, else the fragment ahead of
    // its cursor) reads pixels released on that surface as they gathered in their release slab.
    let planes = globals.planes;
    let distance = globals.depth_planes != 0u;
    let p = y * w + x;
    let records = globals.surface_holds != 0u;
    reader_q = vec2<i32>(i32(x), i32(y));
    reader_hiding = false;
    reader_surface = ReaderSurface(false, 0.0, 0u);
    if records {
        let own = latest_before(p, slab);
        let own_held = slot_held_before(own, slab);
        reader_hiding = globals.held_lit_side != 0u && !own_held;
        let ahead = cursors[p].next;
        if own_held {
            reader_surface = ReaderSurface(true, own.z0, own.triangle);
        } else if ahead < offsets[p + 1u] {
            let z = f32(slab) + (frag_depth[ahead] - front) * globals.inv_slab_distance;
            reader_surface = ReaderSurface(true, z, frag_meta[ahead] >> MESH_BITS);
        }
    }
    for (var l = 0u; l < globals.lights; l++) {
        let light = lights[l];
        let ls = light_slabs[l * globals.slabs + slab];
        let row = row_hash(ls.hash, hy);
        var phase = phase_at(light, ls, row, hx);
        let base = l * planes * w;
        if distance {
            // The tap row of the nearest occluder's level in the pixel's reach.
            phase = distance_row(light, l, slab, phase, ls.shift, x, y);
        }
        let per_phase = light.taps_per_phase;
        let first_tap = light.taps + per_phase * phase;
        tap_rows[l] = phase;
        for (var c = 0u; c < ch; c++) {
            if records {
                iin[l * ch + c] = gather_held(base + c * w, first_tap, per_phase, ls.shift, i32(x), i32(y), OUTSIDE, c, slab, l);
            } else {
                iin[l * ch + c] = gather(base + c * w, first_tap, per_phase, ls.shift, i32(x), i32(y), OUTSIDE);
            }
        }
        if distance {
            if records {
                depth_in[l] = gather_held(base + ch * w, first_tap, per_phase, ls.shift, i32(x), i32(y), OUTSIDE_DEPTH, ch, slab, l);
            } else {
                depth_in[l] = gather(base + ch * w, first_tap, per_phase, ls.shift, i32(x), i32(y), OUTSIDE_DEPTH);
            }
        }
    }

    // 2. Intersection: advance the layer cursor to the slab's back face.
    let state = cursors[p];
    let adv = advance(state.next, offsets[p + 1u], state.inside, back);
    let last = adv.next - 1u; // the last fragment crossed, where one was
    cursors[p] = Cursor(adv.next, adv.inside);
    let crossed = adv.first != NO_CROSSING;
    var mesh = first_mesh(adv.inside);
    if crossed {
        mesh = frag_meta[adv.first] & MESH_MASK;
    }

    // The surface hold (composite.wgsl `hold_step`).
    var held = HELD_FREE;
    var removed_at = f32(slab);
    if globals.surface_holds != 0u {
        var crossed_word = 0u;
        if crossed {
            crossed_word = surface_hold[surface_hold_index(frag_meta[adv.first] >> MESH_BITS)];
            // Leaving a closed mesh starts no hold (cpu/src/parity.rs `leaves_its_mesh`): the
            // mask before the slab holds the first fragment's mesh only on the way out.
            if (state.inside & (1u << (frag_meta[adv.first] & MESH_MASK))) != 0u {
                crossed_word = crossed_word & ~ENTRY_HOLD_MASK;
            }
        }
        let ahead = adv.next < offsets[p + 1u];
        let before = hold[hold_index(p)];
        let step = hold_step(before, slab, crossed_word, crossed && ahead, adv.inside != 0u);
        hold[hold_index(p)] = step.state;
        record_held(p, before, step, crossed, adv.first, slab, front);
        held = step.held;
        removed_at = f32(step.removed_at);
        // The exit hold: inside the mesh of its next fragment, within that triangle's exit hold.
        if held == HELD_FREE && ahead {
            let next_meta = frag_meta[adv.next];
            let exit = (surface_hold[surface_hold_index(next_meta >> MESH_BITS)] >> EXIT_HOLD_SHIFT) & ((1u << (BARRIER_SHIFT - EXIT_HOLD_SHIFT)) - 1u);
            let in_its_mesh = (adv.inside & (1u << (next_meta & MESH_MASK))) != 0u;
            if exit != 0u && in_its_mesh && (frag_depth[adv.next] - back) * globals.inv_slab_distance < f32(exit) {
                held = HELD_PASS;
            }
        }
    }

    // Sub-pixel shadows: a crossed opaque surface shades with its light read at the exact shift
    // (subpixel.wgsl); the buffer keeps the gathered light (`kept`), and the crossing records
    // its removed light at its place inside the slab.
    let exact = globals.subpixel_shadows != 0u && crossed && meshes[mesh].subpixel != 0u;
    var kept: array<f32, MAX_LIGHT_CHANNELS>;
    if exact {
        kept = iin;
        let part = (frag_depth[adv.first] - front) * globals.inv_slab_distance;
        exact_light(x, y, slab, part);
        if held == HELD_FREE {
            removed_at = removal_depth(slab, part);
        }
    }

    // 3. Shading at one point, if inside a mesh or a surface was crossed; 4. composite.
    var attenuation = vec3<f32>(1.0, 1.0, 1.0);
    if mesh != NO_CROSSING {
        let z = shading_depth(crossed, adv.first, faces, hx, hy);
        let mi = meshes[mesh].material;
        let m = materials[mi];
        let xi = f32(i32(x) - i32(globals.guard_left)) + 0.5;
        let yi = f32(i32(y) - i32(globals.guard_top)) + 0.5;
        var e: TfEntry;
        // A medium's entry and exit slabs by the part inside, the light at the point
        // (composite.wgsl `part_of_slab`); a pre-integrated entry has the light's decay inside
        // the slab in its colour.
        var part = slab_part(mesh, state.inside, adv.inside, adv.first, last, front, back);
        if m.pre != NO_PRE {
            part.y = 0.0;
            // Pre-integrated compositing (shading.wgsl `preintegrated`).
            e = preintegrated(p, mesh, m, crossed, z, front, back, xi, yi, first_mesh(adv.inside) == mesh);
        } else {
            if globals.preintegration != 0u {
                pre_front[p] = PRE_NONE;
            }
            var value = 0.0;
            if m.tf_len > 1u {
                value = detail_at(mesh, m, xi, yi, z);
            }
            e = transfer(m, value);
        }
        // Shaded (a crossed surface with its triangle's normal) and composited.
        let sample = shade_sample(accum[p], mi, m, e, part, crossed, adv.first);
        accum[p] = sample.acc;
        attenuation = sample.entry.attenuation;
    }
    if exact {
        iin = kept;
    }

    // 5. Attenuate (and flush) into this slab's outgoing light buffer — a held surface passes
    // it, a released one removes it; distance penumbra: the light this slab removed, at its
    // depth, into the depth plane (`deepen`; a release owns it all, `owned_depth`).
    if held == HELD_PASS {
        attenuation = vec3<f32>(1.0, 1.0, 1.0);
    } else if held == HELD_RELEASE {
        attenuation = vec3<f32>(0.0, 0.0, 0.0);
        // The released pixel keeps the light it gathered, for the gathers of its surface.
        for (var l = 0u; l < globals.lights; l++) {
            var values = vec4<f32>(0.0, 0.0, 0.0, 0.0);
            for (var c = 0u; c < ch; c++) {
                values[c] = iin[l * ch + c];
            }
            values[ch] = depth_in[l];
            keep_release(p, slab, l, values);
        }
    }
    let row_base = y * globals.row_len;
    for (var l = 0u; l < globals.lights; l++) {
        var lit_in = 0.0;
        var lit_out = 0.0;
        for (var c = 0u; c < ch; c++) {
            let k = l * ch + c;
            let out = attenuate(iin[k], attenuation[c]);
            light_cur[row_base + (l * planes + c) * w + x] = out;
            lit_in = lit_in + iin[k];
            lit_out = lit_out + out;
        }
        if distance {
            let occluded = f32(ch) - lit_out;
            let at = depth_coord(removed_at);
            var depth_out = deepen(depth_in[l], at, lit_in - lit_out);
            if held == HELD_RELEASE {
                depth_out = owned_depth(at, occluded);
            }
            light_cur[row_base + (l * planes + ch) * w + x] = depth_out;
            // The level this pixel starts the next slab with.
            level_cur[(y * globals.lights + l) * w + x] = pixel_level(lights[l], occluded, depth_out, level_at(slab + 1u));
        }
    }
}

// `record_held` (cpu/src/sweep/pixel.rs): an entry hold that starts records its crossing's plane,
// one that a crossing cut short its end.
fn record_held(p: u32, before: u32, step: HoldStep, crossed: bool, first: u32, slab: u32, front: f32) {
    let entry_after = step.state != 0u && ((step.state >> HOLD_SHIFT) & HOLD_LENGTH_MASK) != 0u;
    let entry_before = before != 0u && ((before >> HOLD_SHIFT) & HOLD_LENGTH_MASK) != 0u;
    let started = before != step.state && (step.state & HOLD_SLAB_MASK) == slab;
    if step.held == HELD_PASS && crossed && entry_after && started {
        let part = clamp((frag_depth[first] - front) * globals.inv_slab_distance, 0.0, HELD_PART_MAX);
        held_start(p, HeldSlot(true, slab, release_slab(step.state), f32(slab) + part, frag_meta[first] >> MESH_BITS));
    } else if step.held == HELD_RELEASE && entry_before && slab < release_slab(before) {
        held_cut(p, slab);
    }
}

// Sub-pixel shadows at pixel (x, y), which crossed an opaque surface at `part` of slab `slab`:
// every occluded light's channels in `iin` read again at their exact shift through the tap row
// step 1 used (the CPU's `exact_light`).
fn exact_light(x: u32, y: u32, slab: u32, part: f32) {
    let w = globals.grid_w;
    let ch = globals.channels;
    // The exact read reads released corners as step 1 did, held ones from everywhere.
    reader_hiding = false;
    for (var l = 0u; l < globals.lights; l++) {
        var lit = 0.0;
        for (var c = 0u; c < ch; c++) {
            lit = lit + iin[l * ch + c];
        }
        let light = lights[l];
        let s = exact_shift(l, slab, part, lit, depth_in[l], tap_rows[l] / light.phase_count);
        if s.z == 0.0 {
            continue;
        }
        let shift = light_slabs[l * globals.slabs + slab].shift;
        let per_phase = light.taps_per_phase;
        let first_tap = light.taps + per_phase * tap_rows[l];
        let base = l * globals.planes * w;
        for (var c = 0u; c < ch; c++) {
            iin[l * ch + c] = shifted_gather(base + c * w, first_tap, per_phase, shift, i32(x), i32(y), s.xy, c, slab, l);
        }
    }
}

// After the last slab: C += (1 − A)·background, guard band cropped, RGBA f32 out (the RGB
// image and the composited alpha A, before the background).
@compute @workgroup_size(8, 8)
fn finish_image(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    if x >= globals.width || y >= globals.height {
        return;
    }
    let p = (y + globals.guard_top) * globals.grid_w + x + globals.guard_left;
    let acc = accum[p];
    let c = finish(acc);
    let o = 4u * (y * globals.width + x);
    image[o] = c.x;
    image[o + 1u] = c.y;
    image[o + 2u] = c.z;
    image[o + 3u] = acc.w;
}
