//! The edge against the Python library's own predictions (fixtures written by
//! `tests/fixtures/make_fixtures.py`), its refusals, the binary, and the C ABI.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use thermerr_edge::{EdgeError, Predictor};

mod common;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures")
}

/// The fixture run's columns by name.
fn run() -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(fixtures().join("run_60.csv")).unwrap();
    let mut lines = text.lines();
    let names: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (names, rows)
}

fn expected() -> HashMap<String, Vec<f64>> {
    serde_json::from_str(&std::fs::read_to_string(fixtures().join("expected.json")).unwrap())
        .unwrap()
}

const MODELS: [&str; 8] = [
    "mlr_rise",
    "rbf_ols_minmax_rise",
    "rbf_exact_ago",
    "svr_rise",
    "bp_rise",
    "greybp_rise",
    "gm1n_rise",
    "hybrid_rise",
];

#[test]
fn predictions_equal_the_library() {
    let (names, rows) = run();
    let want = expected();
    for name in MODELS {
        let mut p = Predictor::load(fixtures().join(format!("{name}.json"))).unwrap();
        let idx: Vec<usize> = p
            .features()
            .unwrap()
            .iter()
            .map(|f| names.iter().position(|n| n == f).unwrap())
            .collect();
        let mut x = vec![0.0; idx.len()];
        for (k, row) in rows.iter().enumerate() {
            for (v, &j) in x.iter_mut().zip(&idx) {
                *v = row[j];
            }
            let y = p.predict_sample(&x).unwrap();
            let w = want[name][k];
            // the same code on the same bits: equal up to the last place of the JSON numbers
            // (they round-trip exactly), so 1e-12 relative is a generous bound
            assert!(
                (y - w).abs() <= 1e-12 * w.abs().max(1.0),
                "{name} row {k}: edge {y} vs library {w}"
            );
        }
        // a reset starts the run again
        p.reset();
        for (v, &j) in x.iter_mut().zip(&idx) {
            *v = rows[0][j];
        }
        assert_eq!(p.predict_sample(&x).unwrap(), want[name][0]);
    }
}

fn with(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from}");
    text.replacen(from, to, 1)
}

