//! `kind = "mpm_dem_rod"`: the granular rod of B-Sect. 5.2.1 (Zhao et al. 2022) on the
//! MPM×DEM scheme of `thm-coupling` (`thm_coupling::multiscale::RodModel`).
//!
//! A 1 m rod, fixed at both ends, of `cells` material points, each carrying a square packing of
//! `disks_per_side²` disks (r = 5 mm, B-Table 1 contacts, 100 kPa), is heated at x = L from
//! 0 to 100 °C at t = 0. At the probe, the temperature is compared with B-Eq. 55, the change of
//! the axial stress with B-Eq. 56 (K = D_xxxx of B-Eq. 58 measured on the RVE) and the
//! displacement with B-Eq. 57 (as derived: the printed form has `cos(nπx/x)` for
//! `cos(nπx/L)`); the last two are quasi-static solutions, reached after about 0.4 s. All other
//! parameters are the paper's (`GranularRod::paper`). The stepper and material are rebuilt
//! from the parameters on resume; the checkpoint holds the `MpmState` with every RVE.

use serde::{Deserialize, Serialize};
use thm_coupling::multiscale::distributed::SharedDistribution;
use thm_coupling::multiscale::rod::{rod_displacement, rod_stress, rod_temperature};
use thm_coupling::multiscale::{GranularRod, RodModel, RveMaterial, RvePoint};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};
use thm_mpm::{BatchConstitutive, Mpm, MpmState};

use crate::config::TimeControl;
use crate::error::{ConfigError, RunError};
use crate::scenario::{FrameSink, Scenario};
use crate::summary::SummaryRow;
use crate::units::{Length, Quantity};

