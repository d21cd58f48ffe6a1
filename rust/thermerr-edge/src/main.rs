//! `thermerr-edge MODEL.json [RUN.csv]`: reads CSV rows (a header first) from the file or from
//! stdin and writes `time_s,E_<axis>_pred` line by line as rows arrive, flushing each line, so it
//! can sit in a pipe from a data logger. A bad row is reported on stderr with its line number and
//! skipped. The model's feature columns are picked by name; other columns are ignored. Exit
//! status 2 for bad usage, a bad model or header, or when every data row was rejected.
//!
//! `--shape SPEC` (e.g. `limit=50,rate=2,deadband=0.5,unit=0.1,bits=16`) adds a third column,
//! `<target>_offset`: the prediction shaped into what the CNC accepts (clamped, dead band, rate
//! limited per second of `time_s` — per row without it — and quantised; `thermerr_core::shape`).
//!
//! A model file with a `guard` (`thermerr fit` writes one; `thermerr_core::guard`) adds a last
//! column, `status`: `ok`, or the sensors whose reading was faulty (missing, out of range, too
//! fast, stuck) and what was done — `held:T_x` (last good reading), `fallback:T_x` (the model
//! fitted without it), `frozen:T_x` (the last output repeated), joined by `;`. A missing reading
//! is then a fault to handle, not a rejected line. `--no-guard` ignores the guard.
//!
//! `--bench-latency N` times N predictions over the run's rows (cycling, with a reset at each
//! pass) and prints per-sample latency percentiles and the peak resident memory as JSON.
//!
//! `--reference RUN.csv` takes a model's rises from the first data row of RUN.csv (the readings
//! the error is relative to: the training run's start, or the readings when the probes were
//! zeroed) instead of the stream's own first row: for a gateway started, or restarted, in the
//! middle of a run on a warm machine.
//!
//! `--delimiter D` and `--decimal M` read a run written another way, as the library's readers
//! do (`thermerr_core::dialect`): `--delimiter ';' --decimal ,` for a spreadsheet or logger in
//! a German or French locale (`20,5`), `--delimiter tab`. `--reference` is read the same way.
//! The output is always `,` between fields and decimal points (a time written with a decimal
//! comma is written as its number). `--rename OLD=NEW` (repeated) maps a logger's header names
//! to the model's, as the library's readers do (`thermerr_core::dialect::Rename`: `Time (s)=time_s`,
//! `Temp * (°C)=T_*`, a `*` standing for any text); `--reference` is read with them too.

use std::io::{BufRead, BufReader, Write};
use std::process::ExitCode;

use thermerr_core::dialect::{Dialect, Rename};
use thermerr_core::shape::{Shaper, Shaping};
use thermerr_edge::filter::{Guarded, LineFilter};
use thermerr_edge::Predictor;

const USAGE: &str =
    "usage: thermerr-edge MODEL.json [RUN.csv] [--shape SPEC] [--no-guard] [--bench-latency N]
                     [--reference RUN.csv] [--delimiter D] [--decimal M] [--rename OLD=NEW ...]
  Reads CSV rows (header first) from RUN.csv or stdin, writes time_s,<target>_pred per row.
  A model fitted with a sensor-fault guard adds a status column (ok, held:T_x, fallback:T_x,
  frozen:T_x, joined by ;): missing, out-of-range, too fast or stuck readings are held, then
  predicted without (fallback model) or the last output repeated. --no-guard ignores the guard.
  --shape limit=50,rate=2,deadband=0.5,unit=0.1,bits=16 adds <target>_offset, the prediction
  clamped (um), held within a dead band (um), rate-limited (um/s) and quantised (um, register bits).
  --reference RUN.csv takes the rises from RUN.csv's first data row (e.g. the training run's start,
  where the error is zero) instead of the stream's first row: a gateway started mid-run.
  --delimiter ';' (or tab, comma, semicolon) and --decimal , read a run written with that field
  separator and decimal mark (20,5); the output is always , and decimal points.
  --rename 'Time (s)=time_s' --rename 'Temp * (°C)=T_*' maps a logger's header names to the
  model's (a * stands for any text and is put back where the new name has one).";

/// How the run is written: its dialect and the renames of its header's names.
struct Written {
    dialect: Dialect,
    renames: Vec<Rename>,
}

impl Written {
    /// The line filter of a header written this way.
    fn filter(&self, header: &str, p: &Predictor) -> Result<LineFilter, String> {
        LineFilter::with_renames(header, p, self.dialect, &self.renames)
    }
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("thermerr-edge: error: {msg}");
    ExitCode::from(2)
}

