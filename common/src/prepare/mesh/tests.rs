use std::f64::consts::PI;

use super::*;

#[test]
fn cylinder_is_closed_outward_with_the_prism_volume() {
    let c = TriMesh::cylinder(0.5, 0.2, 32);
    let (_, r) = c.analyze();
    assert!(r.is_closed(), "{r:?}");
    assert_eq!(c.triangles.len(), 4 * 32);
    // A regular 32-gon prism: area n/2·r²·sin(2π/n) times the height.
    let v = 16.0 * 0.25 * (2.0 * PI / 32.0).sin() * 0.2;
    assert!(
        (c.signed_volume() - v).abs() < 1e-12,
        "{}",
        c.signed_volume()
    );
    assert_eq!(c.euler_characteristic(), 2);
}

fn all_meshes() -> Vec<(&'static str, TriMesh)> {
    let mut v = vec![("box", TriMesh::unit_box(DVec3::new(1.0, 2.0, 3.0)))];
    for s in 0..=4 {
        v.push(("icosphere", TriMesh::icosphere(1.5, s)));
    }
    v.push(("torus", TriMesh::torus(2.0, 0.5, 24)));
    v
}

#[test]
fn procedural_meshes_are_closed() {
    for (name, m) in all_meshes() {
        let (clean, report) = m.analyze();
        assert_eq!(
            report,
            MeshReport {
                triangles: m.triangles.len(),
                ..MeshReport::default()
            },
            "{name}"
        );
        assert!(report.is_closed(), "{name}");
        assert_eq!(clean, m, "{name}: nothing to drop");
    }
}

#[test]
fn box_counts_volume_and_normals() {
    let size = DVec3::new(1.0, 2.0, 3.0);
    let m = TriMesh::unit_box(size);
    assert_eq!(m.positions.len(), 8);
    assert_eq!(m.triangles.len(), 12);
    assert_eq!(m.euler_characteristic(), 2);
    // 1·2·3 exactly: every term is a product of halves of small integers.
    assert_eq!(m.signed_volume(), 6.0);
    assert_eq!(m.bounds(), (-size * 0.5, size * 0.5));
    // Each triangle's normal is along an axis and points away from the centre.
    for &t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a);
        let centroid = (a + b + c) / 3.0;
        assert!(n.dot(centroid) > 0.0, "{t:?} points inward");
        assert_eq!(
            [n.x != 0.0, n.y != 0.0, n.z != 0.0]
                .iter()
                .filter(|&&x| x)
                .count(),
            1
        );
    }
}

#[test]
fn icosphere_counts_and_orientation() {
    for s in 0..=4u32 {
        let m = TriMesh::icosphere(2.0, s);
        let p4 = 4usize.pow(s);
        assert_eq!(m.triangles.len(), 20 * p4, "s={s}");
        assert_eq!(m.positions.len(), 10 * p4 + 2, "s={s}");
        assert_eq!(m.euler_characteristic(), 2, "s={s}");
        for p in &m.positions {
            assert!((p.length() - 2.0).abs() < 1e-12);
        }
        for &t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!(
                (b - a).cross(c - a).dot(a + b + c) > 0.0,
                "s={s} {t:?} inward"
            );
        }
    }
}

#[test]
fn icosahedron_volume_is_exact() {
    // Circumradius r = a/4·sqrt(10 + 2√5); V = 5/12·(3 + √5)·a³.
    let r = 1.7;
    let s5 = 5.0_f64.sqrt();
    let a = 4.0 * r / (10.0 + 2.0 * s5).sqrt();
    let expected = 5.0 / 12.0 * (3.0 + s5) * a.powi(3);
    let v = TriMesh::icosphere(r, 0).signed_volume();
    assert!((v - expected).abs() < 1e-12 * expected, "{v} vs {expected}");
}

