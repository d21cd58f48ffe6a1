//! exp, ln, log₂, log₁₀ and pow whose bits do not depend on the machine.
//!
//! `f64::exp` and friends call the C library, and glibc picks its kernels by the CPU (an FMA
//! variant where the CPU has FMA, which rounds some results differently) and has changed them
//! between versions (2.28 rewrote exp, log and pow; the wheel runs on glibc 2.17 and newer).
//! The thermal network's calibration and diagnosis decide verdicts on differences that a last
//! bit can flip on a real run, so they take these functions from the `libm` crate (musl's
//! algorithms in pure Rust, compiled without FMA): the same bits on every machine. Square roots
//! need nothing: IEEE 754 rounds them exactly everywhere.

/// eˣ
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// The natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// log₂ x
#[inline]
pub fn log2(x: f64) -> f64 {
    libm::log2(x)
}

/// log₁₀ x
#[inline]
pub fn log10(x: f64) -> f64 {
    libm::log10(x)
}

/// xʸ
#[inline]
pub fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agree_with_the_c_library_to_an_ulp_or_two() {
        for k in 0..2000 {
            let x = -40.0 + 80.0 * k as f64 / 2000.0;
            let (a, b) = (exp(x), x.exp());
            assert!((a - b).abs() <= 2.0 * f64::EPSILON * b, "exp({x})");
            let y = 1e-6 + 1e4 * k as f64 / 2000.0;
            let (a, b) = (ln(y), y.ln());
            assert!(
                (a - b).abs() <= 2.0 * f64::EPSILON * b.abs().max(1.0),
                "ln({y})"
            );
            let (a, b) = (powf(y, 0.37), y.powf(0.37));
            assert!((a - b).abs() <= 2.0 * f64::EPSILON * b, "pow({y}, 0.37)");
        }
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(ln(1.0), 0.0);
        for k in -30..30 {
            assert_eq!(log2(2f64.powi(k)), k as f64);
        }
        assert_eq!(log10(1000.0), 3.0);
        assert!(ln(-1.0).is_nan());
    }
}
