use serde_json::json;

use super::*;

/// An MLR model file y = 2·a + 3·b (+ 1) with inputs `inputs`, optionally with a guard.
fn mlr(features: &[&str], coef: &[f64], inputs: &str, guard: Option<Value>) -> Value {
    let mut v = json!({
        "format_version": 1, "kind": "mlr", "n_features": features.len(),
        "features": features, "target": "E_x", "inputs": inputs,
        "model": {"coef": coef, "intercept": 1.0},
    });
    if let Some(g) = guard {
        v["guard"] = g;
    }
    v
}

fn limits() -> Value {
    json!({"min": 0.0, "max": 100.0, "max_rate": 1.0, "stuck_s": 50.0})
}

fn guarded(fallbacks: Value) -> GuardedPredictor {
    let g = json!({"sensors": [limits(), limits()], "hold_s": 10.0, "step_s": 1.0,
                   "fallbacks": fallbacks});
    let text = mlr(&["T_a", "T_b"], &[2.0, 3.0], "absolute", Some(g)).to_string();
    GuardedPredictor::new(Predictor::from_json(&text).unwrap())
        .unwrap()
        .unwrap()
}

fn status(g: &GuardedPredictor) -> String {
    let mut s = String::new();
    g.write_status(&mut s).unwrap();
    s
}

/// A fallback without T_b: y = 4·a + 1.
fn fallback_b() -> Value {
    json!([{"without": "T_b", "model": mlr(&["T_a"], &[4.0], "absolute", None)}])
}

#[test]
fn good_readings_pass_through_unchanged() {
    let mut g = guarded(json!([]));
    for k in 0..20 {
        let (a, b) = (20.0 + 0.1 * k as f64, 30.0);
        let y = g.step(Some(k as f64), &[a, b + 0.01 * k as f64]).unwrap();
        assert_eq!(y, Some(2.0 * a + 3.0 * (b + 0.01 * k as f64) + 1.0));
        assert_eq!(status(&g), "ok");
    }
}

#[test]
fn a_dropout_is_held_then_falls_back_then_recovers() {
    let mut g = guarded(fallback_b());
    assert_eq!(g.step(Some(0.0), &[20.0, 30.0]).unwrap(), Some(131.0));
    // T_b missing for 10 s: held at 30
    for t in 1..=11 {
        let y = g.step(Some(t as f64), &[21.0, f64::NAN]).unwrap();
        assert_eq!(y, Some(2.0 * 21.0 + 3.0 * 30.0 + 1.0), "t = {t}");
        assert_eq!(status(&g), "held:T_b");
    }
    // beyond hold_s (10 s after the fault began at t = 1): the model without T_b
    let y = g.step(Some(12.0), &[21.0, f64::NAN]).unwrap();
    assert_eq!(y, Some(4.0 * 21.0 + 1.0));
    assert_eq!(status(&g), "fallback:T_b");
    // back: the full model again
    let y = g.step(Some(13.0), &[21.0, 30.5]).unwrap();
    assert_eq!(y, Some(2.0 * 21.0 + 3.0 * 30.5 + 1.0));
    assert_eq!(status(&g), "ok");
}

#[test]
fn without_a_fallback_the_last_output_is_frozen() {
    let mut g = guarded(json!([]));
    g.step(Some(0.0), &[20.0, 30.0]).unwrap();
    g.step(Some(1.0), &[20.5, 30.0]).unwrap();
    let before = 2.0 * 20.5 + 3.0 * 30.0 + 1.0;
    for t in 2..30 {
        let y = g
            .step(Some(t as f64), &[20.5 + 0.01 * t as f64, -273.0])
            .unwrap();
        let expect = if t <= 12 {
            2.0 * (20.5 + 0.01 * t as f64) + 3.0 * 30.0 + 1.0 // held T_b, live T_a
        } else {
            before + 0.01 * 12.0 * 2.0 // the last output before the hold ran out
        };
        assert!(
            (y.unwrap() - expect).abs() < 1e-12,
            "t = {t}: {y:?} vs {expect}"
        );
        let want = if t <= 12 { "held:T_b" } else { "frozen:T_b" };
        assert_eq!(status(&g), want, "t = {t}");
    }
}

