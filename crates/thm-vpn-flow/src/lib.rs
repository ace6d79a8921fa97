//! # thm-vpn-flow — two-phase compressible flow in the virtual pore network
//!
//! The fluid model of Krzaczek, Nitka & Tejchman (2023), *A novel DEM-based pore-scale
//! thermal-hydro-mechanical model for fractured non-saturated porous materials*, Acta
//! Geotechnica (paper "A"), Sect. 2.2: the fluid is stored in virtual pores (VPs, the fluid
//! triangles of `thm-vpn-mesh`), where it is compressible, and moves through channels (T2T and
//! S2S), where it is an incompressible laminar flow between parallel plates.
//!
//! ## What it does
//!
//! - **Channel flow** ([`channel`]): single-phase plane Poiseuille flow, A-Eq. 10,
//!   `M = ρ h³/(12 μ) (P_i − P_j)/L` per unit width; and the stratified two-layer flow of two
//!   immiscible fluids, A-Eqs. 11–15 (no slip at both walls, continuous velocity and shear at a
//!   flat interface), solved in closed form for each phase's flow rate and both wall shear
//!   stresses (derivation in [`channel`]). Mass rate through a channel = `ρ_k Q_k w`, with `w`
//!   the out-of-plane width (the mesh thickness = the largest sphere diameter, A-Sect. 2.2).
//! - **VP mass balance per phase**, A-Eqs. 24–26: `m_k^{n+1} = m_k^n + Δt Σ_f M_k,f`, with the
//!   pore volume `V^{n+1} = V^n + (dV/dt) Δt` (A-Eq. 25, `dV/dt` from the solid motion); then the
//!   closure A-Eq. 29 (both phases at one pressure) through the [`PoreFluid`] trait gives
//!   `α_q`, `ρ_q`, `ρ_p` and `P`. The phase masses are the conserved unknowns; A-Eq. 26 is the
//!   same update written for the density.
//! - **Explicit update with sub-cycling** ([`FlowStepper::step`]): inside a given outer step
//!   (e.g. one DEM step) the stepper takes sub-steps no larger than
//!   - the stability bound `s / max_i (K_i/V_i Σ_c C_c)`, `K_i` the mixture bulk modulus of
//!     pore `i` (`1/K = α_q/K_q + α_p/K_p`, `K_k = ρ_k ∂P/∂ρ_k`), `C_c` the volumetric
//!     conductance of its channels and links (the Gershgorin bound of the linearised pressure
//!     equation `V/K dP/dt = Σ C ΔP`; forward Euler is stable for `Δt ≤ 2/λ_max` and
//!     `λ_max ≤ 2 max_i K_i Σ C / V_i`), `s` = `stability_safety` (0.9);
//!   - the positivity bound: no pore loses more than `positivity_safety` (½) of a phase's
//!     mass in one sub-step.
//!
//!   The outer step is split into equal sub-steps below the limit (recomputed every
//!   sub-step); more than `max_substeps` is an error.
//! - **Implicit pressure step** ([`FlowStepper::implicit_step`]) for water-filled pores,
//!   where the explicit bound is ~10⁻⁸ s: backward Euler in the phase masses, each sub-step
//!   solved by Newton iterations that linearise the closure about the iterate (the pressure
//!   equation `V/K (P* − P)/h = d/h + Σ C' (P_j* − P_i*) + S`, `C'` each phase's conductance
//!   times its upwind-over-local density ratio, sparse LU), evaluate the phase fluxes at `P*`
//!   with the explicit step's channel law and advance the masses from the sub-step start.
//!   Mass is conserved to round-off at every iterate and for any step; a sub-step that would
//!   empty more than `positivity_safety` of a phase, whose closure fails or that does not
//!   converge is halved. First order in time (measured against the explicit step on a
//!   water/air chain, order 0.8–1.3).
//! - **Boundary conditions** on boundary faces of fluid cells, per side ([`BoundaryCondition`]):
//!   prescribed pressure (a reservoir reached through a half-channel from the cell centroid to
//!   the face centre, aperture `γ e sin ω` as A-Eq. 9; fluid that enters has the reservoir's
//!   liquid fraction and the densities of the fluid model at the reservoir pressure and
//!   temperature), prescribed mass flow rate per phase (shared among the side's faces by face
//!   length), impermeable (the default for sides without a condition).
//! - **Forces on spheres** ([`add_sphere_forces`]), A-Eqs. 52–54: pressure `P_i e_k w` along the
//!   normal of every fluid–solid face into the sphere (`A_k = 2 r_max e_k = w e_k`), and the
//!   wall shear of every S2S channel times `L w` along the channel in the flow direction.
//! - **Diagnostics** ([`StepReport`], [`FlowState`]): the largest phase Reynolds number
//!   `Re_k = ρ_k |Q_k| / μ_k = ρ_k ū_k h_k / μ_k` in channels and links (the paper keeps the
//!   flow laminar through γ), the total mass of each phase, the mass rate through each
//!   boundary group and the cumulative mass that entered through it.
//!
//! ## What it does not do
//!
//! Heat (`thm-fvm-heat`), the mesh and its remap (`thm-vpn-mesh`), the Peng–Robinson EOS
//! (`thm-eos`, plugged in through [`PoreFluid`] by [`EosFluid`]), the S2S apertures of A-Eq. 8 (set by the
//! coupling through [`Network::set_channel_apertures`] or the mesh), gravity (neglected, as in
//! A-Sect. 2.2.1), phase change and capillarity (not in the paper).
//!
//! ## Choices where the paper is ambiguous
//!
//! - **Interface position** (A-Sect. 2.2.1 says only that it "is related to fractions of fluid
//!   phases in adjacent VPs"): the liquid layer is `α_q,up h` with `α_q,up` the liquid fraction
//!   of the *upwind* pore (the one at the higher pressure), and the transported densities are
//!   that pore's. A channel is filled from its upstream end, so a phase can only leave a pore
//!   that holds it, and a thin layer of a phase carries a flow that vanishes with its
//!   thickness (≈ `a²` for the liquid next to a wall), which keeps phase masses non-negative.
//!   The face fractions of A-Eq. 24 are then `α_k,f = Q_k/(Q_q + Q_p)` of the two-layer
//!   solution.
//! - **Wall shear for S2S forces**: the network does not say which of the two spheres of a
//!   contact is the liquid-side wall; each sphere gets the mean of the two wall stresses,
//!   `τ̄ = G h/2` (independent of the interface position), so the pair together receives the
//!   exact total `ΔP h w`.
//! - **A-Eq. 12** is garbled in the extracted text; it is read as the incompressible
//!   Navier–Stokes equations of each layer. In fully developed plane-parallel flow it reduces to
//!   `μ_k u_k'' = dP/dx`, which is what [`channel`] solves.
//! - **Paper's Q in A-Sect. 3.2**: "3.5.31×10⁻⁵ m³/s" is garbled. From A-Eq. 56 with its own
//!   `κ = 2.47·10⁻¹⁶ m²`, `A = 20 mm × 8 mm`, `L = 80 mm`, `ΔP = 4.9 MPa`, `μ = 10.02·10⁻⁴ Pa s`
//!   the flow rate is `Q ≈ 2.4·10⁻⁹ m³/s`; the verification case uses κ, not Q.
//! - **Temperature** enters only through the closure; the stepper uses the temperatures in
//!   the state (set by the heat solver between steps) from the first sub-step's closure on.
//!
//! ## Units and validity
//!
//! SI throughout: m, m², m³ (volumes = cell area × thickness), kg, s, Pa, K, Pa·s; mass rates
//! in kg/s. Valid for laminar channel flow (check [`StepReport::max_reynolds`]) and for pores
//! whose fluid the [`PoreFluid`] model describes. [`LinearLiquidIdealGas`] (a weakly
//! compressible liquid `ρ_q = ρ₀(1 + (P − P₀)/K)` and an ideal gas, with an exact closure) is
//! provided for tests and verification; paper A's fluids are
//! `EosFluid(thm_eos::water_air_closure(Model::PrCorrected))` (Peng–Robinson water with the
//! volume correction and air, A-Eqs. 16–29, Table 1).
//!
//! ## Public seam and structure
//!
//! - [`Network`] — the minimal view the solver runs on (pores, channels with endpoints,
//!   lengths and apertures, boundary links, fluid–solid wall faces), built from a
//!   `thm_vpn_mesh::PoreMesh` with [`Network::from_mesh`] or by hand with [`Network::new`].
//! - [`FlowState`] — struct-of-arrays per pore, owned by the caller (serde): the phase masses
//!   (the conserved unknowns), volume and temperature, and their closure (fraction, pressure,
//!   densities, pressure stiffness `K/V`), plus the cumulative boundary inflows. The stepper
//!   keeps it closed; after changing masses or volumes outside it (a remap) call
//!   [`FlowState::close`]. Per-cell inputs map to pores with [`Network::cells_to_pores`].
//! - [`FlowStepper`] — scratch buffers only; `step(network, state, fluid, dv_dt, dt)` runs the
//!   stages of [`stepper`]: channel fluxes → boundary fluxes → gather per pore (with the
//!   sub-step limit) → mass/volume update and closure.
//! - [`FlowParameters`] (serde, `deny_unknown_fields`) → [`FlowConfig`] (validated).
//! - [`PoreFluid`] — the thermodynamic seam (closure, phase density, bulk modulus);
//!   [`EosFluid`] implements it for any `thm_eos::TwoPhaseClosure` (its errors become
//!   [`ClosureFailure::Model`]).
//! - [`FlowError`] — typed errors naming the pore, channel or link, the step and sub-step:
//!   negative aperture, non-positive length or volume, closure failure, non-finite values,
//!   too many sub-steps.
//! - `permeability` (feature `calibration`) — the steady flow of a network solved directly,
//!   the permeability of the bar of A-Sect. 3.2 (A-Eq. 56), and
//!   `permeability::calibrate_t2t_factor`, the T2T reduction factor γ (A-Eq. 9) for which it
//!   equals a target (A-Sect. 3: "DEM and CFD were separately calibrated").
//!
//! Determinism: per-channel and per-pore results are computed in parallel (rayon) and
//! combined per pore in a fixed order, so runs on any number of threads give identical bits.
//!
//! ## Verification (`verification::cases`, feature `verification`)
//!
//! - Pressure diffusion along a chain of pores against the Fourier series.
//! - The Darcy permeability test of A-Sect. 3.2 (A-Eq. 56) on the paper's bar: a seeded
//!   20 × 80 mm packing of 4–8 mm spheres at 10 % porosity meshed by `thm-vpn-mesh` into
//!   virtual pores with T2T (A-Eq. 9) and S2S (A-Eq. 8) channels. The test is pure CFD on an
//!   unloaded specimen, so the S2S apertures are taken **at rest**: `σ_n = 0`, `h = β h_0 =
//!   3.9 µm`. The steady state is solved directly (the explicit stepper would need ~10⁷
//!   sub-steps to relax this mesh) and checked to be the stepper's steady state; κ at the
//!   paper's γ = 0.0115 is compared with the paper's 2.47·10⁻¹⁶ m² over an ensemble of
//!   packings (median within two robust standard deviations of `log10 κ`); `κ ∝ γ³` holds
//!   where T2T channels limit the flow (small γ), more slowly at the paper's γ because S2S
//!   channels (independent of γ) are crossed in series, so the γ that gives the paper's κ is
//!   found by regula falsi rather than by the cubic scaling.
//! - The explicit transient of the same test on a jittered structured triangulation of the
//!   bar, run to steady state against the direct steady solve.
//! - A two-phase drainage column whose phase masses balance the boundary inflows to round-off.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod channel;
mod eos_fluid;
mod error;
pub mod fluid;
mod forces;
mod implicit;
mod network;
mod params;
#[cfg(feature = "calibration")]
pub mod permeability;
pub mod stages;
mod state;
pub mod stepper;
#[cfg(feature = "verification")]
pub mod verification;

pub use eos_fluid::EosFluid;
pub use error::{ClosureFailure, FlowError, Phase};
pub use fluid::{LinearLiquidIdealGas, LinearLiquidIdealGasParameters, PoreFluid, PoreState};
pub use forces::{add_pressure_forces, add_shear_forces, add_sphere_forces};
pub use implicit::MIN_SUBSTEP_FRACTION;
pub use network::{BoundaryCondition, Network, NetworkParts, SECOND_END};
pub use params::{FlowConfig, FlowParameters};
pub use state::FlowState;
pub use stepper::{FlowStepper, StepReport};
