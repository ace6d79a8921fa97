//! The biaxial compression test of B-Sect. 5.3.1 of Zhao et al. (2022): a 1 m × 2 m specimen,
//! 10 × 20 cells with 2 × 2 material points each, every point carrying an RVE of 400 disks
//! (radii in [0.25, 0.5] mm) consolidated to 100 kPa with μ = 0.01 (dense, void ratio 0.165 in
//! the paper) or μ = 0.5 (loose, 0.236) and sheared with μ = 0.5; a confining stress of
//! 100 kPa on both lateral sides; rough plates at the bottom and the top, the top one pushed
//! down at 0.02 m/s to 20 % axial strain with Δt = 10⁻³ s.
//!
//! ## Choices
//!
//! 1. **Plates.** Two rigid walls of `thm-mpm` with infinite friction (no slip while in
//!    contact): the bottom one at rest at `y = 0`, the top one moving down at the plate speed
//!    from `y = H`. The paper says "the loading plate is pushed downwards", one plate; the
//!    axial strain is the top plate's travel over `H`. Limitation: a wall acts on the nodes on
//!    or behind its line, so when the top plate's line passes a node row (every `h / H` of
//!    strain: 5 % on the paper's grid) that row, interior until then, is tied to the plate;
//!    probes on a 4 × 8 grid show the stress ratio jumping up as it happens (12.5 %). The
//!    verification grid (h = 0.5 m) is free of it up to 25 %.
//! 2. **Confinement.** A follower pressure on each side: for every boundary point the force
//!    `σ_c` times the current image `F · (0, 2 l_y)` of its vertical edge, turned to push
//!    inwards, re-set before every step ([`BiaxialModel::update_confinement`]) as
//!    `thm_mpm::SurfaceLoad`s on small boxes around the points, so the pressure stays on the
//!    bulging side and on its current length. The virtual-layer load of B-Eq. 17 spreads a
//!    point's force with the point's own weights: on the outer column alone only `N_I(x_p)`
//!    of it reaches the surface nodes (3/4 with 2 points per cell, 1/2 with one), and the
//!    specimen settles at that fraction of the confinement (a probe with one point per cell
//!    held σ̄_xx at 49 kPa for 100 kPa). The force is therefore put on the boundary point
//!    with weight 3/2 and on its inner neighbour with −1/2: within a cell the weights are
//!    linear, so this is the linear extrapolation of the weights to the surface (half a
//!    point spacing out), exact while both points and the surface share a cell. It needs
//!    at least 2 points per cell along x.
//! 3. **Small-mass nodes.** When a bulging side grazes a node line, the node beyond gets a
//!    sliver of a point's mass but a finite share of its internal force; its velocity, and
//!    the point's velocity gradient, blow up (a probe stretched the boundary points by 8–17 %
//!    laterally within 2–3 % axial strain until their RVEs lost every contact, with the
//!    confinement on the outer points alone as well). Nodes with less than
//!    `node_mass_fraction` (1 %) of a point's mass are left out of the velocity update
//!    (`thm_mpm::MpmParameters::node_mass_tolerance`).
//! 4. **RVEs at rest.** The consolidated packing's residual velocities are set to zero
//!    before the density scaling, which would multiply their kinetic energy by `s` (a probe
//!    with `s = 10⁵` started with 11 times the elastic energy as kinetic energy).
//! 5. **Thermal boundaries.** The paper states none: all boundaries adiabatic (no prescribed
//!    temperature, no flux). Temperature uniform at `initial_temperature` (°C; the paper does
//!    not state it, 20 °C by default); the RVEs see `T − T₀ + T_ref`, so their disks keep the
//!    consolidated radii at the start (B-Eq. 37).
//! 6. **Thermal properties.** B-Sect. 5.3.1 gives "thermal resistance 10³ K/(W m) for an
//!    initial thermal conductivity of 1.6 W/(m K)": α of B-Eq. 34 is set so that the
//!    consolidated packing conducts 1.6 W/(m K) (mean of its diagonal), as for the rod and
//!    the square, and the α it implies is reported. Specific heat 670 J/(kg K).
//! 7. **Bulk density.** The paper does not state the points' density: `ρ_s / (1 + e)` with
//!    `e` the consolidated packing's void ratio.
//! 8. **Stress ratio.** From the plate reaction, as B-Fig. 13 plots it and as a laboratory
//!    test measures it: `σ_yy` = the top plate's reaction over the initial width (the rough
//!    plate holds the top row of points, so the contact width stays `W`), ratio
//!    `(σ_yy − σ_c)/(σ_yy + σ_c)` (the mobilised `sin φ` in 2D). The same ratio of the
//!    volume-averaged point stresses `σ̄ = Σ σ_p V_p / Σ V_p` is recorded beside it; it differs
//!    because the rough plates restrain the ends, so `σ̄_xx` exceeds `σ_c` (a probe at 3 %
//!    strain: 118 kPa), as the mean-stress theorem `σ̄ A = ∮ t ⊗ x ds` says it must.
//! 9. **Heat accounting.** The heat generated in a step is `Σ_p Q_p V_p Δt` with the heat
//!    source the RVEs return (B-Eq. 33) and the point volume the next step's scatter uses; the
//!    friction work is the change of every RVE's running total of B-Eq. 32, upscaled by
//!    `V_p / V_RVE` (the RVE is a sample of the point). Both are summed over the run.
//!
//! Histories ([`BiaxialRecord`]) per step: axial strain, stress ratio, plate stress, mean
//! stresses, volumetric strain `ΔA/A₀` (dilation positive), largest ΔT, heat generated,
//! friction work (raw over all RVEs, and upscaled), thermal energy `Σ m c (T − T₀)`.

