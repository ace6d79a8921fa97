//! `kind = "dem_uniaxial_tension_bar"`: the uniaxial tension test of the bonded bar of
//! Krzaczek et al. (2023), A-Sect. 3.1, on `thm-dem`, as driven by
//! [`thm_dem::tension::BarTension`].
//!
//! A single layer of plane-constrained spheres (a seeded 20 × 80 mm packing, diameters 4–8 mm,
//! or a packing CSV file written by `thm_dem::packing::Packing::write_csv`), bonded stress-free
//! at creation with the cohesive-frictional law (A-Eqs. 1–7, A-Table 1 by default), is pulled
//! apart by two plates moving at `±loading.plate_speed` along `y` until `loading.end_strain`;
//! then the plates hold. Stress = mean plate force / (bar width × `loading.thickness`). The
//! summary compares strength, strain at peak, modulus, broken bonds and coordination with the
//! paper (8.8 MPa, 0.28 %, 3.5 GPa, 12, 6.53); see the verification case
//! `dem/uniaxial_tension_bar` for why the strength falls short with the default bond radius.
//!
//! Geometry: a generated packing is the 20 × 80 mm box; a packing file's bar spans its
//! particles (`min(y − r)` to `max(y + r)`, width `max(x + r) − min(x − r)`). Relative
//! packing-file paths are taken from the working directory. The checkpoint holds the
//! [`DemState`] and the peak tracking; the grips are rebuilt from the packing on resume.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use thm_dem::packing::{Packing, PackingParams, random_packing};
use thm_dem::tension::{BarLoading, BarTension, Grip, rising_branch_modulus};
use thm_dem::{BondRadius, BondState, CohesiveFrictionalParams, DemState, critical_time_step};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};

use crate::config::TimeControl;
use crate::error::{ConfigError, RunError};
use crate::scenario::{FrameSink, Scenario};
use crate::summary::SummaryRow;
use crate::units::{Density, Length, Pressure, Quantity, Velocity};

/// `[packing]`: exactly one of `seed` and `file`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PackingSection {
    /// Seed of the generated 20 × 80 mm bar packing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// A packing CSV file (`particle,x,y,z,radius` and `bond,a,b` rows).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// Generator porosity `1 − Σ A_i/A` (overlaps counted twice); 0.06 gives an area porosity
    /// of about 10 %. Generated packings only.
    #[serde(default = "default_porosity")]
    pub porosity: f64,
    /// Surfaces closer than this are bonded. Generated packings only.
    #[serde(default = "default_bond_gap")]
    pub bond_gap: Quantity<Length>,
}

fn default_porosity() -> f64 {
    thm_dem::tension::GENERATOR_POROSITY
}
fn default_bond_gap() -> Quantity<Length> {
    Quantity::new(4.0, "mm")
}

/// `[material]`: A-Table 1 unless given.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSection {
    /// Contact modulus `E_c`.
    #[serde(default = "default_contact_modulus")]
    pub contact_modulus: Quantity<Pressure>,
    /// Contact Poisson ratio `ν_c` (`K_s = ν_c K_n`).
    #[serde(default = "default_poisson")]
    pub contact_poisson_ratio: f64,
    /// Cohesive contact stress `C`.
    #[serde(default = "default_cohesion")]
    pub cohesion: Quantity<Pressure>,
    /// Tensile normal contact stress `T`.
    #[serde(default = "default_tensile_strength")]
    pub tensile_strength: Quantity<Pressure>,
    /// Inter-particle friction angle `μ_c` in degrees.
    #[serde(default = "default_friction_angle")]
    pub friction_angle_deg: f64,
    /// Mass density.
    #[serde(default = "default_density")]
    pub density: Quantity<Density>,
    /// Which radius enters `T·R²` and `C·R²`: `smaller` or `mean`.
    #[serde(default)]
    pub bond_radius: BondRadius,
}

fn default_contact_modulus() -> Quantity<Pressure> {
    Quantity::new(3.36, "GPa")
}
fn default_poisson() -> f64 {
    0.3
}
fn default_cohesion() -> Quantity<Pressure> {
    Quantity::new(150.0, "MPa")
}
fn default_tensile_strength() -> Quantity<Pressure> {
    Quantity::new(30.0, "MPa")
}
fn default_friction_angle() -> f64 {
    18.0
}
fn default_density() -> Quantity<Density> {
    Quantity::new(2600.0, "kg/m^3")
}

impl Default for MaterialSection {
    fn default() -> Self {
        Self {
            contact_modulus: default_contact_modulus(),
            contact_poisson_ratio: default_poisson(),
            cohesion: default_cohesion(),
            tensile_strength: default_tensile_strength(),
            friction_angle_deg: default_friction_angle(),
            density: default_density(),
            bond_radius: BondRadius::default(),
        }
    }
}

