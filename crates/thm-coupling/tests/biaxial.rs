//! The biaxial test of B-Sect. 5.3.1 (`thm_coupling::multiscale::biaxial`) on a tiny
//! specimen: thread-count independence, save/restore, the confinement reaching the surface,
//! and heat against friction work.

use thm_coupling::multiscale::biaxial::{BiaxialModel, BiaxialTest, Compaction};

/// 2 × 4 cells with 2 × 2 points each (32 RVEs of 30 disks), density-scaled by 10⁴.
fn tiny(steps: u64) -> BiaxialTest {
    let mut t = BiaxialTest::reduced(Compaction::Dense, [2, 4], 2, 30, 1e4);
    t.target_strain = t.plate_speed * t.time_step * steps as f64 / t.height;
    t
}

fn json(m: &BiaxialModel) -> String {
    serde_json::to_string(&(&m.state, &m.totals)).unwrap()
}

/// 1 and 2 rayon threads give the same bits: points, RVEs and the running sums.
#[test]
fn one_and_two_threads_give_the_same_bits() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut m = BiaxialModel::new(&tiny(40)).unwrap();
                while !m.finished() {
                    m.step().unwrap();
                }
                json(&m)
            })
    };
    assert_eq!(run(1), run(2));
}

/// A state and running sums saved mid-run and restored into a freshly built model continue
/// bit for bit.
#[test]
fn save_and_restore_continue_bit_for_bit() {
    let t = tiny(40);
    let mut m = BiaxialModel::new(&t).unwrap();
    for _ in 0..20 {
        m.step().unwrap();
    }
    let saved = json(&m);
    while !m.finished() {
        m.step().unwrap();
    }
    let mut m2 = BiaxialModel::new(&t).unwrap();
    let (state, totals) = serde_json::from_str(&saved).unwrap();
    m2.restore(state, totals).unwrap();
    while !m2.finished() {
        m2.step().unwrap();
    }
    assert_eq!(json(&m), json(&m2));
}

/// The follower confinement reaches the surface nodes: before the end restraint of the rough
/// plates builds up (the first 10 steps, 0.01 % strain), the volume-averaged σ_xx is the
/// confining stress within 1 % (the virtual-layer load on the outer points alone holds it at
/// about 3/4 of it with 2 points per cell); the heat generated equals the friction work
/// summed over the RVEs to round-off.
#[test]
fn confinement_holds_and_heat_is_friction_work() {
    let mut m = BiaxialModel::new(&tiny(10)).unwrap();
    while !m.finished() {
        m.step().unwrap();
        let r = m.record();
        let sc = m.case.test.confining_stress;
        assert!(
            (r.mean_sigma_xx - sc).abs() <= 0.01 * sc,
            "step {}: mean σ_xx = {} Pa",
            m.state.step,
            r.mean_sigma_xx
        );
        assert!(
            (r.heat_generated - r.friction_work_upscaled).abs()
                <= 1e-12 * r.friction_work_upscaled.abs(),
            "heat {} vs friction work {}",
            r.heat_generated,
            r.friction_work_upscaled
        );
    }
}

/// Bad parameters name the field.
#[test]
fn bad_parameters_name_the_field() {
    let mut t = tiny(10);
    t.points_per_cell = 1;
    let e = BiaxialModel::new(&t).unwrap_err().to_string();
    assert!(e.contains("points_per_cell") && e.contains("[2, 8]"), "{e}");
    let mut t = tiny(10);
    t.cells[0] = 10_001;
    let e = BiaxialModel::new(&t).unwrap_err().to_string();
    assert!(e.contains("cells[0]") && e.contains("[1, 10000]"), "{e}");
    let mut t = tiny(10);
    t.height = 3.0;
    let e = BiaxialModel::new(&t).unwrap_err().to_string();
    assert!(e.contains("`height`"), "{e}");
}

/// B-Fig. 18's bonded specimen: bonds only at the contacts that carry force after the
/// consolidation (and at every one of them), the same packing as without bonds, and a bad
/// bond strength names its field.
#[test]
fn bonds_are_installed_at_the_force_carrying_contacts_only() {
    let mut plain = tiny(10);
    plain.compaction = Compaction::Loose;
    plain.consolidation_friction = Compaction::Loose.consolidation_friction();
    plain.confining_stress = 25e3;
    let mut bonded = plain;
    bonded.bond_strength = 0.02;
    let (_, a, _) = thm_coupling::multiscale::biaxial::biaxial_packing(&plain).unwrap();
    let (p, b, _) = thm_coupling::multiscale::biaxial::biaxial_packing(&bonded).unwrap();
    assert!(p.contact.thermal_bond.is_some());
    assert_eq!(a.disks.position, b.disks.position);
    let mut bonds = 0;
    for ((ha, hb), f) in a
        .contacts
        .history
        .iter()
        .zip(&b.contacts.history)
        .zip(&b.contacts.force_on_b)
    {
        assert_eq!(ha.bond, thm_dem::BondState::None);
        let carries = *f != thm_dem::Vec2::ZERO;
        assert_eq!(hb.bond == thm_dem::BondState::Intact, carries);
        bonds += usize::from(carries);
    }
    assert!(bonds > b.disks.len(), "{bonds} bonds");
    bonded.bond_strength = -0.01;
    let e = BiaxialModel::new(&bonded).unwrap_err().to_string();
    assert!(e.contains("bond_strength"), "{e}");
}

/// The paper's void ratios are attached to the tests that state them and to no other.
#[test]
fn paper_void_ratios_follow_the_stated_tests() {
    assert_eq!(
        BiaxialTest::paper(Compaction::Dense).paper_void_ratio(),
        Some(0.165)
    );
    assert_eq!(
        BiaxialTest::paper(Compaction::Loose).paper_void_ratio(),
        Some(0.236)
    );
    for (kpa, e) in [(10.0, 0.251), (25.0, 0.240), (50.0, 0.232)] {
        assert_eq!(
            BiaxialTest::bonded(1e3 * kpa, 0.01).paper_void_ratio(),
            Some(e)
        );
    }
    assert_eq!(BiaxialTest::bonded(7e4, 0.01).paper_void_ratio(), None);
    let mut dense_low = BiaxialTest::paper(Compaction::Dense);
    dense_low.confining_stress = 25e3;
    assert_eq!(dense_low.paper_void_ratio(), None);
}
