use thm_eos::*;
fn main() {
    let water = PengRobinson::water(Model::PrCorrected);
    let air = PengRobinson::air();
    let (t, p, alpha, v) = (
        613.5313472034363,
        10f64.powf(7.3104038111826055),
        0.9924368298680699,
        1e-3,
    );
    let rho_l = water.density(t, p, Branch::Liquid).unwrap();
    println!(
        "rho_l {rho_l} on_branch {:?} dp {:?}",
        water.on_branch(t, rho_l, Branch::Liquid),
        water.dp_drho(t, rho_l)
    );
    let m_l = alpha * v * rho_l;
    let m_g = (1.0 - alpha) * v * air.density(t, p, Branch::Gas).unwrap();
    let s = water_air_closure(Model::PrCorrected)
        .close(t, v, m_l, m_g)
        .unwrap();
    println!("{s:?}");
    println!(
        "pdp l {:?} g {:?}",
        water.pressure_and_dp_drho(t, s.liquid_density),
        air.pressure_and_dp_drho(t, s.gas_density)
    );
    let a = s.liquid_fraction;
    println!(
        "c_g/(1-a) {} gas_density {}",
        m_g / v / (1.0 - a),
        s.gas_density
    );
    println!(
        "Pl {} Pg {}",
        water.pressure(t, s.liquid_density).unwrap(),
        air.pressure(t, s.gas_density).unwrap()
    );
}
#[allow(dead_code)]
fn extra() {}
