//! `kind = "mpm_semi_infinite_bar"`: the thermo-elastic bar of B-Sect. 5.1.1 (Zhao et al.
//! 2022) on `thm-mpm`, as built by `thm_mpm::setups::semi_infinite_bar`.
//!
//! A 6 m bar of unit density, specific heat, conductivity and Young's modulus (ν = 0,
//! β = 10⁻⁶ 1/K), free at both ends and held in uniaxial strain, is heated at x = 0 from 0 to
//! 100 K at t = 0. The temperature at the probe is compared with B-Eq. 52,
//! `T(x, t) = T₁ erfc(x / (2√(κ t)))`, κ = k/(ρ c) = 1 m²/s; stress and displacement at the
//! probe are monitored (the scenario's verification case compares them with a converged 1D
//! finite-difference solution). The stepper and material are rebuilt from the parameters on
//! resume; the checkpoint holds the `MpmState` (points, material history, time, step).

use serde::{Deserialize, Serialize};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};
use thm_mpm::{LinearThermoElastic, Mpm, MpmState};

use crate::config::TimeControl;
use crate::error::{ConfigError, RunError};
use crate::scenario::{FrameSink, Scenario};
use crate::summary::SummaryRow;
use crate::units::{Length, Quantity};

/// Length of the bar of B-Sect. 5.1.1 \[m\].
const BAR_LENGTH: f64 = 6.0;
/// Heating step at x = 0 \[K\].
const HEATING: f64 = 100.0;
/// Thermal diffusivity k/(ρ c) of the bar \[m²/s\].
const DIFFUSIVITY: f64 = 1.0;

/// `[bar]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BarParams {
    /// Cells (and material points) along the 6 m bar.
    pub cells: usize,
    /// Position of the monitored probe along the bar.
    pub probe: Quantity<Length>,
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[bar]`.
    pub bar: BarParams,
}

/// The stepper: MPM scratch, the material, and the reference positions of the points.
#[derive(Debug)]
pub struct SemiInfiniteBar {
    mpm: Mpm,
    material: LinearThermoElastic,
    /// Cell size \[m\].
    h: f64,
    probe: f64,
    /// Initial x of each point (displacement = x − x₀) \[m\].
    x0: Vec<f64>,
    /// Scratch for frames.
    stress_xx: Vec<f64>,
    displacement: Vec<[f64; 2]>,
}

impl SemiInfiniteBar {
    /// Linear interpolation along the bar of a per-point value at the probe (points in one
    /// row at reference positions (i + ½) h).
    fn at_probe(&self, value: impl Fn(usize) -> f64) -> f64 {
        let n = self.x0.len();
        let s = self.probe / self.h - 0.5;
        let i = (s.floor().max(0.0) as usize).min(n.saturating_sub(2));
        let f = s - i as f64;
        (1.0 - f) * value(i) + f * value(i + 1)
    }
}

impl Scenario for SemiInfiniteBar {
    const KIND: &'static str = "mpm_semi_infinite_bar";
    const STATE_VERSION: u32 = 1;
    type Params = Params;
    type State = MpmState<()>;

    fn arrays<'s>(&'s self, state: &'s Self::State) -> Vec<crate::arrays::StateArray<'s>> {
        crate::arrays::point_arrays(&state.points, &crate::arrays::POINTS)
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
        let cells = p.bar.cells;
        if !(2..=100_000).contains(&cells) {
            return Err(ConfigError::new(
                "bar.cells",
                format!("must be in [2, 100000], got {cells}"),
            ));
        }
        let h = BAR_LENGTH / cells as f64;
        let probe = p.bar.probe.si();
        // Within the row of point centres, so the interpolation has two neighbours.
        if !(probe.is_finite() && probe >= 0.5 * h && probe <= BAR_LENGTH - 0.5 * h) {
            return Err(ConfigError::new(
                "bar.probe",
                format!(
                    "must be in [{} m, {} m] (between the first and last point), got {} {}",
                    0.5 * h,
                    BAR_LENGTH - 0.5 * h,
                    probe,
                    "m"
                ),
            ));
        }
        let model = thm_mpm::setups::semi_infinite_bar(cells)
            .map_err(|e| ConfigError::new("bar", e.to_string()))?;
        let limit = model
            .mpm
            .time_step_limits(&model.state, &model.material)
            .min();
        if time.dt > limit {
            return Err(ConfigError::new(
                "time.step",
                format!(
                    "must be ≤ {limit:e} s (B-Eqs. 30–31 stability limit on {cells} cells), got {} s",
                    time.dt
                ),
            ));
        }
        let n = model.state.points.len();
        let x0 = model.state.points.position.iter().map(|x| x[0]).collect();
        Ok((
            Self {
                mpm: model.mpm,
                material: model.material,
                h,
                probe,
                x0,
                stress_xx: vec![0.0; n],
                displacement: vec![[0.0; 2]; n],
            },
            model.state,
        ))
    }

    fn step(&mut self, state: &mut Self::State, step: u64, dt: f64) -> Result<(), RunError> {
        let time = state.time;
        self.mpm
            .step(state, &self.material, dt)
            .map_err(|e| RunError::Physics {
                step,
                time,
                message: e.to_string(),
            })
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("temperature_at_probe", "K"),
            Column::new("stress_xx_at_probe", "Pa"),
            Column::new("displacement_at_probe", "m"),
        ]
    }

    fn monitor(&self, state: &Self::State, values: &mut Vec<f64>) {
        let p = &state.points;
        values.extend([
            self.at_probe(|i| p.temperature[i]),
            self.at_probe(|i| p.stress[i][0]),
            self.at_probe(|i| p.position[i][0] - self.x0[i]),
        ]);
    }

    fn reference(&self, column: usize, time: f64) -> Option<f64> {
        (column == 0).then(|| {
            thm_mpm::analytical::semi_infinite_temperature(
                self.probe,
                time,
                DIFFUSIVITY,
                0.0,
                HEATING,
            )
        })
    }

    fn frame(&mut self, state: &Self::State, sink: &mut FrameSink<'_>) -> Result<(), IoError> {
        let p = &state.points;
        for (k, s) in self.stress_xx.iter_mut().enumerate() {
            *s = p.stress[k][0];
        }
        for (k, u) in self.displacement.iter_mut().enumerate() {
            *u = [p.position[k][0] - self.x0[k], 0.0];
        }
        let grid = UnstructuredGrid::particles(&p.position)
            .with_point_field("temperature [K]", FieldValues::Scalar(&p.temperature))
            .with_point_field("stress_xx [Pa]", FieldValues::Scalar(&self.stress_xx))
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
