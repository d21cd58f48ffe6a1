//! The thermal network simulation against analytic and independent numerical solutions, and
//! the machine file's validation.

use approx::assert_relative_eq;
use thermerr_core::run::{NanPolicy, Run};
use thermerr_core::thermal::{simulate, Init, Machine, RunView};

fn run(cols: Vec<(&str, Vec<f64>)>) -> Run {
    let (names, columns): (Vec<String>, Vec<Vec<f64>>) =
        cols.into_iter().map(|(n, c)| (n.to_string(), c)).unzip();
    Run::from_columns("<test>", names, columns, NanPolicy::Error, None).unwrap()
}

const ONE_NODE: &str = r#"
name = "one"
ambient = "T_ambient"
[[nodes]]
name = "a"
capacity_j_per_k = 1000.0
ambient_w_per_k = 2.0
sensor = "T_a"
[[sources]]
node = "a"
input = "U_rpm"
w = 50.0
ref = 1000.0
exponent = 1.0
[[drift]]
axis = "E_z"
um_per_k = { a = 3.0 }
"#;

/// A run for [`ONE_NODE`]: the room and the node's sensor at 20 °C, its input `rpm`, no drift.
fn one_node_run(t: &[f64], rpm: Vec<f64>) -> Run {
    let n = t.len();
    run(vec![
        ("time_s", t.to_vec()),
        ("T_ambient", vec![20.0; n]),
        ("T_a", vec![20.0; n]),
        ("U_rpm", rpm),
        ("E_z", vec![0.0; n]),
    ])
}

#[test]
fn one_node_step_response_is_exact() {
    let m = Machine::from_toml(ONE_NODE, "one.toml").unwrap();
    // coarse, irregular sampling: the discretisation is exact anyway
    let t = vec![0.0, 10.0, 250.0, 600.0, 601.0, 3000.0];
    let r = one_node_run(&t, vec![1000.0; t.len()]);
    let s = simulate(&m, &RunView::new(&r), &Init::FirstReading).unwrap();
    let e = &s.drift[0].1;
    for (k, tk) in t.iter().enumerate() {
        let rise = 50.0 / 2.0 * (1.0 - (-2.0 * tk / 1000.0).exp());
        assert_relative_eq!(s.temps[k], 20.0 + rise, epsilon = 1e-10);
        assert_relative_eq!(e[k], 3.0 * rise, epsilon = 1e-9);
    }
}

const TWO_NODES: &str = r#"
name = "two"
ambient = 21.0
[[nodes]]
name = "hot"
capacity_j_per_k = 800.0
ambient_w_per_k = 0.5
sensor = "T_hot"
[[nodes]]
name = "cold"
capacity_j_per_k = 5000.0
ambient_w_per_k = 3.0
[[links]]
between = ["hot", "cold"]
w_per_k = 4.0
[[sources]]
node = "hot"
input = "U_rpm"
w = 40.0
ref = 6000.0
exponent = 1.4
[[drift]]
axis = "E_x"
um_per_k = { hot = 1.0, cold = 2.0 }
"#;

fn rk4(t: &[f64], rpm: &[f64]) -> Vec<[f64; 2]> {
    let q = |u: f64| {
        if u > 0.0 {
            40.0 * (u / 6000.0f64).powf(1.4)
        } else {
            0.0
        }
    };
    let f = |x: [f64; 2], u: f64| {
        [
            (4.0 * (x[1] - x[0]) + 0.5 * (21.0 - x[0]) + q(u)) / 800.0,
            (4.0 * (x[0] - x[1]) + 3.0 * (21.0 - x[1])) / 5000.0,
        ]
    };
    let mut x = [20.0, 21.0];
    let mut out = vec![x];
    for k in 0..t.len() - 1 {
        let steps = 2000;
        let h = (t[k + 1] - t[k]) / steps as f64;
        for _ in 0..steps {
            let k1 = f(x, rpm[k]);
            let k2 = f([x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]], rpm[k]);
            let k3 = f([x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]], rpm[k]);
            let k4 = f([x[0] + h * k3[0], x[1] + h * k3[1]], rpm[k]);
            x = [
                x[0] + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
                x[1] + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
            ];
        }
        out.push(x);
    }
    out
}

