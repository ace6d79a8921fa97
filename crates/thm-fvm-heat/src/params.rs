//! Parameters (`serde`, as read from a scenario) and their validated form [`HeatModel`].

use serde::{Deserialize, Serialize};
use thm_vpn_mesh::{BoundarySide, FaceKind, PoreMesh};

use crate::HeatError;
use crate::properties::{MixtureProperties, Phase, mixture, prandtl_cube_root};

/// Thermal properties of the solid (the spheres), Table 1 of Krzaczek et al. (2023).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolidParams {
    /// Mass density ρ_s \[kg/m³\] (Table 1: 2600).
    pub density: f64,
    /// Specific heat c_p \[J/(kg K)\] (Table 1: 920).
    pub specific_heat: f64,
    /// Thermal conductivity λ_s \[W/(m K)\] (Table 1: 3.7).
    pub conductivity: f64,
}

/// Thermal and transport properties of one fluid phase (liquid `q` or gas `p`, Table 1).
/// Densities are not parameters: they come from the flow solver (EOS) each step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseParams {
    /// Specific heat c_p \[J/(kg K)\] (water 4187, air 1006).
    pub specific_heat: f64,
    /// Thermal conductivity λ \[W/(m K)\] (water 0.6, air 0.0262).
    pub conductivity: f64,
    /// Dynamic viscosity μ \[Pa s\] (water 10.02e-4, air 2.0507e-5); enters the Reynolds and
    /// Prandtl numbers of A-Eqs. 43–44.
    pub dynamic_viscosity: f64,
}

/// A prescribed temperature: constant, or piecewise linear in time (held constant outside the
/// table).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged, deny_unknown_fields)]
pub enum TemperatureSchedule {
    /// Constant temperature \[K\].
    Constant(f64),
    /// Piecewise-linear table: strictly increasing `time` \[s\] and `temperature` \[K\].
    Table {
        /// Times \[s\], strictly increasing.
        time: Vec<f64>,
        /// Temperatures \[K\] at those times.
        temperature: Vec<f64>,
    },
}

impl TemperatureSchedule {
    /// The temperature at time `t` \[K\].
    pub fn at(&self, t: f64) -> f64 {
        match self {
            Self::Constant(v) => *v,
            Self::Table { time, temperature } => {
                let n = time.len();
                if t <= time[0] {
                    return temperature[0];
                }
                if t >= time[n - 1] {
                    return temperature[n - 1];
                }
                // First index with time[i] > t (exists and is >= 1 here).
                let i = time.partition_point(|&ti| ti <= t);
                let (t0, t1) = (time[i - 1], time[i]);
                let w = (t - t0) / (t1 - t0);
                temperature[i - 1] + w * (temperature[i] - temperature[i - 1])
            }
        }
    }
}

/// The condition on one side of the outer boundary (cases I–III of Krzaczek et al. 2023,
/// Sect. 2.3.1). Sides without a condition are adiabatic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum BoundaryCondition {
    /// Case I: prescribed temperature T_bc(t) \[K\]. Also the temperature of fluid entering
    /// through this side.
    Temperature {
        /// The temperature, constant or a table in time.
        temperature: TemperatureSchedule,
    },
    /// Case II: prescribed heat flux q \[W/m²\], positive *into* the domain.
    HeatFlux {
        /// Heat flux into the domain \[W/m²\].
        flux: f64,
    },
    /// Case II with q = 0.
    Adiabatic,
    /// Case III: convective exchange q = h_e (T_e − T_f) with the surroundings.
    Convective {
        /// Heat transfer coefficient h_e \[W/(m² K)\].
        coefficient: f64,
        /// Temperature of the surroundings T_e \[K\].
        ambient_temperature: f64,
    },
}

/// One boundary condition applied to all boundary faces of a side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundaryParams {
    /// Which side of the mesh (`left`, `right`, `bottom`, `top`, `outline`).
    pub side: BoundarySide,
    /// The condition.
    pub condition: BoundaryCondition,
}

/// How cell gradients are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GradientScheme {
    /// Weighted least squares over the cell's face neighbours, boundary and interface face
    /// values and Neumann conditions: exact for linear fields on any triangulation.
    #[default]
    LeastSquares,
    /// Green–Gauss with the arithmetic face mean (A-Eqs. 41–42), as in the paper.
    GreenGauss,
}

