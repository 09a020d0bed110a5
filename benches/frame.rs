//! End-to-end frames through the library's render call (scene → geometry → LDI → plan → sweep →
//! image, no file written): the default scene at its full size (512², 512 slabs, 2 lights, fBm
//! detail) and the bunny scene (skipped, loudly, without `../shared/models`).

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{CpuPath, RenderRequest, render};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

fn frames(c: &mut Criterion) {
    let mut group = c.benchmark_group("frame");
    group.sample_size(10);
    let mut scenes = vec![("default", Scene::default_scene())];
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny.toml");
    match convshadow_io::load_scene(&bunny) {
        Ok(s)
            if Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../shared/models")
                .is_dir() =>
        {
            scenes.push(("bunny", s))
        }
        _ => eprintln!("note: ../shared/models missing: the bunny frame is not measured"),
    }
    for (name, scene) in &scenes {
        // The SIMD path only: a scalar frame takes ~20 s here, ten samples of it would dominate the
        // bench run; scalar against SIMD is measured in benches/sweep.rs.
        let request = RenderRequest {
            path: CpuPath::Simd,
            ..RenderRequest::default()
        };
        group.bench_function(BenchmarkId::new(*name, CpuPath::Simd.name()), |b| {
            b.iter(|| render(scene, &request).expect("render"))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = frames
}
criterion_main!(benches);
