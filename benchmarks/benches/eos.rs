//! Peng–Robinson pressure, density and the two-phase pore closure (single thread).
//!
//! Targets: pressure ≤ 20 ns, density ≤ 250 ns, closure ≤ 2 µs per call.
//! Run: `cargo bench -p thm-benchmarks --bench eos -- --warm-up-time 1 --measurement-time 3`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use thm_eos::{Branch, EquationOfState, Model, PengRobinson, PoreClosure, water_air_closure};

fn eos(c: &mut Criterion) {
    let water = PengRobinson::water(Model::PrCorrected);
    let air = PengRobinson::air();

    c.bench_function("eos/pressure/water_liquid", |b| {
        b.iter(|| water.pressure(black_box(300.0), black_box(1000.0)))
    });
    c.bench_function("eos/pressure_and_dp_drho/water_liquid", |b| {
        b.iter(|| water.pressure_and_dp_drho(black_box(300.0), black_box(1000.0)))
    });
    c.bench_function("eos/density/water_liquid_3_roots", |b| {
        b.iter(|| {
            water.density(
                black_box(300.0),
                black_box(1.0e5),
                black_box(Branch::Liquid),
            )
        })
    });
    c.bench_function("eos/density/air_gas_1_root", |b| {
        b.iter(|| air.density(black_box(300.0), black_box(1.0e5), black_box(Branch::Gas)))
    });

    // The thermal contraction test's pore: 80 % water, 20 % air at 0.1 MPa and 368.16 K.
    let pore = water_air_closure(Model::PrCorrected);
    let (t, v) = (368.16, 1.0e-9);
    let m_l = 0.8 * v * water.density(t, 1.0e5, Branch::Liquid).unwrap_or(0.0);
    let m_g = 0.2 * v * air.density(t, 1.0e5, Branch::Gas).unwrap_or(0.0);
    c.bench_function("eos/closure/water_air_80_20_0.1MPa", |b| {
        b.iter(|| pore.close(black_box(t), black_box(v), black_box(m_l), black_box(m_g)))
    });
    // A compressed pore: 30 % water at 30 MPa, 500 K (farther from the first guess).
    let (t2, p2) = (500.0, 3.0e7);
    let m_l2 = 0.3 * v * water.density(t2, p2, Branch::Liquid).unwrap_or(0.0);
    let m_g2 = 0.7 * v * air.density(t2, p2, Branch::Gas).unwrap_or(0.0);
    c.bench_function("eos/closure/water_air_30_70_30MPa", |b| {
        b.iter(|| {
            pore.close(
                black_box(t2),
                black_box(v),
                black_box(m_l2),
                black_box(m_g2),
            )
        })
    });
    // The slowest start seen: a nearly full pore (99 % water) at 70 MPa and 278.15 K, where the
    // liquid at 0.1 MPa would not fit and the search starts by bisection.
    let (t3, p3) = (278.15, 7.0e7);
    let m_l3 = 0.99 * v * water.density(t3, p3, Branch::Liquid).unwrap_or(0.0);
    let m_g3 = 0.01 * v * air.density(t3, p3, Branch::Gas).unwrap_or(0.0);
    c.bench_function("eos/closure/water_air_99_1_70MPa", |b| {
        b.iter(|| {
            pore.close(
                black_box(t3),
                black_box(v),
                black_box(m_l3),
                black_box(m_g3),
            )
        })
    });
}

criterion_group!(benches, eos);
criterion_main!(benches);
