//! Heat generation in the discharge of a granular silo, B-Sect. 5.3.2 of Zhao et al. (2022):
//! a 1 m wide silo with a 0.2 m opening 1 m above a frictional ground, filled with material
//! points of 0.05 m cells (2 × 2 points per cell, B-Fig. 15), each carrying an RVE, discharged
//! under gravity (9.8 m/s²) for 12 s ("free"), or for 2 s with a plate pushing the top down at
//! 0.2 m/s ("forced", gravity on). Walls and ground are rigid with friction 0.5. Friction work
//! in the RVEs heats the points (B-Eqs. 32–33); points A (stays in the silo) and B (ends on the
//! ground) are tracked (B-Fig. 17).
//!
//! ## Choices where the paper is silent
//!
//! 1. **Geometry.** The hopper angle and the silo height are not stated (only the figure
//!    shows them): the hopper walls run at 45° from the opening's edges to the silo's sides
//!    (a hopper 0.4 m high), and the sample fills the hopper and `fill_height` (0.45 m) of
//!    the vertical part, about the paper's 1 088 points at 0.05 m cells (the count is in
//!    [`SiloModel::points`]; the points are those of the 2 × 2 per-cell lattice whose centres
//!    lie inside the silo).
//! 2. **Walls** are finite rigid walls of `thm-mpm` (`RigidWall::segment`, acting on the
//!    grid nodes up to two cells behind them and between their ends), Coulomb friction 0.5; the
//!    ground is a half-plane. The opening is closed by a frictionless gate while the sample
//!    settles under gravity (`settle_time`, both walls and gate, a larger PIC fraction that
//!    damps the settling); the gate is then removed and the discharge time runs from there.
//!    The forced case's plate is a segment across the silo at the initial top of the sample,
//!    moving down at 0.2 m/s from the release; its friction is not stated ("silo walls and
//!    ground" have 0.5) and is 0 here: with 0.5 the material caught between the moving plate
//!    and a side wall was sheared until points passed the corner (a probe at 400-disk RVEs
//!    lost a point above the plate 1.4 s after the release).
//! 3. **Material.** The silo holds "sands": the biaxial test's thermal constants of
//!    B-Sect. 5.3.1 (c = 670 J/(kg K), k = 1.6 W/(m K)), its α_PIC = 0.1 (stated for the silo
//!    in B-Sect. 5.3.2 by the biaxial text), 20 °C initially; the RVE packing of the column
//!    (400 disks consolidated to 10 kPa, about the weight of 1 m of sand, with μ = 0.5), and
//!    the column's DEM time rule. RVE cells in the flow are reduced before every step as in
//!    the column (its module docs, choice 8).
//! 4. **Heat accounting.** No heat crosses the walls (none is prescribed), so the stored heat
//!    `Σ m c (T − T₀)` equals the heat of the sources `Σ Q_p V_p Δt`, the friction work of the
//!    RVEs (B-Eq. 33), to round-off ([`SiloRecord::heat_balance_residual`]).
//!
//! Histories ([`SiloRecord`]): discharged mass fraction (points below the opening), kinetic
//! energy, mean and largest temperature rise and where the largest is, the heat balance,
//! the plate's force (forced), and the deepest penetration of a point centre behind a wall.

use serde::{Deserialize, Serialize};
use thm_mpm::{
    GridParameters, MaterialPoints, Mpm, MpmConfig, MpmParameters, MpmState, PointProperties,
    RigidWall,
};
use thm_rve::{RveParams, RveState};

use super::error::MultiscaleError;
use super::material::RveMaterial;
use super::model::{
    HeatBefore, LoadingPhase, MultiscaleModel, PackingProtocol, PackingReport, Protocol,
    consolidated_packing, flow_step_start, stored_heat,
};
use super::params::{DemTimeRule, MultiscaleParams, check_counts, check_positive};
use super::point::RvePoint;

