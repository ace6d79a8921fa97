//! The 2D square of B-Sect. 5.2.2 (Zhao et al. 2022): `[0, 1]²` m, initially 0 °C, all sides
//! held at 100 °C with their normal displacement fixed, one material point per cell, each with
//! an RVE of disks with radii uniform in [0.25, 0.5] mm consolidated to 100 kPa; and its
//! pure-MPM twin with the moduli measured on the RVE.
//!
//! The grid, boundary conditions and points are those of `thm-mpm`'s own TM-MPM square
//! (`thm_mpm::setups::heated_square`), so the two models differ only in the material.

use serde::{Deserialize, Serialize};
use thm_mpm::{LinearThermoElastic, Mpm, MpmState, ThermoElasticParameters, setups::heated_square};
use thm_rve::{ConsolidationParams, PackingParams, RveParams, RveState, consolidate, measure};

use super::error::MultiscaleError;
use super::material::RveMaterial;
use super::params::{DemTimeRule, MultiscaleParams};
use super::point::RvePoint;

/// The square's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularSquare {
    /// Cells (one point each) along each side (the paper: 40).
    pub cells: usize,
    /// Disks per RVE (the paper: 400).
    pub disks: usize,
    /// Seed of the packing.
    pub seed: u64,
    /// Friction coefficient of the contacts after consolidation (the packing is consolidated
    /// with `rve.contact.friction_coefficient`).
    pub shear_friction: f64,
    /// Conductivity k (W/(m K)) that sets α of B-Eq. 34 (mean of the packing's diagonal).
    pub conductivity: f64,
    /// MPM time step (s).
    pub time_step: f64,
    /// RVE contact law, density, expansion, thickness (α is replaced).
    pub rve: RveParams,
    /// The DEM time rule.
    pub dem_time: DemTimeRule,
    /// Whether the friction heat of the RVEs (B-Eqs. 32–33) heats the points (the paper's
    /// model). With B-Table 1's `ρ c = 1 J/(m³ K)` the friction work of the heated RVEs raises
    /// the square's temperature by tens of kelvin (see `verification::multiscale`); B-Eq. 59 is
    /// conduction alone, so the verification runs with it off and reports the work.
    #[serde(default = "friction_heat_default")]
    pub friction_heat: bool,
}

fn friction_heat_default() -> bool {
    true
}

impl GranularSquare {
    /// B-Sect. 5.2.2 with B-Table 1 at a reduced size: `cells × cells` points with
    /// `disks`-disk RVEs (radii in [0.25, 0.5] mm, seed 1, consolidated with μ = 0.001 to
    /// 100 kPa, then μ = 0.5: with μ = 0.001 the packing has almost no shear stiffness, the
    /// points next to the held sides shear without bound and an RVE cell collapses within
    /// 0.4 s; `thm-rve` finds the paper's E and ν of this packing only with μ = 0.5), α set for k = 0.1 W/(m K), Δt = 2·10⁻⁴ s (B-Eq. 30 allows 2.45·10⁻⁴ s once the
    /// heated RVEs stiffen), the disks density-scaled by
    /// `density_scaling`.
    pub fn reduced(cells: usize, disks: usize, density_scaling: f64) -> Self {
        Self {
            cells,
            disks,
            seed: 1,
            shear_friction: 0.5,
            conductivity: 0.1,
            time_step: 2e-4,
            rve: RveParams::paper_b_table_1(),
            dem_time: DemTimeRule {
                step_fraction: 0.2,
                density_scaling,
            },
            friction_heat: true,
        }
    }
}

/// The consolidated packing of B-Sect. 5.2.2 (random radii in [0.25, 0.5] mm, 100 kPa) with
/// α of B-Eq. 34 set so that the mean of its conductivity's diagonal is `k`.
pub fn square_packing(sq: &GranularSquare) -> Result<(RveParams, RveState), MultiscaleError> {
    let mut p = sq.rve;
    p.thermal_resistance = 1.0;
    let config = p.validate().map_err(MultiscaleError::RveSetup)?;
    let mut pp = PackingParams::paper_b(sq.seed);
    pp.disk_count = sq.disks;
    let mut state = thm_rve::random_packing(&pp, &config).map_err(MultiscaleError::RveSetup)?;
    consolidate(
        &mut state,
        &config,
        &ConsolidationParams::isotropic(1e5, p.contact.friction_coefficient),
    )
    .map_err(MultiscaleError::RveSetup)?;
    let k1 = measure::conductivity(&state, &p);
    if !(sq.conductivity.is_finite() && sq.conductivity > 0.0) {
        return Err(MultiscaleError::InvalidParameter {
            field: "conductivity",
            value: sq.conductivity,
            allowed: "(0, inf) W/(m K)",
        });
    }
    p.thermal_resistance = 0.5 * (k1.at(0, 0) + k1.at(1, 1)) / sq.conductivity;
    p.contact.friction_coefficient = sq.shear_friction;
    Ok((p, state))
}

/// The square as a coupled model, with its pure-MPM twin.
#[derive(Debug, Clone)]
pub struct SquareModel {
    /// The MPM stepper of the multiscale model.
    pub mpm: Mpm,
    /// Points with their RVEs.
    pub state: MpmState<RvePoint>,
    /// The RVE-backed material.
    pub material: RveMaterial,
    /// The twin's stepper.
    pub twin_mpm: Mpm,
    /// The twin's state.
    pub twin_state: MpmState<()>,
    /// The twin's material: thermo-elastic with the RVE's affine moduli (B-Eq. 58) and
    /// conductivity.
    pub twin_material: LinearThermoElastic,
    /// Young's modulus and Poisson's ratio of the twin, `[E, ν]`.
    pub twin_moduli: [f64; 2],
    /// The parameters.
    pub square: GranularSquare,
}

