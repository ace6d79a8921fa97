//! The melting-induced column collapse of B-Sect. 5.3.3 of Zhao et al. (2022): a 2 m × 2 m
//! granular column on a frictional ground (μ = 0.5) between two lateral plates, 20 × 20
//! cells with 2 × 2 material points each, every point carrying an RVE consolidated to
//! 10 kPa (B-Fig. 19). Under gravity (9.8 m/s²) the column settles with both plates in
//! place and the bonds inactive; then the right plate is removed, the left plate is held at
//! 50 °C and thermally sensitive bonds (B-Eqs. 38–40) are installed at every contact that
//! carries force. Heat capacity 1 J/(kg K), initial conductivity 100 W/(m K), α_PIC = 0.01,
//! Δt = 10⁻⁴ s, 3 s (β_b = 0) or 20 s (β_b ≠ 0) after the release. Energies
//! `E_p = Σ m_p g h_p`, `E_k = Σ ½ m_p v_p²` normalised by the initial `E_p` (B-Fig. 20).
//!
//! ## The bond and its melting (B-Eqs. 38–40)
//!
//! A bond breaks when `F_n > F_nb = β_b k_n R` (tension) or `|F_t| > F_tb = μ_b F_nb`
//! (B-Eqs. 38–39), μ_b = 0.5, and stays broken. With melting,
//! `β_b = β_a (T_s − T)/T_s` for `T ≤ T_s` and 0 above (B-Eq. 40), `T_s = 10 °C` "a
//! threshold for temperature change": `T` is read as the rise of the point's temperature
//! above the initial one, so a bond has lost all strength where the point has warmed by
//! 10 K. Without melting `β_b = β_a` at every temperature (`T_s` is set to `f64::MAX`, for
//! which B-Eq. 40 gives exactly `β_a` at any finite rise). The paper's three values
//! β_b = 0, 0.02, 0.1 are `β_a` ([`ColumnTest::bond_strength`]).
//!
//! ## Choices where the paper is silent or ambiguous
//!
//! 1. **Initial temperature.** Not stated; 0 °C (an "icy" column; only the rise matters for
//!    B-Eq. 40 and the plate is 50 K above it).
//! 2. **Settling.** The paper lets the column settle "to reach a state of static
//!    equilibrium" without saying for how long; here for `settle_time` (default 1 s) with both
//!    plates, no heating, no bonds and a larger PIC fraction `settle_pic_fraction` (0.5) that
//!    damps the settling oscillation, then α_PIC returns to the paper's 0.01. Energies,
//!    corner displacement and bond counts are measured from the release.
//! 3. **Plates.** Rigid walls of `thm-mpm`: the ground (`y = 0`) with Coulomb friction 0.5,
//!    the left (heating) plate at `x = 0` and the right one at `x = W` frictionless (the paper
//!    gives no plate friction). The right plate is removed at the release. The heating plate
//!    is a prescribed nodal temperature (B-Eq. 4a) on the grid line `x = 0`, applied from the
//!    release on.
//! 4. **Packing.** B-Sect. 5.3.1's protocol at 10 kPa; its void ratio 0.251 lies between
//!    the dense (μ = 0.01) and the loose (μ = 0.5) protocols at 100 kPa, so the
//!    consolidation friction is a parameter (default 0.5); μ = 0.5 afterwards. α of B-Eq. 34
//!    is set so that the consolidated packing conducts the stated 100 W/(m K) (mean of its
//!    diagonal), as for the biaxial test. Bulk density `ρ_s / (1 + e)`.
//! 5. **Bonds** are installed at the release at every contact carrying force
//!    (`thm_rve::RveState::install_bonds`, keeping the present compression), in every RVE.
//! 6. **Friction heat** (B-Eqs. 32–33) is on; with `c = 1 J/(kg K)` the dissipated work
//!    of the collapse warms the sheared zone, which can melt bonds there too.
//! 7. **Heat accounting.** The heat entering from the plate in a step is read from the grid:
//!    at every node of the plate, `Δt (C_I Ṫ_I − Q_I)` where `Ṫ_I = (T̄ − T_I^mapped)/Δt` is
//!    the rate that brings the node to the plate temperature and `Q_I` the node's conduction
//!    and source load, which the prescription overrides. The stored heat is
//!    `Σ m_p c_p (T_p − T₀)`; the heat of the sources `Σ_p Q_p V_p Δt` (friction, B-Eq. 33).
//!    Since `Σ_p m_p c_p ΔT_p = Δt Σ_I C_I Ṫ_I` and the conduction loads sum to zero over
//!    the nodes, stored = plate + sources to round-off ([`ColumnRecord::heat_balance_residual`]).
//! 8. **Cells in a flow.** A point in the collapsing mass is sheared far beyond what a
//!    periodic cell of a few hundred disks survives: its basis vectors tilt until the cell
//!    is narrower than twice the contact reach (a probe at 4 × 4 cells failed 0.85 s after the
//!    release at `ε_q = 1.6`). Before every step each RVE's basis is reduced
//!    (Lagrange–Gauss, `thm_rve::RveState::reduce_cell`) to a less skewed basis of the same
//!    lattice, so the packing, its contacts and its stress are unchanged (tested in
//!    `thm-rve`) and the cell stays wide enough.
//!
//! Histories ([`ColumnRecord`]) per step: time since the release, `E_p/E_p0`, `E_k/E_p0`,
//! displacement of the top-right corner point, intact and broken bonds on the heated half
//! (`x < W/2` at the start) and on the other, the heat balance, the largest temperature and
//! the runout (rightmost point edge).

