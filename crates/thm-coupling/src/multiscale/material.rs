//! The RVE-backed material of `thm-mpm`: every material point owns an RVE ([`RvePoint`], in
//! the caller's `MpmState`), and [`RveMaterial`] steps them all as one batch through
//! `thm-mpm`'s batched seam, or, when the stage is spread over processes, only this process's
//! block, handing the exchange to [`super::distributed`] (which steps its block through
//! [`BlockMaterial`]).

use rayon::prelude::*;
use thm_mpm::points::Sym2;
use thm_mpm::{BatchConstitutive, MaterialInput, MaterialPoints, MaterialResponse, MpmState};
use thm_rve::{RveBatch, RveLoad, RveResponse, RveState, measure};

use super::distributed::{self, BlockMaterial, SharedDistribution};
use super::error::MultiscaleError;
use super::params::{MultiscaleConfig, MultiscaleParams};
use super::point::{PointOutcome, RvePoint};
use super::stages;

/// An RVE per material point, stepped as one batch (`thm_rve::RveBatch`, rayon; nothing is
/// reduced across RVEs, so any number of threads gives the same bits). Holds the validated
/// parameters, the template packing and scratch only.
#[derive(Debug, Clone)]
pub struct RveMaterial {
    config: MultiscaleConfig,
    template: RvePoint,
    batch: RveBatch,
    loads: Vec<RveLoad>,
    rve_responses: Vec<RveResponse>,
    totals: Vec<f64>,
    outcomes: Vec<PointOutcome>,
    distribution: Option<SharedDistribution>,
}

/// Relative tolerance of the packing check (disk mass against `ρ π R₀² z_p`).
const PACKING_TOLERANCE: f64 = 1e-9;

impl RveMaterial {
    /// A material whose fresh points carry copies of `packing`, a packing made with the
    /// physical density and thickness of `params.rve` whose contacts have been evaluated
    /// (consolidated, or stepped once). The density scaling of the DEM time rule is applied
    /// here. Errors: a parameter out of range (named), a packing whose disk masses do not
    /// match `ρ π R₀² z_p` of the parameters.
    pub fn new(params: &MultiscaleParams, packing: RveState) -> Result<Self, MultiscaleError> {
        let config = params.validate()?;
        let p = config.rve().params();
        if packing.is_empty() {
            return Err(MultiscaleError::PackingMismatch {
                field: "disk count",
                value: 0.0,
                expected: 1.0,
            });
        }
        for (m, r) in packing
            .disks
            .mass
            .iter()
            .zip(&packing.disks.reference_radius)
        {
            let expected = p.density * std::f64::consts::PI * r * r * p.thickness;
            let close = (m - expected).abs() <= PACKING_TOLERANCE * expected;
            if !close {
                return Err(MultiscaleError::PackingMismatch {
                    field: "disk mass (density x pi R0^2 x thickness)",
                    value: *m,
                    expected,
                });
            }
        }
        let mut rve = packing;
        stages::scale_density(&mut rve, params.dem_time.density_scaling);
        let [dx, dy] = stages::axial_moduli(&rve, p);
        let mut template = RvePoint {
            rve_volume: rve.volume(p.thickness),
            rve,
            steps: 0,
            wave_modulus: dx.max(dy),
            friction_work: 0.0,
            inertial_number: 0.0,
            kinetic_ratio: 0.0,
            substeps: 0,
            intact_bonds: 0,
        };
        template.count_bonds();
        Ok(Self {
            batch: RveBatch::new(*config.rve(), 0),
            config,
            template,
            loads: Vec::new(),
            rve_responses: Vec::new(),
            totals: Vec::new(),
            outcomes: Vec::new(),
            distribution: None,
        })
    }

    /// The validated configuration.
    pub fn config(&self) -> &MultiscaleConfig {
        &self.config
    }

    /// A fresh point's history (a copy of the template).
    pub fn initial_point(&self) -> RvePoint {
        self.template.clone()
    }

