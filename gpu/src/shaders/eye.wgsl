// The perspective camera's eye pass: mirrors cpu/src/sweep/eye.rs. Before each slab of the grid's
// sweep (sweep.wgsl), one invocation per image pixel takes its ray's step through the slab: its
// layer cursor over the eye's LDI (parity.wgsl), one shading point (shading.wgsl), the light read
// bilinearly from the grid's incoming light where the ray meets the slab (a per-slab zoom), and
// front-to-back compositing (composite.wgsl). The eye's LDI, cursors, colours and normals are
// bound at the sweep's slots (shared/bindings.wgsl); `eye_finish` adds the background.

#import shared/constants
#import shared/bindings
#import hash
#import noise
#import texture3d
#import parity
#import shading
#import composite

// Every light's channels read from the grid at one point (`MAX_LIGHT_CHANNELS` from the Rust side).
var<private> iin: array<f32, MAX_LIGHT_CHANNELS>;

@compute @workgroup_size(8, 8)
fn eye_slab(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    let view = eye_params;
    if x >= view.width || y >= view.height {
        return;
    }
    let p = y * view.width + x;
    let acc = accum[p];
    let turned = view.turned_round != 0u;
    if acc.w == 1.0 && !turned {
        // Opaque: compositing adds (1 − 1)·α·c, exactly 0, so nothing later changes the pixel
        // (back to front, nearer slabs still do).
        return;
    }
    let slab = slab_params.slab;
    let faces = slabs[slab];
    let front = faces.front;
    let back = faces.back;
    let state = cursors[p];
    let adv = advance(state.next, offsets[p + 1u], state.inside, back);
    cursors[p] = Cursor(adv.next, adv.inside);
    let crossed = adv.first != NO_CROSSING;
    var mesh = first_mesh(adv.inside);
    if crossed {
        mesh = frag_meta[adv.first] & MESH_MASK;
    }
    if mesh == NO_CROSSING {
        return;
    }
    let z = shading_depth(crossed, adv.first, faces, x, y);
    let g = ray_on_grid(x, y, z);
    let gx = g.x;
    let gy = g.y;
    // At a crossing, the light arriving at the surface: not the light of grid pixels already
    // past it (inside a closed mesh; through a thin shell).
    var skip = SKIP_NONE;
    if crossed {
        skip = SKIP_SHELL;
        if (globals.parity_meshes & (1u << mesh)) != 0u {
            skip = SKIP_INSIDE;
        }
    }
    // Turned round, a crossed surface is read one slab further back along each light's ray
    // (cpu/src/sweep/eye.rs `read_light`); `back` < 0: at the point itself.
    var back_along_light = -1.0;
    if turned && crossed {
        back_along_light = (z - front) * globals.inv_slab_distance + 1.0;
    }
    var n = vec3<f32>(0.0, 0.0, 0.0);
    if crossed {
        let o = normals[frag_meta[adv.first] >> MESH_BITS];
        n = vec3<f32>(o[0], o[1], o[2]);
    }
    for (var l = 0u; l < globals.lights; l++) {
        // A shell's side is the light's own.
        var skip_l = skip;
        if skip == SKIP_SHELL && lit_past(l, n) {
            skip_l = SKIP_SHELL_LIT_PAST;
        }
        var at = vec2<f32>(gx, gy);
        if back_along_light >= 0.0 {
            let d = lights[l].drift;
            at = vec2<f32>(gx - back_along_light * d[0], gy - back_along_light * d[1]);
        }
        read_grid_light(l, at.x, at.y, skip_l, mesh);
    }

    let mi = meshes[mesh].material;
    let m = materials[mi];
    var part = slab_part(mesh, state.inside, adv.inside, adv.first, adv.next - 1u, front, back);
    var e: TfEntry;
    if m.pre != NO_PRE {
        // Pre-integrated: the detail on the slab's faces along the ray (at a crossing, from the
        // crossing); the entry has the light's decay inside the slab in its colour.
        part.y = 0.0;
        var zf = front;
        if crossed {
            zf = z;
        }
        e = pre_transfer(m.pre, detail_on_ray(mesh, m, x, y, zf), detail_on_ray(mesh, m, x, y, back));
    } else {
        var value = 0.0;
        if m.tf_len > 1u {
            value = detail_at_grid(mesh, m, g, z);
        }
        e = transfer(m, value);
    }
    accum[p] = shade_sample(acc, mi, m, e, part, crossed, adv.first).acc;
}

// `ray_on_grid`: where eye pixel (x, y)'s ray meets view depth z_origin + z (turned round:
// z_origin − z, x mirrored), in grid pixel coordinates.
fn ray_on_grid(x: u32, y: u32, z: f32) -> vec2<f32> {
    let view = eye_params;
    var view_depth = view.z_origin + z;
    var offset_x = (f32(x) + 0.5) - view.centre.x;
    if view.turned_round != 0u {
        view_depth = view.z_origin - z;
        offset_x = view.centre.x - (f32(x) + 0.5);
    }
    let scale = view.scale + view_depth * view.zoom;
    return vec2<f32>(view.axis.x + offset_x * scale, view.axis.y + ((f32(y) + 0.5) - view.centre.y) * scale);
}

