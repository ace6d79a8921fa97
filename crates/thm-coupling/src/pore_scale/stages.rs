//! The stages of one coupled step (A-Fig. 7), each a function over caller-owned data that can
//! be tested alone. [`super::PoreScaleStepper::step`] runs them in this order.

use thm_dem::{CohesiveFrictional, DemState, Stepper, Vec3};
use thm_fvm_heat::{FlowInput, HeatGeometry, HeatModel, HeatParams, HeatState, HeatStepper};
use thm_vpn_flow::{
    FlowConfig, FlowState, FlowStepper, Network, PoreFluid, SECOND_END, add_pressure_forces,
    add_shear_forces,
};
use thm_vpn_mesh::{
    CellFilter, CellKind, CircleMotion, Contact, MeshMotion, MeshSettings, PackingMesh,
    RemapOperator, RemeshCriteria, RemeshReason, S2sApertureParams, mesh_packing, remesh_needed,
};

use super::error::CouplingError;
use super::params::{FlowScheme, HeatScheme};
use super::pore_forces::UndrainedPores;
use super::state::{
    circles_of, contact_normal_stress, contacts_of, fluid_capacity, sphere_temperatures,
};

/// Stage 1 (A-Eqs. 52–54): the fluid forces on the spheres from the pore pressures on the wall
/// faces (when `wall_pressure`) and the S2S wall shear, written into
/// `dem.particles.external_force` (x, y; z = 0) and `force` (one entry per sphere).
pub fn fluid_forces(
    network: &Network,
    flow: &FlowState,
    config: &FlowConfig,
    mesh_contacts: &[Contact],
    wall_pressure: bool,
    force: &mut Vec<[f64; 2]>,
    dem: &mut DemState,
) -> Result<(), CouplingError> {
    let n = dem.particles.len();
    force.clear();
    force.resize(n, [0.0; 2]);
    let spheres: Vec<[u32; 2]> = mesh_contacts.iter().map(|c| c.circles).collect();
    if wall_pressure {
        add_pressure_forces(network, flow, force).map_err(CouplingError::Flow)?;
    }
    add_shear_forces(network, flow, config, &spheres, force).map_err(CouplingError::Flow)?;
    for (i, (f, out)) in force
        .iter()
        .zip(&mut dem.particles.external_force)
        .enumerate()
    {
        if !(f[0].is_finite() && f[1].is_finite()) {
            return Err(CouplingError::Unphysical {
                stage: "fluid forces",
                quantity: "fluid force",
                place: "sphere",
                index: i,
                value: if f[0].is_finite() { f[1] } else { f[0] },
                step: flow.step,
                why: "not finite",
            });
        }
        *out = Vec3::new(f[0], f[1], 0.0);
    }
    Ok(())
}

/// Stage 2: `n` DEM steps (the stepper's Δt_D each), and the turn of every sphere about z
/// accumulated into `rotation` for the mesh motion. With `undrained`, the pore pressure
/// forces follow each pore's undrained response before every step
/// ([`super::pore_forces::UndrainedPores::apply`]) and the pores' springs are made implicit
/// after it ([`super::pore_forces::UndrainedPores::implicit_correction`]).
pub fn dem_steps(
    stepper: &mut Stepper<CohesiveFrictional>,
    dt_dem: f64,
    n: u64,
    dem: &mut DemState,
    rotation: &mut [f64],
    mut undrained: Option<&mut UndrainedPores>,
    step: u64,
) -> Result<(), CouplingError> {
    for _ in 0..n {
        if let Some(u) = undrained.as_deref_mut() {
            u.apply(dem, step)?;
        }
        stepper.step(dem).map_err(CouplingError::Dem)?;
        if let Some(u) = undrained.as_deref_mut() {
            u.implicit_correction(dem, dt_dem, step)?;
        }
        for (a, w) in rotation.iter_mut().zip(&dem.particles.angular_velocity) {
            *a += w.z * dt_dem;
        }
    }
    Ok(())
}

/// Stage 3: moves the mesh with the spheres (vertices anchored to their circles, exact
/// geometry of every cell, face and channel; T2T apertures A-Eq. 9 on the moved faces).
pub fn mesh_motion(
    motion: &mut MeshMotion,
    mesh: &mut PackingMesh,
    dem: &DemState,
    rotation: &[f64],
    radius_rate: &[f64],
) -> Result<(), CouplingError> {
    let p = &dem.particles;
    let centre: Vec<[f64; 2]> = p.position.iter().map(|x| [x.x, x.y]).collect();
    let velocity: Vec<[f64; 2]> = p.velocity.iter().map(|v| [v.x, v.y]).collect();
    let omega: Vec<f64> = p.angular_velocity.iter().map(|w| w.z).collect();
    let m = CircleMotion {
        centre: &centre,
        radius: &p.radius,
        rotation,
        velocity: &velocity,
        angular_velocity: &omega,
        radius_rate,
    };
    motion.update(mesh, &m).map_err(CouplingError::Mesh)
}

/// Stage 4: S2S apertures (A-Eq. 8) from the current normal stress of the DEM contact of every
/// mesh contact; the T2T apertures (A-Eq. 9) were set by the mesh motion.
pub fn s2s_apertures(
    mesh: &mut PackingMesh,
    mesh_contacts: &[Contact],
    dem: &DemState,
    law: &S2sApertureParams,
) -> Result<(), CouplingError> {
    let stress: Vec<f64> = mesh_contacts
        .iter()
        .map(|c| contact_normal_stress(dem, c.circles))
        .collect();
    mesh.update_s2s_apertures(&stress, law)
        .map_err(CouplingError::Mesh)
}

/// What the flow stage hands on: the mean mass rates of the step for the heat solver.
#[derive(Debug, Clone, Default)]
pub struct FlowTransfer {
    /// Sub-steps the flow took.
    pub substeps: u32,
    /// Largest channel Reynolds number of the step.
    pub max_reynolds: f64,
}

