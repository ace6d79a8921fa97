//! Driver for profiling and regression: `heat_driver hash` prints a hash of the temperature
//! bits after a few outer steps for several models; `heat_driver profile NX NY STEPS` runs
//! outer steps on the benchmark's mesh (for callgrind).

use thm_fvm_heat::{
    BoundaryCondition, BoundaryParams, FlowInput, GradientScheme, HeatGeometry, HeatModel,
    HeatParams, HeatState, HeatStepper, InterfaceModel, TemperatureSchedule,
};
use thm_vpn_mesh::{BoundarySide, CellKind, NONE, PoreMesh};

fn setup(nx: usize, ny: usize) -> (PoreMesh, FlowInput, HeatState) {
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
    (mesh, input, state)
}

fn hash(t: &[f64]) -> u64 {
    let mut h = 0xcbf29ce484222325u64;
    for v in t {
        h ^= v.to_bits();
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mode = args.get(1).map(String::as_str).unwrap_or("hash");
    if mode == "stage" {
        // heat_driver stage NAME REPS: one stage REPS times on a 250 x 100 mesh (callgrind).
        let name = args.get(2).cloned().unwrap_or_default();
        let reps: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(10);
        let (mesh, input, mut state) = setup(250, 100);
        let model = HeatModel::new(&HeatParams::paper_a_table_1(), &mesh).unwrap();
        let g = &HeatGeometry::new(&model, &mesh).unwrap();
        let mut st = HeatStepper::new();
        st.prepare(&model, g, &mesh, &input, &state).unwrap();
        let t = &mut state.temperature;
        stages::prime(&mut st, &model, g, &mesh, &input, t);
        for _ in 0..reps {
            stages::run(&name, &mut st, &model, g, &mesh, &input, t);
        }
        println!("{:016x}", hash(t));
        return;
    }
    if mode == "profile" {
        let nx: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(500);
        let ny: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(200);
        let steps: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(5);
        let (mesh, input, mut state) = setup(nx, ny);
        let model = HeatModel::new(&HeatParams::paper_a_table_1(), &mesh).unwrap();
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let mut stepper = HeatStepper::new();
        let limit = stepper
            .stable_time_step(&model, &geometry, &mesh, &input, &state)
            .unwrap();
        for _ in 0..steps {
            stepper
                .step(&model, &geometry, &mesh, &input, &mut state, 0.8 * limit)
                .unwrap();
        }
        println!("{:016x}", hash(&state.temperature));
        return;
    }
    for (nx, ny) in [(40usize, 24usize), (120, 60)] {
        for (name, gradient, interface, bcs) in [
            (
                "ls-nusselt",
                GradientScheme::LeastSquares,
                InterfaceModel::Nusselt,
                false,
            ),
            (
                "ls-nusselt-bc",
                GradientScheme::LeastSquares,
                InterfaceModel::Nusselt,
                true,
            ),
            (
                "gg-nusselt-bc",
                GradientScheme::GreenGauss,
                InterfaceModel::Nusselt,
                true,
            ),
            (
                "ls-continuous-bc",
                GradientScheme::LeastSquares,
                InterfaceModel::Continuous,
                true,
            ),
        ] {
            let (mesh, mut input, mut state) = setup(nx, ny);
            let mut params = HeatParams::paper_a_table_1();
            params.gradient = gradient;
            params.interface = interface;
            if bcs {
                params.boundaries = vec![
                    BoundaryParams {
                        side: BoundarySide::Left,
                        condition: BoundaryCondition::Temperature {
                            temperature: TemperatureSchedule::Table {
                                time: vec![0.0, 1.0],
                                temperature: vec![290.0, 330.0],
                            },
                        },
                    },
                    BoundaryParams {
                        side: BoundarySide::Right,
                        condition: BoundaryCondition::Convective {
                            coefficient: 500.0,
                            ambient_temperature: 280.0,
                        },
                    },
                    BoundaryParams {
                        side: BoundarySide::Top,
                        condition: BoundaryCondition::HeatFlux { flux: 2e4 },
                    },
                ];
                // Open boundary: the channel flux continues through fluid faces on the left
                // and right sides (in on the left, out on the right).
                for f in 0..mesh.n_faces() {
                    let [c0, c1] = mesh.face_cells[f];
                    if c1 == NONE && mesh.cell_kind[c0 as usize].is_fluid() {
                        let nx_ = mesh.face_normal[f][0];
                        if nx_.abs() > 0.5 {
                            input.boundary_mass_flux[f] =
                                1000.0 * 1e-4 * nx_ * mesh.face_length[f] * mesh.thickness;
                        }
                    }
                }
                // Some gas in places.
                for c in 0..mesh.n_cells() {
                    if c % 7 == 0 {
                        input.liquid_fraction[c] = 0.3;
                    }
                }
            }
            let model = HeatModel::new(&params, &mesh).unwrap();
            let geometry = HeatGeometry::new(&model, &mesh).unwrap();
            let mut stepper = HeatStepper::new();
            let limit = stepper
                .stable_time_step(&model, &geometry, &mesh, &input, &state)
                .unwrap();
            let mut subs = 0;
            for _ in 0..4 {
                let r = stepper
                    .step(&model, &geometry, &mesh, &input, &mut state, 2.5 * limit)
                    .unwrap();
                subs += r.substeps;
            }
            println!(
                "{nx}x{ny} {name}: limit {:e} substeps {subs} hash {:016x} mean {:.12}",
                limit,
                hash(&state.temperature),
                state.temperature.iter().sum::<f64>() / state.temperature.len() as f64
            );
        }
    }
}

mod stages {
    use super::*;
    pub fn prime(
        st: &mut HeatStepper,
        model: &HeatModel,
        g: &HeatGeometry,
        mesh: &PoreMesh,
        _input: &FlowInput,
        t: &mut [f64],
    ) {
        st.face_values(model, g, mesh, t, 0.0);
        st.gradients(model, g, mesh, t);
    }
    pub fn run(
        name: &str,
        st: &mut HeatStepper,
        model: &HeatModel,
        g: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        t: &mut [f64],
    ) {
        match name {
            "none" => {}
            "prepare" => {
                let s = HeatState {
                    time: 0.0,
                    steps: 0,
                    temperature: t.to_vec(),
                };
                st.prepare(model, g, mesh, input, &s).unwrap()
            }
            "validate" => input.validate(mesh).unwrap(),
            "cells" => {
                st.prepare_cells(model, g, mesh, input, t);
            }
            "interfaces" => st.prepare_interfaces(g),
            "channels" => st.prepare_channels(mesh),
            "stability" => {
                std::hint::black_box(st.stability_limit(model, g, mesh, input));
            }
            "values" => st.face_values(model, g, mesh, t, 0.0),
            "gradients" => st.gradients(model, g, mesh, t),
            "face_heat" => st.face_heat(model, g, mesh, input, t, 0.0),
            "channel_heat" => st.channel_heat(model, g, mesh, input, t),
            "advance" => {
                st.advance(g, mesh, t, 1e-9);
            }
            _ => panic!("unknown stage {name}"),
        }
    }
}