#[test]
fn spikes_out_of_range_and_too_fast_are_held() {
    let mut g = guarded(json!([]));
    g.step(Some(0.0), &[20.0, 30.0]).unwrap();
    // out of range (open thermocouple)
    assert_eq!(g.step(Some(1.0), &[1372.0, 30.0]).unwrap(), Some(131.0));
    assert_eq!(status(&g), "held:T_a");
    // in range but 10 units in 1 s (max_rate 1 /s)
    assert_eq!(g.step(Some(2.0), &[20.0, 40.0]).unwrap(), Some(131.0));
    assert_eq!(status(&g), "held:T_b");
    // a slow change passes: 2 units over the 3 s since the last good T_b
    assert_eq!(g.step(Some(3.0), &[20.0, 32.0]).unwrap(), Some(137.0));
    assert_eq!(status(&g), "ok");
}

#[test]
fn a_stuck_sensor_is_detected_after_stuck_s() {
    let mut g = guarded(fallback_b());
    for t in 0..=50 {
        g.step(Some(t as f64), &[20.0 + 0.01 * t as f64, 30.0])
            .unwrap();
        assert_eq!(status(&g), "ok", "t = {t}");
    }
    g.step(Some(51.0), &[20.51, 30.0]).unwrap();
    assert_eq!(status(&g), "held:T_b");
    g.step(Some(62.0), &[20.62, 30.0]).unwrap();
    assert_eq!(status(&g), "fallback:T_b");
    g.step(Some(63.0), &[20.63, 30.1]).unwrap();
    assert_eq!(status(&g), "ok");
}

#[test]
fn two_sensors_out_freeze_and_nothing_is_predicted_before_a_first_good_reading() {
    let mut g = guarded(fallback_b());
    assert_eq!(g.step(Some(0.0), &[f64::NAN, 30.0]).unwrap(), None);
    assert_eq!(status(&g), "waiting:T_a");
    let y0 = g.step(Some(1.0), &[20.0, 30.0]).unwrap().unwrap();
    for t in 2..40 {
        g.step(Some(t as f64), &[f64::NAN, f64::NAN]).unwrap();
    }
    assert_eq!(status(&g), "frozen:T_a;frozen:T_b");
    assert_eq!(g.step(Some(40.0), &[f64::NAN, f64::NAN]).unwrap(), Some(y0));
}

#[test]
fn a_sensor_dead_from_the_start_gives_way_to_its_fallback_after_hold_s() {
    let mut g = guarded(fallback_b());
    // T_b never reads: waiting through hold_s (10 s from the first row), then its fallback
    for t in 0..=10 {
        assert_eq!(
            g.step(Some(t as f64), &[20.0, f64::NAN]).unwrap(),
            None,
            "t = {t}"
        );
        assert_eq!(status(&g), "waiting:T_b");
    }
    assert_eq!(
        g.step(Some(11.0), &[20.5, f64::NAN]).unwrap(),
        Some(4.0 * 20.5 + 1.0)
    );
    assert_eq!(status(&g), "fallback:T_b");
    // it comes alive: the full model from then on
    assert_eq!(
        g.step(Some(12.0), &[20.5, 30.0]).unwrap(),
        Some(2.0 * 20.5 + 3.0 * 30.0 + 1.0)
    );
    assert_eq!(status(&g), "ok");
    // dead from the start without a fallback, or next to another sensor out: nothing to predict
    let mut g = guarded(json!([]));
    for t in 0..30 {
        assert_eq!(g.step(Some(t as f64), &[20.0, f64::NAN]).unwrap(), None);
    }
    assert_eq!(status(&g), "waiting:T_b");
    let mut g = guarded(fallback_b());
    for t in 0..30 {
        assert_eq!(g.step(Some(t as f64), &[f64::NAN, f64::NAN]).unwrap(), None);
    }
    assert_eq!(status(&g), "waiting:T_a;waiting:T_b");
}

#[test]
fn rows_without_times_use_step_s() {
    let mut a = guarded(json!([]));
    let mut b = guarded(json!([]));
    let rows = [[20.0, 30.0], [f64::NAN, 30.0], [20.0, 30.0]];
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(a.step(None, r).unwrap(), b.step(Some(k as f64), r).unwrap());
        assert_eq!(status(&a), status(&b));
    }
}

