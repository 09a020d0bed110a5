// Stage 1, convolution: mirrors cpu/src/kernels.rs. The gather sums tap by tap, corners
// (0,0), (1,0), (0,1), (1,1), each term `acc = acc + w·v` (no fma); reads outside the grid see
// the unoccluded light (1.0), or no occluder (0.0) in a depth plane (distance penumbra). Tap
// tables come from `KernelTable` (uploaded, never recomputed).

#import shared/constants
#import shared/bindings
#import hash

const OUTSIDE: f32 = 1.0;
const OUTSIDE_DEPTH: f32 = 0.0;

// `Plane::fetch` of light-buffer plane `base` (index of its pixel (0, 0)); `outside` beyond the
// grid (`Plane::outside`: OUTSIDE for light, OUTSIDE_DEPTH for a depth plane).
fn fetch(base: u32, x: i32, y: i32, outside: f32) -> f32 {
    if x >= 0 && y >= 0 && x < i32(globals.grid_w) && y < i32(globals.grid_h) {
        return light_prev[base + u32(y) * globals.row_len + u32(x)];
    }
    return outside;
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

// `gather`: one plane at (x, y) through `count` taps starting at tap `first`, shifted; reads
// beyond the grid see `outside`.
fn gather(base: u32, first: u32, count: u32, shift: vec2<i32>, x: i32, y: i32, outside: f32) -> f32 {
    var acc = 0.0;
    for (var k = 0u; k < count; k++) {
        let t = taps[first + k];
        let sx = x + t.dx + shift.x;
        let sy = y + t.dy + shift.y;
        acc = acc + t.w[0] * fetch(base, sx, sy, outside);
        acc = acc + t.w[1] * fetch(base, sx + 1, sy, outside);
        acc = acc + t.w[2] * fetch(base, sx, sy + 1, outside);
        acc = acc + t.w[3] * fetch(base, sx + 1, sy + 1, outside);
    }
    return acc;
}

// `distance_rows` (distance penumbra): the tap row of `light` at pixel (x, y) in `slab`, from the
// light's previous planes at the pixel itself (`base`: its plane 0's pixel (0, 0)). The occluded
// light u = channels − Σ I and the occlusion-weighted depth D give the mean occluder depth D / u;
// the distance h = slab − D / u is rounded (+ ½, truncated) and clamped to 1..=level_top by
// selects, h = 1 without an occluder (u ≤ OCCLUSION_EPS); `level_table` maps h to a level.
// `phase`: the pixel's phase within a level (PHASE_PER_PIXEL, PHASE_PER_SLAB); a schedule's phase
// is the level's own, `slab_phase[level · slabs + slab]`. The CPU's operation order throughout.
fn distance_row(light: LightHeader, base: u32, slab: u32, phase: u32, x: u32, y: u32) -> u32 {
    let ch = globals.channels;
    let at = base + y * globals.row_len + x;
    var lit = light_prev[at];
    for (var c = 1u; c < ch; c++) {
        lit = lit + light_prev[at + c * globals.grid_w];
    }
    let depth = light_prev[at + ch * globals.grid_w];
    let occluded = f32(ch) - lit;
    let has_occluder = occluded > globals.occlusion_eps;
    let mean_depth = depth / select(1.0, occluded, has_occluder);
    var h = (f32(slab) - mean_depth) + 0.5;
    let top = f32(light.level_top);
    h = select(h, 1.0, h < 1.0);
    h = select(h, top, h > top);
    h = select(1.0, h, has_occluder);
    // h is in [1, level_top] here (finite), where u32() truncates as Rust's `as i32 as u32` does.
    let level = level_table[light.level_of + u32(h)];
    var p = phase;
    if light.phase_mode == PHASE_SCHEDULE {
        p = level_table[light.level_phases + level * globals.slabs + slab];
    }
    return level * light.phase_count + p;
}
