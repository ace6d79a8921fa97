//! One heat step on 100 000 fluid + 100 000 solid cells (structured triangulation, 2 × 2-square
//! blocks alternating fluid and solid, uniform flow through the T2T channels), on 1 and 2
//! threads: the explicit sub-step alone, a whole outer step of one sub-step (per-step
//! coefficients prepared + sub-step, the stability limit taken from the sub-step's face pass,
//! with the mesh geometry cached in a `HeatGeometry`), the geometry itself (built once per
//! remesh; refreshed after the vertices move), every stage alone on one thread, and the
//! backward-Euler conduction step (assembly + sparse Cholesky).
//!
//! Run: `cargo bench -p thm-benchmarks --bench fvm_heat`.

use criterion::{Criterion, criterion_group, criterion_main};
use thm_fvm_heat::{FlowInput, HeatGeometry, HeatModel, HeatParams, HeatState, HeatStepper};
use thm_vpn_mesh::{CellKind, PoreMesh};

fn setup() -> (PoreMesh, HeatModel, FlowInput, HeatState) {
    let (nx, ny) = (500, 200);
    let h = 1e-3;
    let mesh =
        PoreMesh::structured_rectangle(nx, ny, nx as f64 * h, ny as f64 * h, 8e-3, 0.0115, |p| {
            let (i, j) = ((p[0] / h) as usize, (p[1] / h) as usize);
            if (i / 2 + j / 2) % 2 == 0 {
                CellKind::Fluid
            } else {
                CellKind::Solid {
                    owner: ((j / 2) * (nx / 2) + i / 2) as u32,
                }
            }
        })
        .unwrap();
    let n_fluid = mesh.cell_kind.iter().filter(|k| k.is_fluid()).count();
    assert_eq!(n_fluid, 100_000);
    assert_eq!(mesh.n_cells() - n_fluid, 100_000);
    let params = HeatParams::paper_a_table_1();
    let model = HeatModel::new(&params, &mesh).unwrap();
    let mut input = FlowInput::liquid_at_rest(&mesh, 1000.0, 1.2);
    for k in 0..mesh.channels.len() {
        let f = mesh.channels.face[k] as usize;
        input.channel_mass_flux[k] =
            1000.0 * 1e-4 * mesh.face_normal[f][0] * mesh.face_length[f] * mesh.thickness;
    }
    let temperature = mesh
        .cell_centroid
        .iter()
        .map(|p| 300.0 + 20.0 * (p[0] * 40.0).sin() * (p[1] * 30.0).cos())
        .collect();
    let state = HeatState {
        time: 0.0,
        steps: 0,
        temperature,
    };
    (mesh, model, input, state)
}