#[test]
fn a_rise_model_falls_back_from_the_same_baseline() {
    let g = json!({"sensors": [limits(), limits()], "hold_s": 0.0, "step_s": 1.0,
                   "fallbacks": [{"without": "T_b",
                                  "model": mlr(&["T_a"], &[4.0], "rise", None)}]});
    let text = mlr(&["T_a", "T_b"], &[2.0, 3.0], "rise", Some(g)).to_string();
    let mut p = GuardedPredictor::new(Predictor::from_json(&text).unwrap())
        .unwrap()
        .unwrap();
    assert_eq!(p.step(Some(0.0), &[20.0, 30.0]).unwrap(), Some(1.0));
    p.step(Some(1.0), &[21.0, f64::NAN]).unwrap(); // held (hold_s 0: fault begins now)
    let y = p.step(Some(2.0), &[22.0, f64::NAN]).unwrap();
    assert_eq!(status(&p), "fallback:T_b");
    assert_eq!(y, Some(4.0 * (22.0 - 20.0) + 1.0));
}

#[test]
fn limits_from_training_follow_the_documented_rules() {
    // T_a: 20..24 rising 0.5 per 10 s step; T_b constant for the whole run
    let n = 9;
    let x: Vec<f64> = (0..n).flat_map(|i| [20.0 + 0.5 * i as f64, 30.0]).collect();
    let t: Vec<f64> = (0..n).map(|i| 10.0 * i as f64).collect();
    let g = Guard::from_training(&x, 2, Some(&t), 60.0).unwrap();
    assert_eq!(g.step_s, 10.0);
    assert_eq!(g.hold_s, 60.0);
    let a = &g.sensors[0];
    assert_eq!((a.min, a.max), (20.0 - 20.0, 24.0 + 20.0)); // span 4 < floor 20
    assert!((a.max_rate - 5.0 * 0.05).abs() < 1e-12);
    assert_eq!(a.stuck_s, STUCK_FLOOR_S);
    let b = &g.sensors[1];
    assert_eq!((b.min, b.max), (10.0, 50.0));
    assert_eq!(b.max_rate, RATE_FLOOR);
    assert_eq!(b.stuck_s, STUCK_FLOOR_S.max(2.0 * 80.0));
    let e = Guard::from_training(&[1.0, f64::NAN, 2.0, 3.0], 2, None, 1.0).unwrap_err();
    assert!(e.to_string().contains("row 0, feature 1"), "{e}");
}

#[test]
fn bad_guards_are_refused_naming_the_part() {
    let cases = [
        (
            json!({"sensors": [limits()], "hold_s": 1.0, "step_s": 1.0}),
            "1 sensor limits for 2",
        ),
        (
            json!({"sensors": [limits(), {"min": 5.0, "max": 1.0, "max_rate": 1.0, "stuck_s": 1.0}],
                   "hold_s": 1.0, "step_s": 1.0}),
            "limits of T_b",
        ),
        (
            json!({"sensors": [limits(), limits()], "hold_s": -1.0, "step_s": 1.0}),
            "hold_s",
        ),
        (
            json!({"sensors": [limits(), limits()], "hold_s": 1.0, "step_s": 1.0,
                   "fallbacks": [{"without": "T_c", "model": mlr(&["T_a"], &[1.0], "absolute", None)}]}),
            "no feature \"T_c\"",
        ),
        (
            json!({"sensors": [limits(), limits()], "hold_s": 1.0, "step_s": 1.0,
                   "fallbacks": [{"without": "T_b", "model": mlr(&["T_b"], &[1.0], "absolute", None)}]}),
            "expected the model's features without it",
        ),
        (
            json!({"sensors": [limits(), limits()], "hold_s": 1.0, "step_s": 1.0,
                   "fallbacks": [{"without": "T_b", "model": mlr(&["T_a"], &[1.0], "rise", None)}]}),
            "from rise inputs",
        ),
        (
            json!({"sensors": [limits(), limits()], "hold_s": 1.0, "step_s": 1.0, "extra": 1}),
            "unknown field",
        ),
    ];
    for (g, want) in cases {
        let text = mlr(&["T_a", "T_b"], &[2.0, 3.0], "absolute", Some(g)).to_string();
        let e = Artifact::from_json(&text).unwrap_err().to_string();
        assert!(e.contains("guard") && e.contains(want), "{want}: {e}");
    }
}

