//! The state a material point carries in the MPM×DEM scheme ([`RvePoint`]: its RVE and
//! what the last exchange measured on it), the fixed-size record one exchange returns per
//! point ([`PointOutcome`]), and how points are cut into blocks by cost ([`rve_cost`],
//! [`partition`]). Below both the material ([`super::material`]) and the distributed stage
//! ([`super::distributed`]), which exchange these records.

use serde::{Deserialize, Serialize};
use thm_mpm::MaterialResponse;
use thm_rve::RveState;

/// The history of one material point: its RVE and what the last exchange measured on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RvePoint {
    /// The RVE (disk masses density-scaled by the DEM time rule).
    pub rve: RveState,
    /// MPM steps this RVE has taken.
    pub steps: u64,
    /// P-wave modulus for B-Eq. 30: the larger of `D_xxxx`, `D_yyyy` of B-Eq. 58 (Pa).
    pub wave_modulus: f64,
    /// Friction work of the last MPM step, `Σ E_f` of B-Eq. 32 over its DEM steps (J).
    pub friction_work: f64,
    /// RVE volume `det H · z_p` after the last step (m³).
    pub rve_volume: f64,
    /// Inertial number after the last step (see the module docs).
    pub inertial_number: f64,
    /// Fluctuating kinetic over contact elastic energy after the last step.
    pub kinetic_ratio: f64,
    /// DEM steps of the last MPM step.
    pub substeps: u32,
    /// Intact bonds of the RVE after the last step (kept here so that a process that does
    /// not own the RVE in a distributed run still reads it; see [`super::distributed`]).
    pub intact_bonds: u32,
}

impl RvePoint {
    /// Recounts [`RvePoint::intact_bonds`] from the RVE (after bonds are installed).
    pub fn count_bonds(&mut self) {
        self.intact_bonds =
            u32::try_from(self.rve.contacts.intact_bond_count()).unwrap_or(u32::MAX);
    }
}

impl AsMut<RveState> for RvePoint {
    fn as_mut(&mut self) -> &mut RveState {
        &mut self.rve
    }
}

impl AsRef<RveState> for RvePoint {
    fn as_ref(&self) -> &RveState {
        &self.rve
    }
}

/// What one material point's exchange produces, a fixed-size record (16 numbers): all a
/// process that did not step the point's RVE needs to continue the MPM step bit for bit
/// (the response, and the diagnostics the time-step limit and the checks read).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PointOutcome {
    /// Stress, heat source and conductivity for the point ([`super::stages::mpm_response`]).
    pub response: MaterialResponse,
    /// See [`RvePoint::wave_modulus`].
    pub wave_modulus: f64,
    /// See [`RvePoint::friction_work`].
    pub friction_work: f64,
    /// See [`RvePoint::rve_volume`].
    pub rve_volume: f64,
    /// See [`RvePoint::inertial_number`].
    pub inertial_number: f64,
    /// See [`RvePoint::kinetic_ratio`].
    pub kinetic_ratio: f64,
    /// See [`RvePoint::substeps`].
    pub substeps: u32,
    /// See [`RvePoint::intact_bonds`].
    pub intact_bonds: u32,
}

impl PointOutcome {
    /// Writes the diagnostics into `point`, counts its step and returns its response.
    pub fn apply(&self, point: &mut RvePoint) -> MaterialResponse {
        point.wave_modulus = self.wave_modulus;
        point.friction_work = self.friction_work;
        point.rve_volume = self.rve_volume;
        point.inertial_number = self.inertial_number;
        point.kinetic_ratio = self.kinetic_ratio;
        point.substeps = self.substeps;
        point.intact_bonds = self.intact_bonds;
        point.steps += 1;
        self.response
    }
}

/// A cost estimate from the point's history alone: its contacts × DEM substeps of its last
/// step (at least 1 each, so a fresh RVE counts its contacts). Deterministic: the same on
/// every process holding the point's history; a distributed run balances its first blocks by
/// it, and later ones by measured seconds (see [`super::distributed`]).
pub fn rve_cost(point: &RvePoint) -> f64 {
    let contacts = point.rve.contacts.force_on_b.len().max(1) as f64;
    contacts * f64::from(point.substeps.max(1))
}

/// Contiguous blocks of points, one per process, balanced by a per-point cost (e.g. the
/// previous step's contacts × substeps): block `r` ends at the first point whose cost prefix
/// sum reaches `(r + 1)/parts` of the total. Deterministic (the same costs give the same
/// blocks on every process); every block is non-empty when `parts ≤ costs.len()` (otherwise the first `costs.len()`
/// blocks hold one point each). Costs that
/// are negative or not finite count as 0; all-zero costs split by point count.
pub fn partition(costs: &[f64], parts: usize) -> Vec<std::ops::Range<usize>> {
    let parts = parts.max(1);
    let n = costs.len();
    let clean: Vec<f64> = costs
        .iter()
        .map(|&c| if c.is_finite() && c > 0.0 { c } else { 0.0 })
        .collect();
    let total: f64 = clean.iter().sum();
    let mut ranges = Vec::with_capacity(parts);
    let mut start = 0;
    let mut prefix = 0.0;
    let mut i = 0;
    for r in 0..parts {
        let left = parts - r - 1;
        let mut end = if r + 1 == parts {
            n
        } else if total > 0.0 {
            let target = total * (r + 1) as f64 / parts as f64;
            while i < n && prefix + clean[i] <= target {
                prefix += clean[i];
                i += 1;
            }
            i
        } else {
            n * (r + 1) / parts
        };
        // Keep one point for this block and for each later one where there are enough.
        end = if n >= parts {
            end.clamp(start + 1, n - left)
        } else {
            (start + 1).min(n)
        };
        while i < end {
            prefix += clean[i];
            i += 1;
        }
        while i > end {
            i -= 1;
            prefix -= clean[i];
        }
        ranges.push(start..end);
        start = end;
    }
    ranges
}
