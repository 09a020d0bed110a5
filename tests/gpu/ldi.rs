//! The GPU LDI equals the CPU LDI: same CSR offsets, depths (bits), triangle and mesh ids, hence
//! the same `ldi_hash` and fragment counts — on every example scene, on real models, and on
//! hand-made triangles that stress the emulated 64-bit edge functions and the top-left rule.

use crate::support;
use crate::support::gpu as gpu_common;

use convshadow::common::prepare::guard::GuardBand;
use convshadow::common::prepare::raster::{FIXED_ONE, RasterSetup, TriangleSetup};
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow_gpu::GpuContext;
use convshadow_gpu::ldi::build_ldi;
use support::TestRng;

const BUDGET: u64 = 1 << 30;

/// Builds both LDIs and asserts they are identical, with a precise message if not.
fn assert_same_ldi(ctx: &GpuContext, setup: &RasterSetup, what: &str) -> (u64, u64) {
    let cpu = Ldi::build(setup, BUDGET).unwrap();
    let gpu = build_ldi(ctx, setup, BUDGET).unwrap();
    assert_eq!(
        cpu.offsets.len(),
        gpu.offsets.len(),
        "{what}: offsets length"
    );
    if let Some(p) = (0..cpu.offsets.len()).find(|&p| cpu.offsets[p] != gpu.offsets[p]) {
        panic!(
            "{what}: CSR offsets differ first at pixel {p} ({}, {}): cpu {} gpu {}",
            p as u32 % setup.width,
            p as u32 / setup.width,
            cpu.offsets[p],
            gpu.offsets[p]
        );
    }
    if let Some(f) = (0..cpu.depth.len()).find(|&f| {
        cpu.depth[f].to_bits() != gpu.depth[f].to_bits() || cpu.triangle[f] != gpu.triangle[f]
    }) {
        let p = cpu.offsets.partition_point(|&o| o as usize <= f) - 1;
        let r = cpu.offsets[p] as usize..cpu.offsets[p + 1] as usize;
        let list = |l: &Ldi| -> Vec<(f32, u32)> {
            r.clone().map(|k| (l.depth[k], l.triangle[k])).collect()
        };
        let g = list(&gpu);
        let bad: Vec<_> = (1..g.len())
            .filter(|&k| g[k - 1].0 > g[k].0)
            .map(|k| (k, g[k - 1], g[k]))
            .collect();
        eprintln!("layers {} unsorted at {bad:?}", g.len());
        let mut a = list(&cpu);
        let mut b = list(&gpu);
        a.sort_by_key(|x| x.1);
        b.sort_by_key(|x| x.1);
        let only_cpu: Vec<_> = a
            .iter()
            .filter(|x| {
                !b.iter()
                    .any(|y| y.1 == x.1 && y.0.to_bits() == x.0.to_bits())
            })
            .collect();
        let only_gpu: Vec<_> = b
            .iter()
            .filter(|x| {
                !a.iter()
                    .any(|y| y.1 == x.1 && y.0.to_bits() == x.0.to_bits())
            })
            .collect();
        panic!(
            "{what}: only cpu {only_cpu:?} only gpu {only_gpu:?}; fragment {f} of pixel ({}, {}) differs: cpu (depth {:e}, triangle {}) gpu \
             (depth {:e}, triangle {})\ncpu {:?}\ngpu {:?}",
            p as u32 % setup.width,
            p as u32 / setup.width,
            cpu.depth[f],
            cpu.triangle[f],
            gpu.depth[f],
            gpu.triangle[f],
            list(&cpu),
            list(&gpu)
        );
    }
    assert_eq!(cpu.mesh, gpu.mesh, "{what}: mesh ids");
    assert_eq!(cpu.stats(), gpu.stats(), "{what}: stats");
    assert_eq!(cpu.fingerprint(), gpu.fingerprint(), "{what}: ldi_hash");
    let fragments = cpu.stats().fragments;
    eprintln!(
        "{what}: {} triangles, {fragments} fragments, ldi_hash {:016x} on both backends",
        setup.triangles.len(),
        cpu.fingerprint()
    );
    (fragments, cpu.fingerprint())
}

