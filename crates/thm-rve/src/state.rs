//! Caller-owned state of one RVE: the cell, the disks (struct of arrays, `thm-dem`'s
//! [`ParticleState`] with disk kinematics), the periodic contacts with their history, and the
//! Verlet anchor of the neighbour list.

use crate::cell::PeriodicCell;
use crate::error::RveError;
use crate::mat2::Mat2;
use serde::{Deserialize, Serialize};
use thm_dem::{BondState, ContactHistory, Kinematics, ParticleState, Vec2, Vec3};

/// Contacts (and near pairs) of a periodic packing, sorted by pair, with their history and
/// the force and branch vector of the last force evaluation.
///
/// Pair `[a, b]` has `a < b`; the branch vector from `a` to the image of `b` is
/// `x_b + H·shift − x_a`. A cell at least twice as wide as the neighbour reach admits at most
/// one touching image per pair, so the history is keyed by the pair alone.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PeriodicContacts {
    /// Pairs `[a, b]`, `a < b`, sorted lexicographically.
    pub pair: Vec<[u32; 2]>,
    /// Integer image shift of `b` per pair.
    pub shift: Vec<[i32; 2]>,
    /// History per pair (shear force, previous normal, bond state), in the plane.
    pub history: Vec<ContactHistory<Vec2>>,
    /// Force on `b` from `a` at the last evaluation \[N\] (zero when not touching).
    pub force_on_b: Vec<Vec2>,
    /// Branch vector `a → image of b` at the last evaluation \[m\].
    pub branch: Vec<Vec2>,
}

impl PeriodicContacts {
    /// Number of listed pairs (touching or not).
    #[inline]
    pub fn len(&self) -> usize {
        self.pair.len()
    }

    /// True when no pair is listed.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.pair.is_empty()
    }

    /// Heap memory of the list \[bytes\].
    pub fn heap_bytes(&self) -> usize {
        fn cap<T>(v: &Vec<T>) -> usize {
            v.capacity() * std::mem::size_of::<T>()
        }
        cap(&self.pair)
            + cap(&self.shift)
            + cap(&self.history)
            + cap(&self.force_on_b)
            + cap(&self.branch)
    }

    /// Number of pairs that carried force at the last evaluation (or hold an intact bond).
    pub fn active_count(&self) -> usize {
        self.force_on_b
            .iter()
            .zip(&self.history)
            .filter(|(f, h)| **f != Vec2::ZERO || h.bond == BondState::Intact)
            .count()
    }

    /// Number of intact bonds.
    pub fn intact_bond_count(&self) -> usize {
        self.history
            .iter()
            .filter(|h| h.bond == BondState::Intact)
            .count()
    }

    pub(crate) fn clear(&mut self) {
        self.pair.clear();
        self.shift.clear();
        self.history.clear();
        self.force_on_b.clear();
        self.branch.clear();
    }

    /// Makes room for at least `count` pairs plus 1/8 headroom (exactly, not doubling), so
    /// that the list can grow a little between rebuilds without reallocating.
    pub(crate) fn reserve_for(&mut self, count: usize) {
        fn room<T>(v: &mut Vec<T>, target: usize) {
            if v.capacity() < target {
                v.reserve_exact(target - v.len());
            }
        }
        let target = count + count / 8 + 8;
        room(&mut self.pair, target);
        room(&mut self.shift, target);
        room(&mut self.history, target);
        room(&mut self.force_on_b, target);
        room(&mut self.branch, target);
    }

    pub(crate) fn push(&mut self, pair: [u32; 2], shift: [i32; 2], history: ContactHistory<Vec2>) {
        self.pair.push(pair);
        self.shift.push(shift);
        self.history.push(history);
        self.force_on_b.push(Vec2::ZERO);
        self.branch.push(Vec2::ZERO);
    }
}

/// Where the disks and the cell were when the neighbour list was built.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct VerletAnchor {
    /// Reduced coordinates of the disks at the build.
    pub reduced_position: Vec<Vec3>,
    /// Cell matrix at the build.
    pub cell: Mat2,
    /// Radii at the build \[m\].
    pub radius: Vec<f64>,
    /// Skin used at the build \[m\]; 0 means "no list yet".
    pub skin: f64,
}

