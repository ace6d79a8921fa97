//! One skeleton for the multiscale cases whose loading changes as they run (the biaxial test
//! of B-Sect. 5.3.1, the silo discharge of 5.3.2, the column collapse of 5.3.3).
//!
//! What every such case does alike lives in [`MultiscaleModel`]: the points and their RVEs
//! (`MpmState<RvePoint>`), the running sums, the loading phases, the RVE materials, and one
//! coupled step — the protocol's events and loads, the MPM×DEM step of B-Algorithm 1 in the
//! current phase, the protocol's running sums — besides restoring a checkpoint and spreading
//! the RVE stage over processes. What differs is a [`Protocol`]:
//!
//! - the RVE material(s) and the [`LoadingPhase`]s (an MPM stepper with its grid, walls,
//!   boundary conditions and PIC fraction, and the material its points are stepped with),
//!   built by the case's constructor;
//! - the loading protocol: what happens before a step (a release that installs bonds or
//!   opens a gate, loads that follow the deforming boundary) and after it (heat, friction
//!   work, plate work), and which phase a step runs in;
//! - the recorder: the history row of a state.
//!
//! A new case is a struct of its parameters and derived data (boundary points, tracked
//! points, wall segments) with its constructor and these few functions.

use std::sync::Arc;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use thm_mpm::{BatchConstitutive, Mpm, MpmState};
use thm_rve::{ConsolidationParams, PackingParams, RveParams, RveState, consolidate, measure};

use super::distributed::{self, SharedDistribution};
use super::error::MultiscaleError;
use super::material::RveMaterial;
use super::point::RvePoint;

/// A stretch of the loading with its own MPM stepper (grid, walls, boundary conditions, PIC
/// fraction) and RVE material.
#[derive(Debug, Clone)]
pub struct LoadingPhase {
    /// The MPM stepper of the phase.
    pub mpm: Mpm,
    /// Index of the phase's material in [`MultiscaleModel::materials`] (phases may share one).
    pub material: usize,
}

/// What a multiscale case adds to the skeleton: its loading protocol and its recorder (see
/// the module docs).
pub trait Protocol: Sized + Clone + std::fmt::Debug {
    /// Running sums and protocol events (a release), carried in checkpoints with the state.
    type Totals: Copy + Default + PartialEq + std::fmt::Debug + Serialize + DeserializeOwned;
    /// One row of the history.
    type Record;
    /// What [`Protocol::before_step`] measures for [`Protocol::after_step`] (the heat before
    /// the step, say).
    type StepStart;

    /// The MPM time step \[s\].
    fn time_step(&self) -> f64;
    /// MPM steps of the whole run.
    fn steps(&self) -> u64;
    /// The loading phase the points are in with running sums `totals`.
    fn phase(totals: &Self::Totals) -> usize;
    /// Before the step from `model.state.step`: the events due (a release), loads that follow
    /// the current boundary, the measures `after_step` needs.
    fn before_step(model: &mut MultiscaleModel<Self>) -> Result<Self::StepStart, MultiscaleError>;
    /// After the MPM×DEM step in `phase`: the running sums.
    fn after_step(
        model: &mut MultiscaleModel<Self>,
        phase: usize,
        start: Self::StepStart,
    ) -> Result<(), MultiscaleError>;
    /// What the protocol derives from the state, derived again after a restore. Default:
    /// nothing.
    fn restored(_model: &mut MultiscaleModel<Self>) -> Result<(), MultiscaleError> {
        Ok(())
    }
    /// The history row of `state` with running sums `totals`, for a state this model's
    /// stepper advanced last (wall reactions are the last step's).
    fn record(
        model: &MultiscaleModel<Self>,
        state: &MpmState<RvePoint>,
        totals: &Self::Totals,
    ) -> Self::Record;
}

/// A multiscale case on the skeleton: the state, the running sums, the case, its loading
/// phases and RVE materials.
#[derive(Debug, Clone)]
pub struct MultiscaleModel<P: Protocol> {
    /// Points with their RVEs.
    pub state: MpmState<RvePoint>,
    /// Running sums and protocol events.
    pub totals: P::Totals,
    /// The case: parameters, what the consolidation gave, derived data.
    pub case: P,
    /// The loading phases, in the order the protocol enters them.
    pub phases: Vec<LoadingPhase>,
    /// The RVE materials the phases step their points with.
    pub materials: Vec<RveMaterial>,
}

impl<P: Protocol> MultiscaleModel<P> {
    /// A model at the start of `case`'s run, with fresh running sums. `phases` must not be
    /// empty and name materials of `materials`.
    pub fn from_parts(
        case: P,
        state: MpmState<RvePoint>,
        phases: Vec<LoadingPhase>,
        materials: Vec<RveMaterial>,
    ) -> Result<Self, MultiscaleError> {
        if phases.is_empty() || phases.iter().any(|p| p.material >= materials.len()) {
            return Err(MultiscaleError::InvalidParameter {
                field: "phases",
                value: phases.len() as f64,
                allowed: "at least one phase, each naming one of the materials",
            });
        }
        Ok(Self {
            state,
            totals: P::Totals::default(),
            case,
            phases,
            materials,
        })
    }

