use convshadow_common::model::scene::Scene;
use convshadow_common::pixel::hash::unit_float;
use convshadow_common::plan::{LIT_LEVEL, RenderPlan};
use convshadow_common::prepare::geometry::SceneGeometry;
use wide::f32x8;

use super::*;
use crate::kernels::LightTaps;
use crate::ldi::Ldi;
use crate::sweep::fast::SimdSlab;
use crate::sweep::fast::TapColumns;
use crate::sweep::fast::quiet::Cursors;
use crate::sweep::kit::Reach;
use crate::sweep::pixel::sweep_pixel;

use convshadow_testkit::TestRng;

/// A value in [0, 1], exactly 0 or exactly 1 one time in eight each.
fn value(rng: &mut TestRng) -> f32 {
    match rng.below(8) {
        0 => 0.0,
        1 => 1.0,
        _ => unit_float(rng.next_u32()),
    }
}

/// One row's state, owned.
#[derive(Clone)]
struct Row {
    light: Vec<f32>,
    levels: Vec<u32>,
    next: Vec<u32>,
    inside: Vec<u32>,
    color: Vec<f32>,
    alpha: Vec<f32>,
    pre: Vec<f32>,
    hold: Vec<u32>,
}

impl Row {
    fn state(&mut self) -> RowState<'_> {
        RowState {
            light: &mut self.light,
            levels: &mut self.levels,
            next: &mut self.next,
            inside: &mut self.inside,
            color: &mut self.color,
            alpha: &mut self.alpha,
            pre: &mut self.pre,
            hold: &mut self.hold,
        }
    }
}

/// The first difference in bits between two rows' states, if any.
fn mismatch(a: &Row, b: &Row) -> Option<String> {
    let floats = [
        ("light", &a.light, &b.light),
        ("color", &a.color, &b.color),
        ("alpha", &a.alpha, &b.alpha),
        ("pre", &a.pre, &b.pre),
    ];
    for (name, u, v) in floats {
        if let Some(i) = (0..u.len()).find(|&i| u[i].to_bits() != v[i].to_bits()) {
            return Some(format!("{name}[{i}]: {} vs {}", u[i], v[i]));
        }
    }
    let ints = [
        ("levels", &a.levels, &b.levels),
        ("next", &a.next, &b.next),
        ("inside", &a.inside, &b.inside),
        ("hold", &a.hold, &b.hold),
    ];
    for (name, u, v) in ints {
        if let Some(i) = (0..u.len()).find(|&i| u[i] != v[i]) {
            return Some(format!("{name}[{i}]: {} vs {}", u[i], v[i]));
        }
    }
    None
}

/// The default scene, small, its wall turned 30° about x so that it is held (surface holds):
/// two coloured lights (six light channels), noise and specular materials, three meshes, through `kernel` with `penumbra` ("iterated" or "distance"),
/// `preintegration` and `held_lit_side`.
fn plan_of(
    kernel: &str,
    penumbra: &str,
    (preintegration, held_lit_side): (bool, bool),
) -> (Scene, SceneGeometry, Ldi, RenderPlan) {
    let sweep =
        format!("[sweep]\npreintegration = {preintegration}\nheld_lit_side = {held_lit_side}");
    let text = include_str!("../../../../../scenes/default.toml")
        .replace("[sweep]", &sweep)
        .replace("width = 512\nheight = 512", "width = 37\nheight = 19")
        .replace(
            "slabs = 512",
            &format!("slabs = 24\npenumbra = \"{penumbra}\""),
        )
        .replace("kernel = \"ellipse2\"", &format!("kernel = \"{kernel}\""))
        .replace(
            "translate = [0.0, 0.0, 1.3]",
            "translate = [0.0, 0.0, 1.3]\nrotate_deg = [30.0, 0.0, 0.0]",
        );
    crate::sweep::built_scene(&text, "lanes")
}

