//! The pore-scale DEM–CFD–heat step of Krzaczek, Nitka & Tejchman (2023), A-Fig. 7.
//!
//! One coupled step of length Δt_C runs the stages of [`stages`] in a fixed order over the
//! caller's [`PoreScaleState`]:
//!
//! 1. [`stages::fluid_forces`]: pore pressures and S2S wall shear to sphere forces
//!    (A-Eqs. 52–54);
//! 2. [`stages::dem_steps`]: `ceil(Δt_C / Δt_D)` equal DEM steps (`thm-dem`, A-Eqs. 1–7) with
//!    those forces held;
//! 3. [`stages::mesh_motion`]: the mesh follows the spheres (`thm-vpn-mesh`), T2T apertures
//!    on the moved faces (A-Eq. 9);
//! 4. [`stages::s2s_apertures`]: S2S apertures from the contacts' normal stress (A-Eq. 8);
//! 5. [`stages::flow_stage`]: the flow over Δt_C (`thm-vpn-flow` with the `thm-eos` closure),
//!    each pore's dV/dt the change of its cell volume over the step;
//! 6. [`stages::heat_stage`]: heat over Δt_C (`thm-fvm-heat`), advected by the step's mean
//!    channel mass rates, fluid capacities from the flow's phase masses, Nusselt interface
//!    (A-Eqs. 43–45); then the pores are closed again at their new temperatures;
//! 7. [`stages::sphere_radii`]: sphere temperatures to radii (A-Eq. 55);
//! 8. [`stages::remesh`]: remesh on trigger and conservative remap of liquid and gas mass and
//!    of fluid and solid energy. New pores that no old fluid covered (a sphere shrank, a gap
//!    opened) are filled from their channel neighbours ([`stages::fill_uncovered_pores`]) and
//!    pores the remap overfilled are levelled with theirs ([`stages::spill_overfilled_pores`]),
//!    both conserving every total to round-off. A pore that one mesh motion leaves with less
//!    than half its volume ([`stages::shrinking_pore`]: a bond snapped, a gap closed) forces
//!    this stage before the flow stage of the same step, which could not keep its fluid
//!    positive.
//!
//! Each sphere keeps the heat capacity of its mass while A-Eq. 55 shrinks its cross-section:
//! its solid cells share `ρ_s c_s A_ref b` by area (`A_ref` its solid area in the first mesh,
//! [`PoreScaleState::solid_area_ref`]).
//!
//! A fixed skeleton ([`Skeleton::Fixed`], A-Sect. 6 case b and the fluid–heat cases of
//! A-Sects. 4–5) runs stages 1, 5 and 6 of the same step: no DEM step, no motion, no change of
//! radius, no remesh.
//!
//! ## Time-step rule
//!
//! The caller chooses Δt_C (a scenario's `time.step`). Inside it:
//!
//! - the DEM takes `n = ceil(Δt_C / Δt_D)` steps of `Δt_C / n ≤ Δt_D` (Δt_D from the
//!   parameters, below [`thm_dem::critical_time_step`]);
//! - the flow either sub-cycles under its own stability and positivity limits
//!   ([`FlowScheme::Explicit`]; `thm-vpn-flow`: the Gershgorin bound of the linearised
//!   pressure equation and at most half of a phase's mass per sub-step) or takes linearly
//!   implicit pressure sub-steps ([`FlowScheme::Implicit`]: one per coupled step unless a
//!   pore would lose half a phase or the closure rejects it), the choice for water-filled
//!   pores, whose explicit limit is ~10⁻⁸ s;
//! - the heat either sub-cycles under its explicit limit ([`HeatScheme::Explicit`]) or takes
//!   one backward-Euler step with first-order upwind advection ([`HeatScheme::Implicit`]).
//!
//! The fluid forces are held over the DEM steps of one coupled step and the flow and heat
//! see the skeleton at its end, so Δt_C is the coupling lag; the flow's and heat's own limits
//! never depend on the caller's choice.
//!
//! ## Conservation
//!
//! The phase masses change only through channel and boundary fluxes (each added to one pore
//! and taken from the other) and the remap (which conserves totals to round-off), so with no
//! boundary flux the liquid and gas masses stay constant to round-off through every step and
//! remesh. The thermal energy `Σ C (T − T_ref)` (fluid capacities from the phase masses) is
//! changed by the heat stage only through boundary heat and advected enthalpy: the capacity
//! change of a fluid cell by the mass the flow moved is folded into its temperature before the
//! heat step (see [`stages::heat_stage`]).

