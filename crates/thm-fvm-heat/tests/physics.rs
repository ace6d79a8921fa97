//! Physics and bad-input tests of single laws: boundary cases I–III, the fluid–solid interface
//! (case IV) with the Nusselt correlations, the S2S conduction source, sphere averages, the
//! implicit step, and typed errors.

mod common;

use common::table1_params;
use thm_fvm_heat::properties::{REYNOLDS_SWITCH, nusselt};
use thm_fvm_heat::{
    BoundaryCondition, BoundaryParams, FlowInput, HeatError, HeatGeometry, HeatModel, HeatParams,
    HeatState, HeatStepper, TemperatureSchedule, sphere_mean_temperatures,
};
use thm_vpn_mesh::{BoundarySide, CellKind, ChannelKind, NONE, PoreMesh};

fn unit_solid_params(boundaries: Vec<BoundaryParams>) -> HeatParams {
    let mut p = table1_params();
    p.solid.density = 1.0;
    p.solid.specific_heat = 1.0;
    p.solid.conductivity = 1.0;
    p.boundaries = boundaries;
    p
}

fn bc(side: BoundarySide, condition: BoundaryCondition) -> BoundaryParams {
    BoundaryParams { side, condition }
}

fn solid_bar(nx: usize) -> PoreMesh {
    PoreMesh::structured_rectangle(nx, 2, 1.0, 0.25, 1.0, 1.0, |_| CellKind::Solid { owner: 0 })
        .unwrap()
}

/// Runs to steady state explicitly and implicitly; returns both temperature fields.
fn steady(mesh: &PoreMesh, params: &HeatParams) -> (Vec<f64>, Vec<f64>) {
    let model = HeatModel::new(params, mesh).unwrap();
    let geometry = HeatGeometry::new(&model, mesh).unwrap();
    let input = FlowInput::liquid_at_rest(mesh, 1000.0, 1.2);
    let mut explicit = HeatState::uniform(mesh, 320.0);
    let mut stepper = HeatStepper::new();
    stepper
        .step(&model, &geometry, mesh, &input, &mut explicit, 12.0)
        .unwrap();
    let mut implicit = HeatState::uniform(mesh, 320.0);
    for _ in 0..60 {
        stepper
            .implicit_step(&model, &geometry, mesh, &input, &mut implicit, 1.0)
            .unwrap();
    }
    (explicit.temperature, implicit.temperature)
}

/// Case III at the left end, case I at the right: the steady profile is linear with the
/// flux (T_e − T_R) / (1/h_e + L/λ); the scheme is exact for linear fields.
#[test]
fn convective_boundary_gives_series_resistance_profile() {
    let (h, te, tr) = (2.0, 350.0, 300.0);
    let mesh = solid_bar(8);
    let params = unit_solid_params(vec![
        bc(
            BoundarySide::Left,
            BoundaryCondition::Convective {
                coefficient: h,
                ambient_temperature: te,
            },
        ),
        bc(
            BoundarySide::Right,
            BoundaryCondition::Temperature {
                temperature: TemperatureSchedule::Constant(tr),
            },
        ),
    ]);
    let q = (te - tr) / (1.0 / h + 1.0);
    let (ex, im) = steady(&mesh, &params);
    for c in 0..mesh.n_cells() {
        let exact = tr + q * (1.0 - mesh.cell_centroid[c][0]);
        assert!(
            (ex[c] - exact).abs() < 1e-6,
            "explicit {} vs {exact}",
            ex[c]
        );
        assert!(
            (im[c] - exact).abs() < 1e-6,
            "implicit {} vs {exact}",
            im[c]
        );
    }
}

