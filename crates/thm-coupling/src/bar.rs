//! The bonded bar of Krzaczek et al. (2023), A-Fig. 8, and the coupled fluid–heat cases run
//! on it: the cooling bar (A-Sect. 4, A-Fig. 11), the advection bar (A-Sect. 5, A-Fig. 14)
//! and the thermal contraction test with every sphere held (A-Sect. 6 case b, A-Fig. 18) or
//! only the end spheres held (case a: the skeleton contracts and cracks; its DEM mass
//! scaling, coupled-step rule and crack measures are [`CASE_A_DENSITY_SCALE`],
//! [`case_a_coupling_step`] and [`crack_report`]).
//!
//! The packing is `thm-vpn-mesh`'s seeded 20 × 80 mm bar of 4–8 mm circles at about 10 %
//! porosity; every overlapping pair is bonded. Its ends are cut ([`BarEnds::Cut`], the
//! default): the packing is generated beyond them and the spheres that reach into the bar are
//! kept, so the end lines cut spheres and the held end temperature (A-Sect. 2, boundary case
//! I, on any face at the domain boundary) acts on their solid faces as on the pore faces.
//! With every sphere inside the bar ([`BarEnds::Film`], the reading before) the ends hold only
//! water and the solid feels them through the Nusselt film (A-Eq. 45). A-Sect. 4's 0.52 K
//! supports the cut ends; A-Sect. 6 case b's 333.3 K the film ends (verification cases
//! `coupling/bar_cooling_advection` and `coupling/bar_contraction_fixed` run both;
//! `docs/cases/bar_cooling.md`). [`steady_conductivity`] measures a bar network's own
//! conductivity, which A-Eq. 63's volume-weighted mean overestimates. The figures with the boundary conditions
//! (A-Figs. 11, 14, 18) are missing from the text; what the text says and how it is read:
//!
//! - **Cooling bar** (A-Sect. 4): single-phase water, cooled by 30 K (323.16 K → ends at
//!   293.16 K), sides adiabatic. The water density after 400 s spans 1000.02–1014.28 kg/m³,
//!   the Peng–Robinson range between those temperatures at about atmospheric pressure, so
//!   the pressure is held: both ends are water reservoirs at 0.1 MPa (the Darcy test's top
//!   pressure, A-Sect. 3.2) and 293.16 K; the water that replaces the contraction enters
//!   through them.
//! - **Advection bar** (A-Sect. 5): the same with `ΔP` between the ends, bottom at
//!   0.1 MPa + ΔP, top at 0.1 MPa (ΔP = 0.9 and 9.9 MPa); water enters at the bottom at
//!   293.16 K.
//! - **Case b** (A-Sect. 6): 80 % water / 20 % air at 100 kPa, 368.16 K, both ends at
//!   278.16 K, closed ends ("to eliminate advection at the start"), solid λ = 420 W/(m K),
//!   fluid λ × 10, α_exp = 8.3·10⁻⁴ 1/K, every sphere held, 17 s.
//!
//! Sides are impermeable and adiabatic in all cases. In the water cases, the pores that no
//! channel connects to a reservoir (none with cut ends on seeds 1–5; 40 of 604 on seed 1
//! with film ends, [`crate::pore_scale::unconnected_pores`]) cool at fixed mass and volume, and
//! their water goes into tension (about −75 MPa by 400 s on the liquid branch of the EOS):
//! the water cases set `liquid_tension`, which lets pores holding only liquid carry a negative
//! pressure (cavitation is not modelled); case b has gas in every pore and does not. The S2S apertures are those of contacts
//! at rest (the skeleton is held, so no contact carries stress: `h = β h₀`, as in the Darcy
//! test of `thm-vpn-flow`).

use serde::{Deserialize, Serialize};
use thm_dem::packing::Packing;
use thm_dem::{CohesiveFrictionalParams, DemState, Kinematics, StepperParams, Vec3};
use thm_eos::{Model, PengRobinson, water_air_closure};
use thm_fvm_heat::{
    BoundaryCondition as HeatBoundary, BoundaryParams, CrossDiffusion, HeatParams,
    TemperatureSchedule,
};
use thm_vpn_flow::{BoundaryCondition as FlowCondition, EosFluid, FlowParameters};
use thm_vpn_mesh::mesher::overlapping_pairs;
use thm_vpn_mesh::packing::{PackingSpec, random_packing};
use thm_vpn_mesh::{BoundarySide, MeshParams, Outline, RemeshCriteriaParams};

use crate::pore_scale::{
    CouplingError, CouplingStepParams, FlowBoundary, FlowScheme, HeatScheme, InitialFluid,
    PoreScaleConfig, PoreScaleParams, PoreScaleState, PressureForce, Skeleton,
};

