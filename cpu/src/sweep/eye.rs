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
//! bilinear read.
//!
//! Two paths, one set of stage functions. `--path scalar` takes each pixel through its step on
//! the 1-lane instances ([`eye_sample`], [`sample_entry`], [`eye_shade`]). `--path simd` first
//! takes a row's cursors (skipping each run of [`WAKE_RUN`] pixels whose [`EyeState::wake`]
//! says none can act in the slab), then shades the row's samples eight at a time on the 8-lane
//! instances, those of one mesh together ([`shade_in_lanes`]): the same IEEE operations per lane,
//! so the same bits, at any thread count (a pixel reads only the previous slab's grid and its
//! own state).

use std::cell::RefCell;

use rayon::prelude::*;
use wide::{f32x8, u32x8};

use convshadow_common::contract::sweep_io::{EyePoint, EyeView};
use convshadow_common::pixel::hash::row_hash;
use convshadow_common::pixel::lane::Lane;
use convshadow_common::plan::RenderPlan;

use super::kit::{MAX_LIGHT_CHANNELS, light_block};
use crate::composite::{shade_sample, shade_sample_with};
use crate::ldi::Ldi;
use crate::parity::{NO_CROSSING, advance, first_mesh, slab_part};
use crate::shading::{
    LightTerms, TfLanes, detail_at, material_at, pre_transfer, shading_depth, uses_normals,
};
use convshadow_common::pixel::lane::MAX_LANES;

/// The eye's per-pixel state: layer cursor, inside mask, composited colour and alpha.
pub(crate) struct EyeState {
    next: Vec<u32>,
    inside: Vec<u32>,
    /// Per pixel `[r, g, b]`.
    pub(crate) color: Vec<[f32; 3]>,
    pub(crate) alpha: Vec<f32>,
    /// Per run of [`WAKE_RUN`] pixels of a row (row by row), the lowest [`wake`] of its pixels:
    /// a slab whose back face is not beyond it shades none of them and moves no cursor, so the
    /// batched path skips the run without reading the LDI.
    wake: Vec<f32>,
}

/// The pixels of a row one [`EyeState::wake`] summarises.
const WAKE_RUN: usize = 8;

impl EyeState {
    /// Before the first slab: each cursor at its pixel's first fragment, nothing composited.
    pub(crate) fn new(view: &EyeView<'_>) -> EyeState {
        let n = (view.width * view.height) as usize;
        let mut state = EyeState {
            next: view.ldi.offsets[..n].to_vec(),
            inside: vec![0; n],
            color: vec![[0.0; 3]; n],
            alpha: vec![0.0; n],
            wake: Vec::new(),
        };
        let w = view.width as usize;
        for y in 0..view.height as usize {
            for x0 in (0..w).step_by(WAKE_RUN) {
                let run = (y * w + x0)..(y * w + (x0 + WAKE_RUN).min(w));
                let wake = run
                    .map(|p| wake(view, p, state.next[p], state.inside[p], state.alpha[p]))
                    .fold(f32::INFINITY, f32::min);
                state.wake.push(wake);
            }
        }
        state
    }
}

