//! The MPM×DEM scheme (`thm_coupling::multiscale`): thread-count independence, save/restore,
//! friction heat against friction work, the DEM time rule, the sign and layout of the
//! exchange, and bad input.

use std::sync::{Arc, OnceLock};

use proptest::prelude::*;
use thm_coupling::multiscale::stages::{
    axial_moduli, contact_measures, dem_substeps, mpm_response,
};
use thm_coupling::multiscale::{
    DemTimeRule, Distribution, GranularRod, MultiscaleError, MultiscaleParams, PointOutcome,
    QuasiStaticLimits, RodModel, RveMaterial, RvePoint, ThreadGroup, distributed, partition,
    rve_cost,
};
use thm_mpm::{
    BatchConstitutive, GridParameters, MaterialInput, MaterialPoints, MaterialResponse, Mpm,
    MpmConfig, MpmParameters, MpmState, NodeSet, PointProperties, Side, TemperatureCondition,
};
use thm_rve::{
    ConsolidationParams, Mat2, PackingParams, RveParams, RveResponse, RveState, consolidate,
    measure, random_packing,
};

/// RVE parameters of the tests: B-Table 1 with μ = 0.05 (sliding at small strains).
fn rve_params() -> RveParams {
    let mut p = RveParams::paper_b_table_1();
    p.contact.friction_coefficient = 0.05;
    p
}

/// A 100-disk packing (radii in [0.25, 0.5] mm) consolidated to 100 kPa with μ = 0.05, made
/// once.
fn packing() -> &'static RveState {
    static PACKING: OnceLock<RveState> = OnceLock::new();
    PACKING.get_or_init(|| {
        let config = rve_params().validate().unwrap();
        let mut pp = PackingParams::paper_b(3);
        pp.disk_count = 100;
        let mut s = random_packing(&pp, &config).unwrap();
        consolidate(&mut s, &config, &ConsolidationParams::isotropic(1e5, 0.05)).unwrap();
        s
    })
}

fn params(density_scaling: f64) -> MultiscaleParams {
    MultiscaleParams {
        rve: rve_params(),
        dem_time: DemTimeRule {
            step_fraction: 0.2,
            density_scaling,
        },
        kelvin_offset: 273.15,
        quasi_static: None,
    }
}

/// A 3 × 3 block of material points (0.1 m cells) with an RVE each, sheared by an initial
/// velocity field `v_x = a (y − 0.25)`, `v_y = b (x − 0.25)`; the left side held at
/// `t_left` °C when given (adiabatic otherwise).
fn block(a: f64, b: f64, t_left: Option<f64>) -> (Mpm, MpmState<RvePoint>, RveMaterial) {
    let mut p = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: 0.1,
        cells: [5, 5],
    });
    if let Some(t) = t_left {
        p.temperature_conditions = vec![TemperatureCondition {
            nodes: NodeSet::Side(Side::Left),
            temperature: t,
        }];
    }
    let config = MpmConfig::new(p).unwrap();
    let material = RveMaterial::new(&params(100.0), packing().clone()).unwrap();
    let mut points = MaterialPoints::new();
    points
        .fill_rectangle(
            config.grid(),
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
        *v = [a * (x[1] - 0.25), b * (x[0] - 0.25)];
    }
    let state = material.state(points);
    (Mpm::new(config), state, material)
}

const DT: f64 = 2e-4;

fn json(st: &MpmState<RvePoint>) -> String {
    serde_json::to_string(st).unwrap()
}

/// 1 and 2 rayon threads give the same bits: points, RVEs (disks, contacts, cells) and
/// the diagnostics, over 30 heated, sheared steps.
#[test]
fn one_and_two_threads_give_the_same_bits() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let (mut mpm, mut st, mut mat) = block(2.0, -1.0, Some(40.0));
                for _ in 0..30 {
                    mpm.step_batch(&mut st, &mut mat, DT).unwrap();
                }
                let work: f64 = st.material.iter().map(|p| p.rve.friction_heat_total).sum();
                assert!(work > 0.0, "no sliding: the test would not see the heat");
                json(&st)
            })
    };
    let one = run(1);
    assert_eq!(one, run(2));
}