/// The model's readings in the first data row of the run file at `path`, picked by name as the
/// stream's are: the rise reference of `--reference`.
fn reference_row(path: &str, p: &Predictor, written: &Written) -> Result<Vec<f64>, String> {
    let f = std::fs::File::open(path).map_err(|e| format!("--reference {path}: {e}"))?;
    let mut lines = BufReader::new(f).lines();
    let header = match lines.next() {
        Some(Ok(h)) => h,
        Some(Err(e)) => return Err(format!("--reference {path}: {e}")),
        None => return Err(format!("--reference {path}: the file is empty")),
    };
    let mut filter = written
        .filter(&header, p)
        .map_err(|e| format!("--reference {path}: {e}"))?;
    match lines.next() {
        Some(Ok(line)) => filter
            .parse_row(line.trim_end_matches('\r'))
            .map(|(x, _)| x.to_vec())
            .map_err(|e| format!("--reference {path}: line 2: {e}")),
        Some(Err(e)) => Err(format!("--reference {path}: line 2: {e}")),
        None => Err(format!("--reference {path}: no data row after the header")),
    }
}

fn run(
    p: &mut Predictor,
    input: Box<dyn BufRead>,
    bench: Option<usize>,
    mut shaper: Option<Shaper>,
    use_guard: bool,
    reference: Option<Vec<f64>>,
    written: &Written,
) -> ExitCode {
    if let Some(x) = &reference {
        if let Err(e) = p.set_reference(x) {
            return fail(format!("--reference: {e}"));
        }
    }
    let mut lines = input.lines();
    let header = match lines.next() {
        Some(Ok(h)) => h,
        Some(Err(e)) => return fail(format!("cannot read the header: {e}")),
        None => return fail("the input is empty (a header row is expected)"),
    };
    let mut filter = match written.filter(&header, p) {
        Ok(f) => f,
        Err(e) => return fail(e),
    };
    let target = p.target().unwrap_or("E").to_string();
    if let Some(n) = bench {
        let mut rows = Vec::new();
        for line in lines.map_while(Result::ok) {
            if let Ok((x, _)) = filter.parse_row(line.trim_end_matches('\r')) {
                rows.push(x.to_vec());
            }
        }
        return latency(p, &rows, n);
    }
    let mut guarded = if use_guard {
        match p.guarded() {
            Ok(g) => g,
            Err(e) => return fail(e),
        }
    } else {
        None
    };
    if let (Some(g), Some(x)) = (guarded.as_mut(), &reference) {
        // the fallback models take the same reference, each for its own sensors
        if let Err(e) = g.set_reference(x) {
            return fail(format!("--reference: {e}"));
        }
    }
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut header = format!("{},{target}_pred", filter.time_name());
    if shaper.is_some() {
        header.push_str(&format!(",{target}_offset"));
    }
    if guarded.is_some() {
        header.push_str(",status");
    }
    if writeln!(out, "{header}").is_err() {
        return ExitCode::SUCCESS; // the reader went away
    }
    let step_s = guarded.as_ref().map_or(1.0, |g| g.step_s());
    let mut status = String::new();
    let mut accepted = 0usize;
    let mut rejected = 0usize;
    for (k, line) in lines.enumerate() {
        let lineno = k + 2;
        let line = match line {
            Ok(l) => l,
            Err(e) => {
                eprintln!("thermerr-edge: line {lineno}: {e}; skipped");
                rejected += 1;
                continue;
            }
        };
        let fed = match guarded.as_mut() {
            None => filter.feed(p, &line).map(|o| o.map(Guarded::Predicted)),
            Some(g) => filter.feed_guarded(g, &line),
        };
        let o = match fed {
            Ok(None) => continue,
            Ok(Some(Guarded::Predicted(o))) => o,
            Ok(Some(Guarded::Waiting)) => {
                status.clear();
                if let Some(g) = guarded.as_ref() {
                    let _ = g.write_status(&mut status);
                }
                eprintln!(
                    "thermerr-edge: line {lineno}: {status} (no good reading yet); nothing predicted"
                );
                rejected += 1;
                continue;
            }
            Err(e) => {
                eprintln!("thermerr-edge: line {lineno}: {e}; skipped");
                rejected += 1;
                continue;
            }
        };
        let ok = (|| -> std::io::Result<()> {
            match (o.time, o.t_s) {
                // a time written with a decimal comma would split the output's field
                (Some(t), Some(s)) if t.contains(',') => write!(out, "{s},{}", o.y)?,
                (Some(t), _) => write!(out, "{t},{}", o.y)?,
                (None, _) => write!(out, "{},{}", o.row, o.y)?,
            }
            if let Some(s) = shaper.as_mut() {
                // the rate limit is per second of the input's time; without one, per row of
                // step_s seconds (the guard's training step, else 1 s)
                let at = o.t_s.unwrap_or(o.row as f64 * step_s);
                write!(out, ",{}", s.apply(at, o.y))?;
            }
            if let Some(g) = guarded.as_ref() {
                status.clear();
                let _ = g.write_status(&mut status);
                write!(out, ",{status}")?;
            }
            writeln!(out)?;
            out.flush()
        })();
        if ok.is_err() {
            return ExitCode::SUCCESS;
        }
        accepted += 1;
    }
    if accepted == 0 && rejected > 0 {
        // nothing came out: the input does not fit the model, which is not a success
        return fail(format!(
            "every data row ({rejected}) was rejected: no compensation was computed"
        ));
    }
    ExitCode::SUCCESS
}

