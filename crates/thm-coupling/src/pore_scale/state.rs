//! The caller-owned state of the pore-scale coupled scheme.

use serde::{Deserialize, Serialize};
use thm_dem::DemState;
use thm_fvm_heat::{HeatParams, HeatState, sphere_mean_temperatures};
use thm_vpn_flow::{FlowState, Network, PoreFluid};
use thm_vpn_mesh::{
    CellKind, Circle, Contact, PackingMesh, mesh_packing, mesher::overlapping_pairs,
};

use super::error::CouplingError;
use super::params::PoreScaleConfig;

/// The fluid a run starts with: one pressure and liquid fraction in every pore.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialFluid {
    /// Pore pressure \[Pa\] (> 0).
    pub pressure: f64,
    /// Liquid fraction α_q ∈ [0, 1] (1: water only; A-Sect. 6: 0.8).
    pub liquid_fraction: f64,
}

/// Everything that evolves: spheres, mesh, fluid and temperatures. A checkpoint of this
/// struct restores a run bit for bit (the stepper rebuilds what it derives from it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoreScaleState {
    /// Coupled steps taken.
    pub step: u64,
    /// Simulated time \[s\].
    pub time: f64,
    /// Spheres, contacts and bonds. `particles.temperature` holds the volume-average sphere
    /// temperature T_avg^n of the last radius update (A-Eq. 55).
    pub dem: DemState,
    /// The pore mesh as it moves, with its ties to the circles.
    pub mesh: PackingMesh,
    /// The contacts given to the mesher (one per S2S channel candidate), in mesher order.
    pub mesh_contacts: Vec<Contact>,
    /// Angle each sphere turned about z since the mesh was built \[rad\].
    pub rotation: Vec<f64>,
    /// dr/dt of each sphere over the last radius update \[m/s\].
    pub radius_rate: Vec<f64>,
    /// Phase masses, pressures, fractions and densities of the pores (one per fluid cell).
    pub flow: FlowState,
    /// Temperatures of all cells.
    pub heat: HeatState,
    /// Mesh rebuilds so far.
    pub remeshes: u64,
    /// Solid area of each sphere's cells in the initial mesh \[m²\]: the sphere's mass, and
    /// so its heat capacity `ρ_s c_s A_ref b`, stays while its cross-section shrinks or swells
    /// (A-Eq. 55) and its cells change; see [`solid_capacity_scale`].
    pub solid_area_ref: Vec<f64>,
    /// The coupled step the adaptive rule tries next \[s\] (0: its largest step); see
    /// [`super::PoreScaleStepper::advance`]. Part of the state so that a restored run takes
    /// the same steps.
    #[serde(default)]
    pub coupling_step: f64,
}

/// Solid area of each sphere's cells in `mesh` \[m²\] (`n` spheres).
pub fn sphere_solid_areas(mesh: &thm_vpn_mesh::PoreMesh, n: usize) -> Vec<f64> {
    let mut area = vec![0.0; n];
    for (c, kind) in mesh.cell_kind.iter().enumerate() {
        if let CellKind::Solid { owner } = *kind
            && let Some(a) = area.get_mut(owner as usize)
        {
            *a += mesh.cell_area[c];
        }
    }
    area
}

/// Per sphere, the factor on `ρ_s c_s V` of its solid cells in `mesh` that keeps the heat
/// capacity of its mass: reference area over current area (1 for a sphere without cells).
pub fn solid_capacity_scale(mesh: &thm_vpn_mesh::PoreMesh, solid_area_ref: &[f64]) -> Vec<f64> {
    sphere_solid_areas(mesh, solid_area_ref.len())
        .iter()
        .zip(solid_area_ref)
        .map(|(&a, &a0)| if a > 0.0 && a0 > 0.0 { a0 / a } else { 1.0 })
        .collect()
}

