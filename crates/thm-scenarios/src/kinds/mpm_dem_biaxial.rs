//! `kind = "mpm_dem_biaxial"`: the biaxial compression test of B-Sect. 5.3.1 of Zhao et al.
//! (2022) on the MPM×DEM scheme of `thm-coupling` (`thm_coupling::multiscale::biaxial`).
//!
//! A 1 m wide specimen of `cells[0] × cells[1]` square cells with `points_per_cell²` points
//! each, every point carrying an RVE of `disks` disks consolidated to the confining stress
//! (dense: μ = 0.01, loose: μ = 0.5; sheared with μ = 0.5), confined laterally by a follower
//! pressure, between rough plates; the top plate moves down at `plate_speed`. The run ends at
//! `time.end` (the paper: 20 % strain of 2 m at 0.02 m/s, 20 s). Monitored: axial strain,
//! stress ratio from the plate and from the point stresses, plate stress, volumetric strain,
//! largest temperature rise, heat generated, friction work (upscaled and raw over all RVEs),
//! thermal energy, plate work, quasi-static measures. The profile `stress_strain` is the
//! plate stress against the axial strain so far (B-Fig. 13). The checkpoint holds the
//! `MpmState` with every RVE, the running sums and the stress–strain samples; the stepper
//! (grid, plates, consolidated template) is rebuilt from the parameters on resume.

use serde::{Deserialize, Serialize};
use thm_coupling::multiscale::biaxial::{
    Biaxial, BiaxialModel, BiaxialRecord, BiaxialTest, BiaxialTotals, Compaction,
};
use thm_coupling::multiscale::{QuasiStaticLimits, RvePoint};
use thm_io::{Column, FieldValues, IoError, UnstructuredGrid};
use thm_mpm::MpmState;

use super::multiscale::{Multiscale, MultiscaleKind, check_time_step, kind_state};
use crate::config::{TimeControl, check_range};
use crate::error::ConfigError;
use crate::profiles::Profile;
use crate::rve_frames::{PointRveFields, RveFrames};
use crate::scenario::FrameSink;
use crate::summary::SummaryRow;
use crate::units::{Pressure, Quantity, Temperature, Velocity};

/// `[biaxial]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BiaxialParams {
    /// `dense` (consolidated with μ = 0.01) or `loose` (μ = 0.5).
    pub compaction: Compaction,
    /// Cells along x and y, each in [1, 1000] (the paper: [10, 20]); the specimen is 1 m wide
    /// and `cells[1]/cells[0]` m high.
    pub cells: [usize; 2],
    /// Points per cell along each direction, in [2, 4] (the paper: 2).
    pub points_per_cell: usize,
    /// Disks per RVE, in [10, 10000] (the paper: 400).
    pub disks: usize,
    /// Seed of the packing.
    #[serde(default = "one")]
    pub seed: u64,
    /// Density scaling of the RVE disks (DEM time rule), in [1, 1e6].
    pub density_scaling: f64,
    /// Confining stress (the paper: 100 kPa).
    pub confining_stress: Quantity<Pressure>,
    /// Speed of the top plate (the paper: 0.02 m/s).
    pub plate_speed: Quantity<Velocity>,
    /// Initial uniform temperature (not stated in the paper; 20 °C).
    pub initial_temperature: Quantity<Temperature>,
    /// Bond strength coefficient β_b of B-Eq. 38, in [0, 10] (0: no bonds; B-Fig. 18: 0.01,
    /// 0.02); bonds are installed after the consolidation at the contacts carrying force and
    /// do not melt.
    #[serde(default)]
    pub bond_strength: f64,
    /// μ_b of B-Eq. 39 (the paper: 0.5), in [1e-6, 1e6].
    #[serde(default = "half")]
    pub bond_shear_ratio: f64,
    /// Local damping of the RVE disks' motion (`thm_rve::RveParams::local_damping`), in
    /// [0, 1); the paper states none: 0.
    #[serde(default)]
    pub rve_local_damping: f64,
    /// Local non-viscous damping of the MPM nodal forces
    /// (`thm_mpm::MpmParameters::local_damping`), in [0, 1); not in the paper: 0.
    #[serde(default)]
    pub mpm_local_damping: f64,
    /// Quasi-static bounds checked after every step (`max_inertial_number`,
    /// `max_kinetic_ratio`, each in (0, 1]): the run stops at the first RVE above one,
    /// naming the point, the step and the quantity. Default: measured, not enforced.
    #[serde(default)]
    pub quasi_static: Option<QuasiStaticLimits>,
    /// Material points whose RVEs are written at every frame (disks, contact forces, cell;
    /// series `rve_K_disks`, `rve_K_contacts`, `rve_K_cell`): the point nearest to each
    /// `[x, y]` (m) of the specimen as built, at most 16, each inside it. Default: none.
    #[serde(default)]
    pub track: Vec<[f64; 2]>,
}

