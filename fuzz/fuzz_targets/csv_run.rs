//! Any bytes through the run reader, under each NaN policy: a refusal or a run that keeps the
//! reader's promises (finite, strictly increasing time; finite, equal-length columns), never a
//! panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use thermerr_core::run::{NanPolicy, Run};

fuzz_target!(|data: &[u8]| {
    for nan in [NanPolicy::Error, NanPolicy::Drop, NanPolicy::Interpolate] {
        let Ok(run) = Run::from_csv_reader(data, "<fuzz>", nan) else {
            continue;
        };
        let n = run.len();
        assert!(n > 0, "a run with no rows");
        assert!(run.time_s.iter().all(|t| t.is_finite()), "{:?}", run.time_s);
        assert!(
            run.time_s.windows(2).all(|w| w[0] < w[1]),
            "{:?}",
            run.time_s
        );
        assert_eq!(run.names.len(), run.columns.len());
        for (name, c) in run.names.iter().zip(&run.columns) {
            assert_eq!(c.len(), n, "{name}");
            assert!(
                c.iter().all(|v| v.is_finite()),
                "{nan:?}: column {name} = {c:?}"
            );
        }
        let m = run.matrix(&run.names).expect("its own columns");
        assert_eq!(m.len(), n * run.names.len());
    }
});
