//! Bounded nonlinear least squares: Levenberg–Marquardt on box-constrained parameters.
//!
//! Bounds are removed by a smooth change of variables, p = lo + (hi − lo)·σ(θ) with σ the
//! logistic function, and Marquardt's damped Gauss–Newton step is taken in θ. The Jacobian is by
//! forward differences, its columns evaluated in parallel (rayon): the residual function must be
//! `Sync`. This is what calibration of the thermal network runs; it is generic and tested on its
//! own here.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::linalg::{dot, gram, Cholesky};
use crate::portable;

/// Options of [`least_squares`].
#[derive(Clone, Debug)]
pub struct LmOptions {
    pub max_iter: usize,
    /// Stop when the relative decrease of the cost over an accepted step is below this.
    pub ftol: f64,
    /// Stop when the absolute decrease of the cost (½·Σr²) over an accepted step is below this
    /// (0: never). For residuals normalised by their noise, a decrease far below one is
    /// statistically nothing.
    pub atol: f64,
    /// Stop when the step in θ is below this (max-norm).
    pub xtol: f64,
    /// Stop when the max-norm of the gradient in θ is below this.
    pub gtol: f64,
    /// Initial damping factor λ (relative to the diagonal of JᵀJ).
    pub lambda0: f64,
    /// Relative step of the forward differences in θ.
    pub diff_step: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iter: 100,
            ftol: 1e-10,
            atol: 0.0,
            xtol: 1e-10,
            gtol: 1e-12,
            lambda0: 1e-3,
            diff_step: 1e-6,
        }
    }
}

/// Outcome of [`least_squares`].
#[derive(Clone, Debug)]
pub struct LmResult {
    /// The parameters at the solution (inside the bounds).
    pub x: Vec<f64>,
    /// Residuals at the solution.
    pub residuals: Vec<f64>,
    /// ½ Σ r².
    pub cost: f64,
    pub n_iter: usize,
    pub n_eval: usize,
    pub converged: bool,
    /// Why it stopped.
    pub message: String,
}

fn sigmoid(t: f64) -> f64 {
    if t >= 0.0 {
        1.0 / (1.0 + portable::exp(-t))
    } else {
        let e = portable::exp(t);
        e / (1.0 + e)
    }
}

fn to_p(theta: &[f64], lo: &[f64], hi: &[f64]) -> Vec<f64> {
    theta
        .iter()
        .zip(lo.iter().zip(hi))
        .map(|(t, (l, h))| l + (h - l) * sigmoid(*t))
        .collect()
}

fn to_theta(p: &[f64], lo: &[f64], hi: &[f64]) -> Vec<f64> {
    p.iter()
        .zip(lo.iter().zip(hi))
        .map(|(v, (l, h))| {
            // keep starts off the flat tails of the logistic, where the gradient vanishes
            let s = ((v - l) / (h - l)).clamp(1e-6, 1.0 - 1e-6);
            portable::ln(s / (1.0 - s))
        })
        .collect()
}

fn half_sq(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|v| v * v).sum::<f64>()
}

