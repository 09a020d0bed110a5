//! The parity test and the per-pixel layer cursor (paper §4.2 step 2).
//!
//! A point at depth z in pixel p is inside mesh m iff an odd number of m's fragments at p lie in
//! front of z. The sweep does not search: each pixel keeps a cursor (the next fragment) and a
//! bit mask of the meshes it is inside, and advances past every fragment before the slab's back
//! face, toggling bits and remembering the first fragment crossed in that slab.
//!
//! Open meshes are thin shells (`Ldi::parity_meshes` lacks their bits): their fragments are
//! crossings like any other (the first one crossed in a slab is shaded) but toggle nothing.

use convshadow_common::pixel::noise::clamp01;

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

/// Whether a pixel's first crossing in a slab, fragment `first` ([`advance`]'s answer, not
/// [`NO_CROSSING`]), left a closed mesh it was inside: the cursor's mask before the slab,
/// `before`, holds the first fragment's mesh only on the way out (a thin shell's bit is never
/// set). sweep.wgsl asks the same.
#[inline(always)]
pub fn leaves_its_mesh(ldi: &Ldi, first: u32, before: u32) -> bool {
    before & (1 << ldi.mesh[first as usize]) != 0
}

/// Where in its slab `[front, back)` a pixel meets the medium of mesh `mesh`, which it shades
/// there: `(inside, lit_from)`, in slab thicknesses (`inv_e` = 1/e), clamped to 0…1.
///
/// - `inside`: the part of the slab inside the mesh, from the crossings the cursor made in it
///   (`before`/`after`: the inside masks at the front and back faces; `first`/`last`: the first
///   and last fragments crossed, [`NO_CROSSING`] if none). 1 without a crossing, and at a thin
///   shell's (a filter, not a slab of medium). Entering: back − z₁; leaving: z₁ − front;
///   entering and leaving: z_last − z₁; leaving and entering again: the two ends.
/// - `lit_from`: how far the light has travelled in the slab's medium where it lights the
///   sample: the middle of the part inside, `inside / 2` (the midpoint rule over that part, second
///   order; the jittered shading point would add its noise); 0 at a shell's crossing.
///
/// The sweep scales a medium's slab by them (`crate::composite::part_of_slab`). With
/// `sweep.media = "first-order"` (`second_order` false) they are (1, 0): the whole slab, lit at
/// its front, which leaves the slab's bits as they were.
#[inline(always)]
pub fn slab_part(
    ldi: &Ldi,
    (mesh, second_order): (u32, bool),
    (before, after): (u32, u32),
    (first, last): (u32, u32),
    (front, back): (f32, f32),
    inv_e: f32,
) -> (f32, f32) {
    let bit = 1u32 << mesh;
    if !second_order || ldi.parity_meshes & bit == 0 {
        return (1.0, 0.0);
    }
    if first == NO_CROSSING {
        return (1.0, 0.5);
    }
    let (z1, z2) = (ldi.depth[first as usize], ldi.depth[last as usize]);
    let length = match (before & bit != 0, after & bit != 0) {
        (true, false) => z1 - front,
        (false, true) => back - z1,
        (false, false) => z2 - z1,
        (true, true) => (z1 - front) + (back - z2),
    };
    let inside = clamp01::<f32>(length * inv_e);
    (inside, inside * 0.5)
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
    fn a_slab_counts_the_part_inside_the_medium_it_shades() {
        // Mesh 0 closed from depth 1 to 3, mesh 1 at 2 (a shell when its bit is clear).
        let ldi = one_pixel(0b01);
        let e = 0.5f32;
        let part = |before, after, crossed: (u32, u32), slab: (f32, f32), second| {
            slab_part(&ldi, (0, second), (before, after), crossed, slab, 1.0 / e)
        };
        // Entering at 1 in [0.75, 1.25): half inside, lit in the middle of that half.
        assert_eq!(part(0, 1, (0, 0), (0.75, 1.25), true), (0.5, 0.25));
        // Leaving at 3 in [2.875, 3.375): a quarter inside.
        assert_eq!(part(1, 0, (2, 2), (2.875, 3.375), true), (0.25, 0.125));
        // Wholly inside, no crossing: the whole slab, lit in its middle.
        assert_eq!(
            part(1, 1, (NO_CROSSING, NO_CROSSING), (1.5, 2.0), true),
            (1.0, 0.5)
        );
        // Entering at 1 and leaving at 3 within one slab [0.5, 3.5): 2/3 of it (e = 3 here).
        let through = slab_part(&ldi, (0, true), (0, 0), (0, 2), (0.5, 3.5), 1.0 / 3.0);
        assert!((through.0 - 2.0 / 3.0).abs() < 1e-6 && through.1 == through.0 * 0.5);
        // First-order media: the whole slab at its front, whatever was crossed.
        assert_eq!(part(0, 1, (0, 0), (0.75, 1.25), false), (1.0, 0.0));
        // A shell's crossing is a filter, not a slab of medium.
        let shells = one_pixel(0b00);
        let shell = slab_part(&shells, (0, true), (0, 0), (0, 0), (0.75, 1.25), 1.0 / e);
        assert_eq!(shell, (1.0, 0.0));
    }

    #[test]
    fn a_crossing_leaves_its_mesh_only_on_the_way_out_of_a_closed_one() {
        // Mesh 0 closed from depth 1 to 3, mesh 1 at 2: closed (entered there), or a shell.
        for mask in [0b11, 0b01] {
            let ldi = one_pixel(mask);
            let (mut next, mut inside) = (0u32, 0u32);
            let mut step = |back: f32| {
                let before = inside;
                let first = advance(&ldi, &mut next, 3, &mut inside, back);
                leaves_its_mesh(&ldi, first, before)
            };
            assert!(!step(1.5), "entering mesh 0");
            assert!(!step(2.5), "entering mesh 1, or crossing the shell");
            assert!(step(3.5), "leaving mesh 0");
        }
        // Entering mesh 0 and leaving it within one slab: the first crossing enters.
        let ldi = one_pixel(0b01);
        let (mut next, mut inside) = (0u32, 0u32);
        let first = advance(&ldi, &mut next, 3, &mut inside, 9.0);
        assert!(!leaves_its_mesh(&ldi, first, 0));
        // Inside mesh 0 from the start, its exit the slab's first crossing.
        let (mut next, mut inside) = (2u32, 0b01u32);
        let first = advance(&ldi, &mut next, 3, &mut inside, 9.0);
        assert!(leaves_its_mesh(&ldi, first, 0b01));
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