/// Paper A's fluids: Peng–Robinson water with the volume correction and air (A-Eqs. 16–29).
pub type WaterAir = EosFluid<PengRobinson, PengRobinson>;

/// Paper A's water–air closure (A-Eqs. 16–29, Table 1).
pub fn water_air() -> WaterAir {
    EosFluid(water_air_closure(Model::PrCorrected))
}

/// Width of the bar (x) \[m\].
pub const BAR_WIDTH: f64 = 0.020;
/// Length of the bar (y) \[m\].
pub const BAR_LENGTH: f64 = 0.080;
/// `[BAR_WIDTH, BAR_LENGTH]`.
pub const PAPER_BAR: [f64; 2] = [BAR_WIDTH, BAR_LENGTH];
/// Density of the solid (A-Table 1) \[kg/m³\].
pub const SOLID_DENSITY: f64 = 2600.0;
/// Pressure of the water reservoirs at the top (and, in A-Sect. 4, the bottom) \[Pa\].
pub const TOP_PRESSURE: f64 = 1e5;

/// How the bar's ends are made, and so how the held end temperature reaches the spheres.
/// A-Sect. 2's boundary case I holds "at the domain boundary" on any cell face; which faces
/// lie on the end lines depends on how the packing meets them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BarEnds {
    /// The bar is cut from a longer packing, as a specimen is sawn from a block: spheres
    /// cross the end lines and are cut by them, so the end lines hold solid faces as well as
    /// pore faces and case I acts on both. The mesh has Steiner points along the box sides
    /// (`thm_vpn_mesh::MeshParams::side_points`). This reading reproduces A-Sect. 4 (see
    /// `docs/cases/bar_cooling.md`).
    #[default]
    Cut,
    /// Every sphere inside the bar (the packing's circles clamped inside its box), so every
    /// face on the end lines belongs to a water cell and the held temperature reaches the
    /// solid only through that water and the Nusselt film of A-Eq. 45: the end step that
    /// case b's 333.3 K needs. The mesh is the mesher's default (no side points).
    Film,
}

/// Which of the paper's bar cases.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "case", rename_all = "snake_case", deny_unknown_fields)]
pub enum BarCase {
    /// A-Sect. 4: single-phase water, 323.16 K, ends at 293.16 K, both ends at 0.1 MPa.
    Cooling,
    /// A-Sect. 5: as [`BarCase::Cooling`] with the bottom at 0.1 MPa + `pressure_drop`.
    Advection {
        /// Pressure difference bottom − top \[Pa\] (paper: 0.9 MPa and 9.9 MPa).
        pressure_drop: f64,
    },
    /// A-Sect. 6 case b: 80 % water / 20 % air at 100 kPa, 368.16 K, ends at 278.16 K, closed.
    ContractionFixed,
    /// A-Sect. 6 case a: as case b, but only the spheres at both ends are held (displacement
    /// and rotation); the others move under contact and fluid forces, shrink with A-Eq. 55,
    /// and the bonds between them may break.
    ContractionFree,
}

impl BarCase {
    /// Initial temperature \[K\].
    pub fn initial_temperature(self) -> f64 {
        match self {
            BarCase::Cooling | BarCase::Advection { .. } => 323.16,
            BarCase::ContractionFixed | BarCase::ContractionFree => 368.16,
        }
    }

    /// Temperature held at both ends \[K\].
    pub fn end_temperature(self) -> f64 {
        match self {
            BarCase::Cooling | BarCase::Advection { .. } => 293.16,
            BarCase::ContractionFixed | BarCase::ContractionFree => 278.16,
        }
    }

    /// The initial pore fluid.
    pub fn initial_fluid(self) -> InitialFluid {
        match self {
            BarCase::Cooling | BarCase::Advection { .. } => InitialFluid {
                pressure: TOP_PRESSURE,
                liquid_fraction: 1.0,
            },
            BarCase::ContractionFixed | BarCase::ContractionFree => InitialFluid {
                pressure: 1e5,
                liquid_fraction: 0.8,
            },
        }
    }
}

/// The bar packing as a DEM state: `thm-vpn-mesh`'s seeded A-Fig. 8 bar with cut ends
/// ([`BarEnds::Cut`]), spheres in the plane, density 2600 kg/m³, every overlapping pair bonded
/// at its current overlap.
pub fn bar_packing(seed: u64, temperature: f64) -> Result<DemState, CouplingError> {
    bar_packing_sized(seed, temperature, PAPER_BAR, BarEnds::Cut)
}