#[test]
fn bad_model_files_are_clear_errors() {
    let good = std::fs::read_to_string(fixtures().join("mlr_rise.json")).unwrap();
    let cases = [
        (
            with(&good, "\"format_version\": 1", "\"format_version\": 2"),
            "format_version 2",
        ),
        (
            with(&good, "\"kind\": \"mlr\"", "\"kind\": \"forest\""),
            "unknown model kind",
        ),
        (
            with(&good, "\"n_features\": 4", "\"n_features\": 3"),
            "n_features is 3",
        ),
        (
            with(&good, "\"inputs\": \"rise\"", "\"inputs\": \"delta\""),
            "inputs",
        ),
        (
            with(&good, "\"model\":", "\"mode\":"),
            "missing field `model`",
        ),
        ("not json".to_string(), "expected"),
    ];
    for (text, msg) in cases {
        match Predictor::from_json(&text) {
            Err(EdgeError::Format(m)) => assert!(m.contains(msg), "{m} lacks {msg}"),
            other => panic!("{msg}: {other:?}"),
        }
    }
    let rbf = std::fs::read_to_string(fixtures().join("rbf_ols_minmax_rise.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&rbf).unwrap();
    let mut bad = v.clone();
    bad["model"]["centers"]["shape"][0] = serde_json::json!(99);
    assert!(Predictor::from_json(&bad.to_string()).is_err());
    let mut bad = v;
    bad["preprocessing"]["x_max"] = serde_json::json!([1.0]);
    let e = Predictor::from_json(&bad.to_string())
        .unwrap_err()
        .to_string();
    assert!(e.contains("preprocessing"), "{e}");
    let e = Predictor::load(fixtures().join("nope.json")).unwrap_err();
    assert!(matches!(e, EdgeError::Io { .. }), "{e}");
}

#[test]
fn bad_samples_are_errors_and_leave_the_state_alone() {
    let mut p = Predictor::load(fixtures().join("rbf_exact_ago.json")).unwrap();
    assert!(p.stateful());
    assert!(p.predict_sample(&[1.0, 2.0]).is_err());
    assert!(p.predict_sample(&[20.0, f64::NAN, 20.0, 20.0]).is_err());
    let mut q = Predictor::load(fixtures().join("rbf_exact_ago.json")).unwrap();
    let x = [20.3, 20.2, 20.3, 20.3];
    assert_eq!(p.predict_sample(&x).unwrap(), q.predict_sample(&x).unwrap());
}

fn exe() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_thermerr-edge"))
}

#[test]
fn binary_streams_predictions_and_skips_bad_rows() {
    let (names, rows) = run();
    let mut csv = names.join(",") + "\n";
    for (k, r) in rows.iter().take(5).enumerate() {
        let mut f: Vec<String> = r.iter().map(|v| v.to_string()).collect();
        if k == 2 {
            let j = names.iter().position(|n| n == "T_s07").unwrap();
            f[j] = "oops".into();
        }
        csv += &(f.join(",") + "\n");
    }
    csv += "1,2,3\n";
    let path = std::env::temp_dir().join(format!("edge_rows_{}.csv", std::process::id()));
    std::fs::write(&path, csv).unwrap();
    let out = Command::new(exe())
        .arg(fixtures().join("mlr_rise.json"))
        .arg(&path)
        .output()
        .unwrap();
    assert!(out.status.success());
    let stdout = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines[0], "time_s,E_z_pred");
    assert_eq!(lines.len(), 1 + 4, "{stdout}");
    let want = &expected()["mlr_rise"];
    let got: f64 = lines[1].split(',').nth(1).unwrap().parse().unwrap();
    assert_eq!(got, want[0]);
    let got: f64 = lines[4].split(',').nth(1).unwrap().parse().unwrap();
    assert_eq!(got, want[4]);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("line 4: column `T_s07`"), "{stderr}");
    assert!(stderr.contains("line 7: expected"), "{stderr}");
    // a run without a feature column is refused, naming it
    std::fs::write(&path, "time_s,T_s01\n0,20\n").unwrap();
    let out = Command::new(exe())
        .arg(fixtures().join("mlr_rise.json"))
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("T_s07"));
    let _ = std::fs::remove_file(&path);
}

/// A run written by a spreadsheet in a German locale (`;` between fields, `20,5`) read with
/// `--delimiter ';' --decimal ,` gives the dotted run's output to the byte (times with a decimal
/// comma written as their numbers); read without `--decimal ,`, each line is refused saying so.
#[test]
fn binary_reads_a_decimal_comma_when_told_and_says_so_when_not() {
    let (names, rows) = run();
    let dotted = |r: &[f64], half: bool| -> Vec<String> {
        r.iter()
            .enumerate()
            .map(|(j, v)| {
                if j == 0 && half {
                    format!("{}", v + 0.5)
                } else {
                    v.to_string()
                }
            })
            .collect()
    };
    let mut csv = names.join(",") + "\n";
    let mut de = names.join(";") + "\n";
    for r in rows.iter().take(6) {
        csv += &(dotted(r, true).join(",") + "\n");
        let cells: Vec<String> = dotted(r, true)
            .iter()
            .map(|c| c.replace('.', ","))
            .collect();
        de += &(cells.join(";") + "\n");
    }
    assert!(de.contains(",5;"), "a time with a decimal comma: {de}");
    let dir = std::env::temp_dir();
    let (a, b) = (
        dir.join(format!("edge_dot_{}.csv", std::process::id())),
        dir.join(format!("edge_de_{}.csv", std::process::id())),
    );
    std::fs::write(&a, csv).unwrap();
    std::fs::write(&b, de).unwrap();
    let model = fixtures().join("mlr_rise.json");
    let edge = |args: &[&str]| Command::new(exe()).arg(&model).args(args).output().unwrap();
    let want = edge(&[a.to_str().unwrap()]);
    assert!(want.status.success());
    let got = edge(&[b.to_str().unwrap(), "--delimiter", ";", "--decimal", ","]);
    assert!(
        got.status.success(),
        "{}",
        String::from_utf8_lossy(&got.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&got.stdout),
        String::from_utf8_lossy(&want.stdout)
    );
    assert_eq!(String::from_utf8_lossy(&want.stdout).lines().count(), 7);
    // the delimiter alone: every line refused with the hint, exit 2
    let wrong = edge(&[b.to_str().unwrap(), "--delimiter", "semicolon"]);
    assert_eq!(wrong.status.code(), Some(2));
    let e = String::from_utf8_lossy(&wrong.stderr);
    assert!(
        e.contains("line 2: column `time_s`: ") && e.contains("--decimal ,"),
        "{e}"
    );
    // neither: the header read as one column names the delimiter it holds
    let e = edge(&[b.to_str().unwrap()]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("separated by ';'"));
    // a decimal comma between comma-separated fields is a usage error
    let e = edge(&[a.to_str().unwrap(), "--decimal", ","]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("another field delimiter"));
    let _ = std::fs::remove_file(&a);
    let _ = std::fs::remove_file(&b);
}

