//! Material points, struct-of-arrays, owned by the caller.

use crate::error::MpmError;
use crate::grid::Grid;
use serde::{Deserialize, Serialize};

/// A symmetric 2 × 2 tensor stored as `[xx, yy, xy]`.
pub type Sym2 = [f64; 3];
/// A general 2 × 2 tensor stored row-major as `[xx, xy, yx, yy]`.
pub type Mat2 = [f64; 4];

/// Material points (struct-of-arrays). All arrays have one entry per point.
///
/// Units: SI. Out of plane the model has unit thickness (1 m): "volume" is area × 1 m, "mass"
/// is kg per metre of thickness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialPoints {
    /// Position `x_p` (m).
    pub position: Vec<[f64; 2]>,
    /// Velocity `v_p` (m/s).
    pub velocity: Vec<[f64; 2]>,
    /// Mass `m_p` (kg), constant.
    pub mass: Vec<f64>,
    /// Current volume `V_p = V_p0 det F` (m³).
    pub volume: Vec<f64>,
    /// Initial volume `V_p0` (m³).
    pub initial_volume: Vec<f64>,
    /// Half-sizes `l_p` of the undeformed top-hat domain (uGIMP), each in `(0, l_e/2]` (m).
    pub half_size: Vec<[f64; 2]>,
    /// Cauchy stress `[σxx, σyy, σxy]` (Pa), tension positive.
    pub stress: Vec<Sym2>,
    /// Deformation gradient `F` (row-major).
    pub deformation_gradient: Vec<Mat2>,
    /// Accumulated small strain `∫ sym(L) dt` `[εxx, εyy, εxy]` (tensor shear component).
    pub strain: Vec<Sym2>,
    /// Tracked temperature `T_p` updated by increments, B-Eq. 28 (K or °C).
    pub temperature: Vec<f64>,
    /// Remapped (smooth) temperature, B-Eq. 29 (same unit); the input of the material.
    pub remapped_temperature: Vec<f64>,
    /// Specific heat capacity `c_p` (J/(kg K)).
    pub specific_heat: Vec<f64>,
    /// Thermal conductivity tensor `k_ij` `[kxx, kyy, kxy]` (W/(m K)), from the material.
    pub conductivity: Vec<Sym2>,
    /// Heat source `Q_tp` (W/m³), from the material.
    pub heat_source: Vec<f64>,
}

/// Uniform properties used by [`MaterialPoints::fill_rectangle`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointProperties {
    /// Mass density ρ (kg/m³).
    pub density: f64,
    /// Specific heat capacity c (J/(kg K)).
    pub specific_heat: f64,
    /// Initial conductivity `[kxx, kyy, kxy]` (W/(m K)), replaced by the material's answer.
    pub conductivity: Sym2,
    /// Initial temperature.
    pub temperature: f64,
    /// Initial velocity (m/s).
    pub velocity: [f64; 2],
}

impl PointProperties {
    /// Checks the properties, naming the offending one.
    pub fn validate(&self) -> Result<(), MpmError> {
        let pos = |name: &str, v: f64, allowed: &'static str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(MpmError::InvalidParameter {
                    name: name.into(),
                    value: v,
                    allowed,
                })
            }
        };
        pos("density", self.density, "(0, inf) kg/m^3")?;
        pos("specific_heat", self.specific_heat, "(0, inf) J/(kg K)")?;
        validate_conductivity("conductivity", self.conductivity)?;
        for (name, v) in [
            ("temperature", self.temperature),
            ("velocity[0]", self.velocity[0]),
            ("velocity[1]", self.velocity[1]),
        ] {
            if !v.is_finite() {
                return Err(MpmError::InvalidParameter {
                    name: name.into(),
                    value: v,
                    allowed: "finite",
                });
            }
        }
        Ok(())
    }
}

impl MaterialPoints {
    /// An empty set.
    pub fn new() -> Self {
        Self::with_capacity(0)
    }

