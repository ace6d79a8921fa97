//! The batched constitutive seam: a per-point model stepped through `Mpm::step_batch` (as
//! `PerPoint`) gives the same bits as `Mpm::step`, on 1 and 2 threads; a batch material that
//! fails names its point.

use thm_mpm::*;

/// A heated, sheared block of Drucker–Prager material (history per point) on more points
/// than one chunk of the point stages (1760 points), with walls, gravity, a traction and a
/// prescribed temperature.
fn block() -> (Mpm, MpmState<DruckerPragerState>, DruckerPrager) {
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.05,
        cells: [40, 12],
    });
    params.gravity = [0.0, -9.81];
    params.pic_fraction = 0.05;
    params.walls = vec![RigidWall {
        point: [0.0, 0.05],
        normal: [0.0, 1.0],
        velocity: [0.0; 2],
        friction: 0.4,
        removal_time: None,
        extent: None,
        depth: None,
    }];
    params.velocity_conditions = vec![VelocityCondition {
        nodes: NodeSet::Side(Side::Left),
        fix_x: true,
        fix_y: false,
    }];
    params.temperature_conditions = vec![TemperatureCondition {
        nodes: NodeSet::Side(Side::Left),
        temperature: 50.0,
    }];
    params.surface_loads = vec![SurfaceLoad {
        lower: [0.05, 0.5],
        upper: [0.6, 0.55],
        layer_thickness: 0.05,
        traction: [2000.0, -5000.0],
        inward_heat_flux: 20.0,
    }];
    let config = MpmConfig::new(params).unwrap();
    let mat = DruckerPrager::new(&DruckerPragerParameters {
        youngs_modulus: 1e6,
        poisson_ratio: 0.3,
        friction_angle_deg: 30.0,
        dilatancy_angle_deg: 5.0,
        cohesion: 100.0,
        thermal_expansion: 1e-4,
        conductivity: [1.0, 0.5, 0.1],
    })
    .unwrap();
    let mut pts = MaterialPoints::new();
    pts.fill_rectangle(
        config.grid(),
        [0.05, 0.05],
        [0.6, 0.55],
        4,
        &PointProperties {
            density: 1500.0,
            specific_heat: 800.0,
            conductivity: [1.0, 1.0, 0.0],
            temperature: 10.0,
            velocity: [0.0; 2],
        },
    )
    .unwrap();
    assert!(pts.len() > 1024, "{} points", pts.len());
    let st = MpmState::new(pts, &mat);
    (Mpm::new(config), st, mat)
}

fn bits(st: &MpmState<DruckerPragerState>) -> Vec<u64> {
    let p = &st.points;
    let mut b = Vec::new();
    for i in 0..p.len() {
        b.extend(p.position[i].iter().map(|v| v.to_bits()));
        b.extend(p.velocity[i].iter().map(|v| v.to_bits()));
        b.extend(p.stress[i].iter().map(|v| v.to_bits()));
        b.extend(p.deformation_gradient[i].iter().map(|v| v.to_bits()));
        b.push(p.temperature[i].to_bits());
        b.push(p.remapped_temperature[i].to_bits());
        b.push(p.volume[i].to_bits());
        b.push(st.material[i].plastic_strain.to_bits());
    }
    b
}

/// `step_batch` with `PerPoint` and `step` agree bit for bit over 60 plastic steps, and the
/// batched path gives the same bits on 1 and 2 threads.
#[test]
fn batched_seam_matches_the_per_point_step() {
    let run = |threads: usize, batched: bool| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let (mut mpm, mut st, mat) = block();
            let mut wrapped = PerPoint(mat);
            for _ in 0..60 {
                if batched {
                    mpm.step_batch(&mut st, &mut wrapped, 1e-4).unwrap();
                } else {
                    mpm.step(&mut st, &mat, 1e-4).unwrap();
                }
            }
            assert!(st.material.iter().any(|s| s.plastic_strain > 0.0));
            bits(&st)
        })
    };
    let reference = run(1, false);
    assert_eq!(run(1, true), reference);
    assert_eq!(run(2, true), reference);
}

/// The batched path checks the time step like `step` does (B-Eq. 30 names the point).
#[test]
fn batched_step_checks_the_time_step() {
    let (mut mpm, mut st, mat) = block();
    let mut wrapped = PerPoint(mat);
    let lim = mpm.time_step_limits(&st, &mat);
    let err = mpm
        .step_batch(&mut st, &mut wrapped, 1.01 * lim.mechanical)
        .unwrap_err();
    assert!(
        matches!(err, MpmError::TimeStepTooLarge { point, .. } if point == lim.mechanical_point),
        "{err}"
    );
}

/// A batch material whose answer is not finite stops the step naming the point.
#[test]
fn non_finite_batch_response_names_the_point() {
    struct Broken;
    impl BatchConstitutive for Broken {
        type PointState = ();
        type Error = MpmError;
        fn respond_batch(
            &mut self,
            _: &mut [()],
            inputs: &[MaterialInput],
            out: &mut [MaterialResponse],
        ) -> Result<(), MpmError> {
            for (i, r) in inputs.iter().zip(out.iter_mut()) {
                let bad = if i.point == 17 { f64::NAN } else { 0.0 };
                *r = MaterialResponse {
                    stress: [bad, 0.0, 0.0],
                    heat_source: 0.0,
                    conductivity: [1.0, 1.0, 0.0],
                };
            }
            Ok(())
        }
        fn wave_modulus(&self, _: &()) -> f64 {
            1e6
        }
    }
    let (mut mpm, st, _) = block();
    let mut st = MpmState {
        points: st.points,
        material: vec![(); st.material.len()],
        time: 0.0,
        step: 0,
    };
    let err = mpm.step_batch(&mut st, &mut Broken, 1e-4).unwrap_err();
    assert!(
        matches!(err, MpmError::NonFinite { index: 17, .. }),
        "{err}"
    );
}
