//! The machine's streaming limit, the roofline the sweep is measured against: a copy between two
//! buffers the size of the default scene's light buffers (2 lights × 3 channels × 512², f32,
//! ping-pong), on 1 and 2 threads, in bytes moved (read + written) per second.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use std::hint::black_box;

/// Floats in one light buffer of the default scene.
const FLOATS: usize = 2 * 3 * 512 * 512;

fn bandwidth(c: &mut Criterion) {
    let mut group = c.benchmark_group("bandwidth/copy_light_buffers");
    group.throughput(Throughput::Bytes(2 * 4 * FLOATS as u64));
    group.sample_size(30);
    let src: Vec<f32> = (0..FLOATS).map(|i| (i % 977) as f32).collect();
    let mut dst = vec![0.0f32; FLOATS];
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        group.bench_function(
            BenchmarkId::new("copy", format!("{threads}_threads")),
            |b| {
                b.iter(|| {
                    pool.install(|| {
                        dst.par_chunks_mut(FLOATS / 64)
                            .zip(src.par_chunks(FLOATS / 64))
                            .for_each(|(d, s)| d.copy_from_slice(s))
                    });
                    black_box(&dst);
                })
            },
        );
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bandwidth
}
criterion_main!(benches);