use serde::{Deserialize, Serialize};
use thm_mpm::{
    GridParameters, MaterialPoints, Mpm, MpmConfig, MpmParameters, MpmState, PointProperties,
    RigidWall, SurfaceLoad,
};
use thm_rve::{RveParams, RveState};

use super::error::MultiscaleError;
use super::material::RveMaterial;
use super::model::{
    LoadingPhase, MultiscaleModel, PackingProtocol, PackingReport, Protocol, consolidated_packing,
};
use super::params::{
    DemTimeRule, MultiscaleParams, QuasiStaticLimits, check_counts, check_positive,
};
use super::point::RvePoint;

fn default_bond_shear_ratio() -> f64 {
    0.5
}

/// The initial state of the specimen (B-Sect. 5.3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Compaction {
    /// Consolidated with μ = 0.01 (void ratio 0.165 in the paper).
    Dense,
    /// Consolidated with μ = 0.5 (void ratio 0.236 in the paper).
    Loose,
}

impl Compaction {
    /// The friction coefficient of the consolidation.
    pub fn consolidation_friction(self) -> f64 {
        match self {
            Compaction::Dense => 0.01,
            Compaction::Loose => 0.5,
        }
    }
    /// The paper's void ratio after consolidation.
    pub fn paper_void_ratio(self) -> f64 {
        match self {
            Compaction::Dense => 0.165,
            Compaction::Loose => 0.236,
        }
    }
    /// `"dense"` or `"loose"`.
    pub fn name(self) -> &'static str {
        match self {
            Compaction::Dense => "dense",
            Compaction::Loose => "loose",
        }
    }
}