mod adaptive;
mod error;
mod params;
pub mod pore_forces;
pub mod stages;
mod state;

pub use adaptive::{AdvanceReport, CouplingStepParams, CouplingStepRule, largest_displacement};
pub use error::CouplingError;
pub use params::{
    FlowBoundary, FlowScheme, HeatScheme, PoreScaleConfig, PoreScaleParams, PressureForce, Skeleton,
};
pub use state::{
    InitialFluid, PoreScaleState, cell_capacities, circles_of, contact_normal_stress, contacts_of,
    solid_capacity_scale, sphere_solid_areas, sphere_temperatures,
};

use std::time::Instant;
use thm_dem::{CohesiveFrictional, Stepper, StepperParams};
use thm_fvm_heat::{FlowInput, HeatGeometry, HeatModel, HeatStepper};
use thm_vpn_flow::{FlowStepper, Network, PoreFluid};
use thm_vpn_mesh::{MeshMotion, RemeshReason};

use stages::{FlowTransfer, HeatParts};

/// What one coupled step did.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    /// DEM steps taken (0 with a fixed skeleton).
    pub dem_steps: u64,
    /// Flow sub-steps.
    pub flow_substeps: u32,
    /// Heat sub-steps (1 for an implicit step).
    pub heat_substeps: usize,
    /// Largest channel Reynolds number.
    pub max_reynolds: f64,
    /// Why the mesh was rebuilt at the end of the step, if it was.
    pub remeshed: Option<RemeshReason>,
    /// Energy \[J\] that entered through the outer boundary in the heat stage (conduction and
    /// the enthalpy of the fluid that crossed it; `HeatStepper::boundary_energy`): the change
    /// of [`PoreScaleState::thermal_energy`] over the step, to round-off.
    pub boundary_energy: f64,
    /// [`Self::boundary_energy`] by boundary side, indexed left, right, bottom, top, outline
    /// (`HeatStepper::boundary_energy_by_side`) \[J\].
    pub boundary_energy_by_side: [f64; 5],
    /// Wall time of each stage \[s\] (a diagnostic for benchmarks; not part of the physics).
    pub stage_seconds: StageSeconds,
}

/// Wall time of the stages of one coupled step \[s\].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageSeconds {
    /// Stage 1: fluid forces on the spheres.
    pub fluid_forces: f64,
    /// Stage 2: the DEM steps.
    pub dem: f64,
    /// Stages 3–4: mesh motion, S2S apertures, the network and heat geometry that follow.
    pub mesh: f64,
    /// Stage 5: flow.
    pub flow: f64,
    /// Stage 6: heat, with the capacities and the closure at the new temperatures.
    pub heat: f64,
    /// Stages 7–8: sphere radii and the remesh (with its remap).
    pub radii_and_remesh: f64,
}

impl StageSeconds {
    /// Adds `other`'s seconds stage by stage.
    pub fn accumulate(&mut self, other: &StageSeconds) {
        self.fluid_forces += other.fluid_forces;
        self.dem += other.dem;
        self.mesh += other.mesh;
        self.flow += other.flow;
        self.heat += other.heat;
        self.radii_and_remesh += other.radii_and_remesh;
    }

