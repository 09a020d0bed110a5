// The layered depth image on the GPU: mirrors cpu/src/ldi.rs and common/src/prepare/raster.rs.
//
// Coverage uses the same fixed-point vertices, the same integer edge functions and the same
// top-left rule as `TriangleSetup::covers`. WGSL has no i64, so the edge function
// `dx·(py − ay) − dy·(px − ax)` is evaluated exactly in 64-bit two's complement held in a
// vec2<u32> (lo, hi): each factor fits an i32 (vertices lie within ±2^21 px = ±2^29 fixed point,
// pixel centres within the grid), each product fits 61 bits, and the difference fits 62 bits.
// Depth is `(depth_ref + depth_dx·Δi) + depth_dy·Δj` in f32, in the CPU's order (perspective:
// the plane is the inverse depth, and the depth `1 / plane − origin`).
//
// Passes: `count` (atomic per-pixel counts), host prefix sum, `fill` (atomic slot claim, sort
// keys), `sort` (per-pixel sort by (sortable depth bits, triangle index), by rank).

#import shared/constants
#import shared/bindings

// Unsigned 32×32 → 64-bit product as (lo, hi), from 16-bit limbs.
fn mul_wide_u32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    let lo = (p00 & 0xffffu) | (mid << 16u);
    let hi = p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u);
    return vec2<u32>(lo, hi);
}

// Two's complement negation of a 64-bit value.
fn neg64(x: vec2<u32>) -> vec2<u32> {
    let lo = ~x.x + 1u;
    let hi = ~x.y + select(0u, 1u, lo == 0u);
    return vec2<u32>(lo, hi);
}

// Signed 32×32 → 64-bit product (exact).
fn mul_i32(a: i32, b: i32) -> vec2<u32> {
    let ua = select(u32(a), u32(-a), a < 0);
    let ub = select(u32(b), u32(-b), b < 0);
    let p = mul_wide_u32(ua, ub);
    return select(p, neg64(p), (a < 0) != (b < 0));
}

// a − b in 64-bit two's complement.
fn sub64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x - b.x;
    let borrow = select(0u, 1u, a.x < b.x);
    return vec2<u32>(lo, a.y - b.y - borrow);
}

// `is_top_left(dx, dy)`: dy < 0 || (dy == 0 && dx > 0).
fn is_top_left(dx: i32, dy: i32) -> bool {
    return dy < 0 || (dy == 0 && dx > 0);
}

// Whether edge k of triangle t, with its bias, covers the fixed-point point (px, py):
// `e + bias >= 0`, i.e. e >= 0 on top-left edges and e >= 1 on the others.
fn edge_covers(t: u32, k: u32, px: i32, py: i32) -> bool {
    let a = tris[t].v[k];
    let b = tris[t].v[(k + 1u) % 3u];
    let ax = a.x;
    let ay = a.y;
    let bx = b.x;
    let by = b.y;
    let dx = bx - ax;
    let dy = by - ay;
    let e = sub64(mul_i32(dx, py - ay), mul_i32(dy, px - ax));
    let non_negative = bitcast<i32>(e.y) >= 0;
    if is_top_left(dx, dy) {
        return non_negative;
    }
    return non_negative && (e.x != 0u || e.y != 0u);
}

fn covers(t: u32, i: i32, j: i32) -> bool {
    let px = i * FIXED_ONE + FIXED_ONE / 2;
    let py = j * FIXED_ONE + FIXED_ONE / 2;
    return edge_covers(t, 0u, px, py) && edge_covers(t, 1u, px, py) && edge_covers(t, 2u, px, py);
}

// `TriangleSetup::depth_at`: (depth_ref + depth_dx·Δi) + depth_dy·Δj.
fn depth_at(t: u32, i: i32, j: i32) -> f32 {
    let tri = tris[t];
    let di = f32(i - tri.bbox[0]);
    let dj = f32(j - tri.bbox[1]);
    let a = tri.depth_dx * di;
    let b = tri.depth_dy * dj;
    return (tri.depth_ref + a) + b;
}

// `RasterSetup::fragment_depth`: the plane, or in perspective 1 / plane − origin.
fn fragment_depth(t: u32, i: i32, j: i32) -> f32 {
    let plane = depth_at(t, i, j);
    if ldi_params.perspective != 0u {
        return 1.0 / plane - ldi_params.depth_origin;
    }
    return plane;
}

// `sortable_bits`: unsigned order of the result is the float's total order.
fn sortable_bits(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    if (b & 0x80000000u) != 0u {
        return ~b;
    }
    return b | 0x80000000u;
}

fn item_index(gid: vec3<u32>) -> u32 {
    return gid.x + gid.y * ldi_params.stride;
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = item_index(gid);
    if n >= ldi_params.items {
        return;
    }
    let item = items[n];
    let t = item.triangle;
    let j = i32(item.row);
    for (var i = tris[t].bbox[0]; i <= tris[t].bbox[2]; i++) {
        if covers(t, i, j) {
            atomicAdd(&counts[u32(j) * ldi_params.width + u32(i)], 1u);
        }
    }
}

@compute @workgroup_size(64)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = item_index(gid);
    if n >= ldi_params.items {
        return;
    }
    let item = items[n];
    let t = item.triangle;
    let j = i32(item.row);
    for (var i = tris[t].bbox[0]; i <= tris[t].bbox[2]; i++) {
        if covers(t, i, j) {
            let slot = atomicAdd(&cursor[u32(j) * ldi_params.width + u32(i)], 1u);
            key_depth[slot] = sortable_bits(fragment_depth(t, i, j));
            key_tri[slot] = t;
        }
    }
}

// Per-pixel sort by (depth key, triangle index), one invocation per fragment: its rank among
// its pixel's fragments (keys are unique: a triangle covers a pixel at most once) is where it goes.
// The result does not depend on the order in which `fill` claimed the slots. O(layers²) work per
// pixel but no in-place hazards and balanced over fragments.
@compute @workgroup_size(64)
fn sort(@builtin(global_invocation_id) gid: vec3<u32>) {
    let f = item_index(gid);
    if f >= ldi_params.items {
        return;
    }
    // The pixel p with offsets[p] <= f < offsets[p + 1]: the last p with offsets[p] <= f.
    var lo = 0u;
    var hi = ldi_params.pixels;
    loop {
        if lo >= hi {
            break;
        }
        let mid = (lo + hi + 1u) / 2u;
        if offsets[mid] <= f {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    let a = offsets[lo];
    let b = offsets[lo + 1u];
    let kd = key_depth[f];
    let kt = key_tri[f];
    var rank = 0u;
    for (var k = a; k < b; k++) {
        let d = key_depth[k];
        if d < kd || (d == kd && key_tri[k] < kt) {
            rank += 1u;
        }
    }
    sorted_depth[a + rank] = kd;
    sorted_tri[a + rank] = kt;
}
