//! Packing generator: reproducibility, porosity, containment, stress-free bonds, CSV.

mod common;
use common::*;
use thm_dem::packing::*;
use thm_dem::*;

fn bar(seed: u64) -> (Packing, PackingReport) {
    random_packing(&PackingParams::paper_a_bar(seed), 2600.0).unwrap()
}

#[test]
fn bar_packing_meets_the_paper_specimen() {
    let (p, rep) = bar(1);
    eprintln!("{} particles, {rep:?}", p.radii.len());
    assert!((rep.porosity - 0.10).abs() < 1e-12);
    // A-Sect. 3: about 40–45 spheres of 4–8 mm fit a 20 × 80 mm bar at 10 % porosity; with
    // uniform diameters E[πd²/4] = 29.3 mm², so 0.9 · 1600 / 29.3 ≈ 49.
    assert!((40..=55).contains(&p.radii.len()));
    assert!(rep.radius_scale <= 1.0 && rep.radius_scale > 0.97);
    let d_min = 0.004 * rep.radius_scale;
    assert!(
        p.radii
            .iter()
            .all(|&r| 2.0 * r >= d_min * (1.0 - 1e-12) && 2.0 * r <= 0.008 * (1.0 + 1e-12))
    );
    // Inside the bar up to the overlap the walls allowed: walls are as stiff as contacts, so a
    // particle pokes through a wall by no more than the largest particle overlap.
    let poke = rep.max_relative_overlap;
    for (c, r) in p.centres.iter().zip(&p.radii) {
        assert!(c.x - r > -poke * r && c.x + r < 0.02 + poke * r);
        assert!(c.y - r > -poke * r && c.y + r < 0.08 + poke * r);
        assert_eq!(c.z, 0.0);
    }
    // 10 % porosity counted as Σ disk area is denser than random disks jam (≈ 16 %), so the
    // compaction leaves overlaps of the order of (0.16 − 0.10) of a radius, not more than 1/3.
    assert!(rep.max_relative_overlap < 1.0 / 3.0);
    assert!(rep.bond_coordination > 3.0);
}