/// Case II (prescribed flux into the domain) at the left, case I at the right.
#[test]
fn prescribed_flux_gives_linear_profile() {
    let (q, tr) = (15.0, 300.0);
    let mesh = solid_bar(8);
    let params = unit_solid_params(vec![
        bc(BoundarySide::Left, BoundaryCondition::HeatFlux { flux: q }),
        bc(
            BoundarySide::Right,
            BoundaryCondition::Temperature {
                temperature: TemperatureSchedule::Constant(tr),
            },
        ),
    ]);
    let (ex, im) = steady(&mesh, &params);
    for c in 0..mesh.n_cells() {
        let exact = tr + q * (1.0 - mesh.cell_centroid[c][0]);
        assert!(
            (ex[c] - exact).abs() < 1e-6,
            "explicit {} vs {exact}",
            ex[c]
        );
        assert!(
            (im[c] - exact).abs() < 1e-6,
            "implicit {} vs {exact}",
            im[c]
        );
    }
}

/// Case I with a temperature table: the boundary follows the schedule (piecewise linear,
/// held outside), and the steady field follows the final value.
#[test]
fn dirichlet_schedule_is_followed() {
    let s = TemperatureSchedule::Table {
        time: vec![0.0, 10.0, 20.0],
        temperature: vec![300.0, 320.0, 310.0],
    };
    assert_eq!(s.at(-1.0), 300.0);
    assert!((s.at(5.0) - 310.0).abs() < 1e-12);
    assert!((s.at(15.0) - 315.0).abs() < 1e-12);
    assert_eq!(s.at(25.0), 310.0);
    let mesh = solid_bar(4);
    let params = unit_solid_params(vec![
        bc(
            BoundarySide::Left,
            BoundaryCondition::Temperature {
                temperature: s.clone(),
            },
        ),
        bc(
            BoundarySide::Right,
            BoundaryCondition::Temperature { temperature: s },
        ),
    ]);
    let model = HeatModel::new(&params, &mesh).unwrap();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let input = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.2);
    let mut state = HeatState::uniform(&mesh, 300.0);
    let mut stepper = HeatStepper::new();
    stepper
        .step(&model, &geometry, &mesh, &input, &mut state, 40.0)
        .unwrap();
    for t in &state.temperature {
        assert!((t - 310.0).abs() < 1e-6, "{t}");
    }
}

/// Two triangles, one fluid (water at rest) and one solid: one short explicit step moves the
/// fluid temperature by Δt G (T_s − T_f) / C_f with G = |A| / (1/h_f + d/λ_s), h_f = Nu λ_w
/// / (2r) (A-Eq. 45), Nu = 7 − 10ε + 5ε² at Re = 0 (A-Eq. 43), ε = 1/2, r from the solid
/// cell's area.
#[test]
fn fluid_solid_interface_uses_nusselt_coefficient() {
    // Lower-right triangle fluid, upper-left solid.
    let mesh = PoreMesh::structured_rectangle(1, 1, 0.004, 0.004, 0.008, 1.0, |p| {
        if p[1] < p[0] {
            CellKind::Fluid
        } else {
            CellKind::Solid { owner: 0 }
        }
    })
    .unwrap();
    let params = table1_params();
    let model = HeatModel::new(&params, &mesh).unwrap();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let input = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.2);
    let (tf0, ts0) = (300.0, 340.0);
    let mut state = HeatState {
        time: 0.0,
        steps: 0,
        temperature: vec![tf0, ts0],
    };
    let (cf, cs) = (0usize, 1usize);
    assert!(mesh.cell_kind[cf].is_fluid() && !mesh.cell_kind[cs].is_fluid());
    let face = mesh.cell_faces[cf]
        .iter()
        .copied()
        .find(|&f| mesh.face_cells[f as usize][1] != NONE)
        .unwrap() as usize;
    let eps: f64 = 0.5;
    let r = (mesh.cell_area[cs] / std::f64::consts::PI).sqrt();
    let h = (7.0 - 10.0 * eps + 5.0 * eps * eps) * 0.6 / (2.0 * r);
    let xf = mesh.face_centroid[face];
    let xs = mesh.cell_centroid[cs];
    let d = ((xf[0] - xs[0]).powi(2) + (xf[1] - xs[1]).powi(2)).sqrt();
    let area = mesh.face_length[face] * mesh.thickness;
    let g = area / (1.0 / h + d / 3.7);
    let c_f = mesh.cell_area[cf] * mesh.thickness * 1000.0 * 4187.0;
    let c_s = mesh.cell_area[cs] * mesh.thickness * 2600.0 * 920.0;
    let mut stepper = HeatStepper::new();
    let dt = 1e-3;
    let report = stepper
        .step(&model, &geometry, &mesh, &input, &mut state, dt)
        .unwrap();
    assert_eq!(report.substeps, 1);
    let expected_f = tf0 + dt * g * (ts0 - tf0) / c_f;
    let expected_s = ts0 - dt * g * (ts0 - tf0) / c_s;
    assert!((state.temperature[cf] - expected_f).abs() < 1e-12 * tf0);
    assert!((state.temperature[cs] - expected_s).abs() < 1e-12 * ts0);
}

