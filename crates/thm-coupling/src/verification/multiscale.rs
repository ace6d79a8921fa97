//! Verification cases of the MPM×DEM scheme (collected by `thm_coupling::verification`).
//!
//! 1. `coupling/mpm_dem_rod` (B-Sect. 5.2.1, not quick): the paper's run, 1 s in 10⁴ steps,
//!    50 RVEs of 400 disks, physical disk masses (N = 5 DEM steps per MPM step). Temperature
//!    against B-Eq. 55 at 0.1, 0.4 and 1 s (≤ 0.5 °C, the bound); the axial stress
//!    change against B-Eq. 56 with K = D_xxxx of B-Eq. 58 measured on the RVE, over every
//!    point and every 10 ms from 0.4 s to 1 s; the displacement against B-Eq. 57 (as derived,
//!    the printed form has `cos(nπx/x)`) at 0.4 s and 1 s; the quasi-static measures of the
//!    DEM time rule; K against B-Table 1's E = 13.3 MPa (reported).
//! 2. `coupling/mpm_dem_rod_quick`: the same rod for 0.5 s with 10 × 10 disks per RVE (a
//!    perfect lattice deforms affinely, so its stress, stiffness and conductivity do not
//!    depend on its size) density-scaled by 20 (N = 1 DEM step per MPM step), with the same
//!    bounds.
//! 3. `coupling/mpm_dem_square` (B-Sect. 5.2.2, not quick): the square at 16 × 16 points with
//!    100-disk RVEs density-scaled by 100 (N = 16), 1 s, against the paper's 40 × 40 points
//!    and 400 disks (about 100 times the DEM work: hours on two cores). On 16 × 16 the grid's
//!    own error at 1 s (0.45 °C, measured by the twin) is below the tolerance (0.85 °C on
//!    10 × 10); 100 disks give a packing whose conductivity is within 1.5 % of isotropic and
//!    whose affine E (16.2 MPa) is within 2 % of the 400-disk one (15.9 MPa).
//! 4. `coupling/mpm_dem_square_quick`: the same packing on 8 × 8 points for 0.25 s.
//!
//! The square's rows. **Temperature** (pass/fail, 0.5 °C): B-Eq. 59 is conduction with a
//! constant conductivity, while the RVEs' conductivity (B-Eq. 34) grows as the heating
//! compresses them (by 1–4 % over the run) and their friction work (B-Eqs. 32–33) is a heat
//! source: with B-Table 1's `ρ c = 1 J/(m³ K)` it would heat the square by 60–115 K-equivalent
//! (measured, independent of the density scaling from 20 to 400, so quasi-static; with
//! μ = 0.001 after consolidation it is larger still: 575 K on 4 × 4 points in 0.5 s). The cases therefore run with the
//! friction heat off (`GranularSquare::friction_heat`) and report the friction work; and
//! they compare with B-Eq. 59 with `κ t` replaced by `∫ κ̄(t) dt`, `κ̄` the points' mean RVE
//! conductivity (exact for a conductivity uniform in space and changing in time). On grids this
//! coarse the centre temperature carries the grid's own error (8.4 °C at 0.25 s on 10 × 10,
//! 0.45 °C at 1 s on 16 × 16; `mpm/heated_square` has 40 × 40 within 1 °C): the twin on the
//! same grid measures it against B-Eq. 59, and the row compares the multiscale temperature
//! less that error. The raw temperatures against B-Eq. 59 with the initial k are reported.
//! **Bounds** (pass/fail): every point's temperature within [0, 100] °C for both models (no
//! source is applied). **Symmetry** (pass/fail): the twin's σxx = σyy at the centre to 10⁻⁹
//! of σxx. **Stress** (reported): σxx against σyy at the centre for both (B-Fig. 11b: equal
//! for TM-MPM, slightly apart for TM-DEMPM from the RVE's anisotropy). **Moduli**
//! (reported): the twin's affine E, ν (B-Eq. 58, `k_n = k_t` gives ν = 0) against the paper's
//! 12 MPa, 0.18 from a uniaxial test. **DEM time rule**: the kinetic/elastic energy ratio ≤ 1 %
//! after the first 10 ms (pass/fail); in them the sides' sudden heating expands the boundary
//! points' disks within a few steps (reported, 1.5 %), as is the inertial number.
//!
//! Quasi-static measures: the kinetic energy of every RVE's fluctuating motion against its
//! elastic energy (≤ 1 %, pass/fail, the whole run: a lattice that buckles or an RVE whose
//! stress lags its deformation fails it); the inertial number is reported only: a perfect
//! lattice under the affine deformation of the rod cannot rearrange, and the uniaxial strain
//! rate near the heated end during the damped stress wave gives `I` above 10⁻³ (0.003 at
//! `s = 1`, `∝ √s`) without any non-affine motion.
//!
//! Tolerances: temperature 0.5 °C; stress 3 % of `K β ΔT` (the full thermal stress range,
//! 4 kPa), which covers the lattice's effective expansion `β · 2r/a` (0.75 % above β, see the
//! module docs) and what is left of the damped stress wave that the quasi-static B-Eq. 56
//! does not have (a continuum twin with the same grid, damping and secant thermo-elasticity
//! stays within 0.45 kPa); displacement 3 % of `β ΔT L / 8` (the largest quasi-static
//! displacement at steady state).