/// Stage 5: the flow over Δt_C (A-Eqs. 10–15, 24–29). Each pore's dV/dt is the change of its
/// cell volume since the flow state last saw it, divided by `dt`, so the flow volumes track
/// the mesh exactly; a fixed skeleton passes rigid pores. Fills `input` (fractions,
/// densities and the step's mean mass rates through channels and boundary faces) for the
/// heat stage.
#[allow(clippy::too_many_arguments)]
pub fn flow_stage(
    stepper: &mut FlowStepper,
    network: &Network,
    fluid: &impl PoreFluid,
    mesh: &PackingMesh,
    moving: bool,
    scheme: FlowScheme,
    liquid_tension: bool,
    flow: &mut FlowState,
    dv_dt: &mut Vec<f64>,
    input: &mut FlowInput,
    phase_specific_heat: [f64; 2],
    dt: f64,
) -> Result<FlowTransfer, CouplingError> {
    dv_dt.clear();
    if moving {
        dv_dt.extend(
            network
                .pore_cell()
                .iter()
                .zip(&flow.volume)
                .map(|(&c, &v)| (mesh.mesh.cell_volume(c as usize) - v) / dt),
        );
    }
    let report = match scheme {
        FlowScheme::Explicit => stepper.step(network, flow, fluid, dv_dt, dt),
        FlowScheme::Implicit => stepper.implicit_step(network, flow, fluid, dv_dt, dt),
    }
    .map_err(CouplingError::Flow)?;
    if liquid_tension {
        check_flow_with_liquid_tension(flow)?;
    } else {
        check_flow(flow)?;
    }
    let m = &mesh.mesh;
    let nc = m.n_cells();
    input.liquid_fraction.resize(nc, 0.0);
    input.liquid_density.resize(nc, 0.0);
    input.gas_density.resize(nc, 0.0);
    input.channel_mass_flux.clear();
    input.channel_specific_heat.clear();
    for (&m, &m_q) in stepper
        .channel_mass_transfer()
        .iter()
        .zip(stepper.channel_liquid_transfer())
    {
        let (mass, c) = advected_transfer(m, m_q, phase_specific_heat);
        input.channel_mass_flux.push(mass / dt);
        input.channel_specific_heat.push(c);
    }
    input.boundary_mass_flux.clear();
    input.boundary_mass_flux.resize(m.n_faces(), 0.0);
    for (&f, &mass) in network
        .link_faces()
        .iter()
        .zip(stepper.link_mass_transfer())
    {
        // Links carry mass into the domain; the heat solver's face flux is outward.
        input.boundary_mass_flux[f as usize] = -mass / dt;
    }
    for (p, &c) in network.pore_cell().iter().enumerate() {
        let c = c as usize;
        input.liquid_fraction[c] = flow.liquid_fraction[p];
        input.liquid_density[c] = flow.liquid_density[p];
        input.gas_density[c] = flow.gas_density[p];
    }
    Ok(FlowTransfer {
        substeps: report.substeps,
        max_reynolds: report.max_reynolds,
    })
}

/// The specific heat of what a channel carried over a step: `(M_q c_q + M_p c_p) / M` for the
/// phase transfers `M_q` and `M_p = M − M_q` \[J/(kg K)\]. Then `M c` is the heat capacity
/// the two pores exchanged, so the heat step's capacity change of a cell equals its advected
/// capacity and a uniform temperature stays uniform (with the upwind cell's mixture `c`
/// instead, a cell filling with gas and emptying of liquid in other proportions than its
/// neighbour holds drifts: 3·10⁻⁵ K in 0.03 s of case a). In one sub-step both phases flow
/// down the common pressure drop, so `M_q` and `M_p` share the sign of `M` and `c` lies
/// between `c_q` and `c_p`; where sub-steps moved the phases opposite ways the value is
/// clamped to that range, and [`advected_transfer`] changes the mass instead. `c_q` where
/// nothing flowed.
pub fn advected_specific_heat(total: f64, liquid: f64, [c_q, c_p]: [f64; 2]) -> f64 {
    if total == 0.0 {
        return c_q;
    }
    let c = (liquid * c_q + (total - liquid) * c_p) / total;
    let (lo, hi) = (c_q.min(c_p), c_q.max(c_p));
    if c.is_finite() { c.clamp(lo, hi) } else { c_q }
}

/// What the heat step advects through a channel over a step with total and liquid transfers
/// `total`, `liquid` (gas `total − liquid`) \[kg\]: a mass and its specific heat whose product
/// is the heat capacity the two pores exchanged, `K = M_q c_q + M_p c_p`. Where both phases
/// moved the same way (or one did not move) that is `total` with
/// [`advected_specific_heat`]. Where sub-steps moved them opposite ways `K` may have either
/// sign, or none, whatever `total` does; the channel then advects `K / c'` with
/// `c' = (|M_q| c_q + |M_p| c_p) / (|M_q| + |M_p|)`, so that the heat step's upwind side is
/// the side the capacity came from and a cell's capacity change still equals its advected
/// capacity (without this a uniform temperature drifted by 1.4·10⁻⁷ K in case a at 0.02 s,
/// where the clamped specific heat broke the balance).
pub fn advected_transfer(total: f64, liquid: f64, [c_q, c_p]: [f64; 2]) -> (f64, f64) {
    let gas = total - liquid;
    if liquid * gas >= 0.0 {
        return (total, advected_specific_heat(total, liquid, [c_q, c_p]));
    }
    let (aq, ap) = (liquid.abs(), gas.abs());
    let c = (aq * c_q + ap * c_p) / (aq + ap);
    ((liquid * c_q + gas * c_p) / c, c)
}

/// The checks at the flow stage's boundary: finite positive pressure, α_q ∈ [0, 1], finite
/// non-negative masses.
pub fn check_flow(flow: &FlowState) -> Result<(), CouplingError> {
    check_pores(flow, "flow", true)
}

/// [`check_flow`] where pores that hold only liquid may be in tension (a finite negative
/// pressure; [`super::PoreScaleParams::liquid_tension`]).
pub fn check_flow_with_liquid_tension(flow: &FlowState) -> Result<(), CouplingError> {
    check_pores(flow, "flow", false)?;
    match (0..flow.n_pores()).find(|&p| flow.pressure[p] <= 0.0 && flow.gas_mass[p] > 0.0) {
        Some(p) => Err(CouplingError::Unphysical {
            stage: "flow",
            quantity: "pressure",
            place: "pore",
            index: p,
            value: flow.pressure[p],
            step: flow.step,
            why: "not a positive pressure in a pore that holds gas",
        }),
        None => Ok(()),
    }
}

