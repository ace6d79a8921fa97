//! `kind = "lumped_cooling"`: a lattice of spheres cooling in a fluid (Newton's law, lumped
//! capacitance). It exercises the whole `thm run` machinery with a model whose exact solution
//! is known, and is the template for physics adapters.
//!
//! Each sphere `i` (radius `rᵢ`, density ρ, specific heat c) exchanges heat with a fluid at
//! `T∞` through a film coefficient h:
//!
//! ```text
//! mᵢ c dTᵢ/dt = −h Aᵢ (Tᵢ − T∞),   τᵢ = mᵢ c / (h Aᵢ) = ρ c rᵢ / (3 h)
//! Tᵢ(t) = T∞ + (T₀ − T∞) exp(−t/τᵢ)
//! ```
//!
//! Valid while the Biot number `h rᵢ / (3 k_s)` is small (uniform sphere temperature); the
//! solid conductivity does not enter. The step applies the exact one-step factor
//! `exp(−Δt/τᵢ)`, so the run matches the solution to round-off for any Δt; the heat released,
//! `Σ mᵢ c (T₀ − Tᵢ)`, is monitored against its closed form.

use serde::{Deserialize, Serialize};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};

use crate::config::TimeControl;
use crate::error::{ConfigError, RunError};
use crate::scenario::{FrameSink, Scenario};
use crate::summary::SummaryRow;
use crate::units::{Density, HeatTransferCoefficient, Length, Quantity, SpecificHeat, Temperature};

/// `[particles]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleParams {
    /// Spheres along x and y.
    pub lattice: [u64; 2],
    /// Centre-to-centre distance.
    pub spacing: Quantity<Length>,
    /// Mean radius.
    pub radius: Quantity<Length>,
    /// Radii spread linearly over `radius·(1 ± radius_spread/2)` (0 ≤ spread < 1).
    #[serde(default)]
    pub radius_spread: f64,
    /// Solid density.
    pub density: Quantity<Density>,
    /// Solid specific heat.
    pub specific_heat: Quantity<SpecificHeat>,
    /// Uniform initial temperature.
    pub initial_temperature: Quantity<Temperature>,
}