/// A-Eqs. 43 and 44: the correlation switches at Re = 100, reduces to 7 − 10ε + 5ε² at rest
/// and grows with Re in both ranges.
#[test]
fn nusselt_correlations_cover_both_reynolds_ranges() {
    let (eps, pr) = (0.3f64, 7.0f64);
    let a = 7.0 - 10.0 * eps + 5.0 * eps * eps;
    let b = 1.33 - 2.19 * eps + 1.15 * eps * eps;
    assert!((nusselt(eps, 0.0, pr) - a).abs() < 1e-12);
    let re = 50.0f64;
    let eq43 = a * (1.0 + 0.1 * re.powf(0.2) * pr.cbrt()) + b * re.powf(0.7) * pr.cbrt();
    assert!((nusselt(eps, re, pr) - eq43).abs() < 1e-12 * eq43);
    let re = 500.0f64;
    let eq44 = 2.0 + 1.1 * re.powf(0.6) * pr.cbrt();
    assert!((nusselt(eps, re, pr) - eq44).abs() < 1e-12 * eq44);
    for lo in [1.0, 10.0, 60.0] {
        assert!(nusselt(eps, 1.5 * lo, pr) > nusselt(eps, lo, pr));
    }
    assert!(nusselt(eps, 2.0 * REYNOLDS_SWITCH, pr) > nusselt(eps, 1.01 * REYNOLDS_SWITCH, pr));
}

/// A-Eq. 40: two fluid cells joined only by an S2S channel (the solid between them does not
/// conduct) exchange λ_eff A_k (T_i − T_j) / L_k with A_k = h b.
#[test]
fn s2s_channel_conducts_by_eq_40() {
    // Cells 0 (lower right of the first square) and 3 (upper right of the second) are fluid
    // and share no face.
    let h = 0.002;
    let mut mesh = PoreMesh::structured_rectangle(2, 1, 2.0 * h, h, 0.008, 1.0, |p| {
        if (p[0] < h && p[1] < p[0]) || (p[0] > h && p[1] > 0.5 * h) {
            CellKind::Fluid
        } else {
            CellKind::Solid { owner: 0 }
        }
    })
    .unwrap();
    assert!(mesh.cell_kind[0].is_fluid() && mesh.cell_kind[3].is_fluid());
    assert!(mesh.channels.is_empty());
    let (a, b) = (0u32, 3u32);
    let (pa, pb) = (mesh.cell_centroid[0], mesh.cell_centroid[3]);
    let len = ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2)).sqrt();
    let aperture = 1e-4;
    let ch = &mut mesh.channels;
    ch.kind.push(ChannelKind::S2S);
    ch.cells.push([a, b]);
    ch.length.push(len);
    ch.aperture.push(aperture);
    ch.face.push(NONE);
    ch.contact.push(0);
    let mut params = table1_params();
    params.solid.conductivity = 0.0;
    let model = HeatModel::new(&params, &mesh).unwrap();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let input = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.2);
    let mut state = HeatState {
        time: 0.0,
        steps: 0,
        temperature: vec![350.0, 300.0, 300.0, 300.0],
    };
    let g = 0.6 * aperture * mesh.thickness / len;
    let cap = |c: usize| mesh.cell_area[c] * mesh.thickness * 1000.0 * 4187.0;
    let dt = 1e-2;
    let mut stepper = HeatStepper::new();
    stepper
        .step(&model, &geometry, &mesh, &input, &mut state, dt)
        .unwrap();
    let q = g * 50.0;
    assert!((state.temperature[0] - (350.0 - dt * q / cap(0))).abs() < 1e-12 * 350.0);
    assert!((state.temperature[3] - (300.0 + dt * q / cap(3))).abs() < 1e-12 * 300.0);
    assert_eq!(state.temperature[1], 300.0);
}