/// How heat crosses a face between a fluid and a solid cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InterfaceModel {
    /// Case IV of A-Sect. 2.3.1: the fluid-side film coefficient h_f from the Nusselt
    /// correlations (A-Eqs. 43–45) in series with the solid's half cell λ_s / d_{r,c}.
    #[default]
    Nusselt,
    /// Perfect thermal contact: the face conducts like a face inside one medium (A-Eq. 47
    /// with the distance-weighted harmonic conductivity of the two cells). This is the
    /// equivalent homogeneous bar of A-Sect. 4, where fluid and solid carry the same
    /// effective properties (A-Eq. 63) and heat diffuses as in one solid.
    Continuous,
}

/// How the non-orthogonal (cross-diffusion) part of A-Eq. 47 enters a face's heat rate.
///
/// On the mesher's meshes, sliver cells along the discretised arcs make some faces nearly
/// tangent to their centroid link (|A| tan θ up to ~90 |A|); the full cross term of such a
/// face can then outweigh the two-point term and make the discrete operator lose its
/// diffusive sign. `Limited` caps the cross term of each face at `ratio` times the magnitude
/// of its two-point term (the "limited" correction of finite-volume codes); the face heat
/// rate stays antisymmetric, so energy is still conserved to round-off.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum CrossDiffusion {
    /// The cross term as printed (exact for linear fields: second order on smooth meshes).
    #[default]
    Full,
    /// |cross term| ≤ `ratio` × |two-point term| on every face (`ratio` ≥ 0; 0 drops the
    /// cross term, 1 is the usual "limited 0.5" of the literature). On a boundary face of
    /// cases I and III the non-orthogonal correction (the temperature difference between the
    /// face centroid and the foot of the normal through the cell centroid) is capped the same
    /// way against the two-point difference between the outside and the cell.
    Limited { ratio: f64 },
}

fn default_stability_safety() -> f64 {
    0.8
}

/// All parameters of the heat solver.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeatParams {
    /// Solid (sphere) properties.
    pub solid: SolidParams,
    /// Liquid phase (`q`) properties.
    pub liquid: PhaseParams,
    /// Gas phase (`p`) properties.
    pub gas: PhaseParams,
    /// Reference temperature T_ref of the enthalpy h = c_p (T − T_ref) (A-Eqs. 31, 51) \[K\].
    pub reference_temperature: f64,
    /// Boundary conditions by side; sides not listed are adiabatic.
    #[serde(default)]
    pub boundaries: Vec<BoundaryParams>,
    /// Fraction (0, 1] of the explicit stability limit used as sub-step (default 0.8).
    #[serde(default = "default_stability_safety")]
    pub stability_safety: f64,
    /// Cell gradient scheme (default least squares; see the crate docs).
    #[serde(default)]
    pub gradient: GradientScheme,
    /// Fluid–solid interface treatment (default: case IV with the Nusselt coefficient).
    #[serde(default)]
    pub interface: InterfaceModel,
    /// Non-orthogonal correction of A-Eq. 47 (default: full).
    #[serde(default)]
    pub cross_diffusion: CrossDiffusion,
}

impl HeatParams {
    /// Table 1 of Krzaczek et al. (2023): solid, water and air properties, reference
    /// temperature 278.16 K, least-squares gradients, the Nusselt interface (case IV), no
    /// boundary conditions (all boundaries adiabatic) and a stability safety factor of 0.8.
    pub fn paper_a_table_1() -> Self {
        Self {
            solid: SolidParams {
                density: 2600.0,
                specific_heat: 920.0,
                conductivity: 3.7,
            },
            liquid: PhaseParams {
                specific_heat: 4187.0,
                conductivity: 0.6,
                dynamic_viscosity: 10.02e-4,
            },
            gas: PhaseParams {
                specific_heat: 1006.0,
                conductivity: 0.0262,
                dynamic_viscosity: 2.0507e-5,
            },
            reference_temperature: 278.16,
            boundaries: Vec::new(),
            stability_safety: 0.8,
            gradient: GradientScheme::LeastSquares,
            interface: InterfaceModel::Nusselt,
            cross_diffusion: CrossDiffusion::Full,
        }
    }
}