/// The checks after a closure at new temperatures or a remap: as [`check_flow`] but a finite
/// negative pressure passes. A liquid pore cooled at fixed mass contracts and its closure
/// pressure falls by about K β ΔT (MPa per kelvin for water) before the next flow stage can
/// bring in the water that replaces the contraction; that flow stage's check then decides
/// whether the tension is real (a sealed pore) or a lag of the sequential step.
pub fn check_closed(flow: &FlowState, stage: &'static str) -> Result<(), CouplingError> {
    check_pores(flow, stage, false)
}

fn check_pores(
    flow: &FlowState,
    stage: &'static str,
    positive_pressure: bool,
) -> Result<(), CouplingError> {
    let bad = |quantity, index, value, why| CouplingError::Unphysical {
        stage,
        quantity,
        place: "pore",
        index,
        value,
        step: flow.step,
        why,
    };
    for p in 0..flow.n_pores() {
        let pr = flow.pressure[p];
        if !pr.is_finite() {
            return Err(bad("pressure", p, pr, "not finite"));
        }
        if positive_pressure && pr <= 0.0 {
            return Err(bad("pressure", p, pr, "not a positive pressure"));
        }
        let a = flow.liquid_fraction[p];
        if !(0.0..=1.0).contains(&a) {
            return Err(bad("liquid fraction", p, a, "outside [0, 1]"));
        }
        for (q, m) in [
            ("liquid mass", flow.liquid_mass[p]),
            ("gas mass", flow.gas_mass[p]),
        ] {
            if !(m.is_finite() && m >= 0.0) {
                return Err(bad(q, p, m, "negative or not finite"));
            }
        }
    }
    Ok(())
}

/// The solver parts of the heat stage.
#[derive(Debug, Clone, Copy)]
pub struct HeatParts<'a> {
    /// Parameters (specific heats for the capacities, reference temperature).
    pub params: &'a HeatParams,
    /// The validated model.
    pub model: &'a HeatModel,
    /// Mesh-derived coefficients for the mesh as it is now.
    pub geometry: &'a HeatGeometry,
    /// How heat is advanced.
    pub scheme: HeatScheme,
}

/// Stage 6: heat over Δt_C (A-Eqs. 30–51) with the flow's fractions, densities and mean mass
/// rates. A cell's capacity changed over the step: a fluid cell's with the mass the flow
/// moved, a solid cell's with its volume as the sphere moved and expanded. To keep the energy
/// `Σ C (T − T_ref)` of A-Eqs. 39 and 50 exact (`ρ^{n+1} E^{n+1} V^{n+1} − ρ^n E^n V^n`), the
/// implicit step balances `C^{n+1}(T^{n+1} − T_ref) − C^n (T^n − T_ref)` against the step's
/// fluxes (`HeatStepper::implicit_step_with_old_capacity`); the explicit step first
/// re-expresses the temperature at the new capacity, `T ← T_ref + (C^n/C^{n+1})(T − T_ref)`.
/// Either way the advective heat of the step, `ṁ c_p (T_f − T_ref)`, carries the entering
/// enthalpy. `capacity` is `(C^n, C^{n+1})` per cell ([`super::cell_capacities`]).
/// Afterwards the fluid temperatures go to the pores and the flow state is closed again at
/// them (thermal pressurisation, A-Eq. 29). Returns the explicit sub-steps taken.
#[allow(clippy::too_many_arguments)]
pub fn heat_stage(
    stepper: &mut HeatStepper,
    parts: HeatParts<'_>,
    mesh: &PackingMesh,
    network: &Network,
    capacity: (&[f64], &[f64]),
    input: &FlowInput,
    fluid: &impl PoreFluid,
    flow: &mut FlowState,
    heat: &mut HeatState,
    dt: f64,
) -> Result<usize, CouplingError> {
    let t_ref = parts.params.reference_temperature;
    let (old, new) = capacity;
    if old.len() != heat.temperature.len() || new.len() != heat.temperature.len() {
        return Err(CouplingError::StateMismatch {
            what: "cell capacities",
            got: old.len().min(new.len()),
            expected: heat.temperature.len(),
        });
    }
    let m = &mesh.mesh;
    // Solid cells: the sphere's energy re-shared over its cells at their new capacities
    // (one shift per sphere), so the balance below sees no capacity change in the solid.
    reshare_solid_energy(&m.cell_kind, old, new, t_ref, &mut heat.temperature);
    let old: Vec<f64> = old
        .iter()
        .zip(new)
        .zip(&m.cell_kind)
        .map(|((&o, &n), k)| if k.is_fluid() { o } else { n })
        .collect();
    let old = old.as_slice();
    let substeps = match parts.scheme {
        HeatScheme::Explicit => {
            for ((t, &c_old), &c_new) in heat.temperature.iter_mut().zip(old).zip(new) {
                if c_new > 0.0 && c_old != c_new {
                    *t = t_ref + c_old / c_new * (*t - t_ref);
                }
            }
            stepper
                .step(parts.model, parts.geometry, m, input, heat, dt)
                .map_err(CouplingError::Heat)?
                .substeps
        }
        HeatScheme::Implicit => {
            // The same balance without the intermediate temperature, which leaves the
            // physical range when a cell loses most of its fluid in one step.
            stepper
                .implicit_step_with_old_capacity(
                    parts.model,
                    parts.geometry,
                    m,
                    input,
                    heat,
                    old,
                    dt,
                )
                .map_err(CouplingError::Heat)?;
            1
        }
    };
    for (c, &t) in heat.temperature.iter().enumerate() {
        if !(t.is_finite() && t > 0.0) {
            return Err(CouplingError::Unphysical {
                stage: "heat",
                quantity: "temperature",
                place: "cell",
                index: c,
                value: t,
                step: flow.step,
                why: "not a finite positive temperature",
            });
        }
    }
    for (p, &c) in network.pore_cell().iter().enumerate() {
        flow.temperature[p] = heat.temperature[c as usize];
    }
    flow.close(fluid).map_err(CouplingError::Flow)?;
    check_closed(flow, "heat")?;
    Ok(substeps)
}

