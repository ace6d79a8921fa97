//! `kind = "mpm_dem_silo"`: heat generation in the discharge of a granular silo, B-Sect. 5.3.2
//! of Zhao et al. (2022), on the MPM×DEM scheme of `thm-coupling`
//! (`thm_coupling::multiscale::silo`).
//!
//! A 1 m wide silo with a 45° hopper and a 0.2 m opening 1 m above the ground is filled with
//! material points (`points_per_cell²` per cell of `cell_size`), each carrying an RVE of
//! `disks` disks consolidated to 10 kPa; the sample settles under gravity with the opening
//! closed for `settle_time`, then the gate opens and it discharges freely, or (`forced`) a
//! plate pushes the top down at `plate_speed`. The run ends at `time.end` (settling included;
//! the paper: 12 s free, 2 s forced). Monitored: time after the release, discharged mass
//! fraction, kinetic energy, mean and largest temperature rise and where the largest is, the
//! heat balance (stored against the RVEs' friction heat), the plate force, points through a
//! wall and the deepest penetration, and the positions of points A and B. Frames: the
//! material points, and the RVEs of A and B (`rve_0_*`, `rve_1_*`: disks, contact-force
//! network, cell; B-Fig. 17). The profile `discharge` is the discharged fraction against the
//! time after the release. The checkpoint holds the `MpmState` with every RVE, the running
//! sums and the discharge samples.

use serde::{Deserialize, Serialize};
use thm_coupling::multiscale::silo::{Silo, SiloModel, SiloRecord, SiloTest, SiloTotals};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};

use super::multiscale::{
    Multiscale, MultiscaleKind, kind_state, rise_and_pressure, time_after_settling,
};
use crate::config::{TimeControl, check_count, check_range};
use crate::error::ConfigError;
use crate::profiles::Profile;
use crate::rve_frames::{PointRveFields, RveFrames};
use crate::scenario::FrameSink;
use crate::summary::SummaryRow;
use crate::units::{Length, Quantity, Temperature, Time, Velocity};

/// `[silo]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SiloParams {
    /// Whether a plate pushes the top down (forced discharge).
    pub forced: bool,
    /// Cell size; the silo's 1 m and the opening's 0.2 m must be whole cells (the paper:
    /// 0.05 m).
    pub cell_size: Quantity<Length>,
    /// Points per cell along each direction, in [1, 4] (the paper: 2).
    pub points_per_cell: usize,
    /// Disks per RVE, in [10, 10000] (the paper: 400).
    pub disks: usize,
    /// Seed of the packing.
    #[serde(default = "one")]
    pub seed: u64,
    /// Density scaling of the RVE disks (DEM time rule), in [1, 1e6].
    pub density_scaling: f64,
    /// Settling time with the opening closed, shorter than `time.end`.
    pub settle_time: Quantity<Time>,
    /// Initial uniform temperature (not stated in the paper; 20 °C).
    pub initial_temperature: Quantity<Temperature>,
    /// Plate speed of the forced discharge, downwards (the paper: 0.2 m/s).
    pub plate_speed: Quantity<Velocity>,
}

