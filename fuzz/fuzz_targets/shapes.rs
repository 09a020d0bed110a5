//! Fuzz target: the procedural shapes (box, icosphere, torus, cylinder) built from any sizes the
//! scene validator accepts (lengths in [1e-9, 1e9], segment counts 3 to 1024). Any panic is a
//! bug, and a shape without degenerate triangles must be closed: no boundary, non-manifold or
//! flipped edge.
#![no_main]

use arbitrary::Arbitrary;
use convshadow_common::prepare::mesh::TriMesh;
use libfuzzer_sys::fuzz_target;

/// A length in the validator's range: 1e-9 × 10^(18·u/65535).
fn length(u: u16) -> f64 {
    1e-9 * 10f64.powf(18.0 * f64::from(u) / 65535.0)
}

#[derive(Arbitrary, Debug)]
struct Input {
    kind: u8,
    a: u16,
    b: u16,
    c: u16,
    segments: u16,
}

fuzz_target!(|input: Input| {
    let (a, b, c) = (length(input.a), length(input.b), length(input.c));
    let segments = 3 + u32::from(input.segments) % 1022;
    let mesh = match input.kind % 4 {
        0 => TriMesh::unit_box(glam::DVec3::new(a, b, c)),
        1 => TriMesh::icosphere(a, u32::from(input.segments) % 5),
        2 => {
            // The validator requires minor < major.
            let (major, minor) = if a > b { (a, b) } else { (b, a) };
            if minor >= major {
                return;
            }
            TriMesh::torus(major, minor, segments % 256 + 3)
        }
        _ => TriMesh::cylinder(a, b, segments),
    };
    let (_, report) = mesh.analyze();
    if report.degenerate_triangles == 0 {
        assert_eq!(report.boundary_edges, 0, "{input:?}: {report:?}");
        assert_eq!(report.nonmanifold_edges, 0, "{input:?}: {report:?}");
        assert_eq!(report.flipped_edges, 0, "{input:?}: {report:?}");
    }
});