impl SquareModel {
    /// Builds both models.
    pub fn new(sq: &GranularSquare) -> Result<Self, MultiscaleError> {
        let (rve, packing) = square_packing(sq)?;
        let base = heated_square(sq.cells)?;
        let material = RveMaterial::new(
            &MultiscaleParams {
                rve,
                dem_time: sq.dem_time,
                kelvin_offset: rve.reference_temperature,
                quasi_static: None,
            },
            packing,
        )?;
        let state = material.state(base.state.points.clone());
        // 2D: D_xxxx = K + G, D_xxyy = K − G (B-Sect. 5.2.2), ν = (K − G)/(K + G),
        // E = 2 K (1 − ν); averaged over the two axes.
        let d = measure::stiffness(&material.initial_point().rve, &rve);
        let k_plus_g = 0.5 * (d[0][0][0][0] + d[1][1][1][1]);
        let k_minus_g = 0.5 * (d[0][0][1][1] + d[1][1][0][0]);
        let nu = k_minus_g / k_plus_g;
        let e = (k_plus_g + k_minus_g) * (1.0 - nu);
        let k = material.initial_conductivity();
        let kbar = 0.5 * (k[0] + k[1]);
        let twin_material = LinearThermoElastic::new(&ThermoElasticParameters {
            youngs_modulus: e,
            poisson_ratio: nu,
            thermal_expansion: rve.thermal_expansion_coefficient,
            conductivity: [kbar, kbar, 0.0],
        })?;
        let twin_state = MpmState::new(base.state.points.clone(), &twin_material);
        Ok(Self {
            twin_mpm: base.mpm.clone(),
            mpm: base.mpm,
            state,
            material,
            twin_state,
            twin_material,
            twin_moduli: [e, nu],
            square: *sq,
        })
    }

    /// One step of both models.
    pub fn step(&mut self) -> Result<(), MultiscaleError> {
        let dt = self.square.time_step;
        self.mpm
            .step_batch(&mut self.state, &mut self.material, dt)?;
        if !self.square.friction_heat {
            // The next step's heat load (B-Eq. 18) reads the points' heat source.
            self.state.points.heat_source.fill(0.0);
        }
        self.twin_mpm
            .step(&mut self.twin_state, &self.twin_material, dt)?;
        Ok(())
    }

    /// Heat the RVEs' friction work of the last step would deliver to the points,
    /// `Σ_p W_f,p V_p / V_RVE,p` (J per metre of thickness), whether or not it is applied.
    pub fn friction_heat_of_step(&self) -> f64 {
        self.state
            .material
            .iter()
            .zip(&self.state.points.volume)
            .map(|(pt, v)| pt.friction_work * v / pt.rve_volume)
            .sum()
    }

    /// Mean of a per-point value over the four points around the centre (`cells` even) or
    /// the centre point (`cells` odd).
    pub fn at_centre(&self, value: impl Fn(usize) -> f64) -> f64 {
        centre_value(self.square.cells, value)
    }
}

/// Mean of a per-point value over the four points around the centre of a `cells × cells`
/// square of points numbered row by row (`cells` even), or the centre point (`cells` odd).
pub fn centre_value(cells: usize, value: impl Fn(usize) -> f64) -> f64 {
    let n = cells;
    if n % 2 == 1 {
        return value((n / 2) * n + n / 2);
    }
    let (a, b) = (n / 2 - 1, n / 2);
    0.25 * (value(a * n + a) + value(a * n + b) + value(b * n + a) + value(b * n + b))
}

/// B-Eq. 59 (corrected) for orthotropic diffusivities `(κ_x, κ_y)` on the unit square held at
/// `t1` from `t0`: `T₁ − (T₁ − T₀) θ(x; κ_x) θ(y; κ_y)` (°C).
pub fn square_temperature(x: [f64; 2], t: f64, kappa: [f64; 2], t0: f64, t1: f64) -> f64 {
    t1 - (t1 - t0) * slab_factor(x[0], 1.0, kappa[0], t) * slab_factor(x[1], 1.0, kappa[1], t)
}

/// `θ(x, t)` of a slab `[0, L]` whose faces are held at the boundary temperature:
/// `(4/π) Σ_m sin((2m+1)πx/L) e^{−(2m+1)² π² κ t/L²}/(2m+1)`, so that the square with
/// orthotropic conductivity `(k_xx, k_yy)` has `T = T₁ − (T₁ − T₀) θ(x; κ_x) θ(y; κ_y)`; with
/// `κ_x = κ_y` this is B-Eq. 59 with the exponent `π²((2m+1)² + (2n+1)²) κ t/L²` (printed as
/// `π²(m² + n²)`).
pub fn slab_factor(x: f64, length: f64, kappa: f64, t: f64) -> f64 {
    use std::f64::consts::PI;
    let mut s = 0.0;
    for m in 0..2000 {
        let a = (2 * m + 1) as f64;
        let e = (-PI * PI * a * a * kappa * t / (length * length)).exp();
        if e < 1e-18 {
            break;
        }
        s += e / a * (a * PI * x / length).sin();
    }
    4.0 / PI * s
}
