//! The space a contact lives in: [`Vec2`] for disks, [`Vec3`] for spheres.
//!
//! The contact kinematics and the force law ([`crate::contact`]) are written once over
//! [`SpaceVector`] and monomorphised for each dimension, so disks pay only 2D arithmetic while
//! spheres and disks share one implementation of every law. Angular quantities (angular
//! velocity, torque) are [`SpaceVector::Angular`]: a vector in 3D, the scalar `z` component in
//! 2D (a disk turns about the normal of its plane only).

use crate::vec3::{Vec3, rotate_about, rotate_minimal, sin_cos};
use serde::{Deserialize, Serialize};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A vector of the contact space (positions, velocities, forces) with the operations the
/// contact kinematics and laws need.
pub trait SpaceVector:
    Copy
    + PartialEq
    + Default
    + Debug
    + Send
    + Sync
    + Add<Output = Self>
    + Sub<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + AddAssign
    + SubAssign
{
    /// Angular velocity or torque: a vector in 3D, the out-of-plane component in 2D.
    type Angular: Copy
        + PartialEq
        + Default
        + Debug
        + Send
        + Sync
        + Add<Output = Self::Angular>
        + AddAssign
        + Neg<Output = Self::Angular>
        + Mul<f64, Output = Self::Angular>;

    /// The zero vector.
    const ZERO: Self;
    /// The unit vector along `x` (the normal of two coincident centres).
    const UNIT_X: Self;

    /// Dot product.
    fn dot(self, o: Self) -> f64;

    /// Squared Euclidean norm.
    #[inline]
    fn norm_squared(self) -> f64 {
        self.dot(self)
    }

    /// Euclidean norm.
    #[inline]
    fn norm(self) -> f64 {
        self.norm_squared().sqrt()
    }

    /// Velocity of a point at lever arm `r` on a body turning at `omega`: `ω × r`.
    fn angular_cross(omega: Self::Angular, r: Self) -> Self;

    /// Moment of the force `f` acting at lever arm `r`: `r × f`.
    fn moment(r: Self, f: Self) -> Self::Angular;

    /// Component of an angular quantity along the unit vector `n`: `ω·n` (0 in 2D, where every
    /// angular quantity is normal to the plane that holds `n`).
    fn angular_along(omega: Self::Angular, n: Self) -> f64;

    /// Carries a tangential vector with the contact frame: the minimal rotation from the unit
    /// vector `from` onto the unit vector `to`, then the rotation by `twist` about `to`
    /// (radians; always 0 in 2D). Antiparallel normals leave `v` unchanged.
    fn rotate_with_frame(v: Self, from: Self, to: Self, twist: f64) -> Self;

    /// Carries a vector of the tangent plane of `from` into the tangent plane of `to`:
    /// [`SpaceVector::rotate_with_frame`], then the projection onto the new tangent plane
    /// (which removes round-off only).
    #[inline]
    fn carry_tangential(v: Self, from: Self, to: Self, twist: f64) -> Self {
        let rotated = Self::rotate_with_frame(v, from, to, twist);
        rotated - to * rotated.dot(to)
    }
}

impl SpaceVector for Vec3 {
    type Angular = Vec3;
    const ZERO: Self = Vec3::ZERO;
    const UNIT_X: Self = Vec3::new(1.0, 0.0, 0.0);

    #[inline]
    fn dot(self, o: Self) -> f64 {
        Vec3::dot(self, o)
    }

    #[inline]
    fn angular_cross(omega: Vec3, r: Self) -> Self {
        omega.cross(r)
    }

    #[inline]
    fn moment(r: Self, f: Self) -> Vec3 {
        r.cross(f)
    }

    #[inline]
    fn angular_along(omega: Vec3, n: Self) -> f64 {
        omega.dot(n)
    }

    #[inline]
    fn rotate_with_frame(v: Self, from: Self, to: Self, twist: f64) -> Self {
        rotate_about(rotate_minimal(v, from, to), to, twist)
    }