/// Parameters of the silo discharge (SI; temperatures in °C on the MPM side).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SiloTest {
    /// Whether a plate pushes the top down ("forced") or not ("free").
    pub forced: bool,
    /// Silo width (m); the paper: 1.
    pub width: f64,
    /// Width of the opening (m); the paper: 0.2.
    pub opening: f64,
    /// Hopper wall angle from the horizontal (degrees); not stated (45).
    pub hopper_angle_deg: f64,
    /// Height of the opening above the ground (m); the paper: 1.
    pub outlet_height: f64,
    /// Height of the sample above the hopper (m); not stated (0.45).
    pub fill_height: f64,
    /// Cell size (m); the paper: 0.05.
    pub cell_size: f64,
    /// Points per cell along each direction; the paper: 2.
    pub points_per_cell: usize,
    /// Grid extent beside the silo on each side, for the heap (m).
    pub ground_margin: f64,
    /// Disks per RVE; the paper: 400.
    pub disks: usize,
    /// Seed of the packing.
    pub seed: u64,
    /// Isotropic consolidation stress of the RVEs (Pa); not stated (10 kPa).
    pub consolidation_stress: f64,
    /// Friction of the consolidation.
    pub consolidation_friction: f64,
    /// Friction of the disks afterwards.
    pub friction: f64,
    /// Coulomb friction of the walls, the plate and the ground; the paper: 0.5.
    pub wall_friction: f64,
    /// Gravity (m/s², downwards); the paper: 9.8.
    pub gravity: f64,
    /// Initial temperature (°C); not stated (20).
    pub initial_temperature: f64,
    /// Plate speed of the forced discharge (m/s, downwards); the paper: 0.2.
    pub plate_speed: f64,
    /// Coulomb friction of the loading plate (not stated; 0).
    pub plate_friction: f64,
    /// Settling under gravity with the gate closed (s).
    pub settle_time: f64,
    /// Discharge time after the gate opens (s); the paper: 12 (free), 2 (forced).
    pub discharge_time: f64,
    /// MPM time step (s).
    pub time_step: f64,
    /// Specific heat capacity (J/(kg K)).
    pub specific_heat: f64,
    /// Initial conductivity (W/(m K)) that sets α of B-Eq. 34.
    pub conductivity: f64,
    /// α_PIC during the discharge.
    pub pic_fraction: f64,
    /// α_PIC while settling.
    pub settle_pic_fraction: f64,
    /// Node mass tolerance of `thm-mpm` as a fraction of a point's mass, in [0, 1].
    pub node_mass_fraction: f64,
    /// Whether the RVEs' friction work heats the points (B-Eqs. 32–33).
    pub friction_heat: bool,
    /// RVE contact law, density, expansion, thickness, damping.
    pub rve: RveParams,
    /// The DEM time rule.
    pub dem_time: DemTimeRule,
}

impl SiloTest {
    /// B-Sect. 5.3.2 with the module docs' choices: free (12 s) or forced (2 s).
    pub fn paper(forced: bool) -> Self {
        Self {
            forced,
            width: 1.0,
            opening: 0.2,
            hopper_angle_deg: 45.0,
            outlet_height: 1.0,
            fill_height: 0.45,
            cell_size: 0.05,
            points_per_cell: 2,
            ground_margin: 2.0,
            disks: 400,
            seed: 1,
            consolidation_stress: 1e4,
            consolidation_friction: 0.5,
            friction: 0.5,
            wall_friction: 0.5,
            gravity: 9.8,
            initial_temperature: 20.0,
            plate_speed: 0.2,
            plate_friction: 0.0,
            settle_time: 0.5,
            discharge_time: if forced { 2.0 } else { 12.0 },
            time_step: 1e-4,
            specific_heat: 670.0,
            conductivity: 1.6,
            pic_fraction: 0.1,
            settle_pic_fraction: 0.5,
            node_mass_fraction: 0.01,
            friction_heat: true,
            rve: RveParams::paper_b_table_1(),
            dem_time: DemTimeRule {
                step_fraction: 0.2,
                density_scaling: 100.0,
            },
        }
    }

    /// The paper's silo at a reduced resolution: cells of `cell_size`, `disks` per RVE,
    /// `discharge_time`, Δt `time_step`; everything else as [`SiloTest::paper`].
    pub fn reduced(
        forced: bool,
        cell_size: f64,
        disks: usize,
        discharge_time: f64,
        time_step: f64,
    ) -> Self {
        let mut t = Self::paper(forced);
        t.cell_size = cell_size;
        t.disks = disks;
        t.discharge_time = discharge_time;
        t.time_step = time_step;
        t
    }

