//! Bad input gets a typed error naming the field and the allowed range, never a panic.

use thm_dem::Vec3;
use thm_rve::*;

#[test]
fn degenerate_or_inverted_cell_is_refused() {
    for h in [
        Mat2::new(1.0, 2.0, 0.5, 1.0),
        Mat2::new(1.0, 0.0, 0.0, -1.0),
    ] {
        match PeriodicCell::new(h) {
            Err(RveError::DegenerateCell { determinant, .. }) => assert_eq!(determinant, h.det()),
            other => panic!("expected DegenerateCell, got {other:?}"),
        }
    }
    assert!(matches!(
        PeriodicCell::new(Mat2::new(f64::NAN, 0.0, 0.0, 1.0)),
        Err(RveError::DegenerateCell { .. })
    ));
    // A velocity gradient that inverts the cell within one step.
    let mut cell = PeriodicCell::rectangle(1.0, 1.0).unwrap();
    let err = cell.deform(&Mat2::diagonal(-2.0, 0.0), 1.0).unwrap_err();
    assert!(matches!(err, RveError::DegenerateCell { determinant, .. } if determinant <= 0.0));
    assert_eq!(
        cell.matrix(),
        &Mat2::IDENTITY,
        "a refused step leaves the cell unchanged"
    );
}

#[test]
fn radii_out_of_order_are_refused() {
    let config = RveParams::paper_b_table_1().validate().unwrap();
    for (lo, hi) in [
        (0.5e-3, 0.25e-3),
        (-1e-3, 1e-3),
        (0.0, 1e-3),
        (1e-3, f64::NAN),
    ] {
        let mut p = PackingParams::paper_b(1);
        p.min_radius = lo;
        p.max_radius = hi;
        match random_packing(&p, &config) {
            Err(RveError::RadiiOutOfOrder {
                min_radius,
                max_radius,
            }) => {
                assert_eq!(min_radius.to_bits(), lo.to_bits());
                assert_eq!(max_radius.to_bits(), hi.to_bits());
            }
            other => panic!("expected RadiiOutOfOrder, got {other:?}"),
        }
    }
}

#[test]
fn unreachable_target_stress_is_refused_before_stepping() {
    let config = RveParams::paper_b_table_1().validate().unwrap();
    let mut p = PackingParams::paper_b(1);
    p.disk_count = 20;
    let mut state = random_packing(&p, &config).unwrap();
    let max = packing::max_reachable_stress(&state, &config);
    let target = 2.0 * max;
    match consolidate(
        &mut state,
        &config,
        &ConsolidationParams::isotropic(target, 0.01),
    ) {
        Err(RveError::UnreachableTargetStress {
            target: t,
            max_reachable,
        }) => {
            assert_eq!(t, target);
            assert_eq!(max_reachable, max);
        }
        other => panic!("expected UnreachableTargetStress, got {other:?}"),
    }
    assert_eq!(state.step, 0);
    for bad in [0.0, -1e5, f64::NAN] {
        assert!(matches!(
            consolidate(
                &mut state,
                &config,
                &ConsolidationParams::isotropic(bad, 0.01)
            ),
            Err(RveError::InvalidParameter {
                field: "target_stress",
                ..
            })
        ));
    }
    // A budget too small to get there is a typed error too.
    let mut c = ConsolidationParams::isotropic(1e5, 0.01);
    c.max_steps = 10;
    assert!(matches!(
        consolidate(&mut state, &config, &c),
        Err(RveError::ConsolidationNotConverged { steps: 10, .. })
    ));
}

