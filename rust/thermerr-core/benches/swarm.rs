//! CSO and PSO on Rastrigin d = 2, population 20 × 100 generations (2 020 evaluations), through
//! the rayon entry points and through the batch entry points with a serial evaluation.

use criterion::{criterion_group, criterion_main, Criterion};
use thermerr_core::swarm::{
    cso_minimize, cso_minimize_batch, pso_minimize, pso_minimize_batch, Bounds, CsoParams,
    PsoParams,
};
use thermerr_core::Result;

fn rastrigin(x: &[f64]) -> f64 {
    10.0 * x.len() as f64
        + x.iter()
            .map(|v| v * v - 10.0 * (std::f64::consts::TAU * v).cos())
            .sum::<f64>()
}

fn serial(pop: &[Vec<f64>]) -> Result<Vec<f64>> {
    Ok(pop.iter().map(|x| rastrigin(x)).collect())
}

fn bench(c: &mut Criterion) {
    let b = Bounds::uniform(2, -5.12, 5.12);
    let cp = CsoParams {
        pop: 20,
        iters: 100,
        seed: 1,
        ..CsoParams::default()
    };
    let pp = PsoParams {
        pop: 20,
        iters: 100,
        seed: 1,
        ..PsoParams::default()
    };
    let mut group = c.benchmark_group("swarm_rastrigin2_20x100");
    group.bench_function("cso_rayon", |bch| {
        bch.iter(|| cso_minimize(rastrigin, &b, &cp).unwrap())
    });
    group.bench_function("cso_batch_serial", |bch| {
        bch.iter(|| cso_minimize_batch(serial, &b, &cp).unwrap())
    });
    group.bench_function("pso_rayon", |bch| {
        bch.iter(|| pso_minimize(rastrigin, &b, &pp).unwrap())
    });
    group.bench_function("pso_batch_serial", |bch| {
        bch.iter(|| pso_minimize_batch(serial, &b, &pp).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