/// A-Eq. 55 input: the volume average over each sphere's solid cells; for a linear field it
/// is the value at the centroid of the sphere's cells. A sphere index without cells is None.
#[test]
fn sphere_mean_temperature_is_volume_average() {
    let mesh = PoreMesh::structured_rectangle(4, 4, 1.0, 1.0, 0.1, 1.0, |p| {
        if p[0] < 0.5 {
            CellKind::Solid { owner: 0 }
        } else if p[1] < 0.5 {
            CellKind::Solid { owner: 2 }
        } else {
            CellKind::Fluid
        }
    })
    .unwrap();
    let temp: Vec<f64> = mesh
        .cell_centroid
        .iter()
        .map(|p| 300.0 + 10.0 * p[0] + 4.0 * p[1])
        .collect();
    let mut out = Vec::new();
    sphere_mean_temperatures(&mesh, &temp, &mut out).unwrap();
    assert_eq!(out.len(), 3);
    assert!((out[0].unwrap() - (300.0 + 2.5 + 2.0)).abs() < 1e-12);
    assert!(out[1].is_none());
    assert!((out[2].unwrap() - (300.0 + 7.5 + 1.0)).abs() < 1e-12);
}

#[test]
fn bad_parameters_are_typed_errors() {
    let mesh = solid_bar(2);
    let field_of = |p: &HeatParams| match HeatModel::new(p, &mesh) {
        Err(HeatError::ParameterOutOfRange { field, .. }) => field,
        other => panic!("expected ParameterOutOfRange, got {other:?}"),
    };
    let mut p = table1_params();
    p.solid.conductivity = -1.0;
    assert_eq!(field_of(&p), "solid.conductivity");
    let mut p = table1_params();
    p.solid.specific_heat = -920.0;
    assert_eq!(field_of(&p), "solid.specific_heat");
    let mut p = table1_params();
    p.liquid.conductivity = -0.6;
    assert_eq!(field_of(&p), "liquid.conductivity");
    let mut p = table1_params();
    p.gas.specific_heat = 0.0;
    assert_eq!(field_of(&p), "gas.specific_heat");
    let mut p = table1_params();
    p.solid.density = f64::NAN;
    assert_eq!(field_of(&p), "solid.density");
    let mut p = table1_params();
    p.cross_diffusion = thm_fvm_heat::CrossDiffusion::Limited { ratio: -0.5 };
    assert_eq!(field_of(&p), "cross_diffusion.ratio");
    let mut p = table1_params();
    p.boundaries = vec![bc(
        BoundarySide::Top,
        BoundaryCondition::Temperature {
            temperature: TemperatureSchedule::Table {
                time: vec![0.0, 0.0],
                temperature: vec![300.0, 310.0],
            },
        },
    )];
    assert_eq!(field_of(&p), "boundaries[0].temperature.time[1]");

    // A side that has no boundary face on this mesh.
    let mut p = table1_params();
    p.boundaries = vec![
        bc(BoundarySide::Left, BoundaryCondition::Adiabatic),
        bc(BoundarySide::Outline, BoundaryCondition::Adiabatic),
    ];
    assert_eq!(
        HeatModel::new(&p, &mesh),
        Err(HeatError::BoundaryNotOnMesh {
            index: 1,
            side: BoundarySide::Outline
        })
    );
    let mut p = table1_params();
    p.boundaries = vec![
        bc(BoundarySide::Left, BoundaryCondition::Adiabatic),
        bc(
            BoundarySide::Left,
            BoundaryCondition::HeatFlux { flux: 1.0 },
        ),
    ];
    assert!(matches!(
        HeatModel::new(&p, &mesh),
        Err(HeatError::DuplicateBoundary { index: 1, .. })
    ));

    // Unknown keys are rejected when reading parameters.
    let mut v = serde_json::to_value(table1_params()).unwrap();
    v["solid"]["conductivty"] = serde_json::json!(3.7);
    assert!(serde_json::from_value::<HeatParams>(v).is_err());
}