fn one() -> u64 {
    1
}

fn half() -> f64 {
    0.5
}

/// The kind's sections of the scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `[biaxial]`.
    pub biaxial: BiaxialParams,
}

kind_state! {
    /// What a checkpoint holds.
    State for Biaxial {
        /// `(axial strain, plate stress)` every [`SAMPLE_EVERY`](super::multiscale::SAMPLE_EVERY)
        /// steps.
        stress_strain: Vec<[f64; 2]>
    }
}

/// The kind: the biaxial test on the multiscale skeleton.
pub type MpmDemBiaxial = Multiscale<BiaxialOutputs>;

/// What the kind keeps for its outputs: frame scratch, the tracked points, the bonds
/// installed.
#[derive(Debug)]
pub struct BiaxialOutputs {
    rise: Vec<f64>,
    sxx: Vec<f64>,
    syy: Vec<f64>,
    deviatoric: Vec<f64>,
    kinetic: Vec<f64>,
    /// Indices of the tracked points.
    tracked: Vec<usize>,
    /// Bonds installed in all RVEs after the consolidation.
    bonds_installed: usize,
    rve_frames: RveFrames,
    rve_fields: PointRveFields,
}

/// Intact bonds over all RVEs.
fn intact_bonds(mpm: &MpmState<RvePoint>) -> usize {
    mpm.material.iter().map(|p| p.intact_bonds as usize).sum()
}

impl MultiscaleKind for BiaxialOutputs {
    const KIND: &'static str = "mpm_dem_biaxial";
    // 2: RvePoint carries its intact bond count.
    const STATE_VERSION: u32 = 2;
    type Params = Params;
    type Case = Biaxial;
    type State = State;

    fn init(p: &Params, time: &TimeControl) -> Result<(BiaxialModel, Self), ConfigError> {
        let b = &p.biaxial;
        for (k, v) in b.cells.iter().enumerate() {
            if !(1..=1000).contains(v) {
                return Err(ConfigError::new(
                    format!("biaxial.cells[{k}]"),
                    format!("must be in [1, 1000], got {v}"),
                ));
            }
        }
        if !(2..=4).contains(&b.points_per_cell) {
            return Err(ConfigError::new(
                "biaxial.points_per_cell",
                format!("must be in [2, 4], got {}", b.points_per_cell),
            ));
        }
        if !(10..=10_000).contains(&b.disks) {
            return Err(ConfigError::new(
                "biaxial.disks",
                format!("must be in [10, 10000], got {}", b.disks),
            ));
        }
        check_range("biaxial.density_scaling", b.density_scaling, 1.0, 1e6)?;
        check_range(
            "biaxial.confining_stress",
            b.confining_stress.si(),
            1.0,
            1e8,
        )?;
        let h = 1.0 / b.cells[0] as f64;
        check_range(
            "biaxial.plate_speed",
            b.plate_speed.si(),
            1e-9,
            0.05 * h / time.dt,
        )?;
        check_range(
            "biaxial.initial_temperature",
            b.initial_temperature.si(),
            1.0,
            1e4,
        )?;
        let mut t = BiaxialTest::reduced(
            b.compaction,
            b.cells,
            b.points_per_cell,
            b.disks,
            b.density_scaling,
        );
        check_range("biaxial.bond_strength", b.bond_strength, 0.0, 10.0)?;
        check_range("biaxial.bond_shear_ratio", b.bond_shear_ratio, 1e-6, 1e6)?;
        t.bond_strength = b.bond_strength;
        t.bond_shear_ratio = b.bond_shear_ratio;
        for (field, v) in [
            ("biaxial.rve_local_damping", b.rve_local_damping),
            ("biaxial.mpm_local_damping", b.mpm_local_damping),
        ] {
            if !(0.0..1.0).contains(&v) {
                return Err(ConfigError::new(
                    field,
                    format!("must be in [0, 1), got {v}"),
                ));
            }
        }
        t.rve.local_damping = b.rve_local_damping;
        t.mpm_local_damping = b.mpm_local_damping;
        t.quasi_static = b.quasi_static;
        t.seed = b.seed;
        t.confining_stress = b.confining_stress.si();
        t.plate_speed = b.plate_speed.si();
        t.initial_temperature = b.initial_temperature.si() - 273.15;
        t.time_step = time.dt;
        let travel = t.plate_speed * time.dt * time.n_steps as f64;
        if travel > 0.5 * t.height {
            return Err(ConfigError::new(
                "time.end",
                format!(
                    "the plate would travel {travel} m, more than half the specimen's {} m",
                    t.height
                ),
            ));
        }
        t.target_strain = (travel / t.height).max(1e-6);
        let model =
            BiaxialModel::new(&t).map_err(|e| ConfigError::new("biaxial", e.to_string()))?;
        check_time_step(&model, time)?;
        if b.track.len() > 16 {
            return Err(ConfigError::new(
                "biaxial.track",
                format!("at most 16 points, got {}", b.track.len()),
            ));
        }
        let mut tracked = Vec::with_capacity(b.track.len());
        for (k, &[x, y]) in b.track.iter().enumerate() {
            let inside = (0.0..=t.width).contains(&x) && (0.0..=t.height).contains(&y);
            if !inside {
                return Err(ConfigError::new(
                    format!("biaxial.track[{k}]"),
                    format!(
                        "must lie in the specimen [0, {}] × [0, {}] m, got [{x}, {y}]",
                        t.width, t.height
                    ),
                ));
            }
            let distance = |q: &[f64; 2]| (q[0] - x).hypot(q[1] - y);
            let nearest = model
                .state
                .points
                .position
                .iter()
                .enumerate()
                .min_by(|a, b| distance(a.1).total_cmp(&distance(b.1)))
                .map_or(0, |(i, _)| i);
            tracked.push(nearest);
        }
        let n = model.state.points.len();
        let bonds_installed = intact_bonds(&model.state);
        let outputs = Self {
            rise: vec![0.0; n],
            sxx: vec![0.0; n],
            syy: vec![0.0; n],
            deviatoric: vec![0.0; n],
            kinetic: vec![0.0; n],
            tracked,
            bonds_installed,
            rve_frames: RveFrames::default(),
            rve_fields: PointRveFields::default(),
        };
        Ok((model, outputs))
    }