/// A logger's own header names (`Time (s)`, `Temp s01 (°C)`) mapped by `--rename` give the
/// output of the run format's names to the byte, the reference read the same way; a rename that
/// matches no column, or one written without `=`, is refused in one line, exit 2.
#[test]
fn binary_maps_a_loggers_header_by_rename() {
    let (names, rows) = run();
    let logger: Vec<String> = names
        .iter()
        .map(|n| match n.strip_prefix("T_") {
            Some(s) => format!("Temp {s} (°C)"),
            None if n == "time_s" => "Time (s)".to_string(),
            None => n.to_string(),
        })
        .collect();
    let body: String = rows
        .iter()
        .take(6)
        .map(|r| r.iter().map(f64::to_string).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let dir = std::env::temp_dir();
    let (a, b) = (
        dir.join(format!("edge_named_{}.csv", std::process::id())),
        dir.join(format!("edge_logger_{}.csv", std::process::id())),
    );
    std::fs::write(&a, names.join(",") + "\n" + &body).unwrap();
    std::fs::write(&b, logger.join(",") + "\n" + &body).unwrap();
    let model = fixtures().join("mlr_rise.json");
    let edge = |args: &[&str]| Command::new(exe()).arg(&model).args(args).output().unwrap();
    let want = edge(&[a.to_str().unwrap()]);
    assert!(want.status.success());
    let renames = ["--rename", "Time (s)=time_s", "--rename", "Temp * (°C)=T_*"];
    let got = edge(&[&[b.to_str().unwrap()][..], &renames].concat());
    assert!(
        got.status.success(),
        "{}",
        String::from_utf8_lossy(&got.stderr)
    );
    assert_eq!(got.stdout, want.stdout);
    let with_ref = edge(
        &[
            &[b.to_str().unwrap(), "--reference", b.to_str().unwrap()][..],
            &renames,
        ]
        .concat(),
    );
    assert!(
        with_ref.status.success(),
        "{}",
        String::from_utf8_lossy(&with_ref.stderr)
    );
    // without the renames the model's columns are missing, and the refusal shows the option; a
    // misspelt one, or no `=`: refused
    let e = edge(&[b.to_str().unwrap()]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("mapped with --rename 'OLD=NEW'"));
    let e = edge(&[b.to_str().unwrap(), "--rename", "Tmp * (°C)=T_*"]);
    assert_eq!(e.status.code(), Some(2));
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(
        err.starts_with("thermerr-edge: error: line 1: --rename 'Tmp * (°C)=T_*' matches no column of the header (columns are: Time (s), U_spindle_rpm, Temp s01 (°C), ")
            && err.lines().count() == 1,
        "{err}"
    );
    let e = edge(&[b.to_str().unwrap(), "--rename", "Time (s)"]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("no `=`"));
    let _ = std::fs::remove_file(&a);
    let _ = std::fs::remove_file(&b);
}

/// A logger or spreadsheet that quotes its header, or every field (`"T_s01"`, `"20.5"`), is read
/// as the library reads it: the same output as the plain file. Before, the quoted header was
/// "the input has no column T_s01, ..." and nothing was predicted. A delimiter inside quotes does
/// not split the field (before, such a line had one field too many and was rejected).
#[test]
fn binary_reads_quoted_fields() {
    let (names, rows) = run();
    let q = |s: &str| format!("\"{s}\"");
    let mut plain = names.join(",") + "\n";
    let header: Vec<String> = names.iter().map(|n| q(n)).collect();
    let mut header_only = header.join(",") + "\n";
    let mut every = header.join(",") + "\n";
    // columns the model does not read, a name and cells quoted around the delimiter
    let mut spare = header.join(",") + ",\"T_x, spare\",T_y\n";
    for r in rows.iter().take(5) {
        let cells: Vec<String> = r.iter().map(|v| v.to_string()).collect();
        plain += &(cells.join(",") + "\n");
        header_only += &(cells.join(",") + "\n");
        every += &(cells.iter().map(|c| q(c)).collect::<Vec<_>>().join(",") + "\n");
        spare += &(cells.join(",") + ",2.5,\"1,5,0\"\n");
    }
    let dir = std::env::temp_dir();
    let model = fixtures().join("mlr_rise.json");
    let out = |name: &str, text: &str| {
        let path = dir.join(format!("edge_{name}_{}.csv", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let o = Command::new(exe()).arg(&model).arg(&path).output().unwrap();
        let _ = std::fs::remove_file(&path);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stdout).unwrap()
    };
    let want = out("plain", &plain);
    assert_eq!(want.lines().count(), 6);
    assert_eq!(out("quoted_header", &header_only), want);
    assert_eq!(out("quoted_all", &every), want);
    assert_eq!(out("quoted_delimiter", &spare), want);
}

/// Compiles `tests/c/NAME.c` against the staticlib cargo built next to this test's binary;
/// `None` (the test skipped, said on stderr) without gcc.
fn compile_c(name: &str) -> Option<PathBuf> {
    if Command::new("gcc").arg("--version").output().is_err() {
        eprintln!("gcc not found: C ABI test skipped");
        return None;
    }
    let dir = exe().parent().unwrap().to_path_buf();
    let lib = [
        dir.join("libthermerr_edge.a"),
        dir.join("deps/libthermerr_edge.a"),
    ]
    .into_iter()
    .find(|p| p.exists())
    .expect("cargo builds the staticlib with the tests");
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let bin = std::env::temp_dir().join(format!("te_{name}_{}", std::process::id()));
    let st = Command::new("gcc")
        .arg(manifest.join(format!("tests/c/{name}.c")))
        .arg("-I")
        .arg(manifest.join("include"))
        .arg(&lib)
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&bin)
        .status()
        .unwrap();
    assert!(st.success());
    Some(bin)
}

/// Runs a compiled C test program on `model` with `input` on its stdin.
fn run_c(bin: &Path, model: &Path, input: &str) -> std::process::Output {
    use std::io::Write;
    let mut child = Command::new(bin)
        .arg(model)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

#[test]
fn c_program_through_the_guard_prints_what_the_edge_does() {
    let Some(bin) = compile_c("guarded") else {
        return;
    };
    // y = 2·a + 3·b + 1, a guard holding for 10 s, a fallback without T_b: y = 4·a + 1
    let model = common::guarded_mlr("absolute", 10.0);
    let path = std::env::temp_dir().join(format!("te_guarded_{}.json", std::process::id()));
    std::fs::write(&path, model.to_string()).unwrap();
    let mut rows = vec![(0.0, [f64::NAN, 30.0]), (1.0, [20.0, 30.0])];
    rows.extend((2..=14).map(|t| (t as f64, [20.5, f64::NAN])));
    rows.push((15.0, [20.5, 30.5]));
    let input: String = rows
        .iter()
        .map(|(t, x)| format!("{t} {} {}\n", x[0], x[1]))
        .collect();
    let out = run_c(&bin, &path, &input);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // the same rows through the library's guard
    let mut g = Predictor::load(&path).unwrap().guarded().unwrap().unwrap();
    let want: Vec<String> = rows
        .iter()
        .map(|(t, x)| {
            let y = g.step(Some(*t), x).unwrap();
            let mut st = String::new();
            g.write_status(&mut st).unwrap();
            match y {
                Some(v) => format!("{v:?} {st}"),
                None => format!("- {st}"),
            }
        })
        .collect();
    let got: Vec<String> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            // %.17g prints 62 where {:?} prints 62.0: compare the numbers, then the status
            let (y, st) = l.split_once(' ').unwrap();
            match y.parse::<f64>() {
                Ok(v) => format!("{v:?} {st}"),
                Err(_) => l.to_string(),
            }
        })
        .collect();
    assert_eq!(got, want);
    assert_eq!(want[0], "- waiting:T_a");
    assert!(want.iter().any(|l| l.ends_with(" held:T_b")));
    assert!(want.iter().any(|l| l.ends_with(" fallback:T_b")));
    assert!(want.last().unwrap().ends_with(" ok"));
    // the 8-byte buffer: "waiting:T_a;waiting:T_b" cut to 7 bytes and a NUL
    assert_eq!(String::from_utf8_lossy(&out.stderr).trim(), "waiting");
    let _ = std::fs::remove_file(&path);
}