fn bench(c: &mut Criterion) {
    let (mesh, model, input, state) = setup();
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let mut probe = HeatStepper::new();
    let limit = probe
        .stable_time_step(&model, &geometry, &mesh, &input, &state)
        .unwrap();
    let dt = 0.8 * limit;
    let mut group = c.benchmark_group("fvm_heat_200k_cells");
    group.sample_size(20);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let g = &geometry;
        let mut stepper = HeatStepper::new();
        let mut s = state.clone();
        stepper.prepare(&model, g, &mesh, &input, &s).unwrap();
        group.bench_function(format!("explicit_substep_{threads}_threads"), |b| {
            b.iter(|| {
                pool.install(|| {
                    stepper.face_values(&model, g, &mesh, &s.temperature, 0.0);
                    stepper.gradients(&model, g, &mesh, &s.temperature);
                    stepper.face_heat(&model, g, &mesh, &input, &s.temperature, 0.0);
                    stepper.channel_heat(&model, g, &mesh, &input, &s.temperature);
                    assert!(
                        stepper
                            .advance(g, &mesh, &mut s.temperature, dt * 1e-6)
                            .is_none()
                    );
                })
            })
        });
        let mut s = state.clone();
        group.bench_function(format!("explicit_outer_step_{threads}_threads"), |b| {
            b.iter(|| {
                pool.install(|| {
                    let r = stepper.step(&model, g, &mesh, &input, &mut s, dt).unwrap();
                    assert_eq!(r.substeps, 1);
                })
            })
        });
        let s = state.clone();
        group.bench_function(format!("prepare_{threads}_threads"), |b| {
            b.iter(|| pool.install(|| stepper.prepare(&model, g, &mesh, &input, &s).unwrap()))
        });
        let mut moved = geometry.clone();
        group.bench_function(
            format!("geometry_update_positions_{threads}_threads"),
            |b| b.iter(|| pool.install(|| moved.update_positions(&model, &mesh).unwrap())),
        );
        group.bench_function(format!("geometry_new_{threads}_threads"), |b| {
            b.iter(|| pool.install(|| HeatGeometry::new(&model, &mesh).unwrap()))
        });
    }
    group.finish();

    // Stage by stage, one thread.
    let mut group = c.benchmark_group("fvm_heat_200k_cells_stages_1_thread");
    group.sample_size(20);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let g = &geometry;
    let mut stepper = HeatStepper::new();
    let mut s = state.clone();
    stepper.prepare(&model, g, &mesh, &input, &s).unwrap();
    stepper.face_values(&model, g, &mesh, &s.temperature, 0.0);
    stepper.gradients(&model, g, &mesh, &s.temperature);
    group.bench_function("prepare", |b| {
        b.iter(|| pool.install(|| stepper.prepare(&model, g, &mesh, &input, &s).unwrap()))
    });
    group.bench_function("prepare_validate_input", |b| {
        b.iter(|| input.validate(&mesh).unwrap())
    });
    group.bench_function("prepare_cells", |b| {
        b.iter(|| pool.install(|| stepper.prepare_cells(&model, g, &mesh, &input, &s.temperature)))
    });
    group.bench_function("prepare_interfaces", |b| {
        b.iter(|| pool.install(|| stepper.prepare_interfaces(g)))
    });
    group.bench_function("prepare_channels", |b| {
        b.iter(|| pool.install(|| stepper.prepare_channels(&mesh)))
    });
    group.bench_function("stability_limit", |b| {
        b.iter(|| pool.install(|| stepper.stability_limit(&model, g, &mesh, &input)))
    });
    group.bench_function("face_values", |b| {
        b.iter(|| pool.install(|| stepper.face_values(&model, g, &mesh, &s.temperature, 0.0)))
    });
    group.bench_function("gradients_and_limiters", |b| {
        b.iter(|| pool.install(|| stepper.gradients(&model, g, &mesh, &s.temperature)))
    });
    group.bench_function("face_heat", |b| {
        b.iter(|| pool.install(|| stepper.face_heat(&model, g, &mesh, &input, &s.temperature, 0.0)))
    });
    group.bench_function("channel_heat", |b| {
        b.iter(|| pool.install(|| stepper.channel_heat(&model, g, &mesh, &input, &s.temperature)))
    });
    group.bench_function("face_heat_and_conductances", |b| {
        b.iter(|| {
            pool.install(|| {
                stepper.face_heat_and_conductances(&model, g, &mesh, &input, &s.temperature, 0.0)
            })
        })
    });
    group.bench_function("net_heat_and_stability_limit", |b| {
        b.iter(|| pool.install(|| stepper.net_heat_and_stability_limit(g, &mesh, &input)))
    });
    group.bench_function("apply_net_heat", |b| {
        b.iter(|| {
            pool.install(|| stepper.apply_net_heat(&mut s.temperature, 1e-9))
                .is_none()
        })
    });
    group.bench_function("advance", |b| {
        b.iter(|| {
            pool.install(|| stepper.advance(g, &mesh, &mut s.temperature, 1e-9))
                .is_none()
        })
    });
    group.finish();

    let rest = FlowInput {
        channel_mass_flux: vec![0.0; input.channel_mass_flux.len()],
        ..input.clone()
    };
    let mut group = c.benchmark_group("fvm_heat_200k_cells_implicit");
    group.sample_size(10);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut stepper = HeatStepper::new();
        let mut s = state.clone();
        group.bench_function(format!("implicit_step_{threads}_threads"), |b| {
            b.iter(|| {
                pool.install(|| {
                    stepper
                        .implicit_step(&model, &geometry, &mesh, &rest, &mut s, 10.0)
                        .unwrap()
                })
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