    /// For `v` in the tangent plane of `from` the minimal rotation onto `to` is
    /// `v − (to·v)/(1 + c) (from + to)`, `c = from·to` (the formula of [`rotate_minimal`] with
    /// `from·v = 0`; it maps any `v` into the tangent plane of `to`), and the twist of a vector
    /// of that plane about `to` is `u cos φ + (to × u) sin φ`. The same rotation as
    /// [`SpaceVector::rotate_with_frame`] followed by the projection, to round-off (property
    /// test below), in about half the arithmetic and without the projection.
    #[inline]
    fn carry_tangential(v: Self, from: Self, to: Self, twist: f64) -> Self {
        let c = from.dot(to);
        if c <= -1.0 + 1e-12 {
            let rotated = rotate_about(v, to, twist);
            return rotated - to * rotated.dot(to);
        }
        let u = v - (from + to) * (to.dot(v) / (1.0 + c));
        if twist == 0.0 {
            return u;
        }
        let (s, cos) = sin_cos(twist);
        u * cos + to.cross(u) * s
    }
}

/// A vector in ℝ² (disks: positions, velocities, forces in the `xy` plane).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Vec2 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
}

impl Vec2 {
    /// The zero vector.
    pub const ZERO: Self = Self::new(0.0, 0.0);

    /// A vector from its components.
    #[inline]
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }

    /// Dot product.
    #[inline]
    pub fn dot(self, o: Self) -> f64 {
        self.x * o.x + self.y * o.y
    }

    /// The scalar cross product `self × o` (the `z` component of the 3D cross product).
    #[inline]
    pub fn perp_dot(self, o: Self) -> f64 {
        self.x * o.y - self.y * o.x
    }

    /// Squared Euclidean norm.
    #[inline]
    pub fn norm_squared(self) -> f64 {
        self.dot(self)
    }

    /// Euclidean norm.
    #[inline]
    pub fn norm(self) -> f64 {
        self.norm_squared().sqrt()
    }

    /// True when both components are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }

    /// The in-plane part of a 3D vector.
    #[inline]
    pub fn from_xy(v: Vec3) -> Self {
        Self::new(v.x, v.y)
    }

    /// This vector in the `z = 0` plane of 3D space.
    #[inline]
    pub fn to_vec3(self) -> Vec3 {
        Vec3::new(self.x, self.y, 0.0)
    }
}

impl SpaceVector for Vec2 {
    type Angular = f64;
    const ZERO: Self = Vec2::ZERO;
    const UNIT_X: Self = Vec2::new(1.0, 0.0);

    #[inline]
    fn dot(self, o: Self) -> f64 {
        Vec2::dot(self, o)
    }

    #[inline]
    fn angular_cross(omega: f64, r: Self) -> Self {
        Self::new(-omega * r.y, omega * r.x)
    }

    #[inline]
    fn moment(r: Self, f: Self) -> f64 {
        r.perp_dot(f)
    }

    #[inline]
    fn angular_along(_omega: f64, _n: Self) -> f64 {
        0.0
    }

    /// In the plane the minimal rotation is the rotation by the angle from `from` to `to`,
    /// `cos = from·to`, `sin = from × to` (exact for unit vectors, no trigonometric call); the
    /// twist about an in-plane normal is zero for disks.
    #[inline]
    fn rotate_with_frame(v: Self, from: Self, to: Self, _twist: f64) -> Self {
        let c = from.dot(to);
        if c <= -1.0 + 1e-12 {
            return v;
        }
        let s = from.perp_dot(to);
        Self::new(c * v.x - s * v.y, s * v.x + c * v.y)
    }

    /// In the plane a tangent "plane" is a line: the component of `v` along the old tangent
    /// `t = (−n_y, n_x)` of `from` is carried onto the new tangent of `to`. Equal to rotating
    /// and projecting up to round-off (for a `v` tangential to `from`, as the shear force is).
    #[inline]
    fn carry_tangential(v: Self, from: Self, to: Self, _twist: f64) -> Self {
        if from.dot(to) <= -1.0 + 1e-12 {
            return v - to * v.dot(to);
        }
        let along = from.perp_dot(v);
        Self::new(-to.y * along, to.x * along)
    }
}

impl Add for Vec2 {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y)
    }
}

impl Sub for Vec2 {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y)
    }
}

impl Neg for Vec2 {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y)
    }
}

impl Mul<f64> for Vec2 {
    type Output = Self;
    #[inline]
    fn mul(self, s: f64) -> Self {
        Self::new(self.x * s, self.y * s)
    }
}