#[test]
fn a_guard_survives_a_write_and_read() {
    let text = mlr(
        &["T_a", "T_b"],
        &[2.0, 3.0],
        "absolute",
        Some(
            json!({"sensors": [limits(), limits()], "hold_s": 10.0, "step_s": 1.0,
                    "fallbacks": fallback_b()}),
        ),
    )
    .to_string();
    let a = Artifact::from_json(&text).unwrap();
    let b = Artifact::from_json(&a.to_json().unwrap()).unwrap();
    assert_eq!(a, b);
    assert_eq!(b.header.guard.unwrap().fallbacks.len(), 1);
    // a file without a guard is written without the key
    let plain = Artifact::from_json(&mlr(&["T_a"], &[1.0], "absolute", None).to_string()).unwrap();
    assert!(!plain.to_json().unwrap().contains("guard"));
}

#[test]
fn long_training_repeats_are_reported_with_their_rows() {
    // feature 0 changes every row; feature 1 holds one value over rows 3..=12 (rows 60 s apart:
    // 540 s, under half the floor, not reported) and then 20..=60 (2 400 s: reported)
    let n = 80;
    let t: Vec<f64> = (0..n).map(|i| 60.0 * i as f64).collect();
    let mut x = Vec::with_capacity(2 * n);
    for i in 0..n {
        let held = (3..=12).contains(&i) || (20..=60).contains(&i);
        x.push(20.0 + 0.01 * i as f64);
        x.push(if held {
            if i <= 12 {
                21.0
            } else {
                22.0
            }
        } else {
            20.0 + 0.013 * i as f64
        });
    }
    let (g, r) = Guard::from_training_with_repeats(&x, 2, Some(&t), 60.0).unwrap();
    assert_eq!(
        r,
        vec![LongRepeat {
            feature: 1,
            from_row: 20,
            seconds: 2400.0
        }]
    );
    assert_eq!(g.sensors[1].stuck_s, 4800.0);
    assert_eq!(g, Guard::from_training(&x, 2, Some(&t), 60.0).unwrap());
}

/// A warming column sampled every 15 s (a slow rise and a small deterministic wobble, never
/// repeating a value), 4 h long.
fn warming(n: usize) -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..n).map(|i| 15.0 * i as f64).collect();
    let y = t
        .iter()
        .enumerate()
        .map(|(i, s)| {
            20.0 + 5.0 * (1.0 - (-s / 3600.0).exp()) + 0.02 * ((i * 7919 % 13) as f64 / 13.0)
        })
        .collect();
    (t, y)
}

#[test]
fn a_clean_column_is_not_suspect() {
    let (t, y) = warming(960);
    assert!(suspect_readings("run.csv", &["T_a"], &[&y], &t).is_empty());
}

#[test]
fn a_spike_is_a_jump_at_its_row() {
    let (t, mut y) = warming(960);
    y[500] += 60.0; // an open thermocouple for one reading: in at row 501, out at row 502
    let s = suspect_readings("run.csv", &["T_a"], &[&y], &t);
    assert_eq!(s.len(), 1, "{s:?}");
    assert_eq!(
        (s[0].kind, s[0].row, s[0].count),
        (SuspectKind::Jump, 501, 2)
    );
    assert!((s[0].size - 60.0).abs() < 0.1, "{}", s[0].size);
    assert!(
        s[0].text.starts_with("run.csv: T_a jumps by up to 60.0"),
        "{}",
        s[0].text
    );
}