    /// An empty set with room for `n` points.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            position: Vec::with_capacity(n),
            velocity: Vec::with_capacity(n),
            mass: Vec::with_capacity(n),
            volume: Vec::with_capacity(n),
            initial_volume: Vec::with_capacity(n),
            half_size: Vec::with_capacity(n),
            stress: Vec::with_capacity(n),
            deformation_gradient: Vec::with_capacity(n),
            strain: Vec::with_capacity(n),
            temperature: Vec::with_capacity(n),
            remapped_temperature: Vec::with_capacity(n),
            specific_heat: Vec::with_capacity(n),
            conductivity: Vec::with_capacity(n),
            heat_source: Vec::with_capacity(n),
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Appends one point of rectangular domain `2 half[0] × 2 half[1]` at rest stress.
    pub fn push(&mut self, position: [f64; 2], half: [f64; 2], props: &PointProperties) {
        let volume = 4.0 * half[0] * half[1];
        self.position.push(position);
        self.velocity.push(props.velocity);
        self.mass.push(props.density * volume);
        self.volume.push(volume);
        self.initial_volume.push(volume);
        self.half_size.push(half);
        self.stress.push([0.0; 3]);
        self.deformation_gradient.push([1.0, 0.0, 0.0, 1.0]);
        self.strain.push([0.0; 3]);
        self.temperature.push(props.temperature);
        self.remapped_temperature.push(props.temperature);
        self.specific_heat.push(props.specific_heat);
        self.conductivity.push(props.conductivity);
        self.heat_source.push(0.0);
    }

    /// Fills the rectangle `[lower, upper]` with `per_cell × per_cell` points in each grid
    /// cell it covers (the rectangle should be aligned with grid lines), each carrying the
    /// domain `l_e/per_cell` square. Errors on invalid properties (non-positive density or
    /// heat capacity, negative or asymmetric conductivity, non-finite values).
    pub fn fill_rectangle(
        &mut self,
        grid: &Grid,
        lower: [f64; 2],
        upper: [f64; 2],
        per_cell: usize,
        props: &PointProperties,
    ) -> Result<(), MpmError> {
        props.validate()?;
        if per_cell == 0 {
            return Err(MpmError::InvalidParameter {
                name: "per_cell".into(),
                value: 0.0,
                allowed: "[1, inf)",
            });
        }
        let n = per_cell;
        let dx = grid.cell_size() / n as f64;
        let nx = ((upper[0] - lower[0]) / dx).round().max(0.0) as usize;
        let ny = ((upper[1] - lower[1]) / dx).round().max(0.0) as usize;
        let half = [0.5 * dx, 0.5 * dx];
        for j in 0..ny {
            for i in 0..nx {
                let p = [
                    lower[0] + (i as f64 + 0.5) * dx,
                    lower[1] + (j as f64 + 0.5) * dx,
                ];
                self.push(p, half, props);
            }
        }
        Ok(())
    }