    /// `(name, seconds)` of every stage, in stage order.
    pub fn named(&self) -> [(&'static str, f64); 6] {
        [
            ("fluid_forces", self.fluid_forces),
            ("dem", self.dem),
            ("mesh", self.mesh),
            ("flow", self.flow),
            ("heat", self.heat),
            ("radii_and_remesh", self.radii_and_remesh),
        ]
    }
}

/// The coupled stepper: the composed solvers' scratch and what is derived from the state's
/// mesh (the flow network, the heat model and geometry). It holds no evolving state: built
/// afresh from a restored [`PoreScaleState`], it continues a run bit for bit.
#[derive(Debug)]
pub struct PoreScaleStepper<F> {
    config: PoreScaleConfig,
    fluid: F,
    dem: Option<(f64, Stepper<CohesiveFrictional>)>,
    network: Network,
    heat_model: HeatModel,
    heat_geometry: HeatGeometry,
    flow: FlowStepper,
    heat: HeatStepper,
    motion: MeshMotion,
    force: Vec<[f64; 2]>,
    undrained: pore_forces::UndrainedPores,
    dv_dt: Vec<f64>,
    input: FlowInput,
    old_capacity: Vec<f64>,
    new_capacity: Vec<f64>,
}

impl<F: PoreFluid> PoreScaleStepper<F> {
    /// Builds the stepper for `state` (its mesh sets the network and the heat geometry).
    pub fn new(
        config: PoreScaleConfig,
        fluid: F,
        state: &PoreScaleState,
    ) -> Result<Self, CouplingError> {
        let (network, heat_model, heat_geometry) = derived(&config, state)?;
        let input = FlowInput::liquid_at_rest(&state.mesh.mesh, 1.0, 1.0);
        Ok(Self {
            flow: FlowStepper::new(config.flow),
            config,
            fluid,
            dem: None,
            network,
            heat_model,
            heat_geometry,
            heat: HeatStepper::new(),
            motion: MeshMotion::new(),
            force: Vec::new(),
            undrained: Default::default(),
            dv_dt: Vec::new(),
            input,
            old_capacity: Vec::new(),
            new_capacity: Vec::new(),
        })
    }

    /// Rebuilds what the stepper derives from `state` (after the caller replaced the state,
    /// as a rejected adaptive step does): the same as a new stepper for it.
    pub fn rebuild(&mut self, state: &PoreScaleState) -> Result<(), CouplingError> {
        let (network, heat_model, heat_geometry) = derived(&self.config, state)?;
        self.network = network;
        self.heat_model = heat_model;
        self.heat_geometry = heat_geometry;
        self.dem = None;
        self.flow = FlowStepper::new(self.config.flow);
        self.heat = HeatStepper::new();
        self.motion = MeshMotion::new();
        self.input = FlowInput::liquid_at_rest(&state.mesh.mesh, 1.0, 1.0);
        self.force.clear();
        self.dv_dt.clear();
        self.old_capacity.clear();
        self.new_capacity.clear();
        Ok(())
    }

    /// The configuration.
    pub fn config(&self) -> &PoreScaleConfig {
        &self.config
    }

    /// The fluid model.
    pub fn fluid(&self) -> &F {
        &self.fluid
    }

    /// The flow network of the current mesh.
    pub fn network(&self) -> &Network {
        &self.network
    }

    /// The heat solver's input of the last step (fractions, densities, mean mass rates).
    pub fn heat_input(&self) -> &FlowInput {
        &self.input
    }

    /// Mean fluid speed in each channel over the last step \[m/s\]: the step's mean mass
    /// rate over the upwind pore's mixture density, the aperture and the width,
    /// `|ṁ| / (ρ_up h w)` (zero before the first step and in closed channels).
    pub fn channel_speeds(&self, state: &PoreScaleState) -> Vec<f64> {
        let parts = self.network.parts();
        let w = self.network.width();
        let flow = &state.flow;
        (0..self.network.n_channels())
            .map(|c| {
                let m = self.input.channel_mass_flux.get(c).copied().unwrap_or(0.0);
                let [i, j] = parts.channel_pores[c];
                let up = if m >= 0.0 { i } else { j } as usize;
                let a = flow.liquid_fraction[up];
                let rho = a * flow.liquid_density[up] + (1.0 - a) * flow.gas_density[up];
                let h = parts.channel_aperture[c];
                if m == 0.0 || h <= 0.0 || rho <= 0.0 {
                    0.0
                } else {
                    m.abs() / (rho * h * w)
                }
            })
            .collect()
    }

    /// Mean liquid speed in each channel at the state's pressures \[m/s\]: the liquid
    /// layer's flow rate over its thickness (`thm_vpn_flow::stages::channel_liquid_speeds`).
    /// A snapshot of the liquid, unlike [`Self::channel_speeds`] (the step's mean, any phase).
    pub fn liquid_speeds(&self, state: &PoreScaleState) -> Vec<f64> {
        thm_vpn_flow::stages::channel_liquid_speeds(&self.network, &state.flow, &self.config.flow)
    }