/// How far beyond each end a cut bar's packing is generated \[m\]: the largest diameter, so
/// that the packing's own walls (where the generator clamps the circles) lie a sphere beyond
/// the end lines.
pub const CUT_MARGIN: f64 = 0.008;

/// The generator's porosity target for a cut bar: the generated box is [`CUT_MARGIN`] longer
/// at each end and its walls hold looser layers, so aiming the whole box at 12 % leaves
/// about 10 % inside the bar (A-Sect. 3: "roughly p = 10 %").
pub const CUT_POROSITY_TARGET: f64 = 0.12;

/// The A-Fig. 8 bar's packing recipe (4–8 mm spheres, about 10 % porosity) on a bar of
/// `[width, length]` \[m\] (the scaling benchmark's larger bars), its ends made as `ends`
/// says: cut, the packing is generated [`CUT_MARGIN`] beyond each end and the spheres that
/// reach into the bar are kept; film, generated inside the bar.
pub fn bar_packing_sized(
    seed: u64,
    temperature: f64,
    size: [f64; 2],
    ends: BarEnds,
) -> Result<DemState, CouplingError> {
    bar_spheres(seed, size, ends)
        .to_state(SOLID_DENSITY, temperature)
        .map_err(CouplingError::Dem)
}

/// The spheres and bonds of [`bar_packing_sized`] (every overlapping pair bonded), for a
/// caller that builds its own state from them (the tension test of A-Sect. 3.1 on this
/// packing, `thm_dem::tension::uniaxial_tension_of`).
pub fn bar_spheres(seed: u64, [width, length]: [f64; 2], ends: BarEnds) -> Packing {
    let mut spec = PackingSpec::paper_bar(seed);
    spec.box_max = [width, length];
    let circles = match ends {
        BarEnds::Film => random_packing(&spec),
        BarEnds::Cut => {
            spec.box_min[1] = -CUT_MARGIN;
            spec.box_max[1] = length + CUT_MARGIN;
            spec.target_porosity = Some(CUT_POROSITY_TARGET);
            // A sphere that only touches an end line leaves no area inside: kept spheres
            // reach at least 1 % of their radius into the bar.
            random_packing(&spec)
                .into_iter()
                .filter(|c| {
                    let reach = 0.01 * c.radius;
                    c.centre[1] + c.radius > reach && c.centre[1] - c.radius < length - reach
                })
                .collect()
        }
    };
    let bonds = overlapping_pairs(&circles)
        .into_iter()
        .map(|[a, b]| (a.min(b) as usize, a.max(b) as usize))
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    Packing {
        kinematics: Kinematics::SpheresInPlane,
        centres: circles
            .iter()
            .map(|c| Vec3::new(c.centre[0], c.centre[1], 0.0))
            .collect(),
        radii: circles.iter().map(|c| c.radius).collect(),
        bonds,
    }
}

/// The parameters of `case` on the bar meshed with `segments` points per circle: fixed
/// skeleton, implicit pressure and heat steps, A-Table 1 properties (A-Sect. 6's for cases
/// a and b), limited cross diffusion (ratio 1; case a, whose mesh moves, ratio 0; see
/// `thm_fvm_heat::CrossDiffusion`).
pub fn bar_params(case: BarCase, segments: u32) -> PoreScaleParams {
    bar_params_sized(case, segments, PAPER_BAR, BarEnds::Cut)
}

