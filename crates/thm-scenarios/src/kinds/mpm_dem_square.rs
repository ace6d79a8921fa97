//! `kind = "mpm_dem_square"`: the 2D square of B-Sect. 5.2.2 (Zhao et al. 2022) on the
//! MPM×DEM scheme of `thm-coupling` (`thm_coupling::multiscale::square::SquareModel`), run
//! side by side with its pure-MPM twin.
//!
//! The unit square, initially 0 °C, has all sides held at 100 °C with their normal
//! displacement fixed; `cells × cells` material points each carry an RVE of `disks` disks
//! (radii in [0.25, 0.5] mm, B-Table 1 contacts, consolidated to 100 kPa with μ = 0.001, then
//! μ = 0.5; see `GranularSquare::reduced`). The twin is thermo-elastic with the RVE's affine
//! moduli (B-Eq. 58) and its mean conductivity. At the centre (the mean of the four points
//! around it for an even `cells`), the temperature of both is compared with B-Eq. 59
//! (corrected: the exponent is `π²((2m+1)² + (2n+1)²) κ t/L²`), with the RVE's initial
//! `k_xx`, `k_yy` for the multiscale model and their mean for the twin. The RVEs' conductivity
//! grows as they are compressed by the heating, and their friction heat (B-Eqs. 32–33, on by
//! default as in the paper) heats the square: B-Eq. 59 has neither (see
//! docs/cases/mpm_dem_square.md). The stepper and materials are rebuilt from the parameters
//! on resume; the checkpoint holds both `MpmState`s, every RVE included.

use serde::{Deserialize, Serialize};
use thm_coupling::multiscale::distributed::SharedDistribution;
use thm_coupling::multiscale::square::{
    GranularSquare, SquareModel, centre_value, square_temperature,
};
use thm_coupling::multiscale::{RveMaterial, RvePoint};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};
use thm_mpm::{BatchConstitutive, LinearThermoElastic, Mpm, MpmState};

use crate::config::TimeControl;
use crate::error::{ConfigError, RunError};
use crate::scenario::{FrameSink, Scenario};
use crate::summary::SummaryRow;

