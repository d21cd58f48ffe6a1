//! Any text through the machine reader: a refusal, or a machine that writes back to TOML which
//! reads back equal, and that simulates a short run of its own columns (Ok or Err), never a
//! panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use thermerr_core::run::{NanPolicy, Run};
use thermerr_core::thermal::{simulate, Init, Machine, RunView};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(m) = Machine::from_toml(text, "<fuzz>") else {
        return;
    };
    let back = m.to_toml().expect("a validated machine writes as TOML");
    let again = Machine::from_toml(&back, "<fuzz: written back>")
        .unwrap_or_else(|e| panic!("written back, it does not load: {e}\n{back}"));
    assert_eq!(m, again, "written back, it loads different:\n{back}");
    // keep the simulation cheap: the reader is under test, not the solver's speed
    if m.nodes.len() > 12 {
        return;
    }
    let mut names = vec!["time_s".to_string()];
    for (c, _) in m.columns() {
        if !names.contains(&c) {
            names.push(c);
        }
    }
    let columns = names
        .iter()
        .enumerate()
        .map(|(k, _)| {
            (0..4)
                .map(|i| {
                    if k == 0 {
                        60.0 * i as f64
                    } else {
                        20.0 + i as f64
                    }
                })
                .collect()
        })
        .collect();
    if let Ok(run) = Run::from_columns("<fuzz run>", names, columns, NanPolicy::Error, None) {
        let _ = simulate(&m, &RunView::new(&run), &Init::FirstReading);
    }
});