    /// The fluid force on each sphere applied in the last step \[N\] (x, y).
    pub fn fluid_force(&self) -> &[[f64; 2]] {
        &self.force
    }

    /// Advances `state` by one coupled step of `dt` \[s\] (see the module docs for the stages).
    /// On error the state is left where the failing stage stopped: restore it from the last
    /// checkpoint.
    pub fn step(
        &mut self,
        state: &mut PoreScaleState,
        dt: f64,
    ) -> Result<StepReport, CouplingError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(CouplingError::Parameter {
                field: "dt",
                range: "> 0 s",
                value: dt,
            });
        }
        self.check(state)?;
        let free = self.config.params.skeleton == params::Skeleton::Free;
        let mut seconds = StageSeconds::default();
        let mut clock = Instant::now();
        let mut lap = |into: &mut f64| {
            let now = Instant::now();
            *into = (now - clock).as_secs_f64();
            clock = now;
        };
        self.old_capacity = cell_capacities(state, &self.config.params.heat);
        let corners = free && self.config.params.pressure_force == PressureForce::CellCorners;
        stages::fluid_forces(
            &self.network,
            &state.flow,
            &self.config.flow,
            &state.mesh_contacts,
            !corners,
            &mut self.force,
            &mut state.dem,
        )?;
        let dt_dem = self.config.params.dem.time_step;
        if corners {
            self.undrained.begin(
                &state.mesh,
                self.network.pore_cell(),
                &state.flow,
                &self.fluid,
                &state.dem,
                &self.force,
            )?;
            self.undrained.add_start_forces(&mut self.force);
        }
        let (h, n) = dem_substeps(dt_dem, dt);
        lap(&mut seconds.fluid_forces);
        let mut dem_steps = 0;
        let mut remeshed = None;
        if free {
            let undrained = corners.then_some(&mut self.undrained);
            let dem = match &mut self.dem {
                Some((old, s)) if *old == h => s,
                _ => Self::new_dem_stepper(&mut self.dem, &self.config, h)?,
            };
            stages::dem_steps(
                dem,
                h,
                n,
                &mut state.dem,
                &mut state.rotation,
                undrained,
                state.flow.step,
            )?;
            dem_steps = n;
            lap(&mut seconds.dem);
            stages::mesh_motion(
                &mut self.motion,
                &mut state.mesh,
                &state.dem,
                &state.rotation,
                &state.radius_rate,
            )?;
            stages::s2s_apertures(
                &mut state.mesh,
                &state.mesh_contacts,
                &state.dem,
                &self.config.mesh.params().s2s,
            )?;
            self.network = Network::from_mesh(
                &state.mesh.mesh,
                &self.config.flow_boundaries(),
                self.config.params.boundary_reduction_factor,
            )
            .map_err(CouplingError::Flow)?;
            self.heat_geometry
                .update_positions(&self.heat_model, &state.mesh.mesh)
                .map_err(CouplingError::Heat)?;
            self.heat_geometry
                .set_solid_capacity_scale(
                    &state.mesh.mesh,
                    &solid_capacity_scale(&state.mesh.mesh, &state.solid_area_ref),
                )
                .map_err(CouplingError::Heat)?;
            // A pore that this motion nearly closed: rebuild the mesh before the flow stage
            // (the remap conserves mass and energy, so the step continues on the new mesh).
            if let Some(reason) = stages::shrinking_pore(&self.network, &state.mesh, &state.flow) {
                remeshed = self.remesh_stage(state, Some(reason))?;
                self.old_capacity = cell_capacities(state, &self.config.params.heat);
            }
            lap(&mut seconds.mesh);
        }
        let FlowTransfer {
            substeps: flow_substeps,
            max_reynolds,
        } = stages::flow_stage(
            &mut self.flow,
            &self.network,
            &self.fluid,
            &state.mesh,
            free,
            self.config.params.flow_scheme,
            self.config.params.liquid_tension,
            &mut state.flow,
            &mut self.dv_dt,
            &mut self.input,
            [
                self.config.params.heat.liquid.specific_heat,
                self.config.params.heat.gas.specific_heat,
            ],
            dt,
        )?;
        lap(&mut seconds.flow);
        self.new_capacity = cell_capacities(state, &self.config.params.heat);
        let heat_substeps = stages::heat_stage(
            &mut self.heat,
            HeatParts {
                params: &self.config.params.heat,
                model: &self.heat_model,
                geometry: &self.heat_geometry,
                scheme: self.config.params.heat_scheme,
            },
            &state.mesh,
            &self.network,
            (&self.old_capacity, &self.new_capacity),
            &self.input,
            &self.fluid,
            &mut state.flow,
            &mut state.heat,
            dt,
        )?;
        lap(&mut seconds.heat);
        let boundary_energy = self.heat.boundary_energy();
        let boundary_energy_by_side = self.heat.boundary_energy_by_side();
        if free {
            stages::sphere_radii(
                &state.mesh,
                &state.heat,
                self.config.params.thermal_expansion,
                &mut state.dem,
                &mut state.radius_rate,
                dt,
            )?;
            if let Some(reason) = self.remesh_stage(state, None)? {
                remeshed = Some(reason);
            }
        }
        if free {
            lap(&mut seconds.radii_and_remesh);
        }
        state.step += 1;
        state.time += dt;
        Ok(StepReport {
            dem_steps,
            flow_substeps,
            heat_substeps,
            max_reynolds,
            remeshed,
            boundary_energy,
            boundary_energy_by_side,
            stage_seconds: seconds,
        })
    }

    /// A new DEM stepper for sub-steps of `h`, stored in `slot`.
    fn new_dem_stepper<'a>(
        slot: &'a mut Option<(f64, Stepper<CohesiveFrictional>)>,
        config: &PoreScaleConfig,
        h: f64,
    ) -> Result<&'a mut Stepper<CohesiveFrictional>, CouplingError> {
        let params = StepperParams {
            time_step: h,
            ..config.params.dem
        };
        let validated = params.validate().map_err(CouplingError::Dem)?;
        let (_, s) = slot.insert((h, Stepper::new(config.law, validated)));
        Ok(s)
    }

    fn check(&self, state: &PoreScaleState) -> Result<(), CouplingError> {
        let n = state.dem.particles.len();
        for (what, got, expected) in [
            ("rotation", state.rotation.len(), n),
            ("radius_rate", state.radius_rate.len(), n),
            ("mesh circles", state.mesh.circles.len(), n),
            ("flow pores", state.flow.n_pores(), self.network.n_pores()),
            (
                "heat temperatures",
                state.heat.temperature.len(),
                state.mesh.mesh.n_cells(),
            ),
        ] {
            if got != expected {
                return Err(CouplingError::StateMismatch {
                    what,
                    got,
                    expected,
                });
            }
        }
        Ok(())
    }
}

