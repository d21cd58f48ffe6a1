//! The hot path allocates nothing: a counting global allocator around `predict_sample` for every
//! model kind and preprocessing in the fixtures.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use thermerr_edge::Predictor;

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: forwarding the caller's layout to the system allocator
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: forwarding a pointer the system allocator gave out
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: as above
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn predict_sample_allocates_nothing() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures");
    for name in [
        "mlr_rise",
        "rbf_ols_minmax_rise",
        "rbf_exact_ago",
        "svr_rise",
    ] {
        let mut p = Predictor::load(dir.join(format!("{name}.json"))).unwrap();
        let xs: Vec<[f64; 4]> = (0..100)
            .map(|k| {
                let t = k as f64 * 0.1;
                [20.0 + t, 20.5 + 0.5 * t, 20.2 + 0.2 * t, 20.1 + 0.1 * t]
            })
            .collect();
        let mut sum = 0.0;
        let before = ALLOCS.load(Ordering::SeqCst);
        for x in &xs {
            sum += p.predict_sample(x).unwrap();
        }
        p.reset();
        sum += p.predict_sample(&xs[0]).unwrap();
        let after = ALLOCS.load(Ordering::SeqCst);
        assert_eq!(after - before, 0, "{name} allocated");
        assert!(sum.is_finite());
    }
}