#[test]
fn a_frozen_reading_is_a_repeat_and_a_long_gap_is_not_a_jump() {
    let (mut t, mut y) = warming(960);
    for v in y.iter_mut().skip(300).take(200) {
        *v = 23.5; // frozen for 199 steps of 15 s (2985 s)
    }
    // the logger off for a day, the machine cold again: a large change over a long gap
    for (i, (ti, yi)) in t.iter_mut().zip(y.iter_mut()).enumerate().skip(800) {
        *ti += 86_400.0;
        *yi -= 4.0 + 0.001 * i as f64;
    }
    let s = suspect_readings("run.csv", &["T_a"], &[&y], &t);
    assert_eq!(s.len(), 2, "{s:?}");
    // the day off is said once, as the log's gap (before row 801), not as the column's jump
    assert_eq!(
        (s[0].column.as_str(), s[0].kind, s[0].row, s[0].count),
        ("time_s", SuspectKind::Gap, 801, 1)
    );
    assert_eq!(s[0].size, 86_400.0 + 15.0);
    assert!(!s[0].fails());
    assert_eq!((s[1].kind, s[1].row), (SuspectKind::Repeat, 301));
    assert_eq!(s[1].size, 199.0 * 15.0);
    // shorter than the stuck floor: not said
    let (t, mut y) = warming(960);
    for v in y.iter_mut().skip(300).take(100) {
        *v = 23.5;
    }
    assert!(suspect_readings("run.csv", &["T_a"], &[&y], &t).is_empty());
}

#[test]
fn a_gap_is_ten_median_steps_and_ten_minutes() {
    // 15-s steps: a 9.5-min gap is not said (under the floor), a 10-min one is
    for (extra, said) in [(570.0 - 15.0, false), (600.0 - 15.0, true)] {
        let (mut t, y) = warming(960);
        for ti in t.iter_mut().skip(400) {
            *ti += extra;
        }
        let s = suspect_readings("run.csv", &["T_a"], &[&y], &t);
        assert_eq!(
            s.iter().any(|x| x.kind == SuspectKind::Gap && x.row == 401),
            said,
            "{s:?}"
        );
    }
    // 120-s steps: the floor is ten steps (20 min), not 10 min
    let t: Vec<f64> = (0..300)
        .map(|i| 120.0 * i as f64 + if i >= 100 { 900.0 } else { 0.0 })
        .collect();
    let y: Vec<f64> = t.iter().map(|v| 20.0 + v / 3600.0).collect();
    assert!(suspect_readings("run.csv", &["T_a"], &[&y], &t).is_empty());
}

#[test]
fn a_failing_sensor_is_not_fitted_from_its_jump_to_the_next_or_the_end() {
    let (t, clean) = warming(960);
    assert!(failing_rows(&clean, &t).is_empty());
    // a spike: one reading out
    let mut y = clean.clone();
    y[500] += 60.0;
    assert_eq!(failing_rows(&y, &t), vec![500..501]);
    // stuck high for a while, then back
    let mut y = clean.clone();
    for v in &mut y[300..420] {
        *v = 85.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![300..420]);
    // an open thermocouple at its rail to the end; its repeat is said inside those rows
    let mut y = clean.clone();
    for v in &mut y[600..] {
        *v = -200.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![600..960]);
    let s = suspect_readings("run.csv", &["T_a"], &[&y], &t);
    assert_eq!((s[0].kind, s[0].row), (SuspectKind::Jump, 601));
    assert!(
        s[0].text.contains("as a node's sensor it is not fitted"),
        "{}",
        s[0].text
    );
    assert_eq!((s[1].kind, s[1].row), (SuspectKind::Repeat, 601));
    assert!(
        s[1].text
            .ends_with("inside the rows of its jump, not fitted"),
        "{}",
        s[1].text
    );
    // a probe's failing rows are neither fitted nor scored
    let s = suspect_readings("run.csv", &["E_a"], &[&y], &t);
    assert!(
        s[0].text.contains("neither fitted nor scored"),
        "{}",
        s[0].text
    );
    // a column with a missing value is not judged
    y[10] = f64::NAN;
    assert!(failing_rows(&y, &t).is_empty());
}