    /// `"free"` or `"forced"`.
    pub fn label(&self) -> &'static str {
        if self.forced { "forced" } else { "free" }
    }

    /// Height of the hopper (m).
    pub fn hopper_height(&self) -> f64 {
        0.5 * (self.width - self.opening) * self.hopper_angle_deg.to_radians().tan()
    }

    /// Height of the initial top of the sample above the ground (m).
    pub fn top(&self) -> f64 {
        self.outlet_height + self.hopper_height() + self.fill_height
    }

    /// MPM steps of the settling.
    pub fn settle_steps(&self) -> u64 {
        (self.settle_time / self.time_step).round() as u64
    }

    /// MPM steps of the whole run.
    pub fn steps(&self) -> u64 {
        self.settle_steps() + (self.discharge_time / self.time_step).round() as u64
    }

    /// Checks the geometry and the loading, naming the first bad field.
    pub fn validate(&self) -> Result<(), MultiscaleError> {
        let bad = |field: &'static str, value: f64, allowed: &'static str| {
            Err(MultiscaleError::InvalidParameter {
                field,
                value,
                allowed,
            })
        };
        let positive = [
            ("width", self.width),
            ("opening", self.opening),
            ("outlet_height", self.outlet_height),
            ("fill_height", self.fill_height),
            ("cell_size", self.cell_size),
            ("ground_margin", self.ground_margin),
            ("consolidation_stress", self.consolidation_stress),
            ("time_step", self.time_step),
            ("specific_heat", self.specific_heat),
            ("conductivity", self.conductivity),
            ("discharge_time", self.discharge_time),
        ];
        check_positive(&positive)?;
        if self.opening >= self.width {
            return bad("opening", self.opening, "(0, width)");
        }
        if !(self.hopper_angle_deg > 0.0 && self.hopper_angle_deg < 90.0) {
            return bad("hopper_angle_deg", self.hopper_angle_deg, "(0, 90) degrees");
        }
        let ranges = [
            (
                "consolidation_friction",
                self.consolidation_friction,
                0.0,
                10.0,
                "[0, 10]",
            ),
            ("friction", self.friction, 0.0, 10.0, "[0, 10]"),
            ("wall_friction", self.wall_friction, 0.0, 100.0, "[0, 100]"),
            ("gravity", self.gravity, 0.0, 1e3, "[0, 1000] m/s^2"),
            (
                "initial_temperature",
                self.initial_temperature,
                -273.15,
                1e4,
                "[-273.15, 1e4] degC",
            ),
            ("plate_speed", self.plate_speed, 0.0, 100.0, "[0, 100] m/s"),
            (
                "plate_friction",
                self.plate_friction,
                0.0,
                100.0,
                "[0, 100]",
            ),
            ("settle_time", self.settle_time, 0.0, 1e6, "[0, 1e6] s"),
            ("pic_fraction", self.pic_fraction, 0.0, 1.0, "[0, 1]"),
            (
                "settle_pic_fraction",
                self.settle_pic_fraction,
                0.0,
                1.0,
                "[0, 1]",
            ),
            (
                "node_mass_fraction",
                self.node_mass_fraction,
                0.0,
                1.0,
                "[0, 1]",
            ),
        ];
        for (field, v, lo, hi, allowed) in ranges {
            if !(v.is_finite() && v >= lo && v <= hi) {
                return bad(field, v, allowed);
            }
        }
        check_counts(&[
            ("points_per_cell", self.points_per_cell, 1, 8, "[1, 8]"),
            ("disks", self.disks, 2, 1_000_000, "[2, 1000000]"),
        ])?;
        // The opening and the silo must span whole cells, so that the lattice of points
        // fits the walls.
        for (field, v) in [("opening", self.opening), ("width", self.width)] {
            let n = v / self.cell_size;
            if (n - n.round()).abs() > 1e-9 * n.max(1.0) {
                return bad(field, v, "a whole number of cell_size");
            }
        }
        if self.steps() > 100_000_000 {
            return bad("time_step", self.time_step, "at most 1e8 steps in all");
        }
        Ok(())
    }

    /// Whether a point centre `x` lies inside the silo (hopper and vertical part, up to the
    /// initial top).
    fn inside(&self, x: [f64; 2]) -> bool {
        let y0 = self.outlet_height;
        let y1 = y0 + self.hopper_height();
        if x[1] <= y0 || x[1] >= self.top() || x[0] <= 0.0 || x[0] >= self.width {
            return false;
        }
        if x[1] >= y1 {
            return true;
        }
        // In the hopper: the half-width grows from opening/2 at y0 to width/2 at y1.
        let c = 0.5 * self.width;
        let half = 0.5 * self.opening + (x[1] - y0) / self.hopper_angle_deg.to_radians().tan();
        (x[0] - c).abs() < half
    }
}

