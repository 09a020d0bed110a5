// Stage 2, intersection: mirrors cpu/src/parity.rs. The pixel's cursor advances past every
// fragment in front of the slab's back face, toggling the mesh's inside bit, and remembers the
// first fragment crossed. Fragment meta is `mesh | triangle << MESH_BITS`. Open meshes are thin
// shells: their bits are clear in `globals.parity_meshes`, so their crossings toggle nothing.

#import shared/constants
#import shared/bindings

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

// `first_mesh`: the lowest set bit (scene order resolves overlapping materials).
fn first_mesh(inside: u32) -> u32 {
    if inside == 0u {
        return NO_CROSSING;
    }
    return countTrailingZeros(inside);
}
