//! The front-to-back slab sweep (DESIGN §2 "Per slab, per pixel"; paper §4.2), scalar reference
//! path. Mirrors `gpu/src/shaders/sweep.wgsl`.
//!
//! Per slab, rows are processed in parallel; each pixel convolves every light buffer (reading
//! the previous slab's buffer, ping-pong), advances its layer cursor, shades one point if it is
//! inside a mesh or crossed a surface, composites front to back and attenuates its light.
//! A pixel's result depends only on the previous slab and its own state, so the image is the
//! same bits for any thread count.

use std::sync::atomic::{AtomicBool, Ordering};

use convshadow_common::hash::{pixel_hash, row_hash, unit_float};
use convshadow_common::plan::RenderPlan;
use convshadow_common::raster::RasterSetup;
use rayon::prelude::*;

use crate::composite::{attenuate, composite, finish};
use crate::kernels::{Plane, gather, light_row_hash, phase_at};
use crate::ldi::Ldi;
use crate::parity::{NO_CROSSING, advance, first_mesh};
use crate::shading::{detail_value, shade, to_detail, transfer};

/// Largest light count × channels handled per pixel on the stack.
const MAX_LIGHT_CHANNELS: usize = 48;

/// Why a sweep stopped early.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SweepError {
    /// The cancel flag was raised (Ctrl-C / SIGTERM).
    #[error("interrupted")]
    Interrupted,
}

/// The result of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOutput {
    /// Linear RGB, `width·height·3`, the guard band cropped away.
    pub image: Vec<f32>,
    /// The light buffers after the last slab (grid-sized, row-major `[row][light][channel][x]`).
    pub light: Vec<f32>,
}

/// Options of a sweep run.
pub struct SweepOptions<'a> {
    /// Called after every slab with the slab index.
    pub progress: &'a (dyn Fn(u32) + Sync),
    /// Checked between slabs; when raised the sweep stops with [`SweepError::Interrupted`].
    pub cancel: Option<&'a AtomicBool>,
    /// Initial light value per light and channel (`None` = 1, the unoccluded light).
    pub initial_light: Option<&'a [f32]>,
}

impl Default for SweepOptions<'_> {
    fn default() -> Self {
        SweepOptions {
            progress: &|_| {},
            cancel: None,
            initial_light: None,
        }
    }
}

/// Runs the scalar reference sweep on the current rayon pool.
pub fn sweep(
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
) -> Result<SweepOutput, SweepError> {
    let w = plan.grid_width as usize;
    let h = plan.grid_height as usize;
    let ch = plan.channels as usize;
    let lights = plan.lights.len();
    let row_len = plan.light_row_len();
    assert!(
        lights * ch <= MAX_LIGHT_CHANNELS,
        "scene validation caps the light count"
    );

    let mut prev = match options.initial_light {
        Some(v) => v.to_vec(),
        None => vec![1.0f32; row_len * h],
    };
    let mut cur = vec![0.0f32; row_len * h];
    let mut next: Vec<u32> = ldi.offsets[..w * h].to_vec();
    let mut inside = vec![0u32; w * h];
    let mut color = vec![0.0f32; w * h * 3];
    let mut alpha = vec![0.0f32; w * h];

    for slab in 0..plan.slabs {
        if options.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(SweepError::Interrupted);
        }
        let prev_ref = &prev;
        cur.par_chunks_mut(row_len)
            .zip(next.par_chunks_mut(w))
            .zip(inside.par_chunks_mut(w))
            .zip(color.par_chunks_mut(w * 3))
            .zip(alpha.par_chunks_mut(w))
            .enumerate()
            .for_each(
                |(y, ((((cur_row, next_row), inside_row), color_row), alpha_row))| {
                    sweep_row(
                        plan,
                        raster,
                        ldi,
                        slab,
                        y,
                        prev_ref,
                        RowState {
                            light: cur_row,
                            next: next_row,
                            inside: inside_row,
                            color: color_row,
                            alpha: alpha_row,
                        },
                    );
                },
            );
        std::mem::swap(&mut prev, &mut cur);
        (options.progress)(slab);
    }

    let g = plan.guard as usize;
    let (iw, ih) = (plan.width as usize, plan.height as usize);
    let mut image = vec![0.0f32; iw * ih * 3];
    image
        .par_chunks_mut(iw * 3)
        .enumerate()
        .for_each(|(y, row)| {
            for x in 0..iw {
                let p = (y + g) * w + x + g;
                let mut c = [color[3 * p], color[3 * p + 1], color[3 * p + 2]];
                finish(&mut c, alpha[p], plan.background);
                row[3 * x..3 * x + 3].copy_from_slice(&c);
            }
        });
    Ok(SweepOutput { image, light: prev })
}