#[test]
fn packing_is_reproducible_from_its_seed() {
    let (a, _) = bar(5);
    let (b, _) = bar(5);
    let (c, _) = bar(6);
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn bonds_are_stress_free_at_creation() {
    let (p, _) = bar(2);
    let mut state = p.to_state(2600.0, 293.15).unwrap();
    assert_eq!(state.contacts.intact_bond_count(), p.bonds.len());
    let mut stepper = Stepper::new(table1(), stepper_params(2e-7, 0.08).validate().unwrap());
    stepper.run(&mut state, 10).unwrap();
    for k in 0..state.contacts.len() {
        assert_eq!(state.contacts.force_on_b(k), Vec3::ZERO);
    }
    assert!(state.particles.velocity.iter().all(|v| *v == Vec3::ZERO));
    assert_eq!(state.particles.position, p.centres);
}

#[test]
fn csv_round_trip_is_exact() {
    let (p, _) = bar(3);
    let q = Packing::from_csv(&p.to_csv()).unwrap();
    assert_eq!(p, q);
    let l = lattice_packing(Kinematics::Spheres3d, [4, 3, 2], 1e-3, 9).unwrap();
    assert_eq!(Packing::from_csv(&l.to_csv()).unwrap(), l);
}

#[test]
fn bad_csv_names_the_line() {
    let text =
        "# thm-dem packing; kinematics=disks\nparticle,0,0,0,1e-3\nparticle,1e-3,0,zero,1e-3\n";
    match Packing::from_csv(text) {
        Err(DemError::PackingFile { line: 3, .. }) => {}
        other => panic!("{other:?}"),
    }
    let text = "# thm-dem packing; kinematics=disks\nparticle,0,0,0,1e-3\nbond,0,4\n";
    assert!(Packing::from_csv(text).is_err());
}

#[test]
fn generator_rejects_bad_parameters() {
    let mut p = PackingParams::paper_a_bar(1);
    p.porosity = 1.5;
    assert!(matches!(
        random_packing(&p, 2600.0),
        Err(DemError::InvalidParameter {
            field: "porosity",
            ..
        })
    ));
    let mut p = PackingParams::paper_a_bar(1);
    p.diameter_max = 0.001;
    assert!(matches!(
        random_packing(&p, 2600.0),
        Err(DemError::InvalidParameter {
            field: "diameter_max",
            ..
        })
    ));
}

fn planar(centres: &[(f64, f64)], radii: &[f64]) -> Packing {
    Packing {
        kinematics: Kinematics::SpheresInPlane,
        centres: centres.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
        radii: radii.to_vec(),
        bonds: Vec::new(),
    }
}

#[test]
fn area_porosity_of_one_disk_is_one_minus_its_area_share() {
    let r = 3e-3;
    let p = planar(&[(5e-3, 6e-3)], &[r]);
    let phi = area_porosity(&p, [0.0, 0.0], [0.01, 0.012], 2e-5).unwrap();
    let exact = 1.0 - std::f64::consts::PI * r * r / (0.01 * 0.012);
    // Cell-centre sampling: error below perimeter × cell / area.
    let bound = 2.0 * std::f64::consts::PI * r * 2e-5 / (0.01 * 0.012);
    assert!((phi - exact).abs() < bound, "{phi} vs {exact}");
}

#[test]
fn area_porosity_counts_an_overlap_once() {
    // Two disks of radius r at distance d: union = 2πr² − lens, lens = 2r²acos(d/2r) − (d/2)√(4r² − d²).
    let (r, d) = (2e-3, 3e-3);
    let p = planar(&[(4e-3, 5e-3), (4e-3 + d, 5e-3)], &[r, r]);
    let (w, h) = (0.012, 0.01);
    let phi = area_porosity(&p, [0.0, 0.0], [w, h], 1e-5).unwrap();
    let lens = 2.0 * r * r * (d / (2.0 * r)).acos() - 0.5 * d * (4.0 * r * r - d * d).sqrt();
    let exact = 1.0 - (2.0 * std::f64::consts::PI * r * r - lens) / (w * h);
    let bound = 4.0 * std::f64::consts::PI * r * 1e-5 / (w * h);
    assert!((phi - exact).abs() < bound, "{phi} vs {exact}");
    // Parts outside the rectangle do not count.
    let outside = planar(&[(0.0, 5e-3)], &[r]);
    let phi = area_porosity(&outside, [0.0, 0.0], [w, h], 1e-5).unwrap();
    let half = 1.0 - 0.5 * std::f64::consts::PI * r * r / (w * h);
    assert!((phi - half).abs() < bound);
}

#[test]
fn area_porosity_rejects_a_bad_cell() {
    let p = planar(&[(1e-3, 1e-3)], &[1e-3]);
    assert!(matches!(
        area_porosity(&p, [0.0, 0.0], [0.01, 0.01], 0.0),
        Err(DemError::InvalidParameter { field: "cell", .. })
    ));
    assert!(matches!(
        area_porosity(&p, [0.0, 0.0], [0.01, 0.01], 1e-7),
        Err(DemError::InvalidParameter { field: "cell", .. })
    ));
}

#[test]
fn a_bad_packing_row_is_quoted_short_whatever_its_length() {
    let long = "x".repeat(5000);
    for text in [
        format!("{long},1,2,3,4\n"),
        format!("particle,{long},0,0,1\n"),
        format!("bond,0,{long}\n"),
        format!("# kinematics={long}\n"),
    ] {
        let message = thm_dem::packing::Packing::from_csv(&text)
            .expect_err("bad row")
            .to_string();
        assert!(message.contains("line 1"), "{message}");
        assert!(message.contains('…'), "{message}");
        assert!(message.chars().count() < 200, "{message}");
    }
    // A short field is quoted whole.
    let message = thm_dem::packing::Packing::from_csv("particle,abc,0,0,1\n")
        .expect_err("bad number")
        .to_string();
    assert!(message.contains("`abc` is not a number"), "{message}");
}

/// Largest index distance `b − a` of the pairs closer than `gap`.
fn index_reach(p: &Packing, gap: f64) -> usize {
    let particles = ParticleState::new(p.kinematics, 2600.0, 293.15, &p.centres, &p.radii).unwrap();
    neighbour::pairs_within(&particles, gap)
        .iter()
        .map(|&(a, b)| b - a)
        .max()
        .unwrap()
}

#[test]
fn locality_order_numbers_a_slab_across_its_longest_axis() {
    // 40 × 40 × 3 spheres numbered x first: a sphere's neighbour above it is 1 600 indices
    // away. Renumbered with the thin axis fastest, every neighbour lies within one row of the
    // 40 × 3 cross-section (120 particles; cells of the largest diameter hold at most two
    // lattice sites along an axis, so allow twice that).
    let p = lattice_packing(Kinematics::Spheres3d, [40, 40, 3], 1e-3, 3).unwrap();
    let gap = 0.05e-3;
    assert!(index_reach(&p, gap) >= 1600);
    let (q, order) = p.in_locality_order();
    let reach = index_reach(&q, gap);
    eprintln!("index reach {} -> {reach}", index_reach(&p, gap));
    assert!(reach <= 2 * 40 * 3, "{reach}");
    // A permutation that carries every particle and every bond along.
    let mut seen = vec![false; order.len()];
    for (new, &old) in order.iter().enumerate() {
        assert!(!std::mem::replace(&mut seen[old], true));
        assert_eq!(q.centres[new], p.centres[old]);
        assert_eq!(q.radii[new], p.radii[old]);
    }
    assert!(q.bonds.windows(2).all(|w| w[0] < w[1]));
    assert!(q.bonds.iter().all(|&(a, b)| a < b));
    let mut carried: Vec<(usize, usize)> = q
        .bonds
        .iter()
        .map(|&(a, b)| (order[a].min(order[b]), order[a].max(order[b])))
        .collect();
    carried.sort_unstable();
    assert_eq!(carried, p.bonds);
}

#[test]
fn locality_order_leaves_what_it_cannot_bin_as_it_is() {
    let c = [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::ZERO,
        Vec3::new(0.5, 0.0, 0.0),
    ];
    assert_eq!(locality_order(&c, 0.1), vec![1, 2, 0]);
    for cell in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(locality_order(&c, cell), vec![0, 1, 2]);
    }
    let nan = [Vec3::new(f64::NAN, 0.0, 0.0), Vec3::ZERO];
    assert_eq!(locality_order(&nan, 0.1), vec![0, 1]);
    assert!(locality_order(&[], 0.1).is_empty());
}