impl Div<f64> for Vec2 {
    type Output = Self;
    #[inline]
    fn div(self, s: f64) -> Self {
        Self::new(self.x / s, self.y / s)
    }
}

impl AddAssign for Vec2 {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl SubAssign for Vec2 {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{
        ContactHistory, ContactKinematics, ContactLaw, LinearSpringParams, PairInput,
    };
    use proptest::prelude::*;

    /// One law, two spaces: a disk B rolling and sliding around a disk A, evaluated by the
    /// 2D instance and by the 3D instance in the `z = 0` plane, gives the same forces,
    /// torques, friction work and shear history to round-off over a thousand steps (the
    /// normal turns by about a radian, the contact slides part of the time).
    #[test]
    fn disk_contact_in_2d_equals_the_3d_law_in_the_plane() {
        let law = LinearSpringParams {
            normal_stiffness: 1e6,
            tangential_stiffness: 8e5,
            friction_coefficient: 0.3,
            thermal_bond: None,
        }
        .validate()
        .unwrap();
        let (ra, rb, dt) = (1e-3, 0.7e-3, 1e-6);
        let pair = PairInput {
            radius_a: ra,
            radius_b: rb,
            temperature: 293.0,
        };
        let mut h2 = ContactHistory::<Vec2>::UNBONDED;
        let mut h3 = ContactHistory::<Vec3>::UNBONDED;
        let (mut slid, mut max_force) = (0, 0.0_f64);
        for k in 0..1000 {
            let t = k as f64 * dt;
            // B rolls around A (the normal turns by one radian over the run) at a varying
            // overlap, with a spin mismatch that makes it stick and slip in turn.
            let orbit = 1000.0;
            let angle = orbit * t;
            let distance = ra + rb - 2e-6 * (1.0 + 0.5 * (3000.0 * t).sin());
            let branch = Vec2::new(angle.cos(), angle.sin()) * distance;
            let velocity = Vec2::new(-angle.sin(), angle.cos()) * (orbit * distance);
            let lever_b = rb - 0.5 * (ra + rb - distance);
            let rolling = orbit * distance / lever_b;
            let wa = 2.0 * (5000.0 * t).sin();
            let wb = rolling * (1.0 + 0.005 * (20_000.0 * t).sin());
            let k2 = ContactKinematics::<Vec2>::from_pair(branch, velocity, wa, wb, ra, rb, dt);
            let k3 = ContactKinematics::<Vec3>::from_pair(
                branch.to_vec3(),
                velocity.to_vec3(),
                Vec3::new(0.0, 0.0, wa),
                Vec3::new(0.0, 0.0, wb),
                ra,
                rb,
                dt,
            );
            let r2 = law.respond(&pair, &k2, &mut h2);
            let r3 = law.respond(&pair, &k3, &mut h3);
            let scale = r3.force_on_b.norm().max(1e-12);
            max_force = max_force.max(scale);
            assert!((r2.force_on_b.to_vec3() - r3.force_on_b).norm() <= 1e-12 * scale);
            assert!((h2.shear_force.to_vec3() - h3.shear_force).norm() <= 1e-12 * scale);
            let torque_scale = scale * ra;
            assert!((r2.torque_on_a - r3.torque_on_a.z).abs() <= 1e-12 * torque_scale);
            assert!((r2.torque_on_b - r3.torque_on_b.z).abs() <= 1e-12 * torque_scale);
            assert!(r3.torque_on_a.x == 0.0 && r3.torque_on_a.y == 0.0);
            let work_scale = scale * scale / 8e5;
            assert!((r2.friction_work - r3.friction_work).abs() <= 1e-12 * work_scale);
            if r3.friction_work > 0.0 {
                slid += 1;
            }
        }
        // The comparison covered sliding and sticking steps under a real load.
        assert!((50..=950).contains(&slid), "sliding steps: {slid}");
        assert!(max_force > 1.0, "{max_force}");
    }