/// A sphere keeps the heat capacity of its mass, shared over its solid cells by area; when a
/// mesh motion changes those areas (a chord moves as two spheres approach or part), each
/// cell's capacity changes while the sphere's does not. Holding each cell's energy would heat
/// a shrinking cell and cool a growing one (a cell that loses half its area would double its
/// excess over `T_ref`); holding its temperature would change the sphere's energy. Instead
/// every cell of sphere `s` is shifted by the same
/// `δ_s = Σ (C^n − C^{n+1})(T − T_ref) / Σ C^{n+1}`, which keeps the sphere's energy to
/// round-off and a uniform sphere uniform. Fluid cells are left alone.
pub fn reshare_solid_energy(
    kind: &[CellKind],
    old_capacity: &[f64],
    new_capacity: &[f64],
    t_ref: f64,
    temperature: &mut [f64],
) {
    let spheres = kind
        .iter()
        .filter_map(|k| match k {
            CellKind::Solid { owner } => Some(*owner as usize + 1),
            CellKind::Fluid => None,
        })
        .max()
        .unwrap_or(0);
    let (mut excess, mut capacity) = (vec![0.0; spheres], vec![0.0; spheres]);
    for (c, k) in kind.iter().enumerate() {
        if let CellKind::Solid { owner } = *k {
            let s = owner as usize;
            excess[s] += (old_capacity[c] - new_capacity[c]) * (temperature[c] - t_ref);
            capacity[s] += new_capacity[c];
        }
    }
    for (c, k) in kind.iter().enumerate() {
        if let CellKind::Solid { owner } = *k {
            let s = owner as usize;
            if capacity[s] > 0.0 {
                temperature[c] += excess[s] / capacity[s];
            }
        }
    }
}

/// Stage 7 (A-Eq. 55): the volume-average temperature of each sphere's solid cells changes
/// its radius, `r^{n+1} = r^n (1 + α_exp (T_avg^{n+1} − T_avg^n))`; `radius_rate` gets
/// `Δr/dt`. A sphere without solid cells keeps its radius.
pub fn sphere_radii(
    mesh: &PackingMesh,
    heat: &HeatState,
    expansion: f64,
    dem: &mut DemState,
    radius_rate: &mut [f64],
    dt: f64,
) -> Result<(), CouplingError> {
    let t_new = sphere_temperatures(mesh, heat, dem)?;
    let old = dem.particles.radius.clone();
    dem.particles
        .expand_incremental(expansion, &t_new)
        .map_err(CouplingError::Dem)?;
    for ((rate, r), r0) in radius_rate.iter_mut().zip(&dem.particles.radius).zip(&old) {
        *rate = (r - r0) / dt;
    }
    Ok(())
}

/// The result of a remesh: the new mesh and its contacts, the remapped fluid and heat states.
#[derive(Debug)]
pub struct Remeshed {
    /// Why the mesh was rebuilt.
    pub reason: RemeshReason,
    /// The new mesh.
    pub mesh: PackingMesh,
    /// Its contacts.
    pub mesh_contacts: Vec<Contact>,
    /// The network of the new mesh.
    pub network: Network,
    /// The remapped flow state (closed).
    pub flow: FlowState,
    /// The remapped temperatures.
    pub heat: HeatState,
}