// The detail of mesh `mesh` (material `m`) where eye pixel (x, y)'s ray meets depth z (the
// CPU's `detail_at` at the grid image's pixel coordinates of that point).
fn detail_on_ray(mesh: u32, m: MaterialHeader, x: u32, y: u32, z: f32) -> f32 {
    return detail_at_grid(mesh, m, ray_on_grid(x, y, z), z);
}

// The detail of mesh `mesh` (material `m`) at grid position g and depth z (`on_image` then
// `detail_at` on the CPU).
fn detail_at_grid(mesh: u32, m: MaterialHeader, g: vec2<f32>, z: f32) -> f32 {
    let xi = (g.x - 0.5) - f32(globals.guard_left);
    let yi = (g.y - 0.5) - f32(globals.guard_top);
    return detail_value(m, to_detail(mesh, xi + 0.5, yi + 0.5, z));
}

const SKIP_NONE: u32 = 0u;
const SKIP_INSIDE: u32 = 1u;
const SKIP_SHELL: u32 = 2u;
const SKIP_SHELL_LIT_PAST: u32 = 3u;

// `lit_past`: whether light l reaches a thin shell of normal n from the side the grid's rays
// reach after crossing it (its travel and the grid's (0, 0, 1) cross the plane oppositely).
fn lit_past(l: u32, n: vec3<f32>) -> bool {
    let d = lights[l].drift;
    let ps = eye_params.pixel_size;
    let tx = d[0] * ps;
    let ty = d[1] * ps;
    let travel = (n.x * tx + n.y * ty) + n.z * globals.slab_distance;
    return (travel > 0.0) != (n.z > 0.0);
}

// `GridLight::past`: whether a read leaves grid pixel q out at the slab's front (`skip`
// SKIP_INSIDE: inside mesh `mesh`; SKIP_SHELL: through one of its fragments, a thin shell;
// SKIP_SHELL_LIT_PAST: not yet through it).
fn past(q: u32, skip: u32, mesh: u32) -> bool {
    if skip == SKIP_INSIDE {
        return (grid_cursors[q].inside & (1u << mesh)) != 0u;
    }
    if skip == SKIP_SHELL || skip == SKIP_SHELL_LIT_PAST {
        var through = false;
        for (var f = grid_offsets[q]; f < grid_cursors[q].next; f++) {
            if (grid_frag_meta[f] & MESH_MASK) == mesh {
                through = true;
            }
        }
        return through != (skip == SKIP_SHELL_LIT_PAST);
    }
    return false;
}

// Whether grid pixel (x, y) exists.
fn in_grid(x: i32, y: i32) -> bool {
    return x >= 0 && y >= 0 && x < i32(globals.grid_w) && y < i32(globals.grid_h);
}

// `read_one_light`: light l's channels into `iin`, bilinear in the grid's incoming light at grid
// position (gx, gy) (pixel centres at +0.5; outside the grid 1), leaving out the neighbours
// already past the crossed mesh at the slab's front (`past`) unless all four are.
fn read_grid_light(l: u32, gx: f32, gy: f32, skip: u32, mesh: u32) {
    let fx = gx - 0.5;
    let fy = gy - 0.5;
    let x0f = floor(fx);
    let y0f = floor(fy);
    let ax = fx - x0f;
    let ay = fy - y0f;
    let x0 = i32(x0f);
    let y0 = i32(y0f);
    let xs = array<i32, 4>(x0, x0 + 1, x0, x0 + 1);
    let ys = array<i32, 4>(y0, y0, y0 + 1, y0 + 1);
    let corner = array<f32, 4>((1.0 - ax) * (1.0 - ay), ax * (1.0 - ay), (1.0 - ax) * ay, ax * ay);
    let w = globals.grid_w;
    var weight = corner;
    for (var k = 0u; k < 4u; k++) {
        if in_grid(xs[k], ys[k]) && past(u32(ys[k]) * w + u32(xs[k]), skip, mesh) {
            weight[k] = 0.0;
        }
    }
    let total = ((weight[0] + weight[1]) + weight[2]) + weight[3];
    if total > 0.0 && skip != SKIP_NONE {
        for (var k = 0u; k < 4u; k++) {
            weight[k] = weight[k] / total;
        }
    } else {
        weight = corner;
    }
    let ch = globals.channels;
    for (var c = 0u; c < ch; c++) {
        var sum = 0.0;
        for (var k = 0u; k < 4u; k++) {
            var v = 1.0;
            if in_grid(xs[k], ys[k]) {
                v = light_prev[u32(ys[k]) * globals.row_len + (l * globals.planes + c) * w + u32(xs[k])];
            }
            sum = sum + weight[k] * v;
        }
        iin[l * ch + c] = sum;
    }
}

// After the last slab: C += (1 − A)·background, RGBA f32 out (as sweep.wgsl `finish_image`).
@compute @workgroup_size(8, 8)
fn eye_finish(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = gid.y;
    if x >= eye_params.width || y >= eye_params.height {
        return;
    }
    let p = y * eye_params.width + x;
    let acc = accum[p];
    let c = finish(acc);
    let o = 4u * p;
    image[o] = c.x;
    image[o + 1u] = c.y;
    image[o + 2u] = c.z;
    image[o + 3u] = acc.w;
}