#[test]
fn c_program_prints_the_same_numbers() {
    let Some(bin) = compile_c("demo") else {
        return;
    };
    let (names, rows) = run();
    let model = fixtures().join("svr_rise.json");
    let p = Predictor::load(&model).unwrap();
    let idx: Vec<usize> = p
        .features()
        .unwrap()
        .iter()
        .map(|f| names.iter().position(|n| n == f).unwrap())
        .collect();
    let input: String = rows
        .iter()
        .map(|r| {
            idx.iter()
                .map(|&j| format!("{:?}", r[j]))
                .collect::<Vec<_>>()
                .join(" ")
                + "\n"
        })
        .collect();
    let out = run_c(&bin, &model, &input);
    assert!(out.status.success());
    let got: Vec<f64> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    let want = &expected()["svr_rise"];
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        // printed with %.17g: the exact double
        assert_eq!(g, w);
    }
    let _ = std::fs::remove_file(&bin);
}

#[test]
fn c_abi_reference_starts_a_stream_mid_run_as_the_whole_run_would() {
    use std::ffi::CString;
    use thermerr_edge::capi::{
        te_close, te_open, te_predict, te_reset, te_set_reference, TE_ERR_FEATURES, TE_ERR_INPUT,
        TE_OK,
    };
    let (names, rows) = run();
    let model = fixtures().join("svr_rise.json");
    let mut whole = Predictor::load(&model).unwrap();
    let idx: Vec<usize> = whole
        .features()
        .unwrap()
        .iter()
        .map(|f| names.iter().position(|n| n == f).unwrap())
        .collect();
    let x: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| idx.iter().map(|&j| r[j]).collect())
        .collect();
    let want: Vec<f64> = x.iter().map(|r| whole.predict_sample(r).unwrap()).collect();
    let path = CString::new(model.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path, buffers of the sizes passed, the model closed once
    unsafe {
        let m = te_open(path.as_ptr());
        assert!(!m.is_null());
        let n = x[0].len();
        assert_eq!(te_set_reference(m, x[0].as_ptr(), n - 1), TE_ERR_FEATURES);
        let nan = vec![f64::NAN; n];
        assert_eq!(te_set_reference(m, nan.as_ptr(), n), TE_ERR_INPUT);
        assert_eq!(te_set_reference(m, x[0].as_ptr(), n), TE_OK);
        let k = x.len() / 2;
        for pass in 0..2 {
            for (r, w) in x[k..].iter().zip(&want[k..]) {
                let mut y = f64::NAN;
                assert_eq!(te_predict(m, r.as_ptr(), n, &mut y), TE_OK);
                assert_eq!(y, *w, "pass {pass}");
            }
            te_reset(m); // the reference outlives a reset
        }
        te_close(m);
    }
}
