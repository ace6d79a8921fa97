//! Packing generation and servo-controlled isotropic consolidation (B-Sects. 5.2.2, 5.3.1).
//!
//! 1. [`random_packing`]: disks with radii uniform in `[r_min, r_max]` (seeded ChaCha8) placed
//!    without overlap by random sequential addition in a square periodic cell at a low solid
//!    fraction;
//! 2. [`consolidate`]: the cell is compressed by a diagonal velocity gradient that a servo sets
//!    each step from the stress error of its axis, until both normal stresses are within the
//!    tolerance of the target and the packing is in equilibrium;
//! 3. the dense/loose protocol ([`ConsolidationParams::dense`], [`ConsolidationParams::loose`])
//!    differs only in the friction coefficient used during consolidation (0.01 vs 0.5);
//!    shearing then runs with μ = 0.5 ([`RveConfig::with_friction`]).

use crate::cell::PeriodicCell;
use crate::error::{RveError, check_positive, check_range};
use crate::mat2::Mat2;
use crate::measure;
use crate::params::RveConfig;
use crate::state::RveState;
use crate::stepper::RveStepper;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use thm_dem::Vec3;

/// Parameters of a random packing, as read from a file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PackingParams {
    /// Number of disks (the paper uses 400).
    pub disk_count: usize,
    /// Smallest radius \[m\].
    pub min_radius: f64,
    /// Largest radius \[m\].
    pub max_radius: f64,
    /// Solid fraction of the loose initial cloud ∈ (0, 0.5].
    pub initial_solid_fraction: f64,
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
}

impl PackingParams {
    /// The packing of B-Sect. 5.2.2: 400 disks, radii uniform in [0.25, 0.5] mm.
    pub fn paper_b(seed: u64) -> Self {
        Self {
            disk_count: 400,
            min_radius: 0.25e-3,
            max_radius: 0.5e-3,
            initial_solid_fraction: 0.3,
            seed,
        }
    }

    fn validate(&self) -> Result<(), RveError> {
        if !(self.min_radius.is_finite()
            && self.max_radius.is_finite()
            && self.min_radius > 0.0
            && self.min_radius <= self.max_radius)
        {
            return Err(RveError::RadiiOutOfOrder {
                min_radius: self.min_radius,
                max_radius: self.max_radius,
            });
        }
        check_range("disk_count", self.disk_count as f64, 2.0, 1e7, "[2, 10^7]")?;
        check_range(
            "initial_solid_fraction",
            self.initial_solid_fraction,
            1e-3,
            0.5,
            "(0, 0.5]",
        )?;
        Ok(())
    }
}

/// Disks at rest, without overlap, in a square periodic cell at the initial solid fraction,
/// at the reference temperature of `config`.
pub fn random_packing(params: &PackingParams, config: &RveConfig) -> Result<RveState, RveError> {
    params.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let n = params.disk_count;
    let mut radii: Vec<f64> = (0..n)
        .map(|_| {
            if params.max_radius > params.min_radius {
                rng.random_range(params.min_radius..=params.max_radius)
            } else {
                params.min_radius
            }
        })
        .collect();
    // Largest first: random sequential addition fills best that way.
    radii.sort_by(|a, b| b.total_cmp(a));
    let solid: f64 = radii.iter().map(|r| std::f64::consts::PI * r * r).sum();
    let side = (solid / params.initial_solid_fraction).sqrt();
    let cell = PeriodicCell::rectangle(side, side)?;
    let mut centres: Vec<Vec3> = Vec::with_capacity(n);
    let max_attempts = 100_000;
    for &r in &radii {
        let mut placed = false;
        for _ in 0..max_attempts {
            let c = Vec3::new(rng.random::<f64>() * side, rng.random::<f64>() * side, 0.0);
            let free = centres.iter().zip(&radii).all(|(&o, &ro)| {
                let mut d = c - o;
                d.x -= side * (d.x / side).round();
                d.y -= side * (d.y / side).round();
                d.norm_squared() >= (r + ro) * (r + ro)
            });
            if free {
                centres.push(c);
                placed = true;
                break;
            }
        }
        if !placed {
            return Err(RveError::InvalidParameter {
                field: "initial_solid_fraction",
                value: params.initial_solid_fraction,
                allowed: "low enough to place every disk without overlap",
            });
        }
    }
    let p = config.params();
    RveState::new(
        cell,
        &centres,
        &radii,
        p.density,
        p.thickness,
        p.reference_temperature,
    )
}

/// Parameters of the servo-controlled isotropic consolidation, as read from a file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConsolidationParams {
    /// Target isotropic stress σ₀ \[Pa\] (compression positive).
    pub target_stress: f64,
    /// Relative tolerance on each normal stress, `|σ_kk − σ₀| ≤ tol σ₀`.
    pub tolerance: f64,
    /// Friction coefficient during consolidation (0.01 dense, 0.5 loose, B-Sect. 5.3.1).
    pub friction_coefficient: f64,
    /// Local damping during consolidation ∈ [0, 1).
    pub damping: f64,
    /// Largest strain increment per step (compaction speed of the loose cloud).
    pub max_strain_increment: f64,
    /// Servo gain: strain increment per step = gain · (σ_kk − σ₀) / (k_n / z_p).
    pub servo_gain: f64,
    /// Largest unbalanced-force ratio accepted as equilibrium.
    pub max_unbalanced_ratio: f64,
    /// Step budget.
    pub max_steps: u64,
    /// DEM time step as a fraction of `√(m_min / k_n)`.
    pub time_step_fraction: f64,
}

