//! Boundary conditions and loads: prescribed nodal velocity (fixed, roller), prescribed nodal
//! temperature (B-Eq. 4a), surface tractions and heat fluxes through the virtual boundary layer
//! (B-Eqs. 17–18), gravity, and rigid walls/plates with Coulomb friction that may move at a
//! prescribed velocity and be removed at a given time.

use crate::error::MpmError;
use crate::grid::Grid;
use serde::{Deserialize, Serialize};

/// A side of the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// `x = x_min`.
    Left,
    /// `x = x_max`.
    Right,
    /// `y = y_min`.
    Bottom,
    /// `y = y_max`.
    Top,
}

/// A set of grid nodes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NodeSet {
    /// The nodes on one side of the grid.
    Side(Side),
    /// Every node (e.g. `v_y = 0` everywhere for a 1D problem).
    All,
    /// The nodes whose positions lie in the closed rectangle `[lower, upper]` (m), e.g. a
    /// grid line inside a padded grid.
    Region {
        /// Lower-left corner (m).
        lower: [f64; 2],
        /// Upper-right corner (m).
        upper: [f64; 2],
    },
}

impl NodeSet {
    /// True when node `(i, j)` belongs to the set.
    pub fn contains(&self, grid: &Grid, i: usize, j: usize) -> bool {
        let [nx, ny] = grid.nodes();
        match self {
            NodeSet::All => true,
            NodeSet::Side(Side::Left) => i == 0,
            NodeSet::Side(Side::Right) => i + 1 == nx,
            NodeSet::Side(Side::Bottom) => j == 0,
            NodeSet::Side(Side::Top) => j + 1 == ny,
            NodeSet::Region { lower, upper } => {
                let x = grid.node_position(i, j);
                x[0] >= lower[0] && x[0] <= upper[0] && x[1] >= lower[1] && x[1] <= upper[1]
            }
        }
    }
}

/// Prescribed zero nodal velocity components: `fix_x` and `fix_y` both true is a fixed
/// boundary, one of them a roller.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityCondition {
    /// Where.
    pub nodes: NodeSet,
    /// Hold `v_x = 0`.
    pub fix_x: bool,
    /// Hold `v_y = 0`.
    pub fix_y: bool,
}

/// Prescribed nodal temperature on a side (B-Eq. 4a).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TemperatureCondition {
    /// Where.
    pub nodes: NodeSet,
    /// The temperature `T̄`.
    pub temperature: f64,
}

/// A traction and an inward heat flux applied through the virtual boundary layer
/// (B-Eqs. 17–18, Zhang et al., 2011): every point whose centre lies in the rectangle
/// `[lower, upper]` receives the body force `t̄ V_p / h` and the heat `q̄ V_p / h`, `h` being
/// `layer_thickness`. Choose the rectangle as the band of thickness `h` under the loaded
/// surface, so that `Σ V_p / h` equals the loaded length.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceLoad {
    /// Lower-left corner of the layer (m).
    pub lower: [f64; 2],
    /// Upper-right corner of the layer (m).
    pub upper: [f64; 2],
    /// Virtual boundary layer thickness `h` (m).
    pub layer_thickness: f64,
    /// Traction `t̄` (Pa).
    pub traction: [f64; 2],
    /// Heat flux into the body through the surface (W/m²); `−q̄·n` of B-Eq. 4b.
    pub inward_heat_flux: f64,
}

impl SurfaceLoad {
    /// True when the point centre `x` lies in the layer.
    #[inline]
    pub fn contains(&self, x: [f64; 2]) -> bool {
        x[0] >= self.lower[0]
            && x[0] <= self.upper[0]
            && x[1] >= self.lower[1]
            && x[1] <= self.upper[1]
    }
}

/// A rigid wall or plate: the half-plane behind the line through `point` with unit normal
/// `normal` (pointing into the material). Grid nodes on or behind the line take the wall's
/// velocity in the normal direction when they approach it, and Coulomb friction
/// `|Δv_t| ≤ μ |Δv_n|` tangentially; nodes that separate are left free. The line moves with
/// `velocity`; the wall disappears at `removal_time` (if any).
///
/// A wall can be finite (a silo's side, a hopper's inclined side): `extent` limits it along
/// the line to `s_min ≤ s ≤ s_max`, with `s = (x − p(t))·t̂` measured from the moving `point`
/// along `t̂ = (n_y, −n_x)`, and `depth` limits the region it acts on to a band `−depth ≤ d ≤ 0`
/// behind the line, so that material on the far side of a thin wall (or past its end) moves
/// freely. [`RigidWall::segment`] builds one from its two end points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidWall {
    /// A point of the wall line at time 0 (m).
    pub point: [f64; 2],
    /// Normal into the material (normalised on validation).
    pub normal: [f64; 2],
    /// Prescribed wall velocity (m/s).
    pub velocity: [f64; 2],
    /// Coulomb friction coefficient μ ≥ 0 (`inf` = no slip).
    pub friction: f64,
    /// Time at which the wall is removed (s); `None` = never.
    #[serde(default)]
    pub removal_time: Option<f64>,
    /// `[s_min, s_max]` along the line (m), see above; `None` = the whole line.
    #[serde(default)]
    pub extent: Option<[f64; 2]>,
    /// Depth of the band behind the line that the wall acts on (m), see above; `None` = the
    /// whole half-plane.
    #[serde(default)]
    pub depth: Option<f64>,
}

