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