/// Parameters of the biaxial test (SI; temperatures in °C on the MPM side).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BiaxialTest {
    /// Dense or loose.
    pub compaction: Compaction,
    /// Specimen width W (m); the paper: 1.
    pub width: f64,
    /// Specimen height H (m); the paper: 2.
    pub height: f64,
    /// Cells along x and y (square cells: `W/nx = H/ny`); the paper: 10 × 20.
    pub cells: [usize; 2],
    /// Points per cell along each direction; the paper: 2 (4 per cell).
    pub points_per_cell: usize,
    /// Disks per RVE; the paper: 400.
    pub disks: usize,
    /// Seed of the packing.
    pub seed: u64,
    /// Friction coefficient of the consolidation (0.01 dense, 0.5 loose).
    pub consolidation_friction: f64,
    /// Friction coefficient while shearing; the paper: 0.5.
    pub shear_friction: f64,
    /// Confining stress σ_xx (Pa, compression positive); the paper: 100 kPa (also the
    /// consolidation stress of the RVEs).
    pub confining_stress: f64,
    /// Speed of the top plate (m/s, downwards); the paper: 0.02.
    pub plate_speed: f64,
    /// Axial strain at which the test ends; the paper: 0.2.
    pub target_strain: f64,
    /// MPM time step (s); the paper: 10⁻³.
    pub time_step: f64,
    /// Initial uniform temperature (°C); not stated in the paper.
    pub initial_temperature: f64,
    /// Specific heat capacity c (J/(kg K)); the paper: 670 (quartz).
    pub specific_heat: f64,
    /// Initial conductivity (W/(m K)) that sets α of B-Eq. 34; the paper: 1.6.
    pub conductivity: f64,
    /// PIC fraction α_PIC of B-Eq. 26 (not stated for this case).
    pub pic_fraction: f64,
    /// Grid damping α_g of B-Eq. 26 (not stated for this case).
    pub grid_damping: f64,
    /// Local non-viscous damping of the nodal forces (`thm_mpm::MpmParameters::local_damping`,
    /// not in the paper), in [0, 1); 0: none.
    #[serde(default)]
    pub mpm_local_damping: f64,
    /// Node mass tolerance of `thm-mpm` as a fraction of a point's mass, in [0, 1]: nodes
    /// with less mass are left out of the velocity update (the small-mass problem at the
    /// bulging sides, see the module docs).
    pub node_mass_fraction: f64,
    /// Merge the nodes below `node_mass_fraction` with their heavier row neighbour instead of
    /// leaving them out (`thm_mpm::MpmParameters::merge_small_mass_nodes`); default false.
    #[serde(default)]
    pub merge_small_mass_nodes: bool,
    /// RVE contact law, density, expansion, thickness, damping (α is replaced).
    pub rve: RveParams,
    /// The DEM time rule.
    pub dem_time: DemTimeRule,
    /// Bond strength coefficient β_b of B-Eq. 38 (`F_nb = β_b k_n R`); 0: no bonds. Bonds
    /// are installed after the consolidation at every contact carrying force, and do not
    /// melt (B-Fig. 18: the bonded biaxial tests).
    #[serde(default)]
    pub bond_strength: f64,
    /// μ_b of B-Eq. 39: the shear force at breakage over the normal breakage force; the
    /// paper: 0.5.
    #[serde(default = "default_bond_shear_ratio")]
    pub bond_shear_ratio: f64,
    /// Quasi-static limits enforced after every step (`None`: measured, not enforced).
    #[serde(default)]
    pub quasi_static: Option<QuasiStaticLimits>,
}

impl BiaxialTest {
    /// B-Sect. 5.3.1 with B-Table 1: 1 m × 2 m, 10 × 20 cells, 2 × 2 points per cell,
    /// 400-disk RVEs (seed 1), consolidation μ = 0.01 (dense) or 0.5 (loose), shearing
    /// μ = 0.5, 100 kPa, plate 0.02 m/s to 20 %, Δt = 10⁻³ s, c = 670 J/(kg K), k = 1.6
    /// W/(m K). Where the paper is silent: 20 °C initially, α_PIC = 0.1 and α_g = 0 (the
    /// silo's α_PIC of B-Sect. 5.3.2), the DEM time rule with density scaling 10⁴ (N = 8 DEM
    /// steps per MPM step; the inertial number at the nominal rate 0.01 /s is about 10⁻⁴).
    pub fn paper(compaction: Compaction) -> Self {
        Self {
            compaction,
            width: 1.0,
            height: 2.0,
            cells: [10, 20],
            points_per_cell: 2,
            disks: 400,
            seed: 1,
            consolidation_friction: compaction.consolidation_friction(),
            shear_friction: 0.5,
            confining_stress: 1e5,
            plate_speed: 0.02,
            target_strain: 0.2,
            time_step: 1e-3,
            initial_temperature: 20.0,
            specific_heat: 670.0,
            conductivity: 1.6,
            pic_fraction: 0.1,
            grid_damping: 0.0,
            mpm_local_damping: 0.0,
            node_mass_fraction: 0.01,
            merge_small_mass_nodes: false,
            rve: RveParams::paper_b_table_1(),
            dem_time: DemTimeRule {
                step_fraction: 0.2,
                density_scaling: 1e4,
            },
            quasi_static: None,
            bond_strength: 0.0,
            bond_shear_ratio: 0.5,
        }
    }

