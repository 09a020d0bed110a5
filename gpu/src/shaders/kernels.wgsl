// Stage 1, convolution: mirrors cpu/src/kernels.rs. The gather sums tap by tap, corners
// (0,0), (1,0), (0,1), (1,1), each term `acc = acc + w·v` (no fma); reads outside the grid see
// the unoccluded light (1.0). Tap tables come from `KernelTable` (uploaded, never recomputed).

#import shared/constants
#import shared/bindings
#import hash

const OUTSIDE: f32 = 1.0;

// `Plane::fetch` of light-buffer plane `base` (index of its pixel (0, 0)).
fn fetch(base: u32, x: i32, y: i32) -> f32 {
    if x >= 0 && y >= 0 && x < i32(globals.grid_w) && y < i32(globals.grid_h) {
        return light_prev[base + u32(y) * globals.row_len + u32(x)];
    }
    return OUTSIDE;
}

// `phase_at`: the phase of `light` in the slab of `ls` at pixel x given the row hash.
fn phase_at(light: LightHeader, ls: LightSlab, row: u32, x: u32) -> u32 {
    let bits = light.phase_bits;
    if light.phase_mode == PHASE_PER_PIXEL {
        return phase_index(pixel_hash(row, x), bits);
    }
    if light.phase_mode == PHASE_PER_SLAB {
        return phase_index(ls.hash, bits);
    }
    return ls.phase;
}

// `gather`: one channel at (x, y) through `count` taps starting at tap `first`, shifted.
fn gather(base: u32, first: u32, count: u32, shift: vec2<i32>, x: i32, y: i32) -> f32 {
    var acc = 0.0;
    for (var k = 0u; k < count; k++) {
        let t = taps[first + k];
        let sx = x + t.dx + shift.x;
        let sy = y + t.dy + shift.y;
        acc = acc + t.w[0] * fetch(base, sx, sy);
        acc = acc + t.w[1] * fetch(base, sx + 1, sy);
        acc = acc + t.w[2] * fetch(base, sx, sy + 1);
        acc = acc + t.w[3] * fetch(base, sx + 1, sy + 1);
    }
    return acc;
}
