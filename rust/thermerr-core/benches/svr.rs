//! ε-SVR: SMO fit at seed 004's size (60 × 4) and at 2000 × 10, and per-sample prediction with
//! ~50 support vectors (the edge's hot path).

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use thermerr_core::svr::{Gamma, SvrParams};
use thermerr_core::Samples;

/// Deterministic pseudo-random data (no rand dependency in the bench).
fn data(n: usize, d: usize) -> (Vec<f64>, Vec<f64>) {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut u = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let x: Vec<f64> = (0..n * d).map(|_| u()).collect();
    let y = x
        .chunks(d)
        .map(|r| r[0].sin() + 0.5 * r[1] * r[1] - r[2] * r[3] + 0.1 * u())
        .collect();
    (x, y)
}

fn bench(c: &mut Criterion) {
    for (n, d, cc) in [(60usize, 4usize, 7.3465), (2000, 10, 10.0)] {
        let (x, y) = data(n, d);
        let s = Samples::new(&x, n, d).unwrap();
        let p = SvrParams::new()
            .c(cc)
            .epsilon(0.05)
            .gamma(Gamma::Value(1.0 / d as f64))
            .check()
            .unwrap();
        let mut g = c.benchmark_group(format!("svr_fit_{n}x{d}"));
        if n > 1000 {
            g.sample_size(10);
        }
        g.bench_function("smo", |b| b.iter(|| p.fit(black_box(s), &y).unwrap()));
        g.finish();
    }
    let (x, y) = data(60, 4);
    let m = SvrParams::new()
        .c(7.3465)
        .epsilon(0.01)
        .gamma(Gamma::Value(0.5))
        .check()
        .unwrap()
        .fit(Samples::new(&x, 60, 4).unwrap(), &y)
        .unwrap();
    let q = [0.1, -0.2, 0.3, 0.05];
    c.bench_function(
        &format!("svr_predict_one_{}sv_4f", m.dual_coef.len()),
        |b| b.iter(|| m.predict_one(black_box(&q))),
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
