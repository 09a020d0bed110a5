//! Sweep throughput in pixel·slab·light updates per second: every kernel on the SIMD path, the
//! scalar path against the SIMD path on 1 and 2 threads, each "model only what the scene needs"
//! measure on and off (quiet-chunk skipping, one light channel for grey transport), and the
//! flush (a medium dense enough to drive the light below f32's normal range must not run slower
//! than a clear one: without the flush, subnormal arithmetic would slow every gather).

use std::path::Path;

use convshadow::common::model::kernel::KERNEL_NAMES;
use convshadow::common::model::scene::{Scene, SlabSpec};
use convshadow::common::plan::RenderPlan;
use convshadow::common::prepare::geometry::SceneGeometry;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::cpu::sweep::{CpuOptions, SweepOptions, SweepPath, sweep_with};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

/// A box of fog filling the view; `opacity` and `transport` set how fast the light dies.
fn fog(opacity: f64, transport: f64) -> Scene {
    let text = format!(
        "[image]\nwidth = 128\nheight = 128\n[camera]\nview_width = 4.0\n[sweep]\nslabs = 256\n\
         optimal_distance = 0.5\n[[light]]\ntilt_deg = [10.0, 0.0]\nvariance = [0.01, 0.01]\n\
         [[mesh]]\nshape = \"box\"\nsize = [5.0, 5.0, 4.0]\nmaterial = \"fog\"\n[material.fog]\n\
         opacity = {opacity}\ntransport = [{transport}, {transport}, {transport}]\n"
    );
    Scene::parse(&text, "bench", Path::new(".")).expect("bench scene")
}

/// The default scene at 256², 256 slabs (a quarter of its pixels and half its slabs).
fn default_256(kernel: &str) -> Scene {
    let mut s = Scene::default_scene();
    s.image.width = 256;
    s.image.height = 256;
    s.sweep.slabs = SlabSpec::Count(256);
    s.sweep.kernel = kernel.parse().expect("kernel");
    s
}

/// Everything a sweep needs, built once per scene.
struct Prepared {
    geometry: SceneGeometry,
    ldi: Ldi,
    plan: RenderPlan,
}

impl Prepared {
    fn new(scene: &Scene) -> Prepared {
        let geometry = convshadow_io::build_geometry(scene).expect("geometry");
        let ldi = Ldi::build(&geometry.raster, u64::MAX).expect("ldi");
        let plan = convshadow_io::build_plan(scene, &geometry).expect("plan");
        Prepared {
            geometry,
            ldi,
            plan,
        }
    }

    /// Pixel·slab·light updates of one sweep.
    fn updates(&self) -> u64 {
        u64::from(self.plan.grid_width)
            * u64::from(self.plan.grid_height)
            * u64::from(self.plan.slabs)
            * self.plan.lights.len() as u64
    }

    fn run(&self, pool: &rayon::ThreadPool, path: SweepPath, skip_quiet: bool) {
        let cpu = CpuOptions {
            path,
            skip_quiet,
            ..CpuOptions::default()
        };
        let (plan, raster, ldi) = (&self.plan, &self.geometry.raster, &self.ldi);
        pool.install(|| sweep_with(plan, raster, ldi, &SweepOptions::default(), &cpu))
            .expect("sweep");
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool")
}

/// Scalar vs SIMD (skipping on and off), 1 vs 2 threads, `ellipse2` on the default scene.
fn paths_and_threads(c: &mut Criterion) {
    let p = Prepared::new(&default_256("ellipse2"));
    let mut group = c.benchmark_group("sweep_paths/default_256/ellipse2");
    group.throughput(Throughput::Elements(p.updates()));
    group.sample_size(10);
    for threads in [1usize, 2] {
        let pool = pool(threads);
        for (name, path, skip) in [
            ("scalar", SweepPath::Scalar, false),
            ("simd_no_skip", SweepPath::Simd, false),
            ("simd", SweepPath::Simd, true),
        ] {
            group.bench_function(BenchmarkId::new(name, format!("{threads}_threads")), |b| {
                b.iter(|| p.run(&pool, path, skip))
            });
        }
    }
    group.finish();
}

/// Every kernel on the SIMD path, 2 threads, skipping off (the kernel's own cost) and on.
fn kernels(c: &mut Criterion) {
    let mut group = c.benchmark_group("sweep_kernels/default_256");
    group.sample_size(10);
    let pool = pool(2);
    for kernel in KERNEL_NAMES {
        // `gaussian:19` and `box` read tens of taps per pixel (a sweep of default_256 takes ~26 s):
        // they run on a quarter of the pixels and half the slabs, with skipping only.
        let heavy = kernel == "gaussian:19" || kernel == "box";
        let mut scene = default_256(kernel);
        if heavy {
            scene.image.width = 128;
            scene.image.height = 128;
            scene.sweep.slabs = SlabSpec::Count(128);
        }
        let p = Prepared::new(&scene);
        group.throughput(Throughput::Elements(p.updates()));
        let configs: &[(&str, bool)] = if heavy {
            &[("simd", true)]
        } else {
            &[("simd_no_skip", false), ("simd", true)]
        };
        for &(name, skip) in configs {
            group.bench_function(BenchmarkId::new(name, kernel), |b| {
                b.iter(|| p.run(&pool, SweepPath::Simd, skip))
            });
        }
    }
    group.finish();
}

/// One light channel when every transport is grey against three: the same scene with the cloud's
/// transport made grey (1 channel) and left coloured (3 channels).
fn channels(c: &mut Criterion) {
    let mut group = c.benchmark_group("sweep_channels/default_256");
    group.sample_size(10);
    let pool = pool(2);
    let rgb = default_256("ellipse2");
    let mut grey = rgb.clone();
    for m in &mut grey.materials {
        m.transport = [m.transport[0]; 3];
    }
    for (name, scene) in [("3_channels", &rgb), ("1_channel", &grey)] {
        let p = Prepared::new(scene);
        assert_eq!(p.plan.channels, if name == "1_channel" { 1 } else { 3 });
        group.throughput(Throughput::Elements(p.updates()));
        group.bench_function(name, |b| b.iter(|| p.run(&pool, SweepPath::Simd, true)));
    }
    group.finish();
}

/// Clear against dense (underflowing, flushed) fog.
fn flush(c: &mut Criterion) {
    let mut group = c.benchmark_group("sweep_flush/fog_128");
    group.sample_size(10);
    let pool = pool(2);
    for (name, scene) in [
        // Clear: the light stays near 1. Dense: 0.35 per slab → 1e-20 after ~45 slabs, flushed.
        ("clear", fog(0.001, 0.9)),
        ("dense_underflow", fog(0.65, 0.0)),
    ] {
        let p = Prepared::new(&scene);
        group.throughput(Throughput::Elements(p.updates()));
        for (path_name, path) in [("scalar", SweepPath::Scalar), ("simd", SweepPath::Simd)] {
            group.bench_function(BenchmarkId::new(path_name, name), |b| {
                b.iter(|| p.run(&pool, path, true))
            });
        }
    }
    group.finish();
}

// Criterion's own plots are off: with plotters' `ab_glyph` feature (used by the report) they
// panic for want of a font. The numbers are printed and kept in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = paths_and_threads, kernels, channels, flush
}
criterion_main!(benches);