/// `ranks` processes simulated in one: each has its own material (scratch) and steps only
/// its block of points, re-balanced every step by [`rve_cost`]; the outcomes are then
/// gathered in point order, as a distributed run exchanges them.
#[derive(Debug)]
struct Blocked {
    materials: Vec<RveMaterial>,
    outcomes: Vec<PointOutcome>,
    blocks_seen: Vec<Vec<std::ops::Range<usize>>>,
}

impl BatchConstitutive for Blocked {
    type PointState = RvePoint;
    type Error = MultiscaleError;

    fn respond_batch(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MultiscaleError> {
        let costs: Vec<f64> = states.iter().map(rve_cost).collect();
        let blocks = partition(&costs, self.materials.len());
        self.outcomes.resize(states.len(), PointOutcome::default());
        // The blocks in reverse order: the order the processes finish in changes no bit.
        for (mat, b) in self.materials.iter_mut().zip(&blocks).rev() {
            mat.step_block(
                &mut states[b.clone()],
                &inputs[b.clone()],
                b.start,
                &mut self.outcomes[b.clone()],
            )?;
        }
        self.materials[0].finish(states, &self.outcomes, responses);
        self.blocks_seen.push(blocks);
        self.materials[0].check_quasi_static(states)
    }

    fn wave_modulus(&self, state: &RvePoint) -> f64 {
        state.wave_modulus
    }
}

/// Stepping the points in 2 and 3 cost-balanced blocks (re-balanced every step) gives the
/// same bits as one batch over 30 heated, sheared steps: the seam a distributed run splits
/// at changes nothing.
#[test]
fn blocks_of_points_give_the_same_bits_as_one_batch() {
    let whole = {
        let (mut mpm, mut st, mut mat) = block(2.0, -1.0, Some(40.0));
        for _ in 0..30 {
            mpm.step_batch(&mut st, &mut mat, DT).unwrap();
        }
        json(&st)
    };
    for ranks in [1, 2, 3] {
        let (mut mpm, mut st, mat) = block(2.0, -1.0, Some(40.0));
        let mut blocked = Blocked {
            materials: vec![mat; ranks],
            outcomes: Vec::new(),
            blocks_seen: Vec::new(),
        };
        for _ in 0..30 {
            mpm.step_batch(&mut st, &mut blocked, DT).unwrap();
        }
        assert_eq!(json(&st), whole, "{ranks} blocks");
        // Every block was non-empty and the blocks covered the 9 points in order.
        for blocks in &blocked.blocks_seen {
            assert_eq!(blocks.len(), ranks);
            assert_eq!(blocks[0].start, 0);
            assert_eq!(blocks[ranks - 1].end, 9);
            for w in blocks.windows(2) {
                assert_eq!(w[0].end, w[1].start);
            }
            assert!(blocks.iter().all(|b| !b.is_empty()), "{blocks:?}");
        }
    }
}

/// The partition balances the cost prefix sums: a heavy point gets a block alone, equal
/// costs split evenly, zero costs split by count, and more parts than points leave the
/// surplus blocks empty at the end.
#[test]
fn partition_balances_contiguous_blocks_by_cost() {
    assert_eq!(partition(&[1.0; 6], 3), vec![0..2, 2..4, 4..6]);
    assert_eq!(partition(&[10.0, 1.0, 1.0, 1.0, 1.0], 2), vec![0..1, 1..5]);
    assert_eq!(partition(&[1.0, 1.0, 1.0, 1.0, 10.0], 2), vec![0..4, 4..5]);
    assert_eq!(partition(&[0.0; 4], 2), vec![0..2, 2..4]);
    assert_eq!(partition(&[f64::NAN, -1.0, 0.0, 0.0], 2), vec![0..2, 2..4]);
    assert_eq!(partition(&[1.0, 1.0], 3), vec![0..1, 1..2, 2..2]);
    assert_eq!(partition(&[], 2), vec![0..0, 0..0]);
    assert_eq!(partition(&[5.0, 5.0, 5.0], 1), vec![0..3]);
}

/// A [`Distribution`] over 1, 2 and 3 processes (threads of this test, [`ThreadGroup`]):
/// 30 heated, sheared steps with a synchronisation (and re-balancing) every 7 give, on every
/// process, the points and diagnostics of one batch at every step; after the last
/// synchronisation every process holds every RVE of the run on one process.
#[test]
fn processes_of_a_distribution_keep_the_bits_of_one_batch() {
    let whole = {
        let (mut mpm, mut st, mut mat) = block(2.0, -1.0, Some(40.0));
        for _ in 0..30 {
            mpm.step_batch(&mut st, &mut mat, DT).unwrap();
        }
        json(&st)
    };
    for size in [1, 2, 3] {
        let results: Vec<(String, Vec<std::ops::Range<usize>>, f64)> = ThreadGroup::new(size)
            .into_iter()
            .map(|handle| {
                std::thread::spawn(move || {
                    let (mut mpm, mut st, mut mat) = block(2.0, -1.0, Some(40.0));
                    let d = Distribution::shared(Arc::new(handle));
                    mat.distribute(Arc::clone(&d));
                    for step in 1..=30 {
                        mpm.step_batch(&mut st, &mut mat, DT).unwrap();
                        if step % 7 == 0 || step == 30 {
                            distributed::lock(&d).synchronise(&mut st.material).unwrap();
                        }
                    }
                    let g = distributed::lock(&d);
                    (
                        json(&st),
                        g.blocks().to_vec(),
                        g.stats().predicted_imbalance,
                    )
                })
            })
            .collect::<Vec<_>>()
            .into_iter()
            .map(|h| h.join().unwrap())
            .collect();
        for (rank, (state, blocks, imbalance)) in results.iter().enumerate() {
            assert!(*state == whole, "{size} processes: process {rank} differs");
            assert_eq!(blocks, &results[0].1, "the same blocks everywhere");
            assert_eq!(blocks.len(), size);
            assert!(*imbalance >= 1.0 && imbalance.is_finite());
        }
    }
}

/// A block that fails on one process ends the exchange on every process with that
/// process's message: the last point squeezed to e^-2 of its width in one step.
#[test]
fn a_failing_block_fails_every_process_with_its_message() {
    let results: Vec<MultiscaleError> = ThreadGroup::new(3)
        .into_iter()
        .map(|handle| {
            std::thread::spawn(move || {
                let (_, mut st, mut mat) = block(0.0, 0.0, None);
                mat.distribute(Distribution::shared(Arc::new(handle)));
                let n = st.material.len();
                let inputs: Vec<_> = (0..n)
                    .map(|point| MaterialInput {
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
                let mut out = vec![MaterialResponse::default(); n];
                mat.respond_batch(&mut st.material, &inputs, &mut out)
                    .unwrap_err()
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .map(|h| h.join().unwrap())
        .collect();
    for e in &results {
        assert_eq!(e, &results[0]);
        match e {
            MultiscaleError::Distributed {
                process, message, ..
            } => {
                assert_eq!(*process, 2);
                assert!(
                    message.contains("RVE of material point 8 failed"),
                    "{message}"
                );
            }
            other => panic!("unexpected {other}"),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// The partition's invariants: `parts` contiguous blocks covering every point in order,
    /// none empty while there are points enough, and no block heavier than its fair share
    /// plus the heaviest single point (the prefix-sum cut).
    #[test]
    fn partition_is_contiguous_complete_and_balanced(
        costs in proptest::collection::vec(0.0f64..100.0, 0..60),
        parts in 1usize..9,
    ) {
        let blocks = partition(&costs, parts);
        prop_assert_eq!(blocks.len(), parts);
        prop_assert_eq!(blocks[0].start, 0);
        prop_assert_eq!(blocks[parts - 1].end, costs.len());
        for w in blocks.windows(2) {
            prop_assert_eq!(w[0].end, w[1].start);
        }
        if costs.len() >= parts {
            prop_assert!(blocks.iter().all(|b| !b.is_empty()), "{:?}", blocks);
        }
        let total: f64 = costs.iter().sum();
        let heaviest = costs.iter().copied().fold(0.0_f64, f64::max);
        for b in &blocks {
            let cost: f64 = costs[b.clone()].iter().sum();
            prop_assert!(
                cost <= total / parts as f64 + 2.0 * heaviest + 1e-9 * total,
                "block {:?} costs {} of {}", b, cost, total
            );
        }
        prop_assert_eq!(partition(&costs, parts), blocks);
    }
}

/// Saving the state mid-run (RVE states included, serde) and continuing with a fresh
/// stepper and material gives the same bits as the run without the break.
#[test]
fn save_and_restore_continue_bit_for_bit() {
    let (mut mpm, mut st, mut mat) = block(2.0, -1.0, Some(40.0));
    for _ in 0..15 {
        mpm.step_batch(&mut st, &mut mat, DT).unwrap();
    }
    let saved = json(&st);
    for _ in 0..15 {
        mpm.step_batch(&mut st, &mut mat, DT).unwrap();
    }
    let (mut mpm2, _, mut mat2) = block(2.0, -1.0, Some(40.0));
    let mut restored: MpmState<RvePoint> = serde_json::from_str(&saved).unwrap();
    for _ in 0..15 {
        mpm2.step_batch(&mut restored, &mut mat2, DT).unwrap();
    }
    assert_eq!(json(&st), json(&restored));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(6))]

    /// Friction heat equals friction work. Per RVE and step, the heat source returned to the
    /// point times the RVE volume and Δt is the friction work of its DEM steps (B-Eqs. 32–33)
    /// to round-off; and in the adiabatic block the thermal energy `Σ m_p c_p T_p` of the MPM
    /// grows in each step by exactly `Σ_p Q_p V_p Δt` of the previous exchange, so over the
    /// run it receives `Σ_p Σ_steps W_f,p V_p / V_RVE,p` (the friction work of the RVEs at the
    /// points' volumes) to round-off.
    #[test]
    fn friction_heat_equals_friction_work(a in 1.0f64..4.0, b in -3.0f64..-0.5) {
        let (mut mpm, mut st, mut mat) = block(a, b, None);
        let energy = |st: &MpmState<RvePoint>| -> f64 {
            let p = &st.points;
            (0..p.len()).map(|i| p.mass[i] * p.specific_heat[i] * p.temperature[i]).sum()
        };
        let mut total_work = 0.0;
        let mut delivered_total = 0.0;
        for _ in 0..25 {
            let e0 = energy(&st);
            let delivered: f64 = (0..st.points.len())
                .map(|i| st.points.heat_source[i] * st.points.volume[i] * DT)
                .sum();
            mpm.step_batch(&mut st, &mut mat, DT).unwrap();
            let e1 = energy(&st);
            let scale = delivered.abs().max(1e-300);
            prop_assert!((e1 - e0 - delivered).abs() <= 1e-11 * scale + 1e-300,
                "ΔE = {} vs delivered {}", e1 - e0, delivered);
            for (q, pt) in st.points.heat_source.iter().zip(&st.material) {
                // W_f is the change of the RVE's running total (consolidation included), so its
                // round-off is that of N additions to the total.
                let heat = q * pt.rve_volume * DT;
                let round_off = 4.0 * f64::from(pt.substeps) * f64::EPSILON * pt.rve.friction_heat_total;
                prop_assert!((heat - pt.friction_work).abs() <= round_off,
                    "Q V dt = {heat} vs W_f = {} (round-off {round_off})", pt.friction_work);
                total_work += pt.friction_work;
            }
            delivered_total += delivered;
        }
        prop_assert!(total_work > 0.0 && delivered_total > 0.0);
    }
}

/// The DEM time rule: the same consolidated RVE driven by the same history (compression,
/// shear and heating by 10 K, 0.02 s in 200 MPM steps of 10⁻⁴ s, μ = 0.5 while shearing as in
/// B-Sect. 5.3.1, no damping) with the disks density-scaled by `s = 1, 4, 16` (N = 80, 40, 20
/// DEM steps per MPM step) stays within the rule's quasi-static limits (I ≤ 10⁻³, kinetic
/// ≤ 1 % of elastic energy: the run stops otherwise), and its stresses agree with the `s = 1`
/// run, relative to the largest stress change of that run: within 2.5 % over the whole history
/// (measured 2.1 % and 1.8 %, in the first steps, where L is switched on at once and the RVE's
/// own response time, ∝ √s, shows), within 1.5 % from 2 ms on (1.1 %, 1.4 %) and within 0.2 %
/// at the end (0.05 %, 0.16 %). The same history 100 times faster (I ≈ 0.02 at s = 16) is
/// stopped by the rule's check, naming the point and the quantity.
#[test]
fn dem_time_rule_does_not_change_the_response() {
    let history = |s: f64, rate: f64| -> Result<(Vec<Mat2>, u32), MultiscaleError> {
        let mut p = params(s);
        p.rve.contact.friction_coefficient = 0.5;
        p.quasi_static = Some(QuasiStaticLimits::default());
        let mut mat = RveMaterial::new(&p, packing().clone())?;
        let mut points = vec![mat.initial_point()];
        let mut out = vec![MaterialResponse {
            stress: [0.0; 3],
            heat_source: 0.0,
            conductivity: [0.0; 3],
        }];
        let mut stress = Vec::new();
        let dt = 1e-4;
        for n in 0..200 {
            let t = n as f64 * dt;
            let input = MaterialInput {
                point: 0,
                velocity_gradient: [-0.2 * rate, 0.3 * rate, 0.3 * rate, 0.1 * rate],
                deformation_gradient: [1.0, 0.0, 0.0, 1.0],
                temperature: 20.0 + 500.0 * t,
                temperature_rate: 500.0,
                stress: [0.0; 3],
                density: 2650.0,
                dt,
            };
            mat.respond_batch(&mut points, &[input], &mut out)?;
            let s = out[0].stress;
            stress.push(Mat2::new(s[0], s[2], s[2], s[1]));
        }
        Ok((stress, points[0].substeps))
    };
    let (reference, n1) = history(1.0, 1.0).unwrap();
    assert_eq!(n1, 80);
    let s0 = measure::stress(packing(), 0.075).scale(-1.0);
    let change = reference
        .iter()
        .map(|s| s.add_scaled(&s0, -1.0).max_abs())
        .fold(0.0_f64, f64::max);
    assert!(change > 5e4, "the history must load the RVE: {change} Pa");
    for (scaling, expect_n) in [(4.0, n1 / 2), (16.0, n1 / 4)] {
        let (h, n) = history(scaling, 1.0).unwrap();
        assert_eq!(n, expect_n);
        let diff_from = |k: usize| {
            h[k..]
                .iter()
                .zip(&reference[k..])
                .map(|(a, b)| a.add_scaled(b, -1.0).max_abs())
                .fold(0.0_f64, f64::max)
                / change
        };
        let end = h[199].add_scaled(&reference[199], -1.0).max_abs() / change;
        assert!(diff_from(0) <= 0.025, "s = {scaling}: {}", diff_from(0));
        assert!(diff_from(20) <= 0.015, "s = {scaling}: {}", diff_from(20));
        assert!(end <= 0.002, "s = {scaling}: final stress differs by {end}");
    }
    match history(16.0, 100.0) {
        Err(MultiscaleError::NotQuasiStatic {
            point: 0,
            quantity,
            value,
            ..
        }) => assert!(quantity == "inertial number" && value > 1e-3, "{value}"),
        other => panic!("a fast history must stop: {:?}", other.map(|h| h.1)),
    }
}

/// N = ⌈Δt / (c √(m/k_n))⌉, at least one; halving the DEM step limit doubles N.
#[test]
fn dem_substeps_follow_the_rule() {
    assert_eq!(dem_substeps(1e-4, 1.5625e-8 * 1e6, 1e6, 0.2), 4);
    assert_eq!(dem_substeps(1e-4, 1e-2, 1e6, 0.2), 5);
    assert_eq!(dem_substeps(1e-4, 4e-2, 1e6, 0.2), 3);
    assert_eq!(dem_substeps(1e-9, 1.0, 1.0, 0.2), 1);
}

/// The point receives the RVE's stress with the sign turned (compression positive →
/// tension positive), the symmetric parts of stress and conductivity, and the heat source.
#[test]
fn the_exchange_turns_the_sign_and_keeps_the_layout() {
    let r = RveResponse {
        stress: Mat2::new(100.0, 10.0, 30.0, 200.0),
        heat_source: 5.0,
        conductivity: Mat2::new(1.0, 0.2, 0.4, 2.0),
    };
    let m = mpm_response(&r);
    assert_eq!(m.stress, [-100.0, -200.0, -20.0]);
    assert_eq!(m.conductivity, [1.0, 2.0, 0.30000000000000004]);
    assert_eq!(m.heat_source, 5.0);
    // An isotropically consolidated packing is in compression on the MPM side.
    let mat = RveMaterial::new(&params(1.0), packing().clone()).unwrap();
    let s = mat.initial_response().stress;
    assert!(s[0] < -9e4 && s[1] < -9e4, "{s:?}");
}

/// B-Eq. 58's axial entries computed alone equal those of the full tensor, and on the rod's
/// square lattice `D_xxxx = k_n / z_p` (B-Table 1's E = 13.3 MPa) up to the overlap.
#[test]
fn axial_moduli_match_the_stiffness_tensor() {
    let p = rve_params();
    let d = measure::stiffness(packing(), &p);
    let a = axial_moduli(packing(), &p);
    // The fused pass of the exchange gives the same moduli and the elastic energy of
    // thm-rve's own measure, to the bit.
    let m = contact_measures(packing(), &p);
    assert_eq!(m.axial_moduli, a);
    let e = measure::elastic_energy(packing(), &p);
    assert!(e > 0.0);
    assert_eq!(m.elastic_energy.to_bits(), e.to_bits());
    assert!((a[0] - d[0][0][0][0]).abs() <= 1e-12 * a[0]);
    assert!((a[1] - d[1][1][1][1]).abs() <= 1e-12 * a[1]);
    let rod = RodModel::new(&GranularRod::paper()).unwrap();
    let k = rod.axial_stiffness();
    let kn_over_z = 1e6 / 0.075;
    assert!((k - kn_over_z).abs() <= 1e-9 * kn_over_z, "{k}");
}

/// The rod's RVE starts at the consolidation stress (both normal stresses 100 kPa) and
/// conducts B-Table 1's 0.1 W/(m K) along and across the rod.
#[test]
fn rod_lattice_is_consolidated_and_conducts_k() {
    let rod = RodModel::new(&GranularRod::paper()).unwrap();
    let s = rod.state.points.stress[0];
    let k = rod.state.points.conductivity[0];
    for v in [s[0], s[1]] {
        assert!((v + 1e5).abs() <= 1e-9 * 1e5, "{s:?}");
    }
    assert!(s[2].abs() <= 1e-6, "{s:?}");
    assert!(
        (k[0] - 0.1).abs() <= 1e-12 && (k[1] - 0.1).abs() <= 1e-12,
        "{k:?}"
    );
}

/// Bad input: a packing made with another density (or thickness) is refused naming the
/// mismatch; out-of-range parameters name their key path.
#[test]
fn bad_input_names_the_field() {
    let mut wrong = params(1.0);
    wrong.rve.density = 2000.0;
    let e = RveMaterial::new(&wrong, packing().clone()).unwrap_err();
    assert!(matches!(e, MultiscaleError::PackingMismatch { .. }), "{e}");
    let mut p = params(1.0);
    p.dem_time.density_scaling = 0.5;
    let e = RveMaterial::new(&p, packing().clone()).unwrap_err();
    assert!(
        matches!(
            e,
            MultiscaleError::InvalidParameter {
                field: "dem_time.density_scaling",
                ..
            }
        ),
        "{e}"
    );
    let mut p = params(1.0);
    p.dem_time.step_fraction = 0.9;
    let e = RveMaterial::new(&p, packing().clone()).unwrap_err();
    assert!(e.to_string().contains("dem_time.step_fraction"), "{e}");
    let text = r#"{"rve": {}, "kelvin_offset": 273.15, "extra": 1}"#;
    assert!(serde_json::from_str::<MultiscaleParams>(text).is_err());
}

/// An RVE whose cell degenerates (too narrow for its neighbour search) stops the step naming
/// the point, the MPM step and the cell strain.
#[test]
fn degenerate_rve_names_point_step_and_strain() {
    let mut mat = RveMaterial::new(&params(1.0), packing().clone()).unwrap();
    let mut points = vec![mat.initial_point(), mat.initial_point()];
    let mut out = vec![
        MaterialResponse {
            stress: [0.0; 3],
            heat_source: 0.0,
            conductivity: [0.0; 3],
        };
        2
    ];
    let input = |point: usize, l: [f64; 4]| MaterialInput {
        point,
        velocity_gradient: l,
        deformation_gradient: [1.0, 0.0, 0.0, 1.0],
        temperature: 20.0,
        temperature_rate: 0.0,
        stress: [0.0; 3],
        density: 2650.0,
        dt: 1e-4,
    };
    // Point 1 is compressed to e^-2 of its width within one step.
    let inputs = [input(0, [0.0; 4]), input(1, [-20000.0, 0.0, 0.0, 0.0])];
    let e = mat
        .respond_batch(&mut points, &inputs, &mut out)
        .unwrap_err();
    match e {
        MultiscaleError::Rve {
            point,
            step,
            volumetric_strain,
            ..
        } => {
            assert_eq!(point, 1);
            assert_eq!(step, 0);
            assert!(volumetric_strain < -0.1, "{volumetric_strain}");
        }
        other => panic!("{other}"),
    }
}

/// The orthotropic slab product with equal diffusivities is B-Eq. 59 (as recomputed in
/// `thm-mpm`): `T₁ − ΔT θ(x) θ(y)`.
#[test]
fn slab_product_is_b_eq_59() {
    use thm_coupling::multiscale::square::slab_factor;
    for t in [0.01, 0.1, 0.5, 1.0] {
        for (x, y) in [(0.5, 0.5), (0.2, 0.7), (0.05, 0.5)] {
            let ours = 100.0 * (1.0 - slab_factor(x, 1.0, 0.1, t) * slab_factor(y, 1.0, 0.1, t));
            let theirs =
                thm_mpm::analytical::heated_square_temperature(x, y, 1.0, 0.1, t, 0.0, 100.0);
            assert!(
                (ours - theirs).abs() < 1e-9,
                "t {t}, ({x}, {y}): {ours} vs {theirs}"
            );
        }
    }
}

/// The square's RVE conducts B-Table 1's k on average, its points start at the consolidation
/// stress, and the twin's affine moduli have ν = 0 (`D_xxyy = 0` for `k_n = k_t`).
#[test]
fn square_model_matches_its_packing() {
    use thm_coupling::multiscale::square::{GranularSquare, SquareModel};
    let m = SquareModel::new(&GranularSquare::reduced(4, 100, 1e4)).unwrap();
    let k = m.state.points.conductivity[0];
    assert!((0.5 * (k[0] + k[1]) - 0.1).abs() < 1e-12, "{k:?}");
    let s = m.state.points.stress[0];
    assert!((0.5 * (s[0] + s[1]) + 1e5).abs() < 0.01 * 1e5, "{s:?}");
    assert!(m.twin_moduli[1].abs() < 1e-9, "{:?}", m.twin_moduli);
    assert!(
        m.twin_moduli[0] > 5e6 && m.twin_moduli[0] < 3e7,
        "{:?}",
        m.twin_moduli
    );
}

/// A 2 × 2 square of 30-disk RVEs (density-scaled so that one MPM step is a few DEM steps).
fn small_square() -> thm_coupling::multiscale::square::SquareModel {
    use thm_coupling::multiscale::square::{GranularSquare, SquareModel};
    SquareModel::new(&GranularSquare::reduced(2, 30, 1e3)).unwrap()
}

fn square_json(m: &thm_coupling::multiscale::square::SquareModel) -> String {
    json(&m.state) + &serde_json::to_string(&m.twin_state).unwrap()
}

/// The square (B-Sect. 5.2.2) on 1 and 2 rayon threads: the same bits, RVEs and twin
/// included, over 20 steps of the heating.
#[test]
fn square_one_and_two_threads_give_the_same_bits() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut m = small_square();
                for _ in 0..20 {
                    m.step().unwrap();
                }
                assert!(m.friction_heat_of_step() > 0.0, "no sliding seen");
                square_json(&m)
            })
    };
    let one = run(1);
    assert_eq!(one, run(2));
}

/// Saving both states of the square mid-run and continuing with freshly built steppers and
/// materials gives the same bits as the run without the break.
#[test]
fn square_save_and_restore_continue_bit_for_bit() {
    let mut m = small_square();
    for _ in 0..10 {
        m.step().unwrap();
    }
    let saved = (
        json(&m.state),
        serde_json::to_string(&m.twin_state).unwrap(),
    );
    for _ in 0..10 {
        m.step().unwrap();
    }
    let mut again = small_square();
    again.state = serde_json::from_str(&saved.0).unwrap();
    again.twin_state = serde_json::from_str(&saved.1).unwrap();
    for _ in 0..10 {
        again.step().unwrap();
    }
    assert_eq!(square_json(&m), square_json(&again));
}

/// With the friction heat off the points receive no heat source, while the RVEs still
/// dissipate (and report) their friction work.
#[test]
fn square_without_friction_heat_reports_but_does_not_apply_it() {
    use thm_coupling::multiscale::square::{GranularSquare, SquareModel};
    let mut sq = GranularSquare::reduced(2, 30, 1e3);
    sq.friction_heat = false;
    let mut m = SquareModel::new(&sq).unwrap();
    let mut work = 0.0;
    for _ in 0..20 {
        m.step().unwrap();
        assert!(m.state.points.heat_source.iter().all(|q| *q == 0.0));
        work += m.friction_heat_of_step();
    }
    assert!(work > 0.0);
}

/// The TM-MPM twin of the rod (B-Fig. 9(a–c)) follows B-Eqs. 55–57 with `K = E`: at 0.4 s
/// (the paper's "quasi-static after 0.4 s") the temperature within 0.5 °C, the stress change
/// within 3 % of `E β ΔT` and the displacement within 3 % of `β ΔT L / 8` at every point.
#[test]
fn rod_twin_follows_b_eqs_55_to_57() {
    use thm_coupling::multiscale::RodTwin;
    use thm_coupling::multiscale::rod::{
        TWIN_YOUNGS_MODULUS, rod_displacement, rod_displacements, rod_stress, rod_temperature,
    };
    let rod = GranularRod::paper();
    let mut twin = RodTwin::new(&rod).unwrap();
    let steps = (0.4 / rod.time_step).round() as u64;
    for _ in 0..steps {
        twin.step().unwrap();
    }
    let t = steps as f64 * rod.time_step;
    let (l, t0, t1, kappa) = (
        rod.length,
        rod.cold_temperature,
        rod.hot_temperature,
        rod.diffusivity(),
    );
    let beta = rod.rve.thermal_expansion_coefficient;
    let e = TWIN_YOUNGS_MODULUS;
    let sigma = rod_stress(t, l, t0, t1, kappa, e, beta);
    let u = rod_displacements(&rod, &twin.state.points);
    let h = rod.cell_size();
    for (p, ((temp, s), u)) in twin
        .state
        .points
        .remapped_temperature
        .iter()
        .zip(&twin.state.points.stress)
        .zip(&u)
        .enumerate()
    {
        let x = (p as f64 + 0.5) * h;
        let want_t = rod_temperature(x, t, l, t0, t1, kappa);
        assert!(
            (temp - want_t).abs() <= 0.5,
            "point {p}: T {temp} vs {want_t}"
        );
        assert!(
            (s[0] - sigma).abs() <= 0.03 * e * beta * (t1 - t0),
            "point {p}: sigma_x {} vs {sigma}",
            s[0]
        );
        let want_u = rod_displacement(x, t, l, t0, t1, kappa, beta);
        assert!(
            (u - want_u).abs() <= 0.03 * beta * (t1 - t0) * l / 8.0,
            "point {p}: u {u} vs {want_u}"
        );
    }
}