/// Heat capacity of every solid cell of `mesh` \[J/K\] (0 for fluid cells): `ρ_s c_s V`
/// times its sphere's [`solid_capacity_scale`].
pub fn solid_cell_capacities(
    mesh: &thm_vpn_mesh::PoreMesh,
    heat: &HeatParams,
    solid_area_ref: &[f64],
) -> Vec<f64> {
    let solid = heat.solid.density * heat.solid.specific_heat;
    let scale = solid_capacity_scale(mesh, solid_area_ref);
    (0..mesh.n_cells())
        .map(|c| match mesh.cell_kind[c] {
            CellKind::Solid { owner } => {
                solid * mesh.cell_volume(c) * scale.get(owner as usize).copied().unwrap_or(1.0)
            }
            CellKind::Fluid => 0.0,
        })
        .collect()
}

/// The circles of the spheres as the mesher takes them: centre (x, y), radius, owner = the
/// sphere's index.
pub fn circles_of(dem: &DemState) -> Vec<Circle> {
    let p = &dem.particles;
    p.position
        .iter()
        .zip(&p.radius)
        .enumerate()
        .map(|(i, (x, &r))| Circle {
            centre: [x.x, x.y],
            radius: r,
            owner: i as u32,
        })
        .collect()
}

/// The contacts of the mesh: every overlapping pair of circles, with the normal stress of
/// the DEM contact between them (compression positive, A-Eq. 8; zero where the DEM lists no
/// active contact for the pair).
pub fn contacts_of(dem: &DemState, circles: &[Circle]) -> Vec<Contact> {
    overlapping_pairs(circles)
        .into_iter()
        .map(|pair| Contact {
            circles: pair,
            normal_stress: contact_normal_stress(dem, pair),
        })
        .collect()
}

/// σ_n of the DEM contact `pair` (`a < b`), 0 when it is not listed or not active.
pub fn contact_normal_stress(dem: &DemState, pair: [u32; 2]) -> f64 {
    let key = if pair[0] <= pair[1] {
        pair
    } else {
        [pair[1], pair[0]]
    };
    match dem.contacts.pair.binary_search(&key) {
        Ok(k) => {
            let r = &dem.contacts.report[k];
            if r.active { r.normal_stress } else { 0.0 }
        }
        Err(_) => 0.0,
    }
}

impl PoreScaleState {
    /// The initial state: the mesh of the spheres as they are, every pore at `fluid`'s
    /// pressure and liquid fraction, every cell at `temperature(centroid)` \[K\] (the phase
    /// masses are those of the pressure at that temperature) and every sphere at the
    /// volume-average temperature of its solid cells.
    pub fn new(
        config: &PoreScaleConfig,
        dem: DemState,
        fluid_model: &impl PoreFluid,
        fluid: InitialFluid,
        temperature: impl Fn([f64; 2]) -> f64,
    ) -> Result<Self, CouplingError> {
        if !(fluid.pressure.is_finite() && fluid.pressure > 0.0) {
            return Err(CouplingError::Parameter {
                field: "initial pressure",
                range: "> 0 Pa",
                value: fluid.pressure,
            });
        }
        if !(0.0..=1.0).contains(&fluid.liquid_fraction) {
            return Err(CouplingError::Parameter {
                field: "initial liquid_fraction",
                range: "in [0, 1]",
                value: fluid.liquid_fraction,
            });
        }
        dem.validate().map_err(CouplingError::Dem)?;
        let mut dem = dem;
        let circles = circles_of(&dem);
        let mesh_contacts = contacts_of(&dem, &circles);
        let mesh =
            mesh_packing(&circles, &mesh_contacts, &config.mesh).map_err(CouplingError::Mesh)?;
        let network = Network::from_mesh(
            &mesh.mesh,
            &config.flow_boundaries(),
            config.params.boundary_reduction_factor,
        )
        .map_err(CouplingError::Flow)?;
        let np = network.n_pores();
        let cell_temperature: Vec<f64> = mesh
            .mesh
            .cell_centroid
            .iter()
            .map(|&x| temperature(x))
            .collect();
        if let Some(c) = cell_temperature
            .iter()
            .position(|t| !(t.is_finite() && *t > 0.0))
        {
            return Err(CouplingError::Unphysical {
                stage: "initial state",
                quantity: "temperature",
                place: "cell",
                index: c,
                value: cell_temperature[c],
                step: 0,
                why: "not a finite positive temperature",
            });
        }
        let mut pore_temperature = vec![0.0; np];
        network
            .cells_to_pores(&cell_temperature, &mut pore_temperature)
            .map_err(CouplingError::Flow)?;
        let flow = FlowState::from_pressure(
            &network,
            network.pore_volumes(&mesh.mesh),
            pore_temperature,
            &vec![fluid.pressure; np],
            &vec![fluid.liquid_fraction; np],
            fluid_model,
        )
        .map_err(CouplingError::Flow)?;
        let heat = HeatState {
            time: 0.0,
            steps: 0,
            temperature: cell_temperature,
        };
        dem.particles.temperature = sphere_temperatures(&mesh, &heat, &dem)?;
        let n = dem.particles.len();
        let solid_area_ref = sphere_solid_areas(&mesh.mesh, n);
        Ok(Self {
            step: 0,
            time: 0.0,
            dem,
            mesh,
            mesh_contacts,
            rotation: vec![0.0; n],
            radius_rate: vec![0.0; n],
            flow,
            heat,
            remeshes: 0,
            solid_area_ref,
            coupling_step: 0.0,
        })
    }

