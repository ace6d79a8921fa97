//! Conservation laws, invariants, determinism, save/restore and bad input of `thm-mpm`.

use proptest::prelude::*;
use thm_mpm::shape::Stencil;
use thm_mpm::*;

fn block_model(
    pic: f64,
    gravity: [f64; 2],
    seed_velocity: impl Fn(usize, [f64; 2]) -> [f64; 2],
) -> (Mpm, MpmState<()>, LinearThermoElastic) {
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.1,
        cells: [12, 12],
    });
    params.pic_fraction = pic;
    params.gravity = gravity;
    let config = MpmConfig::new(params).unwrap();
    let material = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e4,
        poisson_ratio: 0.3,
        thermal_expansion: 1e-3,
        conductivity: [2.0, 1.0, 0.5],
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
                temperature: 10.0,
                velocity: [0.0; 2],
            },
        )
        .unwrap();
    for p in 0..points.len() {
        points.velocity[p] = seed_velocity(p, points.position[p]);
        points.temperature[p] = 10.0 + 5.0 * points.position[p][0];
    }
    let state = MpmState::new(points, &material);
    (Mpm::new(config), state, material)
}

/// A deterministic pseudo-random velocity in [−a, a]² from the index (no global RNG).
fn hashed_velocity(p: usize, a: f64, salt: u64) -> [f64; 2] {
    let mut z = (p as u64)
        .wrapping_add(salt)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z ^= z >> 31;
    z = z.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z ^= z >> 27;
    let u = (z >> 11) as f64 / (1u64 << 53) as f64;
    let v = ((z.rotate_left(17)) >> 11) as f64 / (1u64 << 53) as f64;
    [a * (2.0 * u - 1.0), a * (2.0 * v - 1.0)]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Mass: the point masses never change (bitwise), and the lumped nodal masses (B-Eq. 19)
    /// add up to the total point mass to round-off (partition of unity of uGIMP).
    #[test]
    fn mass_is_conserved_exactly(pic in 0.0f64..1.0, salt in 0u64..1000, amp in 0.0f64..0.5) {
        let (mut mpm, mut st, mat) = block_model(pic, [0.0, -9.81], |p, _| hashed_velocity(p, amp, salt));
        let before: Vec<u64> = st.points.mass.iter().map(|m| m.to_bits()).collect();
        let total = st.points.total_mass();
        for _ in 0..10 {
            mpm.step(&mut st, &mat, 1e-3).unwrap();
            let nodal: f64 = mpm.grid_fields().sums.iter().map(|s| s.mass).sum();
            prop_assert!((nodal - total).abs() <= 1e-13 * total, "nodal {nodal} vs {total}");
        }
        let after: Vec<u64> = st.points.mass.iter().map(|m| m.to_bits()).collect();
        prop_assert_eq!(before, after);
    }

    /// Momentum: without external forces or boundary conditions and without grid/particle
    /// damping, Σ m_p v_p is conserved for any PIC fraction (the PIC term of B-Eq. 25
    /// redistributes momentum; the internal forces sum to zero since Σ_I ∇φ_Ip = 0).
    #[test]
    fn momentum_is_conserved_without_external_forces(
        pic in 0.0f64..1.0, salt in 0u64..1000, amp in 0.01f64..0.5
    ) {
        let (mut mpm, mut st, mat) = block_model(pic, [0.0, 0.0], |p, _| hashed_velocity(p, amp, salt));
        let p0 = st.points.total_momentum();
        let scale: f64 = st.points.mass.iter().zip(&st.points.velocity)
            .map(|(m, v)| m * (v[0].abs() + v[1].abs())).sum();
        for _ in 0..20 {
            mpm.step(&mut st, &mat, 1e-3).unwrap();
        }
        let p1 = st.points.total_momentum();
        for k in 0..2 {
            prop_assert!((p1[k] - p0[k]).abs() <= 1e-11 * scale,
                "component {k}: {} -> {} (scale {scale})", p0[k], p1[k]);
        }
    }

    /// A rigid translation plus rotation of the grid velocity field, `v_I = c + ω × x_I`,
    /// gives a skew velocity gradient at any point (uGIMP reproduces linear fields) and no
    /// stress in the elastic material.
    #[test]
    fn rigid_grid_motion_gives_no_stress(
        x in 0.3f64..0.9, y in 0.3f64..0.9, lp in 0.005f64..0.05,
        c0 in -1.0f64..1.0, c1 in -1.0f64..1.0, omega in -5.0f64..5.0
    ) {
        let grid = Grid::new(&GridParameters { origin: [0.0, 0.0], cell_size: 0.1, cells: [12, 12] }).unwrap();
        let st = Stencil::new(&grid, [x, y], [lp, lp]);
        let mut l = [0.0; 4];
        for b in 0..3 {
            for a in 0..3 {
                let xi = grid.node_position(st.x.base + a, st.y.base + b);
                let v = [c0 - omega * xi[1], c1 + omega * xi[0]];
                let g = st.gradient(a, b);
                l[0] += v[0] * g[0];
                l[1] += v[0] * g[1];
                l[2] += v[1] * g[0];
                l[3] += v[1] * g[1];
            }
        }
        prop_assert!(l[0].abs() < 1e-12 && l[3].abs() < 1e-12 && (l[1] + l[2]).abs() < 1e-12);
        prop_assert!((l[2] - omega).abs() < 1e-11);
        let e = 1e6;
        let mat = LinearThermoElastic::new(&ThermoElasticParameters {
            youngs_modulus: e, poisson_ratio: 0.25, thermal_expansion: 1e-5,
            conductivity: [1.0, 1.0, 0.0],
        }).unwrap();
        let mut s = [0.0; 3];
        for _ in 0..100 {
            let r = mat.respond(&mut (), &MaterialInput {
                point: 0, velocity_gradient: l, deformation_gradient: [1.0, 0.0, 0.0, 1.0],
                temperature: 0.0, temperature_rate: 0.0, stress: s, density: 1.0, dt: 1e-3,
            }).unwrap();
            s = r.stress;
        }
        for v in s {
            prop_assert!(v.abs() <= 1e-12 * e, "stress {s:?}");
        }
    }
}