#[test]
#[allow(clippy::single_range_in_vec_init)] // a list of row ranges that holds one
fn only_spikes_that_come_back_within_a_short_gap_are_short_failures() {
    let (t, clean) = warming(960);
    let step = t[1] - t[0];
    assert_eq!(short_failures(&clean, &t), None);
    // two spikes, each back after a few readings
    let mut y = clean.clone();
    y[500] += 60.0;
    for v in &mut y[700..703] {
        *v = -200.0;
    }
    assert_eq!(short_failures(&y, &t), Some(vec![500..501, 700..703]));
    // out for longer than GAP_FLOOR_S from the last right reading to the next (40 rows out:
    // 41 steps, 615 s): not short
    let long = (GAP_FLOOR_S / step) as usize;
    let mut y = clean.clone();
    for v in &mut y[300..300 + long] {
        *v = 85.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![300..300 + long]);
    assert_eq!(short_failures(&y, &t), None);
    // one row fewer, it spans GAP_FLOOR_S exactly: short
    let mut y = clean.clone();
    for v in &mut y[300..300 + long - 1] {
        *v = 85.0;
    }
    assert_eq!(short_failures(&y, &t), Some(vec![300..300 + long - 1]));
    // open to the end: not short, however late it opens
    let mut y = clean.clone();
    y[959] = -200.0;
    assert_eq!(short_failures(&y, &t), None);
    // a short spike beside a long stretch: the column is not mended
    let mut y = clean.clone();
    y[100] += 60.0;
    for v in &mut y[600..] {
        *v = -200.0;
    }
    assert_eq!(short_failures(&y, &t), None);
}

#[test]
fn a_spike_on_a_short_run_is_seen() {
    // 121 readings: the 99th percentile of 120 steps would be the spike's own second step
    let (t, mut y) = warming(121);
    y[60] = 9999.0;
    assert_eq!(failing_rows(&y, &t), vec![60..61]);
    let s = suspect_readings("run.csv", &["E_a"], &[&y], &t);
    assert_eq!(
        (s[0].kind, s[0].row, s[0].count),
        (SuspectKind::Jump, 61, 2)
    );
}

#[test]
fn a_failing_stretch_ends_only_when_the_column_is_back() {
    let (t, clean) = warming(960);
    // a spike that decays over three readings: two jumps down, neither lands back yet
    let mut y = clean.clone();
    y[400] += 90.0;
    y[401] += 45.0;
    y[402] += 4.0;
    let f = failing_rows(&y, &t);
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].start, 400);
    assert!(f[0].end >= 402 && f[0].end <= 403, "{f:?}");
    // stuck at 85 for a while, back where the machine has gone meanwhile (3 K warmer)
    let mut y = clean.clone();
    for v in &mut y[300..420] {
        *v = 85.0;
    }
    for v in &mut y[420..] {
        *v += 3.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![300..420]);
    // a sensor re-seated 6 K off: it never comes back, failing to the end
    let mut y = clean.clone();
    for v in &mut y[700..] {
        *v += 6.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![700..960]);
}

#[test]
fn a_sensor_dead_in_every_row_is_constant_and_fails() {
    let (t, clean) = warming(960);
    // an open thermocouple at its rail for the whole run
    let y = vec![-200.0; 960];
    let s = suspect_readings("run.csv", &["T_a"], &[&y], &t);
    assert_eq!(s.len(), 1, "{s:?}");
    assert_eq!((s[0].kind, s[0].row), (SuspectKind::Constant, 1));
    assert!(s[0].fails());
    assert_eq!(s[0].size, 959.0 * 15.0);
    assert!(
        s[0].text
            .starts_with("run.csv: T_a reads one value (-200) in every row (14385 s)"),
        "{}",
        s[0].text
    );
    assert_eq!(s[0].fault(), "reads one value in every row (14385 s)");
    // it is not fitted row by row: nothing jumps, the column is used as read where named
    assert!(failing_rows(&y, &t).is_empty());
    // one reading different: a repeat (a steady room on a coarse logger), not a dead sensor
    let mut y2 = y.clone();
    y2[959] = -199.9;
    let s = suspect_readings("run.csv", &["T_a"], &[&y2], &t);
    assert_eq!(s.len(), 1, "{s:?}");
    assert_eq!(s[0].kind, SuspectKind::Repeat);
    assert!(!s[0].fails());
    // a short run (under the stuck floor) of one reading is not said
    let y3 = vec![20.0; 100];
    assert!(suspect_readings("run.csv", &["T_a"], &[&y3], &t[..100]).is_empty());
    // named the room, it does not fail: a climate-controlled room on a coarse logger
    let s = suspect_readings("run.csv", &["T_ambient"], &[&y], &t);
    assert_eq!(s[0].kind, SuspectKind::Constant);
    assert!(!s[0].fails());
    // a probe that never moves
    let z = vec![0.0; 960];
    let s = suspect_readings("run.csv", &["E_a"], &[&z], &t);
    assert_eq!(s[0].kind, SuspectKind::Constant);
    assert!(
        s[0].text.contains("dead or disconnected probe"),
        "{}",
        s[0].text
    );
    let _ = clean;
}