    /// A bonded biaxial test of B-Fig. 18 at the paper's size: the RVEs consolidated to
    /// `confining_stress` with μ = 0.5 (the loose protocol of B-Sect. 5.3.1; the paper's
    /// "medium-dense" void ratios 0.251, 0.240 and 0.232 at 10, 25 and 50 kPa lie near its
    /// 0.236), bonds of strength `bond_strength` (β_b, B-Eq. 38; μ_b = 0.5) installed at
    /// every contact carrying force after the consolidation, sheared with μ = 0.5 to 20 %.
    pub fn bonded(confining_stress: f64, bond_strength: f64) -> Self {
        let mut t = Self::paper(Compaction::Loose);
        t.confining_stress = confining_stress;
        t.bond_strength = bond_strength;
        t
    }

    /// The paper's test at a reduced size: `cells` (keeping the 1 × 2 aspect with square
    /// cells: `H = W · ny / nx`, `W = 1 m`), `points_per_cell` along each direction, `disks`
    /// per RVE, the disks density-scaled by `density_scaling`; everything else as
    /// [`BiaxialTest::paper`].
    pub fn reduced(
        compaction: Compaction,
        cells: [usize; 2],
        points_per_cell: usize,
        disks: usize,
        density_scaling: f64,
    ) -> Self {
        let mut t = Self::paper(compaction);
        t.cells = cells;
        t.height = t.width * cells[1] as f64 / cells[0].max(1) as f64;
        t.points_per_cell = points_per_cell;
        t.disks = disks;
        t.dem_time.density_scaling = density_scaling;
        t
    }

    /// The paper's void ratio after the consolidation of this test's packings, where it
    /// states one: B-Sect. 5.3.1 at 100 kPa (dense 0.165, loose 0.236) and the bonded tests
    /// of B-Fig. 18 at 10, 25 and 50 kPa (0.251, 0.240, 0.232, B-Sect. 5.3.3).
    pub fn paper_void_ratio(&self) -> Option<f64> {
        let at = |kpa: f64| (self.confining_stress - 1e3 * kpa).abs() <= 1e-9 * 1e3 * kpa;
        if at(100.0) {
            Some(self.compaction.paper_void_ratio())
        } else if self.compaction == Compaction::Loose && at(10.0) {
            Some(0.251)
        } else if self.compaction == Compaction::Loose && at(25.0) {
            Some(0.240)
        } else if self.compaction == Compaction::Loose && at(50.0) {
            Some(0.232)
        } else {
            None
        }
    }

    /// Cell size `W / nx` (m).
    pub fn cell_size(&self) -> f64 {
        self.width / self.cells[0] as f64
    }

    /// MPM steps to the target strain.
    pub fn steps(&self) -> u64 {
        (self.target_strain * self.height / (self.plate_speed * self.time_step)).round() as u64
    }

