//! Contact geometry, history and laws, split as in YADE: geometry (normal, penetration,
//! shear increment) → physical properties (stiffnesses and strengths from the two particles)
//! → one force law shared by every material.
//!
//! Everything here is a pure function of its arguments, so a periodic cell can call it with its
//! own branch vectors and velocities (the image shift and the homogeneous velocity field are
//! the caller's business).
//!
//! Kinematics, history, response and the force law are generic over the space
//! ([`SpaceVector`]): one implementation, monomorphised for spheres ([`Vec3`], the default type
//! parameter) and for disks ([`crate::Vec2`], 2D arithmetic only).

use crate::error::{DemError, check_positive, check_range};
use crate::vec3::Vec3;
use crate::vector::SpaceVector;
use serde::{Deserialize, Serialize};

/// Whether a contact carries a cohesive bond.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum BondState {
    /// Never bonded: purely frictional, no tension.
    #[default]
    None,
    /// An intact bond: carries tension up to its tensile strength.
    Intact,
    /// A broken bond: frictional, no tension; cohesion never comes back (A-Eq. 5).
    Broken,
}

/// How a bond broke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BreakMode {
    /// The tensile force exceeded the tensile strength (A-Eq. 6 `T·R²`, B-Eq. 38).
    Tension,
    /// The shear force exceeded the shear strength (A-Eq. 4, B-Eq. 39).
    Shear,
}

/// The history a contact carries from step to step.
///
/// Aligned to a 64-byte cache line (the size of the 3D history): a contact pass that
/// evaluates a contact then reads and writes one line of the list, not two.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ContactHistory<V = Vec3> {
    /// Shear force on particle B \[N\], in the tangent plane of `normal`.
    pub shear_force: V,
    /// Contact normal (A → B) at the previous step; zero for a contact not yet evaluated.
    pub normal: V,
    /// Penetration at which the normal force is zero \[m\]: the creation penetration of a
    /// bond (stress-free at its creation distance; negative across a gap), 0 for a contact
    /// that was never bonded.
    pub reference_penetration: f64,
    /// Bond state.
    pub bond: BondState,
}

const _: () = assert!(std::mem::size_of::<ContactHistory>() == 64);

impl<V: SpaceVector> ContactHistory<V> {
    /// A fresh, unbonded contact.
    pub const UNBONDED: Self = Self {
        shear_force: V::ZERO,
        normal: V::ZERO,
        reference_penetration: 0.0,
        bond: BondState::None,
    };

    /// An intact bond that is stress-free at the given penetration (negative across a gap).
    pub fn bonded_at(penetration: f64) -> Self {
        Self {
            reference_penetration: penetration,
            bond: BondState::Intact,
            ..Self::UNBONDED
        }
    }

    /// The total force on B, `n F_n + F_s`, from this history's normal and shear force and
    /// the normal force `F_n` \[N\]: the one expression [`update_contact`] sums and
    /// [`crate::ContactList::force_on_b`] rebuilds, so both give the same bits.
    #[inline]
    pub fn force_on_b(&self, normal_force: f64) -> V {
        self.normal * normal_force + self.shear_force
    }
}

/// Kinematics of one contact over one step (what the law needs from the geometry).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactKinematics<V = Vec3> {
    /// Unit normal from A to B.
    pub normal: V,
    /// Geometric penetration `R_A + R_B − |x_B − x_A|` \[m\] (negative across a gap).
    pub penetration: f64,
    /// Tangential relative displacement of B with respect to A at the contact point over the
    /// step \[m\] (`Δ X_s` of A-Eq. 2, `δu^t` of B-Eq. 35b).
    pub shear_increment: V,
    /// Rotation of the contact frame about the normal over the step \[rad\]:
    /// `½ (ω_A + ω_B)·n Δt` (0 for disks).
    pub twist_angle: f64,
    /// Distance from the centre of A to the contact point \[m\]: the lever arm of A is
    /// `arm_a · normal`.
    pub arm_a: f64,
    /// Distance from the centre of B to the contact point \[m\]: the lever arm of B is
    /// `−arm_b · normal` (0 for a wall).
    pub arm_b: f64,
}

