//! Caller-owned state: particles (struct of arrays), contacts with their history, walls.

use crate::contact::{BondState, BreakMode, ContactHistory, ContactReport};
use crate::error::DemError;
use crate::vec3::Vec3;
use serde::{Deserialize, Serialize};

/// Which bodies and which motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kinematics {
    /// Spheres moving freely in 3D.
    Spheres3d,
    /// Spheres with centres held in `z = 0`: no `z` motion, no rotation about `x` or `y`
    /// (the single-layer specimens of Krzaczek et al.).
    SpheresInPlane,
    /// Disks in the `xy` plane (2D, per unit thickness): mass `ρπR²` \[kg/m\], inertia `mR²/2`
    /// (the RVEs of Zhao et al.).
    Disks,
}

impl Kinematics {
    /// True when motion is confined to the `xy` plane.
    #[inline]
    pub fn is_planar(self) -> bool {
        !matches!(self, Self::Spheres3d)
    }

    /// Mass of a particle of density `rho` \[kg/m³\] and radius `r` \[m\]: kg (spheres) or kg/m
    /// (disks).
    #[inline]
    pub fn mass(self, rho: f64, r: f64) -> f64 {
        match self {
            Self::Disks => rho * std::f64::consts::PI * r * r,
            _ => rho * 4.0 / 3.0 * std::f64::consts::PI * r * r * r,
        }
    }

    /// Moment of inertia about a centroidal axis of a particle of mass `m` and radius `r`.
    #[inline]
    pub fn inertia(self, m: f64, r: f64) -> f64 {
        match self {
            Self::Disks => 0.5 * m * r * r,
            _ => 0.4 * m * r * r,
        }
    }
}

/// Particles as a struct of arrays. Velocities are leapfrog half-step values
/// (`v^{n−½}` between steps). SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParticleState {
    /// Kinematics of all particles.
    pub kinematics: Kinematics,
    /// Centres \[m\].
    pub position: Vec<Vec3>,
    /// Velocities \[m/s\].
    pub velocity: Vec<Vec3>,
    /// Angular velocities \[rad/s\].
    pub angular_velocity: Vec<Vec3>,
    /// Current radii \[m\].
    pub radius: Vec<f64>,
    /// Radii at the reference temperature (B-Eq. 37) \[m\].
    pub reference_radius: Vec<f64>,
    /// Masses \[kg\] (disks: kg/m).
    pub mass: Vec<f64>,
    /// Moments of inertia \[kg m²\] (disks: kg m).
    pub inertia: Vec<f64>,
    /// Fixed particles ignore forces and move with their current (prescribed) velocity.
    pub fixed: Vec<bool>,
    /// External forces (fluid pressure and shear) \[N\], held until the caller changes them.
    pub external_force: Vec<Vec3>,
    /// External torques \[N m\].
    pub external_torque: Vec<Vec3>,
    /// Temperatures \[K\] (contact temperature of the thermal bond; radius updates).
    pub temperature: Vec<f64>,
    /// Resultant force of the last step before damping \[N\] (contacts + external + gravity).
    pub force: Vec<Vec3>,
    /// Resultant torque of the last step before damping \[N m\].
    pub torque: Vec<Vec3>,
}

impl ParticleState {
    /// The particles whose surface lies within `depth` \[m\] of the plane `y = y_bottom`
    /// (first list) or `y = y_top` (second), in index order; one near both ends is in the
    /// first. The ends a bar test grips or a coupled case holds.
    pub fn near_ends(&self, y_bottom: f64, y_top: f64, depth: f64) -> [Vec<usize>; 2] {
        let (mut bottom, mut top) = (Vec::new(), Vec::new());
        for i in 0..self.len() {
            let (y, r) = (self.position[i].y, self.radius[i]);
            if y - r < y_bottom + depth {
                bottom.push(i);
            } else if y + r > y_top - depth {
                top.push(i);
            }
        }
        [bottom, top]
    }

