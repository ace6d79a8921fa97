//! Bit-for-bit parity of the RVE kernel: `RveStepper` (directly and through `RveBatch` on 1,
//! 2 and 3 threads) against a plain reference kept here, which steps the state the way the
//! crate did before its contact loop was packed (one disk record gather per contact through
//! `thm_dem`'s generic contact law, force arrays zeroed and summed in list order, integration
//! straight from the state's arrays). The batch has intact bonds, bonds melted by heating,
//! a large simple shear and a stretch (pair-list rebuilds, disks wrapped across the cell,
//! cell reductions), damping and none. Every `f64` of the states and responses is compared
//! through its bits, so signed zeros and NaN payloads count.

use thm_dem::{
    BondState, ContactHistory, ContactKinematics, ContactLaw, PairInput, ThermalBondParams, Vec2,
    Vec3,
};
use thm_rve::neighbour::{Candidate, PeriodicGrid};
use thm_rve::verification::consolidated_packing;
use thm_rve::*;

/// The plain reference step.
mod reference {
    use super::*;

    pub struct Reference {
        pub config: RveConfig,
        grid: PeriodicGrid,
        candidates: Vec<Candidate>,
    }

    impl Reference {
        pub fn new(config: RveConfig) -> Self {
            Self {
                config,
                grid: PeriodicGrid::default(),
                candidates: Vec::new(),
            }
        }

        pub fn respond(&mut self, state: &mut RveState, load: &RveLoad) -> RveResponse {
            let p = *self.config.params();
            let t = load.temperature;
            if !state.disks.temperature.iter().all(|&x| x == t) {
                let temps = vec![t; state.len()];
                state
                    .disks
                    .expand_from_reference(
                        p.thermal_expansion_coefficient,
                        p.reference_temperature,
                        &temps,
                    )
                    .unwrap();
            }
            let h = load.dt / f64::from(load.substeps);
            let mut heat = 0.0;
            for _ in 0..load.substeps {
                heat += self.step(state, &load.velocity_gradient, h);
            }
            let volume = state.volume(p.thickness);
            RveResponse {
                stress: measure::stress(state, p.thickness),
                heat_source: heat / (volume * load.dt),
                conductivity: measure::conductivity(state, &p),
            }
        }

        pub fn step(&mut self, state: &mut RveState, l: &Mat2, dt: f64) -> f64 {
            self.integrate(state, l, dt);
            self.update_neighbours(state);
            let heat = self.forces(state, l, dt);
            state.step += 1;
            state.time += dt;
            state.friction_heat_total += heat;
            heat
        }

        fn integrate(&self, state: &mut RveState, l: &Mat2, dt: f64) {
            let alpha = self.config.params().local_damping;
            let damp = |f: f64, v: f64, dt_m: f64| {
                if alpha == 0.0 {
                    return f;
                }
                let v_mid = v + 0.5 * f * dt_m;
                let damped = f - (alpha * f.abs()).copysign(v_mid);
                if v_mid != 0.0 { damped } else { f }
            };
            let d = &mut state.disks;
            for i in 0..d.len() {
                let (dt_m, dt_i) = (dt / d.mass[i], dt / d.inertia[i]);
                let (v, w, f, t) = (
                    d.velocity[i],
                    d.angular_velocity[i],
                    d.force[i],
                    d.torque[i],
                );
                let (fx, fy, tz) = (
                    damp(f.x, v.x, dt_m),
                    damp(f.y, v.y, dt_m),
                    damp(t.z, w.z, dt_i),
                );
                let v_new = Vec2::new(v.x + fx * dt_m, v.y + fy * dt_m);
                let w_new = w.z + tz * dt_i;
                let x_old = Vec2::from_xy(d.position[i]);
                let x_new = x_old + (v_new + l.apply_vec2(x_old)) * dt;
                assert!(v_new.is_finite() && w_new.is_finite() && x_new.is_finite());
                d.velocity[i] = v_new.to_vec3();
                d.angular_velocity[i] = Vec3::new(0.0, 0.0, w_new);
                d.position[i] = x_new.to_vec3();
            }
            state.cell.deform(l, dt).unwrap();
        }