use thm_mpm::MaterialPoints;
use thm_verify::{Case, CaseError, CaseOutput, Plot, Row, Series, SeriesRole};

use crate::multiscale::rod::{
    GranularRod, RodModel, RodTwin, TWIN_YOUNGS_MODULUS, rod_displacement, rod_displacements,
    rod_stress, rod_temperature,
};
use crate::multiscale::square::{GranularSquare, SquareModel, slab_factor};

/// The cases of this module.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "coupling/mpm_dem_rod",
            description: "B-Sect. 5.2.1: granular rod, 50 material points with 400-disk RVEs, 1 s: temperature (B-Eq. 55), stress after 0.4 s (B-Eq. 56, K of B-Eq. 58), displacement (B-Eq. 57)",
            quick: false,
            run: rod_case_full,
        },
        Case {
            name: "coupling/mpm_dem_rod_quick",
            description: "B-Sect. 5.2.1 rod for 0.5 s, 10 x 10-disk lattice RVEs density-scaled by 20 (one DEM step per MPM step): B-Eqs. 55-57",
            quick: true,
            run: rod_case_quick,
        },
        Case {
            name: "coupling/mpm_rod_twin",
            description: "B-Sect. 5.2.1, B-Fig. 9(a-c): the TM-MPM rod (B-Table 1: E = 13.3 MPa, nu = 0) on the granular rod's grid, boundary conditions, damping and time step, 1 s: temperature (B-Eq. 55), stress after 0.4 s (B-Eq. 56 with K = E), displacement (B-Eq. 57)",
            quick: true,
            run: rod_twin_case,
        },
        Case {
            name: "coupling/mpm_dem_square",
            description: "B-Sect. 5.2.2: 2D square heated on all sides, TM-DEMPM and its TM-MPM twin, 1 s, reduced to 16 x 16 points with 100-disk RVEs density-scaled by 100 (the paper: 40 x 40, 400 disks; ~100x the DEM work): centre T vs B-Eq. 59 (friction heat off, reported), bounds, twin symmetry",
            quick: false,
            run: square_case_full,
        },
        Case {
            name: "coupling/mpm_dem_square_quick",
            description: "B-Sect. 5.2.2 square for 0.25 s on 8 x 8 points with 100-disk RVEs density-scaled by 100: centre T vs B-Eq. 59 (friction heat off, reported), bounds, twin symmetry",
            quick: true,
            run: square_case_quick,
        },
    ]
}

fn rod_case_full() -> Result<CaseOutput, CaseError> {
    rod_case(&GranularRod::paper(), 1.0)
}

