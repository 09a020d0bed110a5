// Sub-pixel shadows (sweep.subpixel_shadows, distance penumbra): mirrors cpu/src/subpixel.rs
// function for function. A pixel that crosses an opaque surface is shaded with its light read
// where the exact drift from its mean occluder puts it (`exact_shift`), bilinearly between four
// gathers through its own tap row (`shifted_gather`); the light buffer keeps the carried light.
// An opaque crossing records its removed light at its place inside the slab (`removal_depth`).

#import shared/constants
#import shared/bindings
#import kernels

// `MIN_PART`: the smallest part of its slab a crossing is recorded at.
const MIN_PART: f32 = 0.00390625;

// `removal_depth`: slab + part − ½, part at least MIN_PART (a medium's slab is part ½).
fn removal_depth(slab: u32, part: f32) -> f32 {
    return f32(slab) + (max(part, MIN_PART) - 0.5);
}

// `exact_shift` of light l at a crossing at `part` of slab `slab`, from its gathered channels'
// sum `lit` and depth plane `depth` through the tap row of level `row_level`: (shift x, shift y,
// 1), or (0, 0, 0) where unoccluded or where the mean occluder depth's level is not `row_level`
// (occluders at several depths).
fn exact_shift(l: u32, slab: u32, part: f32, lit: f32, depth: f32, row_level: u32) -> vec3<f32> {
    let occluded = f32(globals.channels) - lit;
    if !(occluded > globals.occlusion_eps) {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    if pixel_level(lights[l], occluded, depth, slab_level(slab)) != row_level {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    let t = depth / occluded + 0.5;
    let last = f32(globals.slabs) - 1.0;
    let j = clamp(floor(t), 0.0, last);
    let part_j = clamp(t - j, 0.0, 1.0);
    let ek = light_slabs[l * globals.slabs + slab].residual;
    let ej = light_slabs[l * globals.slabs + u32(j)].residual;
    let along = part_j - part;
    let drift = lights[l].drift;
    let sx = (ek[0] - ej[0]) + along * drift[0];
    let sy = (ek[1] - ej[1]) + along * drift[1];
    return vec3<f32>(sx, sy, 1.0);
}

// `shifted_gather` of one light plane (`base`) through `count` taps from `first`: the gathers at
// the whole-pixel origins around (x, y) + s, blended as a + f·(b − a) along x, then along y; an
// axis whose fraction is 0 gathers once.
fn shifted_gather(base: u32, first: u32, count: u32, shift: vec2<i32>, x: i32, y: i32, s: vec2<f32>, plane: u32, slab: u32, l: u32) -> f32 {
    let ix = floor(s.x);
    let iy = floor(s.y);
    let fx = s.x - ix;
    let fy = s.y - iy;
    let ox = x + i32(ix);
    let oy = y + i32(iy);
    var top = shifted_read(base, first, count, shift, ox, oy, plane, slab, l);
    if fx != 0.0 {
        let b = shifted_read(base, first, count, shift, ox + 1, oy, plane, slab, l);
        top = top + fx * (b - top);
    }
    if fy == 0.0 {
        return top;
    }
    var bottom = shifted_read(base, first, count, shift, ox, oy + 1, plane, slab, l);
    if fx != 0.0 {
        let b = shifted_read(base, first, count, shift, ox + 1, oy + 1, plane, slab, l);
        bottom = bottom + fx * (b - bottom);
    }
    return top + fy * (bottom - top);
}

// One whole-pixel gather of `shifted_gather`: through `gather_held` where a surface holds (the
// CPU reads corners so near held or released pixels; elsewhere the same bits), else `gather`.
fn shifted_read(base: u32, first: u32, count: u32, shift: vec2<i32>, x: i32, y: i32, plane: u32, slab: u32, l: u32) -> f32 {
    if globals.surface_holds != 0u {
        return gather_held(base, first, count, shift, x, y, OUTSIDE, plane, slab, l);
    }
    return gather(base, first, count, shift, x, y, OUTSIDE);
}