/// Runs `eight` (an 8-lane stage) and the per-pixel stage (`pixel::sweep_pixel`) on each of
/// its eight pixels on the same random inputs, at every chunk position of some rows of every
/// slab; returns the first difference.
fn compare_lanes(
    kernel: &str,
    penumbra: &str,
    (pre, held_lit_side): (bool, bool),
    seed: u32,
    eight: ChunkFn,
) -> Option<String> {
    let (_scene, g, ldi, plan) = plan_of(kernel, penumbra, (pre, held_lit_side));
    assert_eq!(plan.held_lit_side, held_lit_side);
    assert_eq!(plan.materials.iter().any(|m| m.pre.is_some()), pre);
    assert!(plan.has_surface_hold(), "the turned wall is held");
    let (w, h) = (plan.grid_width as usize, plan.grid_height as usize);
    let row_len = plan.light_row_len();
    let meshes = plan.mesh_material.len() as u32;
    let planes = plan.lights.len() * plan.channels as usize;
    assert_eq!(planes, 6, "two lights, three channels");
    let reach = Reach::of(&plan);
    let mut rng = TestRng::new(seed);
    // Pixel-interleaved, with the sweep's slack after the last row.
    let light: Vec<f32> = (0..row_len * h + crate::sweep::LIGHT_SLACK)
        .map(|_| value(&mut rng))
        .collect();
    // Distance penumbra: each pixel's level any of the table's, or none (one in four).
    let lrl = plan.level_row_len();
    let levels: Vec<u32> = (0..lrl * h)
        .map(|_| match rng.below(4) {
            0 => LIT_LEVEL,
            _ => rng.below(plan.lights[0].table.levels),
        })
        .collect();
    let blocks = crate::sweep::LevelBlocks::new(&plan, &levels).blocks;
    let prev = Previous {
        light: &light,
        levels: &levels,
        level_blocks: &blocks,
    };
    let mut counts = [0u32; 9];
    // Chunks whose summary skipped their cursors, and chunks with a summary that did not.
    let mut summaries = [0u32; 2];
    // Chunks near a pixel held in the previous slab (their lanes gathered again, `super::held`).
    let mut near_held = 0u32;
    let columns: Vec<TapColumns> = plan
        .lights
        .iter()
        .map(|l| TapColumns::new(&l.table, row_len, plan.planes_per_light(), lrl))
        .collect();
    let taps: Vec<LightTaps> = plan
        .lights
        .iter()
        .map(|l| LightTaps::new(&l.table))
        .collect();
    let mut held = crate::composite::HeldRecords::new(&plan);
    for slab in 0..plan.slabs {
        held.prepare(slab, (reach.y0, reach.y1));
        let ctx = SlabContext {
            plan: &plan,
            raster: &g.raster,
            ldi: &ldi,
            taps: &taps,
            reach,
            slab,
            back: plan.slab_back[slab as usize],
            front: plan.slab_front[slab as usize],
            next_level_at: convshadow_common::pixel::levels::level_at(&plan, slab + 1),
            held: held.view(),
        };
        let simd = SimdSlab::new(&plan, &columns, slab);
        for y in [0, 1, h / 2, h - 1, rng.below(h as u32) as usize] {
            let row_ctx = RowContext::new(&ctx, &prev, y);
            // Inside masks: none, one mesh everywhere, or mixed (lanes on different meshes).
            let mode = rng.below(3);
            let fixed = 1 << rng.below(meshes);
            let row = Row {
                light: vec![f32::NAN; row_len],
                levels: vec![7; lrl],
                next: (0..w)
                    .map(|x| {
                        let (a, b) = (ldi.offsets[y * w + x], ldi.offsets[y * w + x + 1]);
                        a + rng.below(b - a + 1)
                    })
                    .collect(),
                inside: (0..w)
                    .map(|_| match mode {
                        0 => 0,
                        1 => fixed,
                        _ => rng.next_u32() & ((1 << meshes) - 1),
                    })
                    .collect(),
                color: (0..3 * w).map(|_| value(&mut rng)).collect(),
                alpha: (0..w).map(|_| value(&mut rng)).collect(),
                // Kept front values: none (NaN) one time in three, else any value (both
                // paths must choose kept or fresh lane by lane alike).
                pre: (0..w)
                    .map(|_| match rng.below(3) {
                        0 => f32::NAN,
                        _ => value(&mut rng),
                    })
                    .collect(),
                // Surface holds: none one time in two, else releasing from two slabs before
                // this one to three after it, held 1 to 4 slabs (released at or after the slab
                // held), with a barrier of 0 to 2 slabs (this slab in it, or past it, or not
                // yet released).
                hold: (0..w)
                    .map(|_| match rng.below(2) {
                        0 => 0,
                        _ => match (slab + rng.below(6)).saturating_sub(2) {
                            0 => 0,
                            release => {
                                let held = 1 + rng.below(release.min(4));
                                crate::composite::hold_state(release - held, held, rng.below(3))
                            }
                        },
                    })
                    .collect(),
            };
            for x0 in 0..=w - 8 {
                let (mut a, mut b) = (row.clone(), row.clone());
                let interior = reach.interior(x0, 8, y, w, h);
                // Every other chunk with its cursor summary (the per-pixel stage visits every
                // cursor).
                let cursors = Cursors {
                    next: &row.next,
                    inside: &row.inside,
                    alpha: &row.alpha,
                    hold: &row.hold,
                };
                let summary = (x0 % 2 == 0).then(|| ChunkState::of(&ldi, y, x0, 8, cursors));
                if let Some(s) = summary {
                    summaries[usize::from(s.crosses_nothing(ctx.back))] += 1;
                }
                let chunk = Chunk {
                    x0,
                    interior,
                    known_light: None,
                    gathered: None,
                    summary,
                    held: crate::sweep::pixel::held_near(&row_ctx, x0, 8),
                };
                near_held += u32::from(chunk.held);
                eight(&simd, &row_ctx, &mut a.state(), chunk);
                // The reference: the per-pixel stage, pixel by pixel.
                for x in x0..x0 + 8 {
                    let interior = reach.interior(x, 1, y, w, h);
                    sweep_pixel(&row_ctx, &mut b.state(), x, interior);
                }
                if let Some(d) = mismatch(&a, &b) {
                    return Some(format!(
                        "{kernel} {penumbra}, slab {slab}, row {y}, x0 {x0}: {d}"
                    ));
                }
                let shaded = (0..8).filter(|&i| a.alpha[x0 + i] != row.alpha[x0 + i]);
                counts[shaded.count()] += 1;
            }
        }
    }
    // The inputs must reach every branch: chunks shaded in no lane, in some and in all.
    assert!(
        counts[0] > 0 && counts[8] > 0 && counts[1..8].iter().sum::<u32>() > 0,
        "{kernel}: chunks by shaded lanes {counts:?}"
    );
    // And both cursor paths: summaries that skip the cursors and summaries that do not.
    assert!(
        summaries[0] > 0 && summaries[1] > 0,
        "{kernel}: summaries (visit, skip) {summaries:?}"
    );
    // With held light read from its lit side, chunks whose lanes are gathered again.
    assert!(
        !held_lit_side || near_held > 0,
        "{kernel}: no chunk near a held pixel"
    );
    None
}