    /// Total liquid mass in the pores \[kg\].
    pub fn liquid_mass(&self) -> f64 {
        self.flow.total_liquid_mass()
    }

    /// Total gas mass in the pores \[kg\].
    pub fn gas_mass(&self) -> f64 {
        self.flow.total_gas_mass()
    }

    /// Thermal energy Σ C_c (T_c − T_ref) of all cells \[J\], with the capacity of a fluid cell
    /// from its phase masses (`m_q c_q + m_p c_p`, A-Eqs. 31, 39) and of a solid cell
    /// `ρ_s c_s V` (A-Eqs. 50–51), summed in cell order.
    pub fn thermal_energy(&self, heat: &HeatParams) -> f64 {
        let cap = cell_capacities(self, heat);
        let t_ref = heat.reference_temperature;
        cap.iter()
            .zip(&self.heat.temperature)
            .map(|(c, t)| c * (t - t_ref))
            .sum()
    }
}

/// Heat capacity of every cell \[J/K\]: fluid cells from the phase masses of their pore,
/// solid cells `ρ_s c_s V`.
pub fn cell_capacities(state: &PoreScaleState, heat: &HeatParams) -> Vec<f64> {
    let mesh = &state.mesh.mesh;
    let mut cap = solid_cell_capacities(mesh, heat, &state.solid_area_ref);
    let mut p = 0usize;
    for (c, kind) in mesh.cell_kind.iter().enumerate() {
        if kind.is_fluid() {
            cap[c] = fluid_capacity(state.flow.liquid_mass[p], state.flow.gas_mass[p], heat);
            p += 1;
        }
    }
    cap
}

/// `m_q c_q + m_p c_p` \[J/K\].
#[inline]
pub(crate) fn fluid_capacity(liquid_mass: f64, gas_mass: f64, heat: &HeatParams) -> f64 {
    liquid_mass * heat.liquid.specific_heat + gas_mass * heat.gas.specific_heat
}

/// The volume-average temperature of every sphere's solid cells (its current temperature
/// where it has none).
pub fn sphere_temperatures(
    mesh: &PackingMesh,
    heat: &HeatState,
    dem: &DemState,
) -> Result<Vec<f64>, CouplingError> {
    let mut mean = Vec::new();
    sphere_mean_temperatures(&mesh.mesh, &heat.temperature, &mut mean)
        .map_err(CouplingError::Heat)?;
    Ok(dem
        .particles
        .temperature
        .iter()
        .enumerate()
        .map(|(i, &t)| mean.get(i).copied().flatten().unwrap_or(t))
        .collect())
}
