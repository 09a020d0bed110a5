//! Sweep throughput (pixel·slab·light updates per second) of the scalar path, and the flush:
//! a medium dense enough to drive the light below f32's normal range must not run slower than a
//! clear one (without the flush, subnormal arithmetic would slow every gather).

use std::path::Path;

use convshadow::common::geometry::SceneGeometry;
use convshadow::common::plan::RenderPlan;
use convshadow::common::scene::Scene;
use convshadow::cpu::ldi::Ldi;
use convshadow::cpu::sweep::{SweepOptions, sweep};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

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

fn bench_scene(c: &mut Criterion, name: &str, scene: &Scene) {
    let g = SceneGeometry::build(scene).expect("geometry");
    let ldi = Ldi::build(&g.raster, u64::MAX).expect("ldi");
    let plan = RenderPlan::new(scene, &g).expect("plan");
    let updates = u64::from(plan.grid_width * plan.grid_height * plan.slabs) * plan.lights.len() as u64;
    let mut group = c.benchmark_group("sweep_scalar");
    group.throughput(Throughput::Elements(updates));
    group.sample_size(10);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        group.bench_function(format!("{name}/{threads}_threads"), |b| {
            b.iter(|| pool.install(|| sweep(&plan, &g.raster, &ldi, &SweepOptions::default()).expect("sweep")))
        });
    }
    group.finish();
}

fn sweeps(c: &mut Criterion) {
    // Clear: the light stays near 1. Dense: 0.35 per slab → 1e-20 after ~45 slabs, flushed to 0.
    bench_scene(c, "fog_clear", &fog(0.001, 0.9));
    bench_scene(c, "fog_dense_underflow", &fog(0.65, 0.0));
    let mut default = Scene::default_scene();
    default.image.width = 128;
    default.image.height = 128;
    default.sweep.slabs = convshadow::common::scene::SlabSpec::Count(128);
    bench_scene(c, "default_128", &default);
}

// Criterion's own plots are off: with plotters' `ab_glyph` feature (used by the report) they
// panic for want of a font (DESIGN §6). The numbers are printed and kept in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = sweeps
}
criterion_main!(benches);