    fn v2(x: f64, y: f64) -> Vec2 {
        Vec2::new(x, y)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The 2D operations are the 3D ones restricted to the plane: ω × r, r × f and the
        /// frame rotation of an in-plane vector about `z` agree to round-off.
        #[test]
        fn planar_operations_match_3d_in_the_plane(
            ax in -3.0..3.0_f64, ay in -3.0..3.0_f64,
            bx in -3.0..3.0_f64, by in -3.0..3.0_f64,
            w in -5.0..5.0_f64,
            from_angle in -3.0..3.0_f64, turn in -1.0..1.0_f64,
        ) {
            let (a, b) = (v2(ax, ay), v2(bx, by));
            let wa = Vec2::angular_cross(w, a);
            let wa3 = Vec3::angular_cross(Vec3::new(0.0, 0.0, w), a.to_vec3());
            prop_assert!((wa.to_vec3() - wa3).norm() <= 1e-14 * (1.0 + wa3.norm()));
            let m = Vec2::moment(a, b);
            let m3 = Vec3::moment(a.to_vec3(), b.to_vec3());
            prop_assert!((m - m3.z).abs() <= 1e-14 * (1.0 + m3.norm()));
            prop_assert!(m3.x == 0.0 && m3.y == 0.0);
            let from = v2(from_angle.cos(), from_angle.sin());
            let to = v2((from_angle + turn).cos(), (from_angle + turn).sin());
            let r = Vec2::rotate_with_frame(a, from, to, 0.0);
            let r3 = Vec3::rotate_with_frame(a.to_vec3(), from.to_vec3(), to.to_vec3(), 0.0);
            prop_assert!((r.to_vec3() - r3).norm() <= 1e-13 * (1.0 + a.norm()));
            // A rotation keeps the length and maps `from` onto `to`.
            prop_assert!((r.norm() - a.norm()).abs() <= 1e-13 * (1.0 + a.norm()));
            let f = Vec2::rotate_with_frame(from, from, to, 0.0);
            prop_assert!((f - to).norm() <= 1e-14);
            // Carrying a tangential vector: the 2D shortcut equals rotate-and-project in 3D.
            let tangential = v2(-from.y, from.x) * ax;
            let carried = Vec2::carry_tangential(tangential, from, to, 0.0);
            let carried3 =
                Vec3::carry_tangential(tangential.to_vec3(), from.to_vec3(), to.to_vec3(), 0.0);
            prop_assert!((carried.to_vec3() - carried3).norm() <= 1e-13 * (1.0 + ax.abs()));
            prop_assert!(carried.dot(to).abs() <= 1e-14 * (1.0 + ax.abs()));
        }

        /// The 3D shortcut for a vector of the old tangent plane is the rotation (minimal, then
        /// the twist about the new normal) followed by the projection: to round-off, for any
        /// turn of the normal below π and any twist, and its result lies in the new tangent
        /// plane with the length of the input.
        #[test]
        fn carrying_a_tangential_vector_in_3d_is_rotate_and_project(
            theta in 0.0..3.1_f64, phi in -3.2..3.2_f64,
            turn in 0.0..3.0_f64, turn_dir in -3.2..3.2_f64,
            along in -3.2..3.2_f64, length in 0.0..5.0_f64,
            twist in -2.0..2.0_f64, small in any::<bool>(),
        ) {
            let from = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            // Two unit vectors of the tangent plane of `from`.
            let e1 = if from.x.abs() < 0.9 { Vec3::new(1.0, 0.0, 0.0) } else { Vec3::new(0.0, 1.0, 0.0) };
            let t1 = (e1 - from * e1.dot(from)) / (e1 - from * e1.dot(from)).norm();
            let t2 = from.cross(t1);
            let dir = t1 * turn_dir.cos() + t2 * turn_dir.sin();
            let turn = if small { turn * 1e-4 } else { turn };
            let to = from * turn.cos() + dir * turn.sin();
            let twist = if small { twist * 1e-5 } else { twist };
            let v = (t1 * along.cos() + t2 * along.sin()) * length;
            let fast = Vec3::carry_tangential(v, from, to, twist);
            let rotated = Vec3::rotate_with_frame(v, from, to, twist);
            let slow = rotated - to * rotated.dot(to);
            let scale = 1.0 + length;
            prop_assert!((fast - slow).norm() <= 1e-13 * scale, "{fast:?} vs {slow:?}");
            prop_assert!(fast.dot(to).abs() <= 1e-14 * scale);
            prop_assert!((fast.norm() - length).abs() <= 1e-13 * scale);
        }
    }
}