    /// Checks the geometry and the loading, naming the first bad field.
    pub fn validate(&self) -> Result<(), MultiscaleError> {
        let positive = [
            ("width", self.width),
            ("height", self.height),
            ("confining_stress", self.confining_stress),
            ("plate_speed", self.plate_speed),
            ("time_step", self.time_step),
            ("specific_heat", self.specific_heat),
            ("conductivity", self.conductivity),
        ];
        check_positive(&positive)?;
        check_counts(&[
            ("cells[0]", self.cells[0], 1, 10_000, "[1, 10000]"),
            ("cells[1]", self.cells[1], 1, 10_000, "[1, 10000]"),
            ("points_per_cell", self.points_per_cell, 2, 8, "[2, 8]"),
            ("disks", self.disks, 2, 1_000_000, "[2, 1000000]"),
        ])?;
        let h = self.cell_size();
        let hy = self.height / self.cells[1] as f64;
        if (h - hy).abs() > 1e-9 * h {
            return Err(MultiscaleError::InvalidParameter {
                field: "height",
                value: self.height,
                allowed: "cells[1] x width / cells[0] (square cells)",
            });
        }
        let ranges = [
            (
                "target_strain",
                self.target_strain,
                1e-6,
                0.5,
                "[1e-6, 0.5]",
            ),
            (
                "consolidation_friction",
                self.consolidation_friction,
                0.0,
                10.0,
                "[0, 10]",
            ),
            ("shear_friction", self.shear_friction, 0.0, 10.0, "[0, 10]"),
            ("bond_strength", self.bond_strength, 0.0, 10.0, "[0, 10]"),
            (
                "bond_shear_ratio",
                self.bond_shear_ratio,
                1e-6,
                1e6,
                "[1e-6, 1e6]",
            ),
            (
                "initial_temperature",
                self.initial_temperature,
                -273.15,
                1e4,
                "[-273.15, 1e4] degC",
            ),
            ("pic_fraction", self.pic_fraction, 0.0, 1.0, "[0, 1]"),
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
        if self.plate_speed * self.time_step > 0.05 * h {
            return Err(MultiscaleError::InvalidParameter {
                field: "plate_speed",
                value: self.plate_speed,
                allowed: "at most 5 % of a cell per time step",
            });
        }
        Ok(())
    }
}

/// The consolidated packing of the test (random radii in [0.25, 0.5] mm, `disks` disks,
/// consolidated isotropically to the confining stress with the consolidation friction), with
/// α of B-Eq. 34 set for the stated conductivity, μ set to the shear friction, and the bonds
/// of B-Fig. 18 where `bond_strength > 0` (B-Sect. 5.3.3: installed after the consolidation
/// at the contacts that carry force; they do not melt in these tests).
pub fn biaxial_packing(
    t: &BiaxialTest,
) -> Result<(RveParams, RveState, PackingReport), MultiscaleError> {
    t.validate()?;
    consolidated_packing(
        &t.rve,
        &PackingProtocol {
            seed: t.seed,
            disks: t.disks,
            stress: t.confining_stress,
            consolidation_friction: t.consolidation_friction,
            friction: t.shear_friction,
            conductivity: t.conductivity,
            bonds: (t.bond_strength > 0.0).then_some((t.bond_strength, t.bond_shear_ratio)),
        },
    )
}

/// Running sums of the test, carried in checkpoints with the state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BiaxialTotals {
    /// Heat generated so far, `Σ_steps Σ_p Q_p V_p Δt` (J per metre of thickness).
    pub heat_generated: f64,
    /// Friction work so far upscaled to the points, `Σ_steps Σ_p W_p V_p / V_RVE,p`
    /// (J per metre of thickness).
    pub friction_work_upscaled: f64,
    /// Friction work so far summed over all RVEs as they are, `Σ_steps Σ_p W_p` (J, in the
    /// RVEs' thickness z_p).
    pub friction_work_rves: f64,
    /// Heat generated in the last step (delivered to the grid in the next one).
    pub last_heat: f64,
    /// Work of the top plate so far, `Σ F_y v Δt` (J per metre of thickness).
    pub plate_work: f64,
}

/// One row of the history.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BiaxialRecord {
    /// Time (s).
    pub time: f64,
    /// Axial strain: top plate travel over H.
    pub axial_strain: f64,
    /// Stress ratio `(σ_yy − σ_c)/(σ_yy + σ_c)` with `σ_yy` the plate stress.
    pub stress_ratio: f64,
    /// Stress ratio `(σ̄_yy − σ̄_xx)/(σ̄_yy + σ̄_xx)` of the volume-averaged point stresses.
    pub point_stress_ratio: f64,
    /// Volume-averaged `σ_xx` of the points (Pa, compression positive).
    pub mean_sigma_xx: f64,
    /// Volume-averaged `σ_yy` of the points (Pa, compression positive).
    pub mean_sigma_yy: f64,
    /// Top plate reaction over the initial width (Pa, compression positive).
    pub plate_stress: f64,
    /// Volumetric strain `ΔA/A₀` (dilation positive).
    pub volumetric_strain: f64,
    /// Largest temperature rise of any point (K).
    pub max_temperature_rise: f64,
    /// Heat generated so far (J/m), see [`BiaxialTotals`].
    pub heat_generated: f64,
    /// Friction work so far upscaled to the points (J/m).
    pub friction_work_upscaled: f64,
    /// Friction work so far summed over all RVEs (J).
    pub friction_work_rves: f64,
    /// Thermal energy gained by the points `Σ m c (T − T₀)` (J/m).
    pub thermal_energy: f64,
    /// Work of the top plate so far (J/m).
    pub plate_work: f64,
    /// Largest inertial number of the RVEs that carry pressure, after the step.
    pub max_inertial_number: f64,
    /// Largest kinetic/elastic energy ratio of the RVEs that carry pressure, after the step.
    pub max_kinetic_ratio: f64,
    /// RVEs without pressure or contact energy (their inertial number or kinetic ratio is
    /// infinite: the cell has dilated until no contact carries force).
    pub rves_without_pressure: usize,
    /// Where the largest inertial number of any RVE sits, an infinite one included.
    #[serde(default)]
    pub max_inertial_at: PointPlace,
    /// Where the largest kinetic/elastic energy ratio of any RVE sits, an infinite one
    /// included.
    #[serde(default)]
    pub max_kinetic_at: PointPlace,
}

