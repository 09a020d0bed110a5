// Stage 1, convolution: mirrors cpu/src/kernels.rs. The gather sums tap by tap, corners
// (0,0), (1,0), (0,1), (1,1), each term `acc = acc + w·v` (no fma); reads outside the grid see
// the unoccluded light (1.0). Tap tables come from `KernelTable` (uploaded, never recomputed).

const OUTSIDE: f32 = 1.0;
const PHASE_PER_PIXEL: u32 = 0u;
const PHASE_PER_SLAB: u32 = 1u;

// `Plane::fetch` of light-buffer plane `base` (index of its pixel (0, 0)).
fn fetch(base: u32, x: i32, y: i32) -> f32 {
    if x >= 0 && y >= 0 && x < i32(globals.grid_w) && y < i32(globals.grid_h) {
        return light_prev[base + u32(y) * globals.row_len + u32(x)];
    }
    return OUTSIDE;
}

// `phase_at`: the phase of light header `lh` in slab `slab` at pixel x given the row hash.
fn phase_at(lh: u32, slab: u32, slab_hash: u32, row: u32, x: u32) -> u32 {
    let mode = tu(lh + 3u);
    let bits = tu(lh + 2u);
    if mode == PHASE_PER_PIXEL {
        return phase_index(pixel_hash(row, x), bits);
    }
    if mode == PHASE_PER_SLAB {
        return phase_index(slab_hash, bits);
    }
    return tu(tu(lh + 5u) + slab);
}

// `gather`: one channel at (x, y) through `count` taps starting at word `taps`, shifted.
fn gather(base: u32, taps: u32, count: u32, shift: vec2<i32>, x: i32, y: i32) -> f32 {
    var acc = 0.0;
    for (var k = 0u; k < count; k++) {
        let t = taps + 6u * k;
        let sx = x + bitcast<i32>(tu(t)) + shift.x;
        let sy = y + bitcast<i32>(tu(t + 1u)) + shift.y;
        acc = acc + tf(t + 2u) * fetch(base, sx, sy);
        acc = acc + tf(t + 3u) * fetch(base, sx + 1, sy);
        acc = acc + tf(t + 4u) * fetch(base, sx, sy + 1);
        acc = acc + tf(t + 5u) * fetch(base, sx + 1, sy + 1);
    }
    return acc;
}