#[test]
fn a_sensor_dead_from_the_start_fails_until_it_comes_alive() {
    let (t, clean) = warming(960);
    // at its rail for the first 300 readings (4485 s), then connected
    let mut y = clean.clone();
    for v in &mut y[..300] {
        *v = -200.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![0..300]);
    let s = suspect_readings("run.csv", &["T_a"], &[&y], &t);
    assert_eq!((s[0].kind, s[0].row), (SuspectKind::Jump, 301));
    assert!(s[0].fails());
    assert_eq!((s[1].kind, s[1].row), (SuspectKind::Repeat, 1));
    assert!(
        s[1].text
            .ends_with("inside the rows of its jump, not fitted"),
        "{}",
        s[1].text
    );
    // and a later spike is still its own stretch
    y[700] += 60.0;
    assert_eq!(failing_rows(&y, &t), vec![0..300, 700..701]);
    // the other way round (right, then open at its rail to the end) is unchanged
    let mut y = clean.clone();
    for v in &mut y[300..] {
        *v = -200.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![300..960]);
    // a steady start on a coarse logger (one reading for 45 min) then a spike that comes back:
    // the start is right, the spike fails
    let mut y: Vec<f64> = t
        .iter()
        .map(|&s| {
            let warm = 5.0 * (1.0 - (-(s - 2700.0).max(0.0) / 3600.0).exp());
            ((20.0 + warm) * 10.0).round() / 10.0
        })
        .collect();
    assert!(y[..181].iter().all(|&v| v == 20.0) && y[190] > 20.0);
    y[500] += 60.0;
    assert_eq!(failing_rows(&y, &t), vec![500..501]);
    // shorter than the stuck floor at the start: an ordinary jump, failing from it on
    let mut y = clean.clone();
    for v in &mut y[..100] {
        *v = -200.0;
    }
    assert_eq!(failing_rows(&y, &t), vec![100..960]);
}

#[test]
fn a_probe_that_does_not_start_at_zero_is_taken_from_its_first_reading() {
    let (t, y) = warming(960);
    // a raw reading: 20 µm at the start, moving 5 µm over the run
    let off = probe_offset(&y, &[]).expect("an offset");
    let start = y[0];
    assert_eq!(off, start);
    let s = suspect_readings("run.csv", &["E_a"], &[&y], &t);
    assert_eq!(s.len(), 1, "{s:?}");
    assert_eq!(
        (s[0].kind, s[0].row, s[0].size),
        (SuspectKind::Offset, 1, y[0])
    );
    assert!(!s[0].fails());
    assert!(
        s[0].text.starts_with("run.csv: E_a reads 20.0"),
        "{}",
        s[0].text
    );
    // a temperature is no probe: said nothing of
    assert!(suspect_readings("run.csv", &["T_a"], &[&y], &t).is_empty());
    // an error from the run's start (its first reading within its own movement) is left alone
    let z: Vec<f64> = y.iter().map(|v| v - y[0] + 0.3).collect();
    assert_eq!(probe_offset(&z, &[]), None);
    assert!(suspect_readings("run.csv", &["E_a"], &[&z], &t).is_empty());
    // the first right reading: a probe that fails over its first rows is judged after them
    let mut w = z.clone();
    for v in &mut w[..5] {
        *v = 900.0;
    }
    let first_five = vec![std::ops::Range { start: 0, end: 5 }];
    assert_eq!(probe_offset(&w, &first_five), None);
    assert_eq!(probe_offset(&y, &first_five), Some(y[5]));
}