/// `(h, n)`: `n = ceil(dt / dt_dem)` DEM steps of `h = dt / n`.
pub fn dem_substeps(dt_dem: f64, dt: f64) -> (f64, u64) {
    let n = ((dt / dt_dem) * (1.0 - 1e-12)).ceil().max(1.0) as u64;
    (dt / n as f64, n)
}

impl<F: PoreFluid> PoreScaleStepper<F> {
    /// Stage 8 (or a remesh forced by `forced`): when the criteria or `forced` ask, a new mesh
    /// of the spheres as they are, the conservative remap of the fluid masses and energies,
    /// and everything that derives from the mesh rebuilt. Returns why it remeshed.
    fn remesh_stage(
        &mut self,
        state: &mut PoreScaleState,
        forced: Option<RemeshReason>,
    ) -> Result<Option<RemeshReason>, CouplingError> {
        let Some(r) = stages::remesh(
            forced,
            &self.config.mesh,
            &self.config.remesh,
            &self.config.flow_boundaries(),
            self.config.params.boundary_reduction_factor,
            &self.config.params.heat,
            &self.fluid,
            &self.network,
            state,
        )?
        else {
            return Ok(None);
        };
        state.mesh = r.mesh;
        state.mesh_contacts = r.mesh_contacts;
        state.flow = r.flow;
        state.heat = r.heat;
        state.rotation.fill(0.0);
        state.remeshes += 1;
        // The sphere temperatures of the new cells become T_avg^n, so the remap itself
        // changes no radius.
        let t = state::sphere_temperatures(&state.mesh, &state.heat, &state.dem)?;
        state.dem.particles.temperature = t;
        let (network, model, geometry) = derived(&self.config, state)?;
        self.network = network;
        self.heat_model = model;
        self.heat_geometry = geometry;
        Ok(Some(r.reason))
    }
}