use serde::{Deserialize, Serialize};
use thm_mpm::{
    GridParameters, MaterialPoints, Mpm, MpmConfig, MpmParameters, MpmState, NodeSet,
    PointProperties, RigidWall, TemperatureCondition,
};
use thm_rve::{RveParams, RveState};

use super::error::MultiscaleError;
use super::material::RveMaterial;
use super::model::{
    HeatBefore, LoadingPhase, MultiscaleModel, PackingProtocol, PackingReport, Protocol,
    consolidated_packing, flow_step_start, reduce_cells, stored_heat,
};
use super::params::{DemTimeRule, MultiscaleParams, check_counts, check_positive};
use super::point::RvePoint;

/// Parameters of the column collapse (SI; temperatures in °C on the MPM side).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnTest {
    /// β_a of B-Eq. 40 (β_b at the initial temperature); the paper: 0, 0.02, 0.1 (0: no
    /// bonds).
    pub bond_strength: f64,
    /// Whether β_b follows B-Eq. 40 ("melting") or stays β_a ("no melting").
    pub melting: bool,
    /// μ_b of B-Eq. 39; the paper: 0.5.
    pub bond_shear_ratio: f64,
    /// T_s of B-Eq. 40 (K of rise above the initial temperature); the paper: 10.
    pub melting_threshold: f64,
    /// Column width W (m); the paper: 2.
    pub width: f64,
    /// Column height H (m); the paper: 2.
    pub height: f64,
    /// Cells of the column along x and y (square cells); the paper: 20 × 20.
    pub cells: [usize; 2],
    /// Points per cell along each direction; the paper: 2 (4 per cell).
    pub points_per_cell: usize,
    /// Empty cells to the right of the column for the runout.
    pub runout_cells: usize,
    /// Disks per RVE; the paper: 400 (B-Sect. 5.3.1).
    pub disks: usize,
    /// Seed of the packing.
    pub seed: u64,
    /// Isotropic consolidation stress of the RVEs (Pa); the paper: 10 kPa.
    pub consolidation_stress: f64,
    /// Friction coefficient of the consolidation (see the module docs, choice 4).
    pub consolidation_friction: f64,
    /// Friction coefficient of the disks after consolidation; the paper: 0.5.
    pub friction: f64,
    /// Coulomb friction of the ground; the paper: 0.5.
    pub ground_friction: f64,
    /// Coulomb friction of the lateral plates (not stated; 0).
    pub plate_friction: f64,
    /// Gravity (m/s², downwards); the paper: 9.8.
    pub gravity: f64,
    /// Initial uniform temperature T₀ (°C); not stated in the paper (0).
    pub initial_temperature: f64,
    /// Temperature of the heating plate (°C); the paper: 50.
    pub plate_temperature: f64,
    /// Settling time under gravity before the release (s).
    pub settle_time: f64,
    /// Time after the release (s); the paper: 3 (β_b = 0) or 20.
    pub collapse_time: f64,
    /// MPM time step (s); the paper: 10⁻⁴.
    pub time_step: f64,
    /// Specific heat capacity (J/(kg K)); the paper: 1.
    pub specific_heat: f64,
    /// Initial conductivity (W/(m K)) that sets α of B-Eq. 34; the paper: 100.
    pub conductivity: f64,
    /// PIC fraction α_PIC after the release; the paper: 0.01.
    pub pic_fraction: f64,
    /// PIC fraction while settling (damps the settling oscillation).
    pub settle_pic_fraction: f64,
    /// Grid damping α_g of B-Eq. 26 (not stated; 0).
    pub grid_damping: f64,
    /// Node mass tolerance of `thm-mpm` as a fraction of a point's mass, in [0, 1].
    pub node_mass_fraction: f64,
    /// Whether the RVEs' friction work heats the points (B-Eqs. 32–33).
    pub friction_heat: bool,
    /// RVE contact law, density, expansion, thickness, damping (μ, α and the bond are set
    /// from the fields above).
    pub rve: RveParams,
    /// The DEM time rule.
    pub dem_time: DemTimeRule,
}