/// `[square]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SquareParams {
    /// Cells (one material point each) along each side, in [2, 200] (the paper: 40).
    pub cells: usize,
    /// Disks per RVE, in [20, 5000] (the paper: 400).
    pub disks: usize,
    /// Seed of the RVE packing.
    pub seed: u64,
    /// Density scaling of the RVE disks (DEM time rule), in [1, 1e6] (1: physical masses).
    pub density_scaling: f64,
    /// Whether the RVEs' friction heat (B-Eqs. 32–33) heats the points (the paper's model).
    pub friction_heat: bool,
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[square]`.
    pub square: SquareParams,
}

/// The state: the multiscale model's points with their RVEs, and the twin's points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SquareState {
    /// Points of the TM-DEMPM model, each with its RVE.
    pub multiscale: MpmState<RvePoint>,
    /// Points of the TM-MPM twin.
    pub twin: MpmState<()>,
}

/// The stepper: both MPM steppers and materials (scratch), and what the monitors need.
#[derive(Debug)]
pub struct MpmDemSquare {
    mpm: Mpm,
    material: RveMaterial,
    twin_mpm: Mpm,
    twin_material: LinearThermoElastic,
    square: GranularSquare,
    /// Twin's `[E, ν]` (Pa, -).
    twin_moduli: [f64; 2],
    /// Diffusivities of the RVE's initial conductivity `[κ_xx, κ_yy]` (m²/s).
    kappa: [f64; 2],
    /// Initial positions of the points (m).
    x0: Vec<[f64; 2]>,
    /// Initial stress of the multiscale points (Pa).
    stress0: [f64; 3],
    stress: Vec<[f64; 3]>,
    temperature_change: Vec<f64>,
    displacement: Vec<[f64; 2]>,
    void_ratio: Vec<f64>,
    coordination: Vec<f64>,
    kinetic: Vec<f64>,
}

/// The initial and boundary temperatures of B-Sect. 5.2.2 (°C).
const T0: f64 = 0.0;
const T1: f64 = 100.0;

impl MpmDemSquare {
    fn centre(&self, value: impl Fn(usize) -> f64) -> f64 {
        centre_value(self.square.cells, value)
    }

    /// B-Eq. 59 at the centre (averaged like the points) with diffusivities `kappa`.
    fn centre_reference(&self, kappa: [f64; 2], time: f64) -> f64 {
        self.centre(|i| square_temperature(self.x0[i], time, kappa, T0, T1))
    }
}

impl Scenario for MpmDemSquare {
    const KIND: &'static str = "mpm_dem_square";
    // 2: RvePoint carries its intact bond count.
    const STATE_VERSION: u32 = 2;
    type Params = Params;
    type State = SquareState;

    fn distribute(&mut self, distribution: &SharedDistribution) -> Result<(), RunError> {
        self.material
            .distribute(std::sync::Arc::clone(distribution));
        Ok(())
    }

    fn synchronise(&mut self, state: &mut Self::State) -> Result<(), RunError> {
        let (step, time) = (state.multiscale.step, state.multiscale.time);
        super::multiscale::synchronise_points(
            &self.material,
            &mut state.multiscale.material,
            step,
            time,
        )
    }

    fn arrays<'s>(&'s self, state: &'s SquareState) -> Vec<crate::arrays::StateArray<'s>> {
        let mut arrays =
            crate::arrays::point_arrays(&state.multiscale.points, &crate::arrays::POINTS);
        arrays.extend(crate::arrays::point_arrays(
            &state.twin.points,
            &crate::arrays::TWIN_POINTS,
        ));
        arrays.extend(crate::arrays::rve_arrays(&state.multiscale.material));
        arrays
    }

    fn set_array(
        &mut self,
        state: &mut SquareState,
        name: &str,
        values: &[f64],
    ) -> Result<(), RunError> {
        use crate::arrays::{POINTS, set_point_array, writable_points};
        if set_point_array(&mut state.multiscale.points, &POINTS, name, values)? {
            return Ok(());
        }
        if set_point_array(
            &mut state.twin.points,
            &crate::arrays::TWIN_POINTS,
            name,
            values,
        )? {
            return Ok(());
        }
        Err(crate::arrays::not_writable(
            name,
            &[
                writable_points(&POINTS),
                writable_points(&crate::arrays::TWIN_POINTS),
            ]
            .concat(),
        ))
    }

    fn init(p: &Params, time: &TimeControl) -> Result<(Self, Self::State), ConfigError> {
        let s = &p.square;
        if !(2..=200).contains(&s.cells) {
            return Err(ConfigError::new(
                "square.cells",
                format!("must be in [2, 200], got {}", s.cells),
            ));
        }
        if !(20..=5000).contains(&s.disks) {
            return Err(ConfigError::new(
                "square.disks",
                format!("must be in [20, 5000], got {}", s.disks),
            ));
        }
        if !(s.density_scaling.is_finite() && (1.0..=1e6).contains(&s.density_scaling)) {
            return Err(ConfigError::new(
                "square.density_scaling",
                format!("must be in [1, 1e6], got {}", s.density_scaling),
            ));
        }
        let mut square = GranularSquare::reduced(s.cells, s.disks, s.density_scaling);
        square.seed = s.seed;
        square.friction_heat = s.friction_heat;
        square.time_step = time.dt;
        let model =
            SquareModel::new(&square).map_err(|e| ConfigError::new("square", e.to_string()))?;
        let material = &model.material;
        let limit = model
            .mpm
            .time_step_limits_with(&model.state.points, |i| {
                material.wave_modulus(&model.state.material[i])
            })
            .min()
            .min(
                model
                    .twin_mpm
                    .time_step_limits(&model.twin_state, &model.twin_material)
                    .min(),
            );
        if time.dt > limit {
            return Err(ConfigError::new(
                "time.step",
                format!(
                    "must be ≤ {limit:e} s (B-Eqs. 30–31 stability limit on {} × {} cells), got {} s",
                    s.cells, s.cells, time.dt
                ),
            ));
        }
        let points = &model.state.points;
        let rho_c = points.mass[0] / points.volume[0] * points.specific_heat[0];
        let k = model.material.initial_conductivity();
        let n = points.len();
        let x0 = points.position.clone();
        let stress0 = points.stress[0];
        Ok((
            Self {
                mpm: model.mpm,
                material: model.material,
                twin_mpm: model.twin_mpm,
                twin_material: model.twin_material,
                square,
                twin_moduli: model.twin_moduli,
                kappa: [k[0] / rho_c, k[1] / rho_c],
                x0,
                stress0,
                stress: vec![[0.0; 3]; n],
                temperature_change: vec![0.0; n],
                displacement: vec![[0.0; 2]; n],
                void_ratio: vec![0.0; n],
                coordination: vec![0.0; n],
                kinetic: vec![0.0; n],
            },
            SquareState {
                multiscale: model.state,
                twin: model.twin_state,
            },
        ))
    }

    fn step(&mut self, state: &mut Self::State, step: u64, dt: f64) -> Result<(), RunError> {
        let time = state.multiscale.time;
        let physics = |message: String| RunError::Physics {
            step,
            time,
            message,
        };
        self.mpm
            .step_batch(&mut state.multiscale, &mut self.material, dt)
            .map_err(|e| physics(e.to_string()))?;
        if !self.square.friction_heat {
            // As `SquareModel::step`: the next heat load (B-Eq. 18) reads the heat source.
            state.multiscale.points.heat_source.fill(0.0);
        }
        self.twin_mpm
            .step(&mut state.twin, &self.twin_material, dt)
            .map_err(|e| physics(e.to_string()))
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("centre_temperature", "°C"),
            Column::new("centre_stress_xx", "Pa"),
            Column::new("centre_stress_yy", "Pa"),
            Column::new("twin_centre_temperature", "°C"),
            Column::new("twin_centre_stress_xx", "Pa"),
            Column::new("twin_centre_stress_yy", "Pa"),
            Column::new("largest_rve_kinetic_ratio", "-"),
        ]
    }

    fn monitor(&self, state: &Self::State, values: &mut Vec<f64>) {
        let (p, q) = (&state.multiscale.points, &state.twin.points);
        values.extend([
            self.centre(|i| p.remapped_temperature[i]),
            self.centre(|i| p.stress[i][0]),
            self.centre(|i| p.stress[i][1]),
            self.centre(|i| q.remapped_temperature[i]),
            self.centre(|i| q.stress[i][0]),
            self.centre(|i| q.stress[i][1]),
            state
                .multiscale
                .material
                .iter()
                .fold(0.0_f64, |m, r| m.max(r.kinetic_ratio)),
        ]);
    }

    fn reference(&self, column: usize, time: f64) -> Option<f64> {
        let mean = 0.5 * (self.kappa[0] + self.kappa[1]);
        match column {
            0 => Some(self.centre_reference(self.kappa, time)),
            3 => Some(self.centre_reference([mean, mean], time)),
            _ => None,
        }
    }

    fn frame(&mut self, state: &Self::State, sink: &mut FrameSink<'_>) -> Result<(), IoError> {
        let p = &state.multiscale.points;
        for (k, s) in self.stress.iter_mut().enumerate() {
            *s = p.stress[k];
        }
        for (k, d) in self.temperature_change.iter_mut().enumerate() {
            *d = p.remapped_temperature[k] - T0;
        }
        for (k, u) in self.displacement.iter_mut().enumerate() {
            *u = [
                p.position[k][0] - self.x0[k][0],
                p.position[k][1] - self.x0[k][1],
            ];
        }
        for (k, r) in state.multiscale.material.iter().enumerate() {
            self.void_ratio[k] = r.rve.void_ratio();
            self.coordination[k] = r.rve.coordination_number();
            self.kinetic[k] = r.kinetic_ratio;
        }
        let grid = UnstructuredGrid::particles(&p.position)
            .with_point_field(
                "temperature [°C]",
                FieldValues::Scalar(&p.remapped_temperature),
            )
            .with_point_field(
                "temperature_change [K]",
                FieldValues::Scalar(&self.temperature_change),
            )
            .with_point_field("stress_xx_yy_xy [Pa]", FieldValues::Vector3(&self.stress))
            .with_point_field("heat_source [W/m^3]", FieldValues::Scalar(&p.heat_source))
            .with_point_field("void_ratio", FieldValues::Scalar(&self.void_ratio))
            .with_point_field(
                "coordination_number",
                FieldValues::Scalar(&self.coordination),
            )
            .with_point_field("rve_kinetic_ratio", FieldValues::Scalar(&self.kinetic))
            .with_point_field("velocity [m/s]", FieldValues::Vector2(&p.velocity))
            .with_point_field("displacement [m]", FieldValues::Vector2(&self.displacement));
        sink("material_points", &grid)?;
        let q = &state.twin.points;
        for (k, s) in self.stress.iter_mut().enumerate() {
            *s = q.stress[k];
        }
        for (k, u) in self.displacement.iter_mut().enumerate() {
            *u = [
                q.position[k][0] - self.x0[k][0],
                q.position[k][1] - self.x0[k][1],
            ];
        }
        let twin = UnstructuredGrid::particles(&q.position)
            .with_point_field(
                "temperature [°C]",
                FieldValues::Scalar(&q.remapped_temperature),
            )
            .with_point_field("stress_xx_yy_xy [Pa]", FieldValues::Vector3(&self.stress))
            .with_point_field("displacement [m]", FieldValues::Vector2(&self.displacement));
        sink("twin_points", &twin)
    }

    fn summary(&self, state: &Self::State, time: f64) -> Vec<SummaryRow> {
        let mut values = Vec::new();
        self.monitor(state, &mut values);
        let mut rows: Vec<SummaryRow> = self
            .monitor_columns()
            .into_iter()
            .zip(values)
            .enumerate()
            .map(|(k, (c, measured))| SummaryRow {
                quantity: c.name,
                unit: c.unit,
                measured,
                reference: self.reference(k, time),
            })
            .collect();
        let p = &state.multiscale.points;
        rows.push(SummaryRow::new(
            "centre_stress_change_xx",
            "Pa",
            self.centre(|i| p.stress[i][0] - self.stress0[0]),
            None,
        ));
        rows.push(SummaryRow::new(
            "centre_stress_change_yy",
            "Pa",
            self.centre(|i| p.stress[i][1] - self.stress0[1]),
            None,
        ));
        rows.push(SummaryRow::new(
            "twin_youngs_modulus (B-Eq. 58 affine; the paper: 12 MPa)",
            "Pa",
            self.twin_moduli[0],
            Some(12e6),
        ));
        rows.push(SummaryRow::new(
            "twin_poisson_ratio (B-Eq. 58 affine; the paper: 0.18)",
            "-",
            self.twin_moduli[1],
            Some(0.18),
        ));
        rows
    }
}