/// The parts of the stepper that follow from the state's mesh.
fn derived(
    config: &PoreScaleConfig,
    state: &PoreScaleState,
) -> Result<(Network, HeatModel, HeatGeometry), CouplingError> {
    let mesh = &state.mesh.mesh;
    let network = Network::from_mesh(
        mesh,
        &config.flow_boundaries(),
        config.params.boundary_reduction_factor,
    )
    .map_err(CouplingError::Flow)?;
    check_pressure_paths(&network)?;
    let model = HeatModel::new(&config.params.heat, mesh).map_err(CouplingError::Heat)?;
    let mut geometry = HeatGeometry::new(&model, mesh).map_err(CouplingError::Heat)?;
    geometry
        .set_solid_capacity_scale(mesh, &solid_capacity_scale(mesh, &state.solid_area_ref))
        .map_err(CouplingError::Heat)?;
    Ok((network, model, geometry))
}

/// The pores that no chain of channels joins to a boundary link: closed clusters whose
/// fluid cannot leave or enter the network (in the water cases they cool at fixed mass and
/// go into tension).
pub fn unconnected_pores(network: &Network) -> usize {
    let parts = network.parts();
    let n = network.n_pores();
    let mut reached = vec![false; n];
    let mut queue: Vec<usize> = (0..network.n_links())
        .map(|k| parts.link_pore[k] as usize)
        .collect();
    for &p in &queue {
        reached[p] = true;
    }
    while let Some(p) = queue.pop() {
        for &k in network.pore_channels(p) {
            let [a, b] = parts.channel_pores[(k & !thm_vpn_flow::SECOND_END) as usize];
            let other = if k & thm_vpn_flow::SECOND_END != 0 {
                a
            } else {
                b
            } as usize;
            if !reached[other] {
                reached[other] = true;
                queue.push(other);
            }
        }
    }
    reached.iter().filter(|r| !**r).count()
}

/// Every two prescribed-pressure boundaries at different pressures are joined by some chain
/// of pores and channels ([`CouplingError::NoPressurePath`] otherwise).
pub fn check_pressure_paths(network: &Network) -> Result<(), CouplingError> {
    use thm_vpn_flow::BoundaryCondition;
    let parts = network.parts();
    let n = network.n_pores();
    // Connected components of the pore graph (union–find with path halving).
    let mut root: Vec<usize> = (0..n).collect();
    fn find(root: &mut [usize], mut a: usize) -> usize {
        while root[a] != a {
            root[a] = root[root[a]];
            a = root[a];
        }
        a
    }
    for &[a, b] in &parts.channel_pores {
        let (ra, rb) = (find(&mut root, a as usize), find(&mut root, b as usize));
        if ra != rb {
            root[ra.max(rb)] = ra.min(rb);
        }
    }
    // Components each pressure boundary reaches, sorted.
    let groups = parts.boundaries.len();
    let mut reach: Vec<Vec<usize>> = vec![Vec::new(); groups];
    for k in 0..network.n_links() {
        let g = parts.link_group[k] as usize;
        let c = find(&mut root, parts.link_pore[k] as usize);
        reach[g].push(c);
    }
    for r in &mut reach {
        r.sort_unstable();
        r.dedup();
    }
    let pressure = |g: usize| match parts.boundaries[g] {
        BoundaryCondition::Pressure { pressure, .. } => Some(pressure),
        _ => None,
    };
    for a in 0..groups {
        for b in a + 1..groups {
            let (Some(pa), Some(pb)) = (pressure(a), pressure(b)) else {
                continue;
            };
            let joined = reach[a].iter().any(|c| reach[b].binary_search(c).is_ok());
            if pa != pb && !joined {
                return Err(CouplingError::NoPressurePath {
                    first: a,
                    first_pressure: pa,
                    second: b,
                    second_pressure: pb,
                });
            }
        }
    }
    Ok(())
}
