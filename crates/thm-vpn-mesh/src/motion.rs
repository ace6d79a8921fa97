//! Motion of the mesh with the spheres between remeshes, cell volume rates, and the remesh
//! trigger.
//!
//! Every vertex is *anchored* to up to three circles (an arc point to its circle, a chord end
//! to the two circles that cut, a radical centre to three). Anchor `k` transports the
//! mesh-time position `x₀` rigidly with its circle, scaled by the radius change:
//! `y_k = c_k + r_k R(φ_k) (x₀ − c_k⁰) / r_k⁰`, and the vertex sits at the mean of its `y_k`.
//! A point on a circle therefore stays on it exactly. The vertex velocity is the exact time
//! derivative of that position, the mean of
//! `w_k = v_k + ω_k ẑ × (y_k − c_k) + (ṙ_k / r_k)(y_k − c_k)`.
//! Vertices on a box side keep their coordinate normal to the side (the normal velocity is
//! zero); box corners are fixed.
//!
//! The area rate of a triangle with corners `p_a, p_b, p_c` moving with `u_a, u_b, u_c` is the
//! exact derivative of `A = ½ (p_b − p_a) × (p_c − p_a)`:
//! `dA/dt = ½ [(u_b − u_a) × (p_c − p_a) + (p_b − p_a) × (u_c − u_a)]`,
//! and `dV/dt = thickness · dA/dt` (what A-Eq. 25 needs from the DEM).

use serde::{Deserialize, Serialize};

use crate::circles::Contact;
pub use crate::circles::{VertexAnchors, VertexConstraint};
use crate::error::MeshError;
use crate::mesh::PoreMesh;
use crate::mesher::PackingMesh;

/// The DEM state of the circles (same order as at mesh time), borrowed from the caller.
#[derive(Debug, Clone, Copy)]
pub struct CircleMotion<'a> {
    /// Centres \[m\].
    pub centre: &'a [[f64; 2]],
    /// Radii \[m\].
    pub radius: &'a [f64],
    /// Angle turned counter-clockwise since the mesh was built \[rad\].
    pub rotation: &'a [f64],
    /// Centre velocities [m/s].
    pub velocity: &'a [[f64; 2]],
    /// Angular velocities about z [rad/s].
    pub angular_velocity: &'a [f64],
    /// Radius rates dr/dt [m/s].
    pub radius_rate: &'a [f64],
}