    /// The phase the points are in now.
    pub fn phase(&self) -> &LoadingPhase {
        let k = P::phase(&self.totals).min(self.phases.len() - 1);
        &self.phases[k]
    }

    /// The MPM stepper of the current phase.
    pub fn mpm(&self) -> &Mpm {
        &self.phase().mpm
    }

    /// The RVE material of the current phase.
    pub fn material(&self) -> &RveMaterial {
        &self.materials[self.phase().material]
    }

    /// One coupled step: the protocol's events and loads, the MPM×DEM step (B-Algorithm 1)
    /// of the current phase, the protocol's running sums.
    pub fn step(&mut self) -> Result<(), MultiscaleError> {
        let start = P::before_step(self)?;
        let k = P::phase(&self.totals).min(self.phases.len() - 1);
        let dt = self.case.time_step();
        let LoadingPhase { mpm, material } = &mut self.phases[k];
        mpm.step_batch(&mut self.state, &mut self.materials[*material], dt)?;
        P::after_step(self, k, start)
    }

    /// Whether the run is over.
    pub fn finished(&self) -> bool {
        self.state.step >= self.case.steps()
    }

    /// Restores a saved state (points with RVEs) and running sums.
    pub fn restore(
        &mut self,
        state: MpmState<RvePoint>,
        totals: P::Totals,
    ) -> Result<(), MultiscaleError> {
        if state.points.len() != self.state.points.len() {
            return Err(thm_mpm::MpmError::MaterialStateCount {
                states: state.points.len(),
                points: self.state.points.len(),
            }
            .into());
        }
        self.state = state;
        self.totals = totals;
        P::restored(self)
    }

    /// Spreads the RVE stage over the processes of `d` (every material shares it; see
    /// [`super::distributed`]).
    pub fn distribute(&mut self, d: &SharedDistribution) {
        for m in &mut self.materials {
            m.distribute(Arc::clone(d));
        }
    }

    /// Brings every process's RVEs up to date (a no-op without a distribution).
    pub fn synchronise(&mut self) -> Result<(), MultiscaleError> {
        match self.materials.first().and_then(RveMaterial::distribution) {
            Some(d) => distributed::lock(d).synchronise(&mut self.state.material),
            None => Ok(()),
        }
    }

    /// The smallest time-step limit of B-Eqs. 30–31 over the points of the current state
    /// (s), with the RVEs' wave moduli in the current phase's material.
    pub fn time_step_limit(&self) -> f64 {
        let material = self.material();
        let rves = &self.state.material;
        self.phases[0]
            .mpm
            .time_step_limits_with(&self.state.points, |i| material.wave_modulus(&rves[i]))
            .min()
    }

    /// The history row of the current state.
    pub fn record(&self) -> P::Record {
        P::record(self, &self.state, &self.totals)
    }

    /// The history row of `state` with running sums `totals` (a state this model's stepper
    /// advanced last).
    pub fn record_of(&self, state: &MpmState<RvePoint>, totals: &P::Totals) -> P::Record {
        P::record(self, state, totals)
    }
}

/// Stored heat `Σ m c (T − T₀)` of `state` (J/m), `t0` the initial temperature.
pub fn stored_heat(state: &MpmState<RvePoint>, t0: f64) -> f64 {
    let pts = &state.points;
    pts.mass
        .iter()
        .zip(&pts.specific_heat)
        .zip(&pts.temperature)
        .map(|((m, c), t)| m * c * (t - t0))
        .sum()
}

/// The heat measured before a step of a flowing sample (the column, the silo).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeatBefore {
    /// Heat the sources deliver in the step, `Σ Q_p V_p Δt` (J/m).
    pub source: f64,
    /// Stored heat before the step (J/m).
    pub stored: f64,
}

/// The start of a step of a flowing sample: every skewed RVE cell reduced ([`reduce_cells`]),
/// the heat sources cleared when friction heat is off, then the heat they deliver in a step
/// of `dt` and the stored heat above `t0`.
pub fn flow_step_start(
    state: &mut MpmState<RvePoint>,
    friction_heat: bool,
    dt: f64,
    t0: f64,
) -> Result<HeatBefore, MultiscaleError> {
    reduce_cells(state)?;
    let pts = &mut state.points;
    if !friction_heat {
        pts.heat_source.fill(0.0);
    }
    let source: f64 = pts
        .heat_source
        .iter()
        .zip(&pts.volume)
        .map(|(q, v)| q * v * dt)
        .sum();
    Ok(HeatBefore {
        source,
        stored: stored_heat(state, t0),
    })
}

