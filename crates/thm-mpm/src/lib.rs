//! # thm-mpm — 2D explicit thermo-mechanical uGIMP material point method
//!
//! Implements the continuum solver of Zhao, Zhao, Liang and Niu (2022), *Multiscale modeling
//! of coupled thermo-mechanical behavior of granular media in large deformation and flow*,
//! Comput. Geotech. 149:104855, Sect. 2 (B-Eqs. 1–31), with the linear thermo-elastic
//! material of B-Eqs. 50–51 and the benchmarks of B-Sects. 5.1.1, 5.1.2 and 5.2.2.
//!
//! ## What it does
//!
//! * Balance of energy and momentum (B-Eqs. 1–2) with anisotropic Fourier conduction
//!   `q_i = −k_ij T_,j` (B-Eq. 3), in 2D plane strain, unit thickness, in an updated Lagrangian
//!   frame, discretised by undeformed GIMP (uGIMP, Bardenhagen and Kober 2004): top-hat point
//!   domains of fixed half-sizes `l_p ≤ l_e/2` on a regular grid of square cells `l_e`; the
//!   weighting functions and gradients of B-Eqs. 12–13 in closed form ([`shape`]).
//! * Lumped heat capacity and mass `C_I = Σ m_p c_p φ_Ip`, `M_I = Σ m_p φ_Ip` (B-Eq. 19);
//!   loads `Q_I^ext = Σ V_p φ_Ip Q_tp + Σ (V_p/h) φ_Ip q̄_p`, `Q_I^int = −Σ V_p φ_Ip,i k_ij T_p,j`,
//!   `f_I^ext = Σ m_p φ_Ip b + Σ (V_p/h) φ_Ip t̄`, `f_I^int = −Σ V_p φ_Ip,j σ_ij` (B-Eqs. 17–18);
//!   forward Euler on the grid (B-Eqs. 20–22).
//! * Particle update by the damped FLIP/PIC blend (B-Eq. 26, reducing to B-Eqs. 23–25), the
//!   second-order position update (B-Eq. 27), tracked temperature by increments (B-Eq. 28) and
//!   the remapped temperature (B-Eq. 29).
//! * Time-step limits `Δt < l_e/√(M/ρ)` (B-Eq. 30) and `Δt < l_e² ρ c/(b k̄)` (B-Eq. 31), checked
//!   before every step; a larger `Δt` is [`MpmError::TimeStepTooLarge`] naming the point.
//! * Boundary conditions ([`boundary`]): prescribed nodal temperature (B-Eq. 4a), fixed and
//!   roller nodal velocity, tractions and heat fluxes through the virtual boundary layer of
//!   thickness `h` (B-Eqs. 17–18, Zhang et al. 2011), gravity, rigid walls/plates with Coulomb
//!   friction that move at a prescribed velocity and can be removed at a given time; a wall
//!   is a whole half-plane or finite (`RigidWall::segment`: acting only between its end
//!   points and within a band of given depth behind it, as a silo's sides). Surface
//!   loads may be replaced between steps (`Mpm::set_surface_loads`, e.g. a follower pressure
//!   on a bulging side).
//! * Small-mass nodes: a node that a point's domain only grazes gets a sliver of mass but a
//!   finite share of the point's internal force, so its velocity blows up; nodes with mass at
//!   most `MpmParameters::node_mass_tolerance` are left out of the velocity update (velocity
//!   0). The default 0 updates every node with mass. With
//!   `MpmParameters::merge_small_mass_nodes` such a node is instead merged with the heavier
//!   of its row neighbours: both take their summed force over their summed mass, so no force
//!   is lost (along node rows only).
//! * Local non-viscous damping of the nodal forces (`MpmParameters::local_damping`, not in the
//!   paper): each force component is reduced by `α_l |f_i|` against the node's velocity, so it
//!   removes energy while the forces are out of balance and leaves a steady motion alone
//!   (B-Eq. 26's `α_g` and `α_p` damp the velocity itself). Nodes a wall holds are not damped,
//!   so wall reactions stay the undamped forces. The default 0 is B-Eqs. 20–22 unchanged.
//! * The constitutive seam [`Constitutive`]: a point hands `L`, `F`, remapped `T`, `Ṫ`, `σ`, ρ
//!   and `Δt` to its material and gets back `σ`, a heat source `Q_t` (W/m³) and a 2 × 2
//!   conductivity tensor; per-point history (`PointState`) lives in the caller's [`MpmState`].
//!   Shipped: [`LinearThermoElastic`] (B-Eqs. 50–51), [`DruckerPrager`] (elasto-plastic,
//!   plane strain) and [`StresslessConductor`] (no stiffness; heat only, benchmarks).
//! * The batched form of the seam [`BatchConstitutive`]: one call per step hands every point's
//!   input to the material (`&mut self`, so it may hold scratch), for models best stepped as
//!   one batch (a DEM RVE per point, in `thm-coupling`); [`Mpm::step_batch`] runs the stages of
//!   [`Mpm::step`] up to the gather and then [`Mpm::constitutive_update_batch`]. A per-point
//!   model wrapped in [`PerPoint`] gives the same bits through either path (tested).
//!
//! ## The step (see [`stepper`])
//!
//! `check_time_step` → `reset_grid` → `particle_to_grid` (pass 1: mass, momentum, capacity,
//! heat content, internal forces and external loads; nodal temperature with prescribed values;
//! pass 2: conduction heat loads, which need the nodal temperature) → `grid_update` (B-Eqs. 20–22, velocity conditions, walls) →
//! `grid_to_particle` (B-Eqs. 26–29, velocity gradient) → `constitutive_update`. Stresses are
//! updated last (USL), with the velocity gradient of the updated nodal velocities. P2G scatters
//! in horizontal strips coloured even/odd, so every node sums its contributions in one fixed
//! order: results are bit-identical for any number of rayon threads (tested with 1 and 2).
//! [`Mpm::step`] runs these stages fused into six parallel sweeps (binning with the time-step
//! check, two per scatter pass with the nodal temperature and the grid update finished row by
//! row behind the odd strips, gather with constitutive update per chunk of points), with the
//! results of the stage sequence; no stage is serial over the points.
//! Each point's 1D uGIMP weights and gradients are computed once per step (branch-free
//! closed form, [`shape::axis3`]) and shared by the scatters and the gather; node updates
//! visit only the nodes that the stencils touch.
//!
//! ## Units and validity
//!
//! SI throughout (temperature in K or °C, only differences matter). 2D, unit thickness
//! (masses in kg per metre, forces in N per metre). Explicit: Δt below both limits. uGIMP
//! domains do not deform, so very large distortion of a point's domain is not represented
//! (CPDI is out of scope, as in the paper). Only nodes with zero mass are treated as empty:
//! no force is ever dropped, so momentum balance holds to round-off (nearly empty nodes at the
//! edge of a GIMP support get large accelerations, but points see them weighted by
//! `φ_Ip ∝ M_I`). A point's domain must stay inside the grid: pad the grid by a cell where
//! material sits on a grid side that it could cross.
//!
//! ## Choices where the paper is ambiguous or garbled
//!
//! 1. **Sign of `Q_I^int` (B-Eq. 17).** The extracted text has `+Σ V_p φ_Ip,i k_ij T_p,j`;
//!    the weak form B-Eq. 5 (conduction on the left-hand side) gives a minus sign, the only
//!    one for which heat flows down the gradient. We use `−`; the insulated-block test shows
//!    energy conserved and the temperature spread shrinking, the verification cases match the
//!    analytical solutions.
//! 2. **`m_p` in the boundary terms of B-Eq. 18.** `Σ m_p φ_Ip t̄ h⁻¹` has units kg·Pa/m; the
//!    virtual-layer integral of a traction over a layer of thickness `h` is `Σ V_p φ_Ip t̄/h`.
//!    We use `V_p` for tractions and heat fluxes alike, on the points whose centres lie in a
//!    user-given layer rectangle ([`SurfaceLoad`]); the heat flux is the inward flux `−q̄·n`.
//! 3. **Position update B-Eq. 27.** As printed, both damping terms enter with `+`, which would
//!    move a uniformly translating body under PIC by `v Δt − Δt v` (not at all). We use
//!    Nairn's form `x += Δt Σ v_I^{t+Δt} φ_Ip − (Δt/2)(v_p^{t+Δt} − v_p^t)` with the velocity
//!    change of B-Eq. 26, i.e. the `(α_PIC + α_p) v_p` term with a minus sign. It reduces to
//!    B-Eq. 27 without damping and is tested: a translating block moves by exactly `v Δt`.
//! 4. **Prescribed temperatures and B-Eq. 28.** At a node with prescribed `T̄`, the nodal
//!    temperature used for gradients is `T̄`, and the nodal rate passed to the points is
//!    `(T̄ − T_I^mapped)/Δt`, so that the tracked point temperatures relax to the boundary
//!    value.
//! 5. **Which temperature drives the material.** The tracked temperature (B-Eq. 28) is mapped
//!    to the grid; the remapped temperature (B-Eq. 29) and the rate `Ṫ_p = Σ φ_Ip T_I,t` are
//!    handed to the material, as the paper does for its RVEs (Sect. 2.3).
//! 6. **B-Eq. 51 in 2D.** `ε̇ = sym(L) − β Ṫ I` is read with `I` the in-plane unit tensor and
//!    `D` the plane-strain isotropic tensor, so the thermal stress of a constrained point is
//!    `−2(λ + G) β ΔT` (no out-of-plane thermal strain). The stress rate is Jaumann's, so a
//!    rigid rotation creates no stress (tested).
//! 7. **`E` in B-Eq. 30.** The P-wave modulus `λ + 2G ≥ E` is used (the material's
//!    [`Constitutive::wave_modulus`]): it is the actual dilatational wave speed of plane strain
//!    and the stricter bound. `b` of B-Eq. 31 defaults to the paper's 1.
//! 8. **B-Eq. 59** (verification): the exponent is read as `π²((2m+1)² + (2n+1)²) k t/(L² ρ c)`.
//! 9. **Point A of B-Sect. 5.1.2** is "the plate center with x = y = 0": the origin is the
//!    plate centre, so the heated sides are `x = −0.5` and `y = −0.5` m.
//!
//! ## What it does not do
//!
//! No file output: point and grid fields are public ([`MaterialPoints`], [`Mpm::grid_fields`],
//! [`Grid::node_positions`]) for the shared I/O crate to write. No latent heat, no contact
//! between bodies other than rigid walls, no CPDI, no implicit time integration. The DEM RVE
//! material lives in `thm-coupling`, behind [`Constitutive`].
//!
//! ## Set-ups, analytical solutions and verification
//!
//! [`setups`] builds the TM-MPM problems of B-Sects. 5.1–5.2 as models ready to step;
//! [`analytical`] holds the closed forms scenarios compare with (B-Eqs. 52, 59). Behind the
//! feature `verification`: `reference`, finite-difference solutions of the dynamic
//! thermo-elastic bar and plate, and `verification::cases` (collected by `cargo xtask
//! verify`): the semi-infinite bar (B-Sect. 5.1.1) against B-Eq. 52 and a converged finite-difference
//! solution of the dynamic thermo-elastic bar; the 2D plate (B-Sect. 5.1.2) against the exact
//! temperature series and a finer MPM run; the heated square (B-Sect. 5.2.2) against B-Eq. 59.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod analytical;
pub mod boundary;
pub mod config;
pub mod error;
pub mod grid;
pub mod material;
pub mod points;
#[cfg(feature = "verification")]
pub mod reference;
pub mod setups;
pub mod shape;
pub mod stepper;
#[cfg(feature = "verification")]
pub mod verification;

pub use boundary::{
    NodeSet, RigidWall, Side, SurfaceLoad, TemperatureCondition, VelocityCondition,
};
pub use config::{MpmConfig, MpmParameters};
pub use error::MpmError;
pub use grid::{Grid, GridParameters};
pub use material::{
    BatchConstitutive, Constitutive, DruckerPrager, DruckerPragerParameters, DruckerPragerState,
    LinearThermoElastic, MaterialInput, MaterialResponse, PerPoint, StresslessConductor,
    ThermoElasticParameters,
};
pub use points::{MaterialPoints, PointProperties};
pub use stepper::{GridFields, Mpm, MpmState, NodeSums, TimeStepLimits};