/// [`bar_params`] on a bar of `[width, length]` \[m\].
pub fn bar_params_sized(
    case: BarCase,
    segments: u32,
    size: [f64; 2],
    ends: BarEnds,
) -> PoreScaleParams {
    let end = case.end_temperature();
    let mut heat = HeatParams::paper_a_table_1();
    heat.boundaries = [BoundarySide::Bottom, BoundarySide::Top]
        .into_iter()
        .map(|side| BoundaryParams {
            side,
            condition: HeatBoundary::Temperature {
                temperature: TemperatureSchedule::Constant(end),
            },
        })
        .collect();
    // Case a's mesh moves between remeshes and its triangles distort; the limited cross
    // term is not monotone there (with A-Table 1's bonds a fluid cell left the initial
    // 368.16 K by 0.21 K at 0.3 s, and not with the cross term off), so case a keeps the
    // two-point flux alone, which holds the temperatures between the ends' and the initial.
    let ratio = if case == BarCase::ContractionFree {
        0.0
    } else {
        1.0
    };
    heat.cross_diffusion = CrossDiffusion::Limited { ratio };
    let mut thermal_expansion = 8e-6;
    let reservoir = |pressure| FlowCondition::Pressure {
        pressure,
        temperature: end,
        entering_liquid_fraction: 1.0,
    };
    let flow_boundaries = match case {
        BarCase::Cooling => vec![
            FlowBoundary {
                side: BoundarySide::Bottom,
                condition: reservoir(TOP_PRESSURE),
            },
            FlowBoundary {
                side: BoundarySide::Top,
                condition: reservoir(TOP_PRESSURE),
            },
        ],
        BarCase::Advection { pressure_drop } => vec![
            FlowBoundary {
                side: BoundarySide::Bottom,
                condition: reservoir(TOP_PRESSURE + pressure_drop),
            },
            FlowBoundary {
                side: BoundarySide::Top,
                condition: reservoir(TOP_PRESSURE),
            },
        ],
        BarCase::ContractionFixed | BarCase::ContractionFree => {
            heat.solid.conductivity = 420.0;
            heat.liquid.conductivity *= 10.0;
            heat.gas.conductivity *= 10.0;
            thermal_expansion = 8.3e-4;
            Vec::new()
        }
    };
    PoreScaleParams {
        skeleton: if case == BarCase::ContractionFree {
            Skeleton::Free
        } else {
            Skeleton::Fixed
        },
        dem: StepperParams {
            time_step: 2e-7,
            damping: 0.08,
            gravity: [0.0; 3],
            verlet_skin: 2e-4,
        },
        contact: CohesiveFrictionalParams::paper_a_table_1(),
        thermal_expansion,
        mesh: bar_mesh_params(segments, size, ends),
        remesh: RemeshCriteriaParams::default(),
        flow: FlowParameters {
            // Case a: a flow step that needs more sub-steps fails, and the adaptive coupled
            // step retakes it shorter (the skeleton then moves less within it) instead of
            // sub-stepping a sliver pore up to 10⁵ times.
            max_substeps: if case == BarCase::ContractionFree {
                CASE_A_FLOW_SUBSTEPS
            } else {
                FlowParameters::default().max_substeps
            },
            ..FlowParameters::default()
        },
        flow_scheme: FlowScheme::Implicit,
        liquid_tension: matches!(case, BarCase::Cooling | BarCase::Advection { .. }),
        flow_boundaries,
        boundary_reduction_factor: BAR_T2T_REDUCTION_FACTOR,
        heat,
        heat_scheme: HeatScheme::Implicit,
        // Case a: the pore pressures push through the cell corners with the pores' undrained
        // springs integrated implicitly (`pore_scale::pore_forces`); with A-Eqs. 52–53 the
        // staggered coupling squeezes liquid-filled pores to 10¹¹ Pa and the run stops at
        // 0.67 s (2.05 s with the narrow-gap mesher options; docs/cases/
        // bar_contraction_free.md). A held skeleton feels no force.
        pressure_force: if case == BarCase::ContractionFree {
            PressureForce::CellCorners
        } else {
            PressureForce::WallFaces
        },
    }
}

/// The initial state of `case` on `config` (built from [`bar_params`] or a variant of it):
/// the packing of `seed`, uniform fluid and temperature.
pub fn bar_state(
    case: BarCase,
    config: &PoreScaleConfig,
    seed: u64,
    fluid: &impl thm_vpn_flow::PoreFluid,
) -> Result<PoreScaleState, CouplingError> {
    bar_state_sized(case, config, seed, fluid, PAPER_BAR, BarEnds::Cut)
}

/// [`bar_state`] on a bar of `[width, length]` \[m\] (`config` from [`bar_params_sized`]).
pub fn bar_state_sized(
    case: BarCase,
    config: &PoreScaleConfig,
    seed: u64,
    fluid: &impl thm_vpn_flow::PoreFluid,
    size: [f64; 2],
    ends: BarEnds,
) -> Result<PoreScaleState, CouplingError> {
    let t0 = case.initial_temperature();
    let mut dem = bar_packing_sized(seed, t0, size, ends)?;
    if case == BarCase::ContractionFree {
        hold_ends_of(&mut dem, size[1]);
    }
    PoreScaleState::new(config, dem, fluid, case.initial_fluid(), |_| t0)
}

/// Spheres whose surface lies within this distance of a bar end are held in case a \[m\]
/// (the grip depth of the tension test, `thm_dem::tension::BarLoading::paper_a`).
pub const END_HOLD_DEPTH: f64 = 1e-3;

/// Holds (displacement and rotation) the spheres whose surface lies within
/// [`END_HOLD_DEPTH`] of either end: A-Sect. 6 case a, "fixed only at both ends" (A-Fig. 20a
/// shows them black). Returns how many were held.
pub fn hold_ends(dem: &mut DemState) -> usize {
    hold_ends_of(dem, BAR_LENGTH)
}