/// Kinetic energy and positions (old numbering) after `steps` steps of the bonded A-Table 1
/// law, from velocities that are a function of position, so that both numberings start alike.
fn run_bonded(p: &Packing, order: &[usize], steps: usize) -> (f64, Vec<Vec3>) {
    let mut state = p.to_state(2600.0, 293.15).unwrap();
    for (v, c) in state.particles.velocity.iter_mut().zip(&p.centres) {
        let (x, y, z) = (c.x / 1e-3, c.y / 1e-3, c.z / 1e-3);
        *v = Vec3::new((1.7 * x + y).sin(), (0.9 * y - z).cos(), (x * z).sin()) * 0.5;
    }
    let mut stepper = Stepper::new(table1(), stepper_params(1e-7, 0.0).validate().unwrap());
    for _ in 0..steps {
        stepper.step(&mut state).unwrap();
    }
    let mut x = vec![Vec3::ZERO; order.len()];
    for (new, &old) in order.iter().enumerate() {
        x[old] = state.particles.position[new];
    }
    (state.particles.kinetic_energy(), x)
}

#[test]
fn a_renumbered_packing_moves_the_same() {
    // Bonds stretched and compressed by a velocity field; the physics does not see the
    // numbering, only the order of the force sums does (round-off).
    let p = lattice_packing(Kinematics::Spheres3d, [12, 12, 3], 1e-3, 5).unwrap();
    let identity: Vec<usize> = (0..p.radii.len()).collect();
    let (q, order) = p.in_locality_order();
    assert_ne!(order, identity);
    let (ke_p, x_p) = run_bonded(&p, &identity, 400);
    let (ke_q, x_q) = run_bonded(&q, &order, 400);
    let dx = x_p
        .iter()
        .zip(&x_q)
        .map(|(a, b)| (*a - *b).norm())
        .fold(0.0, f64::max);
    eprintln!("kinetic energy {ke_p:e} / {ke_q:e}, largest position difference {dx:e} m");
    assert!(ke_p > 0.0);
    assert!((ke_p - ke_q).abs() <= 1e-9 * ke_p);
    assert!(dx <= 1e-12);
}