/// Stage 8 (A-Sect. 2.4): when the packing has changed enough since the mesh was built
/// ([`remesh_needed`]), a new mesh of the spheres as they are, and the conservative remap of
/// the liquid and gas masses (to fluid cells) and of the thermal energy `C (T − T_ref)` (fluid
/// energy to fluid cells, solid energy to the same sphere's solid cells); the new temperatures
/// are energy over the new capacities, and pressures and fractions follow from the remapped
/// masses through the closure (A-Eq. 29). `None` when no remesh is needed.
#[allow(clippy::too_many_arguments)]
pub fn remesh(
    forced: Option<RemeshReason>,
    settings: &MeshSettings,
    criteria: &RemeshCriteria,
    boundaries: &[(thm_vpn_mesh::BoundarySide, thm_vpn_flow::BoundaryCondition)],
    boundary_reduction_factor: f64,
    heat_params: &HeatParams,
    fluid: &impl PoreFluid,
    network: &Network,
    state: &super::PoreScaleState,
) -> Result<Option<Remeshed>, CouplingError> {
    let dem = &state.dem;
    let p = &dem.particles;
    let centre: Vec<[f64; 2]> = p.position.iter().map(|x| [x.x, x.y]).collect();
    let velocity: Vec<[f64; 2]> = p.velocity.iter().map(|v| [v.x, v.y]).collect();
    let omega: Vec<f64> = p.angular_velocity.iter().map(|w| w.z).collect();
    let motion = CircleMotion {
        centre: &centre,
        radius: &p.radius,
        rotation: &state.rotation,
        velocity: &velocity,
        angular_velocity: &omega,
        radius_rate: &state.radius_rate,
    };
    let circles = circles_of(dem);
    let contacts = contacts_of(dem, &circles);
    let segments = settings.params().segments_per_circle;
    let reason = match forced {
        Some(r) => r,
        None => match remesh_needed(&state.mesh, &motion, &contacts, segments, criteria)
            .map_err(CouplingError::Mesh)?
        {
            Some(r) => r,
            None => return Ok(None),
        },
    };
    // The run keeps the thickness of its first mesh (A-Sect. 2.4: the largest diameter of the
    // packing). Re-deriving it from the spheres as they are would change every cell volume
    // at each remesh by the change of the largest diameter (3 % over A-Sect. 6 case a as the
    // spheres cool), so the pores' pressures and the spheres' heat capacities would jump.
    let pinned;
    let settings = if settings.params().thickness.is_none() {
        let mut p = *settings.params();
        p.thickness = Some(state.mesh.mesh.thickness);
        pinned = p.validate().map_err(CouplingError::Mesh)?;
        &pinned
    } else {
        settings
    };
    let new = mesh_packing(&circles, &contacts, settings).map_err(CouplingError::Mesh)?;
    let old_mesh = &state.mesh.mesh;
    let op = RemapOperator::new(old_mesh, &new.mesh).map_err(CouplingError::Mesh)?;
    let (no, nn) = (old_mesh.n_cells(), new.mesh.n_cells());
    let t_ref = heat_params.reference_temperature;
    // Old extensive fields per cell.
    let mut mq = vec![0.0; no];
    let mut mp = vec![0.0; no];
    let mut e_fluid = vec![0.0; no];
    for (q, &c) in network.pore_cell().iter().enumerate() {
        let c = c as usize;
        mq[c] = state.flow.liquid_mass[q];
        mp[c] = state.flow.gas_mass[q];
        e_fluid[c] =
            fluid_capacity(mq[c], mp[c], heat_params) * (state.heat.temperature[c] - t_ref);
    }
    let old_solid =
        super::state::solid_cell_capacities(old_mesh, heat_params, &state.solid_area_ref);
    let remap = |filter, old: &[f64]| -> Result<Vec<f64>, CouplingError> {
        let mut out = vec![0.0; nn];
        op.apply(filter, old, &mut out)
            .map_err(CouplingError::Mesh)?;
        Ok(out)
    };
    let (mut nq, mut np_, mut nef) = (
        remap(CellFilter::Fluid, &mq)?,
        remap(CellFilter::Fluid, &mp)?,
        remap(CellFilter::Fluid, &e_fluid)?,
    );
    let new_network = Network::from_mesh(&new.mesh, boundaries, boundary_reduction_factor)
        .map_err(CouplingError::Flow)?;
    let volume = new_network.pore_volumes(&new.mesh);
    fill_uncovered_pores(
        &new_network,
        &volume,
        [&mut nq, &mut np_, &mut nef],
        state.step,
    )?;
    spill_overfilled_pores(&new_network, &volume, [&mut nq, &mut np_, &mut nef]);
    let new_solid =
        super::state::solid_cell_capacities(&new.mesh, heat_params, &state.solid_area_ref);
    let mut temperature = remap_solid_temperature(
        &op,
        SolidCells {
            kind: &old_mesh.cell_kind,
            capacity: &old_solid,
            temperature: &state.heat.temperature,
        },
        &new.mesh.cell_kind,
        &new_solid,
        t_ref,
        state.step,
    )?;
    let pores = new_network.n_pores();
    let (mut lq, mut lp, mut tp) = (
        Vec::with_capacity(pores),
        Vec::with_capacity(pores),
        Vec::with_capacity(pores),
    );
    for (q, &c) in new_network.pore_cell().iter().enumerate() {
        let c = c as usize;
        let cap = fluid_capacity(nq[c], np_[c], heat_params);
        if cap.is_nan() || cap <= 0.0 {
            return Err(CouplingError::Unphysical {
                stage: "remesh",
                quantity: "fluid mass",
                place: "pore",
                index: q,
                value: nq[c] + np_[c],
                step: state.step,
                why: "zero after the remap and the filling of uncovered pores",
            });
        }
        temperature[c] = t_ref + nef[c] / cap;
        lq.push(nq[c]);
        lp.push(np_[c]);
        tp.push(temperature[c]);
    }
    let mut flow = FlowState::from_masses(&new_network, volume, tp, lq, lp, fluid)
        .map_err(CouplingError::Flow)?;
    flow.step = state.flow.step;
    flow.time = state.flow.time;
    flow.boundary_liquid_inflow = state.flow.boundary_liquid_inflow.clone();
    flow.boundary_gas_inflow = state.flow.boundary_gas_inflow.clone();
    check_closed(&flow, "remesh")?;
    let heat = HeatState {
        time: state.heat.time,
        steps: state.heat.steps,
        temperature,
    };
    Ok(Some(Remeshed {
        reason,
        mesh: new,
        mesh_contacts: contacts,
        network: new_network,
        flow,
        heat,
    }))
}

/// The solid cells of the old mesh, as [`remap_solid_temperature`] reads them.
#[derive(Debug, Clone, Copy)]
pub struct SolidCells<'a> {
    /// Kind of every cell (fluid cells are skipped).
    pub kind: &'a [CellKind],
    /// Heat capacity of every cell \[J/K\] (zero for fluid cells).
    pub capacity: &'a [f64],
    /// Temperature of every cell \[K\].
    pub temperature: &'a [f64],
}