#[test]
fn gpu_ldi_equals_cpu_on_every_example_scene() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    for path in gpu_common::example_scenes() {
        for size in [64, 173] {
            let scene = gpu_common::small(&path, size, 16);
            let geometry = convshadow_io::build_geometry(&scene).unwrap();
            let (fragments, _) = assert_same_ldi(
                &ctx,
                &geometry.raster,
                &format!("{} at {size}px", path.display()),
            );
            assert!(
                fragments > 0,
                "{}: the scene covers nothing",
                path.display()
            );
        }
    }
}

#[test]
fn gpu_ldi_equals_cpu_on_real_models() {
    let Some(models) = support::models_dir() else {
        return;
    };
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    for name in ["bunny_hr.obj", "armadillo_100k.obj", "teapot.obj"] {
        let path = models.join(name);
        let mesh = convshadow::io::obj::load_obj(&path).unwrap_or_else(|e| panic!("{e}"));
        let (lo, hi) = mesh.bounds();
        let c = (lo + hi) * 0.5;
        let text = support::obj_scene(&path, 256, (hi - lo).max_element() * 1.2).replace(
            "direction = [0.3, -0.2, 1.0]",
            &format!(
                "direction = [0.3, -0.2, 1.0]\ncenter = [{}, {}, {}]",
                c.x, c.y, c.z
            ),
        );
        let scene = support::scene(&text, &models);
        let geometry = convshadow_io::build_geometry(&scene).unwrap();
        let (fragments, _) = assert_same_ldi(&ctx, &geometry.raster, name);
        assert!(fragments > 1000, "{name}: only {fragments} fragments");
    }
}

