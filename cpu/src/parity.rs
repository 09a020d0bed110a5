//! The parity test and the per-pixel layer cursor (paper §4.2 step 2).
//!
//! A point at depth z in pixel p is inside mesh m iff an odd number of m's fragments at p lie in
//! front of z. The sweep does not search: each pixel keeps a cursor (the next fragment) and a
//! bit mask of the meshes it is inside, and advances past every fragment before the slab's back
//! face, toggling bits and remembering the first fragment crossed in that slab.

use crate::ldi::Ldi;

/// Marks "no fragment crossed in this slab".
pub const NO_CROSSING: u32 = u32::MAX;

/// The meshes (bit i = mesh i) that contain depth `z` in grid pixel (i, j), by counting.
pub fn inside(ldi: &Ldi, i: u32, j: u32, z: f32) -> u32 {
    let mut mask = 0u32;
    for f in ldi.range(i, j) {
        if ldi.depth[f] < z {
            mask ^= 1 << ldi.mesh[f];
        }
    }
    mask
}

/// Advances one pixel's cursor past every fragment with depth `< back_face`.
///
/// `next` is the absolute index of the pixel's next fragment, `end` its pixel's end offset,
/// `inside` the mesh mask. Returns the first fragment crossed, or [`NO_CROSSING`].
#[inline(always)]
pub fn advance(ldi: &Ldi, next: &mut u32, end: u32, inside: &mut u32, back_face: f32) -> u32 {
    let mut first = NO_CROSSING;
    while *next < end && ldi.depth[*next as usize] < back_face {
        if first == NO_CROSSING {
            first = *next;
        }
        *inside ^= 1 << ldi.mesh[*next as usize];
        *next += 1;
    }
    first
}

/// The lowest set bit's mesh (scene order resolves overlapping materials), if any.
#[inline(always)]
pub fn first_mesh(inside: u32) -> Option<u32> {
    if inside == 0 {
        None
    } else {
        Some(inside.trailing_zeros())
    }
}