impl RigidWall {
    /// An infinite, fixed wall: the half-plane behind the line through `point` with normal
    /// `normal` into the material.
    pub fn half_plane(point: [f64; 2], normal: [f64; 2], friction: f64) -> Self {
        Self {
            point,
            normal,
            velocity: [0.0; 2],
            friction,
            removal_time: None,
            extent: None,
            depth: None,
        }
    }

    /// A fixed wall segment from `a` to `b` with the material on its left (the normal is
    /// `b − a` turned by +90°), acting on nodes up to `depth` behind it.
    pub fn segment(a: [f64; 2], b: [f64; 2], friction: f64, depth: f64) -> Self {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let length = (dx * dx + dy * dy).sqrt();
        Self {
            point: a,
            normal: [-dy / length, dx / length],
            velocity: [0.0; 2],
            friction,
            removal_time: None,
            extent: Some([0.0, length]),
            depth: Some(depth),
        }
    }

    pub(crate) fn validated(mut self, k: usize) -> Result<Self, MpmError> {
        let n = (self.normal[0] * self.normal[0] + self.normal[1] * self.normal[1]).sqrt();
        if !(n.is_finite() && n > 0.0) {
            return Err(MpmError::InvalidParameter {
                name: format!("walls[{k}].normal"),
                value: n,
                allowed: "non-zero finite vector",
            });
        }
        self.normal = [self.normal[0] / n, self.normal[1] / n];
        if self.friction.is_nan() || self.friction < 0.0 {
            return Err(MpmError::InvalidParameter {
                name: format!("walls[{k}].friction"),
                value: self.friction,
                allowed: "[0, inf]",
            });
        }
        if let Some([lo, hi]) = self.extent
            && !(lo.is_finite() && hi.is_finite() && lo < hi)
        {
            return Err(MpmError::InvalidParameter {
                name: format!("walls[{k}].extent"),
                value: if lo.is_finite() { hi } else { lo },
                allowed: "[s_min, s_max] finite with s_min < s_max (m)",
            });
        }
        if let Some(h) = self.depth
            && !(h.is_finite() && h > 0.0)
        {
            return Err(MpmError::InvalidParameter {
                name: format!("walls[{k}].depth"),
                value: h,
                allowed: "(0, inf) m",
            });
        }
        for v in self.point.iter().chain(self.velocity.iter()) {
            if !v.is_finite() {
                return Err(MpmError::InvalidParameter {
                    name: format!("walls[{k}].point/velocity"),
                    value: *v,
                    allowed: "finite",
                });
            }
        }
        Ok(self)
    }

    /// Whether the wall acts at time `t`.
    #[inline]
    pub fn active(&self, t: f64) -> bool {
        self.removal_time.is_none_or(|tr| t < tr)
    }

    /// Signed distance of `x` from the wall line at time `t` (positive on the material side).
    #[inline]
    pub fn distance(&self, x: [f64; 2], t: f64) -> f64 {
        let px = self.point[0] + self.velocity[0] * t;
        let py = self.point[1] + self.velocity[1] * t;
        (x[0] - px) * self.normal[0] + (x[1] - py) * self.normal[1]
    }

    /// Coordinate of `x` along the wall line at time `t`, `(x − p(t))·t̂` with
    /// `t̂ = (n_y, −n_x)` (m).
    #[inline]
    pub fn along(&self, x: [f64; 2], t: f64) -> f64 {
        let px = self.point[0] + self.velocity[0] * t;
        let py = self.point[1] + self.velocity[1] * t;
        (x[0] - px) * self.normal[1] - (x[1] - py) * self.normal[0]
    }

    /// Whether the wall constrains a node at `x` at time `t`: present, `x` on or behind the
    /// line, within the band `depth` and within `extent` along it.
    #[inline]
    pub fn acts_on(&self, x: [f64; 2], t: f64) -> bool {
        if !self.active(t) {
            return false;
        }
        let d = self.distance(x, t);
        if d > 0.0 || self.depth.is_some_and(|h| d < -h) {
            return false;
        }
        self.extent.is_none_or(|[lo, hi]| {
            let s = self.along(x, t);
            s >= lo && s <= hi
        })
    }

    /// The contact correction of a nodal velocity `v` (new velocity, after the grid update).
    #[inline]
    pub fn constrain(&self, v: [f64; 2]) -> [f64; 2] {
        let n = self.normal;
        let rel = [v[0] - self.velocity[0], v[1] - self.velocity[1]];
        let vn = rel[0] * n[0] + rel[1] * n[1];
        if vn >= 0.0 {
            return v; // separating
        }
        let mut t = [rel[0] - vn * n[0], rel[1] - vn * n[1]];
        let tn = (t[0] * t[0] + t[1] * t[1]).sqrt();
        let slip = self.friction * (-vn);
        if tn <= slip || self.friction.is_infinite() {
            t = [0.0, 0.0];
        } else {
            let f = (tn - slip) / tn;
            t = [t[0] * f, t[1] * f];
        }
        [self.velocity[0] + t[0], self.velocity[1] + t[1]]
    }
}