impl ColumnTest {
    /// B-Sect. 5.3.3 with B-Table 1: 2 m × 2 m, 20 × 20 cells, 2 × 2 points per cell,
    /// 400-disk RVEs at 10 kPa, μ = 0.5, μ_b = 0.5, T_s = 10 K, plate 50 °C, c = 1 J/(kg K),
    /// k = 100 W/(m K), α_PIC = 0.01, Δt = 10⁻⁴ s, 3 s without bonds and 20 s with. Where the
    /// paper is silent: the module docs' choices, density scaling 100.
    pub fn paper(bond_strength: f64, melting: bool) -> Self {
        Self {
            bond_strength,
            melting,
            bond_shear_ratio: 0.5,
            melting_threshold: 10.0,
            width: 2.0,
            height: 2.0,
            cells: [20, 20],
            points_per_cell: 2,
            runout_cells: 40,
            disks: 400,
            seed: 1,
            consolidation_stress: 1e4,
            consolidation_friction: 0.5,
            friction: 0.5,
            ground_friction: 0.5,
            plate_friction: 0.0,
            gravity: 9.8,
            initial_temperature: 0.0,
            plate_temperature: 50.0,
            settle_time: 1.0,
            collapse_time: if bond_strength > 0.0 { 20.0 } else { 3.0 },
            time_step: 1e-4,
            specific_heat: 1.0,
            conductivity: 100.0,
            pic_fraction: 0.01,
            settle_pic_fraction: 0.5,
            grid_damping: 0.0,
            node_mass_fraction: 0.01,
            friction_heat: true,
            rve: RveParams::paper_b_table_1(),
            dem_time: DemTimeRule {
                step_fraction: 0.2,
                density_scaling: 100.0,
            },
        }
    }

    /// The paper's column at a reduced size: `cells` × `cells` cells of the 2 m column,
    /// 2 × 2 points per cell, `disks` per RVE, Δt `time_step`, the disks density-scaled by
    /// `density_scaling`; everything else as [`ColumnTest::paper`].
    pub fn reduced(
        bond_strength: f64,
        melting: bool,
        cells: usize,
        disks: usize,
        time_step: f64,
        density_scaling: f64,
    ) -> Self {
        let mut t = Self::paper(bond_strength, melting);
        t.cells = [cells, cells];
        t.runout_cells = 2 * cells;
        t.disks = disks;
        t.time_step = time_step;
        t.dem_time.density_scaling = density_scaling;
        t
    }