impl ConsolidationParams {
    /// Isotropic consolidation to `target_stress` with friction μ (0.001 in B-Table 1).
    pub fn isotropic(target_stress: f64, friction_coefficient: f64) -> Self {
        Self {
            target_stress,
            tolerance: 0.005,
            friction_coefficient,
            damping: 0.7,
            max_strain_increment: 2e-4,
            servo_gain: 0.05,
            max_unbalanced_ratio: 1e-3,
            max_steps: 400_000,
            time_step_fraction: 0.2,
        }
    }

    /// The dense protocol of B-Sect. 5.3.1: μ = 0.01 during consolidation.
    pub fn dense(target_stress: f64) -> Self {
        Self::isotropic(target_stress, 0.01)
    }

    /// The loose protocol of B-Sect. 5.3.1: μ = 0.5 during consolidation.
    pub fn loose(target_stress: f64) -> Self {
        Self::isotropic(target_stress, 0.5)
    }
}

/// The outcome of a consolidation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConsolidationReport {
    /// DEM steps taken.
    pub steps: u64,
    /// Stress reached \[Pa\] (B-Eq. 49, compression positive).
    pub stress: Mat2,
    /// Void ratio reached.
    pub void_ratio: f64,
    /// Coordination number of the force-carrying contacts.
    pub coordination_number: f64,
    /// Unbalanced-force ratio at the end.
    pub unbalanced_ratio: f64,
    /// DEM time step used \[s\].
    pub time_step: f64,
}

/// A stable DEM time step `fraction · √(m_min / k_n)` \[s\].
pub fn time_step(state: &RveState, config: &RveConfig, fraction: f64) -> f64 {
    let m_min = state
        .disks
        .mass
        .iter()
        .fold(f64::INFINITY, |m, &v| m.min(v));
    fraction * (m_min / config.params().contact.normal_stiffness).sqrt()
}

/// Largest isotropic stress the contacts carry with a mean overlap of 10 % of the smallest
/// radius, estimated as `σ ≈ Z/2 · k_n δ / (d̄ z_p)` per unit area with a coordination number
/// of 4 and the mean diameter `d̄` \[Pa\].
pub fn max_reachable_stress(state: &RveState, config: &RveConfig) -> f64 {
    let r = &state.disks.reference_radius;
    let r_min = r.iter().fold(f64::INFINITY, |m, &v| m.min(v));
    let d_mean = 2.0 * r.iter().sum::<f64>() / r.len().max(1) as f64;
    let p = config.params();
    2.0 * p.contact.normal_stiffness * 0.1 * r_min / (d_mean * p.thickness)
}

/// Servo-controlled isotropic consolidation of the cell to `params.target_stress`. The cell
/// stays rectangular-diagonal in its deformation (`L = diag(ε̇_x, ε̇_y)`); the strain reference
/// of the cell is reset at the end. Fails with [`RveError::UnreachableTargetStress`] when the
/// target needs overlaps above 10 % of the smallest radius and with
/// [`RveError::ConsolidationNotConverged`] when the step budget runs out.
pub fn consolidate(
    state: &mut RveState,
    config: &RveConfig,
    params: &ConsolidationParams,
) -> Result<ConsolidationReport, RveError> {
    check_positive("target_stress", params.target_stress)?;
    check_range("tolerance", params.tolerance, 1e-6, 0.5, "[1e-6, 0.5]")?;
    check_positive("max_strain_increment", params.max_strain_increment)?;
    check_positive("servo_gain", params.servo_gain)?;
    check_positive("max_unbalanced_ratio", params.max_unbalanced_ratio)?;
    check_range(
        "time_step_fraction",
        params.time_step_fraction,
        1e-4,
        0.5,
        "[1e-4, 0.5]",
    )?;
    let max_reachable = max_reachable_stress(state, config);
    if params.target_stress > max_reachable {
        return Err(RveError::UnreachableTargetStress {
            target: params.target_stress,
            max_reachable,
        });
    }
    let consol = config
        .with_friction(params.friction_coefficient)?
        .with_damping(params.damping)?;
    let mut stepper = RveStepper::new(consol);
    let dt = time_step(state, config, params.time_step_fraction);
    let p = config.params();
    let modulus_scale = p.contact.normal_stiffness / p.thickness;
    let target = params.target_stress;
    let mut l = Mat2::ZERO;
    let mut settled = 0u32;
    for n in 0..params.max_steps {
        stepper.step(state, &l, dt)?;
        let s = measure::stress(state, p.thickness);
        let mut converged = true;
        let mut rates = [0.0; 2];
        for (k, rate) in rates.iter_mut().enumerate() {
            let sigma = s.at(k, k);
            let increment = (params.servo_gain * (sigma - target) / modulus_scale)
                .clamp(-params.max_strain_increment, params.max_strain_increment);
            *rate = increment / dt;
            converged &= (sigma - target).abs() <= params.tolerance * target;
        }
        l = Mat2::diagonal(rates[0], rates[1]);
        if converged && measure::unbalanced_force_ratio(state) <= params.max_unbalanced_ratio {
            settled += 1;
        } else {
            settled = 0;
        }
        if settled >= 20 {
            // Leave the cell at rest, relaxed under the final velocity gradient.
            state.cell.reset_reference();
            return Ok(ConsolidationReport {
                steps: n + 1,
                stress: s,
                void_ratio: state.void_ratio(),
                coordination_number: state.coordination_number(),
                unbalanced_ratio: measure::unbalanced_force_ratio(state),
                time_step: dt,
            });
        }
    }
    let s = measure::stress(state, p.thickness);
    Err(RveError::ConsolidationNotConverged {
        target,
        reached: 0.5 * s.trace(),
        steps: params.max_steps,
        tolerance: params.tolerance,
    })
}
