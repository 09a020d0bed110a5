// The layered depth image on the GPU: mirrors cpu/src/ldi.rs and common/src/raster.rs.
//
// Coverage uses the same fixed-point vertices, the same integer edge functions and the same
// top-left rule as `TriangleSetup::covers`. WGSL has no i64, so the edge function
// `dx·(py − ay) − dy·(px − ax)` is evaluated exactly in 64-bit two's complement held in a
// vec2<u32> (lo, hi): each factor fits an i32 (vertices lie within ±2^21 px = ±2^29 fixed point,
// pixel centres within the grid), each product fits 61 bits, and the difference fits 62 bits.
// Depth is `(depth_ref + depth_dx·Δi) + depth_dy·Δj` in f32, in the CPU's order.
//
// Passes: `count` (atomic per-pixel counts), host prefix sum, `fill` (atomic slot claim, sort
// keys), `sort` (per-pixel sort by (sortable depth bits, triangle index), by rank).

struct Params {
    items: u32,       // (triangle, row) work items
    width: u32,       // grid width
    height: u32,      // grid height
    pixels: u32,      // width · height
    stride: u32,      // invocations per dispatch row (x groups · 64)
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// Triangle t: words 16t.. = v0x v0y v1x v1y v2x v2y (i32), bbox x0 y0 x1 y1 (i32),
// depth_ref depth_dx depth_dy (f32 bits), mesh, pad, pad.
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> tris: array<u32>;
@group(0) @binding(2) var<storage, read> items: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> key_depth: array<u32>;
@group(0) @binding(6) var<storage, read_write> key_tri: array<u32>;
@group(0) @binding(7) var<storage, read> offsets: array<u32>;
@group(0) @binding(8) var<storage, read_write> sorted_depth: array<u32>;
@group(0) @binding(9) var<storage, read_write> sorted_tri: array<u32>;

const FIXED_ONE: i32 = 256;

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

fn tri_i(t: u32, k: u32) -> i32 {
    return bitcast<i32>(tris[16u * t + k]);
}

fn tri_f(t: u32, k: u32) -> f32 {
    return bitcast<f32>(tris[16u * t + k]);
}

// `is_top_left(dx, dy)`: dy < 0 || (dy == 0 && dx > 0).
fn is_top_left(dx: i32, dy: i32) -> bool {
    return dy < 0 || (dy == 0 && dx > 0);
}

// Whether edge k of triangle t, with its bias, covers the fixed-point point (px, py):
// `e + bias >= 0`, i.e. e >= 0 on top-left edges and e >= 1 on the others.
fn edge_covers(t: u32, k: u32, px: i32, py: i32) -> bool {
    let k1 = (k + 1u) % 3u;
    let ax = tri_i(t, 2u * k);
    let ay = tri_i(t, 2u * k + 1u);
    let bx = tri_i(t, 2u * k1);
    let by = tri_i(t, 2u * k1 + 1u);
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
    let di = f32(i - tri_i(t, 6u));
    let dj = f32(j - tri_i(t, 7u));
    let a = tri_f(t, 11u) * di;
    let b = tri_f(t, 12u) * dj;
    return (tri_f(t, 10u) + a) + b;
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
    return gid.x + gid.y * params.stride;
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = item_index(gid);
    if n >= params.items {
        return;
    }
    let item = items[n];
    let t = item.x;
    let j = i32(item.y);
    for (var i = tri_i(t, 6u); i <= tri_i(t, 8u); i++) {
        if covers(t, i, j) {
            atomicAdd(&counts[u32(j) * params.width + u32(i)], 1u);
        }
    }
}

@compute @workgroup_size(64)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = item_index(gid);
    if n >= params.items {
        return;
    }
    let item = items[n];
    let t = item.x;
    let j = i32(item.y);
    for (var i = tri_i(t, 6u); i <= tri_i(t, 8u); i++) {
        if covers(t, i, j) {
            let slot = atomicAdd(&cursor[u32(j) * params.width + u32(i)], 1u);
            key_depth[slot] = sortable_bits(depth_at(t, i, j));
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
    if f >= params.items {
        return;
    }
    // The pixel p with offsets[p] <= f < offsets[p + 1]: the last p with offsets[p] <= f.
    var lo = 0u;
    var hi = params.pixels;
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