/// A triangle set up the way `RasterSetup::new` does (positive area, clipped box), or `None`.
fn setup_triangle(
    mut v: [[i64; 2]; 3],
    w: u32,
    h: u32,
    mesh: u32,
    depth: [f32; 3],
) -> Option<TriangleSetup> {
    let area =
        (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
    if area == 0 {
        return None;
    }
    let front_facing = area < 0;
    if front_facing {
        v.swap(1, 2);
    }
    let first = |x: i64| (x - FIXED_ONE / 2 + FIXED_ONE - 1).div_euclid(FIXED_ONE);
    let last = |x: i64| (x - FIXED_ONE / 2).div_euclid(FIXED_ONE);
    let lo = |k: usize| v.iter().map(|p| p[k]).min().unwrap();
    let hi = |k: usize| v.iter().map(|p| p[k]).max().unwrap();
    let x0 = first(lo(0)).max(0);
    let y0 = first(lo(1)).max(0);
    let x1 = last(hi(0)).min(i64::from(w) - 1);
    let y1 = last(hi(1)).min(i64::from(h) - 1);
    if x0 > x1 || y0 > y1 {
        return None;
    }
    Some(TriangleSetup {
        v: v.map(|p| [p[0] as i32, p[1] as i32]),
        bbox: [x0 as i32, y0 as i32, x1 as i32, y1 as i32],
        depth_ref: depth[0],
        depth_dx: depth[1],
        depth_dy: depth[2],
        mesh,
        front_facing,
        normal: [0.0, 0.0, -1.0],
    })
}

#[test]
fn gpu_ldi_equals_cpu_on_hard_triangles() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let (w, h) = (96u32, 80u32);
    let limit = (1i64 << 21) * FIXED_ONE - 1;
    let mut rng = TestRng::new(42);
    let mut triangles = Vec::new();
    let centre = |i: i64| i * FIXED_ONE + FIXED_ONE / 2;
    // A fan of triangles sharing edges through pixel centres (top-left rule on shared edges).
    for k in 0..12i64 {
        let a = [centre(40), centre(40)];
        let b = [centre(40 + (k * 7) % 30 - 15), centre(10 + k * 5)];
        let c = [
            centre(40 + ((k + 1) * 7) % 30 - 15),
            centre(10 + (k + 1) * 5),
        ];
        triangles.extend(setup_triangle(
            [a, b, c],
            w,
            h,
            (k % 3) as u32,
            [0.5, 0.01, -0.02],
        ));
    }
    for n in 0..3000u32 {
        let v: [[i64; 2]; 3] = match n % 4 {
            // Huge triangles reaching the ±2^21 px coordinate limit: products need 60+ bits.
            0 => std::array::from_fn(|_| {
                [rng.int_range(-limit, limit), rng.int_range(-limit, limit)]
            }),
            // One far vertex, two near the grid: long slivers crossing the image.
            1 => {
                let far = [rng.int_range(-limit, limit), rng.int_range(-limit, limit)];
                let near =
                    |r: &mut TestRng| [r.int_range(-512, 100 * 256), r.int_range(-512, 90 * 256)];
                [far, near(&mut rng), near(&mut rng)]
            }
            // Vertices exactly on pixel centres.
            2 => std::array::from_fn(|_| {
                [
                    centre(rng.int_range(-4, 100)),
                    centre(rng.int_range(-4, 84)),
                ]
            }),
            // Small and sub-pixel triangles anywhere on the grid.
            _ => {
                let x = rng.int_range(0, 96 * 256);
                let y = rng.int_range(0, 80 * 256);
                std::array::from_fn(|_| {
                    [x + rng.int_range(-300, 300), y + rng.int_range(-300, 300)]
                })
            }
        };
        // Depth planes with arbitrary bits, including negative and tiny slopes.
        let d = |r: &mut TestRng| (r.int_range(-1_000_000, 1_000_000) as f32) * 1.37e-4;
        let depth = [d(&mut rng), d(&mut rng) * 1e-3, d(&mut rng) * 1e-3];
        triangles.extend(setup_triangle(v, w, h, n % 5, depth));
    }
    let setup = RasterSetup {
        width: w,
        height: h,
        guard: GuardBand::default(),
        triangles,
        zero_area: 0,
        parity_meshes: u32::MAX,
        perspective_origin: None,
    };
    let (fragments, _) = assert_same_ldi(&ctx, &setup, "hard triangles");
    assert!(fragments > 10_000, "only {fragments} fragments");
    // The same planes read as inverse depths (perspective): `1 / plane − origin`, with planes
    // through zero and of either sign, in the CPU's f32 order.
    let perspective = RasterSetup {
        perspective_origin: Some(0.37),
        ..setup
    };
    assert_same_ldi(&ctx, &perspective, "hard triangles in perspective");
}

#[test]
fn gpu_ldi_equals_cpu_in_perspective() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // A ball on a floor running back, and (with ../shared/models) every closed model close up.
    let mut scenes = vec![(
        "ball on a floor".to_string(),
        support::perspective_ball_scene(160, 96, glam::DVec3::new(0.0, 1.0, -5.0), 60.0, ""),
    )];
    if let Some(models) = support::models_dir() {
        for name in support::CLOSED_MODELS {
            let path = models.join(name);
            let mesh = convshadow::io::obj::load_obj(&path).unwrap_or_else(|e| panic!("{e}"));
            let (lo, hi) = mesh.bounds();
            let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
            for fov in [30.0f64, 90.0] {
                let eye = c - glam::DVec3::new(0.3, -0.2, 1.0).normalize() * r
                    / (0.5 * fov).to_radians().sin();
                let mesh = format!(
                    "[[mesh]]\nshape = \"obj\"\npath = \"{}\"\nmaterial = \"m\"",
                    path.display()
                );
                scenes.push((
                    format!("{name} fov {fov}"),
                    support::perspective_scene_text((256, 192), (eye, c), fov, "", &mesh),
                ));
            }
        }
    }
    for (what, text) in scenes {
        let scene = support::scene(&text, std::path::Path::new("."));
        let geometry = convshadow_io::build_geometry(&scene).unwrap();
        assert!(geometry.raster.perspective_origin.is_some(), "{what}");
        let (fragments, _) = assert_same_ldi(&ctx, &geometry.raster, &what);
        assert!(fragments > 1000, "{what}: only {fragments} fragments");
    }
}