/// A material point and its position at a record: where a measure peaks.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PointPlace {
    /// Point index.
    pub point: usize,
    /// Its position (m).
    pub position: [f64; 2],
    /// The measure's value there.
    pub value: f64,
}

impl PointPlace {
    /// The point of largest `value(p)` (NaN above +inf, the first of equals), with its
    /// position; point 0 with value 0 when there is none.
    pub fn largest(positions: &[[f64; 2]], value: impl Fn(usize) -> f64) -> Self {
        let mut best = Self::default();
        let mut first = true;
        for (p, x) in positions.iter().enumerate() {
            let v = value(p);
            if first || v.total_cmp(&best.value).is_gt() {
                best = Self {
                    point: p,
                    position: *x,
                    value: v,
                };
                first = false;
            }
        }
        best
    }
}

/// The biaxial test as a case of the multiscale skeleton: its parameters, what the
/// consolidation gave, and the boundary points the confinement follows.
#[derive(Debug, Clone)]
pub struct Biaxial {
    /// The parameters.
    pub test: BiaxialTest,
    /// What the consolidation gave.
    pub packing: PackingReport,
    /// Left boundary points (outer column), bottom to top.
    left: Vec<usize>,
    /// Right boundary points (outer column), bottom to top.
    right: Vec<usize>,
    /// Specimen area at the start (m² per metre).
    initial_area: f64,
}

/// The test as a coupled model: one loading phase (the plates and the confinement), one
/// material.
pub type BiaxialModel = MultiscaleModel<Biaxial>;

/// Index of the top plate among the walls.
const TOP_WALL: usize = 1;

impl MultiscaleModel<Biaxial> {
    /// Builds the specimen: consolidates the template packing, lays out the grid (padding of
    /// half the width on each side for the bulge, one cell below and above), the points, the
    /// two plates and the confinement.
    pub fn new(t: &BiaxialTest) -> Result<Self, MultiscaleError> {
        let (rve, packing, report) = biaxial_packing(t)?;
        Self::with_packing(t, rve, packing, report)
    }