#[test]
fn bad_inputs_and_instability_are_typed_errors() {
    let mesh =
        PoreMesh::structured_rectangle(2, 2, 1.0, 1.0, 1.0, 1.0, |_| CellKind::Fluid).unwrap();
    let params = table1_params();
    let model = HeatModel::new(&params, &mesh).unwrap();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let mut stepper = HeatStepper::new();
    let good = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.2);
    let mut state = HeatState::uniform(&mesh, 300.0);

    let mut input = good.clone();
    input.liquid_fraction[3] = 1.5;
    assert!(matches!(
        stepper.step(&model, &geometry, &mesh, &input, &mut state, 1.0),
        Err(HeatError::InputOutOfRange {
            quantity: "liquid_fraction",
            index: 3,
            ..
        })
    ));
    let mut input = good.clone();
    input.channel_mass_flux.pop();
    assert!(matches!(
        stepper.step(&model, &geometry, &mesh, &input, &mut state, 1.0),
        Err(HeatError::LengthMismatch {
            what: "channel_mass_flux",
            ..
        })
    ));
    let mut short = state.clone();
    short.temperature.pop();
    assert!(matches!(
        stepper.step(&model, &geometry, &mesh, &good, &mut short, 1.0),
        Err(HeatError::LengthMismatch {
            what: "temperature",
            ..
        })
    ));
    assert!(matches!(
        stepper.step(&model, &geometry, &mesh, &good, &mut state, -1.0),
        Err(HeatError::ParameterOutOfRange { .. })
    ));
    // An absurd heat flux overflows: the step stops with the quantity, cell and step.
    let mut p = table1_params();
    p.boundaries = vec![bc(
        BoundarySide::Left,
        BoundaryCondition::HeatFlux { flux: 1e308 },
    )];
    let model = HeatModel::new(&p, &mesh).unwrap();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let err = stepper
        .step(&model, &geometry, &mesh, &good, &mut state, 1.0)
        .unwrap_err();
    assert!(
        matches!(
            err,
            HeatError::NonFinite {
                quantity: "temperature",
                ..
            }
        ),
        "{err:?}"
    );
}

/// A sliver: a 1 × 1e-4 strip of four cells split along diagonals, whose centroid links
/// make cos ≈ 2e-4 with the diagonal faces. The geometry takes the minimum-correction flux
/// there (counted), and a step still conserves Σ C T to round-off and makes no new extremum.
#[test]
fn sliver_faces_fall_back_to_a_bounded_conservative_flux() {
    let mesh =
        PoreMesh::structured_rectangle(4, 1, 4.0, 1e-4, 1.0, 1.0, |_| CellKind::Solid { owner: 0 })
            .unwrap();
    let params = unit_solid_params(Vec::new());
    let model = HeatModel::new(&params, &mesh).unwrap();
    assert!(HeatGeometry::new(&model, &mesh).unwrap().sliver_faces() >= 4);
    let model = HeatModel::new(&params, &mesh).unwrap();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let input = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.0);
    let mut state = HeatState::uniform(&mesh, 300.0);
    for (c, t) in state.temperature.iter_mut().enumerate() {
        *t = 300.0 + 2.5 * mesh.cell_centroid[c][0];
    }
    let energy = |s: &HeatState| -> f64 {
        (0..mesh.n_cells())
            .map(|c| mesh.cell_volume(c) * s.temperature[c])
            .sum()
    };
    let (lo, hi) = (300.0, 310.0);
    let e0 = energy(&state);
    let mut stepper = HeatStepper::new();
    stepper
        .implicit_step(&model, &geometry, &mesh, &input, &mut state, 0.05)
        .unwrap();
    assert!(((energy(&state) - e0) / e0).abs() < 1e-12);
    assert!(
        state
            .temperature
            .iter()
            .all(|&t| (lo - 1e-9..=hi + 1e-9).contains(&t))
    );
}