impl CircleMotion<'_> {
    /// Checks lengths against `n` circles and that every value is finite (radii > 0).
    pub fn validate(&self, n: usize) -> Result<(), MeshError> {
        let lens = [
            ("centre", self.centre.len()),
            ("radius", self.radius.len()),
            ("rotation", self.rotation.len()),
            ("velocity", self.velocity.len()),
            ("angular_velocity", self.angular_velocity.len()),
            ("radius_rate", self.radius_rate.len()),
        ];
        for (what, got) in lens {
            if got != n {
                return Err(MeshError::LengthMismatch {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        check_finite("centre", self.centre.iter().flatten().copied())?;
        check_finite("rotation", self.rotation.iter().copied())?;
        check_finite("velocity", self.velocity.iter().flatten().copied())?;
        check_finite("angular_velocity", self.angular_velocity.iter().copied())?;
        check_finite("radius_rate", self.radius_rate.iter().copied())?;
        let radius_ok = |r: f64| r.is_finite() && r > 0.0;
        if self.radius.iter().fold(true, |ok, &r| ok & radius_ok(r)) {
            return Ok(());
        }
        for (circle, &value) in self.radius.iter().enumerate() {
            if !radius_ok(value) {
                return Err(MeshError::InvalidRadius { circle, value });
            }
        }
        Ok(())
    }
}

/// The first non-finite value of `values` as a [`MeshError::NonFinite`] (index in the
/// flattened sequence).
fn check_finite(
    what: &'static str,
    values: impl Iterator<Item = f64> + Clone,
) -> Result<(), MeshError> {
    // A scan without early exit first (a straight loop), the search for the index only when
    // it fails.
    if values.clone().fold(true, |ok, v| ok & v.is_finite()) {
        return Ok(());
    }
    for (index, value) in values.enumerate() {
        if !value.is_finite() {
            return Err(MeshError::NonFinite { what, index, value });
        }
    }
    Ok(())
}

/// The rigid-body-plus-scaling frame of one circle: centre, `r (cos φ, sin φ)`, velocity,
/// angular velocity and `ṙ / r`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CircleFrame {
    centre: [f64; 2],
    r_cos: f64,
    r_sin: f64,
    velocity: [f64; 2],
    omega: f64,
    growth: f64,
}

/// Fills `frames` (one per circle) from the circle state.
pub fn circle_frames(motion: &CircleMotion<'_>, frames: &mut Vec<CircleFrame>) {
    frames.clear();
    frames.extend((0..motion.centre.len()).map(|i| {
        let r = motion.radius[i];
        let (s, c) = motion.rotation[i].sin_cos();
        CircleFrame {
            centre: motion.centre[i],
            r_cos: r * c,
            r_sin: r * s,
            velocity: motion.velocity[i],
            omega: motion.angular_velocity[i],
            growth: motion.radius_rate[i] / r,
        }
    }));
}

/// Position and velocity of every vertex for the given circle state (stage "vertex
/// kinematics"); `n_circles` is the number of circles at mesh time. `pos` and `vel` must have
/// one entry per vertex.
pub fn vertex_kinematics(
    anchors: &VertexAnchors,
    n_circles: usize,
    motion: &CircleMotion<'_>,
    pos: &mut [[f64; 2]],
    vel: &mut [[f64; 2]],
) -> Result<(), MeshError> {
    motion.validate(n_circles)?;
    for (what, got) in [("pos", pos.len()), ("vel", vel.len())] {
        if got != anchors.len() {
            return Err(MeshError::LengthMismatch {
                what,
                expected: anchors.len(),
                got,
            });
        }
    }
    check_anchors(anchors, n_circles)?;
    let mut frames = Vec::new();
    circle_frames(motion, &mut frames);
    vertex_kinematics_in_frames(anchors, &frames, pos, vel);
    Ok(())
}

/// Position `y` and velocity `w` of the point with offset `o = (x₀ − c⁰) / r⁰` carried by the
/// circle frame `f`.
#[inline(always)]
fn anchor_motion(f: &CircleFrame, o: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let rel = [
        f.r_cos * o[0] - f.r_sin * o[1],
        f.r_sin * o[0] + f.r_cos * o[1],
    ];
    (
        [f.centre[0] + rel[0], f.centre[1] + rel[1]],
        [
            f.velocity[0] - f.omega * rel[1] + f.growth * rel[0],
            f.velocity[1] + f.omega * rel[0] + f.growth * rel[1],
        ],
    )
}

/// Checks that the anchor rows are consistent and name circles below `n_circles` (the scans
/// over all rows have no early exit, so they run as straight vector loops).
fn check_anchors(anchors: &VertexAnchors, n_circles: usize) -> Result<(), MeshError> {
    let decreasing = anchors
        .start
        .windows(2)
        .fold(false, |bad, w| bad | (w[0] > w[1]));
    if anchors.start.len() != anchors.len() + 1
        || anchors.start.last().map(|&e| e as usize) != Some(anchors.circle.len())
        || anchors.offset.len() != anchors.circle.len()
        || anchors.reference.len() != anchors.len()
        || anchors.start.first() != Some(&0)
        || decreasing
    {
        return Err(MeshError::LengthMismatch {
            what: "vertex anchor rows",
            expected: anchors.len() + 1,
            got: anchors.start.len(),
        });
    }
    let largest = anchors.circle.iter().fold(0u32, |m, &i| m.max(i));
    if (largest as usize) < n_circles {
        return Ok(());
    }
    if let Some(&bad) = anchors.circle.iter().find(|&&i| i as usize >= n_circles) {
        return Err(MeshError::LengthMismatch {
            what: "circle state (an anchor names a circle beyond it)",
            expected: bad as usize + 1,
            got: n_circles,
        });
    }
    Ok(())
}

/// [`vertex_kinematics`] with the circle frames computed once ([`circle_frames`]): one pass
/// over the vertices and their anchor rows, no allocation.
pub fn vertex_kinematics_in_frames(
    anchors: &VertexAnchors,
    frames: &[CircleFrame],
    pos: &mut [[f64; 2]],
    vel: &mut [[f64; 2]],
) {
    // The mesh-time position is read only for the few vertices that need it (no anchor, or a
    // constraint), so its cache lines are mostly left alone.
    let x0 = &anchors.reference;
    let ends = anchors.start.get(1..).unwrap_or(&[]);
    let mut a = anchors.start.first().map_or(0, |&s| s as usize);
    let rows = ends.iter().zip(&anchors.constraint);
    for (v, ((&end, constraint), (x_out, u_out))) in
        rows.zip(pos.iter_mut().zip(vel.iter_mut())).enumerate()
    {
        let b = end as usize;
        let single = b == a + 1;
        if single && *constraint == VertexConstraint::Free {
            // The common case: a free point on one circle.
            (*x_out, *u_out) =
                anchor_motion(&frames[anchors.circle[a] as usize], anchors.offset[a]);
            a = b;
            continue;
        }
        let (mut x, mut u) = if single {
            anchor_motion(&frames[anchors.circle[a] as usize], anchors.offset[a])
        } else {
            let (mut x, mut u) = (x0[v], [0.0; 2]);
            if b > a {
                x = [0.0; 2];
                for (&circle, &o) in anchors.circle[a..b].iter().zip(&anchors.offset[a..b]) {
                    let (y, w) = anchor_motion(&frames[circle as usize], o);
                    x = [x[0] + y[0], x[1] + y[1]];
                    u = [u[0] + w[0], u[1] + w[1]];
                }
                // 1 / (number of anchors): the same bits as the division, from a table for
                // the rows the mesher makes.
                let n = b - a;
                let inv = match n {
                    2 => 0.5,
                    3 => 1.0 / 3.0,
                    _ => 1.0 / n as f64,
                };
                x = [x[0] * inv, x[1] * inv];
                u = [u[0] * inv, u[1] * inv];
            }
            (x, u)
        };
        a = b;
        match *constraint {
            VertexConstraint::Free => {}
            VertexConstraint::OnSide(s) => {
                let k = if s < 2 { 0 } else { 1 };
                x[k] = x0[v][k];
                u[k] = 0.0;
            }
            VertexConstraint::Fixed => {
                x = x0[v];
                u = [0.0; 2];
            }
        }
        *x_out = x;
        *u_out = u;
    }
}

/// Area rate dA/dt of every cell [m²/s] from the vertex velocities (exact derivative of the
/// triangle area).
pub fn cell_area_rate(mesh: &PoreMesh, vel: &[[f64; 2]], out: &mut [f64]) -> Result<(), MeshError> {
    for (what, got, expected) in [
        ("vel", vel.len(), mesh.vertices.len()),
        ("out", out.len(), mesh.n_cells()),
    ] {
        if got != expected {
            return Err(MeshError::LengthMismatch {
                what,
                expected,
                got,
            });
        }
    }
    area_rate_into(mesh, vel, out);
    Ok(())
}

fn area_rate_into(mesh: &PoreMesh, vel: &[[f64; 2]], out: &mut [f64]) {
    let vx = &mesh.vertices;
    for (t, out) in mesh.cell_vertices.iter().zip(out.iter_mut()) {
        let [a, b, cc] = t.map(|v| v as usize);
        let (pa, pb, pc) = (vx[a], vx[b], vx[cc]);
        let (ua, ub, uc) = (vel[a], vel[b], vel[cc]);
        let e1 = [pb[0] - pa[0], pb[1] - pa[1]];
        let e2 = [pc[0] - pa[0], pc[1] - pa[1]];
        let d1 = [ub[0] - ua[0], ub[1] - ua[1]];
        let d2 = [uc[0] - ua[0], uc[1] - ua[1]];
        *out = 0.5 * ((d1[0] * e2[1] - d1[1] * e2[0]) + (e1[0] * d2[1] - e1[1] * d2[0]));
    }
}

/// Moves a [`PackingMesh`] with the circles between remeshes; holds only scratch buffers.
#[derive(Debug, Clone, Default)]
pub struct MeshMotion {
    frames: Vec<CircleFrame>,
    velocity: Vec<[f64; 2]>,
    volume_rate: Vec<f64>,
}

impl MeshMotion {
    /// Empty scratch (sized on first use).
    pub fn new() -> Self {
        Self::default()
    }

    /// Stage sequence, each stage one allocation-free pass over precomputed index arrays
    /// (scratch is sized on the first call): validate the state; vertex kinematics (anchor
    /// rows → positions and velocities); cells (areas, centroids and dV/dt, see
    /// [`Self::volume_rate`]); faces (lengths, normals, mid-points); channels (lengths and
    /// the T2T apertures of A-Eq. 9, which follow the triangles).
    pub fn update(
        &mut self,
        pm: &mut PackingMesh,
        motion: &CircleMotion<'_>,
    ) -> Result<(), MeshError> {
        motion.validate(pm.circles.len())?;
        check_anchors(&pm.anchors, pm.circles.len())?;
        let nv = pm.anchors.len();
        if pm.mesh.vertices.len() != nv {
            return Err(MeshError::LengthMismatch {
                what: "mesh vertices (against the vertex anchors)",
                expected: nv,
                got: pm.mesh.vertices.len(),
            });
        }
        self.velocity.resize(nv, [0.0; 2]);
        self.volume_rate.resize(pm.mesh.n_cells(), 0.0);
        circle_frames(motion, &mut self.frames);
        vertex_kinematics_in_frames(
            &pm.anchors,
            &self.frames,
            &mut pm.mesh.vertices,
            &mut self.velocity,
        );
        let thickness = pm.mesh.thickness;
        pm.mesh
            .update_cell_geometry_and_rate(&self.velocity, thickness, &mut self.volume_rate);
        pm.mesh.update_face_geometry();
        pm.mesh.update_channel_geometry(Some(pm.t2t_law()));
        Ok(())
    }

    /// dV/dt of every cell after the last [`Self::update`] [m³/s].
    pub fn volume_rate(&self) -> &[f64] {
        &self.volume_rate
    }

    /// Vertex velocities after the last [`Self::update`] [m/s].
    pub fn vertex_velocity(&self) -> &[[f64; 2]] {
        &self.velocity
    }
}

/// When to remesh (serde form); validate with [`RemeshCriteriaParams::validate`].
///
/// The paper (A, Sect. 2.4) tracks displacements, overlaps and size changes and leaves the
/// thresholds to a parametric study; the defaults here keep every triangle valid for the
/// motions the DEM produces between remeshes and trigger on any topology change.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RemeshCriteriaParams {
    /// Largest centre displacement since the mesh, as a fraction of the radius (default 0.05).
    pub max_displacement: f64,
    /// Largest rotation since the mesh, as a fraction of the angular grid step (default 0.25).
    pub max_rotation: f64,
    /// Largest relative radius change since the mesh (default 0.01).
    pub max_radius_change: f64,
    /// Largest change of a pair overlap since the mesh, as a fraction of the smaller radius
    /// (default 0.02).
    pub max_overlap_change: f64,
}

impl Default for RemeshCriteriaParams {
    fn default() -> Self {
        Self {
            max_displacement: 0.05,
            max_rotation: 0.25,
            max_radius_change: 0.01,
            max_overlap_change: 0.02,
        }
    }
}

impl RemeshCriteriaParams {
    /// Checks that every threshold is finite and > 0.
    pub fn validate(&self) -> Result<RemeshCriteria, MeshError> {
        for (name, value) in [
            ("max_displacement", self.max_displacement),
            ("max_rotation", self.max_rotation),
            ("max_radius_change", self.max_radius_change),
            ("max_overlap_change", self.max_overlap_change),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(MeshError::Parameter {
                    name,
                    range: "finite and > 0",
                    value,
                });
            }
        }
        Ok(RemeshCriteria { p: *self })
    }
}

