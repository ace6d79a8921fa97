//! Finite walls (`RigidWall::extent`, `RigidWall::depth`, `RigidWall::segment`): a wall acts
//! only along its extent and within its band, and refuses an inverted extent or a
//! non-positive depth by name.

use thm_mpm::{
    GridParameters, LinearThermoElastic, MaterialPoints, Mpm, MpmConfig, MpmError, MpmParameters,
    MpmState, PointProperties, RigidWall, ThermoElasticParameters,
};

const G: f64 = 10.0;

fn material() -> LinearThermoElastic {
    LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e6,
        poisson_ratio: 0.2,
        thermal_expansion: 0.0,
        conductivity: [0.0; 3],
    })
    .unwrap()
}

/// Two separate blocks released at rest 0.05 m above `y = 0`: the left one over a
/// horizontal segment `x ∈ [0, 1]`, the right one beyond its end (`x ∈ [1.5, 1.9]`, more
/// than two cells away, so no node is shared).
fn two_blocks(wall: RigidWall) -> (Mpm, MpmState<()>, LinearThermoElastic, usize) {
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [-0.5, -1.0],
        cell_size: 0.05,
        cells: [60, 40],
    });
    params.gravity = [0.0, -G];
    params.walls = vec![wall];
    let config = MpmConfig::new(params).unwrap();
    let mat = material();
    let props = PointProperties {
        density: 1000.0,
        specific_heat: 1.0,
        conductivity: [0.0; 3],
        temperature: 0.0,
        velocity: [0.0; 2],
    };
    let mut pts = MaterialPoints::new();
    pts.fill_rectangle(config.grid(), [0.2, 0.05], [0.6, 0.25], 2, &props)
        .unwrap();
    let left = pts.len();
    pts.fill_rectangle(config.grid(), [1.5, 0.05], [1.9, 0.25], 2, &props)
        .unwrap();
    let st = MpmState::new(pts, &mat);
    (Mpm::new(config), st, mat, left)
}

fn mean_velocity_y(st: &MpmState<()>, range: std::ops::Range<usize>) -> f64 {
    let p = &st.points;
    let m: f64 = range.clone().map(|i| p.mass[i]).sum();
    range.map(|i| p.mass[i] * p.velocity[i][1]).sum::<f64>() / m
}

/// The block over the segment comes to rest on it; the block past its end falls freely:
/// `v = −g t` to round-off (a uniform block carries no stress).
#[test]
fn a_segment_holds_what_is_over_it_and_not_what_is_past_its_end() {
    let wall = RigidWall::segment([0.0, 0.0], [1.0, 0.0], 0.5, 0.1);
    assert_eq!(wall.normal, [-0.0, 1.0]);
    let (mut mpm, mut st, mat, left) = two_blocks(wall);
    let n = st.points.len();
    let dt = 2e-4;
    let steps = 500;
    for _ in 0..steps {
        mpm.step(&mut st, &mat, dt).unwrap();
    }
    let t = steps as f64 * dt;
    let free = mean_velocity_y(&st, left..n);
    assert!(
        (free + G * t).abs() < 1e-9 * G * t,
        "past the end: v = {free}, free fall {}",
        -G * t
    );
    // Held: it has fallen at most the 0.05 m gap and a cell into the wall's band, and it
    // has stopped (the free block moves at 1 m/s by now).
    let held = mean_velocity_y(&st, 0..left);
    assert!(held.abs() < 0.05, "over the segment: v = {held}");
    let lowest = (0..left)
        .map(|i| st.points.position[i][1])
        .fold(f64::INFINITY, f64::min);
    assert!(
        lowest > -0.05,
        "lowest point over the segment at y = {lowest}"
    );
    // The wall pushed only on the held block: its impulse is what gravity gave that block
    // beyond its momentum (checked as a force balance on the last step's reaction sign).
    assert!(mpm.wall_reactions()[0][1] < 0.0);
}

/// A wall acts only within its band: a block deeper behind the line than `depth` is not
/// touched (exact free fall), while the same wall without a band stops it.
#[test]
fn a_wall_band_leaves_deeper_material_free() {
    // The line y = 0.4 facing up; the blocks start at y ≤ 0.25, i.e. 0.15 m behind it.
    let banded = RigidWall {
        depth: Some(0.1),
        ..RigidWall::half_plane([0.0, 0.4], [0.0, 1.0], 0.0)
    };
    let (mut mpm, mut st, mat, _) = two_blocks(banded);
    let dt = 2e-4;
    for _ in 0..100 {
        mpm.step(&mut st, &mat, dt).unwrap();
    }
    let v = mean_velocity_y(&st, 0..st.points.len());
    assert!((v + G * 0.02).abs() < 1e-9, "banded: v = {v}");

    let (mut mpm, mut st, mat, _) = two_blocks(RigidWall::half_plane([0.0, 0.4], [0.0, 1.0], 0.0));
    for _ in 0..100 {
        mpm.step(&mut st, &mat, dt).unwrap();
    }
    let v = mean_velocity_y(&st, 0..st.points.len());
    assert!(v.abs() < 1e-12, "whole half-plane: v = {v}");
}

/// The segment's coordinate runs from 0 at `a` to its length at `b`, and the wall acts on
/// a node exactly when it is behind the line, within the band and between the ends.
#[test]
fn segment_geometry() {
    let w = RigidWall::segment([1.0, 1.0], [2.0, 2.0], 0.0, 0.1);
    let l = 2f64.sqrt();
    assert_eq!(w.extent, Some([0.0, l]));
    assert!((w.along([2.0, 2.0], 0.0) - l).abs() < 1e-15);
    assert!(w.along([1.0, 1.0], 0.0).abs() < 1e-15);
    // The material is on the left of a → b: above the diagonal.
    assert!(w.distance([1.0, 2.0], 0.0) > 0.0);
    let behind = [1.52, 1.48];
    assert!(w.acts_on(behind, 0.0));
    assert!(!w.acts_on([1.2, 0.8], 0.0), "beyond the band");
    assert!(!w.acts_on([2.05, 2.0], 0.0), "past the end b");
    assert!(!w.acts_on([0.95, 0.9], 0.0), "before the start a");
}

#[test]
fn inverted_extent_and_bad_depth_are_refused_by_name() {
    let base = || {
        MpmParameters::on_grid(GridParameters {
            origin: [0.0, 0.0],
            cell_size: 0.1,
            cells: [4, 4],
        })
    };
    let mut p = base();
    p.walls = vec![
        RigidWall::half_plane([0.0, 0.0], [0.0, 1.0], 0.0),
        RigidWall {
            extent: Some([1.0, 0.5]),
            ..RigidWall::half_plane([0.0, 0.0], [0.0, 1.0], 0.0)
        },
    ];
    match MpmConfig::new(p) {
        Err(MpmError::InvalidParameter { name, .. }) => assert_eq!(name, "walls[1].extent"),
        other => panic!("{other:?}"),
    }
    let mut p = base();
    p.walls = vec![RigidWall::segment([0.0, 0.0], [1.0, 0.0], 0.0, 0.0)];
    match MpmConfig::new(p) {
        Err(MpmError::InvalidParameter { name, .. }) => assert_eq!(name, "walls[0].depth"),
        other => panic!("{other:?}"),
    }
}
