use std::path::PathBuf;

use serde_json::{json, Value};

use super::*;

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures")
}

const FIXTURES: [&str; 8] = [
    "mlr_rise",
    "rbf_ols_minmax_rise",
    "rbf_exact_ago",
    "svr_rise",
    "bp_rise",
    "greybp_rise",
    "gm1n_rise",
    "hybrid_rise",
];

fn fixture(name: &str) -> String {
    std::fs::read_to_string(fixtures().join(format!("{name}.json"))).unwrap()
}

#[test]
fn every_fixture_reads_writes_and_reads_back_the_same() {
    for name in FIXTURES {
        let a = Artifact::from_json(&fixture(name)).unwrap();
        let text = a.to_json().unwrap();
        let b = Artifact::from_json(&text).unwrap();
        assert_eq!(a, b, "{name}");
        let v: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["format_version"], json!(FORMAT_VERSION), "{name}");
        assert_eq!(v["kind"], json!(a.model.kind()), "{name}");
    }
}

#[test]
fn a_clustering_file_is_named_as_such() {
    let e = Model::from_value("fcm", json!({})).unwrap_err().to_string();
    assert!(e.contains("sensor clustering"), "{e}");
}

#[test]
fn inconsistent_models_are_refused_with_the_part_named() {
    let cases: [(&str, &str, Value, &str); 8] = [
        (
            "rbf_ols_minmax_rise",
            "/model/weights",
            json!([1.0]),
            "weights for",
        ),
        ("rbf_ols_minmax_rise", "/model/spread", json!(0.0), "spread"),
        (
            "svr_rise",
            "/model/dual_coef",
            json!([0.5]),
            "dual coefficients",
        ),
        ("svr_rise", "/model/kernel/gamma", json!(0.0), "gamma"),
        ("bp_rise", "/model/net/sizes", json!([4, 6, 1]), "layer"),
        (
            "greybp_rise",
            "/model/windows",
            json!([1_000_000_000u64, 8, 10]),
            "values per run",
        ),
        (
            "hybrid_rise",
            "/model/ma_lags",
            json!(1u64 << 40),
            "values per run",
        ),
        (
            "mlr_rise",
            "/model/coef",
            json!([1.0, 2.0, 3.0, "1"]),
            "expected",
        ),
    ];
    for (name, path, value, msg) in cases {
        let mut v: Value = serde_json::from_str(&fixture(name)).unwrap();
        *v.pointer_mut(path).unwrap() = value;
        let e = match Artifact::from_json(&v.to_string()) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("{name} {path}: accepted"),
        };
        assert!(e.contains(msg), "{name} {path}: {e}");
    }
}

#[test]
fn a_number_that_overflows_is_refused() {
    let v: Value = serde_json::from_str(&fixture("mlr_rise")).unwrap();
    let text = v
        .to_string()
        .replacen("\"intercept\":", "\"intercept\":1e999,\"x\":", 1);
    assert!(Artifact::from_json(&text).is_err());
}

#[test]
fn non_finite_models_are_not_written() {
    let mut a = Artifact::from_json(&fixture("mlr_rise")).unwrap();
    if let Model::Mlr(m) = &mut a.model {
        m.intercept = f64::NAN;
    }
    let e = a.to_json().unwrap_err().to_string();
    assert!(e.contains("not a finite number"), "{e}");
}

#[test]
fn a_constant_column_scales_to_the_middle_everywhere() {
    let x = [1.0, 5.0, 2.0, 5.0, 3.0, 5.0];
    let p = Preprocessing::fit("minmax", &x, 2, &[]).unwrap();
    let t = p.transform(&x, 2).unwrap();
    assert_eq!(t, vec![0.0, 0.5, 0.5, 0.5, 1.0, 0.5]);
    let mut row = [2.0, 7.0];
    p.scale_row(&mut row);
    assert_eq!(row, [0.5, 0.5]);
}