    fn first_samples(model: &BiaxialModel) -> Vec<[f64; 2]> {
        vec![[0.0, model.case.test.confining_stress]]
    }

    fn sample(r: &BiaxialRecord, _totals: &BiaxialTotals) -> Option<[f64; 2]> {
        Some([r.axial_strain, r.plate_stress])
    }

    fn monitor_columns(&self) -> Vec<Column> {
        vec![
            Column::new("axial_strain", "-"),
            Column::new("stress_ratio_plate", "-"),
            Column::new("stress_ratio_points", "-"),
            Column::new("plate_stress", "Pa"),
            Column::new("mean_sigma_xx", "Pa"),
            Column::new("mean_sigma_yy", "Pa"),
            Column::new("volumetric_strain", "-"),
            Column::new("largest_temperature_rise", "K"),
            Column::new("heat_generated", "J/m"),
            Column::new("friction_work_upscaled", "J/m"),
            Column::new("friction_work_all_rves", "J"),
            Column::new("thermal_energy", "J/m"),
            Column::new("plate_work", "J/m"),
            Column::new("largest_rve_inertial_number", "-"),
            Column::new("largest_rve_kinetic_ratio", "-"),
            Column::new("rves_without_pressure", "-"),
            Column::new("intact_bonds", "-"),
            Column::new("largest_inertial_number_point", "-"),
            Column::new("largest_inertial_number_x", "m"),
            Column::new("largest_inertial_number_y", "m"),
            Column::new("largest_kinetic_ratio_point", "-"),
            Column::new("largest_kinetic_ratio_x", "m"),
            Column::new("largest_kinetic_ratio_y", "m"),
        ]
    }

    fn monitor(&self, r: &BiaxialRecord, state: &State, values: &mut Vec<f64>) {
        values.extend([
            r.axial_strain,
            r.stress_ratio,
            r.point_stress_ratio,
            r.plate_stress,
            r.mean_sigma_xx,
            r.mean_sigma_yy,
            r.volumetric_strain,
            r.max_temperature_rise,
            r.heat_generated,
            r.friction_work_upscaled,
            r.friction_work_rves,
            r.thermal_energy,
            r.plate_work,
            r.max_inertial_number,
            r.max_kinetic_ratio,
            r.rves_without_pressure as f64,
            intact_bonds(&state.mpm) as f64,
        ]);
        for at in [r.max_inertial_at, r.max_kinetic_at] {
            values.extend([at.point as f64, at.position[0], at.position[1]]);
        }
    }

