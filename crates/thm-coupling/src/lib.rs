//! # thm-coupling — the coupled DEM–CFD–heat and MPM×DEM schemes
//!
//! The only crate that knows two physics at once: it adapts one crate's output to another's
//! input and sequences their steps.
//!
//! ## DEM–CFD–heat (Krzaczek, Nitka & Tejchman 2023, A-Fig. 7): [`pore_scale`]
//!
//! One coupled step of length Δt_C over a caller-owned [`pore_scale::PoreScaleState`] (spheres,
//! moving mesh, pore fluid, cell temperatures) runs eight named stages
//! ([`pore_scale::stages`]), each a function that can be tested alone:
//!
//! 1. fluid forces on the spheres from the pore pressures and the S2S wall shear
//!    (A-Eqs. 52–54, `A_k = 2 r_max e_k`, thickness = the largest sphere diameter);
//! 2. `ceil(Δt_C / Δt_D)` DEM steps (`thm-dem`, A-Eqs. 1–7) with those forces held;
//! 3. the mesh follows the spheres (`thm-vpn-mesh`), T2T apertures on the moved faces (A-Eq. 9);
//! 4. S2S apertures from the normal stress of each contact (A-Eq. 8);
//! 5. the flow over Δt_C (`thm-vpn-flow`, closure A-Eq. 29 through `thm-eos`), each pore's
//!    dV/dt (A-Eq. 25) the change of its cell volume over the step;
//! 6. heat over Δt_C (`thm-fvm-heat`), advected by the step's mean channel mass rates, fluid
//!    capacities from the phase masses, fluid–solid interfaces by the Nusselt correlations
//!    (A-Eqs. 43–45); the pores are then closed again at their new temperatures;
//! 7. volume-average sphere temperatures to radii (A-Eq. 55);
//! 8. remesh on the trigger of `thm-vpn-mesh` and conservative remap of liquid mass, gas mass,
//!    fluid energy and solid energy (new pores the old fluid did not cover are filled from
//!    their channel neighbours, pores it overfilled are levelled with theirs); a pore that one
//!    mesh motion more than halves, or any cell it inverts, forces this stage before stage 5.
//!
//! A fixed skeleton (A-Sect. 6 case b, the fluid–heat cases of A-Sects. 4–5) is
//! [`pore_scale::Skeleton::Fixed`]: the same step without stages 2–4, 7 and 8.
//!
//! ### Choices where the paper is silent
//!
//! 1. **Coupling lag.** A-Fig. 7 exchanges forces and volume rates "in each time step Δt_D";
//!    here the fluid forces are held over the DEM steps of one coupled step Δt_C and the flow
//!    and heat see the skeleton at its end. Δt_C = Δt_D reproduces the paper's exchange.
//! 2. **Volume rate.** dV/dt of a pore is `(V_mesh^{n+1} − V_flow^n)/Δt_C`, not the
//!    instantaneous rate of the vertex velocities, so the flow's pore volumes never drift from
//!    the mesh's.
//! 3. **Energy with changing mass.** A-Eq. 39 updates `ρ E V` from `n` to `n + 1`. The
//!    implicit heat step balances `C^{n+1}(T^{n+1} − T_ref) − C^n (T^n − T_ref)` against the
//!    step's fluxes; the explicit one first re-expresses each temperature at the new capacity
//!    (`T ← T_ref + C^n/C^{n+1} (T − T_ref)`). With the advective enthalpy
//!    `ṁ c_p (T_f − T_ref)` of the same mass fluxes both conserve `Σ C (T − T_ref)` exactly.
//!    A sphere keeps the heat capacity of its mass while A-Eq. 55 shrinks it: its solid cells
//!    share `ρ_s c_s A_ref b` by area, `A_ref` its solid area in the first mesh.
//! 4. **Contacts of the mesh.** Every overlapping pair of circles is a mesh contact; its σ_n is
//!    that of the DEM contact of the pair (zero where the DEM has no active contact).
//! 5. **Remap.** Pressures and fractions are not remapped: they follow from the remapped masses
//!    (A-Sect. 2.4); fluid temperatures are remapped energy over the new capacities; solid
//!    temperatures are remapped sphere by sphere (the overlap-weighted mean of the sphere's old
//!    cells, then one shift that restores the sphere's energy, so a uniform sphere stays
//!    uniform), as is the re-sharing of a sphere's capacity when mesh motion changes its cells'
//!    areas; the spheres' T_avg^n is reset to the new cells' mean so that the remap changes no
//!    radius. A moving skeleton runs under an adaptive coupled step
//!    ([`pore_scale::PoreScaleStepper::advance`]) that bounds each step's sphere motion.
//!
//! Units: SI throughout (m, kg, s, K, Pa, J, W). Valid where the composed crates are: laminar
//! channel flow, pore fluids inside the EOS's range, Δt_D below the DEM's critical step.
//!
//! ## MPM×DEM (Zhao et al. 2022, Sect. 4, Algorithm 1): [`multiscale`]
//!
//! Each material point of `thm-mpm` owns an RVE of `thm-rve` ([`multiscale::RvePoint`]): the
//! point's velocity gradient and remapped temperature (B-Eq. 29) drive the RVE, which returns
//! stress (B-Eq. 49, sign turned to tension positive), friction heat source (B-Eqs. 32–33) and
//! conductivity tensor (B-Eq. 34) through `thm-mpm`'s batched constitutive seam, implemented
//! here by [`multiscale::RveMaterial`]: all RVEs of a step are stepped as one batch. The DEM
//! time rule (`N = ⌈Δt/(c √(s m_min/k_n))⌉` DEM steps per MPM step, density scaling `s`) and
//! its quasi-static limits (inertial number ≤ 10⁻³, kinetic ≤ 1 % of elastic energy) are in
//! the module docs, with the granular rod of B-Sect. 5.2.1 ([`multiscale::rod`]). The paper
//! cases on it: the rod (B-Sect. 5.2.1), the 2D square (5.2.2, [`multiscale::square`]), the
//! biaxial test (5.3.1, [`multiscale::biaxial`]), its bonded form of B-Fig. 18
//! ([`multiscale::biaxial::BiaxialTest::bonded`], cases `coupling/mpm_dem_biaxial_bonded_quick`
//! and `coupling/mpm_dem_biaxial_bonded`) and the melting-induced column collapse
//! (5.3.3, [`multiscale::column`]: settling under gravity, release of the right plate, a
//! heating plate, bonds of B-Eqs. 38–40 with and without melting, energies as B-Fig. 20;
//! cases `coupling/mpm_dem_column_quick` and `coupling/mpm_dem_column`,
//! `docs/cases/mpm_dem_column.md`).
//!
//! ## The paper's bar cases ([`bar`])
//!
//! The bonded bar of A-Fig. 8 and the parameters and initial states of the cooling bar
//! (A-Sect. 4), the advection bar (A-Sect. 5) and the thermal contraction test with every
//! sphere held (A-Sect. 6 case b), with how the missing figures (A-Figs. 11, 14, 18) are
//! read. Case b: 17 s in 170 coupled steps, about 2 s optimised; A-Sects. 4–5: 400 s in 400
//! coupled steps, about 4 s. Water sealed in pores that no channel connects to a reservoir
//! contracts at fixed mass as it cools and goes into tension; the water cases allow it
//! (`PoreScaleParams::liquid_tension`), otherwise it stops the run naming the pore.
//!
//! ## Status
//!
//! In place: the pore-scale step, implicit pressure and heat steps for long runs, the bar
//! cases of A-Sects. 4, 5 and 6 case b (also as the `thm run` kind `pore_scale_bar`), and
//! A-Sect. 6 case a ([`bar::BarCase::ContractionFree`], `thm run` case `contraction_free`,
//! `scenarios/bar_contraction_free.toml`) with its crack measures ([`bar::crack_report`]).
//! Case a needs an adaptive coupled step: the fluid forces are held over Δt_C, so a sphere
//! that a breaking bond releases keeps its full fluid force (4.6 N on a sphere against a side
//! wall) for the whole step, and with a fixed Δt_C = 0.01 s (DEM density ×100) the bar comes
//! apart within one step (sphere speeds up to 65 m/s).
//! [`pore_scale::PoreScaleStepper::advance`] retakes a step that moves a sphere by more than
//! a set fraction of the smallest radius at half length ([`bar::case_a_coupling_step`]).
//! With A-Eqs. 52–53 case a still stops (0.67 s): liquid-filled pores squeezed by a
//! neighbour's corner reach 10¹¹ Pa, a pressure that acts on no sphere that squeezed them,
//! one coupled step late. Case a therefore pushes with the pore pressure through every cell
//! corner, `P_i ∂V_i/∂c_s`, each pore answering undrained inside the coupled step, its
//! spring integrated implicitly after every DEM sub-step
//! ([`pore_scale::PressureForce::CellCorners`], [`pore_scale::pore_forces`]): 17 s in about
//! 4.5 minutes on two cores, both phase masses kept to 10⁻¹² through 144 remeshes
//! (`coupling/bar_contraction_free`, `docs/cases/bar_contraction_free.md`).
//!
//! The bar cases' bond strength and T2T reduction factor are calibrated on the packings they
//! run on (A-Sect. 3; [`bar::CASE_A_BOND_TENSILE_STRENGTH`], [`bar::BAR_T2T_REDUCTION_FACTOR`];
//! with the feature `calibration`, `calibration::BarFamily` runs the tension and Darcy tests
//! of that family for `thm calibrate`).
//!
//! Temperatures stay between the ends' 278.16 K and the initial 368.16 K in case a (checked
//! by a `thm run` test through bond breakage). An earlier reading of "fluid cells cooling
//! below the boundary temperature" compared them with the 293.16 K ends of A-Sects. 4–5;
//! case a's ends are at 278.16 K, and the cells at 279–281 K are the thin fluid cells along
//! the cooled ends. What did break the bound was two-phase advection: a channel carried
//! heat with the upwind pore's mixture `c_p` while the pores' capacities changed by each
//! phase's own mass and `c_p`, so a uniform field drifted (3·10⁻⁵ K above 368.16 K within
//! 0.03 s of case a); a channel now advects the capacity the pores exchanged, from the side
//! it came from where sub-steps moved the phases opposite ways
//! ([`pore_scale::stages::advected_transfer`]).
//!
//! The out-of-plane thickness (cell volume = area × thickness) is the largest diameter of the
//! initial packing (A-Sect. 2.4) and stays for the run: a remesh used to take the largest
//! diameter of the spheres as they were, so as case a's spheres cooled every remesh shrank
//! every pore and every sphere's heat capacity (by 3 % over 17 s) and a sphere's mean
//! temperature jumped at each remesh (tested: radii equal the initial radii times
//! Π(1 + α_exp ΔT_avg) to 10⁻¹⁴ through breakage and remeshing).
//!
//! The MPM×DEM scheme with the granular rod of B-Sect. 5.2.1 (also as the `thm run` kind
//! `mpm_dem_rod`), the square of B-Sect. 5.2.2 (`mpm_dem_square`), the biaxial tests of
//! B-Sect. 5.3.1 and B-Fig. 18 (`mpm_dem_biaxial`) and the column collapse of B-Sect. 5.3.3
//! (`mpm_dem_column`); the silo discharge of B-Sect. 5.3.2 (`multiscale::silo`, kind
//! `mpm_dem_silo`), which at the shipped reduced size stops before the paper's 12 s / 2 s.
//!
//! ## Verification (`verification::cases`, feature `verification`)
//!
//! - `coupling/pore_scale_closed_conservation`: liquid mass, gas mass and thermal energy of a
//!   closed, adiabatic bonded packing constant to 10⁻¹² relative, with a free skeleton
//!   remeshed almost every step and with a fixed skeleton, explicit and implicit.
//! - `coupling/bar_cooling_advection`: A-Sects. 4–5, the liquid mass against the reservoir
//!   inflow to 10⁻¹², the thermal energy against the energy through the boundary
//!   (`StepReport::boundary_energy`) to 10⁻¹⁰, the time-step rule (halving Δt_C = 1 s moves
//!   T_max by < 0.05 K), and the paper's 0.52 K, density range, speeds, Péclet numbers and
//!   advection differences as reported rows.
//! - `coupling/mpm_dem_rod` (and `_quick`): B-Sect. 5.2.1, temperature against B-Eq. 55,
//!   stress after 0.4 s against B-Eq. 56 with K of B-Eq. 58, displacement against B-Eq. 57
//!   (derived; the printed form has a slip), the quasi-static measures of the DEM time rule.
//! - `coupling/mpm_dem_square` (and `_quick`): B-Sect. 5.2.2 at a reduced size, the centre
//!   temperature against B-Eq. 59 with the RVEs' conductivity (friction heat off, reported),
//!   temperature bounds, the twin's symmetry; σxx, σyy and the twin's moduli reported.
//! - `coupling/bar_contraction_fixed`: A-Sect. 6 case b, phase masses to 10⁻¹², the energy
//!   balance to 10⁻¹⁰, the time-step rule (halving Δt_C = 0.1 s moves T_max by < 0.1 K), and
//!   the paper's 333.3 K and 73.0 kPa as reported rows.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod bar;
#[cfg(feature = "calibration")]
pub mod calibration;
pub mod multiscale;
pub mod pore_scale;

#[cfg(feature = "verification")]
pub mod verification;
