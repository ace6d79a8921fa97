//! A-Sect. 3's two calibrations on the packing family the coupled bar cases run on
//! (Krzaczek et al. 2023): the bond tensile strength `T` (with `C = 5 T`) against the bar's
//! 8.8 MPa in uniaxial tension (A-Sect. 3.1) and the T2T reduction factor γ (A-Eq. 9) against
//! its permeability 2.47·10⁻¹⁶ m² (A-Sect. 3.2, A-Eq. 56).
//!
//! `thm-dem`'s own calibration runs on its tension-bar generator (bonds within 4 mm) and
//! `thm-vpn-flow`'s on the Darcy test's packings (every circle inside the box): neither is the
//! packing the coupled cases mesh and step. [`BarFamily`] is: [`crate::bar::bar_spheres`]
//! (the A-Fig. 8 recipe, 4–8 mm, about 10 % porosity, every overlapping pair bonded: bonds at
//! grain contacts, A-Sect. 2.1), with the cases' ends, meshed as the cases mesh it
//! ([`crate::bar::bar_state_sized`]). The searches themselves are the crates':
//! [`thm_dem::calibration::calibrate_bond_strength_of`] and
//! [`thm_vpn_flow::permeability::calibrate_t2t_factor_of`].
//!
//! Compiled with the feature `calibration` (on for `thm calibrate` and the verification).

use thm_dem::calibration::{BondCalibration, StrengthCalibration, calibrate_bond_strength_of};
use thm_dem::tension::{BarLoading, TensionResult, uniaxial_tension_of};
use thm_dem::{CohesiveFrictionalParams, DemError};
use thm_vpn_flow::Network;
use thm_vpn_flow::permeability::{
    BarPermeability, DarcyTest, PermeabilityCalibration, T2tCalibration, calibrate_t2t_factor_of,
    incompressible_steady_flow,
};

use crate::bar::{
    BarCase, BarEnds, PAPER_BAR, bar_mesh_params, bar_params_sized, bar_spheres, bar_state_sized,
    water_air,
};
use crate::pore_scale::CouplingError;

/// A packing family of the A-Fig. 8 bar: its ends and how its pore mesh is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarFamily {
    /// The bar's `[width, length]` \[m\] (A-Fig. 8: 20 × 80 mm).
    pub size: [f64; 2],
    /// How the bar's ends are made (cut from a longer packing, or every sphere inside).
    pub ends: BarEnds,
    /// Points per circle of the pore mesh (the permeability only).
    pub segments: u32,
    /// The mesher's snap tolerance (× the radius; `MeshParams::snap_tolerance`).
    pub snap_tolerance: f64,
    /// T2T faces shorter than this \[m\] carry at least the zero-stress S2S aperture
    /// (`MeshParams::narrow_gap_length`; 0: A-Eq. 9 alone).
    pub narrow_gap_length: f64,
}

impl BarFamily {
    /// The family every coupled bar case runs on: cut ends, 32 points per circle.
    pub fn coupled_cases() -> Self {
        let mesh = bar_mesh_params(32, PAPER_BAR, BarEnds::Cut);
        Self {
            size: PAPER_BAR,
            ends: BarEnds::Cut,
            segments: 32,
            snap_tolerance: mesh.snap_tolerance,
            narrow_gap_length: mesh.narrow_gap_length,
        }
    }

    /// The tension test of A-Sect. 3.1 (`BarLoading::paper_a`: plates at ±10 mm/s, grips
    /// 1 mm deep) on packing `seed` with bond law `law`.
    pub fn tension(
        &self,
        seed: u64,
        law: &CohesiveFrictionalParams,
    ) -> Result<TensionResult, DemError> {
        let packing = bar_spheres(seed, self.size, self.ends);
        uniaxial_tension_of(&packing, law, &BarLoading::paper_a(), [0.0; 2], self.size)
    }

    /// The Darcy permeability (A-Eq. 56) of packing `seed`'s pore network as the cases mesh
    /// it (at rest, T2T reduction factor `gamma` on the mesh and the boundary links), between
    /// `test`'s reservoirs at the bottom and the top.
    pub fn permeability(
        &self,
        seed: u64,
        gamma: f64,
        test: &DarcyTest,
    ) -> Result<BarPermeability, CouplingError> {
        let case = BarCase::Cooling;
        let mut params = bar_params_sized(case, self.segments, self.size, self.ends);
        params.mesh.t2t_reduction_factor = gamma;
        params.mesh.snap_tolerance = self.snap_tolerance;
        params.mesh.narrow_gap_length = self.narrow_gap_length;
        params.boundary_reduction_factor = gamma;
        let config = params.validate()?;
        let state = bar_state_sized(case, &config, seed, &water_air(), self.size, self.ends)?;
        let mesh = &state.mesh.mesh;
        let net = Network::from_mesh(mesh, &test.reservoirs(), gamma)?;
        let steady = incompressible_steady_flow(&net, test.viscosity)?;
        Ok(BarPermeability {
            kappa: test.kappa_of_rate(
                steady.group_rate[1],
                self.size[1],
                self.size[0],
                mesh.thickness,
            ),
            percolates: steady.percolates,
        })
    }

    /// `T` (with `C = cal.cohesion_ratio · T`) for which the mean tensile strength of this
    /// family's packings `cal.seeds` is `cal.target_strength`.
    pub fn calibrate_bond_strength(
        &self,
        cal: &StrengthCalibration,
    ) -> Result<BondCalibration, DemError> {
        calibrate_bond_strength_of(cal, |seed, law| self.tension(seed, law))
    }

    /// γ for which the geometric mean of the permeabilities of this family's packings
    /// `cal.seeds` is `cal.target_permeability` (`cal.test` gives the reservoirs and the
    /// viscosity).
    pub fn calibrate_t2t_factor(
        &self,
        cal: &PermeabilityCalibration,
    ) -> Result<T2tCalibration, CouplingError> {
        calibrate_t2t_factor_of(cal, |seed, gamma| self.permeability(seed, gamma, &cal.test))
    }
}

impl BarFamily {
    /// Pores of packing `seed`'s network (case I ends, reservoirs at both ends) that no
    /// channel path joins to a boundary link: sealed by construction unless they are a void
    /// enclosed by solid ([`crate::pore_scale::unconnected_pores`]).
    pub fn sealed_pores(&self, seed: u64) -> Result<usize, CouplingError> {
        let case = BarCase::Cooling;
        let mut params = bar_params_sized(case, self.segments, self.size, self.ends);
        params.mesh.snap_tolerance = self.snap_tolerance;
        params.mesh.narrow_gap_length = self.narrow_gap_length;
        let config = params.validate()?;
        let state = bar_state_sized(case, &config, seed, &water_air(), self.size, self.ends)?;
        let stepper = crate::pore_scale::PoreScaleStepper::new(config, water_air(), &state)?;
        Ok(crate::pore_scale::unconnected_pores(stepper.network()))
    }

    /// Median sphere diameter d50 of packing `seed` (by number) \[m\] and the smallest and
    /// largest diameters.
    pub fn diameters(&self, seed: u64) -> [f64; 3] {
        let mut d: Vec<f64> = bar_spheres(seed, self.size, self.ends)
            .radii
            .iter()
            .map(|r| 2.0 * r)
            .collect();
        d.sort_by(f64::total_cmp);
        let n = d.len();
        if n == 0 {
            return [f64::NAN; 3];
        }
        let median = if n % 2 == 1 {
            d[n / 2]
        } else {
            0.5 * (d[n / 2 - 1] + d[n / 2])
        };
        [median, d[0], d[n - 1]]
    }
}