/// Per-sample latency over `n` predictions, cycling through `rows`.
fn latency(p: &mut Predictor, rows: &[Vec<f64>], n: usize) -> ExitCode {
    if rows.is_empty() {
        return fail("no valid rows to time");
    }
    let lat = match p.latency(rows, n) {
        Ok(l) => l,
        Err(e) => return fail(e),
    };
    let rss_kib = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1).map(str::to_string))
        })
        .unwrap_or_else(|| "null".into());
    println!(
        "{{\"kind\": \"{}\", \"samples\": {n}, \"p50_ns\": {}, \"p99_ns\": {}, \"mean_ns\": {:.1}, \"max_rss_kib\": {rss_kib}, \"checksum\": {}}}",
        p.kind(),
        lat.p50_ns,
        lat.p99_ns,
        lat.mean_ns,
        lat.checksum
    );
    ExitCode::SUCCESS
}

fn main() -> ExitCode {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut bench = None;
    if let Some(k) = args.iter().position(|a| a == "--bench-latency") {
        match args.get(k + 1).and_then(|v| v.parse::<usize>().ok()) {
            Some(n) if n > 0 => bench = Some(n),
            _ => return fail("--bench-latency takes a positive number of samples"),
        }
        args.drain(k..k + 2);
    }
    let mut shaper = None;
    if let Some(k) = args.iter().position(|a| a == "--shape") {
        let spec = match args.get(k + 1) {
            Some(v) => v.clone(),
            None => return fail("--shape takes settings, e.g. limit=50,rate=2,unit=0.1"),
        };
        match Shaping::parse(&spec).and_then(Shaper::new) {
            Ok(s) => shaper = Some(s),
            Err(e) => return fail(format!("--shape {spec}: {e}")),
        }
        args.drain(k..k + 2);
    }
    let mut reference_path = None;
    if let Some(k) = args.iter().position(|a| a == "--reference") {
        match args.get(k + 1) {
            Some(v) => reference_path = Some(v.clone()),
            None => return fail("--reference takes a run file, e.g. the training run"),
        }
        args.drain(k..k + 2);
    }
    let mut dialect_args = [",".to_string(), ".".to_string()];
    for (flag, slot) in ["--delimiter", "--decimal"].into_iter().zip(0..) {
        if let Some(k) = args.iter().position(|a| a == flag) {
            match args.get(k + 1) {
                Some(v) => dialect_args[slot] = v.clone(),
                None => {
                    return fail(format!(
                        "{flag} takes a value, e.g. {flag} {}",
                        [";", ","][slot]
                    ))
                }
            }
            args.drain(k..k + 2);
        }
    }
    let dialect = match Dialect::new(&dialect_args[0], &dialect_args[1]) {
        Ok(d) => d,
        Err(e) => return fail(e),
    };
    let mut renames = Vec::new();
    while let Some(k) = args.iter().position(|a| a == "--rename") {
        match args.get(k + 1).map(|v| Rename::parse(v)) {
            Some(Ok(r)) => renames.push(r),
            Some(Err(e)) => return fail(e),
            None => return fail("--rename takes OLD=NEW, e.g. --rename 'Temp * (°C)=T_*'"),
        }
        args.drain(k..k + 2);
    }
    let written = Written { dialect, renames };
    let use_guard = match args.iter().position(|a| a == "--no-guard") {
        Some(k) => {
            args.remove(k);
            false
        }
        None => true,
    };
    if args.iter().any(|a| a == "-h" || a == "--help") {
        println!("{USAGE}");
        return ExitCode::SUCCESS;
    }
    if args.is_empty() || args.len() > 2 {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    }
    let mut p = match Predictor::load(&args[0]) {
        Ok(p) => p,
        Err(e) => return fail(e),
    };
    let input: Box<dyn BufRead> = match args.get(1) {
        Some(path) => match std::fs::File::open(path) {
            Ok(f) => Box::new(BufReader::new(f)),
            Err(e) => return fail(format!("{path}: {e}")),
        },
        None => Box::new(BufReader::new(std::io::stdin())),
    };
    let reference = match reference_path
        .as_deref()
        .map(|path| reference_row(path, &p, &written))
    {
        None => None,
        Some(Ok(x)) => Some(x),
        Some(Err(e)) => return fail(e),
    };
    run(&mut p, input, bench, shaper, use_guard, reference, &written)
}
