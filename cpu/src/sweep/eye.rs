//! The perspective camera's eye pass (docs/how-it-works.md, "A perspective camera"): the light
//! is swept on the slab grid as for an orthographic camera (light buffers on the slab planes in
//! world units), and before each slab every image pixel's ray from the eye takes its step
//! through the slab: its own layer cursor over the perspective LDI, one shading point, front to
//! back compositing — with the light *read* from the grid's buffer where its ray meets the slab
//! (a per-slab zoom of the read: `centre + (p − centre)·z·zoom`, bilinear), never resampled.
//!
//! At a crossed surface the read leaves out grid pixels that were already inside the crossed
//! mesh at the slab's front (their light is the mesh's inside, not the light arriving at its
//! surface), the weights of the others renormalised; where every neighbour is inside, the plain
//! bilinear read. One code path (plain `f32`, one pixel): the same bits on `--path scalar` and
//! `simd`, at any thread count (a pixel reads only the previous slab's grid and its own state).

use rayon::prelude::*;

use convshadow_common::contract::sweep_io::EyeView;
use convshadow_common::pixel::hash::row_hash;
use convshadow_common::plan::RenderPlan;

use super::kit::{MAX_LIGHT_CHANNELS, light_block};
use crate::composite::{composite, part_of_slab};
use crate::ldi::Ldi;
use crate::parity::{NO_CROSSING, advance, first_mesh, slab_part};
use crate::shading::{Surface, material_at, shade, shading_depth};

/// The eye's per-pixel state: layer cursor, inside mask, composited colour and alpha.
pub(crate) struct EyeState {
    next: Vec<u32>,
    inside: Vec<u32>,
    /// Per pixel `[r, g, b]`.
    pub(crate) color: Vec<[f32; 3]>,
    pub(crate) alpha: Vec<f32>,
}

impl EyeState {
    /// Before the first slab: each cursor at its pixel's first fragment, nothing composited.
    pub(crate) fn new(view: &EyeView<'_>) -> EyeState {
        let n = (view.width * view.height) as usize;
        EyeState {
            next: view.ldi.offsets[..n].to_vec(),
            inside: vec![0; n],
            color: vec![[0.0; 3]; n],
            alpha: vec![0.0; n],
        }
    }
}

/// The grid as the previous slab left it: its outgoing light (pixel-interleaved rows, as the
/// sweep keeps it), every grid pixel's inside mask and layer cursor at this slab's front, and
/// its LDI (which thin shells a pixel has crossed).
pub(crate) struct GridLight<'a> {
    pub(crate) light: &'a [f32],
    pub(crate) inside: &'a [u32],
    pub(crate) ldi: &'a Ldi,
    pub(crate) next: &'a [u32],
}

impl GridLight<'_> {
    /// Whether grid pixel `p` is already past the crossed mesh of `skip` at the slab's front:
    /// inside it (a closed mesh), or through one of its fragments (an open mesh, a thin shell,
    /// whose crossing toggles no inside bit).
    fn past(&self, p: usize, skip: Skip) -> bool {
        match skip {
            Skip::None => false,
            Skip::Inside(bits) => self.inside[p] & bits != 0,
            Skip::Shell { mesh, lit_past } => {
                (self.ldi.offsets[p]..self.next[p])
                    .any(|f| u32::from(self.ldi.mesh[f as usize]) == mesh)
                    != lit_past
            }
        }
    }
}

/// Which grid pixels a read leaves out: none, those inside the meshes of a mask, or those on the
/// side of a thin shell the light does not come from: through it, or (`lit_past`, the light
/// crossing the shell the other way from the grid's rays) not yet through it.
#[derive(Clone, Copy)]
enum Skip {
    None,
    Inside(u32),
    Shell { mesh: u32, lit_past: bool },
}

/// Whether light `l` reaches a thin shell of normal `n` (the view's camera frame) from the side
/// the grid's rays reach after crossing it: its travel `(drift·pixel size, slab distance)` and
/// the grid's `(0, 0, 1)` cross the shell's plane in opposite directions.
fn lit_past(plan: &RenderPlan, l: usize, n: [f32; 3]) -> bool {
    let d = plan.lights[l].drift;
    let ps = plan.pixel_size as f32;
    let (tx, ty) = (d[0] * ps, d[1] * ps);
    let travel = (n[0] * tx + n[1] * ty) + n[2] * plan.slab_distance;
    (travel > 0.0) != (n[2] > 0.0)
}

