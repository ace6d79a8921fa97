//! `kind = "mpm_dem_column"`: the melting-induced column collapse of B-Sect. 5.3.3 of Zhao
//! et al. (2022) on the MPM×DEM scheme of `thm-coupling` (`thm_coupling::multiscale::column`).
//!
//! A 2 m × 2 m column of `cells × cells` square cells with `points_per_cell²` points each,
//! every point carrying an RVE of `disks` disks consolidated to 10 kPa, settles under gravity
//! between two plates for `settle_time`; then the right plate is removed, the left one is held
//! at `plate_temperature` and bonds of strength `bond_strength` (β_b of B-Eq. 38) are installed,
//! melting by B-Eq. 40 when `melting = true`. The run ends at `time.end` (settling included;
//! the paper: 3 s after the release without bonds, 20 s with). Monitored: time after the
//! release, `E_p/E_p0`, `E_k/E_p0` (B-Fig. 20), corner displacement, intact and broken bonds
//! on the heated half and the other, the heat balance (stored, plate, sources, residual),
//! largest temperature, mean rise of the heated half, runout. The profile `energies` is
//! `E_p/E_p0` and `E_k/E_p0` against the time after the release. The checkpoint holds the
//! `MpmState` with every RVE, the running sums and the energy samples; the steppers (grid,
//! plates, consolidated template) are rebuilt from the parameters on resume.

use serde::{Deserialize, Serialize};
use thm_coupling::multiscale::column::{
    Column as ColumnCase, ColumnModel, ColumnRecord, ColumnTest, ColumnTotals,
};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};

use super::multiscale::{
    Multiscale, MultiscaleKind, check_time_step, kind_state, rise_and_pressure, time_after_settling,
};
use crate::config::{TimeControl, check_count, check_range};
use crate::error::ConfigError;
use crate::profiles::Profile;
use crate::rve_frames::PointRveFields;
use crate::scenario::FrameSink;
use crate::summary::SummaryRow;
use crate::units::{Quantity, Temperature, Time};

/// `[column]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnParams {
    /// β_b of B-Eq. 38 at the initial temperature, in [0, 10] (the paper: 0, 0.02, 0.1;
    /// 0 = no bonds).
    pub bond_strength: f64,
    /// Whether the bonds melt by B-Eq. 40.
    pub melting: bool,
    /// T_s of B-Eq. 40: the temperature rise (K) at which a bond has lost its strength, in
    /// (0, 1e4] (the paper: 10).
    #[serde(default = "ten")]
    pub melting_threshold: f64,
    /// Cells along each side of the 2 m column, in [1, 200] (the paper: 20).
    pub cells: usize,
    /// Points per cell along each direction, in [1, 4] (the paper: 2).
    pub points_per_cell: usize,
    /// Disks per RVE, in [10, 10000] (the paper: 400).
    pub disks: usize,
    /// Seed of the packing.
    #[serde(default = "one")]
    pub seed: u64,
    /// Density scaling of the RVE disks (DEM time rule), in [1, 1e6].
    pub density_scaling: f64,
    /// Settling time under gravity before the release, shorter than `time.end`.
    pub settle_time: Quantity<Time>,
    /// Initial uniform temperature (not stated in the paper; 0 °C).
    pub initial_temperature: Quantity<Temperature>,
    /// Temperature of the heating plate (the paper: 50 °C).
    pub plate_temperature: Quantity<Temperature>,
}

fn one() -> u64 {
    1
}

