//! The C ABI (`include/thermerr_edge.h`): open a model file, predict one sample into the caller's
//! buffer (through the file's sensor-fault guard with `te_predict_guarded`), reset, close;
//! negative status codes and a thread-local message for failures. No Rust panic crosses this
//! boundary.

use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::{GuardedPredictor, Predictor};

/// Status codes of `te_predict` (also in the header).
pub const TE_OK: c_int = 0;
pub const TE_ERR_NULL: c_int = -1;
pub const TE_ERR_FEATURES: c_int = -2;
pub const TE_ERR_INPUT: c_int = -3;
pub const TE_ERR_PANIC: c_int = -4;
/// `te_predict_guarded` on a model file without a guard.
pub const TE_ERR_NOGUARD: c_int = -5;
/// `te_predict_guarded`: no prediction yet (a sensor has not given a good reading).
pub const TE_WAITING: c_int = 1;

/// An opened model (opaque to C), with its guard when the file has one.
pub struct TeModel {
    p: Predictor,
    g: Option<GuardedPredictor>,
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_error(msg: &str) {
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

/// Opens a model file; NULL on failure (see `te_last_error`).
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn te_open(path: *const c_char) -> *mut TeModel {
    if path.is_null() {
        set_error("te_open: path is NULL");
        return std::ptr::null_mut();
    }
    let r = catch_unwind(|| {
        // SAFETY: the caller passes a NUL-terminated string
        let s = unsafe { CStr::from_ptr(path) }
            .to_string_lossy()
            .into_owned();
        let p = Predictor::load(s)?;
        let g = p.guarded()?;
        Ok::<_, crate::EdgeError>(TeModel { p, g })
    });
    match r {
        Ok(Ok(m)) => Box::into_raw(Box::new(m)),
        Ok(Err(e)) => {
            set_error(&e.to_string());
            std::ptr::null_mut()
        }
        Err(_) => {
            set_error("te_open: internal error (panic)");
            std::ptr::null_mut()
        }
    }
}

/// Number of features the model takes (-1 if `m` is NULL).
///
/// # Safety
/// `m` must be NULL or a pointer returned by `te_open` and not yet closed.
#[no_mangle]
pub unsafe extern "C" fn te_n_features(m: *const TeModel) -> c_int {
    // SAFETY: per the contract above
    match unsafe { m.as_ref() } {
        Some(m) => m.p.n_inputs() as c_int,
        None => TE_ERR_NULL,
    }
}

/// Predicts the next sample of the run: `n` readings at `x` (in the model's feature order), the
/// prediction written to `*out`. Returns 0, or a negative code: -1 a NULL argument, -2 the wrong
/// number of features, -3 a non-finite reading, -4 an internal error. Allocates nothing on
/// success.
///
/// # Safety
/// `m` as for `te_n_features`; `x` must point to `n` doubles and `out` to one writable double.
#[no_mangle]
pub unsafe extern "C" fn te_predict(
    m: *mut TeModel,
    x: *const f64,
    n: usize,
    out: *mut f64,
) -> c_int {
    if m.is_null() || x.is_null() || out.is_null() {
        set_error("te_predict: NULL argument");
        return TE_ERR_NULL;
    }
    let r = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: per the contract above
        let (m, xs) = unsafe { (&mut *m, std::slice::from_raw_parts(x, n)) };
        if n != m.p.n_inputs() {
            set_error(&format!(
                "te_predict: the model takes {} features, got {n}",
                m.p.n_inputs()
            ));
            return TE_ERR_FEATURES;
        }
        match m.p.predict_sample(xs) {
            Ok(v) => {
                // SAFETY: per the contract above
                unsafe { *out = v };
                TE_OK
            }
            Err(e) => {
                set_error(&e.to_string());
                TE_ERR_INPUT
            }
        }
    }));
    r.unwrap_or_else(|_| {
        set_error("te_predict: internal error (panic)");
        TE_ERR_PANIC
    })
}

/// 1 if the model file has a sensor-fault guard, 0 if not, -1 if `m` is NULL.
///
/// # Safety
/// `m` as for `te_n_features`.
#[no_mangle]
pub unsafe extern "C" fn te_has_guard(m: *const TeModel) -> c_int {
    // SAFETY: per the contract above
    match unsafe { m.as_ref() } {
        Some(m) => c_int::from(m.g.is_some()),
        None => TE_ERR_NULL,
    }
}

/// Writes UTF-8 text into a C buffer, truncating, always leaving room for the final NUL.
struct CBuf<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl std::fmt::Write for CBuf<'_> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let room = self.buf.len().saturating_sub(1 + self.len);
        let k = s.len().min(room);
        self.buf[self.len..self.len + k].copy_from_slice(&s.as_bytes()[..k]);
        self.len += k;
        Ok(())
    }
}

