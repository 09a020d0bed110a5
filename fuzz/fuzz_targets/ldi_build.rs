//! Fuzz target: the LDI builder fed arbitrary triangles. Finite coordinates (small ones on a
//! pixel-ish scale, or any finite f64) go through `RasterSetup::new` with a small camera, then
//! `Ldi::build` with a small memory budget. Checks the CSR invariants, the front-to-back order,
//! and that a closed mesh (a tetrahedron of four arbitrary points) has no odd pixel.
#![no_main]

use arbitrary::Arbitrary;
use convshadow_common::prepare::guard::GuardBand;
use convshadow_common::prepare::camera::Camera;
use convshadow_common::prepare::raster::RasterSetup;
use convshadow_cpu::ldi::{BuildLdi, Ldi, LdiError};
use glam::DVec3;
use libfuzzer_sys::fuzz_target;

/// A coordinate: usually small (pixel scale, exact in fixed point or not), sometimes any f64.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Coord {
    /// Sixteenths of a world unit.
    Small(i16),
    /// Any value; non-finite ones become 0.
    Raw(f64),
}

impl Coord {
    fn value(self) -> f64 {
        match self {
            Coord::Small(v) => f64::from(v) / 16.0,
            Coord::Raw(v) if v.is_finite() => v,
            Coord::Raw(_) => 0.0,
        }
    }
}

/// One mesh: positions and triangles (indices taken modulo the vertex count).
#[derive(Arbitrary, Debug)]
struct Soup {
    points: Vec<[Coord; 3]>,
    triangles: Vec<[u16; 3]>,
}

#[derive(Arbitrary, Debug)]
struct Input {
    width: u8,
    height: u8,
    guard: u8,
    /// Pixel size exponent: 2^(e/16 - 4) world units.
    pixel_size_exp: u8,
    soups: Vec<Soup>,
    /// Four points of a closed tetrahedron, added as the last mesh.
    tetra: Option<[[Coord; 3]; 4]>,
    budget_kib: u16,
}

fuzz_target!(|input: Input| {
    let width = u32::from(input.width % 64) + 1;
    let height = u32::from(input.height % 64) + 1;
    let guard = GuardBand::uniform(u32::from(input.guard % 8));
    let camera = Camera {
        right: DVec3::X,
        down: DVec3::Y,
        forward: DVec3::Z,
        center: DVec3::ZERO,
        pixel_size: 2f64.powf(f64::from(input.pixel_size_exp) / 16.0 - 4.0),
        focal_px: None,
        width,
        height,
    };
    let mut meshes: Vec<(Vec<DVec3>, Vec<[u32; 3]>)> = Vec::new();
    for soup in input.soups.iter().take(8) {
        if soup.points.is_empty() {
            continue;
        }
        let n = soup.points.len().min(1024);
        let positions: Vec<DVec3> = soup.points[..n]
            .iter()
            .map(|p| DVec3::new(p[0].value(), p[1].value(), p[2].value()))
            .collect();
        let triangles: Vec<[u32; 3]> = soup
            .triangles
            .iter()
            .take(2048)
            .map(|t| t.map(|i| u32::from(i) % n as u32))
            .collect();
        meshes.push((positions, triangles));
    }
    let tetra_mesh = input.tetra.map(|pts| {
        let positions: Vec<DVec3> = pts
            .iter()
            .map(|p| DVec3::new(p[0].value(), p[1].value(), p[2].value()))
            .collect();
        // Four faces, each edge shared by exactly two faces with opposite directions.
        let triangles = vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];
        meshes.push((positions, triangles));
        meshes.len() - 1
    });
    if meshes.is_empty() {
        return;
    }
    let z_origin = meshes
        .iter()
        .flat_map(|m| m.0.iter())
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    let refs: Vec<(&[DVec3], &[[u32; 3]])> = meshes
        .iter()
        .map(|(p, t)| (p.as_slice(), t.as_slice()))
        .collect();
    let Ok(setup) = RasterSetup::new(&camera, guard, &refs, z_origin) else {
        return;
    };
    let budget = (u64::from(input.budget_kib) + 1) << 10;
    let ldi = match Ldi::build(&setup, budget) {
        Ok(l) => l,
        Err(LdiError::OverBudget {
            fragments,
            budget_mib,
            ..
        }) => {
            assert!(fragments * convshadow_cpu::ldi::BYTES_PER_FRAGMENT > budget);
            assert_eq!(budget_mib, budget >> 20);
            return;
        }
        // Budgets here are at most 64 MiB: always allocatable.
        Err(e @ LdiError::Unallocatable { .. }) => panic!("{e}"),
    };
    let n = (ldi.width * ldi.height) as usize;
    assert_eq!(ldi.offsets.len(), n + 1);
    assert!(ldi.offsets.windows(2).all(|w| w[0] <= w[1]));
    let total = ldi.offsets[n] as usize;
    assert_eq!(ldi.depth.len(), total);
    assert_eq!(ldi.triangle.len(), total);
    assert_eq!(ldi.mesh.len(), total);
    for p in 0..n {
        let r = ldi.offsets[p] as usize..ldi.offsets[p + 1] as usize;
        let d = &ldi.depth[r.clone()];
        assert!(
            d.windows(2).all(|w| w[0].total_cmp(&w[1]).is_le()),
            "pixel {p}: fragments not front to back: {d:?}"
        );
        for f in r {
            assert!((ldi.triangle[f] as usize) < setup.triangles.len());
        }
    }
    let stats = ldi.stats();
    assert_eq!(stats.fragments, total as u64);
    if let Some(t) = tetra_mesh {
        // Parity of the closed tetrahedron alone: every pixel covers it an even number of times.
        for p in 0..n {
            let r = ldi.offsets[p] as usize..ldi.offsets[p + 1] as usize;
            let count = ldi.mesh[r].iter().filter(|&&m| usize::from(m) == t).count();
            assert!(
                count % 2 == 0,
                "pixel {p}: closed tetrahedron has {count} fragments"
            );
        }
    }
});
