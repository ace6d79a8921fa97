//! The caller-owned state and the per-step input from the flow solver.

use serde::{Deserialize, Serialize};
use thm_vpn_mesh::PoreMesh;

use crate::HeatError;
use crate::geometry::first_where;

/// Temperatures of all cells (fluid and solid), struct-of-arrays, owned by the caller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeatState {
    /// Simulated time \[s\].
    pub time: f64,
    /// Explicit sub-steps (or implicit steps) taken so far.
    pub steps: u64,
    /// Cell-centred temperature \[K\], one per mesh cell.
    pub temperature: Vec<f64>,
}

impl HeatState {
    /// All cells at `temperature` \[K\], at time 0.
    pub fn uniform(mesh: &PoreMesh, temperature: f64) -> Self {
        Self {
            time: 0.0,
            steps: 0,
            temperature: vec![temperature; mesh.n_cells()],
        }
    }
}

/// What the flow solver gives the heat solver for one step: phase fractions and densities of
/// the fluid cells and the mass fluxes of the channels and of the open boundary faces.
///
/// Per-cell arrays have one entry per mesh cell; entries of solid cells are ignored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlowInput {
    /// Liquid volume fraction α_q ∈ [0, 1] per cell (gas fraction 1 − α_q).
    pub liquid_fraction: Vec<f64>,
    /// Liquid density ρ_q per cell \[kg/m³\].
    pub liquid_density: Vec<f64>,
    /// Gas density ρ_p per cell \[kg/m³\].
    pub gas_density: Vec<f64>,
    /// Total (both phases) mass flux per channel \[kg/s\], positive from `channels.cells[k][0]`
    /// to `channels.cells[k][1]`.
    pub channel_mass_flux: Vec<f64>,
    /// Mass flux through each face \[kg/s\], positive outward; only boundary faces of fluid
    /// cells may be non-zero (inflow/outflow through the specimen's boundary).
    pub boundary_mass_flux: Vec<f64>,
    /// Specific heat of what each channel carried over the step \[J/(kg K)\]: with phase
    /// transfers `M_q`, `M_p`, `(M_q c_q + M_p c_p) / (M_q + M_p)`. Empty: the upwind cell's
    /// mixture value (mass-weighted). A flow solver that moves the phases in other
    /// proportions than the upwind cell holds at the end of the step must give it: the
    /// advected heat capacity `ṁ c` then equals the capacity the cells exchanged, so a cell's
    /// capacity change and its advected heat stay consistent (no spurious heating or cooling
    /// of a uniform field; see `channel_specific_heat_keeps_a_uniform_field_uniform`).
    #[serde(default)]
    pub channel_specific_heat: Vec<f64>,
}

impl FlowInput {
    /// The specific heat channel `k` advects with: [`Self::channel_specific_heat`] where
    /// given, else `upwind` (the upwind cell's mixture value) \[J/(kg K)\].
    #[inline]
    pub(crate) fn channel_cp(&self, k: usize, upwind: f64) -> f64 {
        self.channel_specific_heat.get(k).copied().unwrap_or(upwind)
    }

    /// Fluid at rest, fully liquid with uniform density `liquid_density`; the gas density is
    /// set to `gas_density` (irrelevant while α_q = 1).
    pub fn liquid_at_rest(mesh: &PoreMesh, liquid_density: f64, gas_density: f64) -> Self {
        let n = mesh.n_cells();
        Self {
            liquid_fraction: vec![1.0; n],
            liquid_density: vec![liquid_density; n],
            gas_density: vec![gas_density; n],
            channel_mass_flux: vec![0.0; mesh.channels.len()],
            boundary_mass_flux: vec![0.0; mesh.n_faces()],
            channel_specific_heat: Vec::new(),
        }
    }

    /// Checks lengths against `mesh` and ranges of the fluid-cell entries.
    pub fn validate(&self, mesh: &PoreMesh) -> Result<(), HeatError> {
        self.check_lengths(mesh)?;
        // One parallel pass per array family finds the first bad entry; the error is then
        // built serially for that entry (same error as a serial scan).
        if let Some(c) = first_where(mesh.n_cells(), |c| {
            mesh.cell_kind[c].is_fluid() && !self.fluid_entry_ok(c)
        }) {
            return Err(self.fluid_entry_error(c));
        }
        self.check_fluxes(mesh)
    }

