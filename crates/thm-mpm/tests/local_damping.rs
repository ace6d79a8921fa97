//! Local non-viscous damping of the nodal forces (`MpmParameters::local_damping`).

use thm_mpm::*;

/// A 0.6 m × 0.5 m elastic block, every point pre-stressed to `stress` and moving at
/// `velocity`, on a grid with room around it.
fn block(
    damping: f64,
    stress: f64,
    velocity: [f64; 2],
) -> (Mpm, MpmState<()>, LinearThermoElastic) {
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.1,
        cells: [12, 12],
    });
    params.local_damping = damping;
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
            [0.3, 0.3],
            [0.9, 0.8],
            2,
            &PointProperties {
                density: 1000.0,
                specific_heat: 800.0,
                conductivity: [1.0, 1.0, 0.0],
                temperature: 0.0,
                velocity,
            },
        )
        .unwrap();
    points.stress.fill([stress, stress, 0.0]);
    let n = points.len();
    let state = MpmState {
        points,
        material: vec![(); n],
        time: 0.0,
        step: 0,
    };
    (Mpm::new(config), state, material)
}

fn kinetic_energy(st: &MpmState<()>) -> f64 {
    let p = &st.points;
    p.mass
        .iter()
        .zip(&p.velocity)
        .map(|(m, v)| 0.5 * m * (v[0] * v[0] + v[1] * v[1]))
        .sum()
}

/// Damping acts on unbalanced forces only: a stress-free block in uniform translation has
/// none, so with `α_l = 0.5` it moves exactly as without damping (same bits).
#[test]
fn a_uniform_translation_is_not_resisted() {
    let run = |a: f64| {
        let (mut mpm, mut st, mat) = block(a, 0.0, [0.3, -0.2]);
        for _ in 0..20 {
            mpm.step(&mut st, &mat, 1e-3).unwrap();
        }
        st.points.position
    };
    let (free, damped) = (run(0.0), run(0.5));
    assert_eq!(free, damped);
}

/// A block released from a uniform compression of 1 kPa rings (it expands, overshoots and
/// comes back; lowest mode along its 0.6 m width: `T = 2W/c_p ≈ 0.33 s` with the plane-strain
/// `c_p = 3.67 m/s`). Local damping takes energy out while it rings: a one-degree-of-freedom
/// oscillator keeps `((1 − α_l)/(1 + α_l))²` of its energy per half period (0.29 for
/// `α_l = 0.3`), so over steps 500–1000 (1.5 to 3 periods) the damped block's mean kinetic
/// energy must be below 5 % of the undamped one's, and it decreases with `α_l`.
#[test]
fn a_ringing_block_loses_its_kinetic_energy() {
    let late_energy = |a: f64| {
        let (mut mpm, mut st, mat) = block(a, -1e3, [0.0, 0.0]);
        let mut sum = 0.0;
        for k in 0..1000 {
            mpm.step(&mut st, &mat, 1e-3).unwrap();
            if k >= 500 {
                sum += kinetic_energy(&st);
            }
        }
        sum / 500.0
    };
    let e: Vec<f64> = [0.0, 0.1, 0.3].iter().map(|&a| late_energy(a)).collect();
    assert!(e[0] > 0.0, "undamped block at rest: {e:?}");
    assert!(
        e[1] < e[0] && e[2] < e[1],
        "not decreasing with the damping: {e:?}"
    );
    assert!(e[2] < 0.05 * e[0], "{e:?}");
    println!("mean kinetic energy, steps 500-1000, alpha 0 / 0.1 / 0.3: {e:?}");
}

/// `α_l` outside [0, 1) is refused by name.
#[test]
fn damping_out_of_range_is_refused() {
    for a in [-0.1, 1.0, f64::NAN] {
        let mut params = MpmParameters::on_grid(GridParameters {
            origin: [0.0, 0.0],
            cell_size: 0.1,
            cells: [4, 4],
        });
        params.local_damping = a;
        let e = MpmConfig::new(params).unwrap_err().to_string();
        assert!(e.contains("local_damping") && e.contains("[0, 1)"), "{e}");
    }
}