/// The TM-MPM rod of B-Fig. 9(a–c) against B-Eqs. 55–57 with `K = E` (ν = 0), with the
/// tolerances of the granular rod.
fn rod_twin_case() -> Result<CaseOutput, CaseError> {
    let rod = GranularRod::paper();
    let mut m = RodTwin::new(&rod).map_err(CaseError::from_display)?;
    let mut out = compare_rod(&mut m, &rod, TWIN_YOUNGS_MODULUS, 1.0, "TM-MPM")?;
    out.notes.push(
        "The granular rod's grid (50 cells, one point each), end conditions, alpha_g = 0.01, alpha_PIC = 0 and dt = 1e-4 s; linear thermo-elastic points (thm_mpm::LinearThermoElastic) with E = 13.3 MPa, nu = 0, beta = 1e-4 /K, k = 0.1 W/(m K), rho c = 1 J/(m^3 K), stress-free at the start. B-Eq. 56's K is E (uniaxial strain with nu = 0). Tolerances as coupling/mpm_dem_rod: 0.5 °C, 3 % of K beta dT, 3 % of beta dT L / 8.".into(),
    );
    Ok(out)
}

fn rod_case_quick() -> Result<CaseOutput, CaseError> {
    let mut rod = GranularRod::paper();
    rod.dem_time.density_scaling = 20.0;
    rod.disks_per_side = 10;
    rod_case(&rod, 0.5)
}

/// The sudden heating of the end node drives the neighbouring points at their largest rates
/// (the stress wave of B-Fig. 9): the inertial number is reported in and after it.
const SHOCK: f64 = 0.01;

/// Largest absolute value of `a − b` over pairs.
fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
}

/// A rod model stepped by the comparison with B-Eqs. 55–57: the DEM-backed rod or its
/// TM-MPM twin.
trait RodRun {
    /// One step.
    fn advance(&mut self) -> Result<(), CaseError>;
    /// The points after the last step.
    fn points(&self) -> &MaterialPoints;
    /// After every step (`t` its end): the model's own measures.
    fn after_step(&mut self, _t: f64) {}
}

/// The DEM-backed rod with the largest quasi-static measures seen.
struct DemRod {
    model: RodModel,
    inertial: f64,
    shock_inertial: f64,
    kinetic: f64,
    substeps: u32,
}

impl RodRun for DemRod {
    fn advance(&mut self) -> Result<(), CaseError> {
        self.model.step().map_err(CaseError::from_display)
    }
    fn points(&self) -> &MaterialPoints {
        &self.model.state.points
    }
    fn after_step(&mut self, t: f64) {
        for p in &self.model.state.material {
            if t > SHOCK {
                self.inertial = self.inertial.max(p.inertial_number);
            } else {
                self.shock_inertial = self.shock_inertial.max(p.inertial_number);
            }
            self.kinetic = self.kinetic.max(p.kinetic_ratio);
            self.substeps = self.substeps.max(p.substeps);
        }
    }
}

impl RodRun for RodTwin {
    fn advance(&mut self) -> Result<(), CaseError> {
        self.step().map_err(CaseError::from_display)
    }
    fn points(&self) -> &MaterialPoints {
        &self.state.points
    }
}