#[test]
fn icosphere_volume_within_inscribed_bounds() {
    // Every triangle lies inside the ball (its corners are on the sphere), so V < 4/3·π·r³.
    // The cone from the origin over each face contains the spherical sector of radius h_f
    // (the face plane's distance); the faces tile the sphere under central projection, so
    // V ≥ 4/3·π·h_min³.
    let r: f64 = 1.25;
    let ball = 4.0 / 3.0 * PI * r.powi(3);
    let mut previous_error = f64::INFINITY;
    for s in 0..=4 {
        let m = TriMesh::icosphere(r, s);
        let v = m.signed_volume();
        let h_min = m
            .triangles
            .iter()
            .map(|&t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                (b - a).cross(c - a).normalize().dot(a)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(v < ball, "s={s}");
        assert!(v >= 4.0 / 3.0 * PI * h_min.powi(3) * (1.0 - 1e-12), "s={s}");
        let error = ball - v;
        assert!(error < previous_error, "error must shrink with subdivision");
        previous_error = error;
    }
    // Level 4: edges ≈ 1.05·r/16, so the deepest face sits ~r·(1 - 0.0015) deep at most.
    assert!(previous_error < 0.01 * ball);
}

#[test]
fn torus_counts_and_volume() {
    for &(big_r, small_r, seg) in &[(2.0, 0.5, 24u32), (3.0, 1.0, 7), (1.0, 0.25, 64)] {
        let m = TriMesh::torus(big_r, small_r, seg);
        let n = seg as usize;
        let tube = (seg as usize / 2).max(3);
        assert_eq!(m.positions.len(), n * tube);
        assert_eq!(m.triangles.len(), 2 * n * tube);
        assert_eq!(m.euler_characteristic(), 0);
        assert!(m.analyze().1.is_closed());
        // Each sector between two meridians is a prism-like wedge over the inscribed
        // tube polygon P (its quads are planar trapezoids): V = n·sin(2π/n)·A_P·R with
        // A_P = tube/2·r²·sin(2π/tube). Equivalently V = 2π²Rr²·sinc(2π/n)·sinc(2π/tube).
        let exact = 2.0 * PI * PI * big_r * small_r * small_r;
        let xn = 2.0 * PI / n as f64;
        let xm = 2.0 * PI / tube as f64;
        let poly = exact * (xn.sin() / xn) * (xm.sin() / xm);
        let v = m.signed_volume();
        assert!((v - poly).abs() < 1e-9 * poly, "{v} vs {poly}");
        // sinc(x) ∈ [1 − x²/6, 1]
        assert!(v < exact);
        assert!(v > exact * (1.0 - xn * xn / 6.0) * (1.0 - xm * xm / 6.0));
    }
}

#[test]
fn torus_normals_point_away_from_core_circle() {
    let (big_r, m) = (2.0, TriMesh::torus(2.0, 0.5, 16));
    for &t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let centroid = (a + b + c) / 3.0;
        let radial = DVec3::new(centroid.x, centroid.y, 0.0).normalize() * big_r;
        assert!((b - a).cross(c - a).dot(centroid - radial) > 0.0, "{t:?}");
    }
}

#[test]
fn torus_clamps_small_segment_counts() {
    let m = TriMesh::torus(2.0, 0.5, 1);
    assert_eq!(m.positions.len(), 9);
    assert!(m.analyze().1.is_closed());
    assert!(m.signed_volume() > 0.0);
}

#[test]
fn transformed_keeps_closure_and_scales_volume() {
    for (name, m) in all_meshes() {
        let v = m.signed_volume();
        for &s in &[0.5, 3.0, -2.0] {
            let t = m.transformed(
                s,
                DVec3::new(10.0, -35.0, 120.0),
                DVec3::new(1e3, -7.0, 0.25),
            );
            assert!(t.analyze().1.is_closed(), "{name} s={s}");
            let expected = v * s.abs().powi(3);
            assert!(
                (t.signed_volume() - expected).abs() < 1e-9 * expected,
                "{name} s={s}: {} vs {expected}",
                t.signed_volume()
            );
        }
    }
}

#[test]
fn transformed_rotates_x_then_y_then_z() {
    let m = TriMesh {
        positions: vec![DVec3::Y, DVec3::X],
        triangles: vec![],
    };
    // Rx(90°) takes +y to +z, then Ry(90°) takes +z to +x. (Rx·Ry order would give +z.)
    let t = m.transformed(2.0, DVec3::new(90.0, 90.0, 0.0), DVec3::new(0.0, 0.0, 5.0));
    assert!((t.positions[0] - DVec3::new(2.0, 0.0, 5.0)).length() < 1e-12);
    // Rz(90°) takes +x to +y.
    let t = m.transformed(1.0, DVec3::new(0.0, 0.0, 90.0), DVec3::ZERO);
    assert!((t.positions[1] - DVec3::Y).length() < 1e-12);
}

#[test]
fn reversed_triangle_gives_three_flipped_edges() {
    let mut m = TriMesh::unit_box(DVec3::ONE);
    m.triangles[5].swap(0, 1);
    let (_, r) = m.analyze();
    assert_eq!(r.flipped_edges, 3);
    assert_eq!((r.boundary_edges, r.nonmanifold_edges), (0, 0));
    assert!(!r.is_closed());
}

#[test]
fn removed_triangle_gives_three_boundary_edges() {
    let mut m = TriMesh::icosphere(1.0, 1);
    m.triangles.remove(17);
    let (_, r) = m.analyze();
    assert_eq!(r.boundary_edges, 3);
    assert_eq!((r.flipped_edges, r.nonmanifold_edges), (0, 0));
    assert!(!r.is_closed());
    assert_eq!(m.euler_characteristic(), 1);
}