impl<V: SpaceVector> ContactKinematics<V> {
    /// Kinematics of a pair from the branch vector `x_B − x_A` (a periodic cell passes the
    /// vector to the nearest image), the centre velocity of B relative to A, the angular
    /// velocities and the radii. The contact point lies in the middle of the overlap, at
    /// `R_A − δ/2` from A and `R_B − δ/2` from B.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn from_pair(
        branch: V,
        relative_velocity: V,
        angular_velocity_a: V::Angular,
        angular_velocity_b: V::Angular,
        radius_a: f64,
        radius_b: f64,
        dt: f64,
    ) -> Self {
        let distance = branch.norm();
        let normal = if distance > 0.0 {
            branch * (1.0 / distance)
        } else {
            V::UNIT_X
        };
        let penetration = radius_a + radius_b - distance;
        let (arm_a, arm_b) = (radius_a - 0.5 * penetration, radius_b - 0.5 * penetration);
        // ω_B × l_B − ω_A × l_A with both levers along the normal: one cross product.
        let v_rel = relative_velocity
            - V::angular_cross(
                angular_velocity_a * arm_a + angular_velocity_b * arm_b,
                normal,
            );
        let v_t = v_rel - normal * v_rel.dot(normal);
        Self {
            normal,
            penetration,
            shear_increment: v_t * dt,
            twist_angle: 0.5
                * V::angular_along(angular_velocity_a + angular_velocity_b, normal)
                * dt,
            arm_a,
            arm_b,
        }
    }

    /// Kinematics of a particle (A) against a rigid plane wall through `wall_point` with unit
    /// normal `wall_normal` pointing into the domain, moving at `wall_velocity`. The wall is
    /// body B; the contact normal is `−wall_normal`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn from_wall(
        position: V,
        velocity: V,
        angular_velocity: V::Angular,
        radius: f64,
        wall_point: V,
        wall_normal: V,
        wall_velocity: V,
        dt: f64,
    ) -> Self {
        let gap = (position - wall_point).dot(wall_normal);
        let normal = -wall_normal;
        let penetration = radius - gap;
        let arm_a = radius - 0.5 * penetration;
        let v_rel = wall_velocity - velocity - V::angular_cross(angular_velocity, normal * arm_a);
        let v_t = v_rel - normal * v_rel.dot(normal);
        Self {
            normal,
            penetration,
            shear_increment: v_t * dt,
            twist_angle: 0.5 * V::angular_along(angular_velocity, normal) * dt,
            arm_a,
            arm_b: 0.0,
        }
    }
}

/// What a law needs to know about the two particles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairInput {
    /// Radius of A \[m\].
    pub radius_a: f64,
    /// Radius of B \[m\] (for a wall: the particle's own radius, as YADE does).
    pub radius_b: f64,
    /// Contact temperature \[K\]: the mean of the two particle temperatures.
    pub temperature: f64,
}

/// Stiffnesses and strengths of one contact (YADE's "interaction physics").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactProperties {
    /// Normal stiffness `K_n` \[N/m\].
    pub normal_stiffness: f64,
    /// Shear stiffness `K_s` \[N/m\].
    pub shear_stiffness: f64,
    /// Friction coefficient `tan μ_c` (A) or `μ` (B) \[-\].
    pub friction_coefficient: f64,
    /// Tensile strength of an intact bond \[N\] (`T·R²`, `β_b k_n R`).
    pub bond_tensile_strength: f64,
    /// Shear strength of an intact bond at zero normal force \[N\] (`C·R²`, `μ_b F_nb`).
    pub bond_shear_strength: f64,
    /// Whether friction `F_n tan μ` adds to the bond's shear strength (A-Eq. 4: yes; B-Eq. 39:
    /// no).
    pub friction_adds_to_bond_shear: bool,
    /// Area that turns the normal force into the contact normal stress \[m²\].
    pub stress_area: f64,
}