#[test]
fn two_nodes_match_fine_rk4_and_irregular_steps() {
    let m = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    let t: Vec<f64> = (0..40)
        .map(|k| k as f64 * 300.0 + if k % 3 == 1 { 37.0 } else { 0.0 })
        .collect();
    let rpm: Vec<f64> = (0..40)
        .map(|k| [0.0, 3000.0, 6000.0, 4500.0][(k / 10) % 4])
        .collect();
    let mut hot = vec![0.0; 40];
    hot[0] = 20.0;
    let r = run(vec![
        ("time_s", t.clone()),
        ("T_hot", hot),
        ("U_rpm", rpm.clone()),
        ("E_x", vec![0.0; 40]),
    ]);
    let s = simulate(&m, &RunView::new(&r), &Init::FirstReading).unwrap();
    let reference = rk4(&t, &rpm);
    for (k, x) in reference.iter().enumerate() {
        // RK4 with h ≤ 0.17 s: global error far below 1e-8 K
        assert_relative_eq!(s.temps[2 * k], x[0], epsilon = 1e-8);
        assert_relative_eq!(s.temps[2 * k + 1], x[1], epsilon = 1e-8);
    }
}

/// The largest deviation (K) of the simulation from RK4 on each sample's own time, 60-s samples
/// stamped `jitter` s off (on non-binary decimals), with the inputs switching on those times.
fn jittered_deviation(jitter: f64) -> f64 {
    let m = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    let n = 400;
    let t: Vec<f64> = (0..n)
        .map(|k| k as f64 * 60.0 + jitter * (1.7 * k as f64).sin() + 0.0137)
        .collect();
    let rpm: Vec<f64> = (0..n)
        .map(|k| [0.0, 3000.0, 6000.0, 4500.0][(k / 25) % 4])
        .collect();
    let mut hot = vec![0.0; n];
    hot[0] = 20.0;
    let r = run(vec![
        ("time_s", t.clone()),
        ("T_hot", hot),
        ("U_rpm", rpm.clone()),
        ("E_x", vec![0.0; n]),
    ]);
    let s = simulate(&m, &RunView::new(&r), &Init::FirstReading).unwrap();
    let reference = rk4(&t, &rpm);
    // and the rounding is what makes the difference: the hot node rises by tens of K here
    assert!(reference.iter().any(|x| x[0] > 30.0));
    reference
        .iter()
        .enumerate()
        .map(|(k, x)| {
            (s.temps[2 * k] - x[0])
                .abs()
                .max((s.temps[2 * k + 1] - x[1]).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_jittering_logger_is_simulated_on_its_own_times() {
    // 60-s samples with ±0.5 s of jitter: every step length differs. The simulation puts the
    // times on a 1/32-s grid (a power of two near 1/1000 of the step), so a reading is taken at
    // most 1/64 s off its time and the input switches at most 1/64 s off. The hot node moves at
    // most (40 W + links) / 800 J/K ≈ 0.06 K/s, so each such shift costs at most ~1e-3 K, and the
    // shifts do not accumulate (the times are rounded, not the steps).
    let worst = jittered_deviation(0.5);
    assert!(worst < 2e-3, "largest deviation {worst} K");
}

#[test]
fn a_widely_jittering_logger_is_simulated_on_a_coarser_grid_within_its_bound() {
    // ±8 s: steps from 44 to 76 s, a thousand grid steps apart on 1/32 s; the grid is doubled
    // until at most 128 lengths remain (1/4 s), so a time moves by at most 1/8 s: ~8e-3 K at the
    // hot node's 0.06 K/s, the same bound per tick as above
    let worst = jittered_deviation(8.0);
    assert!(worst < 16e-3, "largest deviation {worst} K");
}

#[test]
fn coarse_and_fine_sampling_agree_on_shared_instants() {
    let m = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    let mk = |step: usize| {
        let t: Vec<f64> = (0..=3600).step_by(step).map(|v| v as f64).collect();
        let n = t.len();
        let mut hot = vec![0.0; n];
        hot[0] = 20.0;
        run(vec![
            ("time_s", t),
            ("T_hot", hot),
            ("U_rpm", vec![5000.0; n]),
            ("E_x", vec![0.0; n]),
        ])
    };
    let (fine, coarse) = (mk(1), mk(600));
    let sf = simulate(&m, &RunView::new(&fine), &Init::FirstReading).unwrap();
    let sc = simulate(&m, &RunView::new(&coarse), &Init::FirstReading).unwrap();
    for k in 0..coarse.len() {
        assert_relative_eq!(sc.temps[2 * k], sf.temps[2 * 600 * k], epsilon = 1e-9);
        assert_relative_eq!(sc.drift[0].1[k], sf.drift[0].1[600 * k], epsilon = 1e-9);
    }
}

#[test]
fn toml_round_trip_simulates_identically() {
    let mut m = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    m.drift[0].lag_s = Some(900.0);
    m.drift[0].ambient_um_per_k = Some(1.5);
    m.drift[0].quadratic_um_per_k2.insert("hot".into(), 0.01);
    m.nodes[0].sensor_drift_k_per_h = 0.1;
    let text = m.to_toml().unwrap();
    let back = Machine::from_toml(&text, "back.toml").unwrap();
    assert_eq!(m, back);
}

#[test]
fn the_lag_takes_the_structure_and_the_room_acts_directly() {
    // one heated node; the room steps up by 2 K at 600 s
    let mut m = Machine::from_toml(ONE_NODE, "one.toml").unwrap();
    let t: Vec<f64> = (0..=60).map(|k| k as f64 * 60.0).collect();
    let n = t.len();
    let amb: Vec<f64> = t
        .iter()
        .map(|&s| if s < 600.0 { 20.0 } else { 22.0 })
        .collect();
    let r = run(vec![
        ("time_s", t.clone()),
        ("T_ambient", amb.clone()),
        ("T_a", vec![20.0; n]),
        ("U_rpm", vec![1000.0; n]),
        ("E_z", vec![0.0; n]),
    ]);
    let view = RunView::new(&r);
    let tau = 900.0;
    m.drift[0].quadratic_um_per_k2.insert("a".into(), 0.05);
    let plain = simulate(&m, &view, &Init::FirstReading).unwrap();
    m.drift[0].ambient_um_per_k = Some(1.5);
    let with_room = simulate(&m, &view, &Init::FirstReading).unwrap();
    m.drift[0].lag_s = Some(tau);
    let lagged_room = simulate(&m, &view, &Init::FirstReading).unwrap();
    m.drift[0].ambient_um_per_k = None;
    let lagged = simulate(&m, &view, &Init::FirstReading).unwrap();
    let structure: Vec<f64> = plain.drift[0].1.clone();
    let through_lag = thermerr_core::thermal::sim::lag(&t, &structure, tau);
    for k in 0..n {
        let room = 1.5 * (amb[k] - amb[0]);
        // without a lag: the structure's terms (linear and quadratic) and the room, added
        assert_relative_eq!(with_room.drift[0].1[k], structure[k] + room, epsilon = 1e-9);
        // the lag filters the node terms, linear and quadratic alike ...
        assert_relative_eq!(lagged.drift[0].1[k], through_lag[k], epsilon = 1e-9);
        // ... and the room's term is added as it is: the room acts on the axis directly
        assert_relative_eq!(
            lagged_room.drift[0].1[k],
            through_lag[k] + room,
            epsilon = 1e-9
        );
    }
    assert!(
        through_lag[20] < 0.9 * structure[20],
        "the lag must filter something here"
    );
}

#[test]
fn lag_reaches_63_percent_at_tau() {
    let t: Vec<f64> = (0..=100).map(|k| k as f64 * 10.0).collect();
    let mut y = vec![1.0; t.len()];
    y[0] = 0.0;
    // a step at t = 0⁺ (the ramp over the first 10 s is what the sampled input can say)
    let z = thermerr_core::thermal::sim::lag(&t, &y, 500.0);
    let at_tau = z[50 + 1 - 1];
    assert!((at_tau - (1.0 - (-1.0f64).exp())).abs() < 0.01, "{at_tau}");
}

fn err(text: &str) -> String {
    Machine::from_toml(text, "m.toml").unwrap_err().to_string()
}

#[test]
fn validation_names_the_entry() {
    let e = err(&ONE_NODE.replace("node = \"a\"", "node = \"b\""));
    assert!(
        e.contains("m.toml") && e.contains("sources[0]") && e.contains("unknown node `b`"),
        "{e}"
    );
    let e = err(&ONE_NODE.replace("capacity_j_per_k = 1000.0", "capacity_j_per_k = 0.0"));
    assert!(e.contains("nodes[0] `a`") && e.contains("capacity"), "{e}");
    let e = err(&TWO_NODES.replace("w_per_k = 4.0", "w_per_k = -4.0"));
    assert!(e.contains("links[0]") && e.contains(">= 0"), "{e}");
    let e = err(&TWO_NODES.replace("name = \"cold\"", "name = \"hot\""));
    assert!(e.contains("duplicate node name"), "{e}");
    let e = err(&TWO_NODES
        .replace("ambient_w_per_k = 3.0", "ambient_w_per_k = 0.0")
        .replace("ambient_w_per_k = 0.5", ""));
    assert!(e.contains("singular"), "{e}");
    let e = err(&TWO_NODES.replace(
        "between = [\"hot\", \"cold\"]",
        "between = [\"hot\", \"hot\"]",
    ));
    assert!(e.contains("two different nodes"), "{e}");
    let e = err(&ONE_NODE.replace("ref = 1000.0", "ref = 0.0"));
    assert!(e.contains("ref must be > 0"), "{e}");
    let e = err("name = \"x\"\nambient = 20.0\nnodes = [ { name = \"a\", capacity_j_per_k = 1.0, ambient_w_per_k = 1.0, sensr = \"T\" } ]\n");
    assert!(e.contains("sensr"), "{e}");
    let e = err(&TWO_NODES.replace(
        "between = [\"hot\", \"cold\"]",
        "between = [\"hot\", \"cold\", \"hot\"]",
    ));
    assert!(e.contains("exactly two nodes, got 3"), "{e}");
    let e = err(&format!(
        "{TWO_NODES}[[drift]]\naxis = \"E_x\"\num_per_k = {{ hot = 2.0 }}\n"
    ));
    assert!(
        e.contains("drift[1] `E_x`") && e.contains("one [[drift]] per axis"),
        "{e}"
    );
    let e = err(&format!(
        "{TWO_NODES}[[drift.columns]]\ncolumn = \"T_hot\"\num_per_k = nan\n"
    ));
    assert!(
        e.contains("columns[0] `T_hot`") && e.contains("finite"),
        "{e}"
    );
    let e = err("name = \"x\"\nambient = 20.0\n[[nodes]\n");
    assert!(e.contains("line 3"), "{e}");
}

#[test]
fn missing_run_column_names_the_entry() {
    let m = Machine::from_toml(ONE_NODE, "one.toml").unwrap();
    let r = run(vec![
        ("time_s", vec![0.0, 1.0]),
        ("T_ambient", vec![20.0, 20.0]),
        ("T_a", vec![20.0, 20.0]),
    ]);
    let v = RunView::new(&r);
    let e = m
        .check_columns("one.toml", "<test>", |c| v.has(c))
        .unwrap_err()
        .to_string();
    assert!(e.contains("U_rpm") && e.contains("sources[0]"), "{e}");
}

#[test]
fn calibration_refuses_a_bound_factor_that_freezes_it() {
    use thermerr_core::thermal::calibrate::{calibrate, CalibrationOptions};
    let m = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    let n = 50;
    let r = run(vec![
        ("time_s", (0..n).map(|k| k as f64 * 60.0).collect()),
        ("T_hot", vec![20.0; n]),
        ("U_rpm", vec![3000.0; n]),
        ("E_x", vec![0.0; n]),
    ]);
    for f in [1.0, 0.5, f64::NAN] {
        let opts = CalibrationOptions {
            axis: "E_x".into(),
            bound_factor: f,
            ..CalibrationOptions::default()
        };
        let e = calibrate(&m, &RunView::new(&r), &opts, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("bound_factor") && e.contains("> 1"), "{e}");
    }
}

#[test]
fn the_first_rows_simulate_as_on_the_whole_run() {
    // calibration simulates only the fitted rows (RunView::head): on them, the same numbers
    let m = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    let n = 60;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 60.0).collect();
    let rpm: Vec<f64> = (0..n).map(|k| [0.0, 3000.0, 6000.0][(k / 7) % 3]).collect();
    let hot: Vec<f64> = (0..n).map(|k| 20.0 + 0.01 * k as f64).collect();
    let r = run(vec![
        ("time_s", t),
        ("T_hot", hot),
        ("U_rpm", rpm),
        ("E_x", vec![0.0; n]),
    ]);
    let whole = RunView::new(&r);
    let full = simulate(&m, &whole, &Init::FirstReading).unwrap();
    let head = simulate(&m, &whole.head(41), &Init::FirstReading).unwrap();
    assert_eq!(head.temps.len(), 41 * 2);
    assert_eq!(head.temps[..], full.temps[..41 * 2]);
    assert_eq!(head.drift[0].1[..], full.drift[0].1[..41]);
}

#[test]
fn a_bic_step_stops_a_misfit_calibration_sooner_and_costs_it_little() {
    // a run the network cannot explain (a slow swing on the error axis and the sensor, far above
    // the noise): the fixed tolerance keeps the search crawling; a minimum BIC step of 0.1 stops
    // it sooner, and the BIC it ends with is within a tenth of the evidence rule's 10
    use thermerr_core::thermal::calibrate::{calibrate, CalibrationOptions};
    let mut m = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    let n = 600;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 60.0).collect();
    let rpm: Vec<f64> = (0..n)
        .map(|k| [0.0, 3000.0, 6000.0][(k / 70) % 3])
        .collect();
    let truth = {
        let r = run(vec![
            ("time_s", t.clone()),
            ("T_hot", vec![20.0; n]),
            ("U_rpm", rpm.clone()),
            ("E_x", vec![0.0; n]),
        ]);
        simulate(&m, &RunView::new(&r), &Init::FirstReading).unwrap()
    };
    let swing = |k: usize, a: f64| a * (2.0 * std::f64::consts::PI * t[k] / 20_000.0).sin();
    let wobble = |k: usize| 0.02 * ((k * 7919) % 13) as f64 / 13.0;
    let hot: Vec<f64> = (0..n)
        .map(|k| truth.sensors[0].1[k] + swing(k, 0.4) + wobble(k))
        .collect();
    let e: Vec<f64> = (0..n)
        .map(|k| truth.drift[0].1[k] + swing(k, 3.0) + wobble(k))
        .collect();
    let r = run(vec![
        ("time_s", t),
        ("T_hot", hot),
        ("U_rpm", rpm),
        ("E_x", e),
    ]);
    // start the search off the truth, so that it has a way to go
    m.nodes[0].capacity_j_per_k *= 2.0;
    m.links[0].w_per_k *= 0.5;
    let fit = |step: f64| {
        let opts = CalibrationOptions {
            axis: "E_x".into(),
            min_bic_step: step,
            ..CalibrationOptions::default()
        };
        calibrate(&m, &RunView::new(&r), &opts, None).unwrap()
    };
    let (settled, stepped) = (fit(0.0), fit(0.1));
    assert!(
        settled.ssr / settled.n_data as f64 > 100.0,
        "the run must misfit far above the noise: SSR/n = {}",
        settled.ssr / settled.n_data as f64
    );
    assert!(
        stepped.n_iter < settled.n_iter,
        "{} !< {} iterations",
        stepped.n_iter,
        settled.n_iter
    );
    let d = stepped.bic() - settled.bic();
    assert!(
        d.abs() < 1.0,
        "BIC {} against {}",
        stepped.bic(),
        settled.bic()
    );
    // a negative step is refused
    let opts = CalibrationOptions {
        axis: "E_x".into(),
        min_bic_step: -1.0,
        ..CalibrationOptions::default()
    };
    let err = calibrate(&m, &RunView::new(&r), &opts, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("min_bic_step"), "{err}");
}

const COOLED: &str = r#"
name = "cooled"
ambient = "T_ambient"
[[nodes]]
name = "a"
capacity_j_per_k = 1000.0
ambient_w_per_k = 2.0
sensor = "T_a"
[[nodes]]
name = "coolant"
capacity_j_per_k = 1.0
ambient_w_per_k = 0.0
boundary = "T_cool"
[[links]]
between = ["a", "coolant"]
w_per_k = 3.0
[[drift]]
axis = "E_z"
um_per_k = { a = 3.0 }
"#;

/// A room or boundary sensor that fails (an open thermocouple at -200 °C) drives the network
/// at its last right reading over its failing rows, as a run whose reading stayed there would.
#[test]
fn a_failing_room_or_boundary_sensor_is_held_at_its_last_right_reading() {
    let m = Machine::from_toml(COOLED, "cooled.toml").unwrap();
    let n = 400;
    let t: Vec<f64> = (0..n).map(|k| 60.0 * k as f64).collect();
    let room: Vec<f64> = t.iter().map(|s| 20.0 + (s / 7200.0).sin()).collect();
    let cool: Vec<f64> = t.iter().map(|s| 18.0 + 0.5 * (s / 3000.0).cos()).collect();
    let sim = |room: &[f64], cool: &[f64]| {
        let r = run(vec![
            ("time_s", t.clone()),
            ("T_ambient", room.to_vec()),
            ("T_cool", cool.to_vec()),
            ("T_a", vec![20.0; n]),
            ("E_z", vec![0.0; n]),
        ]);
        simulate(&m, &RunView::new(&r), &Init::FirstReading)
            .unwrap()
            .temps
    };
    let (mut room_bad, mut cool_bad) = (room.clone(), cool.clone());
    let (mut room_held, mut cool_held) = (room.clone(), cool.clone());
    for k in 150..n {
        room_bad[k] = -200.0; // open to the end
        room_held[k] = room[149];
    }
    for k in 250..300 {
        cool_bad[k] = 850.0; // stuck at its rail for 50 readings, then back
        cool_held[k] = cool[249];
    }
    let failed = sim(&room_bad, &cool_bad);
    assert_eq!(failed, sim(&room_held, &cool_held));
    assert_ne!(failed, sim(&room, &cool));
}

/// A run sampled every 15 s and calibrated on every 4th row ([`Thinned`]): the spindle starts
/// at 615 s and stops at 4830 s, between two kept rows. The thinned view's sources take the
/// mean power of the original rows over each step, so the heat they bring is the run's; every
/// 4th input alone would start and stop the spindle up to 45 s late.
#[test]
fn a_thinned_run_keeps_the_heat_of_an_input_that_changes_between_its_rows() {
    use thermerr_core::thermal::sim::Thinned;
    let m = Machine::from_toml(ONE_NODE, "one.toml").unwrap();
    let t: Vec<f64> = (0..=480).map(|k| 15.0 * k as f64).collect();
    let rpm: Vec<f64> = t
        .iter()
        .map(|&s| {
            if (615.0..4830.0).contains(&s) {
                1000.0
            } else {
                0.0
            }
        })
        .collect();
    let full = one_node_run(&t, rpm.clone());
    let every4 = |c: &[f64]| c.iter().step_by(4).copied().collect::<Vec<f64>>();
    let picked = one_node_run(&every4(&t), every4(&rpm));
    let sf = simulate(&m, &RunView::new(&full), &Init::FirstReading).unwrap();
    let thin = Thinned::of(&RunView::new(&full), 4);
    let st = simulate(&m, &thin.view(), &Init::FirstReading).unwrap();
    let sp = simulate(&m, &RunView::new(&picked), &Init::FirstReading).unwrap();
    let worst = |s: &[f64]| {
        (0..s.len())
            .map(|i| (s[i] - sf.temps[4 * i]).abs())
            .fold(0.0, f64::max)
    };
    let (held, every) = (worst(&st.temps), worst(&sp.temps));
    // 50 W into 1000 J/K warms 0.05 K/s: 45 s late is about 2 K at first
    assert!(every > 1.5, "{every}");
    // the mean power over a 60-s step moves the heat within that step only (measured 0.04 K
    // against 2.15 K)
    assert!(held < 0.05 * every, "{held} {every}");
    // a run whose input holds over every thinned step is simulated exactly as every 4th row
    let steady = one_node_run(&t, vec![700.0; t.len()]);
    let a = simulate(
        &m,
        &Thinned::of(&RunView::new(&steady), 4).view(),
        &Init::FirstReading,
    )
    .unwrap();
    let b = simulate(&m, &RunView::new(&steady), &Init::FirstReading).unwrap();
    for i in 0..a.temps.len() {
        assert_relative_eq!(a.temps[i], b.temps[4 * i], epsilon = 1e-9);
    }
}

#[test]
fn an_unsensed_node_of_a_run_starting_warm_is_started_from_the_first_hour_when_the_file_says_fit() {
    // a second run of the day: the part no sensor reads ("cold") starts 6 K above the room,
    // the sensed one at 30 °C; its readings are the network's own (no noise)
    let truth = Machine::from_toml(TWO_NODES, "two.toml").unwrap();
    let t: Vec<f64> = (0..481).map(|k| k as f64 * 60.0).collect();
    let rpm: Vec<f64> = (0..481)
        .map(|k| [0.0, 3000.0, 6000.0][(k / 60) % 3])
        .collect();
    let n = t.len();
    let mut hot = vec![30.0; n];
    let blank = |hot: Vec<f64>| {
        run(vec![
            ("time_s", t.clone()),
            ("T_hot", hot),
            ("U_rpm", rpm.clone()),
            ("E_x", vec![0.0; n]),
        ])
    };
    let warm = simulate(
        &truth,
        &RunView::new(&blank(hot.clone())),
        &Init::Offsets(vec![0.0, 6.0]),
    )
    .unwrap();
    for (k, h) in hot.iter_mut().enumerate() {
        *h = warm.temps[2 * k];
    }
    let r = blank(hot);
    let fit = Machine::from_toml(
        &TWO_NODES.replace(
            "ambient = 21.0\n",
            "ambient = 21.0\nunsensed_start = \"fit\"\n",
        ),
        "two.toml",
    )
    .unwrap();
    let s = simulate(&fit, &RunView::new(&r), &Init::FirstReading).unwrap();
    // the start is recovered (the hour's readings determine it: the network is linear in it)
    assert_relative_eq!(s.temps[1], 27.0, epsilon = 1e-6);
    let worst = |a: &[f64]| {
        a.iter()
            .zip(&warm.drift[0].1)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    assert!(worst(&s.drift[0].1) < 1e-5, "{}", worst(&s.drift[0].1));
    // the default (formats.md) starts it at the room, 6 K low: µm off
    let room = simulate(&truth, &RunView::new(&r), &Init::FirstReading).unwrap();
    assert_eq!(room.temps[1], 21.0);
    assert!(worst(&room.drift[0].1) > 1.0, "{}", worst(&room.drift[0].1));
    // and the file keeps the choice
    assert!(fit.to_toml().unwrap().contains("unsensed_start = \"fit\""));
    assert!(!truth.to_toml().unwrap().contains("unsensed_start"));
}
