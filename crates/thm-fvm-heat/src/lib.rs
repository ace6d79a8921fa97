//! # thm-fvm-heat
//!
//! Finite-volume heat transfer in the fluid cells (virtual pores) and solid cells (sphere
//! cross-sections) of a [`thm_vpn_mesh::PoreMesh`], after Krzaczek, Nitka & Tejchman (2023),
//! Sect. 2.3 (A-Eqs. 30–51). Equations are cited as `A-Eq. n`.
//!
//! ## What it does
//!
//! - **Fluid cells**: the homogeneous energy equation A-Eqs. 30, 37–39, written for the
//!   temperature with enthalpy h = c_p (T − T_ref) (A-Eqs. 31, 51):
//!   C_i dT_i/dt = Σ_f D_f − Σ_k ṁ_k c_p,up (T_f − T_ref) + Σ_{S2S} λ_eff A_k (T_j − T_i)/L_k,
//!   with C_i = V_i Σ_k α_k ρ_k c_p,k. Advection uses the channel mass fluxes ṁ_k \[kg/s\] of
//!   the flow solver with the second-order upwind face value A-Eq. 48,
//!   T_f = T_up + ψ_up ∇T_up · r, limited by Barth–Jespersen (ψ ∈ [0, 1]).
//!   Diffusion D_f across a face uses A-Eq. 47: the primary two-point term
//!   λ_f (T_1 − T_0)/ds · |A|²/(A·e_s) plus the cross-diffusion term
//!   λ_f ∇̄T · (A − e_s |A|²/(A·e_s)), ∇̄T the mean of the two cell gradients, λ_f the
//!   distance-weighted harmonic mean of the two cells. S2S channels (sphere contacts, no face)
//!   add the conduction source A-Eq. 40 with A_k = aperture × thickness.
//! - **Effective properties** (A-Eqs. 32–36) from the liquid fraction α_q and the phase
//!   densities (inputs, [`FlowInput`]): ρ_eff = Σ α_k ρ_k, λ_eff = Σ α_k λ_k,
//!   μ_eff = Σ α_k μ_k, and c_p,eff = Σ α_k ρ_k c_p,k / ρ_eff (see choices).
//! - **Solid cells**: conduction A-Eqs. 49–50, ρ_s c_p V dT/dt = Σ_f λ_s ∇T_f · A_f, with the
//!   same face treatment as the fluid (A-Eq. 47, including the cross term). Faces between
//!   solid cells of different spheres (contacts) conduct like faces inside a sphere.
//! - **Boundaries and interfaces**, cases I–IV of Sect. 2.3.1, per side of the mesh
//!   ([`BoundaryParams`]; sides not listed are adiabatic): I prescribed temperature, constant
//!   or piecewise linear in time ([`TemperatureSchedule`]); II prescribed flux q \[W/m²\] into
//!   the domain, adiabatic = q = 0; III convective exchange h_e (T_e − T_f); IV fluid–solid
//!   interface with h_f(T_f − T_c0) = λ_s (T_c1 − T_f)/d_{r,c}, i.e. the series conductance
//!   |A| / (1/h_f + d_{r,c}/λ_s), with h_f = Nu λ_eff / (2 r) (A-Eq. 45) and Nu from A-Eq. 43
//!   (Tavassoli et al., Re ≤ 100) or A-Eq. 44 (Wakao & Kaguei, Re > 100).
//!   Open boundary faces of fluid cells carry the boundary mass flux of the flow solver:
//!   outflow at the reconstructed cell value, inflow at the side's prescribed temperature
//!   (case I) or else at the cell temperature.
//! - **Sphere temperatures**: [`sphere_mean_temperatures`] gives the volume-average T of each
//!   sphere's solid cells, the T_avg of thermal expansion A-Eq. 55.
//! - **Time stepping**: [`HeatStepper::step`] advances explicitly (A-Eqs. 39, 50) with equal
//!   sub-steps under the stability limit min_i C_i / (Σ conductances + 3 Σ outflow ṁ c_p)
//!   times `stability_safety` (default 0.8), computed each outer step from the mesh, the
//!   properties and the fluxes. [`HeatStepper::implicit_step`] is a backward-Euler
//!   step on a sparse system (conduction alone: SPD, `faer`'s sparse Cholesky; with mass
//!   fluxes: first-order upwind advection, sparse LU), with the cross-diffusion terms as
//!   deferred correction, for long runs. After either, [`HeatStepper::boundary_energy`] is the
//!   energy that crossed the outer boundary (conduction and advected enthalpy), which accounts
//!   for the change of Σ C (T − T_ref) to round-off (property test).
//!
//! - **Mesh-derived coefficients** live in a [`HeatGeometry`] the caller keeps: the topology
//!   part (face classes, boundary table, least-squares stencils, cell → channel adjacency) is
//!   built once per mesh (again after a remesh, [`HeatGeometry::new`]); the position part
//!   (A-Eq. 47 face factors, gradient weights, sphere radii, porosity) is refreshed in one
//!   parallel pass by [`HeatGeometry::update_positions`] after the vertices move. The stepper
//!   recomputes only what depends on the properties and the flow each outer step.
//!
//! A step is the fixed sequence `prepare` → `stability_limit` → (`face_values` → `gradients`
//! (gradient and limiter) → `face_heat` → `channel_heat` → `advance`) per sub-step; each stage
//! is a public method testable alone. [`HeatStepper::step`] runs it with one pass fewer: the
//! heat rates of a sub-step do not depend on its length, so the first sub-step's face pass
//! also stores the face conductances of the stability limit, and one pass over the cells
//! then gives the limit and the net heat to apply (`face_heat_and_conductances` →
//! `channel_heat` → `net_heat_and_stability_limit` → `apply_net_heat`); the result has the
//! same bits as the plain sequence (property test). Face and channel heat rates are computed
//! once per face/channel and gathered per cell in a fixed order, so energy is conserved to
//! round-off and 1-thread and N-thread runs give identical bits.
//!
//! ## What it does not do
//!
//! - No flow: phase fractions, densities and mass fluxes are inputs ([`FlowInput`]) from the
//!   flow solver; within one outer step they are frozen (capacities use the given densities;
//!   the paper's ρ^{n+1} vs ρ^n distinction in A-Eq. 39 is the caller's outer step).
//! - No temperature dependence of c_p, λ, μ (as in the paper, Sect. 4), no viscous dissipation,
//!   no phase change, no radiation.
//! - No remeshing or remap: after a remesh the caller builds a new [`HeatGeometry`] and remaps
//!   the state; after the vertices move it calls [`HeatGeometry::update_positions`]. A
//!   geometry whose sizes do not match the mesh is a typed error.
//!
//! ## Units and validity
//!
//! SI throughout: T \[K\], λ \[W/(m K)\], c_p \[J/(kg K)\], ρ \[kg/m³\], ṁ \[kg/s\], q \[W/m²\],
//! h \[W/(m² K)\], lengths \[m\]; volumes and face areas are the mesh's areas and lengths times
//! `PoreMesh::thickness`. Valid for the laminar, low-Mach pore flow of the paper; the
//! explicit step is stable for sub-steps within the computed limit; faces whose normal and
//! centroid link are nearly perpendicular (cos ≤ 10⁻³) are rejected (typed error).
//!
//! ## Choices where the paper is ambiguous or garbled
//!
//! 1. **Gradients.** The paper uses Green–Gauss with the arithmetic face mean (A-Eqs. 41–42).
//!    That gradient is not exact for linear fields on triangles whose centroid links miss the
//!    face centroids; its error enters the boundary fluxes and cross terms at O(1) and the
//!    scheme drops to first order (measured: observed order 0.6–0.75 on the distorted bar,
//!    verification case 2). The default is a weighted least-squares gradient over the same
//!    face neighbours and face values (interface and boundary temperatures, Neumann rows for
//!    prescribed flux), exact for linear fields, which restores order 2 (measured 1.97–1.98).
//!    `GradientScheme::GreenGauss` keeps the paper's variant.
//! 2. **Boundary distance.** d_r of cases I–III is read as the normal distance of the cell
//!    centroid to the face, with the tangential offset corrected by the cell gradient; at the
//!    fluid–solid interface (case IV) d_{r,c} is the centroid-to-face-centroid distance of the
//!    solid cell, as printed.
//! 3. **Case III formula.** The printed T_f is garbled; we use the consistent balance
//!    λ (T_f − T_c)/d = h_e (T_e − T_f), i.e. T_f = (λ/d T_c + h_e T_e)/(λ/d + h_e).
//! 4. **Specific heat of the mixture** (A-Eq. 36 says c_p = Σ α_i c_p,i, volume-weighted).
//!    The enthalpy of a mixture is mass-weighted, so C = V Σ α_k ρ_k c_p,k and
//!    c_p,eff = Σ α_k ρ_k c_p,k / ρ_eff; both readings agree for a single phase.
//! 5. **Reynolds number** of A-Eqs. 43–44: Re = ρ_eff v (2r)/μ_eff with v the largest channel
//!    speed |ṁ|/(ρ_eff h b) of the fluid cell, r the radius of the circle with the area of the
//!    sphere's solid cells, ε the mesh porosity (fluid area / total area). The switch is at
//!    Re = 100 (the text's "Re > 102" is 10²); Nu is discontinuous there, as in the paper.
//! 6. **Advection stability.** Explicit Euler with a Barth–Jespersen-limited reconstruction
//!    on triangles is local-extremum diminishing for 3 Δt Σ_out ṁ c_p ≤ C (the three face
//!    excursions of a linear reconstruction sum to zero); the limit uses that factor. S2S
//!    channels have no face, so their advection is first-order upwind.
//! 7. **Fourier series** A-Eq. 60 is printed without the offset, the minus sign and the
//!    diffusivity in the exponent: we use T = T_end + Σ_odd 4ΔT/(nπ) sin(nπx/L)
//!    exp(−n²π² α t/L²) (A-Eq. 61 with uniform initial T).
//! 8. **Cooling-bar properties** (A-Eq. 63, Table 1): with porosity 0.1106 (for which
//!    A-Eq. 63 gives the paper's λ_eff = 3.357 W/(m K)) and water at 998 kg/m³, ρ_eff =
//!    2422.8 kg/m³ (paper 2422.74) but the volume-averaged c_p = 1281.3 J/(kg K), not the
//!    paper's 929.51, which is the average with the specific heat of air (1006) instead of
//!    water: a slip. The paper's numbers give α = 1.491e-6 m²/s, its Fourier numbers imply
//!    1.453e-6 m²/s; we use the consistent (ρc)_eff = Σ φ_k ρ_k c_k, α = 1.296e-6 m²/s, in
//!    both the simulation and the reference (verification case 1).
//! 9. **Energy form.** Advection is in conservative form with T_ref (A-Eq. 39), so energy
//!    Σ C_i (T_i − T_ref) is conserved exactly for any fluxes; temperatures stay bounded
//!    only when the fluxes are divergence-free and the upwind and downwind c_p agree (a mixture
//!    of frozen composition cannot follow the advected composition within a step).
//! 10. **Interface in the cooling bar.** A-Sect. 4 runs the bar as "an equivalent solid bar,
//!     made of a fictitious homogeneous material" with the A-Eq. 63 properties in fluid and
//!     solid. Case IV adds a film resistance 1/h_f that a homogeneous medium does not have
//!     (measured on the mesher's bar mesh, backward Euler Δt = 5 s: centreline errors 0.65–1.3 K), so
//!     [`InterfaceModel::Continuous`] lets fluid–solid faces conduct like faces inside one
//!     medium (A-Eq. 47, harmonic λ); the default stays case IV ([`InterfaceModel::Nusselt`]).
//! 11. **Neumann rows on prescribed-flux faces** are written as weights on the face value
//!     T_f − T_c = d_n q / λ, so the gradient is one weighted sum; they are kept wherever the
//!     cell's medium can conduct (λ_k > 0 for some phase), with q / λ = 0 in a cell whose λ is 0.
//! 12. **Limited cross diffusion.** With the real properties of A-Table 1 (fluid 0.6, solid
//!     3.7 W/(m K)) on the mesher's bar mesh, the full cross terms of its sliver faces make
//!     the discrete operator lose its diffusive sign: the explicit step diverged at
//!     t ≈ 57 s and backward Euler (Δt = 1 s) within the first 100 s. [`CrossDiffusion::Limited`]
//!     caps each face's cross term at `ratio` × its two-point term; with `ratio` ≤ 1 every face
//!     carries heat from hot to cold and the explicit step creates no new extrema (property
//!     test), at the cost of accuracy on strongly non-orthogonal faces (homogeneous bar of
//!     `fvm_heat/cooling_bar`, backward Euler Δt = 1 s, largest centreline error over
//!     100–400 s: full 0.13 K, ratio 2: 0.32 K, ratio 1: 1.03 K). The default stays full.
//!
//! ## Analytical solutions and verification
//!
//! [`analytical`] holds the closed forms of A-Sects. 4–5 that scenarios compare with (the
//! bar's effective properties, A-Eq. 63; the cooling bar, A-Eqs. 60–61; the bar with a flow
//! along it; the steady conduction–advection profile). `verification::cases` (feature
//! `verification`, collected by `cargo xtask verify`): the cooling bar (A-Sect. 4) at 100–400 s against the Fourier
//! series (paper: 0.52 K) on the mesher's fluid+solid mesh of the paper's bar (about 0.1 K,
//! backward Euler, Δt = 1 s) and on a structured mesh (about 0.01 K explicit, 0.3 K implicit
//! with Δt = 5 s), second-order
//! convergence on a distorted mesh, steady conduction–advection at Pe = 1, 10, 100 against
//! the exponential profile, and a bounded pure-advection step.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod analytical;
mod error;
pub mod geometry;
mod implicit;
pub mod params;
pub mod properties;
pub mod spheres;
mod state;
pub mod stepper;
#[cfg(feature = "verification")]
pub mod verification;

pub use error::HeatError;
pub use geometry::HeatGeometry;
pub use params::{
    BoundaryCondition, BoundaryParams, CrossDiffusion, GradientScheme, HeatModel, HeatParams,
    InterfaceModel, PhaseParams, SolidParams, TemperatureSchedule,
};
pub use spheres::sphere_mean_temperatures;
pub use state::{FlowInput, HeatState};
pub use stepper::{HeatStepper, StepReport};