/// `[loading]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadingSection {
    /// Speed of each plate (they move apart).
    pub plate_speed: Quantity<Velocity>,
    /// Strain at which the plates stop and hold.
    pub end_strain: f64,
    /// Out-of-plane thickness of the stress area (A-Sect. 2.2: the largest diameter).
    #[serde(default = "default_thickness")]
    pub thickness: Quantity<Length>,
    /// Particles whose surface lies within this distance of a bar end are gripped.
    #[serde(default = "default_grip_depth")]
    pub grip_depth: Quantity<Length>,
    /// `smooth` (axial motion prescribed) or `clamped` (all motion prescribed).
    #[serde(default)]
    pub grip: Grip,
    /// Cundall damping `α_d` (A-Eq. 7).
    #[serde(default = "default_damping")]
    pub damping: f64,
}

fn default_thickness() -> Quantity<Length> {
    Quantity::new(8.0, "mm")
}
fn default_grip_depth() -> Quantity<Length> {
    Quantity::new(1.0, "mm")
}
fn default_damping() -> f64 {
    0.08
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[packing]`.
    pub packing: PackingSection,
    /// `[material]`.
    #[serde(default)]
    pub material: MaterialSection,
    /// `[loading]`.
    pub loading: LoadingSection,
}

/// The evolving state: the DEM state and what the summary needs of the past.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Particles, contacts, bond-break events.
    pub dem: DemState,
    /// Largest stress so far \[Pa\].
    pub peak_stress: f64,
    /// Strain at that stress \[-\].
    pub strain_at_peak: f64,
    /// Coordination number after the first step.
    pub coordination_initial: f64,
    /// The curve every 1 µm of plate travel: strain \[-\], stress \[Pa\] (for the modulus).
    pub curve: Vec<[f64; 2]>,
}

/// Upper bound on the Cundall damping coefficient (A-Eq. 7 needs `α_d < 1`).
const MAX_DAMPING: f64 = 0.99;

/// The stepper: the bar driver and frame scratch.
#[derive(Debug)]
pub struct DemTensionBar {
    bar: BarTension,
    /// Steps between curve samples.
    sample_every: u64,
    positions: Vec<[f64; 3]>,
    velocities: Vec<[f64; 3]>,
    forces: Vec<[f64; 3]>,
    broken_per_particle: Vec<f64>,
    bond_lines: Vec<[u32; 2]>,
    bond_normal_force: Vec<f64>,
}

fn check_range(key: &str, value: f64, lo: f64, hi: f64) -> Result<f64, ConfigError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(ConfigError::new(
            key,
            format!("must be in [{lo}, {hi}], got {value}"),
        ))
    }
}

/// A `thm-dem` error while building, attributed to the key that caused it.
fn dem_config_error(e: thm_dem::DemError) -> ConfigError {
    let key = match &e {
        thm_dem::DemError::InvalidParameter { field, .. } => match *field {
            "plate_speed" | "end_strain" | "thickness" | "grip_depth" => format!("loading.{field}"),
            "porosity" | "bond_gap" => format!("packing.{field}"),
            "contact_modulus"
            | "contact_poisson_ratio"
            | "cohesion"
            | "tensile_strength"
            | "friction_angle_deg" => format!("material.{field}"),
            _ => "packing".into(),
        },
        _ => "packing".into(),
    };
    ConfigError::new(key, e.to_string())
}

/// The packing and its bar: `(packing, y_bottom, y_top, width)`.
fn build_packing(
    p: &PackingSection,
    density: f64,
) -> Result<(Packing, f64, f64, f64), ConfigError> {
    match (p.seed, &p.file) {
        (Some(seed), None) => {
            check_range("packing.porosity", p.porosity, 0.0, 0.5)?;
            let gap = p.bond_gap.within("packing.bond_gap", 0.0, 0.008)?;
            let params = PackingParams {
                porosity: p.porosity,
                bond_gap: gap,
                ..PackingParams::paper_a_bar(seed)
            };
            let (packing, _) = random_packing(&params, density).map_err(dem_config_error)?;
            let width = params.box_max[0] - params.box_min[0];
            Ok((packing, params.box_min[1], params.box_max[1], width))
        }
        (None, Some(file)) => {
            let packing = Packing::read_csv(file).map_err(|e| {
                ConfigError::new("packing.file", format!("{}: {e}", file.display()))
            })?;
            // Disks carry forces per unit thickness, which the stress area does not expect.
            if packing.kinematics != thm_dem::Kinematics::SpheresInPlane || packing.radii.is_empty()
            {
                return Err(ConfigError::new(
                    "packing.file",
                    format!(
                        "must hold one layer of spheres (kinematics=spheres_in_plane) with at least one particle: {}",
                        file.display()
                    ),
                ));
            }
            let lo = |f: &dyn Fn(usize) -> f64| {
                (0..packing.radii.len())
                    .map(f)
                    .fold(f64::INFINITY, f64::min)
            };
            let hi = |f: &dyn Fn(usize) -> f64| {
                (0..packing.radii.len())
                    .map(f)
                    .fold(f64::NEG_INFINITY, f64::max)
            };
            let (c, r) = (&packing.centres, &packing.radii);
            let y_bottom = lo(&|i| c[i].y - r[i]);
            let y_top = hi(&|i| c[i].y + r[i]);
            let width = hi(&|i| c[i].x + r[i]) - lo(&|i| c[i].x - r[i]);
            Ok((packing, y_bottom, y_top, width))
        }
        _ => Err(ConfigError::new(
            "packing",
            "give exactly one of `seed` (a generated 20 × 80 mm bar) and `file` (a packing CSV)",
        )),
    }
}

impl DemTensionBar {
    fn record(&self, state: &mut State) {
        let s = self.bar.sample(&state.dem);
        if s.stress > state.peak_stress {
            state.peak_stress = s.stress;
            state.strain_at_peak = s.strain;
        }
        if state.dem.step.is_multiple_of(self.sample_every) {
            state.curve.push([s.strain, s.stress]);
        }
    }
}

impl Scenario for DemTensionBar {
    const KIND: &'static str = "dem_uniaxial_tension_bar";
    const STATE_VERSION: u32 = 1;
    type Params = Params;
    type State = State;

    fn arrays<'s>(&'s self, state: &'s State) -> Vec<crate::arrays::StateArray<'s>> {
        crate::arrays::sphere_arrays(&state.dem.particles)
    }

    fn set_array(&mut self, state: &mut State, name: &str, values: &[f64]) -> Result<(), RunError> {
        if crate::arrays::set_sphere_force(&mut state.dem.particles, name, values)? {
            return Ok(());
        }
        Err(crate::arrays::not_writable(
            name,
            &["sphere_external_force"],
        ))
    }

    fn init(p: &Params, time: &TimeControl) -> Result<(Self, State), ConfigError> {
        let m = &p.material;
        let density = m.density.positive("material.density")?;
        let law = CohesiveFrictionalParams {
            contact_modulus: m.contact_modulus.positive("material.contact_modulus")?,
            contact_poisson_ratio: check_range(
                "material.contact_poisson_ratio",
                m.contact_poisson_ratio,
                0.0,
                10.0,
            )?,
            cohesion: m.cohesion.within("material.cohesion", 0.0, f64::MAX)?,
            tensile_strength: m.tensile_strength.within(
                "material.tensile_strength",
                0.0,
                f64::MAX,
            )?,
            friction_angle_deg: check_range(
                "material.friction_angle_deg",
                m.friction_angle_deg,
                0.0,
                89.9,
            )?,
            bond_radius: m.bond_radius,
        }
        .validate()
        .map_err(dem_config_error)?;
        let l = &p.loading;
        let loading = BarLoading {
            plate_speed: l.plate_speed.within("loading.plate_speed", 1e-9, 10.0)?,
            end_strain: check_range("loading.end_strain", l.end_strain, 1e-9, 0.5)?,
            thickness: l.thickness.positive("loading.thickness")?,
            grip_depth: l.grip_depth.within("loading.grip_depth", 0.0, 0.1)?,
            grip: l.grip,
            time_step: time.dt,
            damping: check_range("loading.damping", l.damping, 0.0, MAX_DAMPING)?,
        };
        let (packing, y_bottom, y_top, width) = build_packing(&p.packing, density)?;
        let dt_limit = {
            let state = packing
                .to_state(density, 293.15)
                .map_err(dem_config_error)?;
            0.5 * critical_time_step(&state, &law)
        };
        if time.dt > dt_limit {
            return Err(ConfigError::new(
                "time.step",
                format!(
                    "must be ≤ {dt_limit:e} s (half the critical step of this packing and material), got {} s",
                    time.dt
                ),
            ));
        }
        let needed = l.end_strain * (y_top - y_bottom) / (2.0 * loading.plate_speed);
        let end = time.n_steps as f64 * time.dt;
        if end < needed * (1.0 - 1e-9) {
            return Err(ConfigError::new(
                "time.end",
                format!(
                    "must be ≥ {needed:e} s to reach loading.end_strain = {} at ±{} m/s on a {} m bar, got {end:e} s",
                    l.end_strain,
                    loading.plate_speed,
                    y_top - y_bottom
                ),
            ));
        }
        let (bar, dem) = BarTension::new(&packing, law, density, &loading, y_bottom, y_top, width)
            .map_err(dem_config_error)?;
        let n = dem.particles.len();
        let sample_every = ((1e-6 / loading.plate_speed) / time.dt).ceil().max(1.0) as u64;
        Ok((
            Self {
                bar,
                sample_every,
                positions: vec![[0.0; 3]; n],
                velocities: vec![[0.0; 3]; n],
                forces: vec![[0.0; 3]; n],
                broken_per_particle: vec![0.0; n],
                bond_lines: Vec::new(),
                bond_normal_force: Vec::new(),
            },
            State {
                dem,
                peak_stress: 0.0,
                strain_at_peak: 0.0,
                coordination_initial: f64::NAN,
                curve: vec![[0.0, 0.0]],
            },
        ))
    }

    fn step(&mut self, state: &mut State, step: u64, _dt: f64) -> Result<(), RunError> {
        let time = state.dem.time;
        self.bar
            .step(&mut state.dem)
            .map_err(|e| RunError::Physics {
                step,
                time,
                message: e.to_string(),
            })?;
        if state.dem.step == 1 {
            state.coordination_initial = state.dem.coordination_number();
        }
        self.record(state);
        Ok(())
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("strain", "1"),
            Column::new("stress", "Pa"),
            Column::new("broken_bonds", "1"),
            Column::new("coordination_number", "1"),
        ]
    }

    fn monitor(&self, state: &State, values: &mut Vec<f64>) {
        let s = self.bar.sample(&state.dem);
        let dem = &state.dem;
        // Before the first step no contact has been evaluated: the bonds are the contacts.
        let coordination = if dem.step == 0 {
            2.0 * dem.contacts.intact_bond_count() as f64 / dem.particles.len().max(1) as f64
        } else {
            dem.coordination_number()
        };
        values.extend([
            s.strain,
            s.stress,
            dem.bond_breaks.len() as f64,
            coordination,
        ]);
    }

    fn frame(&mut self, state: &State, sink: &mut FrameSink<'_>) -> Result<(), IoError> {
        let p = &state.dem.particles;
        for (k, x) in p.position.iter().enumerate() {
            self.positions[k] = [x.x, x.y, x.z];
            let v = p.velocity[k];
            self.velocities[k] = [v.x, v.y, v.z];
            let f = p.force[k];
            self.forces[k] = [f.x, f.y, f.z];
        }
        self.broken_per_particle.fill(0.0);
        for b in &state.dem.bond_breaks {
            self.broken_per_particle[b.a as usize] += 1.0;
            self.broken_per_particle[b.b as usize] += 1.0;
        }
        let spheres = UnstructuredGrid::particles(&self.positions)
            .with_point_field("radius [m]", FieldValues::Scalar(&p.radius))
            .with_point_field("velocity [m/s]", FieldValues::Vector3(&self.velocities))
            .with_point_field("force [N]", FieldValues::Vector3(&self.forces))
            .with_point_field(
                "broken_bonds [1]",
                FieldValues::Scalar(&self.broken_per_particle),
            );
        sink("spheres", &spheres)?;
        let c = &state.dem.contacts;
        self.bond_lines.clear();
        self.bond_normal_force.clear();
        for k in 0..c.len() {
            if c.history[k].bond == BondState::Intact {
                self.bond_lines.push(c.pair[k]);
                self.bond_normal_force.push(c.report[k].normal_force);
            }
        }
        let bonds = UnstructuredGrid::lines(&self.positions, &self.bond_lines).with_cell_field(
            "normal_force [N] (compression > 0)",
            FieldValues::Scalar(&self.bond_normal_force),
        );
        sink("bonds", &bonds)
    }

    fn summary(&self, state: &State, _time: f64) -> Vec<SummaryRow> {
        let modulus = {
            let (strain, stress): (Vec<f64>, Vec<f64>) =
                state.curve.iter().map(|s| (s[0], s[1])).unzip();
            rising_branch_modulus(&strain, &stress, state.peak_stress, state.strain_at_peak)
        };
        let row = SummaryRow::new;
        vec![
            row(
                "tensile strength",
                "MPa",
                state.peak_stress / 1e6,
                Some(8.8),
            ),
            row(
                "strain at peak",
                "%",
                100.0 * state.strain_at_peak,
                Some(0.28),
            ),
            row(
                "Young's modulus (10–50 % of the peak)",
                "GPa",
                modulus / 1e9,
                Some(3.5),
            ),
            row(
                "broken bonds",
                "",
                state.dem.bond_breaks.len() as f64,
                Some(12.0),
            ),
            row(
                "coordination number, initial",
                "",
                state.coordination_initial,
                Some(6.53),
            ),
            row(
                "coordination number, end",
                "",
                state.dem.coordination_number(),
                None,
            ),
            row("particles", "", state.dem.particles.len() as f64, None),
        ]
    }
}