    fn frame(
        &mut self,
        model: &BiaxialModel,
        state: &State,
        sink: &mut FrameSink<'_>,
    ) -> Result<(), IoError> {
        let p = &state.mpm.points;
        let t0 = model.case.test.initial_temperature;
        for k in 0..p.len() {
            self.rise[k] = p.temperature[k] - t0;
            self.sxx[k] = -p.stress[k][0];
            self.syy[k] = -p.stress[k][1];
            let e = p.strain[k];
            // ε_q of B-Eq. 48 (n = 2) from the accumulated small strain.
            let half = 0.5 * (e[0] - e[1]);
            self.deviatoric[k] = (2.0 * (half * half + e[2] * e[2])).sqrt();
        }
        for (k, r) in self.kinetic.iter_mut().zip(&state.mpm.material) {
            *k = r.kinetic_ratio;
        }
        let grid = UnstructuredGrid::particles(&p.position)
            .with_point_field("temperature_rise [K]", FieldValues::Scalar(&self.rise))
            .with_point_field(
                "sigma_xx [Pa] (compression +)",
                FieldValues::Scalar(&self.sxx),
            )
            .with_point_field(
                "sigma_yy [Pa] (compression +)",
                FieldValues::Scalar(&self.syy),
            )
            .with_point_field("deviatoric_strain", FieldValues::Scalar(&self.deviatoric))
            .with_point_field("heat_source [W/m^3]", FieldValues::Scalar(&p.heat_source))
            .with_point_field("rve_kinetic_ratio", FieldValues::Scalar(&self.kinetic))
            .with_point_field("velocity [m/s]", FieldValues::Vector2(&p.velocity));
        self.rve_fields.fill(&p.strain, &state.mpm.material);
        sink("material_points", &self.rve_fields.add_rve_to(grid))?;
        for (k, &i) in self.tracked.iter().enumerate() {
            if let Some(point) = state.mpm.material.get(i) {
                self.rve_frames
                    .write(&format!("rve_{k}"), &point.rve, sink)?;
            }
        }
        Ok(())
    }

    fn profiles(&self, state: &State) -> Vec<Profile> {
        let (x, y) = state.stress_strain.iter().map(|s| (s[0], s[1])).unzip();
        vec![Profile {
            name: "stress_strain".into(),
            x_label: "axial strain [-]".into(),
            y_label: "plate stress sigma_yy [Pa]".into(),
            x,
            y,
            reference: None,
        }]
    }

    fn summary(&self, model: &BiaxialModel, r: &BiaxialRecord, state: &State) -> Vec<SummaryRow> {
        let sc = model.case.test.confining_stress;
        let ratio = |s: f64| (s - sc) / (s + sc);
        let peak = state
            .stress_strain
            .iter()
            .fold(f64::NEG_INFINITY, |m, s| m.max(ratio(s[1])));
        let end = r.axial_strain;
        let tail: Vec<f64> = state
            .stress_strain
            .iter()
            .filter(|s| s[0] >= end - 0.02)
            .map(|s| ratio(s[1]))
            .collect();
        let residual = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
        let row = |q: &str, unit: &str, measured: f64, reference: Option<f64>| SummaryRow {
            quantity: q.into(),
            unit: unit.into(),
            measured,
            reference,
        };
        vec![
            row(
                "axial_strain (reference: the target of time.end)",
                "-",
                r.axial_strain,
                Some(model.case.test.target_strain),
            ),
            row("peak_stress_ratio_plate", "-", peak, None),
            row(
                "residual_stress_ratio_plate (last 2 % strain)",
                "-",
                residual,
                None,
            ),
            row("residual_over_peak", "-", residual / peak, None),
            row("volumetric_strain", "-", r.volumetric_strain, None),
            row(
                "largest_temperature_rise (paper: up to 1.6 degC)",
                "K",
                r.max_temperature_rise,
                Some(1.6),
            ),
            row(
                "heat_generated (reference: friction work upscaled)",
                "J/m",
                r.heat_generated,
                Some(r.friction_work_upscaled),
            ),
            row(
                "broken_bond_fraction (0 without bonds)",
                "-",
                if self.bonds_installed == 0 {
                    0.0
                } else {
                    1.0 - intact_bonds(&state.mpm) as f64 / self.bonds_installed as f64
                },
                None,
            ),
            row(
                "consolidated void ratio (reference: the paper's)",
                "-",
                model.case.packing.void_ratio,
                model.case.test.paper_void_ratio(),
            ),
        ]
    }
}
