//! # MPM×DEM thermo-mechanics (Zhao et al. 2022, Sect. 4, B-Algorithm 1)
//!
//! Every material point of `thm-mpm` owns a DEM RVE of `thm-rve` ([`RvePoint`], in the
//! caller's `MpmState`); [`RveMaterial`] implements `thm-mpm`'s batched constitutive seam
//! (`thm_mpm::BatchConstitutive`) and steps all RVEs of a step as one batch
//! (`thm_rve::RveBatch`: chunks of RVEs on the rayon pool, nothing reduced across them, so 1
//! and 2 threads give the same bits).
//!
//! ## One MPM step (`thm_mpm::Mpm::step_batch`)
//!
//! Mapping, nodal forces and heat loads, grid update and the gather run in `thm-mpm`
//! (B-Eqs. 7–29). Then, for all points at once, the exchange of B-Algorithm 1, lines 11–19,
//! as the named stages of [`stages`]:
//!
//! 1. the point's velocity gradient `L` and remapped temperature `T_p` (B-Eq. 29, the smooth
//!    one the paper hands to the RVEs, Sect. 2.3) become the RVE's load: `L` held over `N`
//!    DEM steps of `Δt/N` (B-Eqs. 41–46), disk radii from `T_p + T_offset` (B-Eq. 37);
//! 2. the DEM steps of every RVE, as one batch;
//! 3. back to the point: stress `σ = −sym(σ_RVE)` (B-Eq. 49 is compression positive,
//!    `thm-mpm` is tension positive), heat source `Q = Σ E_f/(V N Δt_D)` (B-Eqs. 32–33, W/m³)
//!    and conductivity `sym(k)` (B-Eq. 34, W/(m K));
//! 4. per RVE, the P-wave modulus `max(D_xxxx, D_yyyy)` of B-Eq. 58 for the time-step limit
//!    B-Eq. 30, the friction work of the step, the inertial number and the kinetic/elastic
//!    energy ratio; with [`QuasiStaticLimits`] set, an RVE beyond them stops the run naming
//!    the point and the step.
//!
//! The next step's nodal forces and heat loads (B-Eqs. 17–18) use these stress, heat source
//! and conductivity, so the exchanges follow B-Algorithm 1's order (deformation and
//! temperature → DEM → stress, heat source, conductivity → nodal force and heat load →
//! update of points). `thm-mpm` updates stresses last (USL): the RVE sees the velocity
//! gradient of the updated grid velocities of step n, where B-Algorithm 1 uses the grid
//! velocities mapped from the points at the start of step n + 1.
//!
//! ## The DEM time rule
//!
//! Each MPM step `Δt` runs, in each RVE, `N = ⌈Δt / (c √(s m_min / k_n))⌉` DEM steps of
//! `Δt/N` ([`DemTimeRule`]): `c = 0.2` (the fraction `thm-rve` consolidates with; the
//! critical step of a disk between springs is `≈ 0.7 √(m/k_n)`) and a density scaling
//! `s ≥ 1` of the disks' masses and inertias. So the DEM is stable for every `Δt`, and `s`
//! trades DEM steps for inertia: `N ∝ s^{−1/2}`. The RVE is quasi-static when its inertial
//! number `I = γ̇ d̄ √(s ρ_s / p) ≤ 10⁻³` (`γ̇` the deviatoric rate of `sym L`, the rate of
//! `ε_q` of B-Eq. 48; `d̄` the mean diameter; `p` the RVE's mean pressure) and its fluctuating
//! kinetic energy is at most 1 % of the elastic energy of its contacts (this one also covers
//! volumetric and thermal loading, which `I` does not see) ([`QuasiStaticLimits`], checked
//! after every step when set). `I` grows as `√s`: the scaling is admissible as long as both
//! stay below the limits.
//! Evidence (test `dem_time_rule_does_not_change_the_response`): a consolidated 100-disk RVE
//! driven by the same compression–shear–heating history (0.02 s in MPM steps of 10⁻⁴ s,
//! μ = 0.5, no damping) with `s = 1, 4, 16` (N = 80, 40, 20) stays within the limits; relative
//! to the largest stress change of the `s = 1` run its stresses agree within 2.5 % over the
//! whole history (measured 2.1 % and 1.8 %: the first steps, where L is switched on at once
//! and the RVE's own response time, ∝ √s, shows), within 1.5 % from 2 ms on (1.1 %, 1.4 %)
//! and within 0.2 % at the end (0.05 %, 0.16 %). The same history 100 times faster is stopped
//! by the check. On the rod's square lattice, which deforms affinely, `s = 20` (N = 1) and
//! `s = 1` (N = 5: 10⁻⁴ s is 4.002 times 0.2 √(m/k_n)) pass the same rows (verification).
//!
//! ## Choices where the paper is silent or ambiguous
//!
//! 1. **Temperatures.** The RVE works in kelvin (B-Eq. 37 from its reference temperature);
//!    [`MultiscaleParams::kelvin_offset`] maps the MPM's temperature to it (273.15 for °C).
//! 2. **Stress and conductivity symmetry.** B-Eq. 49's contact part is not exactly symmetric
//!    out of equilibrium; the point takes its symmetric part, as it does of B-Eq. 34.
//! 3. **Time-step modulus.** B-Eq. 30's `E` is read as the RVE's affine P-wave modulus
//!    `max(D_xxxx, D_yyyy)` (B-Eq. 58), an upper bound of the packing's stiffness.
//! 4. **RVE volume vs point volume.** An RVE's heat source is per RVE volume (B-Eq. 33) and
//!    applied to the point's volume, so a point receives `Σ E_f · V_p / V_RVE` per step
//!    (tested to round-off against the friction work summed over the RVEs).
//!
//! ## One skeleton for the cases with a changing load ([`model`])
//!
//! The biaxial test, the silo discharge and the column collapse run on one
//! [`MultiscaleModel`]: the state, the running sums, the loading phases (an MPM stepper and the
//! material its points are stepped with) and the RVE materials, and one coupled step. Each case
//! is a [`Protocol`]: its constructor (grid, walls, points, template packing by
//! [`model::consolidated_packing`]), what happens before a step (a release, loads that follow
//! the boundary) and after it (heat, friction work, plate work), and the history row. The rod
//! and the square, whose load does not change, step `thm-mpm` with an [`RveMaterial`] directly.
//!
//! ## The granular rod (B-Sect. 5.2.1, [`rod`])
//!
//! 50 points on a 1 m rod, each with a 20 × 20 square packing of r = 5 mm disks at 100 kPa,
//! B-Table 1's parameters, Δt = 10⁻⁴ s, 0 → 100 °C at `x = L`. Choices: the packing is built
//! at its consolidated state (overlap `δ = σ₀ z_p 2r/(k_n + σ₀ z_p)`), not by the servo; α of
//! B-Eq. 34 is set so that the packing conducts B-Table 1's k = 0.1 W/(m K) (the paper gives k,
//! not α); the lateral nodes are held (`v_y = 0`) instead of a 100 kPa traction, since the
//! square packing has `D_xxyy = 0` (ν = 0): σ_x and u_x do not depend on the lateral
//! condition, and uGIMP's virtual-layer traction on a single row of points would split between
//! the held bottom and the top nodes; grid damping α_g = 0.01 (B-Eq. 26) so that the stress
//! wave of the sudden heating decays within about 10 ms, as B-Fig. 9's wave "relaxes with
//! time" (undamped, it rings at about ±20 kPa around B-Eq. 56 for the whole run; the damping
//! force on the slow thermal motion, `ρ α_g v/Δt`, is below 300 Pa/m), α_PIC = 0. The quasi-static solutions
//! B-Eqs. 55–57 are read with `T₁` the hot-end temperature (the set-up text's `T₁ = T₀`
//! would make them vanish), and B-Eq. 57's printed `cos(nπx/x)` is `cos(nπx/L)` (derived from
//! `u = β∫₀ˣ T − (x/L) β∫₀ᴸ T`). The lattice expands by `β · 2r/a` (a = 2r − δ, 0.75 % more
//! than β), which the analytical forms with β do not see.
//!
//! ## The 2D square (B-Sect. 5.2.2, [`square`])
//!
//! `thm-mpm`'s TM-MPM square (grid, held normal displacements, 100 °C on all sides) with an
//! RVE per point: random radii in [0.25, 0.5] mm consolidated with μ = 0.001 to 100 kPa and
//! then given μ = 0.5 (with 0.001 the packing has almost no shear stiffness: points by the
//! held sides shear without bound and an RVE cell collapses within 0.4 s), α set
//! so that the mean of the packing's conductivity diagonal is B-Table 1's 0.1 W/(m K), and a
//! pure-MPM twin with the RVE's affine moduli (B-Eq. 58; with `k_n = k_t`, `D_xxyy = 0`, so
//! ν = 0, against the paper's 0.18 from a uniaxial test that includes non-affine motion) and
//! the same mean conductivity. B-Eq. 59 is misprinted: its exponent is
//! `π²((2m+1)² + (2n+1)²) κ t/L²`. A random RVE's conductivity is orthotropic, so the centre
//! temperature is to be compared with the product of the two slab solutions
//! ([`square::slab_factor`]) with `k_xx` and `k_yy` (tested equal to B-Eq. 59 when they are
//! equal), and with B-Eq. 59 for their mean.
//!
//! Verified by `coupling/mpm_dem_square` (and `_quick`, `verification::multiscale`) at a reduced size,
//! with the friction heat off (`square::GranularSquare::friction_heat`): with B-Table 1's
//! `ρ c = 1 J/(m³ K)` the quasi-static friction work of the heated RVEs (the same for density
//! scalings 20 to 400) is worth tens of kelvin, which B-Eq. 59 does not have; and the RVEs'
//! conductivity grows by a few per cent as they are compressed, which the comparison follows
//! with `∫ κ̄ dt`. Density scaling 100 (N = 16 DEM steps per MPM step of 2·10⁻⁴ s) keeps the
//! kinetic energy below 1 % of the elastic after the first 10 ms. An earlier reduced run with
//! `s = 10⁴` (N = 2) was not quasi-static and its friction heat drove the centre to 167 °C;
//! with μ = 0.001 after consolidation the packing slides more, not less (575 K-equivalent of
//! friction work on 4 × 4 points in 0.5 s, kinetic energy 10 % of elastic).
//!
//! ## The biaxial test (B-Sect. 5.3.1, [`biaxial`])
//!
//! A 1 m × 2 m specimen between rough plates (rigid walls of `thm-mpm` with infinite
//! friction), the top one moving down, a follower confining pressure on the sides, RVEs
//! consolidated dense (μ = 0.01) or loose (μ = 0.5) and sheared with μ = 0.5, adiabatic. Its
//! module docs give the choices: the confinement extrapolated to the surface (the
//! virtual-layer load on the outer points alone holds only 3/4 of it), a node mass tolerance
//! against the small-mass nodes the bulging sides graze, the consolidated packing set at rest
//! before the density scaling, the stress ratio from the plate reaction. Cases
//! `coupling/mpm_dem_biaxial_quick` and `coupling/mpm_dem_biaxial`
//! (`verification::biaxial`, feature `verification`); `docs/cases/mpm_dem_biaxial.md`.
//!
//! ## The column collapse (B-Sect. 5.3.3, [`column`](mod@column))
//!
//! A 2 m × 2 m column of RVEs consolidated to 10 kPa settles under gravity between two plates;
//! the right plate is then removed, the left one held at 50 °C, and bonds of B-Eqs. 38–39
//! installed at the force-carrying contacts, their strength melting by B-Eq. 40 (`T` read as
//! the rise above the initial temperature, `T_s = 10 K`) or not. Its module docs give the
//! choices: 0 °C initially, the settling with a larger PIC fraction, frictionless lateral
//! plates, the heat entering from the plate read from the grid so that stored heat = plate +
//! friction heat to round-off, and the reduction of skewed RVE cells in the flow
//! (`thm_rve::RveState::reduce_cell`). A rank-one fabric conductivity of an RVE dilated in the
//! flow is kept positive semi-definite within rounding ([`stages::psd_conductivity`]). Cases
//! `coupling/mpm_dem_column_quick` and `coupling/mpm_dem_column` (`verification::column`);
//! `docs/cases/mpm_dem_column.md`.
//!
//! **Silo discharge** (B-Sect. 5.3.2, [`silo`]): a 1 m silo with a 45° hopper and a 0.2 m
//! opening 1 m above the ground, walls of finite extent (`thm_mpm::RigidWall::segment`), the
//! sample settled with the opening closed and then discharged freely or under a plate moving
//! down at 0.2 m/s; the stored heat equals the RVEs' friction work to round-off. Cases
//! `coupling/mpm_dem_silo_quick` and `coupling/mpm_dem_silo` (`verification::silo`);
//! `docs/cases/mpm_dem_silo.md`.
//!
//! Units: SI; the MPM side of the rod, the square, the biaxial test and the column in °C.

pub mod biaxial;
pub mod column;
pub mod distributed;
pub mod error;
pub mod material;
pub mod model;
pub mod params;
pub mod point;
pub mod rod;
pub mod silo;
pub mod square;
pub mod stages;

pub use biaxial::{Biaxial, BiaxialModel, BiaxialTest, Compaction};
pub use column::{ColumnModel, ColumnTest};
pub use distributed::{BlockMaterial, Collective, Distribution, SharedDistribution, ThreadGroup};
pub use error::MultiscaleError;
pub use material::RveMaterial;
pub use model::{LoadingPhase, MultiscaleModel, PackingReport, Protocol};
pub use params::{DemTimeRule, MultiscaleConfig, MultiscaleParams, QuasiStaticLimits};
pub use point::{PointOutcome, RvePoint, partition, rve_cost};
pub use rod::{GranularRod, RodModel, RodTwin};
pub use silo::{SiloModel, SiloTest};