/// The back face a slab must pass before eye pixel `p` (row-major) next does anything in
/// [`eye_sample`]: −∞ inside a mesh, else its next fragment's depth (a crossing needs a depth
/// `< back`), +∞ with none left or, front to back, once opaque.
/// (`next`, `inside`, `alpha`: its cursor, inside mask and alpha.)
fn wake(view: &EyeView<'_>, p: usize, next: u32, inside: u32, alpha: f32) -> f32 {
    if alpha == 1.0 && !view.turned_round {
        f32::INFINITY
    } else if inside != 0 {
        f32::NEG_INFINITY
    } else if next < view.ldi.offsets[p + 1] {
        view.ldi.depth[next as usize]
    } else {
        f32::INFINITY
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
    batched: bool,
    state: &mut EyeState,
) {
    let w = view.width as usize;
    let (front, back) = (
        plan.slab_front[slab as usize],
        plan.slab_back[slab as usize],
    );
    let (cx, cy) = (view.width as f32 * 0.5, view.height as f32 * 0.5);
    let runs = w.div_ceil(WAKE_RUN);
    state
        .next
        .par_chunks_mut(w)
        .zip(state.inside.par_chunks_mut(w))
        .zip(state.color.par_chunks_mut(w))
        .zip(state.alpha.par_chunks_mut(w))
        .zip(state.wake.par_chunks_mut(runs))
        .enumerate()
        .for_each(|(y, ((((next, inside), color), alpha), wakes))| {
            let jitter_row = row_hash(
                plan.jitter_slab_hash[slab as usize],
                plan.hash_y(y as u32 + plan.guard.top),
            );
            // The pixel centre's offset from the view axis, in image pixels (in a turned-round
            // pass x is mirrored: the turned grid's x axis is the image's reversed).
            let offset_y = y as f32 + 0.5 - cy;
            let pixel = |x: usize| EyePixel {
                x,
                y,
                offset: [
                    if view.turned_round {
                        cx - (x as f32 + 0.5)
                    } else {
                        x as f32 + 0.5 - cx
                    },
                    offset_y,
                ],
                jitter_row,
                front,
                back,
            };
            // A point light's samples each take their own light direction: one by one.
            if !batched || view.point.is_some() {
                for x in 0..w {
                    let cursor = (&mut next[x], &mut inside[x]);
                    if let Some(sample) = eye_sample(plan, view, &pixel(x), cursor, alpha[x]) {
                        let tf = sample_entry(plan, sample.mesh, sample.at, sample.faces);
                        eye_shade(
                            plan,
                            view,
                            grid,
                            &sample,
                            tf,
                            (&mut color[x], &mut alpha[x]),
                        );
                    }
                }
                return;
            }
            ROW_SAMPLES.with_borrow_mut(|samples| {
                samples.clear();
                // The runs some pixel of which may act in this slab.
                let awake = |r: usize| back > wakes[r];
                for x in (0..runs)
                    .filter(|&r| awake(r))
                    .flat_map(|r| run_pixels(r, w))
                {
                    let cursor = (&mut next[x], &mut inside[x]);
                    samples.extend(eye_sample(plan, view, &pixel(x), cursor, alpha[x]));
                }
                shade_in_lanes(plan, grid, samples, (&mut *color, &mut *alpha));
                for (r, run_wake) in wakes.iter_mut().enumerate() {
                    if back <= *run_wake {
                        continue;
                    }
                    *run_wake = run_pixels(r, w)
                        .map(|x| wake(view, y * w + x, next[x], inside[x], alpha[x]))
                        .fold(f32::INFINITY, f32::min);
                }
            });
        });
}

/// The pixels of a row's run `r` of [`WAKE_RUN`] (a row `w` wide).
fn run_pixels(r: usize, w: usize) -> std::ops::Range<usize> {
    r * WAKE_RUN..((r + 1) * WAKE_RUN).min(w)
}

thread_local! {
    /// A row's eye samples between their cursors and their shading (each worker's own).
    static ROW_SAMPLES: RefCell<Vec<EyeSample>> = const { RefCell::new(Vec::new()) };
}

/// Every sample of `samples` (a row's) shaded and composited into its pixel (`color`, `alpha`,
/// indexed by column) as [`eye_shade`] does one by one, eight at a time on the SIMD lanes: the
/// samples of one mesh together; each lane's bilinear corners and weights found on its own
/// ([`Bilinear::at`]; a read per light, [`read_light`], where the lights read at different
/// places), the rest — the sums of the reads, material, part of the slab, shading, compositing —
/// the lane type's operations, which are the scalar ones lane by lane (so the same bits).
fn shade_in_lanes(
    plan: &RenderPlan,
    grid: &GridLight<'_>,
    samples: &[EyeSample],
    (color, alpha): (&mut [[f32; 3]], &mut [f32]),
) {
    let mut order: Vec<usize> = (0..samples.len()).collect();
    order.sort_by_key(|&i| samples[i].mesh);
    for run in order.chunk_by(|&a, &b| samples[a].mesh == samples[b].mesh) {
        for lanes in run.chunks(8) {
            shade_lanes(plan, grid, samples, lanes, (&mut *color, &mut *alpha));
        }
    }
}

/// Up to eight samples of one mesh (`samples[lanes[i]]`) on the lanes of [`shade_in_lanes`];
/// unused lanes repeat the first sample and are neither composited nor stored.
fn shade_lanes(
    plan: &RenderPlan,
    grid: &GridLight<'_>,
    samples: &[EyeSample],
    lanes: &[usize],
    (color, alpha): (&mut [[f32; 3]], &mut [f32]),
) {
    // Every lane's inputs (unused lanes repeat the first sample), and its light, read as the
    // scalar stage reads it.
    let n = plan.lights.len() * plan.channels as usize;
    let mut at = [[0.0f32; 8]; 3];
    let mut faces = [[[0.0f32; 8]; 3]; 2];
    let mut normal = [[0.0f32; 8]; 3];
    let (mut part, mut lit_from, mut pixel) = ([0.0f32; 8], [0.0f32; 8], [0usize; 8]);
    let mut surface_lanes = [false; MAX_LANES];
    let mut iin = [[0.0f32; 8]; MAX_LIGHT_CHANNELS];
    // The lanes whose lights are all read at one place (no crossing read per light): their
    // bilinear reads' corners and weights, summed below on the lanes.
    let mut shared = [false; MAX_LANES];
    let mut corner = [[0u32; 8]; 4];
    let mut in_grid = [[false; MAX_LANES]; 4];
    let mut weight = [[0.0f32; 8]; 4];
    // The lanes' gathers index with u32: a light buffer beyond that reads one lane at a time.
    let lane_indices = u32::try_from(grid.light.len()).is_ok();
    for i in 0..8 {
        let s = &samples[lanes.get(i).copied().unwrap_or(lanes[0])];
        for k in 0..3 {
            at[k][i] = s.at[k];
            normal[k][i] = s.normal.map_or(0.0, |nv| nv[k]);
            for (f, face) in faces.iter_mut().enumerate() {
                face[k][i] = s.faces.map_or(0.0, |v| v[f][k]);
            }
        }
        (part[i], lit_from[i], pixel[i]) = (s.part, s.lit_from, s.x);
        if i >= lanes.len() {
            continue;
        }
        surface_lanes[i] = s.normal.is_some() && s.shades_surface;
        if lane_indices && !reads_per_light(s.skip, s.back_along_light) {
            shared[i] = true;
            let read = Bilinear::at(plan, grid, s.read_at, s.skip);
            for k in 0..4 {
                weight[k][i] = read.weight[k];
                if let Some(offset) = read.corners[k] {
                    (corner[k][i], in_grid[k][i]) = (offset as u32, true);
                }
            }
            continue;
        }
        let read = s.light(plan, grid);
        for (k, v) in read[..n].iter().enumerate() {
            iin[k][i] = *v;
        }
    }
    let mesh = samples[lanes[0]].mesh;
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    let [x, y, z] = at.map(f32x8::from);
    // One mesh, one material: every lane pre-integrated or none.
    let faces = samples[lanes[0]]
        .faces
        .map(|_| faces.map(|f| f.map(f32x8::from)));
    let mut tf = sample_entry(plan, mesh, [x, y, z], faces);
    let mut iin_lanes = [f32x8::ZERO; MAX_LIGHT_CHANNELS];
    for (lane, v) in iin_lanes.iter_mut().zip(&iin[..n]) {
        *lane = f32x8::from(*v);
    }
    if shared.iter().any(|&b| b) {
        // `Bilinear::sum` on the lanes: corner by corner from 0, outside the grid 1.
        let ch = plan.channels as usize;
        let (one, shared) = (f32x8::ONE, f32x8::m_from(&shared));
        let (weight, corner) = (weight.map(f32x8::from), corner.map(u32x8::from));
        let in_grid = in_grid.map(|m| f32x8::m_from(&m));
        for l in 0..plan.lights.len() {
            for c in 0..ch {
                let at = u32x8::splat((light_block(plan, l) + c) as u32);
                let mut sum = f32x8::ZERO;
                for k in 0..4 {
                    let v = f32x8::gather(grid.light, corner[k] + at);
                    sum += weight[k] * f32x8::select(in_grid[k], v, one);
                }
                let lane = &mut iin_lanes[l * ch + c];
                *lane = f32x8::select(shared, sum, *lane);
            }
        }
    }
    let in_use: [bool; MAX_LANES] = std::array::from_fn(|i| i < lanes.len());
    let surface = surface_lanes
        .iter()
        .any(|&b| b)
        .then(|| (normal.map(f32x8::from), f32x8::m_from(&surface_lanes)));
    let part = (f32x8::from(part), f32x8::from(lit_from));
    let mut c = [0, 1, 2].map(|k| f32x8::from(pixel.map(|x| color[x][k])));
    let mut a = f32x8::from(pixel.map(|x| alpha[x]));
    let (target, lanes_in_use) = ((&mut c, &mut a), f32x8::m_from(&in_use));
    let iin = &iin_lanes[..n];
    shade_sample(
        plan,
        material,
        &mut tf,
        part,
        iin,
        surface,
        target,
        lanes_in_use,
    );
    for (i, &x) in pixel.iter().enumerate().take(lanes.len()) {
        color[x] = [0, 1, 2].map(|k| c[k].lane(i));
        alpha[x] = a.lane(i);
    }
}

/// The transfer-function entry of a sample of mesh `mesh` read at `at` (per lane): the
/// material's table at the detail there ([`material_at`]), or for a pre-integrated material the
/// pre-integration table at the detail on the slab's two faces `faces` (`pre_transfer`, as the
/// grid's sweep reads it).
fn sample_entry<L: Lane>(
    plan: &RenderPlan,
    mesh: u32,
    [x, y, z]: [L; 3],
    faces: Option<[[L; 3]; 2]>,
) -> TfLanes<L> {
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    match (&material.pre, faces) {
        (Some(table), Some([f, b])) => pre_transfer(
            table,
            detail_at(plan, mesh, f[0], f[1], f[2]),
            detail_at(plan, mesh, b[0], b[1], b[2]),
        ),
        _ => material_at(plan, mesh, x, y, z),
    }
}

/// Grid position (gx, gy) at relative depth `z` in the coordinates the material is read in: the
/// grid's image pixels (the guard band taken off, pixel corners at integers), and `z`.
fn on_image(plan: &RenderPlan, (gx, gy): (f32, f32), z: f32) -> [f32; 3] {
    [
        gx - 0.5 - plan.guard.left as f32,
        gy - 0.5 - plan.guard.top as f32,
        z,
    ]
}

/// Where the ray of eye pixel `p` meets view depth `z_origin + z` (turned round: `z_origin −
/// z`), in grid pixel coordinates.
fn ray_on_grid(view: &EyeView<'_>, p: &EyePixel, z: f32) -> (f32, f32) {
    let view_depth = view_depth(view, z);
    let scale = view.scale + view_depth * view.zoom;
    let Some(point) = &view.point else {
        return (
            view.axis[0] + p.offset[0] * scale,
            view.axis[1] + p.offset[1] * scale,
        );
    };
    // A point light's grid: the ray's offset from the light's centre, projected from it.
    let k = point.focal / (view_depth - point.depth);
    (
        view.axis[0] + (p.offset[0] * scale - point.offset[0]) * k,
        view.axis[1] + (p.offset[1] * scale - point.offset[1]) * k,
    )
}

/// The eye's view depth of the grid's relative depth `z`: `z_origin + z` (turned round:
/// `z_origin − z`).
fn view_depth(view: &EyeView<'_>, z: f32) -> f32 {
    if view.turned_round {
        view.z_origin - z
    } else {
        view.z_origin + z
    }
}

/// Where the ray of eye pixel `p` meets relative depth `z`, in the eye's slab-grid frame of a
/// point light's grid (`point.shading`'s coordinates: turned round, the turned frame's, where the
/// pixel's offset is mirrored and `z` is the turned depth already).
fn ray_in_frame(view: &EyeView<'_>, point: &EyePoint<'_>, p: &EyePixel, z: f32) -> [f32; 3] {
    let scale = view.scale + view_depth(view, z) * view.zoom;
    [
        point.frame_axis[0] + p.offset[0] * scale,
        point.frame_axis[1] + p.offset[1] * scale,
        z,
    ]
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

/// One eye sample after its cursor, before its material (read by [`material_at`], one by one or
/// in lanes), its light read and its shading ([`eye_shade`]).
struct EyeSample {
    /// The image pixel's column.
    x: usize,
    /// The mesh shaded.
    mesh: u32,
    /// Where the material is read: image-pixel x, y (of the grid's image) and relative depth.
    at: [f32; 3],
    /// A pre-integrated material's two reads ([`sample_entry`]): the ray's points on the slab's
    /// front face (or at the crossing) and back face, as `at`.
    faces: Option<[[f32; 3]; 2]>,
    /// The part of the slab inside the medium and the depth its light is taken at
    /// ([`slab_part`]).
    part: f32,
    lit_from: f32,
    /// The crossed triangle's normal, at a crossing.
    normal: Option<[f32; 3]>,
    /// Whether the crossed surface takes a highlight or the Lambert term.
    shades_surface: bool,
    /// Where the grid's light is read ([`read_light`]): the ray's grid position, the grid
    /// pixels left out, and how many slabs back along each light.
    read_at: (f32, f32),
    skip: Skip,
    back_along_light: Option<f32>,
    /// A point light's grid: where the sample is in the eye's slab-grid frame
    /// ([`ray_in_frame`]), for the direction to the light.
    in_frame: Option<[f32; 3]>,
}

impl EyeSample {
    /// Every light's channels read from `grid` for this sample ([`read_light`]).
    fn light(&self, plan: &RenderPlan, grid: &GridLight<'_>) -> [f32; MAX_LIGHT_CHANNELS] {
        let crossing = (self.skip, self.normal);
        read_light(plan, grid, self.read_at, crossing, self.back_along_light)
    }
}

/// One image pixel through one slab up to its material read: cursor, shading point, where the
/// light is read;
/// `None` where nothing is shaded (an opaque pixel of a front-to-back pass, or no mesh).
fn eye_sample(
    plan: &RenderPlan,
    view: &EyeView<'_>,
    p: &EyePixel,
    (next, inside): (&mut u32, &mut u32),
    alpha: f32,
) -> Option<EyeSample> {
    if alpha == 1.0 && !view.turned_round {
        // Opaque: compositing adds (1 − 1)·α·c, exactly 0 (the early finish's argument), so
        // nothing later changes this pixel's bits. (Back to front, nearer slabs still do.)
        return None;
    }
    let ldi = view.ldi;
    let end = ldi.offsets[p.y * view.width as usize + p.x + 1];
    let before = *inside;
    let crossed = advance(ldi, next, end, inside, p.back);
    let mesh = if crossed != NO_CROSSING {
        u32::from(ldi.mesh[crossed as usize])
    } else {
        first_mesh(*inside)?
    };
    let z = shading_depth(
        plan,
        ldi,
        crossed,
        p.front,
        p.jitter_row,
        p.x + plan.guard.left as usize,
    );
    let (gx, gy) = ray_on_grid(view, p, z);
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
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    // Where the ray is, in the image pixels of the grid's image (the material's coordinates).
    let image_at = |z: f32| on_image(plan, ray_on_grid(view, p, z), z);
    let (part, mut lit_from) = slab_part(
        ldi,
        (mesh, plan.second_order_media),
        (before, *inside),
        (crossed, next.wrapping_sub(1)),
        (p.front, p.back),
        plan.inv_slab_distance,
    );
    // Pre-integrated: the detail on the slab's faces along the ray (at a crossing, from the
    // crossing: the grid's `preintegrated`); the entry has the light's decay inside the slab in
    // its colour.
    let faces = material.pre.is_some().then(|| {
        let front = if crossed == NO_CROSSING { p.front } else { z };
        [image_at(front), image_at(p.back)]
    });
    if faces.is_some() {
        lit_from = 0.0;
    }
    let shades_surface = uses_normals(plan, material);
    Some(EyeSample {
        x: p.x,
        mesh,
        at: on_image(plan, (gx, gy), z),
        faces,
        part,
        lit_from,
        normal,
        shades_surface,
        read_at: (gx, gy),
        skip,
        back_along_light,
        in_frame: view.point.as_ref().map(|pt| ray_in_frame(view, pt, p, z)),
    })
}

/// The rest of an eye sample's step with its transfer-function entry `tf`: the light read from
/// `grid`, the part of the slab inside the medium, shading, compositing into the pixel's `color`
/// and `alpha`.
fn eye_shade(
    plan: &RenderPlan,
    view: &EyeView<'_>,
    grid: &GridLight<'_>,
    sample: &EyeSample,
    mut tf: TfLanes<f32>,
    (color, alpha): (&mut [f32; 3], &mut f32),
) {
    let material = &plan.materials[plan.mesh_material[sample.mesh as usize] as usize];
    let iin = sample.light(plan, grid);
    let n = plan.lights.len() * plan.channels as usize;
    let surface = sample.normal.filter(|_| sample.shades_surface);
    let part = (sample.part, sample.lit_from);
    let surface = surface.map(|normal| (normal, true));
    // A point light (its grid's one light): the direction to it from this sample, and its
    // centre's falloff, cone and pattern in its colour; else the plan's terms.
    let point = (view.point.as_ref().zip(sample.in_frame))
        .map(|(point, at)| point.shading.terms(at, point.phase[sample.mesh as usize]));
    let terms = |l: usize| point.unwrap_or_else(|| LightTerms::of(plan, material, l));
    let target = (color, alpha);
    shade_sample_with(
        plan,
        material,
        &mut tf,
        part,
        &iin[..n],
        surface,
        target,
        true,
        terms,
    );
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
    let per_light = reads_per_light(skip, back_along_light);
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

/// Whether each light is read at its own place or with its own grid pixels left out (a
/// turned-round pass's crossing, a thin shell's), not all with one [`Bilinear`] read.
fn reads_per_light(skip: Skip, back_along_light: Option<f32>) -> bool {
    back_along_light.is_some() || matches!(skip, Skip::Shell { .. })
}

/// A bilinear read of the grid at one position: its four corners and their weights, those
/// already past the crossed mesh left out.
struct Bilinear {
    /// Each corner's first light value in the grid's light rows (its pixel's offset in a
    /// light's block), `None` beyond the grid.
    corners: [Option<usize>; 4],
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
        let weight = if matches!(skip, Skip::None) {
            bilinear
        } else {
            let weight = [0, 1, 2, 3].map(|k| {
                if skipped(corners[k]) {
                    0.0
                } else {
                    bilinear[k]
                }
            });
            let total = ((weight[0] + weight[1]) + weight[2]) + weight[3];
            if total > 0.0 {
                weight.map(|a| a / total)
            } else {
                bilinear
            }
        };
        let (row_len, planes) = (plan.light_row_len(), plan.planes_per_light());
        let corners = corners
            .map(|(x, y)| in_grid(plan, x, y).then(|| y as usize * row_len + x as usize * planes));
        Bilinear { corners, weight }
    }

    /// Light `l`'s channels of this read into `out` (outside the grid the unoccluded light, 1).
    fn sum(&self, plan: &RenderPlan, grid: &GridLight<'_>, l: usize, out: &mut [f32]) {
        let ch = plan.channels as usize;
        let block = light_block(plan, l);
        for c in 0..ch {
            let mut sum = 0.0f32;
            for (corner, w) in self.corners.iter().zip(self.weight) {
                let v = corner.map_or(1.0, |at| grid.light[at + block + c]);
                sum += w * v;
            }
            out[l * ch + c] = sum;
        }
    }
}

/// Whether grid pixel (x, y) exists.
fn in_grid(plan: &RenderPlan, x: i64, y: i64) -> bool {
    x >= 0 && y >= 0 && x < i64::from(plan.grid_width) && y < i64::from(plan.grid_height)
}