/// The state of one RVE (SI units). Disk centres are global coordinates `x = H X`; disk
/// velocities are the fluctuating (non-affine) velocities `v_f` of B-Eq. 42 at the half step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RveState {
    /// The periodic cell.
    pub cell: PeriodicCell,
    /// Disks (`Kinematics::Disks`; masses `ρ π R² z_p`, inertias `½ m R²`).
    pub disks: ParticleState,
    /// Listed pairs and their contact history.
    pub contacts: PeriodicContacts,
    /// Verlet anchor of the pair list.
    pub anchor: VerletAnchor,
    /// DEM steps taken.
    pub step: u64,
    /// Time \[s\].
    pub time: f64,
    /// Friction heat of all steps so far, `Σ E_f` of B-Eq. 32 \[J\].
    pub friction_heat_total: f64,
    /// Contact part `Σ f ⊗ b` of B-Eq. 49 at the last force evaluation \[N m\].
    pub contact_moment: Mat2,
}

impl AsMut<RveState> for RveState {
    fn as_mut(&mut self) -> &mut RveState {
        self
    }
}

impl RveState {
    /// Disks at rest from centres \[m\] and radii \[m\] in a cell; `density` \[kg/m³\] and the
    /// fictitious `thickness` \[m\] give masses `ρ π R² z_p`; all disks at `temperature` \[K\] with
    /// their reference radii.
    pub fn new(
        cell: PeriodicCell,
        centres: &[Vec3],
        radii: &[f64],
        density: f64,
        thickness: f64,
        temperature: f64,
    ) -> Result<Self, RveError> {
        crate::error::check_positive("thickness", thickness)?;
        let mut disks =
            ParticleState::new(Kinematics::Disks, density, temperature, centres, radii)?;
        for (m, i) in disks.mass.iter_mut().zip(disks.inertia.iter_mut()) {
            *m *= thickness;
            *i *= thickness;
        }
        Ok(Self {
            cell,
            disks,
            contacts: PeriodicContacts::default(),
            anchor: VerletAnchor::default(),
            step: 0,
            time: 0.0,
            friction_heat_total: 0.0,
            contact_moment: Mat2::ZERO,
        })
    }

    /// Heap memory held by this state \[bytes\] (capacities of all its arrays).
    pub fn heap_bytes(&self) -> usize {
        fn cap<T>(v: &Vec<T>) -> usize {
            v.capacity() * std::mem::size_of::<T>()
        }
        let d = &self.disks;
        let c = &self.contacts;
        let a = &self.anchor;
        cap(&d.position)
            + cap(&d.velocity)
            + cap(&d.angular_velocity)
            + cap(&d.radius)
            + cap(&d.reference_radius)
            + cap(&d.mass)
            + cap(&d.inertia)
            + cap(&d.fixed)
            + cap(&d.external_force)
            + cap(&d.external_torque)
            + cap(&d.temperature)
            + cap(&d.force)
            + cap(&d.torque)
            + c.heap_bytes()
            + cap(&a.reduced_position)
            + cap(&a.radius)
    }

    /// Number of disks.
    #[inline]
    pub fn len(&self) -> usize {
        self.disks.len()
    }