    /// Checks that all arrays have the same length and that every point has positive mass,
    /// volume and density, non-negative heat capacity, finite fields and a domain inside the
    /// grid with half-sizes in `(0, l_e/2]`.
    pub fn validate(&self, grid: &Grid, step: u64) -> Result<(), MpmError> {
        let n = self.position.len();
        let lens: [(&'static str, usize); 13] = [
            ("velocity", self.velocity.len()),
            ("mass", self.mass.len()),
            ("volume", self.volume.len()),
            ("initial_volume", self.initial_volume.len()),
            ("half_size", self.half_size.len()),
            ("stress", self.stress.len()),
            ("deformation_gradient", self.deformation_gradient.len()),
            ("strain", self.strain.len()),
            ("temperature", self.temperature.len()),
            ("remapped_temperature", self.remapped_temperature.len()),
            ("specific_heat", self.specific_heat.len()),
            ("conductivity", self.conductivity.len()),
            ("heat_source", self.heat_source.len()),
        ];
        for (field, len) in lens {
            if len != n {
                return Err(MpmError::LengthMismatch {
                    field,
                    len,
                    expected: n,
                });
            }
        }
        let h = grid.cell_size();
        for p in 0..n {
            let bad = |field: &'static str, value: f64, allowed: &'static str| {
                Err(MpmError::InvalidPoint {
                    index: p,
                    field,
                    value,
                    allowed,
                })
            };
            let m = self.mass[p];
            if !(m.is_finite() && m > 0.0) {
                return bad("mass", m, "(0, inf) kg");
            }
            let v = self.volume[p];
            if !(v.is_finite() && v > 0.0) {
                return bad("volume", v, "(0, inf) m^3");
            }
            let v0 = self.initial_volume[p];
            if !(v0.is_finite() && v0 > 0.0) {
                return bad("initial_volume", v0, "(0, inf) m^3");
            }
            let c = self.specific_heat[p];
            if !(c.is_finite() && c > 0.0) {
                return bad("specific_heat", c, "(0, inf) J/(kg K)");
            }
            for k in 0..2 {
                let l = self.half_size[p][k];
                if !(l.is_finite() && l > 0.0 && l <= 0.5 * h * (1.0 + 1e-12)) {
                    return bad("half_size", l, "(0, cell_size/2] m");
                }
                if !self.velocity[p][k].is_finite() {
                    return bad("velocity", self.velocity[p][k], "finite");
                }
            }
            if !self.temperature[p].is_finite() {
                return bad("temperature", self.temperature[p], "finite");
            }
            let kt = self.conductivity[p];
            if !(kt[0] >= 0.0 && kt[1] >= 0.0 && kt[0] * kt[1] - kt[2] * kt[2] >= 0.0) {
                return bad(
                    "conductivity",
                    kt[0].min(kt[1]),
                    "positive semi-definite tensor",
                );
            }
            if !self.stress[p].iter().all(|s| s.is_finite()) {
                return bad("stress", self.stress[p][0], "finite");
            }
            self.check_inside(grid, p, step)?;
        }
        Ok(())
    }

    /// Error unless the domain of point `p` lies inside the grid.
    #[inline]
    pub fn check_inside(&self, grid: &Grid, p: usize, step: u64) -> Result<(), MpmError> {
        let [x, y] = self.position[p];
        let [lx, ly] = self.half_size[p];
        let lo = grid.origin();
        let hi = grid.upper();
        let inside = x - lx >= lo[0] && x + lx <= hi[0] && y - ly >= lo[1] && y + ly <= hi[1];
        if inside {
            Ok(())
        } else {
            Err(MpmError::PointOutsideGrid {
                index: p,
                x,
                y,
                lx,
                ly,
                x_min: lo[0],
                x_max: hi[0],
                y_min: lo[1],
                y_max: hi[1],
                step,
            })
        }
    }

    /// Total mass Σ m_p (kg), summed in index order.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Total momentum Σ m_p v_p (kg m/s), summed in index order.
    pub fn total_momentum(&self) -> [f64; 2] {
        let mut s = [0.0; 2];
        for (m, v) in self.mass.iter().zip(&self.velocity) {
            s[0] += m * v[0];
            s[1] += m * v[1];
        }
        s
    }
}

impl Default for MaterialPoints {
    fn default() -> Self {
        Self::new()
    }
}

/// Checks that a conductivity tensor is finite, symmetric positive semi-definite.
pub fn validate_conductivity(name: &str, k: Sym2) -> Result<(), MpmError> {
    if !(k.iter().all(|v| v.is_finite()) && k[0] >= 0.0 && k[1] >= 0.0) || k[0] * k[1] < k[2] * k[2]
    {
        return Err(MpmError::InvalidParameter {
            name: name.into(),
            value: k[0].min(k[1]),
            allowed: "symmetric positive semi-definite [kxx, kyy, kxy] W/(m K)",
        });
    }
    Ok(())
}
