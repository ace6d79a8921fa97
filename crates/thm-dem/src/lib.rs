//! # thm-dem
//!
//! A deterministic, parallel discrete element method (DEM) for cohesive-frictional granular
//! materials: spheres in 3D, spheres held in one plane (the single-layer specimens of
//! Krzaczek, Nitka & Tejchman 2023, "paper A") and disks in 2D (the RVEs of Zhao, Zhao, Liang &
//! Niu 2022, "paper B"). Every contact law has one implementation that serves all three: the
//! kinematics and the force law are written once over a [`SpaceVector`] and monomorphised for
//! [`Vec3`] (spheres) and [`Vec2`] (disks, 2D arithmetic only; the periodic RVEs use it).
//!
//! It does **not** do fluid flow, heat conduction, meshing or periodic cells: it takes the
//! external forces (fluid pressure and shear, A-Eqs. 52–54) and particle temperatures from the
//! caller and returns contact forces, broken bonds and friction work. A periodic cell (thm-rve)
//! reuses [`ContactKinematics::from_pair`], [`ContactLaw`] and [`update_contact`] with its own
//! branch vectors.
//!
//! ## Governing equations (SI units throughout)
//!
//! **Cohesive-frictional law** (paper A, A-Eqs. 1–7, [`CohesiveFrictional`]):
//!
//! - `F_n = K_n (U − U₀) N` (A-Eq. 1) with `U = R_A + R_B − |x_B − x_A|` and `U₀` the bond's
//!   creation penetration (0 for a contact that was never bonded);
//! - `F_s = F_s,prev − K_s ΔX_s` (A-Eq. 2), `F_s,prev` carried with the contact frame (below);
//! - `K_n = E_c 2R_AR_B/(R_A+R_B)`, `K_s = ν_c K_n` (A-Eq. 3) \[N/m\];
//! - intact bond: breaks in tension when `−F_n > F_n,min = T R²`, in shear when
//!   `|F_s| > F_s,max + F_n tan μ_c`, `F_s,max = C R²` (A-Eqs. 4, 6);
//! - no bond or broken bond: `F_n ≥ 0`, `|F_s| ≤ F_n tan μ_c` (A-Eq. 5);
//! - Cundall's non-viscous damping on each component of the resultant force and torque,
//!   `F_k ← F_k (1 − α_d sgn(F_k v_k))` (A-Eq. 7, [`stepper::cundall_damping`]).
//!
//! A-Table 1: `E_c` = 3.36 GPa, `ν_c` = 0.3, `C` = 150 MPa, `T` = 30 MPa, `μ_c` = 18°,
//! `ρ` = 2600 kg/m³, `α_exp` = 8·10⁻⁶ 1/K ([`CohesiveFrictionalParams::paper_a_table_1`]).
//!
//! **Linear spring + Coulomb law** (paper B, B-Eqs. 35–36, [`LinearSpring`]): `f_n = k_n u_n`,
//! `Δf_t = −k_t δu_t`, `|f_t| ≤ μ |f_n|`, with the **thermally sensitive bond** (B-Eqs.
//! 38–40): breaks when `F_n > F_nb = β_b k_n R̄` (tension) or `|F_t| > F_tb = μ_b F_nb`,
//! `R̄ = (R_A + R_B)/2`, `β_b = β_a (T_s − T)/T_s` for `T ≤ T_s`, else 0.
//!
//! **Friction work** (B-Eq. 32): per contact and step, `E_f = |F_s| (|F_s,trial| − |F_s|)/K_s`,
//! i.e. `f_t v_t Δt` with `v_t` the *sliding* part of the tangential velocity
//! ([`ContactResponse::friction_work`], kept per contact in [`ContactReport`]); summed by
//! [`ContactList::friction_work`].
//!
//! **Thermal expansion**: incremental A-Eq. 55 `r^{n+1} = r^n (1 + α_exp (T^{n+1} − T^n))`
//! ([`ParticleState::expand_incremental`]) and from a reference radius B-Eq. 37
//! `R = R⁽⁰⁾ (1 + β ΔT)` ([`ParticleState::expand_from_reference`]). Masses are kept
//! (the solid conserves mass), inertias follow the radius.
//!
//! **Motion**: leapfrog (velocity Verlet in kick-drift form, as YADE's `NewtonIntegrator`):
//! `v^{n+½} = v^{n−½} + Δt F^n/m`, `x^{n+1} = x^n + Δt v^{n+½}`, and the same for `ω` with
//! the scalar moment of inertia (`2mR²/5` spheres, `mR²/2` disks; orientation is not tracked,
//! the bodies are isotropic). Time-step estimate [`critical_time_step`]:
//! `min_i √(m_i / Σ_c (K_n + K_s))` and `√(I_i / Σ_c K_s R_i²)`, a factor √2 inside the
//! leapfrog limit by Gershgorin's bound.
//!
//! ## Choices where the papers are ambiguous
//!
//! - **Which R in `T·R²`, `C·R²`**: the smaller radius, as YADE's `CohFrictPhys`
//!   ([`BondRadius::Smaller`], tested by `bond_breaks_when_tension_reaches_t_r_min_squared`);
//!   `BondRadius::Mean` is available.
//! - **Sign in A-Eq. 4**: the text has `‖F_n‖ tan μ_c`, which would make tension *raise* the
//!   shear strength; we use the signed normal force (compression positive) and clip the
//!   strength at 0, the "modified Mohr–Coulomb" envelope of A-Fig. 2d and YADE's code.
//! - **A-Eq. 7** reads `F − α_d sgn(v) F`; Cundall's damping (and YADE) is `F − α_d |F| sgn(v)`,
//!   i.e. opposing the motion; we use that, with YADE's mid-step velocity estimate.
//! - **Stress-free bonds**: a bond is created with `U₀` = its current penetration, so bonds
//!   across a gap or over an overlap carry no force at rest. After breakage the crack closes at
//!   the same `U₀` (no force jump); the contact is dropped once the surfaces are further apart
//!   than the Verlet skin, and a later contact starts with `U₀ = 0`.
//! - **Contact normal stress** (input of A-Eq. 8): `σ_n = F_n / R²` with the same `R` as the
//!   bond strength, so an intact bond breaks at `σ_n = −T` exactly.
//! - **Walls** are rigid planes treated as a twin of the particle (`R_B = R_A`, as YADE), so
//!   `K_n = E_c R`. Walls carry no bonds. Grips in tension are prescribed-velocity particles.
//! - **B-Eq. 40** uses `T` measured from a stated reference temperature and `T_s` as the rise
//!   above it at which the bond vanishes; the contact temperature is the mean of the two
//!   particles'. The bond shear strength of B-Eq. 39 has no friction term added.
//! - **Disks** have mass per unit thickness `ρπR²` \[kg/m\] and forces are per unit thickness.
//! - **Rolling and twisting moments** are not transmitted (A-Eqs. 1–7 have none).
//!
//! ## Packings and verification
//!
//! [`packing::random_packing`] makes seeded random polydisperse packings in a rectangle or box
//! at a target porosity (`1 − Σ A_i/A` planar, `1 − Σ V_i/V` 3D; overlaps count twice), by
//! growing particles in a frictionless DEM run between walls, and installs bonds stress-free
//! at every pair closer than a given gap; [`packing::Packing`] reads and writes plain CSV
//! (`particle,x,y,z,radius` and `bond,a,b` rows); [`packing::Packing::in_locality_order`]
//! renumbers a packing so that neighbours are close in index ([`packing::locality_order`]:
//! cells in row-major order, the box's longest axis slowest), which keeps the contact pass in
//! the caches on large beds; [`DemState::renumber`] applies such an order to a running state
//! (histories mirrored where a pair changes order). The stepper never renumbers the caller's
//! particles. The A-Sect. 3 bar (20 × 80 mm, 4–8 mm, 10 %)
//! holds about 49 spheres at 10 % porosity with uniform diameters (`0.9·1600 mm² / E[πd²/4]
//! = 29.3 mm²`); the "40–45 spheres" of the specimen description correspond to 18–27 %.
//!
//! ## Features
//!
//! The default build holds the DEM alone. `calibration` adds the uniaxial tension test of
//! A-Sect. 3.1 (`tension`) and `calibration::calibrate_bond_strength`, which finds the bond
//! tensile strength `T` (with `C/T` fixed) for which the mean strength of the seeded bars
//! equals a target, as A-Sect. 3 calibrates the DEM against the measured 8.8 MPa.
//! `verification` (with `calibration`) adds `verification::cases`: the two-sphere
//! restitution, the bond threshold and the tension test of A-Sect. 3.1, collected by `cargo
//! xtask verify`.
//!
//! ## Validity
//!
//! Small overlaps (`U/R` ≲ 0.1 at contacts that were never bonded), quasi-static or moderately
//! dynamic loading, `Δt` below [`critical_time_step`]. Linear contact springs (no Hertz).
//!
//! In 3D the shear force (a vector of the old tangent plane) is carried by the exact minimal
//! rotation `F − (n·F)/(1 + n₀·n) (n₀ + n)` and the exact twist about the new normal; in 2D
//! its component along the old tangent `(−n_y, n_x)` is put on the new tangent. Both equal
//! the general rotation followed by a projection to round-off (property tests in [`vector`]).
//! The twist about the normal is zero for disks.
//!
//! Input ranges are checked by [`validate`] (a structured [`OutOfRange`] that this crate's
//! [`DemError`] and the crates built on it wrap).
//!
//! ## Structure and guarantees
//!
//! State ([`DemState`]: particles as struct of arrays, contact lists with history, walls,
//! events) is owned by the caller and round-trips through serde bit for bit; parameters are
//! serde structs validated once ([`StepperParams`], [`CohesiveFrictionalParams`],
//! [`LinearSpringParams`]); the [`Stepper`] holds only scratch buffers. A step is a fixed
//! sequence of stages (neighbour update, contact forces with gather and integration, events).
//! Contacts are computed in parallel (rayon) by fixed blocks of particles, each thread taking a
//! contiguous run of blocks, each contact writing only its own entry and each block summing
//! the forces on its own particles in contact order; a particle's shares from contacts of
//! earlier blocks are summed in contact-index order from +0 (a running sum inside a run, spill
//! entries where an earlier run reaches), so 1, 2 or more threads give identical bits (no
//! floating-point atomics). A block is integrated as soon as every contact that reaches its
//! particles is done, in the same parallel region.
//! Neighbour search is an O(N) cell grid with a Verlet skin; a listed pair found apart is not
//! looked at again until the particles' drift could have closed its gap (the contact pass
//! lists the other contacts branch-free and evaluates only those), so the skin changes
//! the cost, never the result (a test compares the bits of a wide and a thin skin). Once the
//! contact lists are warm a step does not allocate. Unstable runs stop with
//! [`DemError::NonFinite`] naming the particle and the step.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod blocks;
#[cfg(feature = "calibration")]
pub mod calibration;
pub mod contact;
pub mod error;
pub mod neighbour;
pub mod packing;
pub mod state;
pub mod stepper;
#[cfg(feature = "calibration")]
pub mod tension;
pub mod validate;
pub mod vec3;
pub mod vector;
#[cfg(feature = "verification")]
pub mod verification;

pub use contact::{
    BondRadius, BondState, BreakMode, CohesiveFrictional, CohesiveFrictionalParams, ContactHistory,
    ContactKinematics, ContactLaw, ContactProperties, ContactReport, ContactResponse, LinearSpring,
    LinearSpringParams, PairInput, ThermalBondParams, update_contact,
};
pub use error::DemError;
pub use state::{BondBreak, ContactList, DemState, Kinematics, ParticleState, Wall};
pub use stepper::{Stepper, StepperConfig, StepperParams, critical_time_step};
pub use validate::OutOfRange;
pub use vec3::Vec3;
pub use vector::{SpaceVector, Vec2};