/// The result of one contact update.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ContactResponse<V: SpaceVector = Vec3> {
    /// Total force on B \[N\] (A receives its negative).
    pub force_on_b: V,
    /// Torque on A about its centre \[N m\].
    pub torque_on_a: V::Angular,
    /// Torque on B about its centre \[N m\].
    pub torque_on_b: V::Angular,
    /// Normal force \[N\], compression positive, tension negative (intact bonds only).
    pub normal_force: f64,
    /// Contact normal stress \[Pa\], compression positive (`F_n / R²`, the same `R` as the bond
    /// strength, so that an intact bond of A-Eq. 6 breaks at `σ_n = −T`).
    pub normal_stress: f64,
    /// Energy dissipated by frictional sliding during the step \[J\] (B-Eq. 32).
    pub friction_work: f64,
    /// Set in the step in which the bond broke.
    pub broke: Option<BreakMode>,
    /// True while the contact carries force (bonded, or touching).
    pub active: bool,
}

/// What one contact's last step leaves for the caller: the scalars of its
/// [`ContactResponse`] (the coupling reads the normal stress for the channel aperture,
/// A-Eq. 8, and the friction work, B-Eq. 32). The force itself is not repeated here: the
/// history holds its two parts (see [`crate::ContactList::force_on_b`]).
///
/// Aligned to its size, 32 bytes, so that writing one touches one cache line.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ContactReport {
    /// Normal force \[N\], compression positive, tension negative (intact bonds only).
    pub normal_force: f64,
    /// Contact normal stress \[Pa\], compression positive (`F_n / R²`).
    pub normal_stress: f64,
    /// Energy dissipated by frictional sliding during the step \[J\] (B-Eq. 32).
    pub friction_work: f64,
    /// Set in the step in which the bond broke.
    pub broke: Option<BreakMode>,
    /// True while the contact carries force (bonded, or touching).
    pub active: bool,
}

const _: () = assert!(std::mem::size_of::<ContactReport>() == 32);

impl<V: SpaceVector> From<&ContactResponse<V>> for ContactReport {
    #[inline]
    fn from(r: &ContactResponse<V>) -> Self {
        Self {
            normal_force: r.normal_force,
            normal_stress: r.normal_stress,
            friction_work: r.friction_work,
            broke: r.broke,
            active: r.active,
        }
    }
}

/// A contact law: stiffnesses and strengths of a pair (one small seam). The force update
/// ([`update_contact`]) is shared by every law; a law with a different force update overrides
/// [`ContactLaw::respond`]. Both are generic over the space, so one law serves spheres and
/// disks, monomorphised (no dynamic dispatch in the contact loop).
pub trait ContactLaw: Sync + Send + std::fmt::Debug {
    /// Stiffnesses and strengths of the pair.
    fn properties(&self, pair: &PairInput) -> ContactProperties;

    /// Updates the history of one contact and returns its forces.
    #[inline]
    fn respond<V: SpaceVector>(
        &self,
        pair: &PairInput,
        kinematics: &ContactKinematics<V>,
        history: &mut ContactHistory<V>,
    ) -> ContactResponse<V> {
        update_contact(&self.properties(pair), kinematics, history)
    }
}

/// Carries the shear force with the contact frame: the minimal rotation from the previous
/// normal to the new one, then the twist about the new normal; the result lies in the new
/// tangent plane (exact rotations, written for a vector of the old tangent plane:
/// [`SpaceVector::carry_tangential`]).
#[inline]
pub fn rotate_shear_force<V: SpaceVector>(
    shear_force: V,
    old_normal: V,
    normal: V,
    twist: f64,
) -> V {
    V::carry_tangential(shear_force, old_normal, normal, twist)
}