/// Validated remesh criteria.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RemeshCriteria {
    p: RemeshCriteriaParams,
}

/// Why a remesh is needed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RemeshReason {
    /// A circle moved more than the threshold (value: displacement / radius).
    Displacement {
        /// Circle.
        circle: usize,
        /// Measured ratio.
        value: f64,
    },
    /// A circle turned more than the threshold (value: angle / grid step).
    Rotation {
        /// Circle.
        circle: usize,
        /// Measured ratio.
        value: f64,
    },
    /// A radius changed more than the threshold (value: relative change).
    RadiusChange {
        /// Circle.
        circle: usize,
        /// Measured ratio.
        value: f64,
    },
    /// A cut pair's overlap changed more than the threshold (value: change / smaller radius).
    OverlapChange {
        /// The two circles.
        pair: [u32; 2],
        /// Measured ratio.
        value: f64,
    },
    /// Two circles in contact overlap now but had no cut at mesh time (topology change).
    NewOverlap {
        /// The two circles.
        pair: [u32; 2],
    },
    /// A cell turned inside out (area ≤ 0).
    InvertedCell {
        /// Cell.
        cell: usize,
    },
    /// A cell lost more than a caller's threshold of its area in one step (value: area after
    /// over area before), e.g. a pore closing as a bond snaps, caught before it inverts.
    ShrunkCell {
        /// Cell.
        cell: usize,
        /// Area ratio.
        value: f64,
    },
}

