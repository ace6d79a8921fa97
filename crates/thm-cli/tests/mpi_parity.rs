//! Under `mpirun -np N` (feature `mpi`; run by `.ci/run`): N ranks stepping a sheared,
//! heated 3 × 3 block of RVE material points give, on every rank, the same bits of the points
//! (positions, velocities, stresses, temperatures) and of every point's diagnostics as one
//! process without MPI; the ranks' RVEs match the serial run's for the points they own.
//! After a synchronisation every rank holds every RVE of the serial run. Then a block of one
//! rank fails (an RVE compressed to e^-2 in one step) and every rank returns an error naming
//! the failing rank and carrying its message.

use std::sync::Arc;

use thm_coupling::multiscale::distributed;
use thm_coupling::multiscale::{
    Collective, DemTimeRule, Distribution, MultiscaleError, MultiscaleParams, RveMaterial,
    RvePoint, ThreadGroup,
};
use thm_mpm::{
    GridParameters, MaterialPoints, Mpm, MpmConfig, MpmParameters, MpmState, NodeSet,
    PointProperties, Side, TemperatureCondition,
};
use thm_rve::{ConsolidationParams, PackingParams, RveParams, consolidate, random_packing};

fn block() -> (Mpm, MpmState<RvePoint>, RveMaterial) {
    let mut rp = RveParams::paper_b_table_1();
    rp.contact.friction_coefficient = 0.05;
    let config = rp.validate().unwrap();
    let mut pp = PackingParams::paper_b(3);
    pp.disk_count = 60;
    let mut packing = random_packing(&pp, &config).unwrap();
    consolidate(
        &mut packing,
        &config,
        &ConsolidationParams::isotropic(1e5, 0.05),
    )
    .unwrap();
    let params = MultiscaleParams {
        rve: rp,
        dem_time: DemTimeRule {
            step_fraction: 0.2,
            density_scaling: 100.0,
        },
        kelvin_offset: 273.15,
        quasi_static: None,
    };
    let mut p = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.1,
        cells: [5, 5],
    });
    p.temperature_conditions = vec![TemperatureCondition {
        nodes: NodeSet::Side(Side::Left),
        temperature: 40.0,
    }];
    let mpm_config = MpmConfig::new(p).unwrap();
    let material = RveMaterial::new(&params, packing).unwrap();
    let mut points = MaterialPoints::new();
    points
        .fill_rectangle(
            mpm_config.grid(),
            [0.1, 0.1],
            [0.4, 0.4],
            1,
            &PointProperties {
                density: 2650.0,
                specific_heat: 670.0,
                conductivity: [1.0, 1.0, 0.0],
                temperature: 0.0,
                velocity: [0.0; 2],
            },
        )
        .unwrap();
    for (v, x) in points.velocity.iter_mut().zip(&points.position) {
        *v = [2.0 * (x[1] - 0.25), -(x[0] - 0.25)];
    }
    let state = material.state(points);
    (Mpm::new(mpm_config), state, material)
}

const DT: f64 = 2e-4;
const STEPS: usize = 20;

fn main() {
    let Some((_universe, collective)) = thm_cli::mpi_rve::init() else {
        panic!("MPI was already initialised");
    };
    let collective: Arc<dyn Collective> =
        collective.unwrap_or_else(|| Arc::new(ThreadGroup::new(1).remove(0)));
    let (rank, size) = (collective.rank(), collective.size());

    let (mut mpm, mut serial, mut mat) = block();
    for _ in 0..STEPS {
        mpm.step_batch(&mut serial, &mut mat, DT).unwrap();
    }

    let (mut mpm, mut st, mut mat) = block();
    let dist = Distribution::shared(Arc::clone(&collective));
    mat.distribute(Arc::clone(&dist));
    for _ in 0..STEPS {
        mpm.step_batch(&mut st, &mut mat, DT).unwrap();
    }
    assert_eq!(format!("{:?}", st.points), format!("{:?}", serial.points));
    assert_eq!((st.time, st.step), (serial.time, serial.step));
    let mine = distributed::lock(&dist).blocks()[rank].clone();
    assert_eq!(distributed::lock(&dist).blocks().len(), size);
    for (i, (a, b)) in st.material.iter().zip(&serial.material).enumerate() {
        let diag = |p: &RvePoint| {
            format!(
                "{:?}",
                (
                    p.steps,
                    p.wave_modulus,
                    p.friction_work,
                    p.rve_volume,
                    p.inertial_number,
                    p.kinetic_ratio,
                    p.substeps,
                    p.intact_bonds
                )
            )
        };
        assert_eq!(diag(a), diag(b), "point {i}");
        if mine.contains(&i) {
            assert_eq!(a, b, "owned RVE {i} on rank {rank}");
        }
    }
    // After a synchronisation every rank holds every current RVE.
    distributed::lock(&dist)
        .synchronise(&mut st.material)
        .unwrap();
    assert_eq!(
        st.material, serial.material,
        "rank {rank} after synchronising"
    );
    let stats = distributed::lock(&dist).stats();
    let work: f64 = serial.material.iter().map(|p| p.friction_work).sum();
    assert!(work > 0.0, "no sliding: the test would not see the heat");

    // A failing block: the last point is squeezed to e^-2 of its width in one step.
    let (_, mut st, mut mat) = block();
    mat.distribute(Distribution::shared(Arc::clone(&collective)));
    let n = st.material.len();
    let inputs: Vec<_> = (0..n)
        .map(|point| thm_mpm::MaterialInput {
            point,
            velocity_gradient: if point + 1 == n {
                [-20000.0, 0.0, 0.0, 0.0]
            } else {
                [0.0; 4]
            },
            deformation_gradient: [1.0, 0.0, 0.0, 1.0],
            temperature: 20.0,
            temperature_rate: 0.0,
            stress: [0.0; 3],
            density: 2650.0,
            dt: 1e-4,
        })
        .collect();
    let mut out = vec![thm_mpm::MaterialResponse::default(); n];
    use thm_mpm::BatchConstitutive;
    let e = mat
        .respond_batch(&mut st.material, &inputs, &mut out)
        .unwrap_err();
    let last = size - 1;
    match &e {
        MultiscaleError::Distributed {
            process,
            exchange,
            message,
        } => {
            assert_eq!((*process, *exchange), (last, 0), "rank {rank}");
            assert!(
                message.contains(&format!("RVE of material point {}", n - 1)),
                "{message}"
            );
        }
        _ => panic!("rank {rank}: unexpected {e}"),
    }
    println!(
        "rank {rank}/{size}: {STEPS} steps bit-identical to the serial run (block {mine:?}); \
         per step: RVE block {:.3} ms, communication {:.3} ms; synchronising {:.3} ms; \
         failure: {e}",
        1e3 * stats.compute_seconds / STEPS as f64,
        1e3 * stats.comm_seconds / STEPS as f64,
        1e3 * stats.sync_seconds,
    );
}