/// `[rod]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RodParams {
    /// Cells (and material points) along the 1 m rod, in [2, 10000] (the paper: 50).
    pub cells: usize,
    /// Disks along each side of every RVE's square packing, in [3, 100] (the paper: 20).
    pub disks_per_side: usize,
    /// Density scaling of the RVE disks (DEM time rule), in [1, 1e6] (1: physical masses).
    pub density_scaling: f64,
    /// Grid damping α_g of B-Eq. 26, in [0, 1] (0.01 damps the heating's stress wave).
    pub grid_damping: f64,
    /// Position of the monitored probe along the rod.
    pub probe: Quantity<Length>,
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[rod]`.
    pub rod: RodParams,
}

/// The stepper: MPM scratch, the RVE material (scratch), and what the monitors need.
#[derive(Debug)]
pub struct MpmDemRod {
    mpm: Mpm,
    material: RveMaterial,
    rod: GranularRod,
    /// Axial stiffness K of B-Eq. 58 on the RVE \[Pa\].
    stiffness: f64,
    /// Initial axial stress \[Pa\].
    stress0: f64,
    probe: f64,
    /// Initial x of each point \[m\].
    x0: Vec<f64>,
    stress_xx: Vec<f64>,
    displacement: Vec<[f64; 2]>,
    kinetic: Vec<f64>,
}

impl MpmDemRod {
    /// Linear interpolation along the rod of a per-point value at the probe.
    fn at_probe(&self, value: impl Fn(usize) -> f64) -> f64 {
        let h = self.rod.cell_size();
        let n = self.x0.len();
        let s = self.probe / h - 0.5;
        let i = (s.floor().max(0.0) as usize).min(n.saturating_sub(2));
        let f = s - i as f64;
        (1.0 - f) * value(i) + f * value(i + 1)
    }
}

impl Scenario for MpmDemRod {
    const KIND: &'static str = "mpm_dem_rod";
    // 2: RvePoint carries its intact bond count.
    const STATE_VERSION: u32 = 2;
    type Params = Params;
    type State = MpmState<RvePoint>;

    fn distribute(&mut self, distribution: &SharedDistribution) -> Result<(), RunError> {
        self.material
            .distribute(std::sync::Arc::clone(distribution));
        Ok(())
    }

    fn synchronise(&mut self, state: &mut Self::State) -> Result<(), RunError> {
        let (step, time) = (state.step, state.time);
        super::multiscale::synchronise_points(&self.material, &mut state.material, step, time)
    }

    fn arrays<'s>(&'s self, state: &'s Self::State) -> Vec<crate::arrays::StateArray<'s>> {
        crate::arrays::mpm_rve_arrays(&state.points, &state.material)
    }

    fn set_array(
        &mut self,
        state: &mut Self::State,
        name: &str,
        values: &[f64],
    ) -> Result<(), RunError> {
        crate::arrays::set_points_array(&mut state.points, name, values)
    }

    fn init(p: &Params, time: &TimeControl) -> Result<(Self, Self::State), ConfigError> {
        let r = &p.rod;
        if !(2..=10_000).contains(&r.cells) {
            return Err(ConfigError::new(
                "rod.cells",
                format!("must be in [2, 10000], got {}", r.cells),
            ));
        }
        if !(3..=100).contains(&r.disks_per_side) {
            return Err(ConfigError::new(
                "rod.disks_per_side",
                format!("must be in [3, 100], got {}", r.disks_per_side),
            ));
        }
        if !(r.density_scaling.is_finite() && (1.0..=1e6).contains(&r.density_scaling)) {
            return Err(ConfigError::new(
                "rod.density_scaling",
                format!("must be in [1, 1e6], got {}", r.density_scaling),
            ));
        }
        if !(r.grid_damping.is_finite() && (0.0..=1.0).contains(&r.grid_damping)) {
            return Err(ConfigError::new(
                "rod.grid_damping",
                format!("must be in [0, 1], got {}", r.grid_damping),
            ));
        }
        let mut rod = GranularRod::paper();
        rod.cells = r.cells;
        rod.disks_per_side = r.disks_per_side;
        rod.dem_time.density_scaling = r.density_scaling;
        rod.grid_damping = r.grid_damping;
        rod.time_step = time.dt;
        let h = rod.cell_size();
        let probe = r.probe.si();
        if !(probe.is_finite() && probe >= 0.5 * h && probe <= rod.length - 0.5 * h) {
            return Err(ConfigError::new(
                "rod.probe",
                format!(
                    "must be in [{} m, {} m] (between the first and last point), got {} m",
                    0.5 * h,
                    rod.length - 0.5 * h,
                    probe
                ),
            ));
        }
        let model = RodModel::new(&rod).map_err(|e| ConfigError::new("rod", e.to_string()))?;
        let material = &model.material;
        let limit = model
            .mpm
            .time_step_limits_with(&model.state.points, |i| {
                material.wave_modulus(&model.state.material[i])
            })
            .min();
        if time.dt > limit {
            return Err(ConfigError::new(
                "time.step",
                format!(
                    "must be ≤ {limit:e} s (B-Eqs. 30–31 stability limit on {} cells), got {} s",
                    r.cells, time.dt
                ),
            ));
        }
        let n = model.state.points.len();
        let stiffness = model.axial_stiffness();
        let stress0 = model.state.points.stress[0][0];
        let x0 = model.state.points.position.iter().map(|x| x[0]).collect();
        Ok((
            Self {
                mpm: model.mpm,
                material: model.material,
                rod,
                stiffness,
                stress0,
                probe,
                x0,
                stress_xx: vec![0.0; n],
                displacement: vec![[0.0; 2]; n],
                kinetic: vec![0.0; n],
            },
            model.state,
        ))
    }

    fn step(&mut self, state: &mut Self::State, step: u64, dt: f64) -> Result<(), RunError> {
        let time = state.time;
        self.mpm
            .step_batch(state, &mut self.material, dt)
            .map_err(|e| RunError::Physics {
                step,
                time,
                message: e.to_string(),
            })
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("temperature_at_probe", "°C"),
            Column::new("stress_change_xx_at_probe", "Pa"),
            Column::new("displacement_at_probe", "m"),
            Column::new("largest_rve_kinetic_ratio", "-"),
        ]
    }

    fn monitor(&self, state: &Self::State, values: &mut Vec<f64>) {
        let p = &state.points;
        values.extend([
            self.at_probe(|i| p.remapped_temperature[i]),
            self.at_probe(|i| p.stress[i][0] - self.stress0),
            self.at_probe(|i| p.position[i][0] - self.x0[i]),
            state
                .material
                .iter()
                .fold(0.0_f64, |m, r| m.max(r.kinetic_ratio)),
        ]);
    }

    fn reference(&self, column: usize, time: f64) -> Option<f64> {
        let r = &self.rod;
        let (l, t0, t1, kappa) = (
            r.length,
            r.cold_temperature,
            r.hot_temperature,
            r.diffusivity(),
        );
        let beta = r.rve.thermal_expansion_coefficient;
        match column {
            0 => Some(rod_temperature(self.probe, time, l, t0, t1, kappa)),
            1 => Some(rod_stress(time, l, t0, t1, kappa, self.stiffness, beta)),
            2 => Some(rod_displacement(self.probe, time, l, t0, t1, kappa, beta)),
            _ => None,
        }
    }

    fn frame(&mut self, state: &Self::State, sink: &mut FrameSink<'_>) -> Result<(), IoError> {
        let p = &state.points;
        for (k, s) in self.stress_xx.iter_mut().enumerate() {
            *s = p.stress[k][0];
        }
        for (k, u) in self.displacement.iter_mut().enumerate() {
            *u = [p.position[k][0] - self.x0[k], 0.0];
        }
        for (k, r) in self.kinetic.iter_mut().zip(&state.material) {
            *k = r.kinetic_ratio;
        }
        let grid = UnstructuredGrid::particles(&p.position)
            .with_point_field(
                "temperature [°C]",
                FieldValues::Scalar(&p.remapped_temperature),
            )
            .with_point_field("stress_xx [Pa]", FieldValues::Scalar(&self.stress_xx))
            .with_point_field("heat_source [W/m^3]", FieldValues::Scalar(&p.heat_source))
            .with_point_field("rve_kinetic_ratio", FieldValues::Scalar(&self.kinetic))
            .with_point_field("velocity [m/s]", FieldValues::Vector2(&p.velocity))
            .with_point_field("displacement [m]", FieldValues::Vector2(&self.displacement));
        sink("material_points", &grid)
    }

    fn summary(&self, state: &Self::State, time: f64) -> Vec<SummaryRow> {
        let mut values = Vec::new();
        self.monitor(state, &mut values);
        self.monitor_columns()
            .into_iter()
            .zip(values)
            .enumerate()
            .map(|(k, (c, measured))| SummaryRow {
                quantity: c.name,
                unit: c.unit,
                measured,
                reference: self.reference(k, time),
            })
            .collect()
    }
}
