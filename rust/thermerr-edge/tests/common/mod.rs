//! Shared by the edge's test binaries.

/// A model file y = 2·T_a + 3·T_b + 1 on `inputs` with a sensor-fault guard (limits 0..100,
/// 1 K/s, stuck after 50 s; `hold_s`; 1 s per row) and a fallback without T_b, y = 4·T_a + 1.
pub fn guarded_mlr(inputs: &str, hold_s: f64) -> serde_json::Value {
    let lim = serde_json::json!({"min": 0.0, "max": 100.0, "max_rate": 1.0, "stuck_s": 50.0});
    let mlr = |f: &[&str], c: &[f64]| {
        serde_json::json!({"format_version": 1, "kind": "mlr", "n_features": f.len(),
            "features": f, "target": "E_x", "inputs": inputs,
            "model": {"coef": c, "intercept": 1.0}})
    };
    let mut model = mlr(&["T_a", "T_b"], &[2.0, 3.0]);
    model["guard"] = serde_json::json!({"sensors": [lim, lim], "hold_s": hold_s, "step_s": 1.0,
        "fallbacks": [{"without": "T_b", "model": mlr(&["T_a"], &[4.0])}]});
    model
}
