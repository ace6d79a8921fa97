use thm_eos::*;
fn main() {
    let c = water_air_closure(Model::Pr);
    let r = c.close(278.15, 1e-9, 8.507012969349958e-7, 1.2534515684176752e-11);
    println!("{r:?}");
}
