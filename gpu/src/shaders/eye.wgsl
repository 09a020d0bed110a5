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
    if point_params.on != 0u {
        // A point light (the grid's one light): the direction to it from this sample, its
        // centre's falloff, cone and pattern in its colour.
        terms = point_terms(ray_in_frame(x, y, z), point_params.phase[mesh]);
        terms_on = true;
    }
    accum[p] = shade_sample(acc, mi, m, e, part, crossed, adv.first).acc;
}

// `view_depth`: the eye's view depth of the grid's relative depth z (turned round z_origin − z).
fn view_depth(z: f32) -> f32 {
    if eye_params.turned_round != 0u {
        return eye_params.z_origin - z;
    }
    return eye_params.z_origin + z;
}

// Eye pixel (x, y)'s centre's offset from the image centre, image pixels (turned round, x
// mirrored: the turned grid's x axis is the image's reversed).
fn pixel_offset(x: u32, y: u32) -> vec2<f32> {
    let view = eye_params;
    var offset_x = (f32(x) + 0.5) - view.centre.x;
    if view.turned_round != 0u {
        offset_x = view.centre.x - (f32(x) + 0.5);
    }
    return vec2<f32>(offset_x, (f32(y) + 0.5) - view.centre.y);
}

// `ray_on_grid`: where eye pixel (x, y)'s ray meets view depth z_origin + z (turned round:
// z_origin − z, x mirrored), in grid pixel coordinates.
fn ray_on_grid(x: u32, y: u32, z: f32) -> vec2<f32> {
    let view = eye_params;
    let o = pixel_offset(x, y);
    let depth = view_depth(z);
    let scale = view.scale + depth * view.zoom;
    if point_params.on != 0u {
        // A point light's grid: the ray's offset from the light's centre, projected from it.
        let k = point_params.focal / (depth - point_params.depth);
        let c = point_params.offset;
        return vec2<f32>(view.axis.x + (o.x * scale - c.x) * k, view.axis.y + (o.y * scale - c.y) * k);
    }
    return vec2<f32>(view.axis.x + o.x * scale, view.axis.y + o.y * scale);
}

// `ray_in_frame`: where eye pixel (x, y)'s ray meets relative depth z in the eye's slab-grid
// frame of a point light's grid (`point_params`' coordinates; turned round the turned frame's).
fn ray_in_frame(x: u32, y: u32, z: f32) -> vec3<f32> {
    let view = eye_params;
    let scale = view.scale + view_depth(z) * view.zoom;
    let fa = point_params.frame_axis;
    let o = pixel_offset(x, y);
    return vec3<f32>(fa.x + o.x * scale, fa.y + o.y * scale, z);
}

// `PointShading::terms`: the shading's terms of the point light at `p` (the eye's slab-grid
// frame) for a medium of Henyey–Greenstein constants `phase`, both colours times the light its
// centre gives there (`cone·pattern / |X − P|²`, 0 at the centre). The CPU's operations in its
// order.
fn point_terms(p: vec3<f32>, phase: vec4<f32>) -> LightTerms {
    let ps = point_params.pixel_size;
    let d = vec3<f32>((point_params.center.x - p.x) * ps, (point_params.center.y - p.y) * ps, point_params.center.z - p.z);
    let d2 = (d.x * d.x + d.y * d.y) + d.z * d.z;
    // The direction to the viewer is (0, 0, view_z).
    var view_z = -1.0;
    if point_params.turned != 0u {
        view_z = 1.0;
    }
    // The horizon's spread: the light's variance over the squared distance, towards it.
    var iso = 0.0;
    if d2 > 0.0 {
        iso = point_params.center.w / d2;
    }
    var t = vec3<f32>(0.0, 0.0, view_z);
    var falloff = vec3<f32>(0.0, 0.0, 0.0);
    if d2 > 0.0 {
        let len = sqrt(d2);
        t = vec3<f32>(d.x / len, d.y / len, d.z / len);
        var cone = 1.0;
        if point_params.spot != 0u {
            cone = cone_factor(t);
        }
        falloff = vec3<f32>(cone / d2, cone / d2, cone / d2);
        if point_params.pattern != 0u {
            let v = pattern_at(d);
            falloff = vec3<f32>((cone * v.x) / d2, (cone * v.y) / d2, (cone * v.z) / d2);
        }
    }
    let hv = vec3<f32>(t.x, t.y, t.z + view_z);
    let hl2 = (hv.x * hv.x + hv.y * hv.y) + hv.z * hv.z;
    var h = vec3<f32>(0.0, 0.0, view_z);
    if hl2 > 0.0 {
        let len = sqrt(hl2);
        h = vec3<f32>(hv.x / len, hv.y / len, hv.z / len);
    }
    let hk = (h.x * t.x + h.y * t.y) + h.z * t.z;
    let q = 1.0 - hk;
    let q2 = q * q;
    let fresnel_p = (q2 * q2) * q;
    let c = point_params.color;
    var lc = vec3<f32>(c.x, c.y, c.z);
    // cos θ between the travel (−t) and the direction to the viewer.
    var cos = t.z;
    if point_params.turned != 0u {
        cos = -t.z;
    }
    if phase.z != 0.0 {
        let xp = phase.y - phase.z * cos;
        let factor = phase.x / (xp * sqrt(xp));
        lc = vec3<f32>(c.x * factor, c.y * factor, c.z * factor);
    }
    // Turned round, the direction to the light and the half vector negated (the shading faces
    // normals towards −z, the viewer's side reversed).
    var tl = t;
    var hh = h;
    if point_params.turned != 0u {
        tl = -t;
        hh = -h;
    }
    return LightTerms(
        vec3<f32>(lc.x * falloff.x, lc.y * falloff.y, lc.z * falloff.z),
        vec3<f32>(c.x * falloff.x, c.y * falloff.y, c.z * falloff.z),
        array<f32, 3>(tl.x, tl.y, tl.z),
        array<f32, 3>(hh.x, hh.y, hh.z),
        array<f32, 2>(fresnel_p / hk, (1.0 - fresnel_p) / hk),
        array<f32, 4>(0.0, 0.0, 0.0, iso),
        true,
    );
}