        fn update_neighbours(&mut self, state: &mut RveState) {
            if !needs_rebuild(state) {
                return;
            }
            let r_min = state
                .disks
                .reference_radius
                .iter()
                .fold(f64::INFINITY, |m, &r| m.min(r));
            let skin = self.config.params().verlet_skin_ratio * r_min;
            for x in &mut state.disks.position {
                let p = state.cell.period_of(*x);
                if p != [0, 0] {
                    *x -= state.cell.lattice_vector(p);
                }
            }
            self.grid
                .pairs_within(
                    &state.cell,
                    &state.disks.position,
                    &state.disks.radius,
                    skin,
                    &mut self.candidates,
                )
                .unwrap();
            let old = std::mem::take(&mut state.contacts);
            let mut k = 0;
            let c = &mut state.contacts;
            for &(pair, shift) in &self.candidates {
                while k < old.len() && old.pair[k] < pair {
                    k += 1;
                }
                let history = if k < old.len() && old.pair[k] == pair {
                    old.history[k]
                } else {
                    ContactHistory::UNBONDED
                };
                c.pair.push(pair);
                c.shift.push(shift);
                c.history.push(history);
                c.force_on_b.push(Vec2::ZERO);
                c.branch.push(Vec2::ZERO);
            }
            let a = &mut state.anchor;
            a.reduced_position = state
                .disks
                .position
                .iter()
                .map(|&x| state.cell.to_reduced(x))
                .collect();
            a.radius = state.disks.radius.clone();
            a.cell = *state.cell.matrix();
            a.skin = skin;
        }

        fn forces(&self, state: &mut RveState, l: &Mat2, dt: f64) -> f64 {
            let law = self.config.law();
            let h = *state.cell.matrix();
            let d = &mut state.disks;
            let n = d.len();
            let mut force = vec![Vec2::ZERO; n];
            let mut torque = vec![0.0; n];
            let mut moment = Mat2::ZERO;
            let mut heat = 0.0;
            let c = &mut state.contacts;
            for k in 0..c.len() {
                let (a, b) = (c.pair[k][0] as usize, c.pair[k][1] as usize);
                let s = c.shift[k];
                let lattice = h.apply_vec2(Vec2::new(f64::from(s[0]), f64::from(s[1])));
                let (xa, xb) = (Vec2::from_xy(d.position[a]), Vec2::from_xy(d.position[b]));
                let branch = xb + lattice - xa;
                c.branch[k] = branch;
                let (ra, rb) = (d.radius[a], d.radius[b]);
                let reach = ra + rb;
                let history = &mut c.history[k];
                if history.bond != BondState::Intact && branch.norm_squared() >= reach * reach {
                    history.shear_force = Vec2::ZERO;
                    history.normal = Vec2::ZERO;
                    c.force_on_b[k] = Vec2::ZERO;
                    continue;
                }
                let (va, vb) = (Vec2::from_xy(d.velocity[a]), Vec2::from_xy(d.velocity[b]));
                let relative_velocity = vb - va + l.apply_vec2(branch);
                let kin = ContactKinematics::<Vec2>::from_pair(
                    branch,
                    relative_velocity,
                    d.angular_velocity[a].z,
                    d.angular_velocity[b].z,
                    ra,
                    rb,
                    dt,
                );
                let pair = PairInput {
                    radius_a: ra,
                    radius_b: rb,
                    temperature: 0.5 * (d.temperature[a] + d.temperature[b]),
                };
                let r = law.respond(&pair, &kin, history);
                c.force_on_b[k] = r.force_on_b;
                force[a] -= r.force_on_b;
                torque[a] += r.torque_on_a;
                force[b] += r.force_on_b;
                torque[b] += r.torque_on_b;
                moment = moment.add_scaled(&Mat2::outer_vec2(r.force_on_b, branch), 1.0);
                heat += r.friction_work;
            }
            for i in 0..n {
                d.force[i] = force[i].to_vec3();
                d.torque[i] = Vec3::new(0.0, 0.0, torque[i]);
            }
            state.contact_moment = moment;
            heat
        }
    }

    fn needs_rebuild(state: &RveState) -> bool {
        let a = &state.anchor;
        let n = state.len();
        if a.skin <= 0.0 || a.reduced_position.len() != n || a.radius.len() != n {
            return true;
        }
        let h = state.cell.matrix();
        let deformation = match a.cell.inverse() {
            Some(inv) => h.mul(&inv).add_scaled(&Mat2::IDENTITY, -1.0),
            None => return true,
        };
        let e = deformation.contract(&deformation).sqrt();
        let (mut max_disp2, mut max_growth, mut r_max) = (0.0_f64, 0.0_f64, 0.0_f64);
        for i in 0..n {
            let x0 = a.reduced_position[i];
            let d = Vec2::from_xy(state.disks.position[i]) - h.apply_vec2(Vec2::from_xy(x0));
            max_disp2 = max_disp2.max(d.norm_squared());
            max_growth = max_growth.max(state.disks.radius[i] - a.radius[i]);
            r_max = r_max.max(a.radius[i]);
        }
        let used = 2.0 * max_disp2.sqrt() + e * (2.0 * r_max + a.skin) + 2.0 * max_growth;
        !used.is_finite() || used >= a.skin
    }
}