#[test]
fn bad_parameters_and_loads_name_their_field() {
    let mut p = RveParams::paper_b_table_1();
    p.density = -1.0;
    assert!(matches!(
        p.validate(),
        Err(RveError::InvalidParameter {
            field: "density",
            ..
        })
    ));
    let mut p = RveParams::paper_b_table_1();
    p.local_damping = 1.0;
    assert!(matches!(
        p.validate(),
        Err(RveError::InvalidParameter {
            field: "local_damping",
            ..
        })
    ));
    let mut p = RveParams::paper_b_table_1();
    p.contact.normal_stiffness = 0.0;
    assert!(matches!(p.validate(), Err(RveError::Dem(_))));

    let p = RveParams::paper_b_table_1();
    let config = p.validate().unwrap();
    let cell = PeriodicCell::rectangle(10e-3, 10e-3).unwrap();
    let mut state = RveState::new(
        cell,
        &[Vec3::new(1e-3, 1e-3, 0.0), Vec3::new(5e-3, 5e-3, 0.0)],
        &[0.5e-3, 0.5e-3],
        p.density,
        p.thickness,
        300.0,
    )
    .unwrap();
    let mut stepper = RveStepper::new(config);
    let good = RveLoad {
        velocity_gradient: Mat2::ZERO,
        temperature: 300.0,
        dt: 1e-6,
        substeps: 1,
    };
    let cases: [(RveLoad, &str); 4] = [
        (
            RveLoad {
                velocity_gradient: Mat2::new(f64::NAN, 0.0, 0.0, 0.0),
                ..good
            },
            "velocity_gradient",
        ),
        (
            RveLoad {
                temperature: -3.0,
                ..good
            },
            "temperature",
        ),
        (RveLoad { dt: 0.0, ..good }, "dt"),
        (
            RveLoad {
                substeps: 0,
                ..good
            },
            "substeps",
        ),
    ];
    for (load, name) in cases {
        match stepper.respond(&mut state, &load) {
            Err(RveError::InvalidParameter { field, .. }) => assert_eq!(field, name),
            other => panic!("expected InvalidParameter {name}, got {other:?}"),
        }
    }
    assert!(stepper.respond(&mut state, &good).is_ok());
    // Batch inputs of the wrong length.
    let mut batch = RveBatch::new(config, 2);
    assert!(matches!(
        batch.respond(std::slice::from_mut(&mut state), &[good, good]),
        Err(RveError::LengthMismatch {
            field: "states",
            len: 1,
            expected: 2
        })
    ));
}

#[test]
fn cell_narrower_than_twice_the_reach_is_refused() {
    let p = RveParams::paper_b_table_1();
    let config = p.validate().unwrap();
    // Reach 2 R_max + skin = 1.1 mm: a 2 mm wide cell is below 2.2 mm.
    let cell = PeriodicCell::rectangle(2e-3, 10e-3).unwrap();
    let mut state = RveState::new(
        cell,
        &[Vec3::new(0.5e-3, 1e-3, 0.0), Vec3::new(1.5e-3, 5e-3, 0.0)],
        &[0.5e-3, 0.5e-3],
        p.density,
        p.thickness,
        300.0,
    )
    .unwrap();
    match RveStepper::new(config).step(&mut state, &Mat2::ZERO, 1e-6) {
        Err(RveError::CellTooSmall {
            axis: 0,
            width,
            minimum,
        }) => {
            assert!((width - 2e-3).abs() < 1e-15);
            assert!(minimum > width);
        }
        other => panic!("expected CellTooSmall, got {other:?}"),
    }
}

#[test]
fn instability_stops_with_quantity_place_and_step() {
    let p = RveParams::paper_b_table_1();
    let config = p.validate().unwrap();
    let cell = PeriodicCell::rectangle(10e-3, 10e-3).unwrap();
    let mut state = RveState::new(
        cell,
        &[Vec3::new(1e-3, 1e-3, 0.0), Vec3::new(5e-3, 5e-3, 0.0)],
        &[0.5e-3, 0.5e-3],
        p.density,
        p.thickness,
        300.0,
    )
    .unwrap();
    state.disks.velocity[1] = Vec3::new(f64::INFINITY, 0.0, 0.0);
    match RveStepper::new(config).step(&mut state, &Mat2::ZERO, 1e-6) {
        Err(RveError::NonFinite {
            index: 1, step: 0, ..
        }) => {}
        other => panic!("expected NonFinite at disk 1, got {other:?}"),
    }
}
