//! The thinnest closed-mesh feature along the view direction, for `slabs = "auto"`.
//!
//! Every triangle is rasterized with the LDI's own set-up ([`RasterSetup`]: fixed-point
//! vertices, the exact top-left coverage test, the f32 depth plane) at the pixel centres of a
//! subsampled image grid (every `stride`-th pixel in x and y, `stride` chosen so that at most
//! [`THICKNESS_SAMPLES`]² pixels are sampled). Per sampled pixel and mesh the fragments are
//! sorted by depth and paired by parity, as the sweep's parity test pairs them: fragments 2k and
//! 2k + 1 bound an interval inside the mesh. Its length is a *thickness* along the view when
//! - the entry and exit faces are nearly antiparallel (outward normals with
//!   `n_entry · n_exit ≤ −`[`ANTIPARALLEL_COS`], i.e. within 20° of opposite): the interval
//!   crosses a sheet between two locally parallel surfaces, not the wedge next to a silhouette
//!   edge, whose length goes to zero at the edge whatever the mesh (it would make the minimum a
//!   matter of where a pixel centre happens to fall);
//! - and it is longer than [`THICKNESS_EPSILON`] × the scene's depth (coplanar or duplicate
//!   faces of opposite orientation, a zero-thickness sheet: nothing inside to sample).
//!
//! The thinnest feature is the smallest such length over all sampled pixels and meshes (ties:
//! the lowest mesh index). Everything is serial and sorted by a total key, so the result does
//! not depend on the thread count.

use glam::DVec3;

use crate::prepare::camera::Camera;
use crate::prepare::guard::GuardBand;
use crate::prepare::placement::WorldMesh;
use crate::prepare::raster::{RasterError, RasterSetup};

/// At most this many sampled pixel centres per image side (the stride is
/// `⌈max(width, height) / THICKNESS_SAMPLES⌉`).
pub const THICKNESS_SAMPLES: u32 = 256;
/// Entry and exit faces count as a sheet when `n_entry · n_exit ≤ −ANTIPARALLEL_COS` (cos 20°).
pub const ANTIPARALLEL_COS: f64 = 0.939_692_620_785_908_4;
/// Inside intervals shorter than this fraction of the scene's depth are ignored (coplanar or
/// duplicate faces).
pub const THICKNESS_EPSILON: f64 = 1e-6;

/// The thinnest closed-mesh feature found along the view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thinnest {
    /// Mesh index (scene order).
    pub mesh: usize,
    /// Its thickness along the view direction, world units.
    pub thickness: f64,
}

/// The sampling stride of a `width × height` image (see [`THICKNESS_SAMPLES`]).
pub fn sample_stride(width: u32, height: u32) -> u32 {
    width.max(height).div_ceil(THICKNESS_SAMPLES).max(1)
}

/// The thinnest feature of any closed mesh (open meshes are thin shells, without an inside)
/// along the camera's view (see the module documentation), over
/// the image's pixels (no guard band); depths relative to `z_origin`, `depth` the scene's depth
/// range. `None` when no sampled pixel crosses a sheet.
pub fn thinnest_feature(
    camera: &Camera,
    meshes: &[WorldMesh],
    z_origin: f64,
    depth: f64,
) -> Result<Option<Thinnest>, RasterError> {
    let refs: Vec<(&[DVec3], &[[u32; 3]])> = meshes
        .iter()
        .map(|m| (m.mesh.positions.as_slice(), m.mesh.triangles.as_slice()))
        .collect();
    let setup = RasterSetup::new(camera, GuardBand::default(), &refs, z_origin)?;
    let stride = sample_stride(camera.width, camera.height) as i32;
    // Sampled pixels: (a·stride + offset, b·stride + offset), the centre pixel of each block.
    let offset = (stride - 1) / 2;
    let columns = camera.width.div_ceil(stride as u32) as i32;
    // The first sample index whose pixel is ≥ lo, and the last whose pixel is ≤ hi.
    let first = |lo: i32| (lo - offset + stride - 1).div_euclid(stride).max(0);
    let last = |hi: i32| (hi - offset).div_euclid(stride);
    // (sample, mesh, depth, triangle): one fragment at a sampled pixel.
    let mut fragments: Vec<(u32, u32, f32, u32)> = Vec::new();
    for (t, tri) in setup.triangles.iter().enumerate() {
        if !meshes[tri.mesh as usize].report.is_closed() {
            // An open mesh is a thin shell: no inside, no thickness to resolve.
            continue;
        }
        let [x0, y0, x1, y1] = tri.bbox;
        for b in first(y0)..=last(y1) {
            let j = b * stride + offset;
            for a in first(x0)..=last(x1) {
                let i = a * stride + offset;
                if tri.covers(i, j) {
                    let sample = (b * columns + a) as u32;
                    fragments.push((sample, tri.mesh, setup.fragment_depth(tri, i, j), t as u32));
                }
            }
        }
    }
    // Bucket by sampled pixel (a counting sort: O(fragments)), then sort each pixel's few
    // fragments by (mesh, depth, triangle), a total order.
    let samples = columns as usize * camera.height.div_ceil(stride as u32) as usize;
    let mut start = vec![0u32; samples + 1];
    for f in &fragments {
        start[f.0 as usize + 1] += 1;
    }
    for s in 1..start.len() {
        start[s] += start[s - 1];
    }
    let mut fill = start.clone();
    let mut sorted = vec![(0u32, 0f32, 0u32); fragments.len()];
    for f in &fragments {
        let k = &mut fill[f.0 as usize];
        sorted[*k as usize] = (f.1, f.2, f.3);
        *k += 1;
    }
    for s in 0..samples {
        sorted[start[s] as usize..start[s + 1] as usize]
            .sort_unstable_by(|p, q| p.0.cmp(&q.0).then(p.1.total_cmp(&q.1)).then(p.2.cmp(&q.2)));
    }
    let floor = THICKNESS_EPSILON * depth;
    let mut best: Option<Thinnest> = None;
    for s in 0..samples {
        let pixel = &sorted[start[s] as usize..start[s + 1] as usize];
        for group in pixel.chunk_by(|p, q| p.0 == q.0) {
            for pair in group.chunks_exact(2) {
                let (entry, exit) = (
                    &setup.triangles[pair[0].2 as usize],
                    &setup.triangles[pair[1].2 as usize],
                );
                let n = |v: [f32; 3]| DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
                if n(entry.normal).dot(n(exit.normal)) > -ANTIPARALLEL_COS {
                    continue;
                }
                let gap = f64::from(pair[1].1) - f64::from(pair[0].1);
                if gap <= floor {
                    continue;
                }
                let mesh = pair[0].0 as usize;
                let better = match best {
                    None => true,
                    Some(b) => gap < b.thickness || (gap == b.thickness && mesh < b.mesh),
                };
                if better {
                    best = Some(Thinnest {
                        mesh,
                        thickness: gap,
                    });
                }
            }
        }
    }
    Ok(best)
}
