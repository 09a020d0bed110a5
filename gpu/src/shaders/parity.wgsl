// Stage 2, intersection: mirrors cpu/src/parity.rs. The pixel's cursor advances past every
// fragment in front of the slab's back face, toggling the mesh's inside bit, and remembers the
// first fragment crossed. Fragment meta is `mesh | triangle << MESH_BITS`. Open meshes are thin
// shells: their bits are clear in `globals.parity_meshes`, so their crossings toggle nothing.

#import shared/constants
#import shared/bindings
#import noise

const NO_CROSSING: u32 = 0xffffffffu;

struct Advance {
    next: u32,
    inside: u32,
    first: u32,
}

fn advance(next0: u32, end: u32, inside0: u32, back_face: f32) -> Advance {
    var r = Advance(next0, inside0, NO_CROSSING);
    loop {
        if r.next >= end {
            break;
        }
        if !(frag_depth[r.next] < back_face) {
            break;
        }
        if r.first == NO_CROSSING {
            r.first = r.next;
        }
        r.inside = r.inside ^ ((1u << (frag_meta[r.next] & MESH_MASK)) & globals.parity_meshes);
        r.next = r.next + 1u;
    }
    return r;
}

// `slab_part`: where in its slab [front, back) the pixel meets the medium of `mesh`, which it
// shades there: x = the part of the slab inside the mesh, y = how far the light has travelled in
// the slab's medium where it lights the sample (the middle of that part, x / 2), in slab
// thicknesses (see cpu/src/parity.rs); (1, 0) at a shell and with sweep.media = "first-order".
fn slab_part(mesh: u32, before: u32, after: u32, first: u32, last: u32, front: f32, back: f32) -> vec2<f32> {
    let bit = 1u << mesh;
    if globals.second_order_media == 0u || (globals.parity_meshes & bit) == 0u {
        return vec2<f32>(1.0, 0.0);
    }
    if first == NO_CROSSING {
        return vec2<f32>(1.0, 0.5);
    }
    let z1 = frag_depth[first];
    let z2 = frag_depth[last];
    let was_inside = (before & bit) != 0u;
    let is_inside = (after & bit) != 0u;
    var length: f32;
    if was_inside && !is_inside {
        length = z1 - front;
    } else if !was_inside && is_inside {
        length = back - z1;
    } else if !was_inside {
        length = z2 - z1;
    } else {
        length = (z1 - front) + (back - z2);
    }
    let inside = clamp01(length * globals.inv_slab_distance);
    return vec2<f32>(inside, inside * 0.5);
}

// `first_mesh`: the lowest set bit (scene order resolves overlapping materials).
fn first_mesh(inside: u32) -> u32 {
    if inside == 0u {
        return NO_CROSSING;
    }
    return countTrailingZeros(inside);
}