    /// `"unbonded"`, `"b0.02_melting"`, `"b0.1_no_melting"`, ...
    pub fn label(&self) -> String {
        if self.bond_strength == 0.0 {
            "unbonded".to_string()
        } else if self.melting {
            format!("b{}_melting", self.bond_strength)
        } else {
            format!("b{}_no_melting", self.bond_strength)
        }
    }

    /// Cell size `W / nx` (m).
    pub fn cell_size(&self) -> f64 {
        self.width / self.cells[0] as f64
    }

    /// MPM steps of the settling.
    pub fn settle_steps(&self) -> u64 {
        (self.settle_time / self.time_step).round() as u64
    }

    /// MPM steps of the whole run (settling and collapse).
    pub fn steps(&self) -> u64 {
        self.settle_steps() + (self.collapse_time / self.time_step).round() as u64
    }

    /// Checks the geometry and the loading, naming the first bad field.
    pub fn validate(&self) -> Result<(), MultiscaleError> {
        let positive = [
            ("width", self.width),
            ("height", self.height),
            ("consolidation_stress", self.consolidation_stress),
            ("melting_threshold", self.melting_threshold),
            ("time_step", self.time_step),
            ("specific_heat", self.specific_heat),
            ("conductivity", self.conductivity),
            ("collapse_time", self.collapse_time),
        ];
        check_positive(&positive)?;
        check_counts(&[
            ("cells[0]", self.cells[0], 1, 10_000, "[1, 10000]"),
            ("cells[1]", self.cells[1], 1, 10_000, "[1, 10000]"),
            ("points_per_cell", self.points_per_cell, 1, 8, "[1, 8]"),
            ("runout_cells", self.runout_cells, 1, 100_000, "[1, 100000]"),
            ("disks", self.disks, 2, 1_000_000, "[2, 1000000]"),
        ])?;
        let h = self.cell_size();
        if (h - self.height / self.cells[1] as f64).abs() > 1e-9 * h {
            return Err(MultiscaleError::InvalidParameter {
                field: "height",
                value: self.height,
                allowed: "cells[1] x width / cells[0] (square cells)",
            });
        }
        let ranges = [
            ("bond_strength", self.bond_strength, 0.0, 10.0, "[0, 10]"),
            (
                "bond_shear_ratio",
                self.bond_shear_ratio,
                0.0,
                100.0,
                "[0, 100]",
            ),
            (
                "consolidation_friction",
                self.consolidation_friction,
                0.0,
                10.0,
                "[0, 10]",
            ),
            ("friction", self.friction, 0.0, 10.0, "[0, 10]"),
            (
                "ground_friction",
                self.ground_friction,
                0.0,
                100.0,
                "[0, 100]",
            ),
            (
                "plate_friction",
                self.plate_friction,
                0.0,
                100.0,
                "[0, 100]",
            ),
            ("gravity", self.gravity, 0.0, 1e3, "[0, 1000] m/s^2"),
            (
                "initial_temperature",
                self.initial_temperature,
                -273.15,
                1e4,
                "[-273.15, 1e4] degC",
            ),
            (
                "plate_temperature",
                self.plate_temperature,
                -273.15,
                1e4,
                "[-273.15, 1e4] degC",
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
            ("grid_damping", self.grid_damping, 0.0, 1.0, "[0, 1]"),
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
                return Err(MultiscaleError::InvalidParameter {
                    field,
                    value: v,
                    allowed,
                });
            }
        }
        if self.steps() > 100_000_000 {
            return Err(MultiscaleError::InvalidParameter {
                field: "time_step",
                value: self.time_step,
                allowed: "at most 1e8 steps for settle_time + collapse_time",
            });
        }
        Ok(())
    }