    /// The length checks of [`Self::validate`].
    pub(crate) fn check_lengths(&self, mesh: &PoreMesh) -> Result<(), HeatError> {
        let n = mesh.n_cells();
        for (what, len, expected) in [
            ("liquid_fraction", self.liquid_fraction.len(), n),
            ("liquid_density", self.liquid_density.len(), n),
            ("gas_density", self.gas_density.len(), n),
            (
                "channel_mass_flux",
                self.channel_mass_flux.len(),
                mesh.channels.len(),
            ),
            (
                "boundary_mass_flux",
                self.boundary_mass_flux.len(),
                mesh.n_faces(),
            ),
        ] {
            if len != expected {
                return Err(HeatError::LengthMismatch {
                    what,
                    expected,
                    got: len,
                });
            }
        }
        Ok(())
    }

    /// Whether the entries of fluid cell `c` are in range (lengths checked).
    #[inline]
    pub(crate) fn fluid_entry_ok(&self, c: usize) -> bool {
        fluid_entry_ok(
            self.liquid_fraction[c],
            self.liquid_density[c],
            self.gas_density[c],
        )
    }

    /// The error for a fluid cell whose entries are not in range.
    pub(crate) fn fluid_entry_error(&self, c: usize) -> HeatError {
        let a = self.liquid_fraction[c];
        if !(a.is_finite() && (0.0..=1.0).contains(&a)) {
            return HeatError::InputOutOfRange {
                quantity: "liquid_fraction",
                index: c,
                range: "in [0, 1]",
                value: a,
            };
        }
        for (quantity, v) in [
            ("liquid_density", self.liquid_density[c]),
            ("gas_density", self.gas_density[c]),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return HeatError::InputOutOfRange {
                    quantity,
                    index: c,
                    range: ">= 0 kg/m³",
                    value: v,
                };
            }
        }
        HeatError::InputOutOfRange {
            quantity: "effective fluid density",
            index: c,
            range: "> 0 kg/m³",
            value: a * self.liquid_density[c] + (1.0 - a) * self.gas_density[c],
        }
    }

    /// The mass-flux checks of [`Self::validate`] (lengths checked).
    pub(crate) fn check_fluxes(&self, mesh: &PoreMesh) -> Result<(), HeatError> {
        let cp = &self.channel_specific_heat;
        if !cp.is_empty() && cp.len() != mesh.channels.len() {
            return Err(HeatError::LengthMismatch {
                what: "channel_specific_heat",
                expected: mesh.channels.len(),
                got: cp.len(),
            });
        }
        if let Some(k) = first_where(cp.len(), |k| !(cp[k].is_finite() && cp[k] > 0.0)) {
            return Err(HeatError::InputOutOfRange {
                quantity: "channel_specific_heat",
                index: k,
                range: "finite and > 0 J/(kg K)",
                value: cp[k],
            });
        }
        let flux = &self.channel_mass_flux;
        if let Some(k) = first_where(flux.len(), |k| !flux[k].is_finite()) {
            return Err(HeatError::InputOutOfRange {
                quantity: "channel_mass_flux",
                index: k,
                range: "finite",
                value: self.channel_mass_flux[k],
            });
        }
        let boundary = &self.boundary_mass_flux;
        if let Some(f) = first_where(boundary.len(), |f| {
            let m = boundary[f];
            // The face's cells are only looked at where the flux is not zero.
            !m.is_finite()
                || (m != 0.0 && {
                    let [c0, c1] = mesh.face_cells[f];
                    !(c1 == thm_vpn_mesh::NONE && mesh.cell_kind[c0 as usize].is_fluid())
                })
        }) {
            return Err(HeatError::InputOutOfRange {
                quantity: "boundary_mass_flux",
                index: f,
                range: "finite, and 0 except on boundary faces of fluid cells",
                value: self.boundary_mass_flux[f],
            });
        }
        Ok(())
    }
}

/// Whether a fluid cell's liquid fraction `a` and phase densities `rq`, `rp` are in range:
/// a ∈ [0, 1], ρ ∈ [0, ∞), and a positive mixture density.
#[inline]
pub(crate) fn fluid_entry_ok(a: f64, rq: f64, rp: f64) -> bool {
    // Comparisons with NaN are false: a ∈ [0, 1] and ρ ∈ [0, ∞) exclude NaN and ∞. The
    // terms are joined with `&` (no short circuit), as this runs for every fluid cell every
    // step.
    (0.0..=1.0).contains(&a)
        & (0.0..f64::INFINITY).contains(&rq)
        & (0.0..f64::INFINITY).contains(&rp)
        & (a * rq + (1.0 - a) * rp > 0.0)
}