/// Steps `m` for `duration` and compares it with B-Eqs. 55–57 (axial stiffness `k`): the
/// temperature at 0.1, 0.4 and 1 s, the stress change every 10 ms from 0.4 s, the
/// displacement at 0.4 and 1 s, as pass/fail rows; the plots labelled `label`.
fn compare_rod(
    m: &mut impl RodRun,
    rod: &GranularRod,
    k: f64,
    duration: f64,
    label: &str,
) -> Result<CaseOutput, CaseError> {
    let kappa = rod.diffusivity();
    let (l, t0, t1) = (rod.length, rod.cold_temperature, rod.hot_temperature);
    let beta = rod.rve.thermal_expansion_coefficient;
    let h = rod.cell_size();
    let x: Vec<f64> = (0..rod.cells).map(|i| (i as f64 + 0.5) * h).collect();
    let sigma0 = m.points().stress[0][0];
    let steps = (duration / rod.time_step).round() as u64;
    let per_10ms = ((0.01 / rod.time_step).round() as u64).max(1);
    let profile_steps: Vec<u64> = [0.1, 0.4, 1.0]
        .iter()
        .map(|t| (t / rod.time_step).round() as u64)
        .filter(|s| *s <= steps)
        .collect();
    let mid = rod.cells / 2;
    let (mut t_err, mut s_err, mut u_err) = (Vec::new(), 0.0_f64, Vec::new());
    let mut stress_series = (Vec::new(), Vec::new(), Vec::new());
    let mut plots = Vec::new();
    for n in 1..=steps {
        m.advance()?;
        let t = n as f64 * rod.time_step;
        m.after_step(t);
        let pts = m.points();
        if n % per_10ms == 0 {
            let reference = rod_stress(t, l, t0, t1, kappa, k, beta);
            let sx: Vec<f64> = pts.stress.iter().map(|s| s[0] - sigma0).collect();
            stress_series.0.push(t);
            stress_series.1.push(sx[mid]);
            stress_series.2.push(reference);
            if t >= 0.4 - 1e-9 {
                s_err = s_err.max(sx.iter().fold(0.0_f64, |e, s| e.max((s - reference).abs())));
            }
        }
        if profile_steps.contains(&n) {
            let tp = &pts.remapped_temperature;
            let reference: Vec<f64> = x
                .iter()
                .map(|x| rod_temperature(*x, t, l, t0, t1, kappa))
                .collect();
            t_err.push((t, max_diff(tp, &reference)));
            let u = rod_displacements(rod, pts);
            let u_ref: Vec<f64> = x
                .iter()
                .map(|x| rod_displacement(*x, t, l, t0, t1, kappa, beta))
                .collect();
            if t >= 0.4 - 1e-9 {
                u_err.push((t, max_diff(&u, &u_ref)));
            }
            plots.push(profile_plot(
                &format!("rod_temperature_{:.0}ms", 1e3 * t),
                &format!("B-Eq. 55: rod temperature at t = {t:.1} s"),
                "temperature (°C)",
                label,
                &x,
                tp,
                &reference,
            ));
            plots.push(profile_plot(
                &format!("rod_displacement_{:.0}ms", 1e3 * t),
                &format!("B-Eq. 57: rod displacement at t = {t:.1} s"),
                "u_x (m)",
                label,
                &x,
                &u,
                &u_ref,
            ));
        }
    }
    let mut out = CaseOutput::default();
    for (t, e) in &t_err {
        out.rows.push(Row::at_most(
            format!("max |T - T(B-Eq. 55)| over points, t = {t:.1} s"),
            "°C",
            *e,
            0.5,
        ));
    }
    let stress_range = k * beta * (t1 - t0);
    out.rows.push(Row::at_most(
        "max |Δσ_x - σ_x(B-Eq. 56)| over points, every 10 ms from 0.4 s",
        "Pa",
        s_err,
        0.03 * stress_range,
    ));
    let u_scale = beta * (t1 - t0) * l / 8.0;
    for (t, e) in &u_err {
        out.rows.push(Row::at_most(
            format!("max |u_x - u(B-Eq. 57)| over points, t = {t:.1} s"),
            "m",
            *e,
            0.03 * u_scale,
        ));
    }
    plots.push(Plot {
        name: "rod_stress_midpoint".into(),
        title: "B-Eq. 56: axial stress change at the rod's middle point".into(),
        x_label: "t (s)".into(),
        y_label: "Δσ_x (Pa)".into(),
        series: vec![
            Series {
                label: label.into(),
                role: SeriesRole::Measured,
                x: stress_series.0.clone(),
                y: stress_series.1,
            },
            Series {
                label: "B-Eq. 56".into(),
                role: SeriesRole::Reference,
                x: stress_series.0,
                y: stress_series.2,
            },
        ],
    });
    out.plots = plots;
    Ok(out)
}