/// The solid part of stage 8: temperatures of the new solid cells, sphere by sphere, so that
/// each sphere keeps its thermal energy `Σ C (T − T_ref)` to round-off and a sphere of uniform
/// temperature stays uniform.
///
/// Each new solid cell first takes the overlap-weighted mean temperature of the old cells of
/// the same sphere it overlaps (the sphere's mean temperature where it overlaps none); then
/// every cell of the sphere is shifted by the same `δ = (E_old − Σ C_new (T̃ − T_ref)) / Σ C_new`
/// so that the sphere's energy is what it was. Moving energy instead (each old cell's
/// `C (T − T_ref)` split over the admissible new cells it overlaps) concentrates a large old
/// cell's energy in a small new one wherever the new mesh puts the sphere's boundary elsewhere
/// (chords move as contacts open and close), giving temperatures far outside the old range.
/// Fluid cells get `t_ref`; the caller fills them from the fluid remap.
pub fn remap_solid_temperature(
    op: &RemapOperator,
    old: SolidCells<'_>,
    new_kind: &[CellKind],
    new_capacity: &[f64],
    t_ref: f64,
    step: u64,
) -> Result<Vec<f64>, CouplingError> {
    let owner = |k: CellKind| match k {
        CellKind::Solid { owner } => Some(owner as usize),
        CellKind::Fluid => None,
    };
    let spheres = old
        .kind
        .iter()
        .chain(new_kind)
        .filter_map(|&k| owner(k))
        .max()
        .map_or(0, |m| m + 1);
    // Per sphere: old energy and capacity.
    let (mut energy, mut old_cap) = (vec![0.0; spheres], vec![0.0; spheres]);
    for (o, &k) in old.kind.iter().enumerate() {
        if let Some(s) = owner(k) {
            energy[s] += old.capacity[o] * (old.temperature[o] - t_ref);
            old_cap[s] += old.capacity[o];
        }
    }
    // Overlap-weighted mean of the same sphere's old temperatures on each new cell.
    let nn = new_kind.len();
    let (mut weighted, mut covered) = (vec![0.0; nn], vec![0.0; nn]);
    for (o, &k) in old.kind.iter().enumerate() {
        let Some(s) = owner(k) else { continue };
        for (n, a) in op.overlaps(o) {
            if owner(new_kind[n as usize]) == Some(s) {
                weighted[n as usize] += a * old.temperature[o];
                covered[n as usize] += a;
            }
        }
    }
    let mut temperature = vec![t_ref; nn];
    let mut new_energy = vec![0.0; spheres];
    let mut new_cap = vec![0.0; spheres];
    for n in 0..nn {
        let Some(s) = owner(new_kind[n]) else {
            continue;
        };
        temperature[n] = if covered[n] > 0.0 {
            weighted[n] / covered[n]
        } else if old_cap[s] > 0.0 {
            t_ref + energy[s] / old_cap[s]
        } else {
            t_ref
        };
        new_energy[s] += new_capacity[n] * (temperature[n] - t_ref);
        new_cap[s] += new_capacity[n];
    }
    for s in 0..spheres {
        if old_cap[s] > 0.0 && new_cap[s] <= 0.0 {
            return Err(CouplingError::Unphysical {
                stage: "remesh",
                quantity: "solid heat capacity",
                place: "sphere",
                index: s,
                value: new_cap[s],
                step,
                why: "the new mesh gives the sphere no solid cell to hold its energy",
            });
        }
    }
    for n in 0..nn {
        if let Some(s) = owner(new_kind[n]) {
            temperature[n] += (energy[s] - new_energy[s]) / new_cap[s];
        }
    }
    Ok(temperature)
}

/// A pore whose cell keeps less than this fraction of its volume after one mesh motion
/// forces a remesh before the flow stage ([`shrinking_pore`]).
pub const SHRINK_REMESH_RATIO: f64 = 0.5;

/// After the mesh motion of a free skeleton: the first pore whose cell now has less than
/// [`SHRINK_REMESH_RATIO`] of the volume the flow state holds for it (a pore closing as a
/// bond snaps or a contact closes), as the reason to rebuild the mesh before the flow stage,
/// which could not keep its fluid positive. Any cell (fluid or solid) at or below zero area
/// is [`RemeshReason::InvertedCell`].
pub fn shrinking_pore(
    network: &Network,
    mesh: &PackingMesh,
    flow: &FlowState,
) -> Option<RemeshReason> {
    if let Some(cell) = thm_vpn_mesh::inverted_cell(&mesh.mesh) {
        return Some(RemeshReason::InvertedCell { cell });
    }
    network
        .pore_cell()
        .iter()
        .zip(&flow.volume)
        .find_map(|(&c, &v)| {
            let cell = c as usize;
            let value = mesh.mesh.cell_volume(cell) / v;
            (value < SHRINK_REMESH_RATIO).then_some(RemeshReason::ShrunkCell { cell, value })
        })
}

/// The pores joined to pore `p` by a channel (the network's own adjacency).
fn neighbour_pores(network: &Network, p: usize) -> impl Iterator<Item = usize> + '_ {
    let ends = &network.parts().channel_pores;
    network.pore_channels(p).iter().filter_map(move |&k| {
        let [a, b] = ends[(k & !SECOND_END) as usize];
        let other = if k & SECOND_END != 0 { a } else { b } as usize;
        (other != p).then_some(other)
    })
}

/// A new pore whose remapped fluid density is above this multiple of its group's (itself
/// and the pores its channels join) or of the whole network's spills the excess by
/// [`spill_overfilled_pores`].
pub const OVERFILLED_DENSITY_RATIO: f64 = 1.2;

/// Passes of [`spill_overfilled_pores`] at most (each levels every overfilled pore with its
/// lower neighbours; a squeezed cluster spreads over one more channel layer per pass).
pub const MAX_SPILL_PASSES: usize = 10_000;

