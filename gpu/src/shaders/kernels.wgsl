// Stage 1, convolution: mirrors cpu/src/kernels.rs. The gather sums tap by tap, corners
// (0,0), (1,0), (0,1), (1,1), each term `acc = acc + w·v` (no fma); reads outside the grid see
// the unoccluded light (1.0), or no occluder (0.0) in a depth plane (distance penumbra). Tap
// tables come from `KernelTable` (uploaded, never recomputed).

#import shared/constants
#import shared/bindings
#import hash
#import composite

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

// The gathering pixel, as `gather_held` reads corners for it (cpu/src/sweep/pixel.rs
// `held_fix`): its position, whether it reads held corners behind their surfaces as no light
// (`held_lit_side`, not held itself), and the surface it lies on.
var<private> reader_q: vec2<i32>;
var<private> reader_hiding: bool;
var<private> reader_surface: ReaderSurface;

// `gather_held` (cpu/src/kernels.rs) for plane `plane` of light l (a channel, or the depth plane
// at `channels`): `gather`, each corner read as `held_fix` says (`held_fetch`).
fn gather_held(base: u32, first: u32, count: u32, shift: vec2<i32>, x: i32, y: i32, outside: f32, plane: u32, slab: u32, l: u32) -> f32 {
    var acc = 0.0;
    for (var k = 0u; k < count; k++) {
        let t = taps[first + k];
        let sx = x + t.dx + shift.x;
        let sy = y + t.dy + shift.y;
        acc = acc + t.w[0] * held_fetch(base, sx, sy, outside, plane, slab, l);
        acc = acc + t.w[1] * held_fetch(base, sx + 1, sy, outside, plane, slab, l);
        acc = acc + t.w[2] * held_fetch(base, sx, sy + 1, outside, plane, slab, l);
        acc = acc + t.w[3] * held_fetch(base, sx + 1, sy + 1, outside, plane, slab, l);
    }
    return acc;
}

// One corner of `gather_held`: a held corner the reader lies behind (`hides`) as no light, or in
// the depth plane as light removed at its crossing's slab; else a corner released on the
// reader's surface as it gathered the plane then (`served`); else the buffer's value.
fn held_fetch(base: u32, sx: i32, sy: i32, outside: f32, plane: u32, slab: u32, l: u32) -> f32 {
    let c = vec2<i32>(sx, sy);
    if reader_hiding {
        let crossing = hides(reader_q, c, slab, lights[l].drift);
        if crossing != NO_HELD_SLAB {
            if plane == globals.channels {
                return f32(crossing) * f32(globals.channels);
            }
            return 0.0;
        }
    }
    if reader_surface.ok {
        let s = served(reader_q, reader_surface, c, slab, l, plane);
        if s.ok {
            return s.value;
        }
    }
    return fetch(base, sx, sy, outside);
}

// `LevelAt`: where the level search stands: the slab's coordinate in the depth plane's units
// (a slab grid's slab index) and, on a soft point light's grid (`scaled`), the slab's step there.
struct LevelAt {
    coord: f32,
    step: f32,
    scaled: bool,
}

// `LevelAt::slab`: slab `slab` of a slab grid.
fn slab_level(slab: u32) -> LevelAt {
    return LevelAt(f32(slab), 1.0, false);
}

// `DepthScale`'s ψ at slab coordinate k (its f32 bits after the level tables).
fn psi(k: u32) -> f32 {
    return bitcast<f32>(level_table[globals.psi_at + k]);
}

// `depth_coord`: the depth plane's coordinate of removal depth t (slabs): t itself, or on a soft
// point light's grid `DepthScale::at` (linear between slab coordinates, the end steps continued;
// the floor clamped in float as Rust's `max(0.0)` (NaN: 0) and `min(last)`).
fn depth_coord(t: f32) -> f32 {
    if globals.depth_scaled == 0u {
        return t;
    }
    var fl = floor(t);
    if !(fl > 0.0) {
        fl = 0.0;
    }
    let k = u32(min(fl, f32(globals.psi_last)));
    let f = t - f32(k);
    return psi(k) + f * (psi(k + 1u) - psi(k));
}