    /// The RVE parameters of the collapse: μ after consolidation, and the bond of
    /// B-Eqs. 38–40 (none for `β_a = 0`; `T_s = f64::MAX` without melting, see the module
    /// docs).
    fn bonded_rve(&self, rve: &RveParams) -> RveParams {
        let mut p = *rve;
        p.contact.friction_coefficient = self.friction;
        p.contact.thermal_bond = (self.bond_strength > 0.0).then_some(thm_dem::ThermalBondParams {
            strength_coefficient: self.bond_strength,
            threshold_temperature_rise: if self.melting {
                self.melting_threshold
            } else {
                f64::MAX
            },
            reference_temperature: rve.reference_temperature,
            shear_ratio: self.bond_shear_ratio,
        });
        p
    }
}

/// The consolidated packing of the column (random radii in [0.25, 0.5] mm, `disks` disks,
/// consolidated isotropically to the consolidation stress), at rest, with α of B-Eq. 34 set
/// for the stated conductivity and μ set for the collapse (no bonds yet: they are installed
/// at the release).
pub fn column_packing(
    t: &ColumnTest,
) -> Result<(RveParams, RveState, PackingReport), MultiscaleError> {
    t.validate()?;
    consolidated_packing(
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
    )
}

/// Running sums and the state at the release, carried in checkpoints with the state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnTotals {
    /// Whether the right plate has been removed (and the bonds installed, the plate heated).
    pub released: bool,
    /// `E_p` at the release (J/m).
    pub potential_energy_at_release: f64,
    /// Position of the top-right corner point at the release (m).
    pub corner_at_release: [f64; 2],
    /// Bonds installed at the release on the heated half and on the other.
    pub bonds_installed: [u64; 2],
    /// Heat that entered from the heating plate so far (J/m).
    pub plate_heat: f64,
    /// Heat of the sources so far, `Σ Q_p V_p Δt` (J/m).
    pub source_heat: f64,
    /// Sum of the magnitudes of the per-step heat terms (J/m), the scale of the balance.
    pub heat_scale: f64,
}

/// One row of the history.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ColumnRecord {
    /// Time since the start (s).
    pub time: f64,
    /// Time since the release (s; negative while settling).
    pub time_after_release: f64,
    /// `E_p = Σ m g h` (J/m).
    pub potential_energy: f64,
    /// `E_k = Σ ½ m v²` (J/m).
    pub kinetic_energy: f64,
    /// `E_p / E_p0` with `E_p0` at the release (1 before).
    pub potential_ratio: f64,
    /// `E_k / E_p0`.
    pub kinetic_ratio: f64,
    /// Displacement of the top-right corner point since the release (m).
    pub corner_displacement: f64,
    /// Intact bonds on the heated half (`x < W/2` at the start).
    pub bonds_intact_heated: u64,
    /// Intact bonds on the other half.
    pub bonds_intact_other: u64,
    /// Bonds broken on the heated half since the release.
    pub bonds_broken_heated: u64,
    /// Bonds broken on the other half since the release.
    pub bonds_broken_other: u64,
    /// Stored heat `Σ m c (T − T₀)` (J/m).
    pub stored_heat: f64,
    /// Heat in from the plate so far (J/m).
    pub plate_heat: f64,
    /// Heat of the sources so far (J/m).
    pub source_heat: f64,
    /// `(stored − plate − sources) / scale` with the scale the sum of the per-step heat
    /// magnitudes (0 before any heat moved).
    pub heat_balance_residual: f64,
    /// Largest point temperature (°C).
    pub max_temperature: f64,
    /// Mean temperature rise of the heated half (K).
    pub mean_rise_heated: f64,
    /// Rightmost point edge (m): the runout.
    pub runout: f64,
}