/// A uniformly translating block: nodal velocities equal the block velocity, so no stress
/// appears, and every point moves by exactly `v Δt` per step for any PIC fraction — the
/// second-order position update B-Eq. 27 with the sign discussed in the crate docs.
#[test]
fn uniform_translation_moves_rigidly_without_stress() {
    for pic in [0.0, 0.3, 1.0] {
        let v = [0.7, -0.4];
        let (mut mpm, mut st, mat) = block_model(pic, [0.0, 0.0], |_, _| v);
        // Uniform temperature: no thermal strain.
        st.points.temperature.iter_mut().for_each(|t| *t = 10.0);
        let x0 = st.points.position.clone();
        let dt = 1e-3;
        let n = 20;
        for _ in 0..n {
            mpm.step(&mut st, &mat, dt).unwrap();
        }
        for (p, (x, x0)) in st.points.position.iter().zip(&x0).enumerate() {
            for k in 0..2 {
                let want = x0[k] + v[k] * dt * n as f64;
                assert!(
                    (x[k] - want).abs() < 1e-13,
                    "pic {pic} point {p}: {} vs {want}",
                    x[k]
                );
            }
            for s in st.points.stress[p] {
                assert!(s.abs() < 1e-9, "pic {pic} point {p}: stress {s}");
            }
        }
    }
}

/// Only the nodes that points touch are updated: as a block crosses the grid, every node
/// without mass holds the empty-node values (zero sums, velocities and temperature rate, the
/// prescribed temperature or 0), and the nodal masses add up to the point masses.
#[test]
fn nodes_left_behind_by_a_moving_block_are_empty() {
    let v = [2.0, -2.0];
    let (mut mpm, mut st, mat) = block_model(0.2, [0.0, 0.0], |_, _| v);
    st.points.temperature.iter_mut().for_each(|t| *t = 10.0);
    let total = st.points.total_mass();
    for _ in 0..100 {
        mpm.step(&mut st, &mat, 1e-3).unwrap();
        let gf = mpm.grid_fields();
        let nodal: f64 = gf.sums.iter().map(|s| s.mass).sum();
        assert!((nodal - total).abs() <= 1e-13 * total);
        let mut empty = 0;
        for (i, s) in gf.sums.iter().enumerate() {
            if s.mass == 0.0 {
                empty += 1;
                assert_eq!(*s, NodeSums::default(), "node {i}");
                assert_eq!(gf.velocity[i], [0.0; 2], "node {i}");
                assert_eq!(gf.velocity_old[i], [0.0; 2], "node {i}");
                assert_eq!(gf.temperature_rate[i], 0.0, "node {i}");
                assert_eq!(gf.temperature[i], 0.0, "node {i}");
            }
        }
        assert!(empty > 0);
    }
    // The block has moved by two cells along each axis.
    let x = st.points.position[0];
    assert!((x[0] - (0.325 + 0.2)).abs() < 1e-12 && (x[1] - (0.325 - 0.2)).abs() < 1e-12);
}