/// Decides whether the mesh must be rebuilt for the current state (the first reason found,
/// checked in the order of [`RemeshReason`]'s variants), or `None`.
pub fn remesh_needed(
    pm: &PackingMesh,
    motion: &CircleMotion<'_>,
    contacts: &[Contact],
    segments_per_circle: u32,
    criteria: &RemeshCriteria,
) -> Result<Option<RemeshReason>, MeshError> {
    let n = pm.circles.len();
    motion.validate(n)?;
    let p = &criteria.p;
    for (i, c0) in pm.circles.iter().enumerate() {
        let d = [
            motion.centre[i][0] - c0.centre[0],
            motion.centre[i][1] - c0.centre[1],
        ];
        let value = (d[0] * d[0] + d[1] * d[1]).sqrt() / c0.radius;
        if value > p.max_displacement {
            return Ok(Some(RemeshReason::Displacement { circle: i, value }));
        }
    }
    let step = std::f64::consts::TAU / segments_per_circle.max(1) as f64;
    for i in 0..n {
        let value = motion.rotation[i].abs() / step;
        if value > p.max_rotation {
            return Ok(Some(RemeshReason::Rotation { circle: i, value }));
        }
    }
    for (i, c0) in pm.circles.iter().enumerate() {
        let value = (motion.radius[i] - c0.radius).abs() / c0.radius;
        if value > p.max_radius_change {
            return Ok(Some(RemeshReason::RadiusChange { circle: i, value }));
        }
    }
    let overlap = |a: usize, b: usize| {
        let d = [
            motion.centre[b][0] - motion.centre[a][0],
            motion.centre[b][1] - motion.centre[a][1],
        ];
        motion.radius[a] + motion.radius[b] - (d[0] * d[0] + d[1] * d[1]).sqrt()
    };
    for (k, pair) in pm.chords.circles.iter().enumerate() {
        let (a, b) = (pair[0] as usize, pair[1] as usize);
        let value =
            (overlap(a, b) - pm.chords.overlap[k]).abs() / motion.radius[a].min(motion.radius[b]);
        if value > p.max_overlap_change {
            return Ok(Some(RemeshReason::OverlapChange { pair: *pair, value }));
        }
    }
    for (k, ct) in contacts.iter().enumerate() {
        let [a, b] = ct.circles;
        if a as usize >= n || b as usize >= n || a == b {
            return Err(MeshError::ContactOutOfRange {
                contact: k,
                circle: a.max(b),
                n_circles: n,
            });
        }
        let key = [a.min(b), a.max(b)];
        if overlap(a as usize, b as usize) > 0.0 && pm.chords.circles.binary_search(&key).is_err() {
            return Ok(Some(RemeshReason::NewOverlap { pair: key }));
        }
    }
    Ok(inverted_cell(&pm.mesh).map(|cell| RemeshReason::InvertedCell { cell }))
}

/// The first cell of `mesh` turned inside out (area ≤ 0 or not a number), if any.
pub fn inverted_cell(mesh: &PoreMesh) -> Option<usize> {
    mesh.cell_area.iter().position(|&a| a.is_nan() || a <= 0.0)
}