/// The column collapse as a case of the multiscale skeleton: its parameters, what the
/// consolidation gave, and what its protocol and records need.
#[derive(Debug, Clone)]
pub struct Column {
    /// The parameters.
    pub test: ColumnTest,
    /// What the consolidation gave.
    pub packing: PackingReport,
    /// Flat indices of the heating plate's nodes.
    plate_nodes: Vec<usize>,
    /// Whether each point starts on the heated half.
    heated_half: Vec<bool>,
    /// The top-right corner point.
    corner: usize,
}

/// The column as a coupled model: two loading phases, settling (both plates, no heating, no
/// bonds) and the collapse after the release (right plate gone, heating plate, bonds if
/// any), each with its own material.
pub type ColumnModel = MultiscaleModel<Column>;

/// The phase while settling.
const SETTLE: usize = 0;
/// The phase after the release.
const COLLAPSE: usize = 1;

impl MultiscaleModel<Column> {
    /// Builds the column: consolidates the template packing, lays out the grid (one cell
    /// left of the heating plate, `runout_cells` to the right of the column, one below the
    /// ground and above the top), the points, the plates.
    pub fn new(t: &ColumnTest) -> Result<Self, MultiscaleError> {
        let (rve, packing, report) = column_packing(t)?;
        Self::with_packing(t, rve, packing, report)
    }

    /// Builds the column from a consolidated packing made by [`column_packing`] for `t`.
    pub fn with_packing(
        t: &ColumnTest,
        rve: RveParams,
        packing: RveState,
        report: PackingReport,
    ) -> Result<Self, MultiscaleError> {
        t.validate()?;
        let h = t.cell_size();
        let mut params = MpmParameters::on_grid(GridParameters {
            origin: [-h, -h],
            cell_size: h,
            cells: [t.cells[0] + t.runout_cells + 1, t.cells[1] + 2],
        });
        params.grid_damping = t.grid_damping;
        params.gravity = [0.0, -t.gravity];
        let dx = h / t.points_per_cell as f64;
        params.node_mass_tolerance = t.node_mass_fraction * report.bulk_density * dx * dx;
        let wall = |point: [f64; 2], normal: [f64; 2], friction: f64| RigidWall {
            point,
            normal,
            velocity: [0.0, 0.0],
            friction,
            removal_time: None,
            extent: None,
            depth: None,
        };
        let ground = wall([0.0, 0.0], [0.0, 1.0], t.ground_friction);
        let left = wall([0.0, 0.0], [1.0, 0.0], t.plate_friction);
        let right = wall([t.width, 0.0], [-1.0, 0.0], t.plate_friction);
        let mut settle = params.clone();
        settle.pic_fraction = t.settle_pic_fraction;
        settle.walls = vec![ground, left, right];
        let mut collapse = params;
        collapse.pic_fraction = t.pic_fraction;
        collapse.walls = vec![ground, left];
        let plate = NodeSet::Region {
            lower: [-1e-9 * h, -h],
            upper: [1e-9 * h, t.height + 2.0 * h],
        };
        collapse.temperature_conditions = vec![TemperatureCondition {
            nodes: plate,
            temperature: t.plate_temperature,
        }];
        let settle_config = MpmConfig::new(settle)?;
        let collapse_config = MpmConfig::new(collapse)?;
        let grid = collapse_config.grid();
        let [nx_nodes, ny_nodes] = grid.nodes();
        let mut plate_nodes = Vec::new();
        for j in 0..ny_nodes {
            for i in 0..nx_nodes {
                if plate.contains(grid, i, j) {
                    plate_nodes.push(grid.node_index(i, j));
                }
            }
        }
        let offset = rve.reference_temperature - t.initial_temperature;
        let settle_material = RveMaterial::new(
            &MultiscaleParams {
                rve,
                dem_time: t.dem_time,
                kelvin_offset: offset,
                quasi_static: None,
            },
            packing.clone(),
        )?;
        let collapse_material = RveMaterial::new(
            &MultiscaleParams {
                rve: t.bonded_rve(&rve),
                dem_time: t.dem_time,
                kelvin_offset: offset,
                quasi_static: None,
            },
            packing,
        )?;
        let mut points = MaterialPoints::new();
        points.fill_rectangle(
            settle_config.grid(),
            [0.0, 0.0],
            [t.width, t.height],
            t.points_per_cell,
            &PointProperties {
                density: report.bulk_density,
                specific_heat: t.specific_heat,
                conductivity: settle_material.initial_conductivity(),
                temperature: t.initial_temperature,
                velocity: [0.0; 2],
            },
        )?;
        let heated_half = points
            .position
            .iter()
            .map(|x| x[0] < 0.5 * t.width)
            .collect();
        let nx = t.cells[0] * t.points_per_cell;
        let ny = t.cells[1] * t.points_per_cell;
        let corner = ny * nx - 1;
        let state = settle_material.state(points);
        let case = Column {
            test: *t,
            packing: report,
            plate_nodes,
            heated_half,
            corner,
        };
        let phases = vec![
            LoadingPhase {
                mpm: Mpm::new(settle_config),
                material: 0,
            },
            LoadingPhase {
                mpm: Mpm::new(collapse_config),
                material: 1,
            },
        ];
        Self::from_parts(
            case,
            state,
            phases,
            vec![settle_material, collapse_material],
        )
    }