/// Running sums, carried in checkpoints with the state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SiloTotals {
    /// Whether the gate has opened.
    pub released: bool,
    /// Heat of the sources so far, `Σ Q_p V_p Δt` (J/m).
    pub source_heat: f64,
    /// Sum of the magnitudes of the per-step heat terms (J/m), the scale of the balance.
    pub heat_scale: f64,
    /// Deepest penetration of a point centre behind a wall so far (m).
    pub deepest_penetration: f64,
}

/// One row of the history.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SiloRecord {
    /// Time since the start (s).
    pub time: f64,
    /// Time since the gate opened (s; negative while settling).
    pub time_after_release: f64,
    /// Mass fraction of the points below the opening.
    pub discharged_fraction: f64,
    /// `Σ ½ m v²` (J/m).
    pub kinetic_energy: f64,
    /// Mean temperature rise over all points (K).
    pub mean_rise: f64,
    /// Largest temperature rise (K).
    pub max_rise: f64,
    /// Where the largest rise is (m).
    pub hottest: [f64; 2],
    /// Stored heat `Σ m c (T − T₀)` (J/m).
    pub stored_heat: f64,
    /// Heat of the sources so far (J/m).
    pub source_heat: f64,
    /// `(stored − sources) / scale` (0 before any heat moved).
    pub heat_balance_residual: f64,
    /// Vertical force of the sample on the plate (N/m, upwards positive; forced discharge,
    /// else 0), the last step's wall reaction.
    pub plate_force: f64,
    /// Points that went through a wall: behind a side or hopper wall, within its extent and
    /// deeper than its band (two cells), above the opening.
    pub escaped: usize,
    /// Deepest penetration of a point centre behind a wall so far (m).
    pub deepest_penetration: f64,
    /// Position of point A (m).
    pub point_a: [f64; 2],
    /// Position of point B (m).
    pub point_b: [f64; 2],
}

/// The silo discharge as a case of the multiscale skeleton: its parameters, what the
/// consolidation gave, and what its records need.
#[derive(Debug, Clone)]
pub struct Silo {
    /// The parameters.
    pub test: SiloTest,
    /// What the consolidation gave.
    pub packing: PackingReport,
    /// The silo's wall segments (sides and hopper), for the penetration measure.
    segments: Vec<RigidWall>,
    /// Index of the plate among the discharge walls (forced).
    plate_wall: Option<usize>,
    /// Tracked points A and B.
    tracked: [usize; 2],
}

/// The silo as a coupled model: two loading phases, settling (gate closed) and the discharge
/// (gate open, the plate of a forced discharge), one material.
pub type SiloModel = MultiscaleModel<Silo>;

/// The phase while settling.
const SETTLE: usize = 0;
/// The phase after the gate opened.
const DISCHARGE: usize = 1;

impl MultiscaleModel<Silo> {
    /// Builds the silo: consolidates the template packing, lays out the grid, the points
    /// and the walls.
    pub fn new(t: &SiloTest) -> Result<Self, MultiscaleError> {
        t.validate()?;
        let (rve, packing, report) = consolidated_packing(
            &t.rve,
            &PackingProtocol {
                seed: t.seed,
                disks: t.disks,
                stress: t.consolidation_stress,
                consolidation_friction: t.consolidation_friction,
                friction: t.friction,
                conductivity: t.conductivity,
                bonds: None,
            },
        )?;
        Self::with_packing(t, rve, packing, report)
    }

