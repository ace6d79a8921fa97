//! Surface loads replaced between steps, and the node mass tolerance.

use thm_mpm::*;

fn block(tolerance: f64, left: f64) -> (Mpm, MpmState<()>, LinearThermoElastic) {
    block_merging(tolerance, left, false)
}

fn block_merging(
    tolerance: f64,
    left: f64,
    merge: bool,
) -> (Mpm, MpmState<()>, LinearThermoElastic) {
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.1,
        cells: [12, 12],
    });
    params.node_mass_tolerance = tolerance;
    params.merge_small_mass_nodes = merge;
    let config = MpmConfig::new(params).unwrap();
    let material = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e4,
        poisson_ratio: 0.3,
        thermal_expansion: 0.0,
        conductivity: [1.0, 1.0, 0.0],
    })
    .unwrap();
    let mut points = MaterialPoints::new();
    points
        .fill_rectangle(
            config.grid(),
            [left, 0.3],
            [left + 0.6, 0.8],
            2,
            &PointProperties {
                density: 1000.0,
                specific_heat: 800.0,
                conductivity: [1.0, 1.0, 0.0],
                temperature: 0.0,
                velocity: [0.0; 2],
            },
        )
        .unwrap();
    // A compressed block: every point at σ = −1 kPa, so the sides push outwards.
    points.stress.fill([-1e3, -1e3, 0.0]);
    let n = points.len();
    let state = MpmState {
        points,
        material: vec![(); n],
        time: 0.0,
        step: 0,
    };
    (Mpm::new(config), state, material)
}

fn bits(st: &MpmState<()>) -> Vec<u64> {
    let p = &st.points;
    p.position
        .iter()
        .chain(&p.velocity)
        .flat_map(|v| [v[0].to_bits(), v[1].to_bits()])
        .chain(p.stress.iter().flat_map(|s| s.map(f64::to_bits)))
        .collect()
}

/// Loads set with `set_surface_loads` act from the next step on exactly as loads given at
/// construction; a bad one is refused naming its key path.
#[test]
fn surface_loads_set_between_steps_act_as_configured_ones() {
    let load = SurfaceLoad {
        lower: [0.3, 0.3],
        upper: [0.35, 0.8],
        layer_thickness: 0.05,
        traction: [500.0, 0.0],
        inward_heat_flux: 0.0,
    };
    let (mut a, mut sa, mat) = block(0.0, 0.3);
    let mut params = a.config().parameters().clone();
    params.surface_loads = vec![load];
    let mut b = Mpm::new(MpmConfig::new(params).unwrap());
    let mut sb = sa.clone();
    a.set_surface_loads(vec![load]).unwrap();
    for _ in 0..5 {
        a.step(&mut sa, &mat, 1e-3).unwrap();
        b.step(&mut sb, &mat, 1e-3).unwrap();
    }
    assert_eq!(bits(&sa), bits(&sb));
    let mut bad = load;
    bad.layer_thickness = 0.0;
    let e = a
        .set_surface_loads(vec![load, bad])
        .unwrap_err()
        .to_string();
    assert!(e.contains("surface_loads[1].layer_thickness"), "{e}");
}

/// A block whose left side lies 1 mm beyond a node line gives the node behind it a sliver of
/// mass (about 10⁻⁴ of a point's): without a tolerance its velocity after one step is orders
/// of magnitude above the block's; with a tolerance above the sliver it is left at rest, and
/// the rest of the grid is unchanged. A negative tolerance is refused by name.
#[test]
fn node_mass_tolerance_leaves_grazed_nodes_at_rest() {
    let speed = |tol: f64| {
        let (mut mpm, mut st, mat) = block(tol, 0.299);
        mpm.step(&mut st, &mat, 1e-4).unwrap();
        let grid = mpm.grid();
        let nx = grid.nodes()[0];
        let f = mpm.grid_fields();
        // Node (2, 5): x = 0.2, behind the left side at 0.299.
        let behind = f.velocity[5 * nx + 2];
        let inside = f.velocity[5 * nx + 4];
        (
            behind[0].hypot(behind[1]),
            inside[0].hypot(inside[1]),
            f.sums[5 * nx + 2].mass,
        )
    };
    let (free, inside_free, sliver) = speed(0.0);
    let point_mass = 1000.0 * 0.05 * 0.05;
    assert!(
        sliver > 0.0 && sliver < 1e-3 * point_mass,
        "sliver {sliver}"
    );
    assert!(free > 100.0 * inside_free, "{free} vs {inside_free}");
    let (held, inside_held, _) = speed(1e-2 * point_mass);
    assert_eq!(held, 0.0);
    assert!((inside_held - inside_free).abs() <= 1e-12 * inside_free);
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.1,
        cells: [4, 4],
    });
    params.node_mass_tolerance = -1.0;
    let e = MpmConfig::new(params).unwrap_err().to_string();
    assert!(e.contains("node_mass_tolerance"), "{e}");
}

/// Merging instead of leaving out: the sliver nodes behind the block's left side (about 10⁻⁴
/// of a point's mass) take the acceleration of the group they form with their inner
/// neighbour, so (i) the grid's momentum changes by exactly the total nodal force times Δt
/// (to round-off; left out, the slivers' share of the force is lost), and (ii) the sliver
/// moves at the speed of its neighbour's group, not orders of magnitude faster.
#[test]
fn merged_small_mass_nodes_keep_their_force_and_speed() {
    let dt = 1e-4;
    let balance = |merge: bool| {
        let point_mass = 1000.0 * 0.05 * 0.05;
        let (mut mpm, mut st, mat) = block_merging(1e-2 * point_mass, 0.299, merge);
        mpm.step(&mut st, &mat, dt).unwrap();
        let f = mpm.grid_fields();
        let (mut dp, mut impulse, mut scale) = (0.0, 0.0, 0.0);
        for ((s, v), v0) in f.sums.iter().zip(&f.velocity).zip(&f.velocity_old) {
            dp += s.mass * (v[0] - v0[0]);
            impulse += s.force[0] * dt;
            scale += (s.force[0] * dt).abs();
        }
        let nx = mpm.grid().nodes()[0];
        let behind = f.velocity[5 * nx + 2][0].abs();
        let inside = f.velocity[5 * nx + 3][0].abs();
        ((dp - impulse).abs() / scale, behind, inside)
    };
    let (merged, behind, inside) = balance(true);
    assert!(merged <= 1e-14, "momentum vs impulse {merged}");
    assert!(
        behind > 0.0 && behind <= 2.0 * inside,
        "{behind} vs {inside}"
    );
    let (left_out, held, _) = balance(false);
    assert!(
        left_out > 1e-6,
        "leaving the slivers out should lose their force: {left_out}"
    );
    assert_eq!(held, 0.0);
}
