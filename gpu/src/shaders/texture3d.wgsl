// The trilinear 3D-texture sampler: mirrors common/src/pixel/texture3d.rs (`axis` and `sample`)
// and, for bricked textures, common/src/pixel/volume.rs (`BrickedTexture3d::sample`).

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

// Voxel (x, y, z) of material `m`'s bricked texture: its brick's slot from the index table (an
// exact f32 integer per brick), then the voxel in the slot's 512.
fn brick_voxel(m: MaterialHeader, x: u32, y: u32, z: u32) -> f32 {
    let brick = ((x >> 3u) + (y >> 3u) * m.bricks[0]) + (z >> 3u) * (m.bricks[0] * m.bricks[1]);
    let slot = u32(voxels[m.texture + brick]);
    let local = ((x & 7u) + ((y & 7u) << 3u)) + ((z & 7u) << 6u);
    return voxels[m.pool + (slot << 9u) + local];
}

// Trilinear sample of material `m`'s bricked texture: the dense sampler's axes and lerps, each
// corner read through the brick table.
fn bricked_sample(m: MaterialHeader, u: f32, v: f32, w: f32) -> f32 {
    let ax = texture_axis(u, m.dims[0]);
    let ay = texture_axis(v, m.dims[1]);
    let az = texture_axis(w, m.dims[2]);
    let c00 = lerp(ax.f, brick_voxel(m, ax.i0, ay.i0, az.i0), brick_voxel(m, ax.i1, ay.i0, az.i0));
    let c10 = lerp(ax.f, brick_voxel(m, ax.i0, ay.i1, az.i0), brick_voxel(m, ax.i1, ay.i1, az.i0));
    let c01 = lerp(ax.f, brick_voxel(m, ax.i0, ay.i0, az.i1), brick_voxel(m, ax.i1, ay.i0, az.i1));
    let c11 = lerp(ax.f, brick_voxel(m, ax.i0, ay.i1, az.i1), brick_voxel(m, ax.i1, ay.i1, az.i1));
    let c0 = lerp(ay.f, c00, c10);
    let c1 = lerp(ay.f, c01, c11);
    return lerp(az.f, c0, c1);
}

// Trilinear sample of the texture of material `m` at normalised coordinates.
fn texture_sample(m: MaterialHeader, u: f32, v: f32, w: f32) -> f32 {
    if m.has_texture == TEXTURE_BRICKED {
        return bricked_sample(m, u, v, w);
    }
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
