//! # thm-rve — thermo-mechanical DEM representative volume elements in periodic cells
//!
//! The RVE of Zhao, Zhao, Liang & Niu (2022), Sect. 3 (paper "B"): about 400 disks in a
//! periodic parallelogram cell, deformed by the velocity gradient of a material point and
//! heated to its temperature, returning the homogenised stress, the friction heat source and a
//! fabric-based conductivity tensor. Many RVEs (one per material point) are stepped in
//! parallel by [`RveBatch`].
//!
//! It does **not** conduct heat inside the RVE (the temperature of an RVE is uniform, that of
//! its material point, as in the paper), model rolling resistance, contacts of a disk with its
//! own image, gravity, or walls; the macroscopic heat equation lives in `thm-mpm`, the coupling
//! in `thm-coupling`.
//!
//! ## Physics (by equation)
//!
//! - **Periodic cell** ([`cell`]): `x = H X`, `X = H⁻¹ x` (B-Eq. 41) with the columns of **H**
//!   the cell's basis vectors; in reduced coordinates the cell is the unit square, so the base
//!   lengths of B-Eq. 44 are `l_j = 1` and the period shift is the integer vector `⌊X⌋`
//!   (B-Eqs. 43–44). `ẋ = Ḣ X + H Ẋ = v_h + v_f` (B-Eq. 42); `Ḣ = L H` and `v_h = L x`
//!   (B-Eq. 46). Strain `E = ½(H' + H'ᵀ) − I`, `H' = H H_ref⁻¹` (B-Eq. 47), `ε_v = ε_ii`,
//!   `ε_q = √(2 ε'_ij ε'_ij)` for `n = 2` (B-Eq. 48).
//! - **Contacts** ([`stepper`]): `thm-dem`'s [`thm_dem::LinearSpring`] — `f_n = −k_n u_n`,
//!   `Δf_t = −k_t δu_t`, `|f_t| ≤ μ |f_n|` (B-Eqs. 35–36) and the thermally sensitive bond
//!   `F_nb = β_b k_n R`, `F_tb = μ_b F_nb`, `β_b(T)` (B-Eqs. 38–40) — called with the periodic
//!   branch vector `b = x_b + H s − x_a` and the relative velocity `v_f,b − v_f,a + L b`
//!   (B-Eq. 45: the affine velocity of an image differs by `Ḣ P`, the fluctuating one does
//!   not). No contact law is written here.
//! - **Stress** ([`measure::stress`]): `σ = (1/V) Σ_c f^c ⊗ b^c + (1/V) Σ_p m_p v_f^p ⊗ v_f^p`
//!   (B-Eq. 49), `V = det H · z_p`.
//! - **Friction heat** (B-Eqs. 32–33): `E_f = Σ_c f_t v_t Δt` per DEM step, where only the
//!   sliding part of `v_t` dissipates (`thm-dem` returns `|f_t| · slip` per contact); the heat
//!   source of a macroscopic step of `N` DEM steps is `Q = Σ E_f / (V N Δt_D)`.
//! - **Conductivity** ([`measure::conductivity`]): `k_ij = (1/V) Σ_p r_i r_j / (α l)` (B-Eq. 34),
//!   one heat pipe per contact carrying force or holding an intact bond.
//! - **Thermal expansion** ([`RveStepper::set_temperature`]): `R = R⁽⁰⁾ (1 + β (T − T_ref))`
//!   (B-Eq. 37); masses are kept, inertias follow the radius.
//! - **Stiffness** ([`measure::stiffness`]): `D_αβγφ = (1/V) Σ_c (k_n n_α l_β n_γ l_φ +
//!   k_t t_α l_β t_γ l_φ)` (B-Eq. 58).
//! - **Packing** ([`packing`]): radii uniform in `[r_min, r_max]` from a seeded ChaCha8
//!   generator, random sequential addition at a low solid fraction, servo-controlled isotropic
//!   consolidation to a target stress; dense/loose by the friction during consolidation
//!   (0.01 / 0.5, B-Sect. 5.3.1), 0.5 during shear. A consolidated [`RveState`] is `serde`, so
//!   many RVEs start from one saved packing.
//!
//! ## Choices where the paper is ambiguous or garbled
//!
//! 1. *Sign of B-Eq. 49.* `f^c` is the force on disk `b` from disk `a`, `b^c` points from `a`
//!    to `b`: a repulsive contact gives `f·b > 0`, so σ is **compression positive**, the
//!    geomechanics convention of the paper's figures; the kinetic term then enters with `+`
//!    (momentum flux acts as a pressure). A tension-positive continuum takes `−σ`.
//! 2. *B-Eqs. 45a and 46b* are garbled (`Ḣ_ii P_i`, `Ḣ_ik H⁻¹_ki`); read as `v_h(p') = v_h(p) +
//!    Ḣ P` and `L = Ḣ H⁻¹`, the only dimensionally consistent forms.
//! 3. *Fluctuating dynamics.* `m v̇_f = F` (the pseudo-force `−m L v_f` of a moving frame is
//!    dropped, as usual for quasi-static RVEs). Centres move by `x ← x + Δt (v_f + L x)` and the
//!    cell by `H ← H + Δt L H`: the same explicit step, so the affine motion leaves reduced
//!    coordinates exactly unchanged (tested).
//! 4. *B-Eq. 47* is a small-strain measure of the cell; it is not frame indifferent under a
//!    finite rotation (a rotation by θ gives `(cos θ − 1) I`). It is reported, not used to
//!    compute stress; the stress invariants are frame indifferent (tested).
//! 5. *B-Eq. 34.* The heat-pipe vector `r` is the branch vector joining the two centres and
//!    `l = |r|`. With `V` in m³ the result is in W/(m K). With the paper's α = 10³ K/(W m) and
//!    `z_p` = 75 mm, the 400-disk packing of B-Sect. 5.2.2 gives about 20 W/(m K), not the
//!    "initial conductivity of 1.6 W/(m K)" quoted in B-Sect. 5.3.1; the paper does not say which
//!    `z_p` it used there, so α and `z_p` stay parameters.
//! 6. *Fictitious thickness* `z_p` (B-Sect. 5.2.1, 75 mm): forces are in N (`k_n` in N/m), a
//!    disk is a cylinder of mass `ρ π R² z_p`, `V = det H · z_p`. Stress scales as `1/z_p`; with
//!    `k_n = k_t`, the affine stiffness of B-Eq. 58 gives `ν = 0` and `E ≈ k_n / z_p` =
//!    13.3 MPa, the values of B-Table 1's TM-MPM column.
//! 7. *Bond installation* (B-Sect. 5.3.3): [`RveState::install_bonds`] makes every contact that
//!    carries force after consolidation an intact bond *keeping its present compression* (no
//!    stress-free reset), so installing bonds changes no stress. `R` of B-Eq. 38 is the mean
//!    radius; `T` of B-Eq. 40 is measured from the bond's reference temperature.
//! 8. *Damping.* The paper is silent; Cundall's local non-viscous damping acts on the
//!    fluctuating motion only, a parameter (0 for the energy balance, 0.7 during consolidation).
//! 9. *E and ν* (B-Sect. 5.2.2) come from constrained compression: `Δσ_yy/Δε_yy = K + G`,
//!    `Δσ_xx/Δε_yy = K − G`, `ν = (K − G)/(K + G)`, `E = 2K(1 − ν)` (2D). Recomputed from the
//!    paper's 12.4 and 2.18 MPa: ν = 0.176, E = 12.02 MPa, as stated. The packing consolidated
//!    with μ = 0.001 (B-Table 1) gives the paper's order only when compressed with μ = 0.5; a
//!    nearly frictionless packing has a tiny shear modulus (ν ≈ 0.76). See the verification
//!    (`verification::cases`, feature `verification`, collected by `cargo xtask verify`).
//! 10. *Energy.* The heat returned equals the sliding work to round-off; the cell's mechanical
//!     energy balance (boundary work = Δ elastic + Δ kinetic + friction heat) closes only to
//!     first order in Δt with explicit integration (≈ 4·10⁻⁴ at 0.2 √(m/k_n), tested to
//!     shrink 4× with Δt/4), not to 10⁻⁹.
//! 11. *Cells in a flow.* The paper does not say how its periodic cells survive the unbounded
//!     shear of a flowing material point (B-Sect. 5.3.3). [`RveState::reduce_cell`] replaces a
//!     skewed basis by a Lagrange–Gauss reduced basis `H U` (`U` unimodular) of the same
//!     lattice: the packing, its contacts and its stress are unchanged (tested) and the cell
//!     stays wide enough for the periodic search under shear. Elongation (a cell stretched
//!     along one axis and thinned along the other) it cannot cure.
//!
//! ## Units and validity
//!
//! SI throughout; temperatures in K. Valid for quasi-static RVEs of disks: a DEM step below
//! the critical step (`0.2 √(m_min / k_n)` is used), strain per DEM step far below the Verlet
//! skin over the radius, overlaps small against radii (consolidation refuses targets that need
//! mean overlaps above 10 % of `r_min`), and a cell at least `2 (2 R_max + skin)` wide (a pair
//! then touches at most one image; narrower cells are refused).
//!
//! ## Numerics and determinism
//!
//! A step is a fixed sequence of stages: integration with the forces of the last evaluation,
//! neighbour update (Verlet list on a periodic cell grid in reduced coordinates, rebuilt when
//! fluctuating displacements, the cell deformation since the build and radius growth could use
//! up the skin; disks are wrapped back into the cell only then), then contact forces in list
//! order at the configuration the step ends in (so stress, fabric and stiffness measured after
//! a step are those of the state's own configuration; see [`stepper`]). Contacts go through
//! `thm-dem`'s law monomorphised for [`thm_dem::Vec2`] (2D arithmetic only); the disks are
//! copied once per step into compact records, so a contact reads two records. Each RVE is
//! stepped serially; a batch distributes chunks of RVEs (one scratch stepper per chunk) over
//! rayon's pool and reduces nothing across them, so 1 and 2 threads give the same bits
//! (tested). A warm step does not allocate (tested with a counting allocator). State ([`RveState`]), stepper
//! ([`RveStepper`], scratch only) and parameters ([`RveParams`] → [`RveConfig`]) are separate.
//!
//! ## Public seam
//!
//! [`RveStepper::respond`]`(state, RveLoad { velocity_gradient, temperature, dt, substeps })
//! → RveResponse { stress, heat_source, conductivity }` per RVE, and
//! [`RveBatch::respond`] for many. `thm-coupling` adapts it to `thm-mpm`'s constitutive trait.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod batch;
pub mod cell;
pub mod error;
mod kernel;
pub mod mat2;
pub mod measure;
pub mod neighbour;
pub mod packing;
pub mod params;
pub mod state;
pub mod stepper;
#[cfg(feature = "verification")]
pub mod verification;

pub use batch::RveBatch;
pub use cell::{CellStrain, PeriodicCell};
pub use error::RveError;
pub use mat2::Mat2;
pub use packing::{
    ConsolidationParams, ConsolidationReport, PackingParams, consolidate, random_packing,
};
pub use params::{RveConfig, RveParams};
pub use state::{PeriodicContacts, RveState};
pub use stepper::{RveLoad, RveResponse, RveStepper};