proptest::proptest! {
    /// Any centres and cell: a permutation, and the cells come in the row-major order of their
    /// indices (fewest-cell axis fastest), so a sphere's cell never precedes an earlier one's.
    #[test]
    fn locality_order_is_a_permutation_in_cell_order(
        xyz in proptest::collection::vec((-1.0..1.0_f64, -1.0..1.0_f64, -0.2..0.2_f64), 0..200),
        cell in 0.01..0.5_f64,
    ) {
        let centres: Vec<Vec3> = xyz.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        let order = locality_order(&centres, cell);
        let mut seen = vec![false; centres.len()];
        for &i in &order {
            proptest::prop_assert!(!std::mem::replace(&mut seen[i], true));
        }
        proptest::prop_assert!(seen.iter().all(|&s| s));
        if centres.len() > 1 {
            let lo = |k: usize| centres.iter().map(|c| [c.x, c.y, c.z][k]).fold(f64::INFINITY, f64::min);
            let hi = |k: usize| centres.iter().map(|c| [c.x, c.y, c.z][k]).fold(f64::NEG_INFINITY, f64::max);
            let cells: Vec<u64> = (0..3).map(|k| ((hi(k) - lo(k)) / cell) as u64 + 1).collect();
            let mut axes = [0, 1, 2];
            axes.sort_by_key(|&k| cells[k]);
            let index = |i: usize| -> Vec<u64> {
                let c = [centres[i].x, centres[i].y, centres[i].z];
                axes.iter().rev().map(|&k| ((c[k] - lo(k)) / cell) as u64).collect()
            };
            for w in order.windows(2) {
                let (a, b) = (index(w[0]), index(w[1]));
                proptest::prop_assert!(a < b || (a == b && w[0] < w[1]));
            }
        }
    }
}

/// A bonded lattice under a velocity field (a function of position) after `steps` steps.
fn stirred_lattice(speed: f64) -> DemState {
    let p = lattice_packing(Kinematics::Spheres3d, [10, 10, 4], 1e-3, 9).unwrap();
    let mut state = p.to_state(2600.0, 293.15).unwrap();
    for (v, c) in state.particles.velocity.iter_mut().zip(&p.centres) {
        let (x, y, z) = (c.x / 1e-3, c.y / 1e-3, c.z / 1e-3);
        *v = Vec3::new((1.7 * x + y).sin(), (0.9 * y - z).cos(), (x * z).sin()) * speed;
    }
    state
}

#[test]
fn a_running_state_renumbered_moves_the_same() {
    // Reversed, every pair changes order (its history is mirrored); in locality order of the
    // current positions, some do. The stepper that advanced the state goes on after the
    // renumbering (its contact index and bounds must follow).
    let law = table1();
    // A skin wide enough that no search runs after the renumbering, where a search would
    // rebuild the contact index anyway.
    let params = || {
        let mut p = stepper_params(1e-7, 0.0);
        p.verlet_skin = 1.5e-3;
        p.validate().unwrap()
    };
    let mut reference = stirred_lattice(8.0);
    let mut stepper = Stepper::new(law, params());
    stepper.run(&mut reference, 200).unwrap();
    let n = reference.particles.len();
    let reversed: Vec<usize> = (0..n).rev().collect();
    let local = locality_order(&reference.particles.position, 2e-3);
    let mut renumbered = Vec::new();
    for order in [reversed, local] {
        let mut state = stirred_lattice(8.0);
        let mut s = Stepper::new(law, params());
        s.run(&mut state, 200).unwrap();
        assert_eq!(state, reference);
        state.renumber(&order).unwrap();
        renumbered.push((state, order, s));
    }
    stepper.run(&mut reference, 400).unwrap();
    let broken = reference.contacts.broken_bond_count();
    assert!(broken > 0 && reference.contacts.intact_bond_count() > 0);
    let ke = reference.particles.kinetic_energy();
    for (mut state, order, mut s) in renumbered {
        s.run(&mut state, 400).unwrap();
        let dx = order
            .iter()
            .enumerate()
            .map(|(new, &old)| {
                (state.particles.position[new] - reference.particles.position[old]).norm()
            })
            .fold(0.0, f64::max);
        let dke = (state.particles.kinetic_energy() - ke).abs() / ke;
        eprintln!("{broken} bonds broken; position difference {dx:e} m, energy {dke:e}");
        assert!(dx <= 1e-12 && dke <= 1e-9);
        assert_eq!(state.contacts.broken_bond_count(), broken);
        assert_eq!(state.bond_breaks.len(), reference.bond_breaks.len());
        for e in &state.bond_breaks {
            let (a, b) = (order[e.a as usize], order[e.b as usize]);
            let pair = (a.min(b) as u32, a.max(b) as u32);
            assert!(
                reference
                    .bond_breaks
                    .iter()
                    .any(|r| (r.a, r.b) == pair && r.step == e.step)
            );
        }
    }
}