fn ten() -> f64 {
    10.0
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[column]`.
    pub column: ColumnParams,
}

kind_state! {
    /// What a checkpoint holds.
    State for ColumnCase {
        /// `(time after release, E_p/E_p0, E_k/E_p0)` every
        /// [`SAMPLE_EVERY`](super::multiscale::SAMPLE_EVERY) steps after the release.
        energies: Vec<[f64; 3]>
    }
}

/// The kind: the column collapse on the multiscale skeleton.
pub type MpmDemColumn = Multiscale<ColumnOutputs>;

/// What the kind keeps for its outputs: frame scratch.
#[derive(Debug)]
pub struct ColumnOutputs {
    rise: Vec<f64>,
    pressure: Vec<f64>,
    bonds: Vec<f64>,
    rve_fields: PointRveFields,
}

impl MultiscaleKind for ColumnOutputs {
    const KIND: &'static str = "mpm_dem_column";
    // 2: RvePoint carries its intact bond count.
    const STATE_VERSION: u32 = 2;
    type Params = Params;
    type Case = ColumnCase;
    type State = State;

    fn init(p: &Params, time: &TimeControl) -> Result<(ColumnModel, Self), ConfigError> {
        let c = &p.column;
        check_range("column.bond_strength", c.bond_strength, 0.0, 10.0)?;
        check_range("column.melting_threshold", c.melting_threshold, 1e-9, 1e4)?;
        check_count("column.cells", c.cells, 1, 200)?;
        check_count("column.points_per_cell", c.points_per_cell, 1, 4)?;
        check_count("column.disks", c.disks, 10, 10_000)?;
        check_range("column.density_scaling", c.density_scaling, 1.0, 1e6)?;
        check_range(
            "column.initial_temperature",
            c.initial_temperature.si(),
            1.0,
            1e4,
        )?;
        check_range(
            "column.plate_temperature",
            c.plate_temperature.si(),
            1.0,
            1e4,
        )?;
        let end = time.dt * time.n_steps as f64;
        let settle = c.settle_time.si();
        check_range("column.settle_time", settle, 0.0, end)?;
        let mut t = ColumnTest::reduced(
            c.bond_strength,
            c.melting,
            c.cells,
            c.disks,
            time.dt,
            c.density_scaling,
        );
        t.points_per_cell = c.points_per_cell;
        t.melting_threshold = c.melting_threshold;
        t.seed = c.seed;
        t.initial_temperature = c.initial_temperature.si() - 273.15;
        t.plate_temperature = c.plate_temperature.si() - 273.15;
        t.settle_time = settle;
        t.collapse_time = time_after_settling(t.settle_steps(), time)?;
        let model = ColumnModel::new(&t).map_err(|e| ConfigError::new("column", e.to_string()))?;
        check_time_step(&model, time)?;
        let n = model.state.points.len();
        let outputs = Self {
            rise: vec![0.0; n],
            pressure: vec![0.0; n],
            bonds: vec![0.0; n],
            rve_fields: PointRveFields::default(),
        };
        Ok((model, outputs))
    }

    fn sample(r: &ColumnRecord, totals: &ColumnTotals) -> Option<[f64; 3]> {
        totals
            .released
            .then_some([r.time_after_release, r.potential_ratio, r.kinetic_ratio])
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("time_after_release", "s"),
            Column::new("potential_energy_ratio", "-"),
            Column::new("kinetic_energy_ratio", "-"),
            Column::new("potential_energy", "J/m"),
            Column::new("kinetic_energy", "J/m"),
            Column::new("corner_displacement", "m"),
            Column::new("bonds_intact_heated_half", "-"),
            Column::new("bonds_intact_other_half", "-"),
            Column::new("bonds_broken_heated_half", "-"),
            Column::new("bonds_broken_other_half", "-"),
            Column::new("stored_heat", "J/m"),
            Column::new("plate_heat", "J/m"),
            Column::new("source_heat", "J/m"),
            Column::new("heat_balance_residual", "-"),
            Column::new("largest_temperature", "degC"),
            Column::new("mean_rise_heated_half", "K"),
            Column::new("runout", "m"),
        ]
    }

    fn monitor(&self, r: &ColumnRecord, _state: &State, values: &mut Vec<f64>) {
        values.extend([
            r.time_after_release,
            r.potential_ratio,
            r.kinetic_ratio,
            r.potential_energy,
            r.kinetic_energy,
            r.corner_displacement,
            r.bonds_intact_heated as f64,
            r.bonds_intact_other as f64,
            r.bonds_broken_heated as f64,
            r.bonds_broken_other as f64,
            r.stored_heat,
            r.plate_heat,
            r.source_heat,
            r.heat_balance_residual,
            r.max_temperature,
            r.mean_rise_heated,
            r.runout,
        ]);
    }

    fn frame(
        &mut self,
        model: &ColumnModel,
        state: &State,
        sink: &mut FrameSink<'_>,
    ) -> Result<(), IoError> {
        let p = &state.mpm.points;
        let t0 = model.case.test.initial_temperature;
        rise_and_pressure(p, t0, &mut self.rise, &mut self.pressure);
        for (b, r) in self.bonds.iter_mut().zip(&state.mpm.material) {
            *b = r.rve.contacts.intact_bond_count() as f64;
        }
        let grid = UnstructuredGrid::particles(&p.position)
            .with_point_field("temperature_rise [K]", FieldValues::Scalar(&self.rise))
            .with_point_field(
                "mean_pressure [Pa] (compression +)",
                FieldValues::Scalar(&self.pressure),
            )
            .with_point_field("intact_bonds", FieldValues::Scalar(&self.bonds))
            .with_point_field("heat_source [W/m^3]", FieldValues::Scalar(&p.heat_source))
            .with_point_field("velocity [m/s]", FieldValues::Vector2(&p.velocity));
        self.rve_fields.fill(&p.strain, &state.mpm.material);
        sink("material_points", &self.rve_fields.add_to(grid))
    }

    fn profiles(&self, state: &State) -> Vec<Profile> {
        let x: Vec<f64> = state.energies.iter().map(|s| s[0]).collect();
        vec![
            Profile {
                name: "potential_energy".into(),
                x_label: "time after release [s]".into(),
                y_label: "E_p / E_p0 [-]".into(),
                x: x.clone(),
                y: state.energies.iter().map(|s| s[1]).collect(),
                reference: None,
            },
            Profile {
                name: "kinetic_energy".into(),
                x_label: "time after release [s]".into(),
                y_label: "E_k / E_p0 [-]".into(),
                x,
                y: state.energies.iter().map(|s| s[2]).collect(),
                reference: None,
            },
        ]
    }

    fn summary(&self, model: &ColumnModel, r: &ColumnRecord, state: &State) -> Vec<SummaryRow> {
        let peak = state.energies.iter().fold(0.0_f64, |m, s| m.max(s[2]));
        let failure = state
            .energies
            .iter()
            .find(|s| s[1] < 0.95)
            .map_or(f64::NAN, |s| s[0]);
        let row = |q: &str, unit: &str, measured: f64, reference: Option<f64>| SummaryRow {
            quantity: q.into(),
            unit: unit.into(),
            measured,
            reference,
        };
        let t = &model.case.test;
        let paper_failure = if t.bond_strength >= 0.1 && t.melting {
            Some(15.0)
        } else {
            None
        };
        vec![
            row(
                "potential_energy_ratio E_p/E_p0",
                "-",
                r.potential_ratio,
                None,
            ),
            row("peak kinetic_energy_ratio E_k/E_p0", "-", peak, None),
            row(
                "failure time after release (E_p/E_p0 first < 0.95; NaN: stood)",
                "s",
                failure,
                paper_failure,
            ),
            row("corner_displacement", "m", r.corner_displacement, None),
            row(
                "bonds broken on the heated half",
                "-",
                r.bonds_broken_heated as f64,
                None,
            ),
            row(
                "bonds broken on the other half",
                "-",
                r.bonds_broken_other as f64,
                None,
            ),
            row(
                "stored heat (reference: plate + sources)",
                "J/m",
                r.stored_heat,
                Some(r.plate_heat + r.source_heat),
            ),
            row(
                "consolidated void ratio (reference: the paper's at 10 kPa)",
                "-",
                model.case.packing.void_ratio,
                Some(0.251),
            ),
        ]
    }
}
