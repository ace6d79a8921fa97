use thm_eos::*;
fn main() {
    let water = PengRobinson::water(Model::PrCorrected);
    let air = PengRobinson::air();
    let pore = water_air_closure(Model::PrCorrected);
    let v = 1e-9;
    let (t2, p2) = (500.0, 3.0e7);
    let m_l2 = 0.3 * v * water.density(t2, p2, Branch::Liquid).unwrap();
    let m_g2 = 0.7 * v * air.density(t2, p2, Branch::Gas).unwrap();
    println!("{:?}", pore.close(t2, v, m_l2, m_g2));
}