/// Validated solid properties.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solid {
    pub(crate) density: f64,
    pub(crate) specific_heat: f64,
    pub(crate) conductivity: f64,
}

impl Solid {
    /// Volumetric heat capacity ρ_s c_p \[J/(m³ K)\].
    pub fn volumetric_heat_capacity(&self) -> f64 {
        self.density * self.specific_heat
    }
    /// Thermal conductivity \[W/(m K)\].
    pub fn conductivity(&self) -> f64 {
        self.conductivity
    }
}

/// Validated boundary condition of one side.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum SideCondition {
    Temperature(TemperatureSchedule),
    HeatFlux(f64),
    Convective { coefficient: f64, ambient: f64 },
}

/// The validated model: parameters that cannot hold invalid values, with the boundary
/// conditions resolved per [`BoundarySide`] and checked against a mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatModel {
    pub(crate) solid: Solid,
    pub(crate) liquid: Phase,
    pub(crate) gas: Phase,
    pub(crate) reference_temperature: f64,
    /// Indexed by [`side_index`]; `HeatFlux(0.0)` for adiabatic sides.
    pub(crate) sides: [SideCondition; 5],
    pub(crate) stability_safety: f64,
    pub(crate) gradient: GradientScheme,
    pub(crate) interface: InterfaceModel,
    /// Largest |cross term| / |two-point term| of a face (`None`: unlimited).
    pub(crate) cross_limit: Option<f64>,
    /// Pr^{1/3} = (c_p μ / λ)^{1/3} of the pure liquid and the pure gas (0 for a phase that
    /// does not conduct): a fluid cell holding one phase only needs no cube root per step.
    pub(crate) pure_prandtl_cbrt: [f64; 2],
}

/// Index of a side in [`HeatModel::sides`].
pub(crate) fn side_index(side: BoundarySide) -> usize {
    match side {
        BoundarySide::Left => 0,
        BoundarySide::Right => 1,
        BoundarySide::Bottom => 2,
        BoundarySide::Top => 3,
        BoundarySide::Outline => 4,
    }
}

fn check(field: String, value: f64, ok: bool, range: &'static str) -> Result<(), HeatError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(HeatError::ParameterOutOfRange {
            field,
            range,
            value,
        })
    }
}

fn positive(field: &str, v: f64) -> Result<(), HeatError> {
    check(field.to_owned(), v, v > 0.0, "> 0")
}

fn non_negative(field: &str, v: f64) -> Result<(), HeatError> {
    check(field.to_owned(), v, v >= 0.0, ">= 0")
}

fn temperature(field: String, v: f64) -> Result<(), HeatError> {
    check(field, v, v > 0.0, "> 0 K")
}