// `cone_factor`: the spot's smoothstep in the cosine for unit direction t towards the light.
fn cone_factor(t: vec3<f32>) -> f32 {
    let a = point_params.axis;
    let cos = 0.0 - ((t.x * a.x + t.y * a.y) + t.z * a.z);
    let inner = point_params.inner;
    let outer = point_params.outer;
    if cos >= inner {
        return 1.0;
    }
    if cos > outer {
        let s = (cos - outer) / (inner - outer);
        return s * s * (3.0 - 2.0 * s);
    }
    return 0.0;
}

// `pattern_at`: a spot pattern's value per channel for emission along −d (d towards the light),
// where the ray from the centre meets the unit plane along the axis; 0 at 90° or more.
fn pattern_at(d: vec3<f32>) -> vec3<f32> {
    let o = vec3<f32>(0.0 - d.x, 0.0 - d.y, 0.0 - d.z);
    let along = (o.x * point_params.axis.x + o.y * point_params.axis.y) + o.z * point_params.axis.z;
    if !(along > 0.0) {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    let a = ((o.x * point_params.right.x + o.y * point_params.right.y) + o.z * point_params.right.z) / along;
    let b = ((o.x * point_params.down.x + o.y * point_params.down.y) + o.z * point_params.down.z) / along;
    let tx = ((a - point_params.pattern_centre.x) / point_params.pattern_size.x + 0.5) * f32(point_params.pattern_width);
    let ty = ((b - point_params.pattern_centre.y) / point_params.pattern_size.y + 0.5) * f32(point_params.pattern_height);
    return vec3<f32>(pattern_sample(tx, ty, 0u), pattern_sample(tx, ty, 1u), pattern_sample(tx, ty, 2u));
}

// `Pattern::sample_f32`: bilinear at texel coordinates (tx, ty), clamped to the edge texels.
fn pattern_sample(tx: f32, ty: f32, c: u32) -> f32 {
    let w = f32(point_params.pattern_width);
    let h = f32(point_params.pattern_height);
    let fx = tx - 0.5;
    let fy = ty - 0.5;
    let x0f = floor(fx);
    let y0f = floor(fy);
    let ax = fx - x0f;
    let ay = fy - y0f;
    let x0 = i32(clamp(x0f, -1.0, w));
    let y0 = i32(clamp(y0f, -1.0, h));
    let top = texel(x0, y0, c) * (1.0 - ax) + texel(x0 + 1, y0, c) * ax;
    let bottom = texel(x0, y0 + 1, c) * (1.0 - ax) + texel(x0 + 1, y0 + 1, c) * ax;
    return top * (1.0 - ay) + bottom * ay;
}

// A pattern texel's channel c, (x, y) clamped to the image.
fn texel(x: i32, y: i32, c: u32) -> f32 {
    let w = i32(point_params.pattern_width);
    let xc = u32(clamp(x, 0, w - 1));
    let yc = u32(clamp(y, 0, i32(point_params.pattern_height) - 1));
    return spot_pattern[(yc * u32(w) + xc) * 3u + c];
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
    return detail_at(mesh, m, xi + 0.5, yi + 0.5, z);
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