/// [`compare_lanes`] for `kernels` (seeds from `seed`), both penumbra models, and for each
/// both 8-lane instances: the one that reads the shape from the plan and the one that knows it.
fn compare_every_instance(kernels: &[&str], options: (bool, bool), seed: u32) {
    for (k, kernel) in kernels.iter().enumerate() {
        for (penumbra, shape) in [("iterated", RGB_ITERATED), ("distance", RGB_DISTANCE)] {
            for shape in [ANY_SHAPE, shape] {
                let eight = chunk_fn::<f32x8>(6, shape);
                assert_eq!(
                    compare_lanes(kernel, penumbra, options, seed + k as u32, eight),
                    None,
                    "shape {shape}"
                );
            }
        }
    }
}

#[test]
fn every_chunk_instance_gives_the_bits_of_the_pixel_stage() {
    // Per-pixel, per-slab and scheduled phases.
    let kernels = ["ellipse2", "ellipse2:slab", "gaussian:7", "poisson8"];
    compare_every_instance(&kernels, (false, false), 17);
}

#[test]
fn every_chunk_instance_gives_the_bits_of_the_pixel_stage_with_preintegration() {
    compare_every_instance(&["ellipse2", "gaussian:7"], (true, false), 41);
}

#[test]
fn every_chunk_instance_gives_the_bits_of_the_pixel_stage_with_held_light_on_its_lit_side() {
    // The lanes near held pixels gathered again through the rows the chunk's search found.
    compare_every_instance(&["ellipse2", "poisson8"], (false, true), 59);
}

#[test]
fn a_lane_that_disagrees_fails_the_comparison() {
    // The 8-lane stage with one lane's first light value off by one bit.
    let wrong_lane: ChunkFn = |simd, row, state, chunk| {
        let r = sweep_chunk::<f32x8, 6, ANY_SHAPE>(simd, row, state, chunk);
        // (the outcome is returned unchanged: only the light is wrong)
        let at = chunk.x0 + 5;
        state.light[at] = f32::from_bits(state.light[at].to_bits() ^ 1);
        r
    };
    let d = compare_lanes("ellipse2", "distance", (false, false), 3, wrong_lane)
        .expect("the flipped bit is found");
    assert!(d.contains("light["), "{d}");
}
