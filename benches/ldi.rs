//! LDI build throughput on `../shared/models/bunny_hr.obj` at 512² (an icosphere when the models
//! folder is missing), reported in fragments per second.

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::cpu::ldi::{BuildLdi, Ldi};
use convshadow::io::obj::load_obj;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn scene() -> Scene {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models");
    let bunny = models.join("bunny_hr.obj");
    let mesh = if bunny.is_file() && load_obj(&bunny).is_ok() {
        format!(
            "shape = \"obj\"\npath = \"{}\"\nscale = 6.0",
            bunny.display()
        )
    } else {
        eprintln!(
            "note: ../shared/models/bunny_hr.obj not found; benchmarking an icosphere instead"
        );
        "shape = \"sphere\"\nsize = [0.4, 6]".to_string()
    };
    let text = format!(
        "[image]\nwidth = 512\nheight = 512\n[camera]\ndirection = [0.3, -0.2, 1.0]\ncenter = [-0.1, 0.6, 0.0]\nview_width = 1.2\n\
         [sweep]\nslabs = 64\noptimal_distance = 0.5\n[[mesh]]\n{mesh}\nmaterial = \"m\"\n[material.m]\n"
    );
    Scene::parse(&text, "bench", Path::new(".")).expect("bench scene")
}

fn ldi_build(c: &mut Criterion) {
    let scene = scene();
    let g = convshadow_io::build_geometry(&scene).expect("geometry");
    let fragments = Ldi::build(&g.raster, u64::MAX)
        .expect("ldi")
        .stats()
        .fragments;
    let mut group = c.benchmark_group("ldi_build_512");
    group.throughput(Throughput::Elements(fragments));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        group.bench_function(format!("{threads}_threads"), |b| {
            b.iter(|| pool.install(|| Ldi::build(&g.raster, u64::MAX).expect("ldi")))
        });
    }
    group.finish();
}

// Criterion's own plots are off: with plotters' `ab_glyph` feature (used by the report) they
// panic for want of a font. The numbers are printed and kept in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = ldi_build
}
criterion_main!(benches);