/// Slab `slab` for every image pixel (rows in parallel).
pub(crate) fn eye_slab(
    plan: &RenderPlan,
    view: &EyeView<'_>,
    grid: &GridLight<'_>,
    slab: u32,
    state: &mut EyeState,
) {
    let w = view.width as usize;
    let (front, back) = (
        plan.slab_front[slab as usize],
        plan.slab_back[slab as usize],
    );
    let (cx, cy) = (view.width as f32 * 0.5, view.height as f32 * 0.5);
    state
        .next
        .par_chunks_mut(w)
        .zip(state.inside.par_chunks_mut(w))
        .zip(state.color.par_chunks_mut(w))
        .zip(state.alpha.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (((next, inside), color), alpha))| {
            let jitter_row = row_hash(
                plan.jitter_slab_hash[slab as usize],
                plan.hash_y(y as u32 + plan.guard.top),
            );
            // The pixel centre's offset from the view axis, in image pixels (in a turned-round
            // pass x is mirrored: the turned grid's x axis is the image's reversed).
            let offset_y = y as f32 + 0.5 - cy;
            for x in 0..w {
                let offset_x = if view.turned_round {
                    cx - (x as f32 + 0.5)
                } else {
                    x as f32 + 0.5 - cx
                };
                let pixel = EyePixel {
                    x,
                    y,
                    offset: [offset_x, offset_y],
                    jitter_row,
                    front,
                    back,
                };
                eye_pixel(
                    plan,
                    view,
                    grid,
                    &pixel,
                    (&mut next[x], &mut inside[x]),
                    (&mut color[x], &mut alpha[x]),
                );
            }
        });
}

/// Where one eye pixel is in the sweep.
struct EyePixel {
    x: usize,
    y: usize,
    /// The pixel centre's offset from the image centre (the view axis), in image pixels.
    offset: [f32; 2],
    jitter_row: u32,
    front: f32,
    back: f32,
}

/// One image pixel through one slab: cursor, shading point, light read, composite.
fn eye_pixel(
    plan: &RenderPlan,
    view: &EyeView<'_>,
    grid: &GridLight<'_>,
    p: &EyePixel,
    (next, inside): (&mut u32, &mut u32),
    (color, alpha): (&mut [f32; 3], &mut f32),
) {
    if *alpha == 1.0 && !view.turned_round {
        // Opaque: compositing adds (1 − 1)·α·c, exactly 0 (the early finish's argument), so
        // nothing later changes this pixel's bits. (Back to front, nearer slabs still do.)
        return;
    }
    let ldi = view.ldi;
    let end = ldi.offsets[p.y * view.width as usize + p.x + 1];
    let before = *inside;
    let crossed = advance(ldi, next, end, inside, p.back);
    let mesh = if crossed != NO_CROSSING {
        u32::from(ldi.mesh[crossed as usize])
    } else {
        match first_mesh(*inside) {
            Some(m) => m,
            None => return,
        }
    };
    let z = shading_depth(
        plan,
        ldi,
        crossed,
        p.front,
        p.jitter_row,
        p.x + plan.guard.left as usize,
    );
    // The ray's point at view depth z_origin + z (turned round: z_origin − z), in grid pixel
    // coordinates.
    let view_depth = if view.turned_round {
        view.z_origin - z
    } else {
        view.z_origin + z
    };
    let scale = view_depth * view.zoom;
    let gx = view.axis[0] + p.offset[0] * scale;
    let gy = view.axis[1] + p.offset[1] * scale;
    // At a crossing, the light arriving at the surface: not the light of grid pixels already
    // past it.
    let skip = if crossed == NO_CROSSING {
        Skip::None
    } else if ldi.parity_meshes & (1 << mesh) != 0 {
        Skip::Inside(1 << mesh)
    } else {
        Skip::Shell {
            mesh,
            lit_past: false,
        }
    };
    let normal = (crossed != NO_CROSSING)
        .then(|| view.raster.triangles[ldi.triangle[crossed as usize] as usize].normal);
    // Turned round, a crossed surface is read where each light's ray through it crossed the
    // plane one slab before this slab's front (see `read_light`).
    let back_along_light = (view.turned_round && crossed != NO_CROSSING)
        .then_some((z - p.front) * plan.inv_slab_distance + 1.0);
    let iin = read_light(plan, grid, (gx, gy), (skip, normal), back_along_light);
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    let (xi, yi) = (
        gx - 0.5 - plan.guard.left as f32,
        gy - 0.5 - plan.guard.top as f32,
    );
    let (part, lit_from) = slab_part(
        ldi,
        (mesh, plan.second_order_media),
        (before, *inside),
        (crossed, next.wrapping_sub(1)),
        (p.front, p.back),
        plan.inv_slab_distance,
    );
    let mut tf = material_at(plan, mesh, xi, yi, z);
    let surface = (crossed != NO_CROSSING && (material.specular.is_some() || material.lambert))
        .then(|| Surface {
            normal: view.raster.triangles[ldi.triangle[crossed as usize] as usize].normal,
            lanes: true,
            alpha: tf.alpha,
        });
    let light = part_of_slab(&mut tf, part, lit_from);
    let n = plan.lights.len() * plan.channels as usize;
    let shaded = shade(plan, material, tf.color, &iin[..n], surface.as_ref());
    let shaded = [0, 1, 2].map(|c| shaded[c] * light[c]);
    composite(color, alpha, shaded, tf.alpha, true, plan.turned_round);
}

