//! `kind = "pore_scale_bar"`: the coupled DEM–CFD–heat bar cases of Krzaczek et al. (2023)
//! on `thm_coupling::bar` (A-Fig. 8 packing; A-Sect. 4 cooling, A-Sect. 5 advection, A-Sect. 6
//! cases b and a). In case a (`contraction_free`) each `[time] step` is an output interval
//! that the coupled step covers adaptively (`thm_coupling::pore_scale::PoreScaleStepper::
//! advance`, rule in `[bar.coupling_step]`). This adapter only reads the file, steps `thm_coupling::pore_scale` and writes
//! what it sees; the cases themselves (boundary conditions, properties, how the missing
//! figures are read) live in `thm_coupling::bar`, where a library user reaches them too.

use serde::{Deserialize, Serialize};
use thm_coupling::bar::{
    BarCase, BarEnds, CASE_A_DENSITY_SCALE, EquivalentMedium, PAPER_BAR, bar_params_sized,
    bar_state_sized, case_a_coupling_step, centreline_cells, crack_report, largest_bond_tension,
    mean_mass_flux, scale_sphere_density,
};
use thm_coupling::bar::{WaterAir, water_air};
use thm_coupling::pore_scale::{
    CouplingError, CouplingStepParams, CouplingStepRule, PoreScaleParams, PoreScaleState,
    PoreScaleStepper, PressureForce, StageSeconds,
};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};

use crate::config::TimeControl;
use crate::error::{ConfigError, RunError};
use crate::profiles::Profile;
use crate::scenario::{FrameSink, Scenario};
use crate::summary::SummaryRow;
use crate::units::{Length, Pressure, Quantity, Time};

/// Which case of the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CaseName {
    /// A-Sect. 4.
    Cooling,
    /// A-Sect. 5 (needs `bar.pressure_drop`).
    Advection,
    /// A-Sect. 6 case b.
    ContractionFixed,
    /// A-Sect. 6 case a.
    ContractionFree,
}

fn default_seed() -> u64 {
    1
}

fn default_segments() -> u32 {
    32
}

/// `[bar]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BarParams {
    /// `cooling`, `advection`, `contraction_fixed` or `contraction_free`.
    pub case: CaseName,
    /// Pressure difference bottom − top (advection only).
    #[serde(default)]
    pub pressure_drop: Option<Quantity<Pressure>>,
    /// Seed of the A-Fig. 8 packing.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Points per circle of the mesh (8 … 256).
    #[serde(default = "default_segments")]
    pub segments: u32,
    /// How the bar's ends are made: `cut` (the default: spheres cross the end lines and are
    /// cut by them, so the held temperature acts on solid and pore faces alike; reproduces
    /// A-Sect. 4) or `film` (every sphere inside the bar: the ends hold water, and the solid
    /// feels them through the Nusselt film; see `thm_coupling::bar::BarEnds`).
    #[serde(default)]
    pub ends: BarEnds,
    /// Whether pores holding only liquid may go into tension (default: the case's choice,
    /// true for the single-phase water cases; see `thm_coupling::bar`).
    #[serde(default)]
    pub liquid_tension: Option<bool>,
    /// DEM mass scaling (case a only; default `thm_coupling::bar::CASE_A_DENSITY_SCALE`).
    #[serde(default)]
    pub density_scale: Option<f64>,
    /// Bond tensile strength T (case a only; the cohesion follows at C = 5 T, A-Table 1's
    /// ratio; default A-Table 1's 30 MPa).
    #[serde(default)]
    pub bond_tensile_strength: Option<Quantity<Pressure>>,
    /// Whether the spheres at the ends are held (case a only; default true, A-Sect. 6: "fixed
    /// only at both ends"; `thm_coupling::bar::END_HOLD_DEPTH`). With false no sphere is held
    /// and the bar contracts freely: the run that tells the grips' share in where it cracks.
    #[serde(default)]
    pub held_ends: Option<bool>,
    /// The coupled-step rule (case a only; default `thm_coupling::bar::case_a_coupling_step`).
    #[serde(default)]
    pub coupling_step: Option<CouplingStepSection>,
    /// How the pore pressures push the spheres (case a only): `wall_faces` (A-Eqs. 52–53, the
    /// default) or `cell_corners` (`thm_coupling::pore_scale::pore_forces`).
    #[serde(default)]
    pub pressure_force: Option<PressureForce>,
    /// Snap tolerance of the mesher, × the radius (case a only; in 0 … 1e-3; default the
    /// mesher's 1e-6).
    #[serde(default)]
    pub snap_tolerance: Option<f64>,
    /// T2T faces shorter than this carry at least the zero-stress S2S aperture (case a only;
    /// default 0 m: A-Eq. 9 alone; `thm_vpn_mesh::T2tApertureLaw`).
    #[serde(default)]
    pub narrow_gap_length: Option<Quantity<Length>>,
}

