//! Parameters of the MPM×DEM coupling, as read from a file, validated once into
//! [`MultiscaleConfig`].

use serde::{Deserialize, Serialize};
use thm_rve::{RveConfig, RveParams};

use super::error::MultiscaleError;

/// The rule for the RVE's DEM time (see the module docs): each MPM step of `Δt` runs
/// `N = ⌈Δt / (c √(s m_min / k_n))⌉` DEM steps of `Δt / N` on disks whose masses and
/// inertias are `s` times their physical values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemTimeRule {
    /// `c`: the DEM step as a fraction of `√(s m_min / k_n)`, in `[1e-3, 0.5]` (0.2 is the
    /// fraction `thm-rve` consolidates with).
    pub step_fraction: f64,
    /// `s`: density scaling of the RVE disks, in `[1, 1e6]` (1 = physical masses).
    pub density_scaling: f64,
}

impl Default for DemTimeRule {
    fn default() -> Self {
        Self {
            step_fraction: 0.2,
            density_scaling: 1.0,
        }
    }
}

/// Limits of the quasi-static check made after every step (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuasiStaticLimits {
    /// Largest inertial number `I = ε̇ d̄ √(s ρ_s / p)` of any RVE, in `(0, 1]`.
    pub max_inertial_number: f64,
    /// Largest ratio of fluctuating kinetic to contact elastic energy of any RVE, in `(0, 1]`.
    pub max_kinetic_ratio: f64,
}

impl Default for QuasiStaticLimits {
    fn default() -> Self {
        Self {
            max_inertial_number: 1e-3,
            max_kinetic_ratio: 1e-2,
        }
    }
}

/// Parameters of the RVE-backed material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiscaleParams {
    /// The RVE's contact law, density, thickness, expansion, resistance, damping.
    pub rve: RveParams,
    /// The DEM time rule.
    #[serde(default)]
    pub dem_time: DemTimeRule,
    /// RVE temperature (K) of an MPM temperature of 0: the MPM may work in °C (273.15) or K
    /// (0). Finite, in `[0, 1e4]`.
    pub kelvin_offset: f64,
    /// Quasi-static limits; `None`: measured and reported, never enforced (flows).
    #[serde(default)]
    pub quasi_static: Option<QuasiStaticLimits>,
}

/// Validated [`MultiscaleParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiscaleConfig {
    params: MultiscaleParams,
    rve: RveConfig,
}

fn check(
    field: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    allowed: &'static str,
) -> Result<(), MultiscaleError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(MultiscaleError::InvalidParameter {
            field,
            value,
            allowed,
        })
    }
}

/// The first of `fields` that is not finite and positive, as an error naming it.
pub(crate) fn check_positive(fields: &[(&'static str, f64)]) -> Result<(), MultiscaleError> {
    for &(field, value) in fields {
        if !(value.is_finite() && value > 0.0) {
            return Err(MultiscaleError::InvalidParameter {
                field,
                value,
                allowed: "(0, inf)",
            });
        }
    }
    Ok(())
}

/// The first of `counts` outside its range `[lo, hi]`, as an error naming it and the range
/// (`allowed`, the range in words).
pub(crate) fn check_counts(
    counts: &[(&'static str, usize, usize, usize, &'static str)],
) -> Result<(), MultiscaleError> {
    for &(field, value, lo, hi, allowed) in counts {
        if !(lo..=hi).contains(&value) {
            return Err(MultiscaleError::InvalidParameter {
                field,
                value: value as f64,
                allowed,
            });
        }
    }
    Ok(())
}

impl MultiscaleParams {
    /// Validates every field once, naming the first one out of range (as its key path).
    pub fn validate(&self) -> Result<MultiscaleConfig, MultiscaleError> {
        let rve = self.rve.validate().map_err(MultiscaleError::RveSetup)?;
        check(
            "dem_time.step_fraction",
            self.dem_time.step_fraction,
            1e-3,
            0.5,
            "[0.001, 0.5]",
        )?;
        check(
            "dem_time.density_scaling",
            self.dem_time.density_scaling,
            1.0,
            1e6,
            "[1, 1e6]",
        )?;
        check("kelvin_offset", self.kelvin_offset, 0.0, 1e4, "[0, 1e4] K")?;
        if let Some(q) = self.quasi_static {
            check(
                "quasi_static.max_inertial_number",
                q.max_inertial_number,
                f64::MIN_POSITIVE,
                1.0,
                "(0, 1]",
            )?;
            check(
                "quasi_static.max_kinetic_ratio",
                q.max_kinetic_ratio,
                f64::MIN_POSITIVE,
                1.0,
                "(0, 1]",
            )?;
        }
        Ok(MultiscaleConfig { params: *self, rve })
    }
}

impl MultiscaleConfig {
    /// The validated parameters.
    pub fn params(&self) -> &MultiscaleParams {
        &self.params
    }
    /// The RVE configuration.
    pub fn rve(&self) -> &RveConfig {
        &self.rve
    }
}
