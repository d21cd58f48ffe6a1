//! Any text through the model-file reader: a refusal, or a model that writes back to the same
//! model and predicts a few samples (a finite number or Err), never a panic or an absurd
//! allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use thermerr_core::artifact::{Artifact, Predictor};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(a) = Artifact::from_json(text) else {
        return;
    };
    let back = a.to_json().expect("a validated model writes back");
    let again = Artifact::from_json(&back)
        .unwrap_or_else(|e| panic!("written back, it does not load: {e}\n{back}"));
    assert_eq!(a, again, "written back, it loads different");
    let n = a.n_features();
    let mut p = Predictor::new(a);
    for v in [0.0, 1.0, -3.5, 20.0, 1e6] {
        let x = vec![v; n];
        for y in [p.predict_sample(&x), p.predict_sample_measured(&x, Some(v))] {
            if let Ok(y) = y {
                assert!(y.is_finite(), "predicted {y}");
            }
        }
    }
    p.reset();
    let _ = p.predict_sample(&vec![0.0; n]);
    let _ = p.predict_sample(&vec![0.0; n + 1]);
});