/// Predicts the next sample through the model file's guard, as `thermerr-edge` does: `n` raw
/// readings at `x` (NaN for a missing one: a fault to handle, not an error), at time `t`
/// seconds (NaN: the row count times the guard's step). Returns 0 with the prediction in
/// `*out`; 1 (TE_WAITING) when nothing can be predicted yet (a sensor has not read well since
/// the start), `*out` untouched; or a negative code (-5: the file has no guard). When `status`
/// is not NULL, the row's status (`ok`, `held:T_x`, `fallback:T_x`, `frozen:T_x`,
/// `waiting:T_x`, joined by `;`) is written there, truncated to `status_len` bytes with the
/// final NUL. Allocates nothing.
///
/// # Safety
/// `m` as for `te_n_features`; `x` must point to `n` doubles, `out` to one writable double,
/// and `status` be NULL or point to `status_len` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn te_predict_guarded(
    m: *mut TeModel,
    t: f64,
    x: *const f64,
    n: usize,
    out: *mut f64,
    status: *mut c_char,
    status_len: usize,
) -> c_int {
    if m.is_null() || x.is_null() || out.is_null() {
        set_error("te_predict_guarded: NULL argument");
        return TE_ERR_NULL;
    }
    let r = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: per the contract above
        let (m, xs) = unsafe { (&mut *m, std::slice::from_raw_parts(x, n)) };
        let Some(g) = m.g.as_mut() else {
            set_error("te_predict_guarded: the model file has no guard (thermerr fit writes one)");
            return TE_ERR_NOGUARD;
        };
        if n != m.p.n_inputs() {
            set_error(&format!(
                "te_predict_guarded: the model takes {} features, got {n}",
                m.p.n_inputs()
            ));
            return TE_ERR_FEATURES;
        }
        let y = match g.step(t.is_finite().then_some(t), xs) {
            Ok(y) => y,
            Err(e) => {
                set_error(&e.to_string());
                return TE_ERR_INPUT;
            }
        };
        if !status.is_null() && status_len > 0 {
            // SAFETY: per the contract above
            let buf = unsafe { std::slice::from_raw_parts_mut(status.cast::<u8>(), status_len) };
            let mut w = CBuf { buf, len: 0 };
            let _ = g.write_status(&mut w);
            w.buf[w.len] = 0;
        }
        match y {
            Some(v) => {
                // SAFETY: per the contract above
                unsafe { *out = v };
                TE_OK
            }
            None => TE_WAITING,
        }
    }));
    r.unwrap_or_else(|_| {
        set_error("te_predict_guarded: internal error (panic)");
        TE_ERR_PANIC
    })
}

/// Fixes the readings the rises are taken from (`n` of them at `x`, in the model's feature
/// order), for `te_predict` and `te_predict_guarded` alike, instead of each run's first sample:
/// a gateway started in the middle of a run on a warm machine (`thermerr-edge --reference`).
/// Kept across `te_reset`. Returns 0, or -1 a NULL argument, -2 the wrong number of features,
/// -3 a non-finite reading or a model on absolute readings, -4 an internal error.
///
/// # Safety
/// `m` as for `te_n_features`; `x` must point to `n` doubles.
#[no_mangle]
pub unsafe extern "C" fn te_set_reference(m: *mut TeModel, x: *const f64, n: usize) -> c_int {
    if m.is_null() || x.is_null() {
        set_error("te_set_reference: NULL argument");
        return TE_ERR_NULL;
    }
    let r = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: per the contract above
        let (m, xs) = unsafe { (&mut *m, std::slice::from_raw_parts(x, n)) };
        if n != m.p.n_inputs() {
            set_error(&format!(
                "te_set_reference: the model takes {} features, got {n}",
                m.p.n_inputs()
            ));
            return TE_ERR_FEATURES;
        }
        let set = m.p.set_reference(xs).and_then(|()| match &mut m.g {
            Some(g) => g
                .set_reference(xs)
                .map_err(|e| crate::EdgeError::Input(e.to_string())),
            None => Ok(()),
        });
        match set {
            Ok(()) => TE_OK,
            Err(e) => {
                set_error(&e.to_string());
                TE_ERR_INPUT
            }
        }
    }));
    r.unwrap_or_else(|_| {
        set_error("te_set_reference: internal error (panic)");
        TE_ERR_PANIC
    })
}

/// Starts a new run (forgets the first sample and accumulated state).
///
/// # Safety
/// `m` as for `te_n_features`.
#[no_mangle]
pub unsafe extern "C" fn te_reset(m: *mut TeModel) {
    // SAFETY: per the contract above
    if let Some(m) = unsafe { m.as_mut() } {
        m.p.reset();
        if let Some(g) = &mut m.g {
            g.reset();
        }
    }
}

/// Frees a model opened by `te_open` (NULL is ignored).
///
/// # Safety
/// `m` must be NULL or a pointer returned by `te_open`, closed at most once.
#[no_mangle]
pub unsafe extern "C" fn te_close(m: *mut TeModel) {
    if !m.is_null() {
        // SAFETY: per the contract above
        drop(unsafe { Box::from_raw(m) });
    }
}

/// The message of the last failure on this thread ("" if none). Valid until the next call on
/// this thread.
#[no_mangle]
pub extern "C" fn te_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}