    /// Particles at rest from centres and radii, of uniform density \[kg/m³\] and temperature
    /// \[K\]. Plane kinematics put the centres into `z = 0`.
    pub fn new(
        kinematics: Kinematics,
        density: f64,
        temperature: f64,
        centres: &[Vec3],
        radii: &[f64],
    ) -> Result<Self, DemError> {
        crate::error::check_positive("density", density)?;
        crate::error::check_positive("temperature", temperature)?;
        if centres.len() != radii.len() {
            return Err(DemError::LengthMismatch {
                field: "radius",
                len: radii.len(),
                expected: centres.len(),
            });
        }
        let n = centres.len();
        let position: Vec<Vec3> = centres
            .iter()
            .map(|&c| {
                if kinematics.is_planar() {
                    Vec3::new(c.x, c.y, 0.0)
                } else {
                    c
                }
            })
            .collect();
        let mass: Vec<f64> = radii.iter().map(|&r| kinematics.mass(density, r)).collect();
        let inertia = mass
            .iter()
            .zip(radii)
            .map(|(&m, &r)| kinematics.inertia(m, r))
            .collect();
        let state = Self {
            kinematics,
            position,
            velocity: vec![Vec3::ZERO; n],
            angular_velocity: vec![Vec3::ZERO; n],
            radius: radii.to_vec(),
            reference_radius: radii.to_vec(),
            mass,
            inertia,
            fixed: vec![false; n],
            external_force: vec![Vec3::ZERO; n],
            external_torque: vec![Vec3::ZERO; n],
            temperature: vec![temperature; n],
            force: vec![Vec3::ZERO; n],
            torque: vec![Vec3::ZERO; n],
        };
        state.validate()?;
        Ok(state)
    }

    /// Number of particles.
    #[inline]
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// True when there are no particles.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Checks array lengths, finiteness and positivity of radii, masses and inertias.
    pub fn validate(&self) -> Result<(), DemError> {
        let n = self.len();
        let lens = [
            ("velocity", self.velocity.len()),
            ("angular_velocity", self.angular_velocity.len()),
            ("radius", self.radius.len()),
            ("reference_radius", self.reference_radius.len()),
            ("mass", self.mass.len()),
            ("inertia", self.inertia.len()),
            ("fixed", self.fixed.len()),
            ("external_force", self.external_force.len()),
            ("external_torque", self.external_torque.len()),
            ("temperature", self.temperature.len()),
            ("force", self.force.len()),
            ("torque", self.torque.len()),
        ];
        for (field, len) in lens {
            if len != n {
                return Err(DemError::LengthMismatch {
                    field,
                    len,
                    expected: n,
                });
            }
        }
        if n > u32::MAX as usize / 2 {
            return Err(DemError::InvalidParameter {
                field: "particle count",
                value: n as f64,
                allowed: "[0, 2^31)",
            });
        }
        let positive = [
            ("radius", &self.radius),
            ("reference_radius", &self.reference_radius),
            ("mass", &self.mass),
            ("inertia", &self.inertia),
            ("temperature", &self.temperature),
        ];
        for (field, values) in positive {
            if let Some((index, &value)) = values
                .iter()
                .enumerate()
                .find(|(_, v)| !(v.is_finite() && **v > 0.0))
            {
                return Err(DemError::InvalidParticle {
                    index,
                    field,
                    value,
                    allowed: "(0, ∞)",
                });
            }
        }
        let vectors = [
            ("position", &self.position),
            ("velocity", &self.velocity),
            ("angular_velocity", &self.angular_velocity),
            ("external_force", &self.external_force),
            ("external_torque", &self.external_torque),
        ];
        for (field, values) in vectors {
            if let Some((index, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(DemError::InvalidParticle {
                    index,
                    field,
                    value: v.max_abs(),
                    allowed: "finite",
                });
            }
        }
        Ok(())
    }

    /// Total linear momentum \[kg m/s\] (free and fixed particles).
    pub fn momentum(&self) -> Vec3 {
        self.mass
            .iter()
            .zip(&self.velocity)
            .fold(Vec3::ZERO, |acc, (&m, &v)| acc + v * m)
    }

    /// Total kinetic energy, translational and rotational \[J\].
    pub fn kinetic_energy(&self) -> f64 {
        let mut e = 0.0;
        for i in 0..self.len() {
            e += 0.5 * self.mass[i] * self.velocity[i].norm_squared()
                + 0.5 * self.inertia[i] * self.angular_velocity[i].norm_squared();
        }
        e
    }

    /// Sum of the last step's resultant forces on the given particles \[N\] (e.g. the grips of
    /// a specimen: the force a plate exerts through them is its negative).
    pub fn resultant_force(&self, particles: &[usize]) -> Vec3 {
        particles
            .iter()
            .fold(Vec3::ZERO, |acc, &i| acc + self.force[i])
    }

    /// Thermal expansion from the volume-average temperature change (A-Eq. 55):
    /// `r^{n+1} = r^n (1 + α_exp (T^{n+1} − T^n))`, then `T ← T^{n+1}`. Masses are kept
    /// (the solid conserves mass); inertias follow the radius.
    pub fn expand_incremental(
        &mut self,
        expansion_coefficient: f64,
        new_temperature: &[f64],
    ) -> Result<(), DemError> {
        self.check_temperatures(new_temperature)?;
        for ((r, t), &t_new) in self
            .radius
            .iter_mut()
            .zip(&mut self.temperature)
            .zip(new_temperature)
        {
            *r *= 1.0 + expansion_coefficient * (t_new - *t);
            *t = t_new;
        }
        self.refresh_inertia()
    }

    /// Thermal expansion from the reference radius (B-Eq. 37):
    /// `R = R⁽⁰⁾ (1 + β (T − T_ref))`, then `T ← T_new`.
    pub fn expand_from_reference(
        &mut self,
        expansion_coefficient: f64,
        reference_temperature: f64,
        new_temperature: &[f64],
    ) -> Result<(), DemError> {
        self.check_temperatures(new_temperature)?;
        for (((r, r0), t), &t_new) in self
            .radius
            .iter_mut()
            .zip(&self.reference_radius)
            .zip(&mut self.temperature)
            .zip(new_temperature)
        {
            *r = r0 * (1.0 + expansion_coefficient * (t_new - reference_temperature));
            *t = t_new;
        }
        self.refresh_inertia()
    }

    fn check_temperatures(&self, t: &[f64]) -> Result<(), DemError> {
        if t.len() != self.len() {
            return Err(DemError::LengthMismatch {
                field: "new_temperature",
                len: t.len(),
                expected: self.len(),
            });
        }
        if let Some((index, &value)) = t
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v > 0.0))
        {
            return Err(DemError::InvalidParticle {
                index,
                field: "new_temperature",
                value,
                allowed: "(0, ∞) K",
            });
        }
        Ok(())
    }

    fn refresh_inertia(&mut self) -> Result<(), DemError> {
        for i in 0..self.len() {
            let r = self.radius[i];
            if !(r.is_finite() && r > 0.0) {
                return Err(DemError::InvalidParticle {
                    index: i,
                    field: "radius",
                    value: r,
                    allowed: "(0, ∞)",
                });
            }
            self.inertia[i] = self.kinematics.inertia(self.mass[i], r);
        }
        Ok(())
    }
}

