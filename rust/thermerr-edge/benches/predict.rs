//! Per-sample latency of the edge predictor at seed sizes: MLR (4 features), RBF (50 centres ×
//! 4 features), SVR (50 support vectors × 4 features), with and without stateful preprocessing.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use thermerr_edge::Predictor;

fn matrix(r: usize, c: usize, seed: u64) -> String {
    let mut s = seed;
    let vals: Vec<String> = (0..r * c)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            format!("{}", (s >> 11) as f64 / (1u64 << 53) as f64)
        })
        .collect();
    format!("{{\"shape\": [{r}, {c}], \"data\": [{}]}}", vals.join(","))
}

fn envelope(kind: &str, model: String, pre: &str, inputs: &str) -> String {
    format!(
        "{{\"format_version\": 1, \"kind\": \"{kind}\", \"params\": {{}}, \"n_features\": 4, \
         \"features\": [\"T_a\", \"T_b\", \"T_c\", \"T_d\"], \"target\": \"E_z\", \"inputs\": \"{inputs}\", \
         \"preprocessing\": {pre}, \"model\": {model}}}"
    )
}

fn bench(c: &mut Criterion) {
    let w50: Vec<String> = (0..50)
        .map(|k| format!("{}", (k as f64 * 0.37).sin()))
        .collect();
    let w50 = w50.join(",");
    let models = [
        (
            "mlr",
            envelope("mlr", "{\"coef\": [0.7, 1.0, 0.1, -0.3], \"intercept\": 0.02}".into(), "null", "absolute"),
        ),
        (
            "rbf_50",
            envelope(
                "rbf",
                format!("{{\"centers\": {}, \"spread\": 0.8, \"weights\": [{w50}], \"bias\": 0.1, \"selected\": [], \"sse_history\": []}}", matrix(50, 4, 1)),
                "null",
                "absolute",
            ),
        ),
        (
            "svr_50",
            envelope(
                "svr",
                format!("{{\"kernel\": {{\"type\": \"rbf\", \"gamma\": 0.5}}, \"support_vectors\": {}, \"dual_coef\": [{w50}], \"intercept\": 0.3}}", matrix(50, 4, 2)),
                "null",
                "absolute",
            ),
        ),
        (
            "rbf_50_minmax_ago_rise",
            envelope(
                "rbf",
                format!("{{\"centers\": {}, \"spread\": 0.8, \"weights\": [{w50}], \"bias\": 0.1, \"selected\": [], \"sse_history\": []}}", matrix(50, 4, 3)),
                "{\"kind\": \"minmax_ago\", \"x_min\": [0,0,0,0], \"x_max\": [1,1,1,1], \"y_min\": 0, \"y_max\": 10}",
                "rise",
            ),
        ),
    ];
    let x = [0.31, 0.52, 0.13, 0.74];
    for (name, text) in models {
        let mut p = Predictor::from_json(&text).expect("bench model");
        c.bench_function(&format!("edge_predict_sample_{name}"), |b| {
            b.iter(|| p.predict_sample(black_box(&x)).unwrap())
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
