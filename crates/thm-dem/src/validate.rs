//! Range checks of input values, shared with the crates built on this one: each returns the
//! value or a structured [`OutOfRange`] that the caller's error enum wraps (`From`), so every
//! crate reports a bad field the same way without its own copy of the checks.

use thiserror::Error;

/// A value outside its allowed range (or not finite).
#[derive(Debug, Error, Clone, Copy, PartialEq)]
#[error("parameter `{field}` = {value} is outside the allowed range {allowed}")]
pub struct OutOfRange {
    /// Field name (serde key path).
    pub field: &'static str,
    /// The offending value.
    pub value: f64,
    /// The allowed range, in words.
    pub allowed: &'static str,
}

/// Checks that `value` is finite and within `[lo, hi]`; `allowed` states the range in words.
#[inline]
pub fn check_range(
    field: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    allowed: &'static str,
) -> Result<f64, OutOfRange> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(OutOfRange {
            field,
            value,
            allowed,
        })
    }
}

/// Checks that `value` is finite and strictly positive.
#[inline]
pub fn check_positive(field: &'static str, value: f64) -> Result<f64, OutOfRange> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(OutOfRange {
            field,
            value,
            allowed: "(0, ∞)",
        })
    }
}

impl From<OutOfRange> for crate::DemError {
    fn from(e: OutOfRange) -> Self {
        Self::InvalidParameter {
            field: e.field,
            value: e.value,
            allowed: e.allowed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_name_the_field_value_and_range() {
        assert_eq!(check_range("a", 0.5, 0.0, 1.0, "[0, 1]"), Ok(0.5));
        assert_eq!(check_range("a", 1.0, 0.0, 1.0, "[0, 1]"), Ok(1.0));
        let e = check_range("a", 1.5, 0.0, 1.0, "[0, 1]").unwrap_err();
        assert_eq!((e.field, e.value, e.allowed), ("a", 1.5, "[0, 1]"));
        assert!(check_range("a", f64::NAN, 0.0, 1.0, "[0, 1]").is_err());
        assert_eq!(check_positive("b", 2.0), Ok(2.0));
        for bad in [0.0, -1.0, f64::INFINITY, f64::NAN] {
            let e = check_positive("b", bad).unwrap_err();
            assert_eq!((e.field, e.allowed), ("b", "(0, ∞)"));
        }
        let dem: crate::DemError = check_positive("b", -1.0).unwrap_err().into();
        assert_eq!(
            dem,
            crate::DemError::InvalidParameter {
                field: "b",
                value: -1.0,
                allowed: "(0, ∞)"
            }
        );
    }
}