/// The force law shared by every material (A-Eqs. 1–6, B-Eqs. 35–36, 38–39):
///
/// 1. rotate the stored shear force with the contact frame;
/// 2. `F_n = K_n (U − U₀)` with `U₀` the bond's creation penetration (A-Eq. 1);
/// 3. trial shear `F_s = F_s,prev − K_s ΔX_s` (A-Eq. 2, B-Eq. 35b; force on B opposes B's
///    slip relative to A);
/// 4. an intact bond breaks in tension when `−F_n > F_n,min` (A-Eq. 6, B-Eq. 38), else in shear
///    when `|F_s| > F_s,max + F_n tan μ` (A-Eq. 4, signed `F_n`: tension lowers the strength, the
///    modified Mohr–Coulomb envelope) or `|F_s| > F_tb` (B-Eq. 39);
/// 5. without an intact bond: no tension, `|F_s| ≤ F_n tan μ` (A-Eq. 5, B-Eq. 36); the slip
///    dissipates `|F_s| (|F_s,trial| − |F_s|)/K_s` (B-Eq. 32 with the sliding part of the
///    tangential velocity).
#[inline]
pub fn update_contact<V: SpaceVector>(
    props: &ContactProperties,
    kin: &ContactKinematics<V>,
    history: &mut ContactHistory<V>,
) -> ContactResponse<V> {
    let n = kin.normal;
    let old_normal = if history.normal == V::ZERO {
        n
    } else {
        history.normal
    };
    history.normal = n;
    let overlap = kin.penetration - history.reference_penetration;
    if history.bond != BondState::Intact && overlap <= 0.0 {
        history.shear_force = V::ZERO;
        return ContactResponse::default();
    }
    let rotated = rotate_shear_force(history.shear_force, old_normal, n, kin.twist_angle);
    let mut normal_force = props.normal_stiffness * overlap;
    let mut shear = rotated - kin.shear_increment * props.shear_stiffness;
    let mut broke = None;
    let mut friction_work = 0.0;
    if history.bond == BondState::Intact {
        if -normal_force > props.bond_tensile_strength {
            broke = Some(BreakMode::Tension);
        } else {
            let friction = if props.friction_adds_to_bond_shear {
                normal_force * props.friction_coefficient
            } else {
                0.0
            };
            let strength = (props.bond_shear_strength + friction).max(0.0);
            // |F_s| > strength, compared squared (both sides are non-negative): no root.
            if shear.norm_squared() > strength * strength {
                broke = Some(BreakMode::Shear);
            }
        }
        if broke.is_some() {
            history.bond = BondState::Broken;
        }
    }
    if history.bond != BondState::Intact {
        normal_force = normal_force.max(0.0);
        let limit = normal_force * props.friction_coefficient;
        // Sliding when |F_s| > limit, compared squared (both sides are non-negative): a
        // sticking contact takes no root.
        if shear.norm_squared() > limit * limit {
            let trial = shear.norm();
            shear = if trial > 0.0 {
                shear * (limit / trial)
            } else {
                V::ZERO
            };
            if props.shear_stiffness > 0.0 {
                friction_work = limit * (trial - limit) / props.shear_stiffness;
            }
        }
    }
    history.shear_force = shear;
    let force_on_b = history.force_on_b(normal_force);
    // Both levers lie along the normal: (arm_a n) × (−F) = −arm_a (n × F) and
    // (−arm_b n) × F = −arm_b (n × F), one cross product.
    let moment = V::moment(n, force_on_b);
    ContactResponse {
        force_on_b,
        torque_on_a: moment * -kin.arm_a,
        torque_on_b: moment * -kin.arm_b,
        normal_force,
        normal_stress: normal_force / props.stress_area,
        friction_work,
        broke,
        active: normal_force != 0.0 || history.bond == BondState::Intact || shear != V::ZERO,
    }
}

/// Which radius enters `T·R²` and `C·R²` (A-Eq. 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BondRadius {
    /// `min(R_A, R_B)`, as YADE's `CohFrictPhys` (the default).
    #[default]
    Smaller,
    /// `(R_A + R_B)/2`.
    Mean,
}