/// Heat conduction conserves energy: with no prescribed temperatures or fluxes, Σ m_p c_p T_p
/// is constant to round-off (FLIP increments B-Eq. 28; Σ_I Q_int,I = 0), and an anisotropic
/// tensor is accepted.
#[test]
fn heat_content_is_conserved_with_insulated_boundaries() {
    let (mut mpm, mut st, mat) = block_model(0.0, [0.0, 0.0], |_, _| [0.0; 2]);
    let energy = |s: &MpmState<()>| -> f64 {
        (0..s.points.len())
            .map(|p| s.points.mass[p] * s.points.specific_heat[p] * s.points.temperature[p])
            .sum()
    };
    let e0 = energy(&st);
    for _ in 0..50 {
        mpm.step(&mut st, &mat, 1e-3).unwrap();
    }
    let e1 = energy(&st);
    assert!((e1 - e0).abs() <= 1e-12 * e0.abs(), "{e0} -> {e1}");
    // And the temperature spread has decreased (heat flowed down the gradient).
    let spread = |s: &MpmState<()>| {
        let t = &s.points.temperature;
        t.iter().cloned().fold(f64::MIN, f64::max) - t.iter().cloned().fold(f64::MAX, f64::min)
    };
    let (_, st0, _) = block_model(0.0, [0.0, 0.0], |_, _| [0.0; 2]);
    assert!(spread(&st) < spread(&st0));
}

/// A column under gravity on a frictional floor, walls, heat: the full set of stages.
fn column(
    walls_removed_at: Option<f64>,
    per_cell: usize,
) -> (Mpm, MpmState<()>, LinearThermoElastic) {
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.05,
        cells: [40, 12],
    });
    params.gravity = [0.0, -9.81];
    params.pic_fraction = 0.05;
    params.grid_damping = 0.01;
    params.particle_damping = 0.01;
    params.walls = vec![
        RigidWall {
            point: [0.0, 0.05],
            normal: [0.0, 1.0],
            velocity: [0.0; 2],
            friction: 0.4,
            removal_time: None,
            extent: None,
            depth: None,
        },
        RigidWall {
            point: [0.6, 0.0],
            normal: [-1.0, 0.0],
            velocity: [0.0; 2],
            friction: 0.0,
            removal_time: walls_removed_at,
            extent: None,
            depth: None,
        },
    ];
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
        lower: [0.0, 0.5],
        upper: [0.6, 0.55],
        layer_thickness: 0.05,
        traction: [0.0, -100.0],
        inward_heat_flux: 20.0,
    }];
    let config = MpmConfig::new(params).unwrap();
    let mat = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e5,
        poisson_ratio: 0.3,
        thermal_expansion: 1e-5,
        conductivity: [1.0, 0.5, 0.1],
    })
    .unwrap();
    let mut pts = MaterialPoints::new();
    pts.fill_rectangle(
        config.grid(),
        [0.05, 0.05],
        [0.6, 0.55],
        per_cell,
        &PointProperties {
            density: 1500.0,
            specific_heat: 1.0,
            conductivity: [1.0, 1.0, 0.0],
            temperature: 0.0,
            velocity: [0.0; 2],
        },
    )
    .unwrap();
    let st = MpmState::new(pts, &mat);
    (Mpm::new(config), st, mat)
}

fn bits(st: &MpmState<()>) -> Vec<u64> {
    let p = &st.points;
    let mut v = Vec::new();
    for i in 0..p.len() {
        v.extend(p.position[i].iter().map(|x| x.to_bits()));
        v.extend(p.velocity[i].iter().map(|x| x.to_bits()));
        v.extend(p.stress[i].iter().map(|x| x.to_bits()));
        v.push(p.temperature[i].to_bits());
        v.push(p.remapped_temperature[i].to_bits());
        v.push(p.volume[i].to_bits());
    }
    v
}

/// One and two threads give the same bits (deterministic strip-coloured scatter), with more
/// points (5390) than one binning chunk holds.
#[test]
fn serial_and_parallel_runs_are_bit_identical() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let (mut mpm, mut st, mat) = column(Some(0.01), 7);
            for _ in 0..40 {
                mpm.step(&mut st, &mat, 5e-4).unwrap();
            }
            (bits(&st), mpm.wall_reactions().to_vec())
        })
    };
    let (a, ra) = run(1);
    let (b, rb) = run(2);
    assert_eq!(a, b);
    assert_eq!(ra, rb);
}