/// Every light's channels read bilinearly from the grid's outgoing light at grid position
/// (gx, gy) (pixel centres at +0.5; outside the grid the unoccluded light, 1), leaving out the
/// neighbours on the crossed surface's far side from the light at the slab's front (`skip`, the
/// crossed triangle's `normal`: [`GridLight::past`]) unless all four are.
///
/// `back_along_light`: each light is read `s` slabs of its drift back along its ray instead, at
/// `(gx, gy) − s·drift`. A turned-round pass reads a crossed surface so, `s` = its place in the
/// slab + 1: the surface the eye sees is one the far end's sweep *leaves* its mesh through, and
/// the grid around it at the slab's front is still the mesh's inside; where the light reaches
/// the surface, its ray one slab further back is outside (a one-slab bias, as a shadow map's).
fn read_light(
    plan: &RenderPlan,
    grid: &GridLight<'_>,
    (gx, gy): (f32, f32),
    (skip, normal): (Skip, Option<[f32; 3]>),
    back_along_light: Option<f32>,
) -> [f32; MAX_LIGHT_CHANNELS] {
    let mut out = [0.0f32; MAX_LIGHT_CHANNELS];
    let per_light = back_along_light.is_some() || matches!(skip, Skip::Shell { .. });
    // Every light read at the same place: one set of corners and weights.
    let shared = (!per_light).then(|| Bilinear::at(plan, grid, (gx, gy), skip));
    for l in 0..plan.lights.len() {
        if let Some(read) = &shared {
            read.sum(plan, grid, l, &mut out);
            continue;
        }
        // A shell's side is the light's own.
        let skip = match (skip, normal) {
            (Skip::Shell { mesh, .. }, Some(n)) => Skip::Shell {
                mesh,
                lit_past: lit_past(plan, l, n),
            },
            _ => skip,
        };
        let at = match back_along_light {
            Some(s) => {
                let d = plan.lights[l].drift;
                (gx - s * d[0], gy - s * d[1])
            }
            None => (gx, gy),
        };
        Bilinear::at(plan, grid, at, skip).sum(plan, grid, l, &mut out);
    }
    out
}

/// A bilinear read of the grid at one position: its four corners (grid pixel x, y) and their
/// weights, those already past the crossed mesh left out.
struct Bilinear {
    corners: [(i64, i64); 4],
    weight: [f32; 4],
}

impl Bilinear {
    /// The read at grid position (gx, gy) (pixel centres at +0.5), leaving out the corners
    /// [`GridLight::past`] `skip` unless all four are.
    fn at(plan: &RenderPlan, grid: &GridLight<'_>, (gx, gy): (f32, f32), skip: Skip) -> Bilinear {
        let w = plan.grid_width as i64;
        let (fx, fy) = (gx - 0.5, gy - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (ax, ay) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let corners = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)];
        let bilinear = [
            (1.0 - ax) * (1.0 - ay),
            ax * (1.0 - ay),
            (1.0 - ax) * ay,
            ax * ay,
        ];
        let skipped =
            |(x, y): (i64, i64)| in_grid(plan, x, y) && grid.past((y * w + x) as usize, skip);
        // The weights of the neighbours read: all four, or those on the light's side.
        let mut weight = [0, 1, 2, 3].map(|k| {
            if skipped(corners[k]) {
                0.0
            } else {
                bilinear[k]
            }
        });
        let total = ((weight[0] + weight[1]) + weight[2]) + weight[3];
        if total > 0.0 && !matches!(skip, Skip::None) {
            weight = weight.map(|a| a / total);
        } else {
            weight = bilinear;
        }
        Bilinear { corners, weight }
    }

    /// Light `l`'s channels of this read into `out` (outside the grid the unoccluded light, 1).
    fn sum(&self, plan: &RenderPlan, grid: &GridLight<'_>, l: usize, out: &mut [f32]) {
        let (ch, planes, row_len) = (
            plan.channels as usize,
            plan.planes_per_light(),
            plan.light_row_len(),
        );
        for c in 0..ch {
            let mut sum = 0.0f32;
            for (k, &(x, y)) in self.corners.iter().enumerate() {
                let v = if in_grid(plan, x, y) {
                    let at = y as usize * row_len + light_block(plan, l) + x as usize * planes;
                    grid.light[at + c]
                } else {
                    1.0
                };
                sum += self.weight[k] * v;
            }
            out[l * ch + c] = sum;
        }
    }
}

/// Whether grid pixel (x, y) exists.
fn in_grid(plan: &RenderPlan, x: i64, y: i64) -> bool {
    x >= 0 && y >= 0 && x < i64::from(plan.grid_width) && y < i64::from(plan.grid_height)
}