/// One row's mutable per-pixel state.
struct RowState<'a> {
    light: &'a mut [f32],
    next: &'a mut [u32],
    inside: &'a mut [u32],
    color: &'a mut [f32],
    alpha: &'a mut [f32],
}

/// Processes one row of one slab (all five stages for every pixel of the row).
fn sweep_row(
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    slab: u32,
    y: usize,
    prev: &[f32],
    row: RowState<'_>,
) {
    let w = plan.grid_width as usize;
    let ch = plan.channels as usize;
    let row_len = plan.light_row_len();
    let back = plan.slab_back[slab as usize];
    let front = plan.slab_front[slab as usize];
    let jitter_row = row_hash(plan.jitter_slab_hash[slab as usize], y as u32);
    let mut row_hashes = [0u32; MAX_LIGHT_CHANNELS];
    for (l, light) in plan.lights.iter().enumerate() {
        row_hashes[l] = light_row_hash(light.slab_hash[slab as usize], y as u32);
    }
    let mut iin = [0.0f32; MAX_LIGHT_CHANNELS];

    for x in 0..w {
        // 1. Convolution of every light buffer.
        for (l, light) in plan.lights.iter().enumerate() {
            let t = &light.table;
            let phase = phase_at(
                t,
                slab,
                light.slab_hash[slab as usize],
                row_hashes[l],
                x as u32,
            );
            let taps = t.phase(phase);
            let shift = t.slab_shift[slab as usize];
            for c in 0..ch {
                let plane = Plane {
                    data: prev,
                    base: (l * ch + c) * w,
                    row_stride: row_len,
                    width: w as i32,
                    height: plan.grid_height as i32,
                };
                iin[l * ch + c] = gather(&plane, taps, shift, x as i32, y as i32);
            }
        }

        // 2. Intersection: advance the layer cursor to the slab's back face.
        let p = y * w + x;
        let end = ldi.offsets[p + 1];
        let crossed = advance(ldi, &mut row.next[x], end, &mut row.inside[x], back);

        // 3. Shading at one point, if inside a mesh or a surface was crossed.
        let mesh = if crossed != NO_CROSSING {
            Some(u32::from(ldi.mesh[crossed as usize]))
        } else {
            first_mesh(row.inside[x])
        };
        let mut attenuation = [1.0f32; 3];
        if let Some(mesh) = mesh {
            let z = if crossed != NO_CROSSING {
                ldi.depth[crossed as usize]
            } else if plan.jitter {
                front + unit_float(pixel_hash(jitter_row, x as u32)) * plan.slab_distance
            } else {
                front + 0.5 * plan.slab_distance
            };
            let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
            let value = if material.tf.len() > 1 {
                let q = to_detail(
                    &plan.mesh_to_detail[mesh as usize],
                    x as f32 + 0.5,
                    y as f32 + 0.5,
                    z,
                );
                detail_value(material, q)
            } else {
                0.0
            };
            let tf = transfer(&material.tf, value);
            let spec = match material.specular {
                Some((strength, exponent)) if crossed != NO_CROSSING => {
                    let n = raster.triangles[ldi.triangle[crossed as usize] as usize].normal;
                    Some((strength, exponent, n))
                }
                _ => None,
            };
            let shaded = shade(plan, tf.color, &iin[..plan.lights.len() * ch], spec);
            // 4. Composite front to back.
            let mut c = [row.color[3 * x], row.color[3 * x + 1], row.color[3 * x + 2]];
            composite(&mut c, &mut row.alpha[x], shaded, tf.alpha);
            row.color[3 * x..3 * x + 3].copy_from_slice(&c);
            attenuation = tf.attenuation;
        }

        // 5. Attenuate (and flush) into this slab's outgoing light buffer.
        for l in 0..plan.lights.len() {
            for c in 0..ch {
                row.light[(l * ch + c) * w + x] = attenuate(iin[l * ch + c], attenuation[c]);
            }
        }
    }
}