/// A list of contacts sorted by pair, with history and the last step's report.
///
/// For particle–particle contacts a pair is `[a, b]` with `a < b`; for particle–wall contacts
/// it is `[particle, wall]`. The stepper checks the order (a particle's contacts as `a` are
/// then one range) and rejects an unsorted list with [`DemError::InvalidContact`].
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ContactList {
    /// Pairs, sorted lexicographically.
    pub pair: Vec<[u32; 2]>,
    /// History per contact.
    pub history: Vec<ContactHistory>,
    /// Last step's report per contact (normal force and stress, friction work, bond
    /// breakage); the force itself is [`ContactList::force_on_b`].
    pub report: Vec<ContactReport>,
}

impl ContactList {
    /// Number of entries (touching or not).
    #[inline]
    pub fn len(&self) -> usize {
        self.pair.len()
    }

    /// True when empty.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.pair.is_empty()
    }

    /// Number of contacts carrying force (bonded or touching) in the last step.
    pub fn active_count(&self) -> usize {
        self.report.iter().filter(|r| r.active).count()
    }

    /// Number of intact bonds.
    pub fn intact_bond_count(&self) -> usize {
        self.history
            .iter()
            .filter(|h| h.bond == BondState::Intact)
            .count()
    }

    /// Number of broken bonds.
    pub fn broken_bond_count(&self) -> usize {
        self.history
            .iter()
            .filter(|h| h.bond == BondState::Broken)
            .count()
    }

    /// Force on B of contact `k` in the last step \[N\] (A receives its negative):
    /// `n F_n + F_s` from the normal and shear force the history keeps and the report's normal
    /// force, the same bits the contact law summed (zero for a contact that carried none).
    #[inline]
    pub fn force_on_b(&self, k: usize) -> Vec3 {
        self.history[k].force_on_b(self.report[k].normal_force)
    }

    /// Friction work of the last step summed over contacts, in contact order \[J\].
    pub fn friction_work(&self) -> f64 {
        self.report.iter().map(|r| r.friction_work).sum()
    }

    pub(crate) fn clear(&mut self) {
        self.pair.clear();
        self.history.clear();
        self.report.clear();
    }

    /// The list with each entry's pair and history replaced by `rename`'s, sorted by pair again
    /// (the reports follow their entries).
    fn renamed(
        &self,
        rename: impl Fn([u32; 2], ContactHistory) -> ([u32; 2], ContactHistory),
    ) -> Self {
        let mut entries: Vec<([u32; 2], ContactHistory, ContactReport)> = (0..self.len())
            .map(|k| {
                let (pair, history) = rename(self.pair[k], self.history[k]);
                (pair, history, self.report[k])
            })
            .collect();
        entries.sort_by_key(|e| e.0);
        Self {
            pair: entries.iter().map(|e| e.0).collect(),
            history: entries.iter().map(|e| e.1).collect(),
            report: entries.iter().map(|e| e.2).collect(),
        }
    }

    pub(crate) fn push(&mut self, pair: [u32; 2], history: ContactHistory) {
        self.pair.push(pair);
        self.history.push(history);
        self.report.push(ContactReport::default());
    }
}