    /// Builds the silo from a consolidated packing.
    pub fn with_packing(
        t: &SiloTest,
        rve: RveParams,
        packing: RveState,
        report: PackingReport,
    ) -> Result<Self, MultiscaleError> {
        t.validate()?;
        let h = t.cell_size;
        let cells_x = ((t.width + 2.0 * t.ground_margin) / h).ceil() as usize;
        let cells_y = ((t.top() + 2.0 * h) / h).ceil() as usize + 1;
        let mut params = MpmParameters::on_grid(GridParameters {
            origin: [-t.ground_margin, -h],
            cell_size: h,
            cells: [cells_x, cells_y],
        });
        params.gravity = [0.0, -t.gravity];
        let dx = h / t.points_per_cell as f64;
        params.node_mass_tolerance = t.node_mass_fraction * report.bulk_density * dx * dx;
        let (w, y0) = (t.width, t.outlet_height);
        let y1 = y0 + t.hopper_height();
        let top = t.top() + 2.0 * h;
        let (l, r) = (0.5 * (w - t.opening), 0.5 * (w + t.opening));
        let mu = t.wall_friction;
        // Each segment has the material on its left (thm_mpm::RigidWall::segment) and acts on
        // the nodes up to two cells behind it: with one, the nodes of an inclined wall's band
        // (at perpendicular depths 0 and h/√2 for 45°) left points at the hopper's foot a free
        // node layer to slip through (probe: 2 of 275 points through the wall in 3 s).
        let band = 2.0 * h;
        let segments = vec![
            RigidWall::segment([0.0, top], [0.0, y1], mu, band),
            RigidWall::segment([0.0, y1], [l, y0], mu, band),
            RigidWall::segment([r, y0], [w, y1], mu, band),
            RigidWall::segment([w, y1], [w, top], mu, band),
        ];
        let ground = RigidWall::half_plane([0.0, 0.0], [0.0, 1.0], mu);
        let gate = RigidWall::segment([l, y0], [r, y0], 0.0, h);
        let mut settle = params.clone();
        settle.pic_fraction = t.settle_pic_fraction;
        settle.walls = segments.clone();
        settle.walls.extend([ground, gate]);
        let mut discharge = params;
        discharge.pic_fraction = t.pic_fraction;
        discharge.walls = segments.clone();
        discharge.walls.push(ground);
        let mut plate_wall = None;
        if t.forced {
            // Across the silo, material below, moving down; at the release (t = settle_time,
            // the MPM time of the walls) it is at the initial top of the sample.
            let at = t.top() + t.plate_speed * t.settle_steps() as f64 * t.time_step;
            let mut plate = RigidWall::segment([w, at], [0.0, at], t.plate_friction, band);
            plate.velocity = [0.0, -t.plate_speed];
            plate_wall = Some(discharge.walls.len());
            discharge.walls.push(plate);
        }
        let settle_config = MpmConfig::new(settle)?;
        let discharge_config = MpmConfig::new(discharge)?;
        let material = RveMaterial::new(
            &MultiscaleParams {
                rve,
                dem_time: t.dem_time,
                kelvin_offset: rve.reference_temperature - t.initial_temperature,
                quasi_static: None,
            },
            packing,
        )?;
        // The 2 × 2 per-cell lattice over the silo's bounding box, kept where the centre is
        // inside.
        let mut lattice = MaterialPoints::new();
        let props = PointProperties {
            density: report.bulk_density,
            specific_heat: t.specific_heat,
            conductivity: material.initial_conductivity(),
            temperature: t.initial_temperature,
            velocity: [0.0; 2],
        };
        let rows = ((t.top() - y0) / h).ceil() * h;
        lattice.fill_rectangle(
            settle_config.grid(),
            [0.0, y0],
            [w, y0 + rows],
            t.points_per_cell,
            &props,
        )?;
        let mut points = MaterialPoints::new();
        for (x, half) in lattice.position.iter().zip(&lattice.half_size) {
            if t.inside(*x) {
                points.push(*x, *half, &props);
            }
        }
        let nearest = |target: [f64; 2]| {
            (0..points.len())
                .min_by(|&a, &b| {
                    let d = |i: usize| {
                        let x = points.position[i];
                        (x[0] - target[0]).powi(2) + (x[1] - target[1]).powi(2)
                    };
                    d(a).total_cmp(&d(b))
                })
                .unwrap_or(0)
        };
        // A: high, near the left wall (stays in the silo); B: just above the opening.
        let tracked = [
            nearest([0.15 * w, y1 + 0.7 * t.fill_height]),
            nearest([0.5 * w, y0 + 0.1]),
        ];
        let state = material.state(points);
        let case = Silo {
            test: *t,
            packing: report,
            segments,
            plate_wall,
            tracked,
        };
        let phases = vec![
            LoadingPhase {
                mpm: Mpm::new(settle_config),
                material: 0,
            },
            LoadingPhase {
                mpm: Mpm::new(discharge_config),
                material: 0,
            },
        ];
        Self::from_parts(case, state, phases, vec![material])
    }

    /// Number of material points.
    pub fn points(&self) -> usize {
        self.state.points.len()
    }

    /// The tracked points A and B.
    pub fn tracked(&self) -> [usize; 2] {
        self.case.tracked
    }

    /// Stored heat `Σ m c (T − T₀)` of `state` (J/m).
    pub fn stored_heat_of(&self, state: &MpmState<RvePoint>) -> f64 {
        stored_heat(state, self.case.test.initial_temperature)
    }

