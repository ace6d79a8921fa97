//! # thm-eos — Peng–Robinson equation of state and the two-phase pore closure
//!
//! Implements the fluid thermodynamics of Krzaczek, Nitka & Tejchman (2023), *A novel DEM-based
//! pore-scale thermal-hydro-mechanical model for fractured non-saturated porous materials*,
//! Acta Geotechnica (paper "A"):
//!
//! - the Peng–Robinson cubic, A-Eqs. 16–22, with the optional c1..c3 extension of the alpha
//!   function (c = 0 gives the original equation);
//! - the Péneloux volume correction, A-Eq. 23, with the sign convention of A-Eqs. 27–28;
//! - the two-phase pore closure, A-Eq. 29: from the liquid and gas masses in a pore, its volume
//!   and temperature, the liquid volume fraction at which both phases have the same pressure.
//!
//! Units are SI throughout, except molar volumes, which are in m³/kmol as in the paper.
//!
//! ## Public seam
//!
//! - [`EquationOfState`]: pressure from (T, ρ), density from (T, P, branch), ∂P/∂ρ and ∂P/∂T.
//! - [`PoreClosure`]: phase fractions, densities and the common pressure from phase masses,
//!   pore volume and temperature.
//!
//! The implementation of both (and this documentation's account of the choices made where the
//! paper is ambiguous) is the subject of the crate's first full version.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

/// Which root of the cubic is wanted where several exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Branch {
    /// The smallest molar volume above the co-volume b (the dense, liquid-like root).
    Liquid,
    /// The largest molar volume (the vapour-like root).
    Gas,
}

pub mod verification {
    //! Verification cases of this crate, collected by `cargo xtask verify`.
    use thm_verify::Case;

    /// All verification cases of `thm-eos`.
    pub fn cases() -> Vec<Case> {
        Vec::new()
    }
}
