//! # thm-coupling — the coupled DEM–CFD–heat and MPM×DEM schemes
//!
//! The only crate that knows two physics at once: it adapts one crate's output to another's
//! input and sequences their steps.
//!
//! ## DEM–CFD–heat (Krzaczek, Nitka & Tejchman 2023, Fig. 7)
//!
//! Per DEM step Δt_D: fluid pressure and channel shear forces (A-Eqs. 52–54, thickness = the
//! largest sphere diameter) from `thm-vpn-flow` are applied to the spheres of `thm-dem`; the DEM
//! motion gives each virtual pore's dV/dt through `thm-vpn-mesh`; the flow (`thm-vpn-flow`, with
//! the closure of `thm-eos`) and heat (`thm-fvm-heat`) solvers sub-cycle with Δt_C; the solid
//! cells' volume-average temperatures change the sphere radii (A-Eq. 55); contact normal
//! stresses set the S2S apertures (A-Eq. 8); the mesh is rebuilt and fields remapped
//! conservatively when the configuration has changed enough.
//!
//! ## MPM×DEM (Zhao et al. 2022, Sect. 4, Algorithm 1)
//!
//! Each material point of `thm-mpm` owns an RVE of `thm-rve`: the point's velocity gradient
//! and temperature drive the RVE, which returns stress, friction heat source and conductivity
//! tensor through `thm-mpm`'s constitutive trait, implemented here for the RVE.
//!
//! ## Status
//!
//! The schemes are assembled here once the single-physics crates they compose are complete;
//! this crate holds no coupling code yet.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod pore_scale;

pub mod verification {
    //! Verification cases of this crate, collected by `cargo xtask verify`.
    use thm_verify::Case;

    /// All verification cases of `thm-coupling`.
    pub fn cases() -> Vec<Case> {
        Vec::new()
    }
}