/// `[fluid]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidParams {
    /// Far-field fluid temperature.
    pub temperature: Quantity<Temperature>,
    /// Film heat-transfer coefficient.
    pub heat_transfer_coefficient: Quantity<HeatTransferCoefficient>,
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[particles]`.
    pub particles: ParticleParams,
    /// `[fluid]`.
    pub fluid: FluidParams,
}

/// The evolving state: sphere temperatures \[K\].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Temperature of each sphere \[K\].
    pub temperature: Vec<f64>,
}

/// Largest number of spheres.
const MAX_SPHERES: u64 = 10_000_000;

/// The stepper: geometry, validated parameters and per-sphere constants.
#[derive(Debug)]
pub struct LumpedCooling {
    position: Vec<[f64; 3]>,
    radius: Vec<f64>,
    /// `mᵢ c` \[J/K\].
    heat_capacity: Vec<f64>,
    /// `τᵢ` \[s\].
    time_constant: Vec<f64>,
    /// `exp(−Δt/τᵢ)`.
    step_factor: Vec<f64>,
    fluid_temperature: f64,
    initial_temperature: f64,
    film_coefficient: f64,
    /// Scratch for frames: heat flow to the fluid \[W\].
    heat_flow: Vec<f64>,
}

impl LumpedCooling {
    fn exact_temperature(&self, i: usize, t: f64) -> f64 {
        let (t0, tf) = (self.initial_temperature, self.fluid_temperature);
        tf + (t0 - tf) * (-t / self.time_constant[i]).exp()
    }

    fn heat_released(&self, temperature: impl Iterator<Item = f64>) -> f64 {
        self.heat_capacity
            .iter()
            .zip(temperature)
            .map(|(c, t)| c * (self.initial_temperature - t))
            .sum()
    }

    fn extreme_indices(&self) -> (usize, usize) {
        // Smallest sphere cools fastest (min T), largest slowest (max T).
        let by_radius = |a: &usize, b: &usize| self.radius[*a].total_cmp(&self.radius[*b]);
        let idx = 0..self.radius.len();
        (
            idx.clone().min_by(by_radius).unwrap_or(0),
            idx.max_by(by_radius).unwrap_or(0),
        )
    }
}

impl Scenario for LumpedCooling {
    const KIND: &'static str = "lumped_cooling";
    const STATE_VERSION: u32 = 1;
    type Params = Params;
    type State = State;

    fn arrays<'s>(&'s self, state: &'s State) -> Vec<crate::arrays::StateArray<'s>> {
        use crate::arrays::StateArray;
        vec![
            StateArray::rows("sphere_position", "m", &self.position),
            StateArray::scalar("sphere_radius", "m", &self.radius),
            StateArray::scalar("sphere_temperature", "K", &state.temperature).writable(),
        ]
    }

    fn set_array(&mut self, state: &mut State, name: &str, values: &[f64]) -> Result<(), RunError> {
        if name != "sphere_temperature" {
            return Err(crate::arrays::not_writable(name, &["sphere_temperature"]));
        }
        crate::arrays::check_input(
            name,
            values,
            state.temperature.len(),
            (0.0, crate::arrays::MAX_TEMPERATURE),
            true,
            "K",
        )?;
        state.temperature.copy_from_slice(values);
        Ok(())
    }

    fn init(p: &Params, time: &TimeControl) -> Result<(Self, State), ConfigError> {
        let pp = &p.particles;
        let [nx, ny] = pp.lattice;
        if nx == 0 || ny == 0 || nx.saturating_mul(ny) > MAX_SPHERES {
            return Err(ConfigError::new(
                "particles.lattice",
                format!(
                    "must be [nx, ny] with nx, ny ≥ 1 and nx·ny ≤ {MAX_SPHERES}, got [{nx}, {ny}]"
                ),
            ));
        }
        if !(0.0..1.0).contains(&pp.radius_spread) {
            return Err(ConfigError::new(
                "particles.radius_spread",
                format!("must be in [0, 1), got {}", pp.radius_spread),
            ));
        }
        let spacing = pp.spacing.positive("particles.spacing")?;
        let r_mean = pp.radius.positive("particles.radius")?;
        let r_max = r_mean * (1.0 + pp.radius_spread / 2.0);
        if 2.0 * r_max > spacing {
            return Err(ConfigError::new(
                "particles.radius",
                format!(
                    "spheres overlap: largest diameter {} m exceeds particles.spacing {spacing} m",
                    2.0 * r_max
                ),
            ));
        }
        let rho = pp.density.positive("particles.density")?;
        let c = pp.specific_heat.positive("particles.specific_heat")?;
        let t0 = pp
            .initial_temperature
            .positive("particles.initial_temperature")?;
        let tf = p.fluid.temperature.positive("fluid.temperature")?;
        let h = p
            .fluid
            .heat_transfer_coefficient
            .positive("fluid.heat_transfer_coefficient")?;

        let n = (nx * ny) as usize;
        let mut position = Vec::with_capacity(n);
        let mut radius = Vec::with_capacity(n);
        for j in 0..ny {
            for i in 0..nx {
                let k = (j * nx + i) as f64;
                let frac = if n > 1 { k / (n - 1) as f64 - 0.5 } else { 0.0 };
                position.push([i as f64 * spacing, j as f64 * spacing, 0.0]);
                radius.push(r_mean * (1.0 + pp.radius_spread * frac));
            }
        }
        let heat_capacity: Vec<f64> = radius
            .iter()
            .map(|r| rho * 4.0 / 3.0 * std::f64::consts::PI * r * r * r * c)
            .collect();
        let time_constant: Vec<f64> = radius.iter().map(|r| rho * c * r / (3.0 * h)).collect();
        let step_factor = time_constant
            .iter()
            .map(|tau| (-time.dt / tau).exp())
            .collect();
        Ok((
            Self {
                position,
                radius,
                heat_capacity,
                time_constant,
                step_factor,
                fluid_temperature: tf,
                initial_temperature: t0,
                film_coefficient: h,
                heat_flow: vec![0.0; n],
            },
            State {
                temperature: vec![t0; n],
            },
        ))
    }

    fn step(&mut self, state: &mut State, step: u64, dt: f64) -> Result<(), RunError> {
        let tf = self.fluid_temperature;
        for (t, f) in state.temperature.iter_mut().zip(&self.step_factor) {
            *t = tf + (*t - tf) * f;
        }
        if let Some(i) = state
            .temperature
            .iter()
            .position(|t| !(t.is_finite() && *t > 0.0))
        {
            return Err(RunError::Unstable {
                quantity: "temperature [K]".into(),
                place: format!("sphere {i}"),
                step,
                time: step as f64 * dt,
                value: state.temperature[i],
            });
        }
        Ok(())
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("mean_temperature", "K"),
            Column::new("min_temperature", "K"),
            Column::new("max_temperature", "K"),
            Column::new("heat_released", "J"),
        ]
    }

    fn monitor(&self, state: &State, values: &mut Vec<f64>) {
        let t = &state.temperature;
        let mean = t.iter().sum::<f64>() / t.len() as f64;
        let min = t.iter().copied().fold(f64::INFINITY, f64::min);
        let max = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        values.extend([mean, min, max, self.heat_released(t.iter().copied())]);
    }

    fn reference(&self, column: usize, time: f64) -> Option<f64> {
        let n = self.radius.len();
        let (small, large) = self.extreme_indices();
        match column {
            0 => Some((0..n).map(|i| self.exact_temperature(i, time)).sum::<f64>() / n as f64),
            1 => Some(self.exact_temperature(small, time)),
            2 => Some(self.exact_temperature(large, time)),
            3 => Some(self.heat_released((0..n).map(|i| self.exact_temperature(i, time)))),
            _ => None,
        }
    }

    fn frame(&mut self, state: &State, sink: &mut FrameSink<'_>) -> Result<(), IoError> {
        let (h, tf) = (self.film_coefficient, self.fluid_temperature);
        for ((q, r), t) in self
            .heat_flow
            .iter_mut()
            .zip(&self.radius)
            .zip(&state.temperature)
        {
            *q = h * 4.0 * std::f64::consts::PI * r * r * (t - tf);
        }
        let grid = UnstructuredGrid::particles(&self.position)
            .with_point_field("radius [m]", FieldValues::Scalar(&self.radius))
            .with_point_field("temperature [K]", FieldValues::Scalar(&state.temperature))
            .with_point_field("heat_flow [W]", FieldValues::Scalar(&self.heat_flow));
        sink("particles", &grid)
    }

    fn summary(&self, state: &State, time: f64) -> Vec<SummaryRow> {
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