    /// The template's response as a material point sees it (stress tension positive, heat
    /// source 0, conductivity), for the initial state of the points.
    pub fn initial_response(&self) -> MaterialResponse {
        let p = self.config.rve().params();
        let r = RveResponse {
            stress: measure::stress(&self.template.rve, p.thickness),
            heat_source: 0.0,
            conductivity: measure::conductivity(&self.template.rve, p),
        };
        stages::mpm_response(&r)
    }

    /// An MPM state of `points` at time 0, each point with a fresh RVE and the RVE's stress
    /// and conductivity.
    pub fn state(&self, mut points: MaterialPoints) -> MpmState<RvePoint> {
        let r = self.initial_response();
        points.stress.fill(r.stress);
        points.conductivity.fill(r.conductivity);
        points.heat_source.fill(0.0);
        let n = points.len();
        MpmState {
            points,
            material: vec![self.initial_point(); n],
            time: 0.0,
            step: 0,
        }
    }

    /// The conductivity of the template `[kxx, kyy, kxy]` (W/(m K)).
    pub fn initial_conductivity(&self) -> Sym2 {
        self.initial_response().conductivity
    }

    /// The stage sequence of one exchange for all points (see [`super::stages`]): every
    /// point's block is stepped here ([`RveMaterial::step_block`] over `0..n`), then the
    /// outcomes are applied and checked.
    fn exchange(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MultiscaleError> {
        let n = inputs.len();
        if states.len() != n || responses.len() != n {
            return Err(thm_mpm::MpmError::MaterialStateCount {
                states: states.len(),
                points: n,
            }
            .into());
        }
        if let Some(d) = self.distribution.clone() {
            return distributed::lock(&d).exchange(self, states, inputs, responses);
        }
        let mut outcomes = std::mem::take(&mut self.outcomes);
        outcomes.resize(n, PointOutcome::default());
        let stepped = self.step_block(states, inputs, 0, &mut outcomes);
        if stepped.is_ok() {
            self.finish(states, &outcomes, responses);
        }
        self.outcomes = outcomes;
        stepped?;
        self.check_quasi_static(states)
    }

    /// Spreads the RVE stage over the processes of `distribution` (see
    /// [`super::distributed`]); every exchange from now on steps only this process's block.
    pub fn distribute(&mut self, distribution: SharedDistribution) {
        self.distribution = Some(distribution);
    }

    /// Wall-clock seconds each RVE of the last [`RveMaterial::step_block`] took (its block's
    /// points in order; a measured cost for balancing, no result depends on it).
    pub fn step_seconds(&self) -> &[f64] {
        self.batch.step_seconds()
    }

    /// The distribution, if the RVE stage is spread over processes.
    pub fn distribution(&self) -> Option<&SharedDistribution> {
        self.distribution.as_ref()
    }

    /// Lines 12–19 of B-Algorithm 1 for the contiguous block of points `states` (the points
    /// `first..first + states.len()` of the material, `inputs` theirs): their DEM steps as one
    /// batch, then each point's [`PointOutcome`] into `outcomes`. Each RVE is stepped alone,
    /// so stepping the points in blocks (one per process, in any order) gives the same bits
    /// as one block of all points; this is the seam a distributed run splits at, exchanging
    /// only the fixed-size outcomes. The states' RVEs are advanced; their diagnostics are set
    /// by [`PointOutcome::apply`]. Errors name the failing point by its material index.
    pub fn step_block(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        first: usize,
        outcomes: &mut [PointOutcome],
    ) -> Result<(), MultiscaleError> {
        let n = states.len();
        if inputs.len() != n || outcomes.len() != n {
            return Err(thm_mpm::MpmError::MaterialStateCount {
                states: n,
                points: inputs.len().min(outcomes.len()),
            }
            .into());
        }
        let params = *self.config.params();
        let p = self.config.rve().params();
        if self.batch.len() != n {
            self.batch = RveBatch::new(*self.config.rve(), n);
        }
        // Lines 12, 15: deformation and temperature to each RVE.
        stages::rve_loads(
            inputs,
            states,
            p,
            params.kelvin_offset,
            params.dem_time.step_fraction,
            &mut self.loads,
        );
        self.rve_responses.resize(n, RveResponse::default());
        // Friction work of this step = change of the RVE's running total.
        self.totals.clear();
        self.totals
            .extend(states.iter().map(|s| s.rve.friction_heat_total));
        // Line 16: every RVE's DEM steps, as one batch.
        if let Err((local, source)) =
            self.batch
                .respond_into(states, &self.loads, &mut self.rve_responses)
        {
            let s = states.get(local).map(|s| s.rve.cell.strain());
            return Err(MultiscaleError::Rve {
                point: first + local,
                step: states.get(local).map_or(0, |s| s.steps),
                volumetric_strain: s.map_or(f64::NAN, |s| s.volumetric),
                deviatoric_strain: s.map_or(f64::NAN, |s| s.deviatoric),
                source,
            });
        }
        // Lines 18–19: stress, heat source, conductivity; the time-step modulus and the
        // quasi-static measures.
        let scaling = params.dem_time.density_scaling;
        states
            .par_iter()
            .zip(outcomes.par_iter_mut())
            .zip(inputs.par_iter().zip(&self.rve_responses).zip(&self.loads))
            .zip(self.totals.par_iter())
            .for_each(|(((point, out), ((input, r), load)), before)| {
                let measures = stages::contact_measures(&point.rve, p);
                let [dx, dy] = measures.axial_moduli;
                let (i, k) = stages::quasi_static_measures_with(
                    &point.rve,
                    p,
                    scaling,
                    input,
                    &r.stress,
                    measures.elastic_energy,
                );
                *out = PointOutcome {
                    response: stages::mpm_response(r),
                    wave_modulus: dx.max(dy),
                    friction_work: point.rve.friction_heat_total - before,
                    rve_volume: point.rve.volume(p.thickness),
                    inertial_number: i,
                    kinetic_ratio: k,
                    substeps: load.substeps,
                    intact_bonds: u32::try_from(point.rve.contacts.intact_bond_count())
                        .unwrap_or(u32::MAX),
                };
            });
        Ok(())
    }

    /// Applies every point's outcome (all blocks gathered, in point order) to its history and
    /// response.
    pub fn finish(
        &self,
        states: &mut [RvePoint],
        outcomes: &[PointOutcome],
        responses: &mut [MaterialResponse],
    ) {
        for ((point, out), r) in states.iter_mut().zip(outcomes).zip(responses) {
            *r = out.apply(point);
        }
    }

    /// The quasi-static check of the parameters over all points (lowest failing point first).
    pub fn check_quasi_static(&self, states: &[RvePoint]) -> Result<(), MultiscaleError> {
        let params = self.config.params();
        if let Some(limits) = params.quasi_static {
            for (i, s) in states.iter().enumerate() {
                let checks = [
                    (
                        "inertial number",
                        s.inertial_number,
                        limits.max_inertial_number,
                    ),
                    (
                        "kinetic/elastic energy ratio",
                        s.kinetic_ratio,
                        limits.max_kinetic_ratio,
                    ),
                ];
                for (quantity, value, limit) in checks {
                    // NaN fails the check too.
                    let within = value <= limit;
                    if !within {
                        return Err(MultiscaleError::NotQuasiStatic {
                            point: i,
                            step: s.steps,
                            quantity,
                            value,
                            limit,
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

impl BlockMaterial for RveMaterial {
    fn step_block(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        first: usize,
        outcomes: &mut [PointOutcome],
    ) -> Result<(), MultiscaleError> {
        RveMaterial::step_block(self, states, inputs, first, outcomes)
    }
    fn step_seconds(&self) -> &[f64] {
        RveMaterial::step_seconds(self)
    }
    fn finish(
        &self,
        states: &mut [RvePoint],
        outcomes: &[PointOutcome],
        responses: &mut [MaterialResponse],
    ) {
        RveMaterial::finish(self, states, outcomes, responses);
    }
    fn check_quasi_static(&self, states: &[RvePoint]) -> Result<(), MultiscaleError> {
        RveMaterial::check_quasi_static(self, states)
    }
}

impl BatchConstitutive for RveMaterial {
    type PointState = RvePoint;
    type Error = MultiscaleError;

    fn respond_batch(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MultiscaleError> {
        self.exchange(states, inputs, responses)
    }

    fn wave_modulus(&self, state: &RvePoint) -> f64 {
        state.wave_modulus
    }
}
