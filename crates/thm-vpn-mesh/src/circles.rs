//! What the mesher is given and how its vertices hang on it: the circles (spheres projected
//! on the mid-plane) and their contacts, and each mesh vertex's anchor circles
//! ([`VertexAnchors`]), which the mesher writes and the motion between remeshes
//! ([`crate::motion`]) reads.

use serde::{Deserialize, Serialize};

/// A sphere projected on the mid-plane.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Circle {
    /// Centre \[m\].
    pub centre: [f64; 2],
    /// Radius \[m\].
    pub radius: f64,
    /// The caller's sphere id, recorded in [`crate::CellKind::Solid`] and `vertex_sphere`.
    pub owner: u32,
}

/// A contact between two circles (indices into the circle list).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    /// The two circles.
    pub circles: [u32; 2],
    /// Effective normal stress at the contact σ_n \[Pa\], compression positive (A-Eq. 8).
    pub normal_stress: f64,
}

/// How a vertex is held in place besides its anchors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum VertexConstraint {
    /// Follows its anchors.
    Free,
    /// On box side `0` left, `1` right, `2` bottom, `3` top: follows its anchors along the side.
    OnSide(u8),
    /// Does not move (box corners).
    Fixed,
}

/// Vertex anchors: for each vertex its anchor circles with the offsets `(x₀ − c⁰) / r⁰`, in
/// compressed rows (most vertices lie on one circle and have one anchor), plus its constraint
/// and mesh-time position (struct-of-arrays).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VertexAnchors {
    /// Anchors of vertex `v` are entries `start[v]..start[v + 1]` of `circle` and `offset`
    /// (0–3 each); length `n_vertices + 1`.
    pub start: Vec<u32>,
    /// Anchor circles (indices into the circle list at mesh time).
    pub circle: Vec<u32>,
    /// `(x₀ − c⁰) / r⁰` for each anchor [-].
    pub offset: Vec<[f64; 2]>,
    /// Side or fixed constraint.
    pub constraint: Vec<VertexConstraint>,
    /// Position at mesh time \[m\].
    pub reference: Vec<[f64; 2]>,
}

impl Default for VertexAnchors {
    fn default() -> Self {
        Self {
            start: vec![0],
            circle: Vec::new(),
            offset: Vec::new(),
            constraint: Vec::new(),
            reference: Vec::new(),
        }
    }
}

impl VertexAnchors {
    /// Appends a vertex at `pos` anchored to `list` (at most three circles are kept).
    pub fn push(
        &mut self,
        pos: [f64; 2],
        list: &[u32],
        constraint: VertexConstraint,
        circles: &[Circle],
    ) {
        for &i in list.iter().take(3) {
            let c = &circles[i as usize];
            self.circle.push(i);
            self.offset.push([
                (pos[0] - c.centre[0]) / c.radius,
                (pos[1] - c.centre[1]) / c.radius,
            ]);
        }
        self.start.push(self.circle.len() as u32);
        self.constraint.push(constraint);
        self.reference.push(pos);
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.constraint.len()
    }

    /// True when there is no vertex.
    pub fn is_empty(&self) -> bool {
        self.constraint.is_empty()
    }

    /// The kinematics group of vertex `v`: its number of anchors (0–3) for a free vertex,
    /// 4 + that number for a vertex on a box side or fixed. Group 1 (a free point on one
    /// circle, e.g. on an arc) is the common case.
    ///
    /// A vertex beyond the rows, or a malformed row, counts as having no anchor (the checks
    /// of [`crate::motion::vertex_kinematics`] reject such anchors).
    pub fn kinematics_group(&self, v: usize) -> u8 {
        let n = match (self.start.get(v), self.start.get(v + 1)) {
            (Some(&a), Some(&b)) => b.saturating_sub(a).min(3) as u8,
            _ => 0,
        };
        match self.constraint.get(v) {
            Some(VertexConstraint::OnSide(_) | VertexConstraint::Fixed) => 4 + n,
            _ => n,
        }
    }

    /// The vertex order that sorts the vertices by [`Self::kinematics_group`], group 1 first
    /// (the simple ones), then 2, 3, 0, 4, …, each group in its present order:
    /// `order[new] = old`. In that order the branches of the vertex kinematics (how many
    /// anchors, which constraint) change only at group boundaries.
    pub fn kinematics_order(&self) -> Vec<u32> {
        // Group 1 first, group 0 (a free vertex without anchor: none in a mesh of circles)
        // after the other free ones.
        let rank = |v: u32| match self.kinematics_group(v as usize) {
            0 => 3,
            1 => 0,
            g @ 2..=3 => g - 1,
            g => g,
        };
        let mut order: Vec<u32> = (0..self.len() as u32).collect();
        order.sort_by_key(|&v| rank(v));
        order
    }

    /// The same anchors with the vertices in the order `order` (`order[new] = old`, a
    /// permutation of `0..len` of well-formed rows, as the mesher makes them).
    pub(crate) fn permuted(&self, order: &[u32]) -> Self {
        let mut out = Self::default();
        for &v in order {
            let (a, b) = (
                self.start[v as usize] as usize,
                self.start[v as usize + 1] as usize,
            );
            out.circle.extend_from_slice(&self.circle[a..b]);
            out.offset.extend_from_slice(&self.offset[a..b]);
            out.start.push(out.circle.len() as u32);
            out.constraint.push(self.constraint[v as usize]);
            out.reference.push(self.reference[v as usize]);
        }
        out
    }

    /// Anchor circles of vertex `v`.
    pub fn circles_of(&self, v: usize) -> &[u32] {
        &self.circle[self.start[v] as usize..self.start[v + 1] as usize]
    }
}