/// Saving the state (serde) and restoring it continues the run bit for bit.
#[test]
fn save_restore_round_trip() {
    let (mut mpm, mut st, mat) = column(None, 2);
    for _ in 0..10 {
        mpm.step(&mut st, &mat, 5e-4).unwrap();
    }
    let json = serde_json::to_string(&st).unwrap();
    let mut restored: MpmState<()> = serde_json::from_str(&json).unwrap();
    assert_eq!(bits(&st), bits(&restored));
    let cfg_json = serde_json::to_string(mpm.config().parameters()).unwrap();
    let params: MpmParameters = serde_json::from_str(&cfg_json).unwrap();
    let mut mpm2 = Mpm::new(MpmConfig::new(params).unwrap());
    for _ in 0..10 {
        mpm.step(&mut st, &mat, 5e-4).unwrap();
        mpm2.step(&mut restored, &mat, 5e-4).unwrap();
    }
    assert_eq!(bits(&st), bits(&restored));
}

/// Coulomb friction on a rigid floor: a block sliding under gravity decelerates at μ g.
#[test]
fn block_sliding_on_floor_decelerates_at_mu_g() {
    let (mu, g, v0) = (0.3, 10.0, 1.0);
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, -0.1],
        cell_size: 0.05,
        cells: [60, 8],
    });
    params.gravity = [0.0, -g];
    params.walls = vec![RigidWall {
        point: [0.0, 0.0],
        normal: [0.0, 1.0],
        velocity: [0.0; 2],
        friction: mu,
        removal_time: None,
        extent: None,
        depth: None,
    }];
    let config = MpmConfig::new(params).unwrap();
    let mat = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e6,
        poisson_ratio: 0.2,
        thermal_expansion: 0.0,
        conductivity: [0.0; 3],
    })
    .unwrap();
    let mut pts = MaterialPoints::new();
    pts.fill_rectangle(
        config.grid(),
        [0.2, 0.0],
        [0.6, 0.2],
        2,
        &PointProperties {
            density: 1000.0,
            specific_heat: 1.0,
            conductivity: [0.0; 3],
            temperature: 0.0,
            velocity: [v0, 0.0],
        },
    )
    .unwrap();
    let mut st = MpmState::new(pts, &mat);
    let mut mpm = Mpm::new(config);
    let dt = 2e-4;
    let t_end = 0.2;
    for _ in 0..(t_end / dt) as usize {
        mpm.step(&mut st, &mat, dt).unwrap();
    }
    let m = st.points.total_mass();
    let v = st.points.total_momentum()[0] / m;
    let decel = (v0 - v) / t_end;
    assert!(
        (decel - mu * g).abs() < 0.1 * mu * g,
        "deceleration {decel} vs μg = {}",
        mu * g
    );
}

/// A wall removed at a given time stops acting: its reaction is zero afterwards.
#[test]
fn removed_wall_stops_acting() {
    let (mut mpm, mut st, mat) = column(Some(0.01), 2);
    let mut before = 0.0f64;
    let mut after = 0;
    for _ in 0..40 {
        let t_start = st.time;
        mpm.step(&mut st, &mat, 5e-4).unwrap();
        if t_start < 0.01 {
            before = before.max(mpm.wall_reactions()[1][0].abs());
        } else {
            assert_eq!(mpm.wall_reactions()[1], [0.0, 0.0]);
            after += 1;
        }
    }
    assert!(after > 10);
    assert!(before > 0.0, "the side wall carried no load before removal");
}