    /// Intact bonds on the heated half and on the other.
    pub fn intact_bonds(&self) -> [u64; 2] {
        self.intact_bonds_of(&self.state)
    }

    /// Intact bonds of `state` on the heated half and on the other.
    pub fn intact_bonds_of(&self, state: &MpmState<RvePoint>) -> [u64; 2] {
        let mut n = [0u64; 2];
        for (r, heated) in state.material.iter().zip(&self.case.heated_half) {
            n[usize::from(!*heated)] += u64::from(r.intact_bonds);
        }
        n
    }

    /// `E_p = Σ m g h` and `E_k = Σ ½ m v²` (J/m).
    pub fn energies(&self) -> (f64, f64) {
        self.energies_of(&self.state)
    }

    /// `E_p` and `E_k` of `state` (J/m).
    pub fn energies_of(&self, state: &MpmState<RvePoint>) -> (f64, f64) {
        let pts = &state.points;
        let (mut ep, mut ek) = (0.0, 0.0);
        for ((m, x), v) in pts.mass.iter().zip(&pts.position).zip(&pts.velocity) {
            ep += m * self.case.test.gravity * x[1];
            ek += 0.5 * m * (v[0] * v[0] + v[1] * v[1]);
        }
        (ep, ek)
    }

    /// Stored heat `Σ m c (T − T₀)` (J/m).
    pub fn stored_heat(&self) -> f64 {
        self.stored_heat_of(&self.state)
    }

    /// Stored heat of `state` (J/m).
    pub fn stored_heat_of(&self, state: &MpmState<RvePoint>) -> f64 {
        stored_heat(state, self.case.test.initial_temperature)
    }

    /// The release: bonds installed in every RVE (β_a > 0), `E_p0`, the corner position. In a
    /// distributed run every process first takes the current RVEs, so that the bonds are
    /// installed on the same disks everywhere.
    fn release(&mut self) -> Result<(), MultiscaleError> {
        if self.case.test.bond_strength > 0.0 {
            self.synchronise()?;
            for r in &mut self.state.material {
                r.rve.install_bonds();
                r.count_bonds();
            }
        }
        self.totals.released = true;
        self.totals.bonds_installed = self.intact_bonds();
        self.totals.potential_energy_at_release = self.energies().0;
        self.totals.corner_at_release = self.state.points.position[self.case.corner];
        Ok(())
    }

    /// Reduces every RVE cell whose basis has become skewed (`thm_rve::RveState::reduce_cell`:
    /// the same lattice, so nothing physical changes), see the module docs, choice 8.
    pub fn reduce_cells(&mut self) -> Result<(), MultiscaleError> {
        reduce_cells(&mut self.state)
    }
}