#[test]
fn batch_ago_equals_the_stream() {
    let x = [1.0, 10.0, 2.0, 30.0, 4.0, 20.0];
    let y = [0.0, 1.0, 3.0];
    let p = Preprocessing::fit("minmax_ago", &x, 2, &y).unwrap();
    let t = p.transform(&x, 2).unwrap();
    let mut acc = [0.0; 2];
    for (i, row) in x.chunks(2).enumerate() {
        let mut r = [row[0], row[1]];
        p.scale_row(&mut r);
        for j in 0..2 {
            acc[j] += r[j];
            assert_eq!(t[2 * i + j], acc[j]);
        }
    }
    // the target round-trips through its accumulation
    let back = p.inverse(&p.transform_target(&y));
    for (a, b) in back.iter().zip(&y) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
}

/// Deterministic mutations of a JSON document: every leaf and array is replaced, shortened,
/// lengthened or retyped, one at a time.
fn mutations(v: &Value) -> Vec<Value> {
    let mut paths = Vec::new();
    collect(v, String::new(), &mut paths);
    let mut out = Vec::new();
    for p in &paths {
        let here = v.pointer(p).unwrap().clone();
        let mut replacements = vec![
            json!(null),
            json!("x"),
            json!(-1),
            json!(0),
            json!(1_000_000_000u64),
            json!(1e300),
        ];
        if let Value::Array(a) = &here {
            let mut shorter = a.clone();
            shorter.pop();
            let mut longer = a.clone();
            longer.push(a.first().cloned().unwrap_or(json!(1.0)));
            replacements.extend([json!(shorter), json!(longer), json!([])]);
        }
        for r in replacements {
            let mut m = v.clone();
            *m.pointer_mut(p).unwrap() = r;
            out.push(m);
        }
        if let Some((parent, key)) = p.rsplit_once('/') {
            let mut m = v.clone();
            if let Some(Value::Object(o)) = m.pointer_mut(parent) {
                o.remove(key);
                out.push(m);
            }
        }
    }
    out
}

fn collect(v: &Value, path: String, out: &mut Vec<String>) {
    match v {
        Value::Object(o) => {
            for (k, x) in o {
                let p = format!("{path}/{k}");
                out.push(p.clone());
                collect(x, p, out);
            }
        }
        Value::Array(a) if a.len() <= 4 || a.iter().all(|x| !x.is_number()) => {
            for (i, x) in a.iter().enumerate() {
                let p = format!("{path}/{i}");
                out.push(p.clone());
                collect(x, p, out);
            }
        }
        // long numeric arrays: the first and last entries stand for the rest
        Value::Array(a) => {
            for i in [0, a.len() - 1] {
                out.push(format!("{path}/{i}"));
            }
        }
        _ => {}
    }
}

#[test]
fn mutated_model_files_never_panic() {
    let mut n_files = 0;
    let mut n_loaded = 0;
    for name in FIXTURES {
        let v: Value = serde_json::from_str(&fixture(name)).unwrap();
        for m in mutations(&v) {
            n_files += 1;
            let Ok(mut p) = Predictor::from_json(&m.to_string()) else {
                continue;
            };
            n_loaded += 1;
            let d = p.n_features();
            for x in [vec![20.0; d], vec![0.0; d], vec![1e6; d], vec![20.0; d + 1]] {
                let _ = p.predict_sample(&x);
            }
            p.reset();
            for (k, e) in [0.0, 1.0, 2.0].into_iter().enumerate() {
                let _ = p.predict_sample_measured(&vec![21.0 + k as f64; d], Some(e));
            }
        }
    }
    assert!(n_files > 500, "only {n_files} mutated files");
    // mutations of values that carry no structure (numbers in range) must still load
    assert!(
        n_loaded > 50,
        "only {n_loaded} of {n_files} mutated files loaded"
    );
}