/// Spills the excess of new pores that the remap overfilled (fluid of an old pore that the
/// skeleton squeezed within one step, which the flow had no time to move). A pore is
/// overfilled when its density is above [`OVERFILLED_DENSITY_RATIO`] times the smaller of its
/// group's (itself and the pores its channels join) and the whole network's mean density.
/// Each such pore, in index order, levels itself with its lower neighbours: with `ρ_g` the
/// common density of the pore and the neighbours below `ρ_g`, it keeps `ρ_g V_e` and each of
/// them receives `(ρ_g − ρ_j) V_j`, all with the pore's liquid/gas split and specific energy.
/// Passes repeat until none spills (at most [`MAX_SPILL_PASSES`]), so a squeezed cluster
/// spreads outwards one channel layer per pass. Every total is kept to round-off. `fields`
/// are cell-indexed (liquid mass, gas mass, fluid energy). Returns the levellings made.
pub fn spill_overfilled_pores(
    network: &Network,
    volume: &[f64],
    fields: [&mut Vec<f64>; 3],
) -> usize {
    let cell = network.pore_cell();
    let n = cell.len();
    let [mq, mp, ef] = fields;
    let mass = |q: usize, mq: &[f64], mp: &[f64]| {
        let c = cell[q] as usize;
        mq[c] + mp[c]
    };
    let density = |q: usize, mq: &[f64], mp: &[f64]| mass(q, mq, mp) / volume[q];
    let global = (0..n).map(|q| mass(q, mq, mp)).sum::<f64>() / volume.iter().sum::<f64>();
    let mut spilled = 0;
    let mut lower: Vec<usize> = Vec::new();
    let mut gift: Vec<f64> = Vec::new();
    for _pass in 0..MAX_SPILL_PASSES {
        let before = spilled;
        for e in 0..n {
            let m_e = mass(e, mq, mp);
            let (m_nb, v_nb) = neighbour_pores(network, e)
                .fold((0.0, 0.0), |(m, v), j| (m + mass(j, mq, mp), v + volume[j]));
            if v_nb <= 0.0 || m_e <= 0.0 {
                continue;
            }
            let rho_e = m_e / volume[e];
            let target = global.min((m_e + m_nb) / (volume[e] + v_nb));
            if rho_e <= OVERFILLED_DENSITY_RATIO * target {
                continue;
            }
            // The level ρ_g of e and its lower neighbours, dropping those above it until none
            // is: e keeps ρ_g V_e and each remaining neighbour j receives (ρ_g − ρ_j) V_j,
            // which add up to e's excess.
            lower.clear();
            lower.extend(neighbour_pores(network, e).filter(|&j| density(j, mq, mp) < rho_e));
            // Each pass drops at least one neighbour or ends.
            let level = loop {
                let (m, v) = lower.iter().fold((m_e, volume[e]), |(m, v), &j| {
                    (m + mass(j, mq, mp), v + volume[j])
                });
                let level = m / v;
                let kept = lower.len();
                lower.retain(|&j| density(j, mq, mp) < level);
                if lower.len() == kept {
                    break level;
                }
            };
            if lower.is_empty() {
                continue;
            }
            gift.clear();
            gift.extend(
                lower
                    .iter()
                    .map(|&j| (level - density(j, mq, mp)) * volume[j]),
            );
            let total: f64 = gift.iter().sum();
            let f = 1.0 - level * volume[e] / m_e;
            let ce = cell[e] as usize;
            for field in [&mut *mq, &mut *mp, &mut *ef] {
                let out = f * field[ce];
                field[ce] -= out;
                for (&j, &g) in lower.iter().zip(&gift) {
                    field[cell[j] as usize] += out * g / total;
                }
            }
            spilled += 1;
        }
        if spilled == before {
            break;
        }
    }
    spilled
}

/// A new pore whose remapped fluid density is below this fraction of its neighbours' is
/// filled from them by [`fill_uncovered_pores`].
pub const UNCOVERED_DENSITY_FRACTION: f64 = 0.01;

