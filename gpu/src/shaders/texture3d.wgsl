// The trilinear 3D-texture sampler: mirrors common/src/pixel/texture3d.rs (`axis` and `sample_lanes`).

#import shared/bindings
#import noise

struct Axis {
    i0: u32,
    i1: u32,
    f: f32,
}

// One axis: g = u·dim − 0.5 clamped to [0, dim−1] with selects (NaN → 0), floor, fraction.
fn texture_axis(u: f32, dim: u32) -> Axis {
    let hi = f32(max(dim, 1u) - 1u);
    var g = u * f32(dim) - 0.5;
    g = select(0.0, g, g > 0.0);
    g = select(hi, g, g < hi);
    let fl = floor(g);
    let f = g - fl;
    let fl1 = select(hi, fl + 1.0, fl < hi);
    return Axis(u32(fl), u32(fl1), f);
}

// Trilinear sample of the texture of material `m` at normalised coordinates.
fn texture_sample(m: MaterialHeader, u: f32, v: f32, w: f32) -> f32 {
    let base = m.texture;
    let dx = m.dims[0];
    let dy = m.dims[1];
    let dz = m.dims[2];
    let ax = texture_axis(u, dx);
    let ay = texture_axis(v, dy);
    let az = texture_axis(w, dz);
    let sy = dx;
    let sz = dx * dy;
    let r00 = ay.i0 * sy + az.i0 * sz;
    let r10 = ay.i1 * sy + az.i0 * sz;
    let r01 = ay.i0 * sy + az.i1 * sz;
    let r11 = ay.i1 * sy + az.i1 * sz;
    let c00 = lerp(ax.f, voxels[base + ax.i0 + r00], voxels[base + ax.i1 + r00]);
    let c10 = lerp(ax.f, voxels[base + ax.i0 + r10], voxels[base + ax.i1 + r10]);
    let c01 = lerp(ax.f, voxels[base + ax.i0 + r01], voxels[base + ax.i1 + r01]);
    let c11 = lerp(ax.f, voxels[base + ax.i0 + r11], voxels[base + ax.i1 + r11]);
    let c0 = lerp(ay.f, c00, c10);
    let c1 = lerp(ay.f, c01, c11);
    return lerp(az.f, c0, c1);
}
