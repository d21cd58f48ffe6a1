//! The hot path allocates nothing: a counting global allocator (per thread) around
//! `predict_sample` for every model kind and preprocessing in the fixtures, and around the C
//! ABI's `te_predict_guarded` through hold and fallback.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;

use thermerr_edge::Predictor;

mod common;

struct Counting;

thread_local! {
    /// Allocations made by this thread: the test harness and the other tests run on threads of
    /// their own, so only the hot path under test counts (const, no destructor: usable inside
    /// the allocator).
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
}

fn allocs() -> usize {
    ALLOCS.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        count();
        // SAFETY: forwarding the caller's layout to the system allocator
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: forwarding a pointer the system allocator gave out
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        count();
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
        let before = allocs();
        for x in &xs {
            sum += p.predict_sample(x).unwrap();
        }
        p.reset();
        sum += p.predict_sample(&xs[0]).unwrap();
        let after = allocs();
        assert_eq!(after - before, 0, "{name} allocated");
        assert!(sum.is_finite());
    }
}

#[test]
fn the_guarded_c_call_allocates_nothing() {
    use thermerr_edge::capi::{te_close, te_open, te_predict_guarded, TE_OK};
    let model = common::guarded_mlr("rise", 5.0);
    let path = std::env::temp_dir().join(format!("te_alloc_{}.json", std::process::id()));
    std::fs::write(&path, model.to_string()).unwrap();
    let c_path = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path; the model is closed once below
    let m = unsafe { te_open(c_path.as_ptr()) };
    assert!(!m.is_null());
    let mut status = [0 as std::ffi::c_char; 64];
    let mut y = 0.0;
    let before = allocs();
    for k in 0..40 {
        // T_b missing from row 10 on: ok, then held, then its fallback
        let x = [20.0 + 0.1 * k as f64, if k < 10 { 30.0 } else { f64::NAN }];
        // SAFETY: two readings, one output, a 64-byte status buffer
        let rc = unsafe {
            te_predict_guarded(m, k as f64, x.as_ptr(), 2, &mut y, status.as_mut_ptr(), 64)
        };
        assert_eq!(rc, TE_OK);
    }
    let after = allocs();
    // SAFETY: the status is NUL-terminated
    let st = unsafe { std::ffi::CStr::from_ptr(status.as_ptr()) };
    assert_eq!(st.to_str().unwrap(), "fallback:T_b");
    assert_eq!(after - before, 0, "te_predict_guarded allocated");
    // SAFETY: opened above, closed once
    unsafe { te_close(m) };
    let _ = std::fs::remove_file(&path);
}
