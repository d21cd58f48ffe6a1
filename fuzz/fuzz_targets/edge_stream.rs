//! Arbitrary lines through the edge's streaming filter (the CLI's own line parser) into a
//! predictor loaded from a fixture model: each line is skipped with a reason or predicted,
//! never a panic. The first byte picks the model and whether the header is the model's own
//! feature columns (so that data lines get through) or the input's first line.
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use thermerr_edge::filter::LineFilter;
use thermerr_edge::Predictor;

const MODELS: [&str; 9] = [
    include_str!("../../tests/fixtures/mlr_rise.json"),
    include_str!("../../tests/fixtures/rbf_ols_minmax_rise.json"),
    include_str!("../../tests/fixtures/rbf_exact_ago.json"),
    include_str!("../../tests/fixtures/svr_rise.json"),
    include_str!("../../tests/fixtures/bp_rise.json"),
    include_str!("../../tests/fixtures/greybp_rise.json"),
    include_str!("../../tests/fixtures/gm1n_rise.json"),
    include_str!("../../tests/fixtures/hybrid_rise.json"),
    include_str!("../../tests/fixtures/mlr_guard.json"),
];

fn predictors() -> &'static [Predictor] {
    static P: OnceLock<Vec<Predictor>> = OnceLock::new();
    P.get_or_init(|| {
        MODELS
            .iter()
            .map(|t| Predictor::from_json(t).expect("fixture model loads"))
            .collect()
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let ps = predictors();
    let mut p = ps[pick as usize % ps.len()].clone();
    let text = String::from_utf8_lossy(rest);
    let mut lines = text.split('\n');
    let header = if pick & 0x80 != 0 {
        let f = p.features().expect("fixtures record their features");
        format!("time_s,{}", f.join(","))
    } else {
        match lines.next() {
            Some(h) => h.to_string(),
            None => return,
        }
    };
    let Ok(mut filter) = LineFilter::new(&header, &p) else {
        return;
    };
    // a model with a sensor-fault guard goes through the guarded path, as the CLI runs it
    if let Ok(Some(mut g)) = p.guarded() {
        let mut status = String::new();
        for line in lines {
            if filter.feed_guarded(&mut g, line).is_ok() {
                status.clear();
                let _ = g.write_status(&mut status);
            }
        }
        return;
    }
    for line in lines {
        if let Ok(Some(o)) = filter.feed(&mut p, line) {
            let _ = o.y;
        }
    }
});