impl BondRadius {
    /// The radius of the pair.
    #[inline]
    pub fn of(self, radius_a: f64, radius_b: f64) -> f64 {
        match self {
            Self::Smaller => radius_a.min(radius_b),
            Self::Mean => 0.5 * (radius_a + radius_b),
        }
    }
}

/// Parameters of the cohesive-frictional law of Krzaczek et al. (A-Eqs. 1–7), as read from
/// a file. SI units; the friction angle in degrees as in A-Table 1.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CohesiveFrictionalParams {
    /// Contact modulus `E_c` \[Pa\].
    pub contact_modulus: f64,
    /// Contact Poisson ratio `ν_c` \[-\]: `K_s = ν_c K_n` (A-Eq. 3).
    pub contact_poisson_ratio: f64,
    /// Cohesive contact stress `C` \[Pa\].
    pub cohesion: f64,
    /// Tensile normal contact stress `T` \[Pa\].
    pub tensile_strength: f64,
    /// Inter-particle friction angle `μ_c` \[°\].
    pub friction_angle_deg: f64,
    /// Which radius enters `T·R²` and `C·R²`.
    #[serde(default)]
    pub bond_radius: BondRadius,
}

impl CohesiveFrictionalParams {
    /// The solid of A-Table 1: `E_c` = 3.36 GPa, `ν_c` = 0.3, `C` = 150 MPa, `T` = 30 MPa,
    /// `μ_c` = 18°.
    pub fn paper_a_table_1() -> Self {
        Self {
            contact_modulus: 3.36e9,
            contact_poisson_ratio: 0.3,
            cohesion: 150e6,
            tensile_strength: 30e6,
            friction_angle_deg: 18.0,
            bond_radius: BondRadius::Smaller,
        }
    }

    /// Validates into the law.
    pub fn validate(&self) -> Result<CohesiveFrictional, DemError> {
        check_positive("contact_modulus", self.contact_modulus)?;
        check_range(
            "contact_poisson_ratio",
            self.contact_poisson_ratio,
            0.0,
            10.0,
            "[0, 10]",
        )?;
        check_range("cohesion", self.cohesion, 0.0, f64::MAX, "[0, ∞)")?;
        check_range(
            "tensile_strength",
            self.tensile_strength,
            0.0,
            f64::MAX,
            "[0, ∞)",
        )?;
        check_range(
            "friction_angle_deg",
            self.friction_angle_deg,
            0.0,
            89.9,
            "[0, 89.9]",
        )?;
        Ok(CohesiveFrictional {
            params: *self,
            tan_friction: self.friction_angle_deg.to_radians().tan(),
        })
    }
}

/// The cohesive-frictional law of Krzaczek et al. (A-Eqs. 1–6); built by
/// [`CohesiveFrictionalParams::validate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CohesiveFrictional {
    params: CohesiveFrictionalParams,
    tan_friction: f64,
}

impl CohesiveFrictional {
    /// The validated parameters.
    pub fn params(&self) -> &CohesiveFrictionalParams {
        &self.params
    }
}

impl ContactLaw for CohesiveFrictional {
    #[inline]
    fn properties(&self, pair: &PairInput) -> ContactProperties {
        let (ra, rb) = (pair.radius_a, pair.radius_b);
        let kn = self.params.contact_modulus * 2.0 * ra * rb / (ra + rb);
        let r = self.params.bond_radius.of(ra, rb);
        let r2 = r * r;
        ContactProperties {
            normal_stiffness: kn,
            shear_stiffness: self.params.contact_poisson_ratio * kn,
            friction_coefficient: self.tan_friction,
            bond_tensile_strength: self.params.tensile_strength * r2,
            bond_shear_strength: self.params.cohesion * r2,
            friction_adds_to_bond_shear: true,
            stress_area: r2,
        }
    }
}

