//! Fuzzy c-means fit time per problem size (objects × features), 4 clusters, 20 iterations.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermerr_core::fcm::FcmParams;
use thermerr_core::Samples;

fn data(n: usize, d: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    (0..n * d)
        .map(|k| (k / d % 4) as f64 * 0.5 + rng.random::<f64>())
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("fcm_fit_20_iter");
    group.sample_size(10);
    for (n, d) in [(20, 500), (200, 5000), (2000, 20000)] {
        let x = data(n, d);
        // tol tiny so every size runs exactly max_iter iterations
        let p = FcmParams::new(4)
            .seed(Some(1))
            .tol(1e-300)
            .max_iter(20)
            .check()
            .unwrap();
        group.bench_with_input(
            BenchmarkId::from_parameter(format!("{n}x{d}")),
            &x,
            |b, x| {
                let s = Samples::new(x, n, d).unwrap();
                b.iter(|| p.fit(s).unwrap())
            },
        );
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