    /// True when there are no disks.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.disks.is_empty()
    }

    /// RVE volume `V = det H · z_p` \[m³\].
    #[inline]
    pub fn volume(&self, thickness: f64) -> f64 {
        self.cell.area() * thickness
    }

    /// Solid area `Σ π R²` \[m²\].
    pub fn solid_area(&self) -> f64 {
        self.disks
            .radius
            .iter()
            .map(|r| std::f64::consts::PI * r * r)
            .sum()
    }

    /// Void ratio `e = (A − A_s) / A_s` (void over solid, B-Sect. 5.3.1).
    pub fn void_ratio(&self) -> f64 {
        let solid = self.solid_area();
        (self.cell.area() - solid) / solid
    }

    /// Mean coordination number `2 N_c / N` over contacts carrying force.
    pub fn coordination_number(&self) -> f64 {
        2.0 * self.contacts.active_count() as f64 / self.len().max(1) as f64
    }

    /// Installs thermally sensitive bonds (B-Eqs. 38–40) at every contact that carried force
    /// at the last evaluation: the bond keeps the present compression and adds tensile and
    /// shear strength (B-Sect. 5.3.3: "bonds are installed only at contacts with non-zero
    /// contact forces" after consolidation). Returns the number of bonds installed.
    pub fn install_bonds(&mut self) -> usize {
        let mut n = 0;
        for (h, f) in self
            .contacts
            .history
            .iter_mut()
            .zip(&self.contacts.force_on_b)
        {
            if *f != Vec2::ZERO && h.bond == BondState::None {
                h.bond = BondState::Intact;
                n += 1;
            }
        }
        n
    }

    /// Moves every disk by the lattice vector `H·shift` (a periodic shift of the packing:
    /// changes nothing physical). The neighbour list is rebuilt at the next step.
    pub fn shift_by_lattice_vector(&mut self, shift: [i32; 2]) {
        let t = self.cell.lattice_vector(shift);
        for x in &mut self.disks.position {
            *x += t;
        }
        self.anchor.skin = 0.0;
    }

    /// Rotates the whole RVE rigidly by `angle` (cell, centres, velocities, contact history):
    /// a frame change that changes no stress invariant.
    pub fn rotate_rigidly(&mut self, angle: f64) -> Result<(), RveError> {
        let q = crate::mat2::Mat2::rotation(angle);
        let h = q.mul(self.cell.matrix());
        let h_ref = q.mul(self.cell.reference());
        self.cell = PeriodicCell::new(h_ref)?;
        self.cell.set_matrix(h)?;
        for x in &mut self.disks.position {
            *x = q.apply(*x);
        }
        for v in &mut self.disks.velocity {
            *v = q.apply(*v);
        }
        for h in &mut self.contacts.history {
            h.shear_force = q.apply_vec2(h.shear_force);
            h.normal = q.apply_vec2(h.normal);
        }
        for (f, b) in self
            .contacts
            .force_on_b
            .iter_mut()
            .zip(self.contacts.branch.iter_mut())
        {
            *f = q.apply_vec2(*f);
            *b = q.apply_vec2(*b);
        }
        self.contact_moment = q.mul(&self.contact_moment).mul(&q.transpose());
        self.anchor.skin = 0.0;
        Ok(())
    }

    /// One Lagrange–Gauss reduction step of the cell basis: `h₂ ← h₂ − k h₁` with
    /// `k = round(h₁·h₂ / |h₁|²)`, then `h₁ ← h₁ − k' h₂` with `k' = round(h₁·h₂ / |h₂|²)`.
    /// The new basis `H' = H U` (`U` unimodular, `det U = 1`) spans the same lattice, so the
    /// periodic packing, its stress and its contacts are unchanged; only the cell drawn around
    /// it is less skewed, which keeps a cell sheared without bound (a material point in a
    /// flow) wide enough for the periodic search. The image shifts become `U⁻¹ s`, the
    /// reference cell `H_ref U` (so the cell strain B-Eq. 47 is unchanged), and the neighbour
    /// list is rebuilt at the next step. Returns whether the basis changed.
    pub fn reduce_cell(&mut self) -> Result<bool, RveError> {
        let h = *self.cell.matrix();
        let (mut h1, mut h2) = ([h.at(0, 0), h.at(1, 0)], [h.at(0, 1), h.at(1, 1)]);
        let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
        let k2 = (dot(h1, h2) / dot(h1, h1)).round();
        if k2 != 0.0 {
            h2 = [h2[0] - k2 * h1[0], h2[1] - k2 * h1[1]];
        }
        let k1 = (dot(h1, h2) / dot(h2, h2)).round();
        if k1 != 0.0 {
            h1 = [h1[0] - k1 * h2[0], h1[1] - k1 * h2[1]];
        }
        if k1 == 0.0 && k2 == 0.0 {
            return Ok(false);
        }
        if !(k1.abs() < 1e6 && k2.abs() < 1e6) {
            return Err(RveError::DegenerateCell {
                field: "cell reduction",
                determinant: h.det(),
            });
        }
        let (k1, k2) = (k1 as i32, k2 as i32);
        // H' = H U with U = U₂ U₁, U₂ = [[1, −k2], [0, 1]], U₁ = [[1, 0], [−k1, 1]].
        let u =
            Mat2::new(1.0, -f64::from(k2), 0.0, 1.0).mul(&Mat2::new(1.0, 0.0, -f64::from(k1), 1.0));
        let h_new = Mat2::new(h1[0], h2[0], h1[1], h2[1]);
        let h_ref = self.cell.reference().mul(&u);
        self.cell = PeriodicCell::new(h_ref)?;
        self.cell.set_matrix(h_new)?;
        // s' = U⁻¹ s = U₁⁻¹ U₂⁻¹ s: U₂⁻¹ s = (s0 + k2 s1, s1), then U₁⁻¹ (a, b) = (a, k1 a + b).
        for s in &mut self.contacts.shift {
            let a = s[0] + k2 * s[1];
            *s = [a, k1 * a + s[1]];
        }
        self.anchor.skin = 0.0;
        Ok(true)
    }
}