// `level_at`: slab `slab`'s `LevelAt` (on a soft point light's grid its ψ and its step
// `DepthScale::step`, the step from slab k − 1 with k clamped to 1..=psi.len() − 1).
fn level_at(slab: u32) -> LevelAt {
    if globals.depth_scaled == 0u {
        return slab_level(slab);
    }
    let k = clamp(slab, 1u, globals.psi_last + 1u);
    return LevelAt(depth_coord(f32(slab)), psi(k) - psi(k - 1u), true);
}

// `pixel_level` (distance penumbra): the level of a pixel whose light, after a slab, has the
// occluded part `occluded` (channels − Σ I) and the occlusion-weighted depth `depth`, in the slab
// at `at`: the mean occluder depth depth / occluded, the distance h = coord − depth / occluded
// (on a point light's grid n·h − (n² − 1)/2 for the slab's step n) rounded (+ ½, truncated) and
// clamped to 1..=level_top by selects, `level_of[h]` from `level_table`; LIT_LEVEL without an
// occluder (occluded ≤ OCCLUSION_EPS). The CPU's order.
fn pixel_level(light: LightHeader, occluded: f32, depth: f32, at: LevelAt) -> u32 {
    let has_occluder = occluded > globals.occlusion_eps;
    let mean_depth = depth / select(1.0, occluded, has_occluder);
    var h = at.coord - mean_depth;
    if at.scaled {
        h = at.step * h - (at.step * at.step - 1.0) * 0.5;
    }
    h = h + 0.5;
    let top = f32(light.level_top);
    h = select(h, 1.0, h < 1.0);
    h = select(h, top, h > top);
    h = select(1.0, h, has_occluder);
    // h is in [1, level_top] here (finite), where u32() truncates as Rust's `as i32 as u32` does.
    let level = level_table[light.level_of + u32(h)];
    return select(LIT_LEVEL, level, has_occluder);
}

// `level_rows`: the tap row of `level` at `phase`, or for a scheduled kernel the level's own
// phase of `slab` (`slab_phase[level · slabs + slab]`).
fn level_row(light: LightHeader, level: u32, phase: u32, slab: u32) -> u32 {
    if light.phase_mode == PHASE_SCHEDULE {
        return level * light.phase_count + level_table[light.level_phases + level * globals.slabs + slab];
    }
    return level * light.phase_count + phase;
}

// Light `base`'s level plane of the previous slab at (x, y) (`base`: the light's pixel (0, 0),
// rows `lights · grid_w` apart); LIT_LEVEL beyond the grid.
fn fetch_level(base: u32, x: i32, y: i32) -> u32 {
    if x >= 0 && y >= 0 && x < i32(globals.grid_w) && y < i32(globals.grid_h) {
        return level_prev[base + u32(y) * globals.lights * globals.grid_w + u32(x)];
    }
    return LIT_LEVEL;
}

// `distance_rows` (distance penumbra): the tap row of light `l` at pixel (x, y) in `slab`. The
// pixel's own level (level 0's when it has none) gives a row; the smallest level among its own
// and the levels at the four corners of every tap of that row (slab shift included, padding taps
// too) is the nearest occluder's in reach, whose row (level 0's when there is none) the pixel
// gathers through. `phase`: the pixel's phase within a level (PHASE_PER_PIXEL, PHASE_PER_SLAB).
fn distance_row(light: LightHeader, l: u32, slab: u32, phase: u32, shift: vec2<i32>, x: u32, y: u32) -> u32 {
    let base = l * globals.grid_w;
    let own = level_prev[base + y * globals.lights * globals.grid_w + x];
    let own_row = level_row(light, select(own, 0u, own == LIT_LEVEL), phase, slab);
    var nearest = own;
    let first = light.taps + light.taps_per_phase * own_row;
    for (var k = 0u; k < light.taps_per_phase; k++) {
        let t = taps[first + k];
        let sx = i32(x) + t.dx + shift.x;
        let sy = i32(y) + t.dy + shift.y;
        nearest = min(nearest, fetch_level(base, sx, sy));
        nearest = min(nearest, fetch_level(base, sx + 1, sy));
        nearest = min(nearest, fetch_level(base, sx, sy + 1));
        nearest = min(nearest, fetch_level(base, sx + 1, sy + 1));
    }
    return level_row(light, select(nearest, 0u, nearest == LIT_LEVEL), phase, slab);
}