impl HeatModel {
    /// Validates `params` and checks that every side named in `params.boundaries` has at
    /// least one boundary face on `mesh`.
    pub fn new(params: &HeatParams, mesh: &PoreMesh) -> Result<Self, HeatError> {
        let s = &params.solid;
        positive("solid.density", s.density)?;
        positive("solid.specific_heat", s.specific_heat)?;
        non_negative("solid.conductivity", s.conductivity)?;
        let phase = |name: &str, p: &PhaseParams| -> Result<Phase, HeatError> {
            positive(&format!("{name}.specific_heat"), p.specific_heat)?;
            non_negative(&format!("{name}.conductivity"), p.conductivity)?;
            positive(&format!("{name}.dynamic_viscosity"), p.dynamic_viscosity)?;
            Ok(Phase {
                specific_heat: p.specific_heat,
                conductivity: p.conductivity,
                dynamic_viscosity: p.dynamic_viscosity,
            })
        };
        let liquid = phase("liquid", &params.liquid)?;
        let gas = phase("gas", &params.gas)?;
        temperature(
            "reference_temperature".to_owned(),
            params.reference_temperature,
        )?;
        let f = params.stability_safety;
        check(
            "stability_safety".to_owned(),
            f,
            f > 0.0 && f <= 1.0,
            "in (0, 1]",
        )?;
        let cross_limit = match params.cross_diffusion {
            CrossDiffusion::Full => None,
            CrossDiffusion::Limited { ratio } => {
                check(
                    "cross_diffusion.ratio".to_owned(),
                    ratio,
                    ratio.is_finite() && ratio >= 0.0,
                    "finite, >= 0",
                )?;
                Some(ratio)
            }
        };

        let mut present = [false; 5];
        for k in &mesh.face_kind {
            if let FaceKind::Boundary(side) = k {
                present[side_index(*side)] = true;
            }
        }
        let mut sides: [SideCondition; 5] = std::array::from_fn(|_| SideCondition::HeatFlux(0.0));
        let mut set = [false; 5];
        for (i, b) in params.boundaries.iter().enumerate() {
            let k = side_index(b.side);
            if !present[k] {
                return Err(HeatError::BoundaryNotOnMesh {
                    index: i,
                    side: b.side,
                });
            }
            if set[k] {
                return Err(HeatError::DuplicateBoundary {
                    index: i,
                    side: b.side,
                });
            }
            set[k] = true;
            let path = format!("boundaries[{i}]");
            sides[k] = match &b.condition {
                BoundaryCondition::Temperature { temperature: sched } => {
                    validate_schedule(&path, sched)?;
                    SideCondition::Temperature(sched.clone())
                }
                BoundaryCondition::HeatFlux { flux } => {
                    check(format!("{path}.flux"), *flux, true, "finite")?;
                    SideCondition::HeatFlux(*flux)
                }
                BoundaryCondition::Adiabatic => SideCondition::HeatFlux(0.0),
                BoundaryCondition::Convective {
                    coefficient,
                    ambient_temperature,
                } => {
                    check(
                        format!("{path}.coefficient"),
                        *coefficient,
                        *coefficient >= 0.0,
                        ">= 0 W/(m² K)",
                    )?;
                    temperature(format!("{path}.ambient_temperature"), *ambient_temperature)?;
                    SideCondition::Convective {
                        coefficient: *coefficient,
                        ambient: *ambient_temperature,
                    }
                }
            };
        }
        Ok(Self {
            solid: Solid {
                density: s.density,
                specific_heat: s.specific_heat,
                conductivity: s.conductivity,
            },
            liquid,
            gas,
            reference_temperature: params.reference_temperature,
            sides,
            stability_safety: f,
            gradient: params.gradient,
            interface: params.interface,
            cross_limit,
            pure_prandtl_cbrt: [liquid, gas]
                .map(|p| prandtl_cube_root(p.specific_heat, p.dynamic_viscosity, p.conductivity)),
        })
    }

    /// The solid properties.
    pub fn solid(&self) -> Solid {
        self.solid
    }

    /// Reference temperature of the enthalpy \[K\].
    pub fn reference_temperature(&self) -> f64 {
        self.reference_temperature
    }
}

fn validate_schedule(path: &str, s: &TemperatureSchedule) -> Result<(), HeatError> {
    match s {
        TemperatureSchedule::Constant(v) => temperature(format!("{path}.temperature"), *v),
        TemperatureSchedule::Table {
            time,
            temperature: temps,
        } => {
            if time.is_empty() || time.len() != temps.len() {
                return Err(HeatError::LengthMismatch {
                    what: "temperature schedule (time, temperature)",
                    expected: time.len().max(1),
                    got: temps.len(),
                });
            }
            for (j, &t) in time.iter().enumerate() {
                let increasing = j == 0 || t > time[j - 1];
                check(
                    format!("{path}.temperature.time[{j}]"),
                    t,
                    increasing,
                    "finite and strictly increasing",
                )?;
            }
            for (j, &v) in temps.iter().enumerate() {
                temperature(format!("{path}.temperature.temperature[{j}]"), v)?;
            }
            Ok(())
        }
    }
}

impl HeatModel {
    /// Mixture properties of a fluid cell.
    pub fn fluid_mixture(
        &self,
        liquid_fraction: f64,
        liquid_density: f64,
        gas_density: f64,
    ) -> MixtureProperties {
        mixture(
            &self.liquid,
            &self.gas,
            liquid_fraction,
            liquid_density,
            gas_density,
        )
    }
}
