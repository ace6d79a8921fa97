//! The state arrays the kinds share, for front ends that read and write a run's state between
//! steps (see [`crate::scenario::Scenario::arrays`]): material points of `thm-mpm`, spheres of
//! `thm-dem`, pores and cells of the pore-scale model.
//!
//! Names say what a row is (`point_`, `sphere_`, `pore_`, `cell_`) and what it holds; units
//! are SI. Stresses are Cauchy `[σxx, σyy, σxy]`, tension positive, as `thm-mpm` holds them.
//! Writable arrays are part of the state, so what is written is checkpointed with it.

use std::borrow::Cow;

use thm_dem::{ParticleState, Vec3};
use thm_mpm::MaterialPoints;

use crate::error::RunError;

/// Highest temperature accepted from outside \[K\].
pub const MAX_TEMPERATURE: f64 = 1.0e5;
/// Largest speed accepted from outside \[m/s\].
pub const MAX_SPEED: f64 = 1.0e4;
/// Largest external force accepted from outside \[N\].
pub const MAX_FORCE: f64 = 1.0e12;

/// The names of the material-point arrays of one set of points (a kind may have two, as the
/// square's multiscale model and its pure-MPM twin).
#[derive(Debug, Clone, Copy)]
pub struct PointNames {
    /// Centres \[m\], 2 columns.
    pub position: &'static str,
    /// Velocities \[m/s\], 2 columns (writable).
    pub velocity: &'static str,
    /// Cauchy stress \[Pa\], `[xx, yy, xy]`.
    pub stress: &'static str,
    /// Temperatures \[K\] (writable).
    pub temperature: &'static str,
    /// Heat source \[W/m³\].
    pub heat_source: &'static str,
    /// Volumes \[m³ per m of thickness\].
    pub volume: &'static str,
    /// Masses \[kg per m of thickness\].
    pub mass: &'static str,
}

/// The material points of a kind with one set.
pub const POINTS: PointNames = PointNames {
    position: "point_position",
    velocity: "point_velocity",
    stress: "point_stress",
    temperature: "point_temperature",
    heat_source: "point_heat_source",
    volume: "point_volume",
    mass: "point_mass",
};

/// The pure-MPM twin's points (the square).
pub const TWIN_POINTS: PointNames = PointNames {
    position: "twin_point_position",
    velocity: "twin_point_velocity",
    stress: "twin_point_stress",
    temperature: "twin_point_temperature",
    heat_source: "twin_point_heat_source",
    volume: "twin_point_volume",
    mass: "twin_point_mass",
};

/// The arrays of material points `p`.
pub fn point_arrays<'a>(p: &'a MaterialPoints, names: &PointNames) -> Vec<StateArray<'a>> {
    vec![
        StateArray::rows(names.position, "m", &p.position),
        StateArray::rows(names.velocity, "m/s", &p.velocity).writable(),
        StateArray::rows(names.stress, "Pa", &p.stress),
        StateArray::scalar(names.temperature, "K", &p.temperature).writable(),
        StateArray::scalar(names.heat_source, "W/m^3", &p.heat_source),
        StateArray::scalar(names.volume, "m^3", &p.volume),
        StateArray::scalar(names.mass, "kg", &p.mass),
    ]
}

/// Writes `values` into the writable point array `name`, if it is one of `names`';
/// `Ok(false)` when the name is not a point array of `names`.
pub fn set_point_array(
    p: &mut MaterialPoints,
    names: &PointNames,
    name: &str,
    values: &[f64],
) -> Result<bool, RunError> {
    if name == names.temperature {
        check_input(name, values, p.len(), (0.0, MAX_TEMPERATURE), true, "K")?;
        p.temperature.copy_from_slice(values);
        Ok(true)
    } else if name == names.velocity {
        check_input(
            name,
            values,
            2 * p.len(),
            (-MAX_SPEED, MAX_SPEED),
            false,
            "m/s",
        )?;
        p.velocity.as_flattened_mut().copy_from_slice(values);
        Ok(true)
    } else {
        Ok(false)
    }
}

/// The writable point arrays of `names`.
pub fn writable_points(names: &PointNames) -> [&'static str; 2] {
    [names.velocity, names.temperature]
}

fn flatten(v: &[Vec3]) -> Cow<'static, [f64]> {
    Cow::Owned(v.iter().flat_map(|a| [a.x, a.y, a.z]).collect())
}

/// The arrays of spheres `s`: centres, velocities and external forces are copied (the DEM
/// keeps them as `Vec3`); radii and temperatures are borrowed.
pub fn sphere_arrays(s: &ParticleState) -> Vec<StateArray<'_>> {
    vec![
        StateArray {
            name: "sphere_position",
            unit: "m",
            columns: 3,
            values: flatten(&s.position),
            writable: false,
        },
        StateArray {
            name: "sphere_velocity",
            unit: "m/s",
            columns: 3,
            values: flatten(&s.velocity),
            writable: false,
        },
        StateArray::scalar("sphere_radius", "m", &s.radius),
        StateArray::scalar("sphere_temperature", "K", &s.temperature),
        StateArray {
            name: "sphere_external_force",
            unit: "N",
            columns: 3,
            values: flatten(&s.external_force),
            writable: true,
        },
    ]
}