/// Found by `tests/test_properties.py` (mutated model files): a file whose coefficients are
/// finite but near the f64 limit loaded, and predicted `inf` for every sample, with no error.
/// Every family's batch predict and the streaming predictor refuse a non-finite prediction.
#[test]
fn a_prediction_that_overflows_is_an_error_not_inf() {
    let mut v: Value = serde_json::from_str(&fixture("mlr_rise")).unwrap();
    v["model"]["coef"] = json!([1e308, 1e308, 0.0, 0.0]);
    v["inputs"] = json!("absolute");
    let a = Artifact::from_json(&v.to_string()).unwrap();
    let x = [10.0, 10.0, 0.0, 0.0];
    let Model::Mlr(m) = &a.model else {
        unreachable!()
    };
    let e = m
        .predict(crate::Samples::new(&x, 1, 4).unwrap())
        .unwrap_err();
    assert!(matches!(e, Error::Numerical(_)), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.contains("mlr model") && msg.contains("sample 0") && msg.contains("not a finite"),
        "{msg}"
    );
    let mut p = Predictor::new(a);
    let e = p.predict_sample(&x).unwrap_err().to_string();
    assert!(e.contains("mlr model") && e.contains("not a finite"), "{e}");
    // the same file on small inputs predicts as before
    assert_eq!(p.predict_sample(&[0.0; 4]).unwrap(), -0.551132886101243);

    // kernel models: weights at the limit overflow once several kernels add up
    for name in ["svr_rise", "rbf_ols_minmax_rise"] {
        let mut v: Value = serde_json::from_str(&fixture(name)).unwrap();
        let field = if name.starts_with("svr") {
            "dual_coef"
        } else {
            "weights"
        };
        let w = v["model"][field].as_array().unwrap().len();
        v["model"][field] = json!(vec![1.7e308; w]);
        let mut p = Predictor::new(Artifact::from_json(&v.to_string()).unwrap());
        let mut err = None;
        for k in 0..50 {
            let x = vec![20.0 + k as f64 * 0.1; p.n_features()];
            match p.predict_sample(&x) {
                Ok(y) => assert!(y.is_finite(), "{name}: {y}"),
                Err(e) => err = Some(e.to_string()),
            }
        }
        let e = err.unwrap_or_else(|| panic!("{name}: never overflowed"));
        assert!(e.contains("not a finite"), "{name}: {e}");
    }
}

/// A preprocessing range whose ends are finite but whose width is not (-1e308 to 1e308) is
/// refused at load: it scaled every reading to 0, and its target range overflowed the IAGO.
#[test]
fn a_range_of_infinite_width_is_refused() {
    let mut v: Value = serde_json::from_str(&fixture("rbf_exact_ago")).unwrap();
    v["preprocessing"]["x_min"][0] = json!(-1e308);
    v["preprocessing"]["x_max"][0] = json!(1e308);
    let e = Artifact::from_json(&v.to_string()).unwrap_err().to_string();
    assert!(e.contains("range of feature 0"), "{e}");
    let mut v: Value = serde_json::from_str(&fixture("rbf_exact_ago")).unwrap();
    v["preprocessing"]["y_min"] = json!(-1e308);
    v["preprocessing"]["y_max"] = json!(1e308);
    let e = Artifact::from_json(&v.to_string()).unwrap_err().to_string();
    assert!(e.contains("target range"), "{e}");
}

#[test]
fn a_fixed_rise_reference_replaces_the_first_sample_and_outlives_a_reset() {
    let mut p = Predictor::from_json(&fixture("mlr_rise")).unwrap();
    let n = p.n_inputs();
    let start: Vec<f64> = (0..n).map(|j| 20.0 + j as f64).collect();
    let later: Vec<f64> = start.iter().map(|v| v + 1.5).collect();
    // the stream from the start: its second sample is 1.5 K above the first
    let mut whole = p.clone();
    whole.predict_sample(&start).unwrap();
    let want = whole.predict_sample(&later).unwrap();
    // a stream that starts at the second sample, with the start as its reference
    p.set_reference(&start).unwrap();
    assert_eq!(p.predict_sample(&later).unwrap(), want);
    p.reset();
    assert_eq!(p.predict_sample(&later).unwrap(), want);
    // without one, the first sample is the reference: rises of 0
    let mut own = Predictor::from_json(&fixture("mlr_rise")).unwrap();
    assert_ne!(own.predict_sample(&later).unwrap(), want);
    // wrong count, non-finite reading: errors naming what
    let e = p.set_reference(&start[1..]).unwrap_err().to_string();
    assert!(e.contains(&format!("needs {n} readings")), "{e}");
    let mut bad = start.clone();
    bad[0] = f64::NAN;
    let e = p.set_reference(&bad).unwrap_err().to_string();
    assert!(e.contains("reading 0") && e.contains("not a finite"), "{e}");
}