    /// Builds the specimen from a consolidated packing made by [`biaxial_packing`] for `t`.
    pub fn with_packing(
        t: &BiaxialTest,
        rve: RveParams,
        packing: RveState,
        report: PackingReport,
    ) -> Result<Self, MultiscaleError> {
        t.validate()?;
        let h = t.cell_size();
        let pad = (t.cells[0] / 2).max(2);
        let mut params = MpmParameters::on_grid(GridParameters {
            origin: [-(pad as f64) * h, -h],
            cell_size: h,
            cells: [t.cells[0] + 2 * pad, t.cells[1] + 2],
        });
        params.pic_fraction = t.pic_fraction;
        params.grid_damping = t.grid_damping;
        params.local_damping = t.mpm_local_damping;
        params.merge_small_mass_nodes = t.merge_small_mass_nodes;
        let dx = h / t.points_per_cell as f64;
        params.node_mass_tolerance = t.node_mass_fraction * report.bulk_density * dx * dx;
        params.walls = vec![
            RigidWall {
                point: [0.0, 0.0],
                normal: [0.0, 1.0],
                velocity: [0.0, 0.0],
                friction: f64::INFINITY,
                removal_time: None,
                extent: None,
                depth: None,
            },
            RigidWall {
                point: [0.0, t.height],
                normal: [0.0, -1.0],
                velocity: [0.0, -t.plate_speed],
                friction: f64::INFINITY,
                removal_time: None,
                extent: None,
                depth: None,
            },
        ];
        let config = MpmConfig::new(params)?;
        let material = RveMaterial::new(
            &MultiscaleParams {
                rve,
                dem_time: t.dem_time,
                kelvin_offset: rve.reference_temperature - t.initial_temperature,
                quasi_static: t.quasi_static,
            },
            packing,
        )?;
        let mut points = MaterialPoints::new();
        let k = material.initial_conductivity();
        points.fill_rectangle(
            config.grid(),
            [0.0, 0.0],
            [t.width, t.height],
            t.points_per_cell,
            &PointProperties {
                density: report.bulk_density,
                specific_heat: t.specific_heat,
                conductivity: k,
                temperature: t.initial_temperature,
                velocity: [0.0; 2],
            },
        )?;
        let nx = t.cells[0] * t.points_per_cell;
        let ny = t.cells[1] * t.points_per_cell;
        let left = (0..ny).map(|j| j * nx).collect();
        let right = (0..ny).map(|j| j * nx + nx - 1).collect();
        let state = material.state(points);
        let initial_area = state.points.volume.iter().sum();
        let case = Biaxial {
            test: *t,
            packing: report,
            left,
            right,
            initial_area,
        };
        let phase = LoadingPhase {
            mpm: Mpm::new(config),
            material: 0,
        };
        let mut m = Self::from_parts(case, state, vec![phase], vec![material])?;
        m.update_confinement()?;
        Ok(m)
    }

    /// Re-sets the confining loads from the boundary points' current positions and
    /// deformation gradients (see the module docs, choice 2).
    pub fn update_confinement(&mut self) -> Result<(), MultiscaleError> {
        let pts = &self.state.points;
        let c = &self.case;
        let s = c.test.confining_stress;
        let mut loads = Vec::with_capacity(c.left.len() + c.right.len());
        for (side, list) in [(1.0, &c.left), (-1.0, &c.right)] {
            for &p in list {
                let f = pts.deformation_gradient[p];
                let l = 2.0 * pts.half_size[p][1];
                // Image of the vertical edge (0, l): (F_xy l, F_yy l).
                let e = [f[1] * l, f[3] * l];
                // Left side: σ (e_y, −e_x); right side: σ (−e_y, e_x).
                let force = [side * s * e[1], -side * s * e[0]];
                // Linear extrapolation to the surface: the boundary point (weight 3/2) and
                // its inner neighbour (weight −1/2, one point spacing further in).
                let q = if side > 0.0 { p + 1 } else { p - 1 };
                for (k, w) in [(p, 1.5), (q, -0.5)] {
                    let xk = pts.position[k];
                    let eps = 1e-6 * pts.half_size[k][0];
                    loads.push(SurfaceLoad {
                        lower: [xk[0] - eps, xk[1] - eps],
                        upper: [xk[0] + eps, xk[1] + eps],
                        layer_thickness: pts.volume[k],
                        traction: [w * force[0], w * force[1]],
                        inward_heat_flux: 0.0,
                    });
                }
            }
        }
        self.phases[0].mpm.set_surface_loads(loads)?;
        Ok(())
    }

    /// Axial strain (top plate travel over H).
    pub fn axial_strain(&self) -> f64 {
        self.case.test.plate_speed * self.state.time / self.case.test.height
    }
}

impl Protocol for Biaxial {
    type Totals = BiaxialTotals;
    type Record = BiaxialRecord;
    type StepStart = ();

    fn time_step(&self) -> f64 {
        self.test.time_step
    }

    fn steps(&self) -> u64 {
        self.test.steps()
    }

    fn phase(_totals: &BiaxialTotals) -> usize {
        0
    }

    /// The confinement from the current boundary.
    fn before_step(model: &mut BiaxialModel) -> Result<(), MultiscaleError> {
        model.update_confinement()
    }