/// Fills the new pores that the old fluid cells did not cover (space that was solid: a
/// sphere that shrank, a gap that opened): each such pore, in index order, takes the share
/// `f = V_e / (V_e + Σ V_j)` of the liquid mass, gas mass and fluid energy of each pore `j`
/// joined to it by a channel, so donors keep their temperatures, all densities in the group
/// end near the group's mean, and every total is kept to round-off. This is the fluid
/// filling the new pore volume (A-Sect. 6.1: "the pressure drop was produced by an increase
/// in fluid volume in the damaged area"). A pore is uncovered when its remapped mass per
/// volume is below [`UNCOVERED_DENSITY_FRACTION`] of its neighbours'; pores whose neighbours
/// are all uncovered are filled in a later pass. `fields` are cell-indexed (liquid mass, gas
/// mass, fluid energy).
pub fn fill_uncovered_pores(
    network: &Network,
    volume: &[f64],
    fields: [&mut Vec<f64>; 3],
    step: u64,
) -> Result<usize, CouplingError> {
    let cell = network.pore_cell();
    let n = cell.len();
    let [mq, mp, ef] = fields;
    let mass = |q: usize, mq: &[f64], mp: &[f64]| {
        let c = cell[q] as usize;
        mq[c] + mp[c]
    };
    let mut filled = 0;
    // Each pass fills at least one pore or stops; n passes bound any cascade.
    for _pass in 0..n.max(1) {
        let mut changed = false;
        let mut remaining = 0;
        for e in 0..n {
            let density_e = mass(e, mq, mp) / volume[e];
            let (m_nb, v_nb) = neighbour_pores(network, e)
                .fold((0.0, 0.0), |(m, v), j| (m + mass(j, mq, mp), v + volume[j]));
            if v_nb <= 0.0 || m_nb <= 0.0 {
                if density_e.is_nan() || density_e <= 0.0 {
                    remaining += 1;
                }
                continue;
            }
            if density_e >= UNCOVERED_DENSITY_FRACTION * m_nb / v_nb {
                continue;
            }
            let f = volume[e] / (volume[e] + v_nb);
            let ce = cell[e] as usize;
            for j in neighbour_pores(network, e) {
                let cj = cell[j] as usize;
                for field in [&mut *mq, &mut *mp, &mut *ef] {
                    let share = f * field[cj];
                    field[cj] -= share;
                    field[ce] += share;
                }
            }
            filled += 1;
            changed = true;
        }
        if remaining == 0 || !changed {
            break;
        }
    }
    if let Some(q) = (0..n).find(|&q| mass(q, mq, mp).is_nan() || mass(q, mq, mp) <= 0.0) {
        return Err(CouplingError::Unphysical {
            stage: "remesh",
            quantity: "fluid mass",
            place: "pore",
            index: q,
            value: mass(q, mq, mp),
            step,
            why: "zero after the remap, and no channel joins it to a pore holding fluid",
        });
    }
    Ok(filled)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pore_scale::Skeleton;
    use crate::verification::{eager_remesh, lattice_params, lattice_state};

    /// The old mesh of the test lattice and a new one with every sphere moved by a different
    /// fraction of its radius (chords and arcs land elsewhere), with the overlap operator.
    fn moved_meshes() -> (PackingMesh, PackingMesh, RemapOperator) {
        let config = lattice_params(Skeleton::Free, eager_remesh())
            .validate()
            .expect("params");
        let s = lattice_state(&config).expect("state");
        let mut dem = s.dem.clone();
        for (i, x) in dem.particles.position.iter_mut().enumerate() {
            let r = dem.particles.radius[i];
            x.x += 0.03 * r * ((i * 7 % 5) as f64 - 2.0);
            x.y += 0.02 * r * ((i * 3 % 4) as f64 - 1.5);
        }
        let circles = circles_of(&dem);
        let contacts = contacts_of(&dem, &circles);
        let new = mesh_packing(&circles, &contacts, &config.mesh).expect("new mesh");
        let op = RemapOperator::new(&s.mesh.mesh, &new.mesh).expect("operator");
        (s.mesh, new, op)
    }

    fn capacities(mesh: &PackingMesh) -> Vec<f64> {
        (0..mesh.mesh.n_cells())
            .map(|c| match mesh.mesh.cell_kind[c] {
                CellKind::Solid { .. } => 2.0e6 * mesh.mesh.cell_volume(c),
                CellKind::Fluid => 0.0,
            })
            .collect()
    }

    fn sphere_energy(mesh: &PackingMesh, cap: &[f64], t: &[f64], t_ref: f64) -> Vec<f64> {
        let mut e = vec![0.0; mesh.circles.len()];
        for c in 0..mesh.mesh.n_cells() {
            if let CellKind::Solid { owner } = mesh.mesh.cell_kind[c] {
                e[owner as usize] += cap[c] * (t[c] - t_ref);
            }
        }
        e
    }

    #[test]
    fn resharing_keeps_each_sphere_energy_and_a_uniform_sphere_uniform() {
        let (old, _, _) = moved_meshes();
        let kind = &old.mesh.cell_kind;
        let t_ref = 293.15;
        let c_old = capacities(&old);
        // Areas change cell by cell; each sphere's total stays.
        let mut c_new: Vec<f64> = c_old
            .iter()
            .enumerate()
            .map(|(c, &x)| x * (1.0 + 0.4 * ((c * 13 % 7) as f64 / 7.0 - 0.5)))
            .collect();
        let (a, b) = (
            sphere_energy(&old, &c_old, &vec![t_ref + 1.0; kind.len()], t_ref),
            sphere_energy(&old, &c_new, &vec![t_ref + 1.0; kind.len()], t_ref),
        );
        for (c, k) in kind.iter().enumerate() {
            if let CellKind::Solid { owner } = *k {
                c_new[c] *= a[owner as usize] / b[owner as usize];
            }
        }
        let mut t: Vec<f64> = (0..kind.len())
            .map(|c| 330.0 + 20.0 * ((c * 37 % 101) as f64 / 101.0))
            .collect();
        let before = sphere_energy(&old, &c_old, &t, t_ref);
        reshare_solid_energy(kind, &c_old, &c_new, t_ref, &mut t);
        let after = sphere_energy(&old, &c_new, &t, t_ref);
        for (s, (b, a)) in before.iter().zip(&after).enumerate() {
            assert!((a - b).abs() <= 1e-13 * b.abs(), "sphere {s}: {a} vs {b}");
        }
        let mut u: Vec<f64> = kind
            .iter()
            .map(|k| match k {
                CellKind::Solid { owner } => 300.0 + *owner as f64,
                CellKind::Fluid => 350.0,
            })
            .collect();
        let want = u.clone();
        reshare_solid_energy(kind, &c_old, &c_new, t_ref, &mut u);
        for c in 0..kind.len() {
            assert!((u[c] - want[c]).abs() <= 1e-12 * want[c], "cell {c}");
        }
    }

    #[test]
    fn solid_remap_keeps_each_sphere_energy_and_a_uniform_sphere_uniform() {
        let (old, new, op) = moved_meshes();
        let t_ref = 293.15;
        let (old_cap, mut new_cap) = (capacities(&old), capacities(&new));
        // The sphere keeps the capacity of its mass (as `solid_cell_capacities` scales it).
        let (oc, nc) = (
            sphere_energy(&old, &old_cap, &vec![t_ref + 1.0; old_cap.len()], t_ref),
            sphere_energy(&new, &new_cap, &vec![t_ref + 1.0; new_cap.len()], t_ref),
        );
        for (cap, k) in new_cap.iter_mut().zip(&new.mesh.cell_kind) {
            if let CellKind::Solid { owner } = *k {
                *cap *= oc[owner as usize] / nc[owner as usize];
            }
        }
        let kind = &old.mesh.cell_kind;
        let owner_of = |k: CellKind| match k {
            CellKind::Solid { owner } => owner as usize,
            CellKind::Fluid => usize::MAX,
        };
        // Uniform per sphere (a different value for each): stays exactly uniform.
        let uniform: Vec<f64> = kind
            .iter()
            .map(|&k| 300.0 + 3.0 * (owner_of(k) % 17) as f64)
            .collect();
        let cells = SolidCells {
            kind,
            capacity: &old_cap,
            temperature: &uniform,
        };
        let t = remap_solid_temperature(&op, cells, &new.mesh.cell_kind, &new_cap, t_ref, 0)
            .expect("remap");
        for (c, &k) in new.mesh.cell_kind.iter().enumerate() {
            if let CellKind::Solid { owner } = k {
                let want = 300.0 + 3.0 * (owner as usize % 17) as f64;
                assert!(
                    (t[c] - want).abs() <= 1e-12 * want,
                    "cell {c}: {} vs {want}",
                    t[c]
                );
            }
        }
        // A field that varies within each sphere: each sphere's energy to round-off.
        let varied: Vec<f64> = (0..kind.len())
            .map(|c| 330.0 + 20.0 * ((c * 37 % 101) as f64 / 101.0))
            .collect();
        let cells = SolidCells {
            temperature: &varied,
            ..cells
        };
        let t = remap_solid_temperature(&op, cells, &new.mesh.cell_kind, &new_cap, t_ref, 0)
            .expect("remap");
        let before = sphere_energy(&old, &old_cap, &varied, t_ref);
        let after = sphere_energy(&new, &new_cap, &t, t_ref);
        for (s, (b, a)) in before.iter().zip(&after).enumerate() {
            assert!((a - b).abs() <= 1e-13 * b.abs(), "sphere {s}: {a} vs {b}");
        }
        // And no temperature leaves the old range by more than a small share of it.
        for (c, &k) in new.mesh.cell_kind.iter().enumerate() {
            if !k.is_fluid() {
                assert!((329.0..=351.0).contains(&t[c]), "cell {c}: {}", t[c]);
            }
        }
    }
}
