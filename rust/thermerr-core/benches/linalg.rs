//! The calibration's JᵀJ (a Jacobian of 11 670 residuals × 25 parameters, the real run of issue
//! 15 on its 5-node identified network): `linalg::gram` (a fixed order of operations, the same
//! bits on every CPU) side by side with faer's matrix product (CPU-dispatched kernels), and
//! exp / pow from the `libm` crate (`portable`) against the C library's.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use thermerr_core::linalg::gram;
use thermerr_core::portable;

fn jacobian(m: usize, n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|j| {
            (0..m)
                .map(|i| (((i * 7919 + j * 104_729) % 1009) as f64 / 97.0 - 5.0) * 1e-3)
                .collect()
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let (m, n) = (11_670, 25);
    let cols = jacobian(m, n);
    let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    let jac = faer::Mat::from_fn(m, n, |i, j| cols[j][i]);
    let mut g = c.benchmark_group("JtJ 11670 x 25");
    g.bench_function("linalg::gram (fixed order)", |b| {
        b.iter(|| gram(black_box(&refs), m).unwrap())
    });
    g.bench_function("faer (CPU-dispatched)", |b| {
        b.iter(|| black_box(&jac).transpose() * black_box(&jac))
    });
    g.finish();

    let xs: Vec<f64> = (0..10_000).map(|k| -20.0 + k as f64 * 4e-3).collect();
    let mut g = c.benchmark_group("10 000 calls");
    g.bench_function("exp: portable (libm crate)", |b| {
        b.iter(|| xs.iter().map(|&x| portable::exp(black_box(x))).sum::<f64>())
    });
    g.bench_function("exp: C library", |b| {
        b.iter(|| xs.iter().map(|&x| black_box(x).exp()).sum::<f64>())
    });
    g.bench_function("pow: portable (libm crate)", |b| {
        b.iter(|| {
            xs.iter()
                .map(|&x| portable::powf(black_box(x) + 21.0, 1.37))
                .sum::<f64>()
        })
    });
    g.bench_function("pow: C library", |b| {
        b.iter(|| {
            xs.iter()
                .map(|&x| (black_box(x) + 21.0).powf(1.37))
                .sum::<f64>()
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = bench
}
criterion_main!(benches);