/// [`hold_ends`] of a bar of `length` \[m\].
pub fn hold_ends_of(dem: &mut DemState, length: f64) -> usize {
    let p = &mut dem.particles;
    let [bottom, top] = p.near_ends(0.0, length, END_HOLD_DEPTH);
    for &i in bottom.iter().chain(&top) {
        p.fixed[i] = true;
        p.velocity[i] = Vec3::new(0.0, 0.0, 0.0);
        p.angular_velocity[i] = Vec3::new(0.0, 0.0, 0.0);
    }
    bottom.len() + top.len()
}

/// Cells crossed by the vertical centreline x = W/2.
pub fn centreline_cells(mesh: &thm_vpn_mesh::PoreMesh) -> Vec<usize> {
    let xc = 0.5 * BAR_WIDTH;
    (0..mesh.n_cells())
        .filter(|&c| {
            let xs = mesh.cell_vertices[c].map(|v| mesh.vertices[v as usize][0]);
            let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            lo <= xc && xc <= hi
        })
        .collect()
}

/// The equivalent homogeneous bar of A-Eq. 63 on a state's mesh: the volume-weighted
/// conductivity and heat capacity of the liquid (at the state's mean liquid density) and the
/// solid, with the porosity of the mesh. A-Sects. 4–5 compare the network with this medium.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EquivalentMedium {
    /// λ_eff \[W/(m K)\].
    pub conductivity: f64,
    /// (ρc)_eff \[J/(m³ K)\].
    pub volumetric_heat_capacity: f64,
    /// c of the liquid \[J/(kg K)\], for the heat that a mass flux carries.
    pub liquid_specific_heat: f64,
}

impl EquivalentMedium {
    /// A-Eq. 63 on `state` (single-phase liquid) with the properties of `heat`.
    pub fn of(state: &PoreScaleState, heat: &HeatParams) -> Self {
        let mesh = &state.mesh.mesh;
        let porosity = mesh.fluid_area() / (BAR_WIDTH * BAR_LENGTH);
        let rho = &state.flow.liquid_density;
        let rho_w = rho.iter().sum::<f64>() / (rho.len().max(1) as f64);
        Self {
            conductivity: porosity * heat.liquid.conductivity
                + (1.0 - porosity) * heat.solid.conductivity,
            volumetric_heat_capacity: porosity * rho_w * heat.liquid.specific_heat
                + (1.0 - porosity) * heat.solid.density * heat.solid.specific_heat,
            liquid_specific_heat: heat.liquid.specific_heat,
        }
    }

    /// α_eff = λ_eff / (ρc)_eff \[m²/s\].
    pub fn diffusivity(&self) -> f64 {
        self.conductivity / self.volumetric_heat_capacity
    }

    /// Speed of a thermal front carried by the liquid mass flux `mass_flux` \[kg/(m² s)\]:
    /// V = c_w q_m / (ρc)_eff \[m/s\].
    pub fn front_speed(&self, mass_flux: f64) -> f64 {
        self.liquid_specific_heat * mass_flux / self.volumetric_heat_capacity
    }

    /// The bar Péclet number V L / α_eff = c_w q_m L / λ_eff at mass flux `mass_flux`.
    pub fn bar_peclet(&self, mass_flux: f64) -> f64 {
        self.front_speed(mass_flux) * BAR_LENGTH / self.diffusivity()
    }

    /// Temperature at height `y` and time `t` of this medium in `case` with the liquid moving
    /// upwards at `mass_flux` (A-Eqs. 60–61 at zero flux, with advection otherwise; see
    /// `thm_fvm_heat::analytical::advection_diffusion_bar_temperature`).
    pub fn temperature(&self, case: BarCase, y: f64, t: f64, mass_flux: f64) -> f64 {
        thm_fvm_heat::analytical::advection_diffusion_bar_temperature(
            y,
            t,
            BAR_LENGTH,
            self.diffusivity(),
            self.front_speed(mass_flux),
            case.initial_temperature(),
            case.end_temperature(),
        )
    }
}