#[test]
fn fin_triangle_gives_nonmanifold_edge() {
    let mut m = TriMesh::unit_box(DVec3::ONE);
    m.positions.push(DVec3::new(0.0, 0.0, 5.0));
    // Edge 0-4 belongs to the box; the fin adds a third user and two boundary edges.
    m.triangles.push([0, 4, 8]);
    let (_, r) = m.analyze();
    assert_eq!(r.nonmanifold_edges, 1);
    assert_eq!(r.boundary_edges, 2);
    assert_eq!(r.flipped_edges, 0);
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let mut m = TriMesh::unit_box(DVec3::ONE);
    let base = m.clone();
    let d = DVec3::new(0.1, 0.7, 0.3);
    let n = m.positions.len() as u32;
    // d, 2d and 8d are exactly collinear in f64 (power-of-two scaling is exact), although
    // c − a = 7d rounds; the exact predicate must still see zero area.
    m.positions
        .extend([d, d * 2.0, d * 8.0, DVec3::new(0.5, 0.5, 0.5)]);
    m.triangles.push([0, 0, 1]); // repeated index
    m.triangles.push([n, n + 1, n + 2]); // collinear
    m.triangles.push([7, n + 3, 6]); // n+3 duplicates vertex 7's position: zero area
    m.triangles.push([0, 1, 99]); // out of range
    m.triangles.insert(0, [n, n + 2, n + 1]);
    let (clean, r) = m.analyze();
    assert_eq!(r.degenerate_triangles, 5);
    assert_eq!(r.triangles, 12);
    assert!(r.is_closed());
    assert_eq!(clean.triangles, base.triangles);
    assert_eq!(clean.positions, m.positions);
    // A nearly collinear (but not exactly) triangle is kept.
    let sliver = TriMesh {
        positions: vec![
            DVec3::ZERO,
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(2.0, 2.0, 2.0 + 1e-15),
        ],
        triangles: vec![[0, 1, 2]],
    };
    assert_eq!(sliver.analyze().1.degenerate_triangles, 0);
}

#[test]
fn exact_orientation_predicate() {
    assert!(orient2d_is_zero([0.0, 0.0], [1.0, 1.0], [3.0, 3.0]));
    assert!(!orient2d_is_zero(
        [0.0, 0.0],
        [1.0, 1.0],
        [3.0, 3.0 + 4.0 * f64::EPSILON]
    ));
    // Points on y = x + 0.1 offset by tiny steps: exact arithmetic, not the rounded determinant.
    let a = [0.1, 0.2];
    let b = [0.1 + 2f64.powi(-40), 0.2 + 2f64.powi(-40)];
    let c = [0.1 + 2f64.powi(-30), 0.2 + 2f64.powi(-30)];
    assert!(orient2d_is_zero(a, b, c));
    let c2 = [c[0], f64::from_bits(c[1].to_bits() + 1)];
    assert!(!orient2d_is_zero(a, b, c2));
}

#[test]
fn bounds_and_volume_of_empty_mesh() {
    let m = TriMesh::default();
    assert_eq!(m.bounds(), (DVec3::ZERO, DVec3::ZERO));
    assert_eq!(m.signed_volume(), 0.0);
    assert_eq!(m.analyze().1, MeshReport::default());
}

#[test]
fn volume_is_accurate_far_from_origin() {
    let m = TriMesh::unit_box(DVec3::splat(1e-3)).transformed(1.0, DVec3::ZERO, DVec3::splat(1e6));
    let v = m.signed_volume();
    assert!((v - 1e-9).abs() < 1e-6 * 1e-9, "{v}");
}

proptest::proptest! {
    #[test]
    fn any_rigid_transform_keeps_closure_and_volume(
        s in 0.01f64..100.0,
        neg in proptest::bool::ANY,
        rx in -360.0f64..360.0, ry in -360.0f64..360.0, rz in -360.0f64..360.0,
        tx in -1e4f64..1e4, ty in -1e4f64..1e4, tz in -1e4f64..1e4,
    ) {
        let m = TriMesh::icosphere(1.0, 1);
        let scale = if neg { -s } else { s };
        let t = m.transformed(scale, DVec3::new(rx, ry, rz), DVec3::new(tx, ty, tz));
        proptest::prop_assert!(t.analyze().1.is_closed());
        let expected = m.signed_volume() * s.powi(3);
        proptest::prop_assert!((t.signed_volume() - expected).abs() < 1e-9 * expected);
    }
}
