//! Volume-average temperature of each sphere's solid cells: T_avg of A-Eq. 55, the input of
//! thermal expansion in the DEM.

use thm_vpn_mesh::{CellKind, PoreMesh};

use crate::HeatError;

/// Writes into `out[j]` the volume-average temperature Σ V_c T_c / Σ V_c of the solid cells
/// owned by sphere `j` \[K\], for `j` in `0..=max owner`; `None` for a sphere without solid
/// cells. Sums run in cell order (deterministic).
pub fn sphere_mean_temperatures(
    mesh: &PoreMesh,
    temperature: &[f64],
    out: &mut Vec<Option<f64>>,
) -> Result<(), HeatError> {
    if temperature.len() != mesh.n_cells() {
        return Err(HeatError::LengthMismatch {
            what: "temperature",
            expected: mesh.n_cells(),
            got: temperature.len(),
        });
    }
    let n_spheres = sphere_count(mesh);
    // Σ A T and Σ A per sphere (thickness cancels).
    out.clear();
    out.resize(n_spheres, None);
    let mut area = vec![0.0; n_spheres];
    let mut sum = vec![0.0; n_spheres];
    for (c, k) in mesh.cell_kind.iter().enumerate() {
        if let CellKind::Solid { owner } = k {
            let j = *owner as usize;
            area[j] += mesh.cell_area[c];
            sum[j] += mesh.cell_area[c] * temperature[c];
        }
    }
    for j in 0..n_spheres {
        if area[j] > 0.0 {
            out[j] = Some(sum[j] / area[j]);
        }
    }
    Ok(())
}

/// Number of spheres the mesh's solid cells refer to: one more than the largest owner index
/// (0 for a mesh without solid cells).
pub(crate) fn sphere_count(mesh: &PoreMesh) -> usize {
    mesh.cell_kind
        .iter()
        .filter_map(|k| match k {
            CellKind::Solid { owner } => Some(*owner as usize + 1),
            CellKind::Fluid => None,
        })
        .max()
        .unwrap_or(0)
}