    /// The heat and friction-work sums and the plate work.
    fn after_step(model: &mut BiaxialModel, _phase: usize, (): ()) -> Result<(), MultiscaleError> {
        let dt = model.case.test.time_step;
        let pts = &model.state.points;
        let (mut heat, mut up, mut raw) = (0.0, 0.0, 0.0);
        for ((q, v), r) in pts
            .heat_source
            .iter()
            .zip(&pts.volume)
            .zip(&model.state.material)
        {
            heat += q * v * dt;
            up += r.friction_work * v / r.rve_volume;
            raw += r.friction_work;
        }
        let totals = &mut model.totals;
        totals.heat_generated += heat;
        totals.friction_work_upscaled += up;
        totals.friction_work_rves += raw;
        totals.last_heat = heat;
        let force = model.phases[0]
            .mpm
            .wall_reactions()
            .get(TOP_WALL)
            .map_or(0.0, |r| r[1]);
        model.totals.plate_work += force * model.case.test.plate_speed * dt;
        Ok(())
    }

    /// The confinement of the restored boundary.
    fn restored(model: &mut BiaxialModel) -> Result<(), MultiscaleError> {
        model.update_confinement()
    }

    fn record(
        model: &BiaxialModel,
        state: &MpmState<RvePoint>,
        totals: &BiaxialTotals,
    ) -> BiaxialRecord {
        let test = &model.case.test;
        let pts = &state.points;
        let t0 = test.initial_temperature;
        let sc = test.confining_stress;
        let (mut sxx, mut syy, mut area, mut eth, mut dt_max) = (0.0, 0.0, 0.0, 0.0, 0.0_f64);
        for p in 0..pts.len() {
            let v = pts.volume[p];
            sxx -= pts.stress[p][0] * v;
            syy -= pts.stress[p][1] * v;
            area += v;
            let rise = pts.temperature[p] - t0;
            eth += pts.mass[p] * pts.specific_heat[p] * rise;
            dt_max = dt_max.max(rise);
        }
        let (sxx, syy) = (sxx / area, syy / area);
        let (mut inertial, mut kinetic, mut loose_rves) = (0.0_f64, 0.0_f64, 0usize);
        for r in &state.material {
            if r.inertial_number.is_finite() && r.kinetic_ratio.is_finite() {
                inertial = inertial.max(r.inertial_number);
                kinetic = kinetic.max(r.kinetic_ratio);
            } else {
                loose_rves += 1;
            }
        }
        let plate = model.phases[0]
            .mpm
            .wall_reactions()
            .get(TOP_WALL)
            .map_or(0.0, |r| r[1] / test.width);
        let initial_area = model.case.initial_area;
        BiaxialRecord {
            time: state.time,
            axial_strain: test.plate_speed * state.time / test.height,
            stress_ratio: (plate - sc) / (plate + sc),
            point_stress_ratio: (syy - sxx) / (syy + sxx),
            mean_sigma_xx: sxx,
            mean_sigma_yy: syy,
            plate_stress: plate,
            volumetric_strain: (area - initial_area) / initial_area,
            max_temperature_rise: dt_max,
            heat_generated: totals.heat_generated,
            friction_work_upscaled: totals.friction_work_upscaled,
            friction_work_rves: totals.friction_work_rves,
            thermal_energy: eth,
            plate_work: totals.plate_work,
            max_inertial_number: inertial,
            max_kinetic_ratio: kinetic,
            rves_without_pressure: loose_rves,
            max_inertial_at: PointPlace::largest(&pts.position, |p| {
                state.material[p].inertial_number.abs()
            }),
            max_kinetic_at: PointPlace::largest(&pts.position, |p| {
                state.material[p].kinetic_ratio.abs()
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::PointPlace;

    /// The history names the RVE in free flight (infinite ratio) before any finite one, a
    /// NaN above both, and the first of equal values.
    #[test]
    fn the_largest_measure_names_its_point_and_place() {
        let x = [[0.0, 0.0], [1.0, 0.5], [0.5, 2.0], [0.25, 1.0]];
        let at = PointPlace::largest(&x, |p| [0.1, f64::INFINITY, 0.3, f64::INFINITY][p]);
        assert_eq!((at.point, at.position), (1, [1.0, 0.5]));
        let at = PointPlace::largest(&x, |p| [0.1, f64::INFINITY, f64::NAN, 0.0][p]);
        assert_eq!(at.point, 2);
        let at = PointPlace::largest(&x, |_| 0.2);
        assert_eq!((at.point, at.value), (0, 0.2));
        assert_eq!(PointPlace::largest(&[], |_| 1.0), PointPlace::default());
    }
}