#[test]
fn a_probe_that_starts_away_from_zero_within_its_movement_is_said() {
    // the drift from some earlier start: 29.5 µm over the run, 4 µm at this run's first row
    let (t, y) = warming(960);
    let e: Vec<f64> = y.iter().map(|v| 6.0 * (v - y[0]) + 4.0).collect();
    let s = suspect_readings("piece.csv", &["E_a"], &[&e], &t);
    assert_eq!(s.len(), 1, "{s:?}");
    assert_eq!(
        (s[0].kind, s[0].row, s[0].size),
        (SuspectKind::Start, 1, 4.0)
    );
    assert!(!s[0].fails());
    assert!(
        s[0].text.starts_with("piece.csv: E_a reads 4.00 µm at its first right reading, 14 % of what it moves over the run (29.5 µm): a run's drift is predicted from its start, where it is 0"),
        "{}",
        s[0].text
    );
    // within the floor (a probe's noise at its zero) or a tenth of its movement: nothing said;
    // beyond its movement it is an offset, taken from its first reading, not this
    for (start, said) in [
        (1.9, None),
        (2.5, None),
        (3.5, Some(SuspectKind::Start)),
        (40.0, Some(SuspectKind::Offset)),
    ] {
        let e: Vec<f64> = y.iter().map(|v| 6.0 * (v - y[0]) + start).collect();
        let s = suspect_readings("piece.csv", &["E_a"], &[&e], &t);
        assert_eq!(s.first().map(|s| s.kind), said, "{start}: {s:?}");
        assert!(s.len() <= 1, "{s:?}");
    }
}

#[test]
fn a_probe_that_moves_by_less_than_a_micron_is_said_to_be_in_another_unit() {
    let (t, y) = warming(960);
    // the same drift from the run's start, in µm (moves 5 µm) and in mm (moves 0.005)
    let um: Vec<f64> = y.iter().map(|v| v - y[0]).collect();
    let mm: Vec<f64> = um.iter().map(|v| v / 1000.0).collect();
    assert!(suspect_readings("run.csv", &["E_a"], &[&um], &t).is_empty());
    let s = suspect_readings("run.csv", &["E_a"], &[&mm], &t);
    assert_eq!(s.len(), 1, "{s:?}");
    let range = mm.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - mm.iter().cloned().fold(f64::INFINITY, f64::min);
    assert_eq!((s[0].kind, s[0].size), (SuspectKind::Scale, range));
    assert!(!s[0].fails() && s[0].dead_probe().is_none());
    assert!(
        s[0].text.starts_with(&format!(
            "run.csv: E_a moves by {range:.4} over the whole run"
        )) && s[0].text.contains("multiply the column by 1000"),
        "{}",
        s[0].text
    );
    // a temperature in its units is no probe; a probe that does not move at all is a constant
    assert!(suspect_readings("run.csv", &["T_a"], &[&mm], &t).is_empty());
    let flat = vec![0.0; t.len()];
    let s = suspect_readings("run.csv", &["E_a"], &[&flat], &t);
    assert_eq!(
        s.iter().map(|x| x.kind).collect::<Vec<_>>(),
        vec![SuspectKind::Constant]
    );
}

/// Two warm-ups joined, the clock running on: every column steps back to its cold reading at
/// row 481, by less than a sensor's jump. Two columns of six stepping at one row (a logger
/// module's, the few on it) are not a second run.
#[test]
fn every_column_stepping_at_one_row_is_a_second_run_joined_but_two_are_faults() {
    let (t, y) = warming(960);
    let joined: Vec<Vec<f64>> = (0..6)
        .map(|c| {
            (0..960)
                // steps back of 0.9-1.9 K (µm): under the jump floor, as at the real run's join
                .map(|i| (0.2 + 0.05 * c as f64) * y[i % 480] + c as f64)
                .collect()
        })
        .collect();
    let names = ["T_a", "T_b", "T_c", "T_d", "T_e", "T_f"];
    let cols: Vec<&[f64]> = joined.iter().map(Vec::as_slice).collect();
    let e = one_run("run.csv", &names, &cols, &t)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("run.csv, row 481: 6 of the 6 temperature columns step at once, each far faster than it moves otherwise (T_f by -"),
        "{e}"
    );
    assert!(e.contains("a second run appended to the first?"), "{e}");
    // two of six stepping at row 481, the others warming on: not a second run
    let (_, clean) = warming(960);
    let mut cols: Vec<&[f64]> = vec![clean.as_slice(); 6];
    cols[0] = &joined[0];
    cols[3] = &joined[3];
    one_run("run.csv", &names, &cols, &t).unwrap();
    // three of six is half: a second run
    cols[5] = &joined[5];
    assert!(one_run("run.csv", &names, &cols, &t).is_err());
}
