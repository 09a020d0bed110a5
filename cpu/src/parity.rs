//! The parity test and the per-pixel layer cursor (paper §4.2 step 2).
//!
//! A point at depth z in pixel p is inside mesh m iff an odd number of m's fragments at p lie in
//! front of z. The sweep does not search: each pixel keeps a cursor (the next fragment) and a
//! bit mask of the meshes it is inside, and advances past every fragment before the slab's back
//! face, toggling bits and remembering the first fragment crossed in that slab.
//!
//! Open meshes are thin shells (`Ldi::parity_meshes` lacks their bits): their fragments are
//! crossings like any other (the first one crossed in a slab is shaded) but toggle nothing.

use crate::ldi::Ldi;

/// Marks "no fragment crossed in this slab".
pub const NO_CROSSING: u32 = u32::MAX;

/// The closed meshes (bit i = mesh i) that contain depth `z` in grid pixel (i, j), by counting.
pub fn inside(ldi: &Ldi, i: u32, j: u32, z: f32) -> u32 {
    let mut mask = 0u32;
    for f in ldi.range(i, j) {
        if ldi.depth[f] < z {
            mask ^= (1 << ldi.mesh[f]) & ldi.parity_meshes;
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
        *inside ^= (1 << ldi.mesh[*next as usize]) & ldi.parity_meshes;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// One pixel crossed by mesh 0 (closed) at depths 1 and 3 and by mesh 1 at depth 2.
    fn one_pixel(parity_meshes: u32) -> Ldi {
        Ldi {
            width: 1,
            height: 1,
            offsets: vec![0, 3],
            depth: vec![1.0, 2.0, 3.0],
            triangle: vec![0, 1, 2],
            mesh: vec![0, 1, 0],
            parity_meshes,
        }
    }

    #[test]
    fn a_shell_is_crossed_but_toggles_nothing() {
        // Mesh 1 closed: inside it between its crossings; mesh 1 a shell: never inside it, but
        // its crossing is still the slab's first crossing.
        for (mask, inside_after_2) in [(u32::MAX, 0b11), (!0b10u32, 0b01)] {
            let ldi = one_pixel(mask);
            let (mut next, mut inside) = (0u32, 0u32);
            assert_eq!(advance(&ldi, &mut next, 3, &mut inside, 1.5), 0);
            assert_eq!(inside, 0b01);
            assert_eq!(advance(&ldi, &mut next, 3, &mut inside, 2.5), 1);
            assert_eq!(inside, inside_after_2, "mask {mask:#x}");
            assert_eq!(super::inside(&ldi, 0, 0, 2.5), inside_after_2);
            assert_eq!(advance(&ldi, &mut next, 3, &mut inside, 3.5), 2);
            assert_eq!(inside, inside_after_2 & !0b01);
            assert_eq!(advance(&ldi, &mut next, 3, &mut inside, 9.0), NO_CROSSING);
        }
    }
}