/// Bad input: typed errors naming the point or parameter.
#[test]
fn bad_input_gives_typed_errors() {
    // A point outside the grid.
    let (mut mpm, mut st, mat) = block_model(0.0, [0.0, 0.0], |_, _| [0.0; 2]);
    st.points.position[7] = [1.19, 0.5];
    match mpm.step(&mut st, &mat, 1e-3) {
        Err(MpmError::PointOutsideGrid { index: 7, .. }) => {}
        other => panic!("expected PointOutsideGrid for point 7, got {other:?}"),
    }
    // Time step above the mechanical limit B-Eq. 30: l_e / sqrt(M/ρ).
    let (mut mpm, mut st, mat) = block_model(0.0, [0.0, 0.0], |_, _| [0.0; 2]);
    let lim = mpm.time_step_limits(&st, &mat);
    let m = mat.lambda() + 2.0 * mat.shear_modulus();
    assert!((lim.mechanical - 0.1 / (m / 1000.0f64).sqrt()).abs() < 1e-12);
    match mpm.step(&mut st, &mat, 1.01 * lim.mechanical) {
        Err(MpmError::TimeStepTooLarge {
            criterion, limit, ..
        }) => {
            assert!(criterion.contains("B-Eq. 30"));
            assert_eq!(limit, lim.mechanical);
        }
        other => panic!("expected TimeStepTooLarge, got {other:?}"),
    }
    // The thermal limit B-Eq. 31: l_e² ρ c / (b k̄), k̄ = (kxx + kyy)/2 = 1.5.
    assert!((lim.thermal - 0.01 * 1000.0 * 800.0 / 1.5).abs() < 1e-9);
    // Negative density.
    let grid = Grid::new(&GridParameters {
        origin: [0.0; 2],
        cell_size: 0.1,
        cells: [4, 4],
    })
    .unwrap();
    let mut pts = MaterialPoints::new();
    let err = pts.fill_rectangle(
        &grid,
        [0.1, 0.1],
        [0.3, 0.3],
        1,
        &PointProperties {
            density: -5.0,
            specific_heat: 1.0,
            conductivity: [1.0, 1.0, 0.0],
            temperature: 0.0,
            velocity: [0.0; 2],
        },
    );
    match err {
        Err(MpmError::InvalidParameter { name, value, .. }) => {
            assert_eq!(name, "density");
            assert_eq!(value, -5.0);
        }
        other => panic!("expected InvalidParameter(density), got {other:?}"),
    }
    // A point whose mass was made negative directly names the point.
    let (mut mpm, mut st, mat) = block_model(0.0, [0.0, 0.0], |_, _| [0.0; 2]);
    st.points.mass[3] = -1.0;
    match mpm.step(&mut st, &mat, 1e-3) {
        Err(MpmError::InvalidPoint {
            index: 3,
            field: "mass",
            ..
        }) => {}
        other => panic!("expected InvalidPoint(3, mass), got {other:?}"),
    }
    // Parameters out of range.
    let mut p = MpmParameters::on_grid(GridParameters {
        origin: [0.0; 2],
        cell_size: 0.1,
        cells: [4, 4],
    });
    p.pic_fraction = 1.5;
    assert!(
        matches!(MpmConfig::new(p), Err(MpmError::InvalidParameter { ref name, .. }) if name == "pic_fraction")
    );
    assert!(matches!(
        Grid::new(&GridParameters { origin: [0.0; 2], cell_size: -1.0, cells: [4, 4] }),
        Err(MpmError::InvalidParameter { ref name, .. }) if name == "grid.cell_size"
    ));
    assert!(
        LinearThermoElastic::new(&ThermoElasticParameters {
            youngs_modulus: 1.0,
            poisson_ratio: 0.5,
            thermal_expansion: 0.0,
            conductivity: [1.0, 1.0, 0.0],
        })
        .is_err()
    );
    // Unknown keys are rejected.
    let bad = r#"{"grid":{"origin":[0,0],"cell_size":0.1,"cells":[4,4]},"pic_fractoin":0.1}"#;
    assert!(serde_json::from_str::<MpmParameters>(bad).is_err());
}