#[test]
fn renumbering_rejects_what_is_not_a_permutation() {
    let state = stirred_lattice(1.0);
    let n = state.particles.len();
    let mut repeated: Vec<usize> = (0..n).collect();
    repeated[3] = 2;
    let mut beyond: Vec<usize> = (0..n).collect();
    beyond[0] = n;
    for order in [vec![0; n - 1], repeated, beyond] {
        let mut s = state.clone();
        match s.renumber(&order) {
            Err(DemError::InvalidParameter { field, allowed, .. }) => {
                assert_eq!(field, "order");
                assert!(allowed.contains("permutation"));
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(s, state);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
    /// Any renumbering of a stepped state keeps every particle's data and every contact's
    /// force exactly: a contact whose pair changed order reports the negated force on its
    /// new B, i.e. the same force on the same particle.
    #[test]
    fn renumbering_keeps_every_particle_and_contact_force(
        keys in proptest::collection::vec(0..u32::MAX, 160),
    ) {
        let p = lattice_packing(Kinematics::Spheres3d, [8, 5, 4], 1e-3, 2).unwrap();
        let mut state = p.to_state(2600.0, 293.15).unwrap();
        for (v, c) in state.particles.velocity.iter_mut().zip(&p.centres) {
            *v = Vec3::new((c.y / 1e-3).sin(), (c.z / 1e-3).cos(), (c.x / 1e-3).sin()) * 5.0;
        }
        Stepper::new(table1(), stepper_params(1e-7, 0.0).validate().unwrap())
            .run(&mut state, 50)
            .unwrap();
        let mut order: Vec<usize> = (0..keys.len()).collect();
        order.sort_by_key(|&i| (keys[i], i));
        let mut renumbered = state.clone();
        renumbered.renumber(&order).unwrap();
        for (new, &old) in order.iter().enumerate() {
            proptest::prop_assert_eq!(renumbered.particles.position[new], state.particles.position[old]);
            proptest::prop_assert_eq!(renumbered.particles.velocity[new], state.particles.velocity[old]);
            proptest::prop_assert_eq!(renumbered.particles.radius[new], state.particles.radius[old]);
        }
        proptest::prop_assert_eq!(renumbered.contacts.len(), state.contacts.len());
        proptest::prop_assert!(renumbered.contacts.pair.windows(2).all(|w| w[0] < w[1]));
        for k in 0..renumbered.contacts.len() {
            let [a, b] = renumbered.contacts.pair[k];
            let (oa, ob) = (order[a as usize] as u32, order[b as usize] as u32);
            let key = [oa.min(ob), oa.max(ob)];
            let j = state.contacts.pair.binary_search(&key).unwrap();
            let force = renumbered.contacts.force_on_b(k);
            let expected = if oa < ob { state.contacts.force_on_b(j) } else { -state.contacts.force_on_b(j) };
            proptest::prop_assert_eq!(force, expected);
            proptest::prop_assert_eq!(renumbered.contacts.history[k].bond, state.contacts.history[j].bond);
        }
    }
}