/// The effective conductivity of a bar's own network along its length \[W/(m K)\], measured
/// by a steady conduction run through it: the state's mesh, heat model and fluid (at rest, at
/// the state's mean liquid density) with the bottom held at `T` and the top at `T + 10 K`, the
/// sides adiabatic, solved to steady state (backward Euler steps of 10⁹ s until the heat rate
/// through the top changes by less than 10⁻¹⁰ of itself), then `λ = Q L / (ΔT W b)` with `Q`
/// the heat rate through the top, `L` and `W` the bar's length and width and `b` the mesh
/// thickness. It holds every path heat takes in the network (solid cells, contact chords,
/// the pore water and the Nusselt film between them, A-Eqs. 43–45, at rest), which A-Eq. 63's
/// volume-weighted mean does not see. `size` is `[W, L]`.
pub fn steady_conductivity(
    state: &PoreScaleState,
    heat: &HeatParams,
    size: [f64; 2],
) -> Result<f64, CouplingError> {
    use thm_fvm_heat::{FlowInput, HeatGeometry, HeatModel, HeatState, HeatStepper};
    let mesh = &state.mesh.mesh;
    let [width, length] = size;
    let (t_low, rise) = (293.15, 10.0);
    let mut params = heat.clone();
    params.boundaries = vec![
        BoundaryParams {
            side: BoundarySide::Bottom,
            condition: HeatBoundary::Temperature {
                temperature: TemperatureSchedule::Constant(t_low),
            },
        },
        BoundaryParams {
            side: BoundarySide::Top,
            condition: HeatBoundary::Temperature {
                temperature: TemperatureSchedule::Constant(t_low + rise),
            },
        },
    ];
    let model = HeatModel::new(&params, mesh).map_err(CouplingError::Heat)?;
    let geometry = HeatGeometry::new(&model, mesh).map_err(CouplingError::Heat)?;
    let rho = &state.flow.liquid_density;
    let rho_w = rho.iter().sum::<f64>() / (rho.len().max(1) as f64);
    let gas = &state.flow.gas_density;
    let rho_g = gas.iter().sum::<f64>() / (gas.len().max(1) as f64);
    let input = FlowInput::liquid_at_rest(mesh, rho_w, rho_g);
    let mut hs = HeatState::uniform(mesh, t_low + 0.5 * rise);
    let mut stepper = HeatStepper::default();
    let dt = 1e9;
    let top = 3; // BoundarySide::Top in `boundary_energy_by_side`
    let mut q = f64::NAN;
    for _ in 0..200 {
        stepper
            .implicit_step(&model, &geometry, mesh, &input, &mut hs, dt)
            .map_err(CouplingError::Heat)?;
        let next = stepper.boundary_energy_by_side()[top] / dt;
        let converged = (next - q).abs() <= 1e-10 * next.abs();
        q = next;
        if converged {
            break;
        }
    }
    Ok(q * length / (rise * width * mesh.thickness))
}

/// The liquid mass flux through the bar averaged since the start: the liquid that entered
/// through the inlet over the section W b and the elapsed time \[kg/(m² s)\] (0 at t = 0 or
/// without inflow).
pub fn mean_mass_flux(state: &PoreScaleState) -> f64 {
    let entered = state
        .flow
        .boundary_liquid_inflow
        .iter()
        .copied()
        .fold(0.0, f64::max);
    if state.time > 0.0 {
        entered / (BAR_WIDTH * state.mesh.mesh.thickness * state.time)
    } else {
        0.0
    }
}

/// Mass scaling of the DEM in case a: the spheres' masses and inertias × [`CASE_A_DENSITY_SCALE`]
/// and the DEM step × its square root (Δt_D ∝ √(m/k)). The contraction and cracking take
/// seconds, the elastic waves of the bar microseconds: at the real density A-Table 1's
/// Δt_D = 2·10⁻⁷ s needs 8.5·10⁷ DEM steps for 17 s. ×100 keeps the bar's lowest mode
/// (about 40 µs at the real density, 0.4 ms scaled) four orders of magnitude faster than the
/// cooling, so the skeleton still follows the temperature quasi-statically; what it changes is
/// how long a released sphere takes to settle after a bond breaks (10× longer).
pub const CASE_A_DENSITY_SCALE: f64 = 100.0;

/// The bond tensile strength of case a \[Pa\]: `thm calibrate`'s T for a mean tensile strength of
/// 8.8 MPa (A-Sect. 3.1) on the packings the bar cases run on (`thm_coupling::calibration::
/// BarFamily::coupled_cases`, seeds 1–5: cut ends, every overlapping pair bonded), with
/// C = 5 T as in A-Table 1. A-Table 1's 30 MPa gives 2.81 MPa there; `thm-dem`'s tension-bar
/// generator (bonds within 4 mm, 1.7 times the bonds per sphere) needs 48.29 MPa. Checked by
/// `coupling/bar_packing_family`.
pub const CASE_A_BOND_TENSILE_STRENGTH: f64 = 92.96e6;