/// The virtual boundary layer (B-Eqs. 17–18): a traction `t̄` and an inward heat flux `q̄`
/// applied on the layer of thickness `h` under a free surface of length `ℓ` put exactly the
/// force `t̄ Σ V_p/h ≈ t̄ ℓ` and the power `q̄ Σ V_p/h` into the body: momentum and heat grow
/// by exactly these times `Δt` per step (no other loads), with the current point volumes.
#[test]
fn surface_layer_loads_integrate_to_traction_times_length() {
    let h = 0.1;
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: h,
        cells: [12, 12],
    });
    let (traction, flux) = ([3.0, -7.0], 40.0);
    // Top surface of the block [0.3, 0.9] × [0.3, 0.8]; layer = the top row of cells.
    params.surface_loads = vec![SurfaceLoad {
        lower: [0.3, 0.8 - h],
        upper: [0.9, 0.8],
        layer_thickness: h,
        traction,
        inward_heat_flux: flux,
    }];
    let length = 0.6;
    let config = MpmConfig::new(params).unwrap();
    let mat = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e4,
        poisson_ratio: 0.3,
        thermal_expansion: 0.0,
        conductivity: [1.0, 1.0, 0.0],
    })
    .unwrap();
    let mut pts = MaterialPoints::new();
    pts.fill_rectangle(
        config.grid(),
        [0.3, 0.3],
        [0.9, 0.8],
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
    let mut st = MpmState::new(pts, &mat);
    let mut mpm = Mpm::new(config);
    let heat = |s: &MpmState<()>| -> f64 {
        (0..s.points.len())
            .map(|p| s.points.mass[p] * s.points.specific_heat[p] * s.points.temperature[p])
            .sum()
    };
    let dt = 1e-3;
    let n = 20;
    // Σ V_p/h over the layer, with the current volumes (the layer deforms with the body).
    let mut loaded_length = 0.0;
    let layer = mpm.config().parameters().surface_loads[0];
    for _ in 0..n {
        let l: f64 = (0..st.points.len())
            .filter(|&p| layer.contains(st.points.position[p]))
            .map(|p| st.points.volume[p] / h)
            .sum();
        loaded_length += l * dt;
        mpm.step(&mut st, &mat, dt).unwrap();
    }
    let t = n as f64 * dt;
    // The loaded length equals the surface length up to the small volume change.
    assert!((loaded_length / t - length).abs() < 1e-3 * length);
    let p = st.points.total_momentum();
    for k in 0..2 {
        let want = traction[k] * loaded_length;
        assert!(
            (p[k] - want).abs() < 1e-10 * want.abs(),
            "momentum {k}: {} vs {want}",
            p[k]
        );
    }
    let q = heat(&st);
    let want = flux * loaded_length;
    assert!((q - want).abs() < 1e-10 * want, "heat {q} vs {want}");
}

/// A plate moving at a prescribed velocity drives the material it touches: a block
/// compressed by a frictionless top plate moving down at `v` ends with its top layer moving
/// at the plate's velocity and a compressive reaction on the plate.
#[test]
fn moving_plate_drives_the_material() {
    let h = 0.05;
    let v = -0.05;
    // One padding cell below the block: points on the grid edge could round off out of it.
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, -h],
        cell_size: h,
        cells: [10, 13],
    });
    params.velocity_conditions = vec![VelocityCondition {
        nodes: NodeSet::Region {
            lower: [-1.0, -1.0],
            upper: [1.0, 1e-9],
        },
        fix_x: false,
        fix_y: true,
    }];
    params.walls = vec![RigidWall {
        point: [0.0, 0.4],
        normal: [0.0, -1.0],
        velocity: [0.0, v],
        friction: 0.0,
        removal_time: None,
        extent: None,
        depth: None,
    }];
    let config = MpmConfig::new(params).unwrap();
    let mat = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e5,
        poisson_ratio: 0.2,
        thermal_expansion: 0.0,
        conductivity: [0.0; 3],
    })
    .unwrap();
    let mut pts = MaterialPoints::new();
    pts.fill_rectangle(
        config.grid(),
        [0.1, 0.0],
        [0.4, 0.4],
        2,
        &PointProperties {
            density: 1000.0,
            specific_heat: 1.0,
            conductivity: [0.0; 3],
            temperature: 0.0,
            velocity: [0.0; 2],
        },
    )
    .unwrap();
    let mut st = MpmState::new(pts, &mat);
    let mut mpm = Mpm::new(config);
    let dt = 5e-4;
    for _ in 0..400 {
        mpm.step(&mut st, &mat, dt).unwrap();
    }
    // The plate has moved 0.01 m down; the topmost points follow it.
    let top = st
        .points
        .position
        .iter()
        .map(|x| x[1])
        .fold(f64::MIN, f64::max);
    let plate = 0.4 + v * st.time;
    assert!(top < plate, "points {top} crossed the plate at {plate}");
    let reaction = mpm.wall_reactions()[0][1];
    assert!(
        reaction > 0.0,
        "the plate should be pushed up by the block, got {reaction}"
    );
    // Mean axial stress magnitude of the order of E × strain (strain 0.01/0.4 = 2.5 %).
    let mean_syy: f64 = st.points.stress.iter().map(|s| s[1]).sum::<f64>() / st.points.len() as f64;
    assert!(
        mean_syy < 0.0 && mean_syy.abs() < 1e5 * 0.025 * 3.0,
        "mean σyy {mean_syy}"
    );
}