/// Writes the spheres' external forces (a load); `Ok(false)` for another name.
pub fn set_sphere_force(
    s: &mut ParticleState,
    name: &str,
    values: &[f64],
) -> Result<bool, RunError> {
    if name != "sphere_external_force" {
        return Ok(false);
    }
    check_input(
        name,
        values,
        3 * s.len(),
        (-MAX_FORCE, MAX_FORCE),
        false,
        "N",
    )?;
    for (f, v) in s.external_force.iter_mut().zip(values.chunks_exact(3)) {
        *f = Vec3::new(v[0], v[1], v[2]);
    }
    Ok(true)
}

/// Per-point figures of the RVEs of an MPM×DEM kind, computed when read (read-only):
/// disks, DEM steps of the last MPM step (their product summed over points is the step's
/// disk-steps), void ratio (void over solid area), coordination number, intact bonds and the
/// friction work of the last MPM step \[J\].
pub fn rve_arrays(material: &[thm_coupling::multiscale::RvePoint]) -> Vec<StateArray<'static>> {
    let owned =
        |name: &'static str,
         unit: &'static str,
         f: &dyn Fn(&thm_coupling::multiscale::RvePoint) -> f64| StateArray {
            name,
            unit,
            columns: 1,
            values: Cow::Owned(material.iter().map(f).collect()),
            writable: false,
        };
    vec![
        owned("point_rve_disks", "1", &|p| p.rve.len() as f64),
        owned("point_dem_substeps", "1", &|p| f64::from(p.substeps)),
        owned("point_void_ratio", "1", &|p| p.rve.void_ratio()),
        owned("point_coordination", "1", &|p| p.rve.coordination_number()),
        owned("point_intact_bonds", "1", &|p| {
            p.rve.contacts.intact_bond_count() as f64
        }),
        owned("point_friction_work", "J", &|p| p.friction_work),
    ]
}

/// The arrays of an MPM×DEM kind with one set of points: the points' and their RVEs'.
pub fn mpm_rve_arrays<'a>(
    points: &'a MaterialPoints,
    material: &[thm_coupling::multiscale::RvePoint],
) -> Vec<StateArray<'a>> {
    let mut arrays = point_arrays(points, &POINTS);
    arrays.extend(rve_arrays(material));
    arrays
}

/// Writes a writable point array of a kind with one set of points, or names the writable
/// ones.
pub fn set_points_array(
    points: &mut MaterialPoints,
    name: &str,
    values: &[f64],
) -> Result<(), RunError> {
    if set_point_array(points, &POINTS, name, values)? {
        Ok(())
    } else {
        Err(not_writable(name, &writable_points(&POINTS)))
    }
}

/// A named array of a run's state, for front ends (the Python module): `rows × columns`
/// values, row-major, in the unit named.
#[derive(Debug, Clone, PartialEq)]
pub struct StateArray<'a> {
    /// Name, e.g. `sphere_temperature` (file-name safe, unique within a kind).
    pub name: &'static str,
    /// Unit of the values, e.g. `K`.
    pub unit: &'static str,
    /// Values per row (1 for scalars, 2 or 3 for vectors, 3 for `[xx, yy, xy]` tensors).
    pub columns: usize,
    /// The values, borrowed from the state where its layout is already a flat `f64` array.
    pub values: std::borrow::Cow<'a, [f64]>,
    /// Whether [`crate::scenario::Scenario::set_array`] accepts new values for it between steps.
    pub writable: bool,
}

impl<'a> StateArray<'a> {
    /// A read-only scalar per row, borrowed.
    pub fn scalar(name: &'static str, unit: &'static str, values: &'a [f64]) -> Self {
        Self {
            name,
            unit,
            columns: 1,
            values: std::borrow::Cow::Borrowed(values),
            writable: false,
        }
    }

    /// A read-only row of `N` values per item, borrowed.
    pub fn rows<const N: usize>(
        name: &'static str,
        unit: &'static str,
        values: &'a [[f64; N]],
    ) -> Self {
        Self {
            name,
            unit,
            columns: N,
            values: std::borrow::Cow::Borrowed(values.as_flattened()),
            writable: false,
        }
    }

    /// The same array, marked writable.
    pub fn writable(mut self) -> Self {
        self.writable = true;
        self
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.values.len() / self.columns.max(1)
    }

    /// Whether the array has no rows.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// Checks new values for a writable array: the length of the current array, and every value
/// finite and in `[lo, hi]`, or in `(0, hi]` when `lo` is 0 and `above_zero` (temperatures).
/// Errors name the array, the value's index and the allowed range.
pub fn check_input(
    name: &str,
    values: &[f64],
    expected_len: usize,
    (lo, hi): (f64, f64),
    above_zero: bool,
    unit: &str,
) -> Result<(), RunError> {
    let bad = |detail: String| RunError::Input {
        array: name.to_string(),
        detail,
    };
    if values.len() != expected_len {
        return Err(bad(format!(
            "needs {expected_len} values, got {}",
            values.len()
        )));
    }
    let ok = |v: f64| v.is_finite() && v >= lo && v <= hi && !(above_zero && v <= 0.0);
    if let Some(i) = values.iter().position(|v| !ok(*v)) {
        let open = if above_zero { "(" } else { "[" };
        return Err(bad(format!(
            "value {i} must be finite and in {open}{lo}, {hi}] {unit}, got {}",
            values[i]
        )));
    }
    Ok(())
}

/// The error for an array name a kind does not accept.
pub fn not_writable(name: &str, writable: &[&str]) -> RunError {
    RunError::Input {
        array: name.to_string(),
        detail: if writable.is_empty() {
            "this kind has no writable arrays".into()
        } else {
            format!(
                "not a writable array of this kind; writable: {}",
                writable
                    .iter()
                    .map(|w| format!("`{w}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        },
    }
}