    /// Deepest penetration of a point centre behind one of the silo's walls (m): the
    /// largest `−d` over points within a wall's extent and band.
    fn penetration(&self) -> f64 {
        let mut deepest = 0.0f64;
        for x in &self.state.points.position {
            for w in &self.case.segments {
                if w.acts_on(*x, 0.0) {
                    deepest = deepest.max(-w.distance(*x, 0.0));
                }
            }
        }
        deepest
    }

    /// Points of `state` that went through a wall (see [`SiloRecord::escaped`]).
    pub fn escaped_of(&self, state: &MpmState<RvePoint>) -> usize {
        state
            .points
            .position
            .iter()
            .filter(|x| {
                x[1] > self.case.test.outlet_height
                    && self.case.segments.iter().any(|w| {
                        let s = w.along(**x, 0.0);
                        let [lo, hi] = w.extent.unwrap_or([f64::NEG_INFINITY, f64::INFINITY]);
                        let band = w.depth.unwrap_or(f64::INFINITY);
                        s >= lo && s <= hi && w.distance(**x, 0.0) < -band
                    })
            })
            .count()
    }
}

impl Protocol for Silo {
    type Totals = SiloTotals;
    type Record = SiloRecord;
    type StepStart = HeatBefore;

    fn time_step(&self) -> f64 {
        self.test.time_step
    }

    fn steps(&self) -> u64 {
        self.test.steps()
    }

    fn phase(totals: &SiloTotals) -> usize {
        if totals.released { DISCHARGE } else { SETTLE }
    }

    /// The gate opens when the settling is over; the heat before the step.
    fn before_step(model: &mut SiloModel) -> Result<HeatBefore, MultiscaleError> {
        if !model.totals.released && model.state.step >= model.case.test.settle_steps() {
            model.totals.released = true;
        }
        let t = &model.case.test;
        flow_step_start(
            &mut model.state,
            t.friction_heat,
            t.time_step,
            t.initial_temperature,
        )
    }

    /// The heat sums and the deepest penetration behind a wall.
    fn after_step(
        model: &mut SiloModel,
        _phase: usize,
        before: HeatBefore,
    ) -> Result<(), MultiscaleError> {
        model.totals.source_heat += before.source;
        let stored_after = model.stored_heat_of(&model.state);
        model.totals.heat_scale += before.source.abs() + (stored_after - before.stored).abs();
        model.totals.deepest_penetration =
            model.totals.deepest_penetration.max(model.penetration());
        Ok(())
    }

    /// The history row (the plate force is the last step's).
    fn record(model: &SiloModel, state: &MpmState<RvePoint>, totals: &SiloTotals) -> SiloRecord {
        let pts = &state.points;
        let t0 = model.case.test.initial_temperature;
        let (mut below, mut mass, mut ek, mut rise) = (0.0, 0.0, 0.0, 0.0);
        let (mut max_rise, mut hottest) = (f64::NEG_INFINITY, [0.0; 2]);
        for p in 0..pts.len() {
            let m = pts.mass[p];
            let [x, v] = [pts.position[p], pts.velocity[p]];
            mass += m;
            if x[1] < model.case.test.outlet_height {
                below += m;
            }
            ek += 0.5 * m * (v[0] * v[0] + v[1] * v[1]);
            let dt = pts.temperature[p] - t0;
            rise += m * dt;
            if dt > max_rise {
                max_rise = dt;
                hottest = x;
            }
        }
        let stored = model.stored_heat_of(state);
        let residual = if totals.heat_scale > 0.0 {
            (stored - totals.source_heat) / totals.heat_scale
        } else {
            0.0
        };
        let plate_force = match (model.case.plate_wall, totals.released) {
            (Some(k), true) => model.phases[DISCHARGE]
                .mpm
                .wall_reactions()
                .get(k)
                .map_or(0.0, |f| f[1]),
            _ => 0.0,
        };
        SiloRecord {
            time: state.time,
            time_after_release: state.time
                - model.case.test.settle_steps() as f64 * model.case.test.time_step,
            discharged_fraction: below / mass,
            kinetic_energy: ek,
            mean_rise: rise / mass,
            max_rise,
            hottest,
            stored_heat: stored,
            source_heat: totals.source_heat,
            heat_balance_residual: residual,
            plate_force,
            escaped: model.escaped_of(state),
            deepest_penetration: totals.deepest_penetration,
            point_a: pts.position[model.case.tracked[0]],
            point_b: pts.position[model.case.tracked[1]],
        }
    }
}