/// Every `f64` (as bits) and integer of a state, in a fixed order.
fn state_bits(s: &RveState) -> Vec<u64> {
    let mut out = Vec::new();
    let v3 = |out: &mut Vec<u64>, v: &[Vec3]| {
        for x in v {
            out.extend([x.x.to_bits(), x.y.to_bits(), x.z.to_bits()]);
        }
    };
    let f = |out: &mut Vec<u64>, v: &[f64]| out.extend(v.iter().map(|x| x.to_bits()));
    let v2 = |out: &mut Vec<u64>, v: Vec2| out.extend([v.x.to_bits(), v.y.to_bits()]);
    let m = |out: &mut Vec<u64>, m: &Mat2| {
        for i in 0..2 {
            for j in 0..2 {
                out.push(m.at(i, j).to_bits());
            }
        }
    };
    let d = &s.disks;
    v3(&mut out, &d.position);
    v3(&mut out, &d.velocity);
    v3(&mut out, &d.angular_velocity);
    v3(&mut out, &d.force);
    v3(&mut out, &d.torque);
    f(&mut out, &d.radius);
    f(&mut out, &d.reference_radius);
    f(&mut out, &d.mass);
    f(&mut out, &d.inertia);
    f(&mut out, &d.temperature);
    let c = &s.contacts;
    out.push(c.len() as u64);
    for k in 0..c.len() {
        out.extend([u64::from(c.pair[k][0]), u64::from(c.pair[k][1])]);
        out.extend([c.shift[k][0] as u64, c.shift[k][1] as u64]);
        let h = &c.history[k];
        v2(&mut out, h.shear_force);
        v2(&mut out, h.normal);
        out.push(h.reference_penetration.to_bits());
        out.push(h.bond as u64);
        v2(&mut out, c.force_on_b[k]);
        v2(&mut out, c.branch[k]);
    }
    v3(&mut out, &s.anchor.reduced_position);
    f(&mut out, &s.anchor.radius);
    m(&mut out, &s.anchor.cell);
    out.push(s.anchor.skin.to_bits());
    m(&mut out, s.cell.matrix());
    m(&mut out, s.cell.inverse());
    m(&mut out, s.cell.reference());
    out.extend([s.step, s.time.to_bits(), s.friction_heat_total.to_bits()]);
    m(&mut out, &s.contact_moment);
    out
}

fn response_bits(r: &RveResponse) -> Vec<u64> {
    let mut out = vec![r.heat_source.to_bits()];
    for i in 0..2 {
        for j in 0..2 {
            out.push(r.stress.at(i, j).to_bits());
            out.push(r.conductivity.at(i, j).to_bits());
        }
    }
    out
}

/// Bonded and unbonded RVEs of one small consolidated packing (each shifted and rotated a
/// little so that the RVEs differ), the configuration with thermally sensitive bonds that
/// melt `T_s = 6 K` above the reference temperature, and the load of RVE `i` at macroscopic
/// step `k`: heating by 0.5 K per step, a simple shear of 2 % per step (up to 60 %) or a
/// stretch, in `substeps` DEM steps.
struct Case {
    config: RveConfig,
    states: Vec<RveState>,
    dt: f64,
}

impl Case {
    fn new(damping: f64, count: usize) -> Self {
        let (config, template, report) = consolidated_packing(60, 7, 0.01).unwrap();
        let mut p = *config.params();
        p.contact.friction_coefficient = 0.3;
        p.local_damping = damping;
        p.contact.thermal_bond = Some(ThermalBondParams {
            strength_coefficient: 0.02,
            threshold_temperature_rise: 6.0,
            reference_temperature: p.reference_temperature,
            shear_ratio: 0.5,
        });
        let config = p.validate().unwrap();
        let states = (0..count)
            .map(|i| {
                let mut s = template.clone();
                if i % 3 != 2 {
                    assert!(s.install_bonds() > 0);
                }
                s.shift_by_lattice_vector([i as i32 % 2, -(i as i32 % 3)]);
                s.rotate_rigidly(0.1 * i as f64).unwrap();
                s
            })
            .collect();
        Self {
            config,
            states,
            dt: report.time_step,
        }
    }

    fn load(&self, i: usize, k: u32) -> RveLoad {
        let rate = 0.02 / (8.0 * self.dt);
        let l = match i % 3 {
            0 => Mat2::new(0.0, rate, 0.0, 0.0),
            1 => Mat2::new(0.5 * rate, -0.3 * rate, 0.2 * rate, -0.5 * rate),
            _ => Mat2::new(-0.2 * rate, 0.0, rate, 0.1 * rate),
        };
        RveLoad {
            velocity_gradient: l,
            temperature: self.config.params().reference_temperature + 0.5 * f64::from(k),
            dt: 8.0 * self.dt,
            substeps: 8 - (i as u32 % 2) * 3,
        }
    }
}