/// The thermally sensitive bond of Zhao et al. (B-Eqs. 38–40).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalBondParams {
    /// `β_a` \[-\]: the breakage strength coefficient at the reference temperature.
    pub strength_coefficient: f64,
    /// `T_s` \[K\]: temperature rise above `reference_temperature` at which the bond vanishes.
    pub threshold_temperature_rise: f64,
    /// Temperature at which `T = 0` in B-Eq. 40 \[K\].
    pub reference_temperature: f64,
    /// `μ_b` \[-\]: shear strength over normal strength (B-Eq. 39).
    pub shear_ratio: f64,
}

impl ThermalBondParams {
    /// `β_b(T)` of B-Eq. 40, with `T` measured from `reference_temperature`.
    #[inline]
    pub fn breakage_coefficient(&self, temperature: f64) -> f64 {
        let rise = temperature - self.reference_temperature;
        if rise <= self.threshold_temperature_rise {
            self.strength_coefficient * (self.threshold_temperature_rise - rise)
                / self.threshold_temperature_rise
        } else {
            0.0
        }
    }
}

/// Parameters of the linear spring + Coulomb law of Zhao et al. (B-Eqs. 35–36) with an optional
/// thermally sensitive bond (B-Eqs. 38–40).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearSpringParams {
    /// `k_n` \[N/m\].
    pub normal_stiffness: f64,
    /// `k_t` \[N/m\].
    pub tangential_stiffness: f64,
    /// `μ` \[-\].
    pub friction_coefficient: f64,
    /// Bond parameters; `None` for a cohesionless material.
    #[serde(default)]
    pub thermal_bond: Option<ThermalBondParams>,
}

impl LinearSpringParams {
    /// Validates into the law.
    pub fn validate(&self) -> Result<LinearSpring, DemError> {
        check_positive("normal_stiffness", self.normal_stiffness)?;
        check_range(
            "tangential_stiffness",
            self.tangential_stiffness,
            0.0,
            f64::MAX,
            "[0, ∞)",
        )?;
        check_range(
            "friction_coefficient",
            self.friction_coefficient,
            0.0,
            100.0,
            "[0, 100]",
        )?;
        if let Some(b) = &self.thermal_bond {
            check_range(
                "thermal_bond.strength_coefficient",
                b.strength_coefficient,
                0.0,
                f64::MAX,
                "[0, ∞)",
            )?;
            check_positive(
                "thermal_bond.threshold_temperature_rise",
                b.threshold_temperature_rise,
            )?;
            check_positive(
                "thermal_bond.reference_temperature",
                b.reference_temperature,
            )?;
            check_range(
                "thermal_bond.shear_ratio",
                b.shear_ratio,
                0.0,
                f64::MAX,
                "[0, ∞)",
            )?;
        }
        Ok(LinearSpring { params: *self })
    }
}

/// The linear spring + Coulomb law of Zhao et al. (B-Eqs. 35–40); built by
/// [`LinearSpringParams::validate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearSpring {
    params: LinearSpringParams,
}

impl LinearSpring {
    /// The validated parameters.
    pub fn params(&self) -> &LinearSpringParams {
        &self.params
    }
}

impl ContactLaw for LinearSpring {
    #[inline]
    fn properties(&self, pair: &PairInput) -> ContactProperties {
        let kn = self.params.normal_stiffness;
        let r_min = pair.radius_a.min(pair.radius_b);
        let (tensile, shear) = match &self.params.thermal_bond {
            Some(b) => {
                let mean_radius = 0.5 * (pair.radius_a + pair.radius_b);
                let fnb = b.breakage_coefficient(pair.temperature) * kn * mean_radius;
                (fnb, b.shear_ratio * fnb)
            }
            None => (0.0, 0.0),
        };
        ContactProperties {
            normal_stiffness: kn,
            shear_stiffness: self.params.tangential_stiffness,
            friction_coefficient: self.params.friction_coefficient,
            bond_tensile_strength: tensile,
            bond_shear_strength: shear,
            friction_adds_to_bond_shear: false,
            stress_area: r_min * r_min,
        }
    }
}