/// The T2T reduction factor γ (A-Eq. 9) of every bar case, on the mesh and the boundary links:
/// `thm calibrate`'s γ for the paper's permeability 2.47·10⁻¹⁶ m² (A-Sect. 3.2, geometric
/// mean over seeds 1–5) on the same packings as [`CASE_A_BOND_TENSILE_STRENGTH`].
/// A-Table 1's 0.0115 gives 5.9·10⁻¹⁶ m² there (the cut ends and the Steiner points on the
/// box sides open paths the Darcy test's packings lack). Checked by
/// `coupling/bar_packing_family`.
pub const BAR_T2T_REDUCTION_FACTOR: f64 = 0.006064;

/// Most flow sub-steps in one coupled step of case a: beyond them the coupled step is
/// retaken shorter ([`case_a_coupling_step`]).
pub const CASE_A_FLOW_SUBSTEPS: u32 = 20;

/// The coupled-step rule of case a (see [`crate::pore_scale::PoreScaleStepper::advance`]):
/// steps up to 0.01 s, none moving a sphere by more than 1 % of the smallest radius, halved
/// down to 10⁻⁷ s, grown by 1.2 after each accepted step.
pub fn case_a_coupling_step() -> CouplingStepParams {
    CouplingStepParams {
        max_step: 0.01,
        min_step: 1e-7,
        max_displacement: 0.01,
        growth: 1.2,
    }
}

/// Multiplies every sphere's mass and moment of inertia by `factor` (≥ 1): DEM mass scaling.
/// The caller multiplies the DEM time step by `√factor` (the stable step scales so). Thermal
/// capacities are untouched: the heat solver takes the solid's `ρ c` from its own parameters.
pub fn scale_sphere_density(state: &mut PoreScaleState, factor: f64) -> Result<(), CouplingError> {
    if !(factor.is_finite() && factor >= 1.0) {
        return Err(CouplingError::Parameter {
            field: "density_scale",
            range: ">= 1 and finite",
            value: factor,
        });
    }
    let p = &mut state.dem.particles;
    for m in p.mass.iter_mut().chain(p.inertia.iter_mut()) {
        *m *= factor;
    }
    Ok(())
}

/// What case a's summary reports about the crack (A-Sect. 6, A-Figs. 19–22), read from the
/// state at any time.
///
/// The broken bonds are grouped into cracks by height: sorted by the height of their
/// mid-points, a gap of more than [`CRACK_BAND`] between neighbours starts a new crack. The
/// macro-crack is the crack with the most broken bonds (the higher one on a tie).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrackReport {
    /// Bonds broken so far (every break event of the run, tension or shear).
    pub broken_bonds: usize,
    /// Of those, broken in tension.
    pub broken_in_tension: usize,
    /// How many cracks the broken bonds form (0 before the first break).
    pub cracks: usize,
    /// Height of the macro-crack: the median height of its bonds' mid-points \[m\] (NaN
    /// before the first break).
    pub crack_height: f64,
    /// Broken bonds in the macro-crack.
    pub broken_in_crack: usize,
    /// Inclination of the macro-crack from the horizontal \[°\], in (−90, 90]: the principal
    /// axis of its bonds' mid-points (NaN with fewer than two).
    pub crack_inclination: f64,
    /// Horizontal extent of the macro-crack's bond mid-points over the bar width (a crack
    /// across the bar spans most of the width less a sphere).
    pub crack_span: f64,
    /// Median sphere diameter d50 \[m\] (by number).
    pub d50: f64,
    /// Largest difference of the mean temperatures of two spheres whose bond broke \[K\]:
    /// the temperature step across the crack.
    pub temperature_step: f64,
}

/// Largest height gap between the mid-points of the broken bonds of one crack \[m\]: half
/// the largest sphere diameter of the packing (8 mm).
pub const CRACK_BAND: f64 = 4e-3;