impl Protocol for Column {
    type Totals = ColumnTotals;
    type Record = ColumnRecord;
    type StepStart = HeatBefore;

    fn time_step(&self) -> f64 {
        self.test.time_step
    }

    fn steps(&self) -> u64 {
        self.test.steps()
    }

    fn phase(totals: &ColumnTotals) -> usize {
        if totals.released { COLLAPSE } else { SETTLE }
    }

    /// The release when the settling is over; the heat before the step.
    fn before_step(model: &mut ColumnModel) -> Result<HeatBefore, MultiscaleError> {
        if !model.totals.released && model.state.step >= model.case.test.settle_steps() {
            model.release()?;
        }
        let t = &model.case.test;
        flow_step_start(
            &mut model.state,
            t.friction_heat,
            t.time_step,
            t.initial_temperature,
        )
    }

    /// The heat that entered from the plate (read from the grid: the nodes' capacity times
    /// their temperature rate less their heat load) and the heat sums.
    fn after_step(
        model: &mut ColumnModel,
        phase: usize,
        before: HeatBefore,
    ) -> Result<(), MultiscaleError> {
        let dt = model.case.test.time_step;
        let mut plate = 0.0;
        if model.totals.released {
            let gf = model.phases[phase].mpm.grid_fields();
            for &i in &model.case.plate_nodes {
                let s = &gf.sums[i];
                plate += dt * (s.capacity * gf.temperature_rate[i] - s.heat_load);
            }
        }
        model.totals.plate_heat += plate;
        model.totals.source_heat += before.source;
        let stored_after = model.stored_heat();
        model.totals.heat_scale +=
            plate.abs() + before.source.abs() + (stored_after - before.stored).abs();
        Ok(())
    }

    fn record(
        model: &ColumnModel,
        state: &MpmState<RvePoint>,
        totals: &ColumnTotals,
    ) -> ColumnRecord {
        let case = &model.case;
        let pts = &state.points;
        let (ep, ek) = model.energies_of(state);
        let tot = totals;
        let ep0 = if tot.released {
            tot.potential_energy_at_release
        } else {
            ep
        };
        let corner = if tot.released {
            let x = pts.position[case.corner];
            let c = tot.corner_at_release;
            ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2)).sqrt()
        } else {
            0.0
        };
        let intact = model.intact_bonds_of(state);
        let broken = if tot.released {
            [
                tot.bonds_installed[0].saturating_sub(intact[0]),
                tot.bonds_installed[1].saturating_sub(intact[1]),
            ]
        } else {
            [0, 0]
        };
        let stored = model.stored_heat_of(state);
        let residual = if tot.heat_scale > 0.0 {
            (stored - tot.plate_heat - tot.source_heat) / tot.heat_scale
        } else {
            0.0
        };
        let t0 = case.test.initial_temperature;
        let (mut tmax, mut rise, mut n, mut runout) =
            (f64::NEG_INFINITY, 0.0, 0usize, f64::NEG_INFINITY);
        for p in 0..pts.len() {
            tmax = tmax.max(pts.temperature[p]);
            if case.heated_half[p] {
                rise += pts.temperature[p] - t0;
                n += 1;
            }
            runout = runout.max(pts.position[p][0] + pts.half_size[p][0]);
        }
        ColumnRecord {
            time: state.time,
            time_after_release: state.time - case.test.settle_steps() as f64 * case.test.time_step,
            potential_energy: ep,
            kinetic_energy: ek,
            potential_ratio: ep / ep0,
            kinetic_ratio: ek / ep0,
            corner_displacement: corner,
            bonds_intact_heated: intact[0],
            bonds_intact_other: intact[1],
            bonds_broken_heated: broken[0],
            bonds_broken_other: broken[1],
            stored_heat: stored,
            plate_heat: tot.plate_heat,
            source_heat: tot.source_heat,
            heat_balance_residual: residual,
            max_temperature: tmax,
            mean_rise_heated: rise / n.max(1) as f64,
            runout,
        }
    }
}