/// Runs the rod for `duration` and compares it with B-Eqs. 55–57.
pub fn rod_case(rod: &GranularRod, duration: f64) -> Result<CaseOutput, CaseError> {
    let model = RodModel::new(rod).map_err(CaseError::from_display)?;
    let k = model.axial_stiffness();
    let mut m = DemRod {
        model,
        inertial: 0.0,
        shock_inertial: 0.0,
        kinetic: 0.0,
        substeps: 0,
    };
    let start = std::time::Instant::now();
    let mut out = compare_rod(&mut m, rod, k, duration, "TM-DEMPM")?;
    let wall = start.elapsed().as_secs_f64();
    let steps = (duration / rod.time_step).round() as u64;
    let (inertial, shock_inertial, kinetic, substeps) =
        (m.inertial, m.shock_inertial, m.kinetic, m.substeps);
    let disk_steps =
        steps as f64 * rod.cells as f64 * (rod.disks_per_side.pow(2)) as f64 * f64::from(substeps);
    out.rows.push(Row::at_most(
        "largest RVE kinetic/elastic energy ratio (DEM time rule)",
        "-",
        kinetic,
        1e-2,
    ));
    out.rows.push(Row::reported(
        "largest RVE inertial number after the heat shock (t > 10 ms), vs 1e-3",
        "-",
        inertial,
        1e-3,
    ));
    out.rows.push(Row::reported(
        "largest RVE inertial number in the heat shock (t <= 10 ms), vs 1e-3",
        "-",
        shock_inertial,
        1e-3,
    ));
    out.rows.push(Row::reported(
        "K = D_xxxx of the RVE (B-Eq. 58) vs B-Table 1's E",
        "Pa",
        k,
        TWIN_YOUNGS_MODULUS,
    ));
    out.rows.push(Row::reported(
        "DEM steps per MPM step (N)",
        "-",
        f64::from(substeps),
        f64::NAN,
    ));
    out.rows.push(Row::reported(
        "disk-steps per second (wall clock)",
        "1/s",
        disk_steps / wall,
        f64::NAN,
    ));
    out.notes.push(format!(
        "{} material points x {} disks, {} MPM steps of {} s, N = {} DEM steps each, density scaling {}, {:.1} s wall.",
        rod.cells,
        rod.disks_per_side.pow(2),
        steps,
        rod.time_step,
        substeps,
        rod.dem_time.density_scaling,
        wall
    ));
    out.notes.push(
        "B-Eq. 57 as printed has cos(nπx/x); derived from u = β∫₀ˣT dx − (x/L)β∫₀ᴸT dx it is cos(nπx/L). B-Eq. 55's T₁ is the hot-end temperature (100 °C)."
            .into(),
    );
    out.notes.push(
        "The square lattice expands by β·2r/a (a = 2r − δ), 0.75 % above β; B-Eqs. 56–57 use β. Lateral nodes held (ν = 0: σ_x and u_x do not depend on it); α of B-Eq. 34 set for k = 0.1 W/(m K); α_PIC = 0."
            .into(),
    );
    Ok(out)
}

fn profile_plot(
    name: &str,
    title: &str,
    y_label: &str,
    label: &str,
    x: &[f64],
    y: &[f64],
    r: &[f64],
) -> Plot {
    Plot {
        name: name.into(),
        title: title.into(),
        x_label: "x (m)".into(),
        y_label: y_label.into(),
        series: vec![
            Series {
                label: label.into(),
                role: SeriesRole::Measured,
                x: x.to_vec(),
                y: y.to_vec(),
            },
            Series {
                label: "analytical".into(),
                role: SeriesRole::Reference,
                x: x.to_vec(),
                y: r.to_vec(),
            },
        ],
    }
}

/// Size of the full square case: points per side, disks per RVE, density scaling.
const FULL_CELLS: usize = 16;
const FULL_DISKS: usize = 100;
const FULL_SCALING: f64 = 100.0;
/// Size and duration of the quick square case.
const QUICK_CELLS: usize = 8;
const QUICK_DISKS: usize = 100;
const QUICK_SCALING: f64 = 100.0;
const QUICK_DURATION: f64 = 0.25;

fn square_case_full() -> Result<CaseOutput, CaseError> {
    let mut sq = GranularSquare::reduced(FULL_CELLS, FULL_DISKS, FULL_SCALING);
    sq.friction_heat = false;
    square_case(&sq, 1.0)
}

fn square_case_quick() -> Result<CaseOutput, CaseError> {
    let mut sq = GranularSquare::reduced(QUICK_CELLS, QUICK_DISKS, QUICK_SCALING);
    sq.friction_heat = false;
    square_case(&sq, QUICK_DURATION)
}