fn one() -> u64 {
    1
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[silo]`.
    pub silo: SiloParams,
}

kind_state! {
    /// What a checkpoint holds.
    State for Silo {
        /// `(time after release, discharged fraction, largest rise)` every
        /// [`SAMPLE_EVERY`](super::multiscale::SAMPLE_EVERY) steps after the release.
        samples: Vec<[f64; 3]>
    }
}

/// The kind: the silo discharge on the multiscale skeleton.
pub type MpmDemSilo = Multiscale<SiloOutputs>;

/// What the kind keeps for its outputs: frame scratch.
#[derive(Debug)]
pub struct SiloOutputs {
    rise: Vec<f64>,
    pressure: Vec<f64>,
    rve_fields: PointRveFields,
    rve_frames: RveFrames,
}

impl MultiscaleKind for SiloOutputs {
    const KIND: &'static str = "mpm_dem_silo";
    // 2: RvePoint carries its intact bond count.
    const STATE_VERSION: u32 = 2;
    type Params = Params;
    type Case = Silo;
    type State = State;

    fn init(p: &Params, time: &TimeControl) -> Result<(SiloModel, Self), ConfigError> {
        let s = &p.silo;
        let h = s.cell_size.positive("silo.cell_size")?;
        check_range("silo.cell_size", h, 0.005, 0.2)?;
        check_count("silo.points_per_cell", s.points_per_cell, 1, 4)?;
        check_count("silo.disks", s.disks, 10, 10_000)?;
        check_range("silo.density_scaling", s.density_scaling, 1.0, 1e6)?;
        check_range(
            "silo.initial_temperature",
            s.initial_temperature.si(),
            1.0,
            1e4,
        )?;
        check_range("silo.plate_speed", s.plate_speed.si(), 0.0, 100.0)?;
        let end = time.dt * time.n_steps as f64;
        let settle = s.settle_time.si();
        check_range("silo.settle_time", settle, 0.0, end)?;
        let mut t = SiloTest::reduced(s.forced, h, s.disks, 1.0, time.dt);
        for (key, v) in [("silo.cell_size", t.width), ("silo.cell_size", t.opening)] {
            let n = v / h;
            if (n - n.round()).abs() > 1e-9 * n.max(1.0) {
                return Err(ConfigError::new(
                    key,
                    format!("{v} m must be a whole number of cells, got cells of {h} m"),
                ));
            }
        }
        t.points_per_cell = s.points_per_cell;
        t.seed = s.seed;
        t.dem_time.density_scaling = s.density_scaling;
        t.initial_temperature = s.initial_temperature.si() - 273.15;
        t.plate_speed = s.plate_speed.si();
        t.settle_time = settle;
        t.discharge_time = time_after_settling(t.settle_steps(), time)?;
        let model = SiloModel::new(&t).map_err(|e| ConfigError::new("silo", e.to_string()))?;
        let n = model.state.points.len();
        let outputs = Self {
            rise: vec![0.0; n],
            pressure: vec![0.0; n],
            rve_fields: PointRveFields::default(),
            rve_frames: RveFrames::default(),
        };
        Ok((model, outputs))
    }

    fn sample(r: &SiloRecord, totals: &SiloTotals) -> Option<[f64; 3]> {
        totals
            .released
            .then_some([r.time_after_release, r.discharged_fraction, r.max_rise])
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("time_after_release", "s"),
            Column::new("discharged_fraction", "-"),
            Column::new("kinetic_energy", "J/m"),
            Column::new("mean_temperature_rise", "K"),
            Column::new("largest_temperature_rise", "K"),
            Column::new("hottest_x", "m"),
            Column::new("hottest_y", "m"),
            Column::new("stored_heat", "J/m"),
            Column::new("friction_heat", "J/m"),
            Column::new("heat_balance_residual", "-"),
            Column::new("plate_force", "N/m"),
            Column::new("points_through_walls", "-"),
            Column::new("deepest_penetration", "m"),
            Column::new("point_a_x", "m"),
            Column::new("point_a_y", "m"),
            Column::new("point_b_x", "m"),
            Column::new("point_b_y", "m"),
        ]
    }

    fn monitor(&self, r: &SiloRecord, _state: &State, values: &mut Vec<f64>) {
        values.extend([
            r.time_after_release,
            r.discharged_fraction,
            r.kinetic_energy,
            r.mean_rise,
            r.max_rise,
            r.hottest[0],
            r.hottest[1],
            r.stored_heat,
            r.source_heat,
            r.heat_balance_residual,
            r.plate_force,
            r.escaped as f64,
            r.deepest_penetration,
            r.point_a[0],
            r.point_a[1],
            r.point_b[0],
            r.point_b[1],
        ]);
    }

    fn frame(
        &mut self,
        model: &SiloModel,
        state: &State,
        sink: &mut FrameSink<'_>,
    ) -> Result<(), IoError> {
        let p = &state.mpm.points;
        let t0 = model.case.test.initial_temperature;
        rise_and_pressure(p, t0, &mut self.rise, &mut self.pressure);
        let grid = UnstructuredGrid::particles(&p.position)
            .with_point_field("temperature_rise [K]", FieldValues::Scalar(&self.rise))
            .with_point_field(
                "mean_pressure [Pa] (compression +)",
                FieldValues::Scalar(&self.pressure),
            )
            .with_point_field("heat_source [W/m^3]", FieldValues::Scalar(&p.heat_source))
            .with_point_field("velocity [m/s]", FieldValues::Vector2(&p.velocity));
        self.rve_fields.fill(&p.strain, &state.mpm.material);
        sink("material_points", &self.rve_fields.add_to(grid))?;
        for (k, &i) in model.tracked().iter().enumerate() {
            if let Some(point) = state.mpm.material.get(i) {
                self.rve_frames
                    .write(&format!("rve_{k}"), &point.rve, sink)?;
            }
        }
        Ok(())
    }

    fn profiles(&self, state: &State) -> Vec<Profile> {
        let x: Vec<f64> = state.samples.iter().map(|s| s[0]).collect();
        vec![
            Profile {
                name: "discharge".into(),
                x_label: "time after release [s]".into(),
                y_label: "discharged mass fraction [-]".into(),
                x: x.clone(),
                y: state.samples.iter().map(|s| s[1]).collect(),
                reference: None,
            },
            Profile {
                name: "largest_temperature_rise".into(),
                x_label: "time after release [s]".into(),
                y_label: "largest temperature rise [K]".into(),
                x,
                y: state.samples.iter().map(|s| s[2]).collect(),
                reference: None,
            },
        ]
    }

    fn summary(&self, model: &SiloModel, r: &SiloRecord, _state: &State) -> Vec<SummaryRow> {
        let row = |q: &str, unit: &str, measured: f64, reference: Option<f64>| SummaryRow {
            quantity: q.into(),
            unit: unit.into(),
            measured,
            reference,
        };
        vec![
            row("discharged mass fraction", "-", r.discharged_fraction, None),
            row("largest temperature rise", "K", r.max_rise, None),
            row(
                "height of the hottest point above the opening",
                "m",
                r.hottest[1] - model.case.test.outlet_height,
                None,
            ),
            row("mean temperature rise", "K", r.mean_rise, None),
            row(
                "stored heat (reference: friction heat of the RVEs)",
                "J/m",
                r.stored_heat,
                Some(r.source_heat),
            ),
            row("points through a wall", "-", r.escaped as f64, Some(0.0)),
            row(
                "material points (the paper: 1088 at 0.05 m cells)",
                "-",
                model.points() as f64,
                None,
            ),
        ]
    }
}