/// Minimises ½‖f(p)‖² subject to `lo ≤ p ≤ hi` (strictly inside: every `lo < hi`), from `x0`.
///
/// `f` returns the residual vector, always of the same length, or an error (which aborts the
/// search; a non-finite residual counts as a failed trial step instead).
pub fn least_squares<F>(
    f: F,
    x0: &[f64],
    lo: &[f64],
    hi: &[f64],
    opts: &LmOptions,
) -> Result<LmResult>
where
    F: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let n = x0.len();
    if lo.len() != n || hi.len() != n {
        return Err(Error::Shape(
            "least_squares: x0, lo and hi differ in length".into(),
        ));
    }
    if n == 0 {
        return Err(Error::Shape("least_squares: no parameters".into()));
    }
    for j in 0..n {
        if !lo[j].is_finite() || !hi[j].is_finite() || !x0[j].is_finite() || lo[j] >= hi[j] {
            return Err(Error::param(
                "bounds",
                format!(
                    "parameter {j}: need finite lo < hi and a finite start, got {} <= {} <= {}",
                    lo[j], x0[j], hi[j]
                ),
            ));
        }
    }
    let mut theta = to_theta(x0, lo, hi);
    let mut r = f(&to_p(&theta, lo, hi))?;
    let m = r.len();
    if m == 0 || r.iter().any(|v| !v.is_finite()) {
        return Err(Error::Numerical(
            "the residuals at the start are empty or not finite".into(),
        ));
    }
    let mut cost = half_sq(&r);
    let mut n_eval = 1;
    let mut lambda = opts.lambda0;
    let mut message = String::from("reached max_iter");
    let mut converged = false;
    let mut iter = 0;
    // one Jacobian for every iteration, column-major: each column is overwritten whole (its
    // length is checked)
    let mut jac = vec![0.0; m * n];
    while iter < opts.max_iter {
        iter += 1;
        crate::interrupt::check()?;
        // forward-difference Jacobian in θ, columns in parallel, each written in place (a
        // non-finite difference counts as no influence); the first failing column's error wins
        let done: Vec<Result<()>> = jac
            .par_chunks_mut(m)
            .enumerate()
            .map(|(j, col)| {
                let h = opts.diff_step * (1.0 + theta[j].abs());
                let mut t = theta.clone();
                t[j] += h;
                let rj = f(&to_p(&t, lo, hi))?;
                if rj.len() != m {
                    return Err(Error::Shape("the residual vector changed length".into()));
                }
                for ((d, a), b) in col.iter_mut().zip(&rj).zip(&r) {
                    let v = (a - b) / h;
                    *d = if v.is_finite() { v } else { 0.0 };
                }
                Ok(())
            })
            .collect();
        n_eval += n;
        done.into_iter().collect::<Result<()>>()?;
        // JᵀJ and Jᵀr in a fixed order of operations: the same steps on every CPU
        let cols: Vec<&[f64]> = jac.chunks_exact(m).collect();
        let jtj = gram(&cols, m)?;
        let g: Vec<f64> = cols.iter().map(|c| dot(c, &r)).collect();
        let gmax = g.iter().map(|v| v.abs()).fold(0.0, f64::max);
        if gmax < opts.gtol {
            message = "gradient below gtol".into();
            converged = true;
            break;
        }
        // Marquardt's diagonal scaling, floored relative to the largest entry so that
        // parameters with (almost) no influence do not make the damped system singular
        let dmax = (0..n).map(|j| jtj[j * n + j]).fold(0.0_f64, f64::max);
        let floor = (dmax * 1e-10).max(1e-300);
        let mut accepted = false;
        for _ in 0..40 {
            let mut a = jtj.clone();
            for j in 0..n {
                a[j * n + j] += lambda * jtj[j * n + j].max(floor);
            }
            let Some(chol) = Cholesky::new(&a, n) else {
                lambda *= 4.0;
                continue;
            };
            let neg_g: Vec<f64> = g.iter().map(|v| -v).collect();
            let delta = chol.solve(&neg_g);
            let trial: Vec<f64> = (0..n).map(|j| theta[j] + delta[j]).collect();
            let rt = f(&to_p(&trial, lo, hi))?;
            n_eval += 1;
            let ct = if rt.len() == m && rt.iter().all(|v| v.is_finite()) {
                half_sq(&rt)
            } else {
                f64::INFINITY
            };
            if ct < cost {
                let step = delta.iter().map(|v| v.abs()).fold(0.0, f64::max);
                let rel = (cost - ct) / cost.max(f64::MIN_POSITIVE);
                let cost_before = cost;
                theta = trial;
                r = rt;
                cost = ct;
                lambda = (lambda / 3.0).max(1e-12);
                accepted = true;
                if rel < opts.ftol {
                    message = "cost decrease below ftol".into();
                    converged = true;
                } else if cost_before - ct < opts.atol {
                    message = "cost decrease below atol".into();
                    converged = true;
                } else if step < opts.xtol {
                    message = "step below xtol".into();
                    converged = true;
                }
                break;
            }
            lambda *= 2.0;
        }
        if !accepted {
            message = "no step decreases the cost (a local minimum at working precision)".into();
            converged = true;
            break;
        }
        if converged {
            break;
        }
    }
    Ok(LmResult {
        x: to_p(&theta, lo, hi),
        residuals: r,
        cost,
        n_iter: iter,
        n_eval,
        converged,
        message,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn rosenbrock() {
        let f = |p: &[f64]| Ok(vec![10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]]);
        let opts = LmOptions {
            max_iter: 500,
            ..Default::default()
        };
        let r = least_squares(f, &[-1.2, 1.0], &[-5.0, -5.0], &[5.0, 5.0], &opts).unwrap();
        assert_relative_eq!(r.x[0], 1.0, epsilon = 1e-6);
        assert_relative_eq!(r.x[1], 1.0, epsilon = 1e-6);
    }

    #[test]
    fn exponential_fit() {
        // y = a·exp(−t/τ) + c, noiseless: recovers the parameters
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 10.0).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|t| 3.0 * portable::exp(-t / 120.0) + 0.5)
            .collect();
        let f = |p: &[f64]| {
            Ok(t.iter()
                .zip(&y)
                .map(|(t, y)| p[0] * portable::exp(-t / p[1]) + p[2] - y)
                .collect())
        };
        let r = least_squares(
            f,
            &[1.0, 50.0, 0.0],
            &[0.0, 1.0, -10.0],
            &[10.0, 1000.0, 10.0],
            &LmOptions::default(),
        )
        .unwrap();
        assert_relative_eq!(r.x[0], 3.0, epsilon = 1e-6);
        assert_relative_eq!(r.x[1], 120.0, epsilon = 1e-4);
        assert_relative_eq!(r.x[2], 0.5, epsilon = 1e-6);
    }

    #[test]
    fn respects_bounds() {
        // unconstrained optimum at 3, bound at 2
        let f = |p: &[f64]| Ok(vec![p[0] - 3.0]);
        let r = least_squares(f, &[0.0], &[-1.0], &[2.0], &LmOptions::default()).unwrap();
        assert!(r.x[0] <= 2.0 && r.x[0] > 1.99, "{}", r.x[0]);
    }

    #[test]
    fn refuses_bad_bounds() {
        let f = |p: &[f64]| Ok(vec![p[0]]);
        assert!(least_squares(f, &[0.0], &[1.0], &[0.0], &LmOptions::default()).is_err());
    }
}