/// Reduces every RVE cell of `state` whose basis has become skewed
/// (`thm_rve::RveState::reduce_cell`: the same lattice, so nothing physical changes); for
/// points in a flow (the column, the silo), see the column's module docs, choice 8.
pub fn reduce_cells(state: &mut MpmState<RvePoint>) -> Result<(), MultiscaleError> {
    let step = state.step;
    for (point, r) in state.material.iter_mut().enumerate() {
        if let Err(source) = r.rve.reduce_cell() {
            let s = r.rve.cell.strain();
            return Err(MultiscaleError::Rve {
                point,
                step,
                volumetric_strain: s.volumetric,
                deviatoric_strain: s.deviatoric,
                source,
            });
        }
    }
    Ok(())
}

/// What the consolidation of a case's template packing gave.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PackingReport {
    /// Void ratio (void over solid area).
    pub void_ratio: f64,
    /// Coordination number of the force-carrying contacts.
    pub coordination_number: f64,
    /// DEM steps of the consolidation.
    pub consolidation_steps: u64,
    /// α of B-Eq. 34 that gives the stated conductivity (K/(W m)).
    pub thermal_resistance: f64,
    /// Bulk density of the points `ρ_s/(1 + e)` (kg/m³).
    pub bulk_density: f64,
    /// Contacts carrying force after the consolidation.
    pub force_contacts: usize,
}

/// How a case's template packing is made: `disks` random disks (seed `seed`, radii in
/// [0.25, 0.5] mm, B-Sect. 5.2.2) consolidated isotropically to `stress` with friction
/// `consolidation_friction`, then set at rest, optionally bonded, given the conductivity and
/// the friction of the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackingProtocol {
    /// Seed of the packing.
    pub seed: u64,
    /// Disks per RVE.
    pub disks: usize,
    /// Consolidation stress (Pa).
    pub stress: f64,
    /// Friction coefficient while consolidating (0.01 dense, 0.5 loose).
    pub consolidation_friction: f64,
    /// Friction coefficient of the run.
    pub friction: f64,
    /// Conductivity the packing is given through α of B-Eq. 34 (mean of the diagonal,
    /// W/(m K)).
    pub conductivity: f64,
    /// Bonds of B-Eqs. 38–39 installed after the consolidation at every contact carrying
    /// force, `(β_b, μ_b)`, that do not melt (B-Fig. 18); `None`: no bonds.
    pub bonds: Option<(f64, f64)>,
}

/// The template packing every point's RVE starts from, made by `protocol` with the contact
/// law, density, expansion, thickness and damping of `rve` (α is replaced): the RVE
/// parameters of the run, the packing at rest, and what the consolidation gave.
///
/// At rest: the consolidation leaves residual velocities (unbalanced-force ratio up to
/// 10⁻³) whose kinetic energy the density scaling of the DEM time rule would multiply by
/// `s` (a probe with s = 10⁵ started with 11 times the elastic energy as kinetic energy).
pub fn consolidated_packing(
    rve: &RveParams,
    protocol: &PackingProtocol,
) -> Result<(RveParams, RveState, PackingReport), MultiscaleError> {
    let mut p = *rve;
    p.thermal_resistance = 1.0;
    p.contact.thermal_bond = None;
    let config = p.validate().map_err(MultiscaleError::RveSetup)?;
    let mut pp = PackingParams::paper_b(protocol.seed);
    pp.disk_count = protocol.disks;
    let mut state = thm_rve::random_packing(&pp, &config).map_err(MultiscaleError::RveSetup)?;
    let report = consolidate(
        &mut state,
        &config,
        &ConsolidationParams::isotropic(protocol.stress, protocol.consolidation_friction),
    )
    .map_err(MultiscaleError::RveSetup)?;
    for v in state
        .disks
        .velocity
        .iter_mut()
        .chain(state.disks.angular_velocity.iter_mut())
    {
        *v = thm_dem::Vec3::ZERO;
    }
    state.friction_heat_total = 0.0;
    if let Some((strength, shear_ratio)) = protocol.bonds {
        p.contact.thermal_bond = Some(thm_dem::ThermalBondParams {
            strength_coefficient: strength,
            threshold_temperature_rise: f64::MAX,
            reference_temperature: p.reference_temperature,
            shear_ratio,
        });
        p.validate().map_err(MultiscaleError::RveSetup)?;
        state.install_bonds();
    }
    let k1 = measure::conductivity(&state, &p);
    p.thermal_resistance = 0.5 * (k1.at(0, 0) + k1.at(1, 1)) / protocol.conductivity;
    p.contact.friction_coefficient = protocol.friction;
    let void_ratio = state.void_ratio();
    let force_contacts = state
        .contacts
        .force_on_b
        .iter()
        .filter(|f| **f != thm_dem::Vec2::ZERO)
        .count();
    Ok((
        p,
        state,
        PackingReport {
            void_ratio,
            coordination_number: report.coordination_number,
            consolidation_steps: report.steps,
            thermal_resistance: p.thermal_resistance,
            bulk_density: p.density / (1.0 + void_ratio),
            force_contacts,
        },
    ))
}
