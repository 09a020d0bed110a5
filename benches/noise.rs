//! Detail-function evaluations per second: fBm (4 octaves) and turbulence (5 octaves) of 3D
//! improved Perlin noise, scalar against 8 lanes (the two give the same bits).

use convshadow::common::model::scene::DetailKind;
use convshadow::common::pixel::noise::Detail;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use wide::f32x8;

/// Points spread over a few noise periods.
const POINTS: usize = 4096;

fn noise(c: &mut Criterion) {
    let mut group = c.benchmark_group("noise");
    group.throughput(Throughput::Elements(POINTS as u64));
    let xs: Vec<f32> = (0..POINTS).map(|i| i as f32 * 0.0137 - 3.1).collect();
    for (name, detail) in [
        ("fbm4", Detail::new(DetailKind::Fbm, 3.0, 4, 2.0, 0.5, None)),
        (
            "turbulence5",
            Detail::new(DetailKind::Turbulence, 2.5, 5, 2.0, 0.5, None),
        ),
    ] {
        group.bench_function(BenchmarkId::new("scalar", name), |b| {
            b.iter(|| {
                let mut s = 0.0f32;
                for &x in &xs {
                    s += detail.eval([x, 0.5 * x + 0.25, 0.75 - x]);
                }
                black_box(s)
            })
        });
        group.bench_function(BenchmarkId::new("simd8", name), |b| {
            b.iter(|| {
                let mut s = f32x8::ZERO;
                for x in xs.chunks_exact(8) {
                    let x = f32x8::new(x.try_into().expect("8"));
                    s += detail.eval([
                        x,
                        f32x8::splat(0.5) * x + f32x8::splat(0.25),
                        f32x8::splat(0.75) - x,
                    ]);
                }
                black_box(s)
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = noise
}
criterion_main!(benches);