/// A rigid plane wall (or plate) moving at a prescribed velocity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    /// A point of the plane \[m\].
    pub point: Vec3,
    /// Unit normal pointing into the domain.
    pub normal: Vec3,
    /// Prescribed velocity \[m/s\].
    pub velocity: Vec3,
    /// Force the particles exerted on the wall in the last step \[N\].
    pub force: Vec3,
}

impl Wall {
    /// A wall at rest; `normal` is normalised.
    pub fn new(point: Vec3, normal: Vec3) -> Result<Self, DemError> {
        let len = normal.norm();
        if !(len.is_finite() && len > 0.0 && point.is_finite()) {
            return Err(DemError::InvalidParameter {
                field: "wall.normal",
                value: len,
                allowed: "a finite non-zero vector and a finite point",
            });
        }
        Ok(Self {
            point,
            normal: normal / len,
            velocity: Vec3::ZERO,
            force: Vec3::ZERO,
        })
    }
}

/// A broken-bond event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct BondBreak {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Step in which it broke (the step counter before the step).
    pub step: u64,
    /// Tension or shear.
    pub mode: BreakMode,
}

/// Everything a DEM run carries from step to step (owned by the caller; serde round-trips it
/// bit for bit).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DemState {
    /// The particles.
    pub particles: ParticleState,
    /// Particle–particle contacts (and candidate pairs within the Verlet skin).
    pub contacts: ContactList,
    /// Walls and plates.
    pub walls: Vec<Wall>,
    /// Particle–wall contacts, pairs `[particle, wall]`.
    pub wall_contacts: ContactList,
    /// Steps done.
    pub step: u64,
    /// Simulated time \[s\].
    pub time: f64,
    /// Broken-bond events not yet drained by the caller.
    pub bond_breaks: Vec<BondBreak>,
    /// Centres at the last neighbour search (Verlet criterion); empty forces a search.
    pub search_reference_position: Vec<Vec3>,
    /// Radii at the last neighbour search.
    pub search_reference_radius: Vec<f64>,
    /// Wall points at the last neighbour search.
    pub search_reference_wall_point: Vec<Vec3>,
    /// Incremented whenever the contact lists change membership (a stepper rebuilds its
    /// per-particle contact index when it sees a new value). A caller that edits a contact's
    /// history in place (its bond state, `reference_penetration` or shear force) increments
    /// it too, so that the stepper looks at every listed pair again: a stepper does not read
    /// the history of a pair it has proven apart and found unbonded and without shear.
    pub contact_generation: u64,
}

impl DemState {
    /// A state with no contacts yet.
    pub fn new(particles: ParticleState, walls: Vec<Wall>) -> Self {
        Self {
            particles,
            contacts: ContactList::default(),
            walls,
            wall_contacts: ContactList::default(),
            step: 0,
            time: 0.0,
            bond_breaks: Vec::new(),
            search_reference_position: Vec::new(),
            search_reference_radius: Vec::new(),
            search_reference_wall_point: Vec::new(),
            contact_generation: 0,
        }
    }

    /// Mean coordination number `2 N_c / N` over contacts carrying force in the last step
    /// (particle–particle only).
    pub fn coordination_number(&self) -> f64 {
        if self.particles.is_empty() {
            return 0.0;
        }
        2.0 * self.contacts.active_count() as f64 / self.particles.len() as f64
    }

