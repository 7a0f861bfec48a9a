//! Errors as values: every message names what was wrong and where (parameter, particle,
//! scene key or line), so a user can act on it.

use thiserror::Error;

/// A contact-model parameter that breaks one of the model's rules.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("invalid parameter `{param}`: {message}")]
pub struct ParamError {
    /// The parameter's name as written in scenes and on the command line.
    pub param: &'static str,
    /// What is wrong and which rule it breaks.
    pub message: String,
}

impl ParamError {
    /// A parameter error for `param` with the rule it breaks.
    pub fn new(param: &'static str, message: impl Into<String>) -> Self {
        Self {
            param,
            message: message.into(),
        }
    }
}

/// Every error the library hands back.
#[derive(Debug, Error)]
pub enum PowderError {
    /// A contact-model parameter that breaks a rule.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A scene file that cannot be read, parsed or validated.
    #[error("{0}")]
    Scene(String),
    /// A run that cannot go on (bad state detected while stepping).
    #[error("{0}")]
    Run(String),
    /// An I/O failure, with what was being read or written.
    #[error("{context}: {source}")]
    Io {
        /// What was being done, e.g. the file path and operation.
        context: String,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
}

impl PowderError {
    /// A [`PowderError::Io`] with `context` describing what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Self::Io {
            context: context.into(),
            source,
        }
    }
}

/// The library's result type, [`PowderError`] by default.
pub type Result<T, E = PowderError> = std::result::Result<T, E>;

/// `x` for a message: as written where that is short, in `e` notation beyond ~10¹⁶ and
/// below 10⁻⁵ (where `{}` would print hundreds of digits).
pub fn num(x: f64) -> impl std::fmt::Display {
    struct Num(f64);
    impl std::fmt::Display for Num {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            let a = self.0.abs();
            if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
                write!(f, "{:e}", self.0)
            } else {
                write!(f, "{}", self.0)
            }
        }
    }
    Num(x)
}

/// `x` for a message with `decimals` digits after the point: fixed where that is short,
/// in `e` notation beyond 10⁶ and below 10⁻³ (where `{:.4}` prints hundreds of digits, or
/// 0.0000).
pub fn fixed(x: f64, decimals: usize) -> String {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-3..1e6).contains(&a) {
        format!("{x:.decimals$e}")
    } else {
        format!("{x:.decimals$}")
    }
}

/// A limit `x` in `e` notation with `decimals` digits after the point, rounded down, so that
/// a value typed from the advice "use dt <= ..." is within the limit.
pub fn sci_at_most(x: f64, decimals: usize) -> String {
    let s = format!("{x:.decimals$e}");
    match s.parse::<f64>() {
        Ok(y) if y > x && x > 0.0 && x.is_finite() => {
            // x cut to its digits (the unit of the last one at x's own exponent, read from
            // its shortest `e` form: log10 rounds up just below a power of ten), one unit
            // lower where the quotient's rounding left it above x
            let exponent = exponent_of(x);
            let unit = 10f64.powi(exponent - decimals as i32);
            let cut = (x / unit).floor();
            let t = format!("{:.decimals$e}", cut * unit);
            match t.parse::<f64>() {
                Ok(z) if z > x => format!("{:.decimals$e}", (cut - 1.0) * unit),
                _ => t,
            }
        }
        _ => s,
    }
}

/// The decimal exponent of `x` as `{:e}` writes it.
fn exponent_of(x: f64) -> i32 {
    let s = format!("{x:e}");
    s.split_once('e')
        .and_then(|(_, e)| e.parse().ok())
        .unwrap_or(0)
}

/// Checks that a value is finite, naming the parameter otherwise.
pub fn require_finite(param: &'static str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParamError::new(
            param,
            format!("must be a finite number, got {value}"),
        ))
    }
}

/// Checks value > 0 (and finite).
pub fn require_positive(param: &'static str, value: f64, what: &str) -> Result<f64, ParamError> {
    require_finite(param, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(
            param,
            format!("{what} must be > 0, got {value}"),
        ))
    }
}

/// Checks value >= 0 (and finite).
pub fn require_non_negative(
    param: &'static str,
    value: f64,
    what: &str,
) -> Result<f64, ParamError> {
    require_finite(param, value)?;
    if value >= 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(
            param,
            format!("{what} must be >= 0, got {value}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The advice's limit, typed back, is within the limit, and at most one unit of its last
    /// digit below it (`{:.3e}` rounds 1.93974e-10 up to 1.940e-10).
    #[test]
    fn a_limit_printed_as_advice_is_rounded_down() {
        assert_eq!(sci_at_most(1.93974e-10, 3), "1.939e-10");
        assert_eq!(fixed(2.5, 3), "2.500");
        assert_eq!(fixed(3.3e300, 3), "3.300e300");
        assert_eq!(fixed(1e-300, 4), "1.0000e-300");
        assert_eq!(sci_at_most(1.93944e-10, 3), "1.939e-10");
        assert_eq!(sci_at_most(9.99996e-5, 4), "9.9999e-5");
        // just below a power of ten (log10 rounds to the power there)
        let below = 0.0009999999999999998;
        assert_eq!(sci_at_most(below, 3), "9.999e-4");
        assert_eq!(sci_at_most(below, 0), "9e-4");
        let mut x = 1.0e-12;
        while x < 1e3 {
            for d in [0, 3, 4] {
                let y: f64 = sci_at_most(x, d).parse().unwrap();
                let unit = 10f64.powi(exponent_of(x) - d as i32);
                assert!(y <= x && x - y <= 1.000001 * unit, "{x:e} -> {y:e}");
            }
            x *= 1.0137;
        }
    }
}