/// What the multiscale coupling may add to the grid's own error in the centre temperature
/// (°C): the RVEs' conductivity against the twin's constant mean one.
const SQUARE_COUPLING_TOLERANCE: f64 = 0.5;

/// The heating of the sides heats the boundary points by tens of kelvin in the first steps
/// (s): the RVEs' kinetic energy is reported in it and checked after it.
const SQUARE_SHOCK: f64 = 0.01;

/// Runs the square and its pure-MPM twin for `duration` and compares the centre with B-Eq. 59.
pub fn square_case(sq: &GranularSquare, duration: f64) -> Result<CaseOutput, CaseError> {
    let mut m = SquareModel::new(sq).map_err(CaseError::from_display)?;
    let (t0, t1) = (0.0, 100.0);
    let p0 = &m.state.points;
    let rho_c = p0.mass[0] / p0.volume[0] * p0.specific_heat[0];
    let k = m.material.initial_conductivity();
    let (kappa_x, kappa_y) = (k[0] / rho_c, k[1] / rho_c);
    let kappa_mean = 0.5 * (k[0] + k[1]) / rho_c;
    let x0 = p0.position.clone();
    let volume: f64 = p0.volume.iter().sum();
    let reference = |kx: f64, ky: f64, t: f64| -> Vec<f64> {
        x0.iter()
            .map(|x| t1 - (t1 - t0) * slab_factor(x[0], 1.0, kx, t) * slab_factor(x[1], 1.0, ky, t))
            .collect()
    };
    let s0 = m.state.points.stress[0];
    let steps = (duration / sq.time_step).round() as u64;
    let every = ((0.01 / sq.time_step).round() as u64).max(1);
    let checks: Vec<u64> = [0.25, 0.5, 1.0]
        .iter()
        .map(|t| (t / sq.time_step).round() as u64)
        .filter(|s| *s <= steps)
        .collect();
    let mut series: [Vec<f64>; 11] = Default::default();
    let mut centre = Vec::new();
    let (mut t_min, mut t_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut twin_min, mut twin_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut inertial, mut substeps) = (0.0_f64, 0u32);
    let (mut kinetic, mut shock_kinetic) = (0.0_f64, 0.0_f64);
    let (mut twin_asym, mut twin_scale) = (0.0_f64, 0.0_f64);
    let mut friction = 0.0;
    let start = std::time::Instant::now();
    // ∫ κ dt of the points' mean conductivity: B-Eq. 59 with κ t replaced by it solves the
    // heat equation with a conductivity that changes in time (uniformly).
    let (mut tau_x, mut tau_y) = (0.0, 0.0);
    for n in 1..=steps {
        let kp = &m.state.points.conductivity;
        let np = kp.len() as f64;
        tau_x += kp.iter().map(|k| k[0]).sum::<f64>() / np / rho_c * sq.time_step;
        tau_y += kp.iter().map(|k| k[1]).sum::<f64>() / np / rho_c * sq.time_step;
        m.step().map_err(CaseError::from_display)?;
        friction += m.friction_heat_of_step();
        let t = n as f64 * sq.time_step;
        for pt in &m.state.material {
            inertial = inertial.max(pt.inertial_number);
            if t > SQUARE_SHOCK {
                kinetic = kinetic.max(pt.kinetic_ratio);
            } else {
                shock_kinetic = shock_kinetic.max(pt.kinetic_ratio);
            }
            substeps = substeps.max(pt.substeps);
        }
        let (p, q) = (&m.state.points, &m.twin_state.points);
        for v in &p.remapped_temperature {
            t_min = t_min.min(*v);
            t_max = t_max.max(*v);
        }
        for v in &q.remapped_temperature {
            twin_min = twin_min.min(*v);
            twin_max = twin_max.max(*v);
        }
        let (tsx, tsy) = (
            m.at_centre(|i| q.stress[i][0]),
            m.at_centre(|i| q.stress[i][1]),
        );
        twin_asym = twin_asym.max((tsx - tsy).abs());
        twin_scale = twin_scale.max(tsx.abs());
        if n % every == 0 || checks.contains(&n) {
            let r = reference(kappa_x, kappa_y, t);
            let rm = reference(kappa_mean, kappa_mean, t);
            let rt = reference(tau_x / t, tau_y / t, t);
            let tc = m.at_centre(|i| p.remapped_temperature[i]);
            let twin_tc = m.at_centre(|i| q.remapped_temperature[i]);
            let rc = m.at_centre(|i| r[i]);
            let rmc = m.at_centre(|i| rm[i]);
            let rtc = m.at_centre(|i| rt[i]);
            if checks.contains(&n) {
                centre.push((t, tc, rc, twin_tc, rmc, rtc));
            }
            if n % every == 0 {
                for (s, v) in series.iter_mut().zip([
                    t,
                    tc,
                    twin_tc,
                    rc,
                    rmc,
                    m.at_centre(|i| p.stress[i][0] - s0[0]),
                    m.at_centre(|i| p.stress[i][1] - s0[1]),
                    tsx,
                    tsy,
                    tc - (twin_tc - rmc),
                    rtc,
                ]) {
                    s.push(v);
                }
            }
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let mut out = CaseOutput::default();
    for (t, tc, rc, twin_tc, rmc, rtc) in &centre {
        let grid = twin_tc - rmc;
        out.rows.push(Row::absolute(
            format!(
                "T centre, TM-DEMPM less the grid's own error, t = {t:.2} s, vs B-Eq. 59 with the RVEs' k_xx(t), k_yy(t)"
            ),
            "°C",
            tc - grid,
            *rtc,
            SQUARE_COUPLING_TOLERANCE,
        ));
        out.rows.push(Row::reported(
            format!(
                "T centre, TM-DEMPM, t = {t:.2} s, vs B-Eq. 59 with the RVE's initial k_xx, k_yy"
            ),
            "°C",
            *tc,
            *rc,
        ));
        out.rows.push(Row::reported(
            format!(
                "T centre, TM-MPM twin, t = {t:.2} s, vs B-Eq. 59 (mean k): the grid's own error"
            ),
            "°C",
            *twin_tc,
            *rmc,
        ));
    }
    out.rows.push(Row::at_least(
        "lowest point temperature, TM-DEMPM",
        "°C",
        t_min,
        t0,
    ));
    out.rows.push(Row::at_most(
        "highest point temperature, TM-DEMPM",
        "°C",
        t_max,
        t1,
    ));
    out.rows.push(Row::at_least(
        "lowest point temperature, TM-MPM twin",
        "°C",
        twin_min,
        t0,
    ));
    out.rows.push(Row::at_most(
        "highest point temperature, TM-MPM twin",
        "°C",
        twin_max,
        t1,
    ));
    out.rows.push(Row::at_most(
        "max over the run |σxx − σyy| / max |σxx| at the centre, TM-MPM twin (symmetry)",
        "-",
        twin_asym / twin_scale.max(f64::MIN_POSITIVE),
        1e-9,
    ));
    let last = |s: &Vec<f64>| s.last().copied().unwrap_or(f64::NAN);
    out.rows.push(Row::reported(
        format!(
            "Δσxx vs Δσyy at the centre, TM-DEMPM, t = {:.2} s (B-Fig. 11b: slightly apart)",
            last(&series[0])
        ),
        "Pa",
        last(&series[5]),
        last(&series[6]),
    ));
    out.rows.push(Row::reported(
        format!(
            "σxx vs σyy at the centre, TM-MPM twin, t = {:.2} s (B-Fig. 11b: identical)",
            last(&series[0])
        ),
        "Pa",
        last(&series[7]),
        last(&series[8]),
    ));
    out.rows.push(Row::reported(
        "twin's E (affine moduli of the RVE, B-Eq. 58) vs the paper's 12 MPa",
        "Pa",
        m.twin_moduli[0],
        12e6,
    ));
    out.rows.push(Row::reported(
        "twin's ν (affine moduli of the RVE, B-Eq. 58) vs the paper's 0.18",
        "-",
        m.twin_moduli[1],
        0.18,
    ));
    let kp = &m.state.points.conductivity;
    let kmean = kp.iter().map(|k| 0.5 * (k[0] + k[1])).sum::<f64>() / kp.len() as f64;
    out.rows.push(Row::reported(
        "mean over points of the RVE conductivity (k_xx + k_yy)/2 at the end vs at the start",
        "W/(m K)",
        kmean,
        0.5 * (k[0] + k[1]),
    ));
    out.rows.push(Row::reported(
        "RVE conductivity (k_xx + k_yy)/2 at the centre at the end vs at the start",
        "W/(m K)",
        m.at_centre(|i| 0.5 * (kp[i][0] + kp[i][1])),
        0.5 * (k[0] + k[1]),
    ));
    out.rows.push(Row::reported(
        "friction work of the RVEs over the square's heat capacity (not applied, see notes)",
        "°C",
        friction / (rho_c * volume),
        0.0,
    ));
    out.rows.push(Row::at_most(
        "largest RVE kinetic/elastic energy ratio after the heat shock (t > 10 ms)",
        "-",
        kinetic,
        1e-2,
    ));
    out.rows.push(Row::reported(
        "largest RVE kinetic/elastic energy ratio in the heat shock (t <= 10 ms), vs 1e-2",
        "-",
        shock_kinetic,
        1e-2,
    ));
    out.rows.push(Row::reported(
        "largest RVE inertial number, vs 1e-3",
        "-",
        inertial,
        1e-3,
    ));
    out.rows.push(Row::reported(
        "DEM steps per MPM step (N)",
        "-",
        f64::from(substeps),
        f64::NAN,
    ));
    let disk_steps =
        steps as f64 * (sq.cells * sq.cells) as f64 * sq.disks as f64 * f64::from(substeps);
    out.rows.push(Row::reported(
        "disk-steps per second (wall clock)",
        "1/s",
        disk_steps / wall,
        f64::NAN,
    ));
    let [t, tc, twin_tc, rc, rmc, sx, sy, tsx, tsy, corrected, rtc] = series;
    let line = |label: &str, role: SeriesRole, y: Vec<f64>| Series {
        label: label.into(),
        role,
        x: t.clone(),
        y,
    };
    out.plots.push(Plot {
        name: "square_centre_temperature".into(),
        title: "B-Eq. 59: temperature at the square's centre".into(),
        x_label: "t (s)".into(),
        y_label: "temperature (°C)".into(),
        series: vec![
            line("TM-DEMPM", SeriesRole::Measured, tc),
            line("TM-MPM twin", SeriesRole::Measured, twin_tc),
            line("B-Eq. 59, RVE's k_xx, k_yy", SeriesRole::Reference, rc),
            line("B-Eq. 59, mean k", SeriesRole::Reference, rmc),
            line(
                "TM-DEMPM less the grid's error (twin - B-Eq. 59)",
                SeriesRole::Measured,
                corrected,
            ),
            line("B-Eq. 59, RVEs' ∫κ dt", SeriesRole::Reference, rtc),
        ],
    });
    out.plots.push(Plot {
        name: "square_centre_stress".into(),
        title: "Stress at the square's centre (cf. B-Fig. 11b)".into(),
        x_label: "t (s)".into(),
        y_label: "σ (Pa)".into(),
        series: vec![
            line("Δσxx TM-DEMPM", SeriesRole::Measured, sx),
            line("Δσyy TM-DEMPM", SeriesRole::Measured, sy),
            line("σxx TM-MPM twin", SeriesRole::Measured, tsx),
            line("σyy TM-MPM twin", SeriesRole::Measured, tsy),
        ],
    });
    out.notes.push(format!(
        "{} x {} material points x {} disks (the paper: 40 x 40 x 400), {} MPM steps of {} s, N = {} DEM steps each, density scaling {}, friction heat {}, {:.1} s wall; RVE conductivity k_xx = {:.4}, k_yy = {:.4}, k_xy = {:.2e} W/(m K).",
        sq.cells,
        sq.cells,
        sq.disks,
        steps,
        sq.time_step,
        substeps,
        sq.dem_time.density_scaling,
        if sq.friction_heat { "applied" } else { "not applied" },
        wall,
        k[0],
        k[1],
        k[2]
    ));
    Ok(out)
}