    /// Renumbers the particles of a running state: particle `i` becomes the one that was
    /// `order[i]` (e.g. [`crate::packing::locality_order`] of the current positions, as
    /// LIGGGHTS sorts its atoms every 1 000 steps of a flowing bed). Every per-particle array,
    /// the search reference, the bond-break records and both contact lists follow; a pair
    /// whose particles change order is written `a < b` again with its history's shear force
    /// and normal negated (both are taken on B, from A to B), so that the contact law sees
    /// the same contact mirrored; the lists are sorted again and the contact generation
    /// increments (a stepper rebuilds its contact index). The physics does not change; the
    /// order of the force sums does (round-off).
    ///
    /// # Errors
    /// [`DemError::InvalidParameter`] (`order`) unless `order` is a permutation of
    /// `0..particle count`; the state is then unchanged.
    pub fn renumber(&mut self, order: &[usize]) -> Result<(), DemError> {
        let n = self.particles.len();
        let bad = |value: usize| DemError::InvalidParameter {
            field: "order",
            value: value as f64,
            allowed: "a permutation of 0..particle count (each index once)",
        };
        if order.len() != n {
            return Err(bad(order.len()));
        }
        let mut new_index = vec![u32::MAX; n];
        for (new, &old) in order.iter().enumerate() {
            match new_index.get_mut(old) {
                Some(slot) if *slot == u32::MAX => *slot = new as u32,
                _ => return Err(bad(old)),
            }
        }
        fn permute<T: Copy>(v: &mut Vec<T>, order: &[usize]) {
            if v.len() == order.len() {
                *v = order.iter().map(|&i| v[i]).collect();
            }
        }
        let p = &mut self.particles;
        permute(&mut p.position, order);
        permute(&mut p.velocity, order);
        permute(&mut p.angular_velocity, order);
        permute(&mut p.radius, order);
        permute(&mut p.reference_radius, order);
        permute(&mut p.mass, order);
        permute(&mut p.inertia, order);
        permute(&mut p.fixed, order);
        permute(&mut p.external_force, order);
        permute(&mut p.external_torque, order);
        permute(&mut p.temperature, order);
        permute(&mut p.force, order);
        permute(&mut p.torque, order);
        permute(&mut self.search_reference_position, order);
        permute(&mut self.search_reference_radius, order);
        let renamed = |i: u32| new_index.get(i as usize).copied().unwrap_or(i);
        for e in &mut self.bond_breaks {
            let (a, b) = (renamed(e.a), renamed(e.b));
            (e.a, e.b) = (a.min(b), a.max(b));
        }
        self.contacts = self.contacts.renamed(|[a, b], h| {
            let (a, b) = (renamed(a), renamed(b));
            if a < b {
                ([a, b], h)
            } else {
                let mirrored = ContactHistory {
                    shear_force: -h.shear_force,
                    normal: -h.normal,
                    ..h
                };
                ([b, a], mirrored)
            }
        });
        self.wall_contacts = self.wall_contacts.renamed(|[a, w], h| ([renamed(a), w], h));
        self.contact_generation += 1;
        Ok(())
    }

    /// Bonded pairs `(a, b)` as installed (intact or broken).
    pub fn bonds(&self) -> Vec<(usize, usize)> {
        self.contacts
            .pair
            .iter()
            .zip(&self.contacts.history)
            .filter(|(_, h)| h.bond != BondState::None)
            .map(|(p, _)| (p[0] as usize, p[1] as usize))
            .collect()
    }

    /// Checks the whole state (particles, contact indices, walls).
    pub fn validate(&self) -> Result<(), DemError> {
        self.particles.validate()?;
        let n = self.particles.len();
        for (index, p) in self.contacts.pair.iter().enumerate() {
            let (a, b) = (p[0] as usize, p[1] as usize);
            if a >= b || b >= n {
                return Err(DemError::InvalidContact {
                    index,
                    a,
                    b,
                    particle_count: n,
                });
            }
        }
        for (index, p) in self.wall_contacts.pair.iter().enumerate() {
            let (a, w) = (p[0] as usize, p[1] as usize);
            if a >= n || w >= self.walls.len() {
                return Err(DemError::InvalidContact {
                    index,
                    a,
                    b: w,
                    particle_count: n,
                });
            }
        }
        for (field, list) in [
            ("contacts", &self.contacts),
            ("wall_contacts", &self.wall_contacts),
        ] {
            for len in [list.history.len(), list.report.len()] {
                if len != list.len() {
                    return Err(DemError::LengthMismatch {
                        field,
                        len,
                        expected: list.len(),
                    });
                }
            }
        }
        Ok(())
    }
}