const STEPS: u32 = 30;

/// What the reference gives: the states after each macroscopic step and the responses.
fn reference_run(case: &Case) -> (Vec<Vec<u64>>, Vec<Vec<u64>>) {
    let mut states = case.states.clone();
    let mut r = reference::Reference::new(case.config);
    let (mut s_bits, mut r_bits) = (Vec::new(), Vec::new());
    let (mut reduced, mut rebuilds) = (0, 0);
    for k in 0..STEPS {
        for (i, s) in states.iter_mut().enumerate() {
            let anchor = s.anchor.cell;
            let resp = r.respond(s, &case.load(i, k));
            rebuilds += usize::from(s.anchor.cell != anchor);
            r_bits.push(response_bits(&resp));
            s_bits.push(state_bits(s));
            if k % 10 == 9 {
                reduced += usize::from(s.reduce_cell().unwrap());
            }
        }
    }
    assert!(
        reduced > 0 && rebuilds > STEPS as usize,
        "{reduced} reductions, {rebuilds} rebuilds"
    );
    assert!(
        states.iter().all(|s| s.friction_heat_total > 0.0),
        "every RVE slides"
    );
    // The case must exercise what it claims: bonds broken by melting and shear, a large
    // shear, rebuilds.
    let intact: usize = states.iter().map(|s| s.contacts.intact_bond_count()).sum();
    let installed: usize = case
        .states
        .iter()
        .map(|s| s.contacts.intact_bond_count())
        .sum();
    assert!(
        installed > 100 && intact < installed / 2,
        "{installed} → {intact}"
    );
    (s_bits, r_bits)
}

fn assert_same(what: &str, got: &[Vec<u64>], want: &[Vec<u64>]) {
    assert_eq!(got.len(), want.len(), "{what}: count");
    for (n, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(g == w, "{what}: record {n} differs from the reference");
    }
}

fn check(damping: f64) {
    let case = Case::new(damping, 6);
    let (want_s, want_r) = reference_run(&case);

    // The stepper, one RVE after the other.
    let mut states = case.states.clone();
    let mut stepper = RveStepper::new(case.config);
    let (mut s_bits, mut r_bits) = (Vec::new(), Vec::new());
    for k in 0..STEPS {
        for (i, s) in states.iter_mut().enumerate() {
            let resp = stepper.respond(s, &case.load(i, k)).unwrap();
            r_bits.push(response_bits(&resp));
            s_bits.push(state_bits(s));
            if k % 10 == 9 {
                s.reduce_cell().unwrap();
            }
        }
    }
    assert_same("stepper states", &s_bits, &want_s);
    assert_same("stepper responses", &r_bits, &want_r);

    // The batch on 1, 2 and 3 threads.
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut states = case.states.clone();
        let mut batch = RveBatch::new(case.config, states.len());
        let (mut s_bits, mut r_bits) = (Vec::new(), Vec::new());
        pool.install(|| {
            for k in 0..STEPS {
                let loads: Vec<RveLoad> = (0..states.len()).map(|i| case.load(i, k)).collect();
                let resp = batch.respond(&mut states, &loads).unwrap();
                for (s, r) in states.iter_mut().zip(&resp) {
                    r_bits.push(response_bits(r));
                    s_bits.push(state_bits(s));
                    if k % 10 == 9 {
                        s.reduce_cell().unwrap();
                    }
                }
            }
        });
        assert_same(
            &format!("batch on {threads} threads, states"),
            &s_bits,
            &want_s,
        );
        assert_same(
            &format!("batch on {threads} threads, responses"),
            &r_bits,
            &want_r,
        );
    }
}

#[test]
fn kernel_matches_the_plain_reference_bit_for_bit_undamped() {
    check(0.0);
}

#[test]
fn kernel_matches_the_plain_reference_bit_for_bit_damped() {
    check(0.2);
}

/// Single DEM steps (`RveStepper::step`, no `respond` around them) interleaved with the
/// homogenised measures give the reference's bits too.
#[test]
fn single_steps_match_the_plain_reference() {
    let case = Case::new(0.1, 1);
    let mut a = case.states[0].clone();
    let mut b = a.clone();
    let mut r = reference::Reference::new(case.config);
    let mut stepper = RveStepper::new(case.config);
    let load = case.load(0, 3);
    let dt = case.dt;
    for k in 0..200 {
        let ha = r.step(&mut a, &load.velocity_gradient, dt);
        let hb = stepper.step(&mut b, &load.velocity_gradient, dt).unwrap();
        assert_eq!(ha.to_bits(), hb.to_bits(), "heat of step {k}");
        assert!(state_bits(&a) == state_bits(&b), "state after step {k}");
    }
}