/// `[bar.coupling_step]`: see `thm_coupling::pore_scale::CouplingStepParams`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingStepSection {
    /// Longest coupled step.
    pub max: Quantity<Time>,
    /// Shortest coupled step before the run stops.
    pub min: Quantity<Time>,
    /// Largest sphere displacement per coupled step, as a fraction of the smallest radius.
    pub max_displacement: f64,
    /// Growth factor of the step after an accepted one.
    pub growth: f64,
}

/// Cohesion over tensile strength of A-Table 1 (150 / 30 MPa), kept when T is changed.
const COHESION_RATIO: f64 = 5.0;

/// The evolving state: the coupled state and what the summary needs of the past.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BarRun {
    /// Spheres, mesh, fluid and heat.
    pub coupled: PoreScaleState,
    /// Largest tensile force of an intact bond, sampled at the end of every `[time] step`
    /// before the first bond broke \[N\].
    pub largest_bond_tension: f64,
    /// Largest mean channel speed seen at the end of a `[time] step` \[m/s\].
    pub largest_fluid_speed: f64,
    /// d50 of the initial packing \[m\].
    pub initial_d50: f64,
    /// Coupled steps taken and rejected (case a) over the run.
    pub coupled_steps: [u64; 2],
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[bar]`.
    pub bar: BarParams,
}

/// The coupled stepper of one bar case and the buffers of its frames.
pub struct PoreScaleBar {
    case: BarCase,
    params: PoreScaleParams,
    /// The coupled-step rule of case a.
    rule: Option<CouplingStepRule>,
    stepper: PoreScaleStepper<WaterAir>,
    /// Cells on the vertical centreline, by height.
    centre: Vec<usize>,
    /// The equivalent bar of A-Eq. 63 on the initial state (the profiles' reference).
    equivalent: EquivalentMedium,
    /// Wall seconds of the coupled step's stages in this invocation (case a: with the retakes'
    /// saving and restoring last).
    stage_seconds: (StageSeconds, f64),
    // Frame buffers.
    cell_pressure: Vec<f64>,
    cell_fraction: Vec<f64>,
    cell_liquid_density: Vec<f64>,
    cell_gas_density: Vec<f64>,
    cell_kind: Vec<f64>,
    cell_velocity: Vec<[f64; 3]>,
    channels_of_cell: Vec<f64>,
    sphere_position: Vec<[f64; 3]>,
    sphere_force: Vec<[f64; 3]>,
}

impl std::fmt::Debug for PoreScaleBar {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PoreScaleBar")
            .field("case", &self.case)
            .finish_non_exhaustive()
    }
}

fn physics(step: u64, time: f64, e: CouplingError) -> RunError {
    match e {
        CouplingError::Unphysical {
            quantity,
            place,
            index,
            value,
            step: s,
            ..
        } => RunError::Unstable {
            quantity: quantity.into(),
            place: format!("{place} {index} (coupled step {s})"),
            step,
            time,
            value,
        },
        other => RunError::Physics {
            step,
            time,
            message: other.to_string(),
        },
    }
}

impl PoreScaleBar {
    fn sorted_centre(state: &PoreScaleState) -> Vec<usize> {
        let mesh = &state.mesh.mesh;
        let mut centre = centreline_cells(mesh);
        centre.sort_by(|&a, &b| mesh.cell_centroid[a][1].total_cmp(&mesh.cell_centroid[b][1]));
        centre
    }

    /// The summary of case a: each figure of A-Sect. 6 against the paper's (see
    /// `docs/cases/bar_contraction_free.md` for how each is measured and read).
    fn case_a_summary(&self, run: &BarRun) -> Vec<SummaryRow> {
        let state = &run.coupled;
        let crack = crack_report(state);
        let [t_min, t_max] = range(&state.heat.temperature);
        let [p_min, _] = range(&state.flow.pressure);
        let row = SummaryRow::new;
        let mut rows = vec![
            row("max_temperature", "K", t_max, Some(328.1)),
            row("min_temperature", "K", t_min, None),
            row("lowest_pore_pressure", "Pa", p_min, Some(0.0116e6)),
            row("broken_bonds", "1", crack.broken_bonds as f64, Some(34.0)),
            row(
                "broken_in_tension",
                "1",
                crack.broken_in_tension as f64,
                None,
            ),
            row(
                "broken_bonds_in_macro_crack_band",
                "1",
                crack.broken_in_crack as f64,
                Some(5.0),
            ),
            row("cracks", "1", crack.cracks as f64, None),
            row(
                "crack_height_over_bar_length",
                "1",
                crack.crack_height / thm_coupling::bar::BAR_LENGTH,
                None,
            ),
            row("crack_inclination", "deg", crack.crack_inclination, None),
            row("crack_span_over_width", "1", crack.crack_span, None),
            row(
                "largest_bond_tension_before_breakage",
                "N",
                run.largest_bond_tension,
                Some(29.313),
            ),
            row("d50_initial", "mm", run.initial_d50 * 1e3, Some(6.032)),
            row("d50_final", "mm", crack.d50 * 1e3, Some(5.837)),
            row(
                "temperature_step_across_broken_bonds",
                "K",
                crack.temperature_step,
                Some(20.9),
            ),
            row(
                "liquid_speed_at_end",
                "m/s",
                self.stepper
                    .liquid_speeds(state)
                    .into_iter()
                    .fold(0.0, f64::max),
                Some(0.0057),
            ),
            row("largest_fluid_speed", "m/s", run.largest_fluid_speed, None),
            row("liquid_mass", "kg", state.liquid_mass(), None),
            row("gas_mass", "kg", state.gas_mass(), None),
            row("remeshes", "1", state.remeshes as f64, None),
            row("coupled_steps", "1", run.coupled_steps[0] as f64, None),
            row(
                "rejected_coupled_steps",
                "1",
                run.coupled_steps[1] as f64,
                None,
            ),
        ];
        // Where this invocation's wall time went, stage by stage (every step tried).
        for (stage, seconds) in self.stage_seconds.0.named() {
            rows.push(row(&format!("wall_seconds_{stage}"), "s", seconds, None));
        }
        rows.push(row("wall_seconds_retakes", "s", self.stage_seconds.1, None));
        rows
    }

    /// Temperature of the centreline cell nearest mid-height \[K\].
    fn mid_temperature(&self, state: &PoreScaleState) -> f64 {
        let mesh = &state.mesh.mesh;
        let mid = 0.5 * thm_coupling::bar::BAR_LENGTH;
        self.centre
            .iter()
            .min_by(|&&a, &&b| {
                (mesh.cell_centroid[a][1] - mid)
                    .abs()
                    .total_cmp(&(mesh.cell_centroid[b][1] - mid).abs())
            })
            .map_or(f64::NAN, |&c| state.heat.temperature[c])
    }
}

/// Pore values on the `n` cells of the mesh (`solid` in the cells that are no pore).
fn pores_to_cells(
    network: &thm_vpn_flow::Network,
    n: usize,
    values: &[f64],
    solid: f64,
    out: &mut Vec<f64>,
) {
    out.clear();
    out.resize(n, solid);
    for (&c, &v) in network.pore_cell().iter().zip(values) {
        out[c as usize] = v;
    }
}

/// Linear interpolation through evenly spaced colour `stops` at `x` in [0, 1] (clamped).
fn ramp(stops: &[[u8; 3]], x: f64) -> [u8; 3] {
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let n = stops.len().saturating_sub(1).max(1);
    let k = ((x * n as f64).floor() as usize).min(n - 1);
    let f = x * n as f64 - k as f64;
    let (a, b) = (stops[k], stops[(k + 1).min(stops.len() - 1)]);
    std::array::from_fn(|i| (a[i] as f64 + f * (b[i] as f64 - a[i] as f64)).round() as u8)
}

/// Solid cells by temperature: blue (cold) – pale yellow – red (hot).
const TEMPERATURE_RAMP: [[u8; 3]; 3] = [[49, 54, 149], [255, 255, 191], [165, 0, 38]];
/// Fluid cells by pressure: light grey (low) – purple (high).
const PRESSURE_RAMP: [[u8; 3]; 2] = [[240, 240, 240], [63, 0, 125]];

/// A ramp sampled at the middles of 40 equal bands: the colour bar of a picture.
fn ramp_steps(stops: &[[u8; 3]]) -> Vec<[u8; 3]> {
    const BANDS: u32 = 40;
    (0..BANDS)
        .map(|k| ramp(stops, (f64::from(k) + 0.5) / f64::from(BANDS)))
        .collect()
}

fn range(v: &[f64]) -> [f64; 2] {
    v.iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[a, b], &x| {
            [a.min(x), b.max(x)]
        })
}

impl Scenario for PoreScaleBar {
    const KIND: &'static str = "pore_scale_bar";
    // 2: the state carries each sphere's reference solid area (heat capacity of its mass).
    // 3: the coupled state inside `BarRun` with the run's records.
    const STATE_VERSION: u32 = 4;
    type Params = Params;
    type State = BarRun;

    fn arrays<'s>(&'s self, run: &'s BarRun) -> Vec<crate::arrays::StateArray<'s>> {
        use crate::arrays::StateArray;
        let c = &run.coupled;
        // The spheres' forces are set by the coupling every step (pore pressure), so none of
        // this kind's arrays is writable.
        let mut arrays = crate::arrays::sphere_arrays(&c.dem.particles);
        for a in &mut arrays {
            a.writable = false;
        }
        arrays.extend([
            StateArray::scalar("pore_pressure", "Pa", &c.flow.pressure),
            StateArray::scalar("pore_liquid_fraction", "1", &c.flow.liquid_fraction),
            StateArray::scalar("pore_volume", "m^3", &c.flow.volume),
            StateArray::scalar("pore_temperature", "K", &c.flow.temperature),
            StateArray::scalar("pore_liquid_mass", "kg", &c.flow.liquid_mass),
            StateArray::scalar("pore_gas_mass", "kg", &c.flow.gas_mass),
            StateArray::scalar("cell_temperature", "K", &c.heat.temperature),
        ]);
        arrays
    }

    fn init(p: &Params, _time: &TimeControl) -> Result<(Self, BarRun), ConfigError> {
        let b = &p.bar;
        let case = match (b.case, &b.pressure_drop) {
            (CaseName::Advection, Some(dp)) => BarCase::Advection {
                pressure_drop: dp.positive("bar.pressure_drop")?,
            },
            (CaseName::Advection, None) => {
                return Err(ConfigError::new(
                    "bar.pressure_drop",
                    "required for case = \"advection\" (paper: \"0.9 MPa\" or \"9.9 MPa\")",
                ));
            }
            (_, Some(_)) => {
                return Err(ConfigError::new(
                    "bar.pressure_drop",
                    "only for case = \"advection\"",
                ));
            }
            (CaseName::Cooling, None) => BarCase::Cooling,
            (CaseName::ContractionFixed, None) => BarCase::ContractionFixed,
            (CaseName::ContractionFree, None) => BarCase::ContractionFree,
        };
        let free = case == BarCase::ContractionFree;
        for (key, given) in [
            ("bar.density_scale", b.density_scale.is_some()),
            (
                "bar.bond_tensile_strength",
                b.bond_tensile_strength.is_some(),
            ),
            ("bar.held_ends", b.held_ends.is_some()),
            ("bar.coupling_step", b.coupling_step.is_some()),
            ("bar.pressure_force", b.pressure_force.is_some()),
            ("bar.snap_tolerance", b.snap_tolerance.is_some()),
            ("bar.narrow_gap_length", b.narrow_gap_length.is_some()),
        ] {
            if given && !free {
                return Err(ConfigError::new(
                    key,
                    "only for case = \"contraction_free\" (the spheres of the other cases are held)",
                ));
            }
        }
        if !(8..=256).contains(&b.segments) {
            return Err(ConfigError::new(
                "bar.segments",
                format!("must be in 8 … 256, got {}", b.segments),
            ));
        }
        let mut params = bar_params_sized(case, b.segments, PAPER_BAR, b.ends);
        if let Some(t) = b.liquid_tension {
            params.liquid_tension = t;
        }
        if let Some(f) = b.pressure_force {
            params.pressure_force = f;
        }
        if let Some(t) = b.snap_tolerance {
            if !(0.0..=1e-3).contains(&t) {
                return Err(ConfigError::new(
                    "bar.snap_tolerance",
                    format!("must be in 0 … 1e-3 (× the radius), got {t}"),
                ));
            }
            params.mesh.snap_tolerance = t;
        }
        if let Some(l) = &b.narrow_gap_length {
            params.mesh.narrow_gap_length = l.within("bar.narrow_gap_length", 0.0, 1e-3)?;
        }
        let density_scale = b.density_scale.unwrap_or(CASE_A_DENSITY_SCALE);
        let mut rule = None;
        if free {
            if !(density_scale.is_finite() && (1.0..=1e6).contains(&density_scale)) {
                return Err(ConfigError::new(
                    "bar.density_scale",
                    format!("must be in 1 … 1e6, got {density_scale}"),
                ));
            }
            params.dem.time_step *= density_scale.sqrt();
            if let Some(t) = &b.bond_tensile_strength {
                let t = t.within("bar.bond_tensile_strength", 1e3, 1e10)?;
                params.contact.tensile_strength = t;
                params.contact.cohesion = COHESION_RATIO * t;
            }
            let step = match &b.coupling_step {
                None => case_a_coupling_step(),
                Some(c) => CouplingStepParams {
                    max_step: c.max.positive("bar.coupling_step.max")?,
                    min_step: c.min.positive("bar.coupling_step.min")?,
                    max_displacement: c.max_displacement,
                    growth: c.growth,
                },
            };
            rule = Some(step.validate().map_err(|e| match e {
                CouplingError::Parameter { field, .. } => {
                    let key = match field {
                        "max_step" => "max",
                        "min_step" => "min",
                        other => other,
                    };
                    ConfigError::new(format!("bar.coupling_step.{key}"), e.to_string())
                }
                other => ConfigError::new("bar.coupling_step", other.to_string()),
            })?);
        }
        let config = params
            .validate()
            .map_err(|e| ConfigError::new("bar", e.to_string()))?;
        let mut state = bar_state_sized(case, &config, b.seed, &water_air(), PAPER_BAR, b.ends)
            .map_err(|e| ConfigError::new("bar", e.to_string()))?;
        if free {
            scale_sphere_density(&mut state, density_scale)
                .map_err(|e| ConfigError::new("bar.density_scale", e.to_string()))?;
            if b.held_ends == Some(false) {
                state.dem.particles.fixed.fill(false);
            }
        }
        let stepper = PoreScaleStepper::new(config, water_air(), &state)
            .map_err(|e| ConfigError::new("bar", e.to_string()))?;
        let centre = Self::sorted_centre(&state);
        let equivalent = EquivalentMedium::of(&state, &params.heat);
        Ok((
            Self {
                case,
                params,
                rule,
                stepper,
                centre,
                equivalent,
                stage_seconds: (StageSeconds::default(), 0.0),
                cell_pressure: Vec::new(),
                cell_fraction: Vec::new(),
                cell_liquid_density: Vec::new(),
                cell_gas_density: Vec::new(),
                cell_kind: Vec::new(),
                cell_velocity: Vec::new(),
                channels_of_cell: Vec::new(),
                sphere_position: Vec::new(),
                sphere_force: Vec::new(),
            },
            BarRun {
                initial_d50: crack_report(&state).d50,
                coupled: state,
                largest_bond_tension: 0.0,
                largest_fluid_speed: 0.0,
                coupled_steps: [0, 0],
            },
        ))
    }

    fn restore(&mut self, run: &BarRun) -> Result<(), RunError> {
        let state = &run.coupled;
        let config = self.params.validate().map_err(|e| RunError::Physics {
            step: state.step,
            time: state.time,
            message: e.to_string(),
        })?;
        self.stepper = PoreScaleStepper::new(config, water_air(), state)
            .map_err(|e| physics(state.step, state.time, e))?;
        self.centre = Self::sorted_centre(state);
        Ok(())
    }

    fn step(&mut self, run: &mut BarRun, step: u64, dt: f64) -> Result<(), RunError> {
        let state = &mut run.coupled;
        let time = state.time;
        let remeshes = state.remeshes;
        match &self.rule {
            Some(rule) => {
                let r = self
                    .stepper
                    .advance(state, dt, rule)
                    .map_err(|e| physics(step, time, e))?;
                run.coupled_steps[0] += r.steps;
                run.coupled_steps[1] += r.rejected;
                self.stage_seconds.0.accumulate(&r.stage_seconds);
                self.stage_seconds.1 += r.retake_seconds;
            }
            None => {
                self.stepper
                    .step(state, dt)
                    .map_err(|e| physics(step, time, e))?;
                run.coupled_steps[0] += 1;
            }
        }
        if state.remeshes != remeshes {
            self.centre = Self::sorted_centre(state);
        }
        if state.dem.bond_breaks.is_empty() {
            run.largest_bond_tension = run.largest_bond_tension.max(largest_bond_tension(state));
        }
        let speed = self
            .stepper
            .channel_speeds(state)
            .into_iter()
            .fold(0.0, f64::max);
        run.largest_fluid_speed = run.largest_fluid_speed.max(speed);
        Ok(())
    }

    fn monitor_columns(&self) -> Vec<Column> {
        let mut columns = vec![
            Column::new("max_temperature", "K"),
            Column::new("min_temperature", "K"),
            Column::new("mid_centreline_temperature", "K"),
            Column::new("min_pressure", "Pa"),
            Column::new("max_pressure", "Pa"),
            Column::new("min_liquid_density", "kg/m^3"),
            Column::new("max_liquid_density", "kg/m^3"),
            Column::new("liquid_mass", "kg"),
            Column::new("gas_mass", "kg"),
            Column::new("thermal_energy", "J"),
        ];
        if self.case == BarCase::ContractionFree {
            columns.extend([
                Column::new("broken_bonds", "1"),
                Column::new("largest_bond_tension_before_breakage", "N"),
                Column::new("largest_fluid_speed", "m/s"),
                Column::new("d50", "m"),
            ]);
        }
        columns
    }

    fn monitor(&self, run: &BarRun, values: &mut Vec<f64>) {
        let state = &run.coupled;
        let [t_min, t_max] = range(&state.heat.temperature);
        let [p_min, p_max] = range(&state.flow.pressure);
        let [r_min, r_max] = range(&state.flow.liquid_density);
        values.extend([
            t_max,
            t_min,
            self.mid_temperature(state),
            p_min,
            p_max,
            r_min,
            r_max,
            state.liquid_mass(),
            state.gas_mass(),
            state.thermal_energy(&self.params.heat),
        ]);
        if self.case == BarCase::ContractionFree {
            values.extend([
                state.dem.bond_breaks.len() as f64,
                run.largest_bond_tension,
                run.largest_fluid_speed,
                crack_report(state).d50,
            ]);
        }
    }

    fn frame(&mut self, run: &BarRun, sink: &mut FrameSink<'_>) -> Result<(), IoError> {
        let state = &run.coupled;
        let mesh = &state.mesh.mesh;
        let n = mesh.n_cells();
        let flow = &state.flow;
        let network = self.stepper.network();
        pores_to_cells(network, n, &flow.pressure, 0.0, &mut self.cell_pressure);
        pores_to_cells(
            network,
            n,
            &flow.liquid_fraction,
            0.0,
            &mut self.cell_fraction,
        );
        pores_to_cells(
            network,
            n,
            &flow.liquid_density,
            0.0,
            &mut self.cell_liquid_density,
        );
        pores_to_cells(
            network,
            n,
            &flow.gas_density,
            0.0,
            &mut self.cell_gas_density,
        );
        // Velocity of a fluid cell: the mean over its channels of the channel's speed over the
        // last step along the channel, signed by the flow direction (zero before the first
        // step).
        self.cell_velocity.clear();
        self.cell_velocity.resize(n, [0.0; 3]);
        self.channels_of_cell.clear();
        self.channels_of_cell.resize(n, 0.0);
        let parts = network.parts();
        let mass_rate = &self.stepper.heat_input().channel_mass_flux;
        for (c, speed) in self.stepper.channel_speeds(state).into_iter().enumerate() {
            let e = parts.channel_direction.get(c).copied().unwrap_or([0.0; 2]);
            let sign = if mass_rate.get(c).copied().unwrap_or(0.0) < 0.0 {
                -1.0
            } else {
                1.0
            };
            for p in parts.channel_pores[c] {
                let cell = network.pore_cell()[p as usize] as usize;
                self.cell_velocity[cell][0] += sign * speed * e[0];
                self.cell_velocity[cell][1] += sign * speed * e[1];
                self.channels_of_cell[cell] += 1.0;
            }
        }
        for (v, k) in self.cell_velocity.iter_mut().zip(&self.channels_of_cell) {
            if *k > 0.0 {
                v[0] /= k;
                v[1] /= k;
            }
        }
        self.cell_kind.clear();
        self.cell_kind.extend(
            mesh.cell_kind
                .iter()
                .map(|k| if k.is_fluid() { 0.0 } else { 1.0 }),
        );
        let cells = UnstructuredGrid::triangles(&mesh.vertices, &mesh.cell_vertices)
            .with_cell_field(
                "temperature [K]",
                FieldValues::Scalar(&state.heat.temperature),
            )
            .with_cell_field(
                "pressure [Pa] (fluid cells)",
                FieldValues::Scalar(&self.cell_pressure),
            )
            .with_cell_field(
                "liquid_fraction [1]",
                FieldValues::Scalar(&self.cell_fraction),
            )
            .with_cell_field(
                "liquid_density [kg/m^3]",
                FieldValues::Scalar(&self.cell_liquid_density),
            )
            .with_cell_field(
                "gas_density [kg/m^3]",
                FieldValues::Scalar(&self.cell_gas_density),
            )
            .with_cell_field("solid [1]", FieldValues::Scalar(&self.cell_kind))
            .with_cell_field(
                "velocity [m/s] (mean of the cell's channels)",
                FieldValues::Vector3(&self.cell_velocity),
            );
        sink("cells", &cells)?;
        let p = &state.dem.particles;
        self.sphere_position.clear();
        self.sphere_position
            .extend(p.position.iter().map(|x| [x.x, x.y, x.z]));
        self.sphere_force.clear();
        // The force of the last fluid-forces stage (A-Eqs. 52–54), also with a held skeleton.
        // (zero before the first step).
        self.sphere_force
            .extend(self.stepper.fluid_force().iter().map(|f| [f[0], f[1], 0.0]));
        self.sphere_force.resize(p.position.len(), [0.0; 3]);
        let spheres = UnstructuredGrid::particles(&self.sphere_position)
            .with_point_field("radius [m]", FieldValues::Scalar(&p.radius))
            .with_point_field("temperature [K]", FieldValues::Scalar(&p.temperature))
            .with_point_field("fluid_force [N]", FieldValues::Vector3(&self.sphere_force));
        sink("spheres", &spheres)
    }

    fn summary(&self, run: &BarRun, _time: f64) -> Vec<SummaryRow> {
        if self.case == BarCase::ContractionFree {
            return self.case_a_summary(run);
        }
        let mut values = Vec::new();
        self.monitor(run, &mut values);
        // The paper's figures at the end of its run, where they are stated.
        let paper = |k: usize| match (self.case, k) {
            (BarCase::ContractionFixed, 0) => Some(333.3),
            (BarCase::ContractionFixed, 4) => Some(73.0e3),
            (BarCase::Cooling, 5) => Some(1000.02),
            (BarCase::Cooling, 6) => Some(1014.28),
            _ => None,
        };
        self.monitor_columns()
            .into_iter()
            .zip(values)
            .enumerate()
            .map(|(k, (c, measured))| SummaryRow {
                quantity: c.name,
                unit: c.unit,
                measured,
                reference: paper(k),
            })
            .collect()
    }

    /// A-Figs. 19–22 in one picture per frame: solid cells by temperature between the ends'
    /// and the initial temperature, fluid cells by pressure over the frame's range, broken
    /// bonds as black segments between the sphere centres.
    fn pictures(&self, run: &BarRun, time: f64) -> Vec<(String, thm_io::Picture)> {
        let state = &run.coupled;
        let mesh = &state.mesh.mesh;
        let network = self.stepper.network();
        let mut pore_of_cell = vec![None; mesh.n_cells()];
        for (p, &c) in network.pore_cell().iter().enumerate() {
            pore_of_cell[c as usize] = Some(p);
        }
        let [p_lo, p_hi] = range(&state.flow.pressure);
        let (t_lo, t_hi) = (self.case.end_temperature(), self.case.initial_temperature());
        let scale = |v: f64, lo: f64, hi: f64| if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
        let polygons = (0..mesh.n_cells())
            .map(|c| {
                let fill = match pore_of_cell[c] {
                    Some(p) => ramp(&PRESSURE_RAMP, scale(state.flow.pressure[p], p_lo, p_hi)),
                    None => ramp(
                        &TEMPERATURE_RAMP,
                        scale(state.heat.temperature[c], t_lo, t_hi),
                    ),
                };
                thm_io::FilledPolygon {
                    corners: mesh.cell_vertices[c]
                        .iter()
                        .map(|&v| mesh.vertices[v as usize])
                        .collect(),
                    fill,
                    outline: None,
                }
            })
            .collect();
        let x = &state.dem.particles.position;
        let segments = state
            .dem
            .bond_breaks
            .iter()
            .map(|b| thm_io::Segment {
                ends: [b.a, b.b].map(|i| [x[i as usize].x, x[i as usize].y]),
                colour: [0, 0, 0],
            })
            .collect();
        vec![(
            "state".into(),
            thm_io::Picture {
                title: format!(
                    "t = {time:.3} s, p {:.0}-{:.0} kPa, {} broken",
                    p_lo / 1e3,
                    p_hi / 1e3,
                    state.dem.bond_breaks.len()
                ),
                width_px: 360,
                background: [255, 255, 255],
                polygons,
                segments,
                colour_bars: vec![
                    thm_io::ColourBar {
                        label: "solid temperature [K]".into(),
                        range: [t_lo, t_hi],
                        colours: ramp_steps(&TEMPERATURE_RAMP),
                    },
                    thm_io::ColourBar {
                        label: "pore pressure [kPa]".into(),
                        range: [p_lo / 1e3, p_hi / 1e3],
                        colours: ramp_steps(&PRESSURE_RAMP),
                    },
                ],
                length_scale: Some(0.01),
            },
        )]
    }

    fn profiles(&self, run: &BarRun, time: f64) -> Vec<Profile> {
        let state = &run.coupled;
        let mesh = &state.mesh.mesh;
        let y: Vec<f64> = self
            .centre
            .iter()
            .map(|&c| mesh.cell_centroid[c][1])
            .collect();
        let reference = match self.case {
            BarCase::Cooling => {
                Some(("equivalent bar of A-Eq. 63 (A-Eqs. 60-61)".to_string(), 0.0))
            }
            BarCase::Advection { .. } => Some((
                "equivalent bar of A-Eq. 63 with advection at the mean flux so far".to_string(),
                mean_mass_flux(state),
            )),
            BarCase::ContractionFixed | BarCase::ContractionFree => None,
        }
        // At t = 0 the reference is the initial state itself.
        .filter(|_| time > 0.0)
        .map(|(label, q_m)| {
            let values = y
                .iter()
                .map(|&yy| self.equivalent.temperature(self.case, yy, time, q_m))
                .collect();
            (label, values)
        });
        // The centreline x = W/2: every cell it crosses, and the fluid cells among them.
        let temperature = Profile {
            name: "centreline_temperature".into(),
            x_label: "y [m]".into(),
            y_label: "T [K]".into(),
            x: y,
            y: self
                .centre
                .iter()
                .map(|&c| state.heat.temperature[c])
                .collect(),
            reference,
        };
        let mut cell_pressure = Vec::new();
        pores_to_cells(
            self.stepper.network(),
            mesh.n_cells(),
            &state.flow.pressure,
            f64::NAN,
            &mut cell_pressure,
        );
        let (xs, ps): (Vec<f64>, Vec<f64>) = self
            .centre
            .iter()
            .filter(|&&c| mesh.cell_kind[c].is_fluid())
            .map(|&c| (mesh.cell_centroid[c][1], cell_pressure[c]))
            .unzip();
        let pressure = Profile {
            name: "centreline_pore_pressure".into(),
            x_label: "y [m]".into(),
            y_label: "p [Pa]".into(),
            x: xs,
            y: ps,
            reference: None,
        };
        vec![temperature, pressure]
    }
}