/// The crack report of `state` (see [`CrackReport`]).
pub fn crack_report(state: &PoreScaleState) -> CrackReport {
    let dem = &state.dem;
    let p = &dem.particles;
    let mut mids: Vec<[f64; 2]> = dem
        .bond_breaks
        .iter()
        .map(|b| {
            let (a, c) = (p.position[b.a as usize], p.position[b.b as usize]);
            [0.5 * (a.x + c.x), 0.5 * (a.y + c.y)]
        })
        .collect();
    mids.sort_by(|a, b| a[1].total_cmp(&b[1]).then(a[0].total_cmp(&b[0])));
    // Cracks: runs of mid-points whose heights are within CRACK_BAND of the previous one.
    let mut cracks: Vec<&[[f64; 2]]> = Vec::new();
    let mut first = 0;
    for k in 1..=mids.len() {
        if k == mids.len() || mids[k][1] - mids[k - 1][1] > CRACK_BAND {
            cracks.push(&mids[first..k]);
            first = k;
        }
    }
    let macro_crack: &[[f64; 2]] = cracks
        .iter()
        .copied()
        .filter(|c| !c.is_empty())
        .max_by_key(|c| c.len())
        .unwrap_or(&[]);
    let heights: Vec<f64> = macro_crack.iter().map(|m| m[1]).collect();
    let mut diameters: Vec<f64> = p.radius.iter().map(|r| 2.0 * r).collect();
    diameters.sort_by(f64::total_cmp);
    let temperature_step = dem
        .bond_breaks
        .iter()
        .map(|b| (p.temperature[b.a as usize] - p.temperature[b.b as usize]).abs())
        .fold(0.0, f64::max);
    let xs = macro_crack.iter().map(|m| m[0]);
    let span = xs.clone().fold(f64::NEG_INFINITY, f64::max) - xs.fold(f64::INFINITY, f64::min);
    CrackReport {
        broken_bonds: dem.bond_breaks.len(),
        broken_in_tension: dem
            .bond_breaks
            .iter()
            .filter(|b| b.mode == thm_dem::BreakMode::Tension)
            .count(),
        cracks: cracks.iter().filter(|c| !c.is_empty()).count(),
        crack_height: median_sorted(&heights),
        broken_in_crack: macro_crack.len(),
        crack_inclination: principal_inclination(macro_crack),
        crack_span: if macro_crack.is_empty() {
            f64::NAN
        } else {
            span / BAR_WIDTH
        },
        d50: median_sorted(&diameters),
        temperature_step,
    }
}

/// Angle of the principal axis of `points` from the x axis \[°\], in (−90, 90] (NaN with
/// fewer than two points).
fn principal_inclination(points: &[[f64; 2]]) -> f64 {
    if points.len() < 2 {
        return f64::NAN;
    }
    let n = points.len() as f64;
    let [mx, my] = points
        .iter()
        .fold([0.0, 0.0], |[x, y], p| [x + p[0] / n, y + p[1] / n]);
    let [sxx, syy, sxy] = points.iter().fold([0.0; 3], |[a, b, c], p| {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        [a + dx * dx, b + dy * dy, c + dx * dy]
    });
    let angle = (0.5 * (2.0 * sxy).atan2(sxx - syy)).to_degrees();
    if angle <= -90.0 { angle + 180.0 } else { angle }
}

fn median_sorted(v: &[f64]) -> f64 {
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The largest tensile normal force carried by an intact bond in the last DEM step \[N\]
/// (0 when no bond is in tension).
pub fn largest_bond_tension(state: &PoreScaleState) -> f64 {
    let c = &state.dem.contacts;
    c.history
        .iter()
        .zip(&c.report)
        .filter(|(h, _)| h.bond == thm_dem::BondState::Intact)
        .map(|(_, r)| -r.normal_force)
        .fold(0.0, f64::max)
}

/// The mesher settings of the bar of `[width, length]` \[m\] with `segments` points per
/// circle: the paper's (A-Eq. 9 alone with γ = [`BAR_T2T_REDUCTION_FACTOR`], the default snap
/// tolerance). The narrow-gap floor and
/// a coarser snap (`thm_vpn_mesh::T2tApertureLaw`, `MeshParams::snap_tolerance`) are options
/// of a scenario (`docs/cases/bar_contraction_free.md` compares case a with and without).
/// Cut ends ([`BarEnds::Cut`]) add the Steiner points along the box sides.
pub fn bar_mesh_params(segments: u32, size: [f64; 2], ends: BarEnds) -> MeshParams {
    let mut mesh = MeshParams::new(
        Outline::Box {
            min: [0.0, 0.0],
            max: size,
        },
        segments,
    );
    mesh.side_points = ends == BarEnds::Cut;
    mesh.t2t_reduction_factor = BAR_T2T_REDUCTION_FACTOR;
    mesh
}

#[cfg(test)]
mod tests {
    use super::principal_inclination;

    #[test]
    fn principal_inclination_of_points_on_a_line_is_its_angle() {
        for deg in [-60.0f64, -10.0, 0.0, 25.0, 89.0, 90.0] {
            let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
            let pts: Vec<[f64; 2]> = (0..7)
                .map(|k| {
                    let t = f64::from(k) * 1e-3 - 3e-3;
                    [0.01 + t * c, 0.07 + t * s]
                })
                .collect();
            assert!((principal_inclination(&pts) - deg).abs() < 1e-9, "{deg}");
        }
        assert!(principal_inclination(&[[0.0, 0.0]]).is_nan());
    }
}
