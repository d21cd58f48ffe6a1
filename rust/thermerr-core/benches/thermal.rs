//! Simulation of a 10-node and a 5-node network over 86 400 one-second steps (issue target: < 20 ms), and a
//! calibration of the 5-node VMC-like network on a 20-hour, 1-minute run.

use criterion::{criterion_group, criterion_main, Criterion};
use thermerr_core::run::{NanPolicy, Run};
use thermerr_core::thermal::{simulate, Init, Machine, RunView};

fn chain(n: usize) -> String {
    let mut s = String::from("name = \"chain\"\nambient = \"T_ambient\"\n");
    for i in 0..n {
        s += &format!(
            "[[nodes]]\nname = \"n{i}\"\ncapacity_j_per_k = {}\nambient_w_per_k = {}\n{}\n",
            1000.0 * (i + 1) as f64,
            0.5 + i as f64,
            if i % 2 == 0 {
                format!("sensor = \"T_n{i}\"")
            } else {
                String::new()
            }
        );
    }
    for i in 1..n {
        s += &format!(
            "[[links]]\nbetween = [\"n{}\", \"n{i}\"]\nw_per_k = 3.0\n",
            i - 1
        );
    }
    s += "[[sources]]\nnode = \"n0\"\ninput = \"U_rpm\"\nw = 80.0\nref = 6000.0\nexponent = 1.4\n";
    let terms: Vec<String> = [(0, 1.0), (3, 2.0), (6, -0.5)]
        .iter()
        .filter(|(i, _)| *i < n)
        .map(|(i, v)| format!("n{i} = {v:?}"))
        .collect();
    s += &format!(
        "[[drift]]\naxis = \"E_z\"\num_per_k = {{ {} }}\n",
        terms.join(", ")
    );
    s
}

fn run(n_nodes: usize, steps: usize) -> Run {
    let t: Vec<f64> = (0..steps).map(|k| k as f64).collect();
    let rpm: Vec<f64> = (0..steps)
        .map(|k| [3000.0, 6000.0, 4500.0, 0.0][(k / 7200) % 4])
        .collect();
    let amb: Vec<f64> = t
        .iter()
        .map(|v| 20.0 + (v / 86400.0 * std::f64::consts::TAU).sin())
        .collect();
    let mut names = vec![
        "time_s".to_string(),
        "U_rpm".into(),
        "T_ambient".into(),
        "E_z".into(),
    ];
    let mut cols = vec![t, rpm, amb, vec![0.0; steps]];
    for i in (0..n_nodes).step_by(2) {
        names.push(format!("T_n{i}"));
        cols.push(vec![20.0; steps]);
    }
    Run::from_columns("<bench>", names, cols, NanPolicy::Error, None).unwrap()
}

fn bench(c: &mut Criterion) {
    let m = Machine::from_toml(&chain(10), "chain.toml").unwrap();
    let r = run(10, 86_400);
    c.bench_function("simulate 10 nodes x 86400 steps", |b| {
        b.iter(|| simulate(&m, &RunView::new(&r), &Init::FirstReading).unwrap())
    });
    // the size of an identified network (5 nodes; the march unrolled for it)
    let m5 = Machine::from_toml(&chain(5), "chain5.toml").unwrap();
    let r5 = run(5, 86_400);
    c.bench_function("simulate 5 nodes x 86400 steps", |b| {
        b.iter(|| simulate(&m5, &RunView::new(&r5), &Init::FirstReading).unwrap())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