/// The solid capacity scale multiplies ρ_s c_s V per owner: a sphere whose cells shrink to
/// half their area with scale 2 keeps its heat capacity, so the same heat flux changes its
/// temperature at the same rate.
#[test]
fn solid_capacity_scale_multiplies_the_owners_capacity() {
    let mesh = solid_bar(4);
    let params = unit_solid_params(Vec::new());
    let model = HeatModel::new(&params, &mesh).unwrap();
    let mut geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let input = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.0);
    let state = HeatState::uniform(&mesh, 300.0);
    let mut stepper = HeatStepper::new();
    stepper
        .prepare(&model, &geometry, &mesh, &input, &state)
        .unwrap();
    let plain: Vec<f64> = stepper.heat_capacity().to_vec();
    geometry.set_solid_capacity_scale(&mesh, &[2.0]).unwrap();
    stepper
        .prepare(&model, &geometry, &mesh, &input, &state)
        .unwrap();
    for (a, b) in plain.iter().zip(stepper.heat_capacity()) {
        assert_eq!(2.0 * a, *b);
    }
    // Bad factors are errors naming the sphere.
    let err = geometry
        .set_solid_capacity_scale(&mesh, &[f64::NAN])
        .unwrap_err();
    assert!(err.to_string().contains("solid capacity scale"), "{err}");
    assert!(geometry.set_solid_capacity_scale(&mesh, &[]).is_err());
}

/// The implicit step with a capacity change: closed and adiabatic, so
/// `Σ C^{n+1}(T^{n+1} − T_ref) = Σ C^n (T^n − T_ref)` to round-off; a uniform field stays
/// uniform at `T_ref + (C^n/C^{n+1})(T − T_ref)`.
#[test]
fn implicit_step_balances_the_old_capacity_against_the_new() {
    let mesh = solid_bar(6);
    let params = unit_solid_params(Vec::new());
    let model = HeatModel::new(&params, &mesh).unwrap();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let input = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.0);
    let t_ref = params.reference_temperature;
    let mut stepper = HeatStepper::new();
    let new_capacity: Vec<f64> = (0..mesh.n_cells()).map(|c| mesh.cell_volume(c)).collect();
    // Uniform: stays uniform at the rescaled temperature.
    let old: Vec<f64> = new_capacity.iter().map(|c| 2.0 * c).collect();
    let mut state = HeatState::uniform(&mesh, 300.0);
    stepper
        .implicit_step_with_old_capacity(&model, &geometry, &mesh, &input, &mut state, &old, 0.1)
        .unwrap();
    for &t in &state.temperature {
        assert!((t - (t_ref + 2.0 * (300.0 - t_ref))).abs() < 1e-9, "{t}");
    }
    // Non-uniform capacities and temperatures: the energy balance holds to round-off.
    let old: Vec<f64> = new_capacity
        .iter()
        .enumerate()
        .map(|(c, v)| v * (0.5 + 0.1 * (c % 7) as f64))
        .collect();
    let mut state = HeatState::uniform(&mesh, 300.0);
    for (c, t) in state.temperature.iter_mut().enumerate() {
        *t = 295.0 + (c % 5) as f64;
    }
    let before: f64 = old
        .iter()
        .zip(&state.temperature)
        .map(|(c, t)| c * (t - t_ref))
        .sum();
    stepper
        .implicit_step_with_old_capacity(&model, &geometry, &mesh, &input, &mut state, &old, 0.1)
        .unwrap();
    let after: f64 = new_capacity
        .iter()
        .zip(&state.temperature)
        .map(|(c, t)| c * (t - t_ref))
        .sum();
    assert!(
        ((after - before) / before).abs() < 1e-12,
        "{after} vs {before}"
    );
    // A wrong length is an error naming the array.
    let err = stepper
        .implicit_step_with_old_capacity(
            &model,
            &geometry,
            &mesh,
            &input,
            &mut state,
            &old[1..],
            0.1,
        )
        .unwrap_err();
    assert!(err.to_string().contains("old_capacity"), "{err}");
}
