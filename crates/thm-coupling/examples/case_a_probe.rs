use std::time::Instant;
use thm_coupling::bar::{BarCase, bar_params, bar_state};
use thm_coupling::pore_scale::{CouplingStepParams, PoreScaleStepper};
use thm_coupling::verification::water_air;

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let (t_end, interval, density_factor, disp) = (a[0], a[1], a[2], a[3]);
    let case = BarCase::ContractionFree;
    let seg: u32 = std::env::var("SEG")
        .map(|v| v.parse().unwrap())
        .unwrap_or(32);
    let mut params = bar_params(case, seg);
    if let Ok(t) = std::env::var("TBOND") {
        let t: f64 = t.parse().unwrap();
        params.contact.tensile_strength = t;
        params.contact.cohesion = 5.0 * t;
    }
    params.dem.time_step *= density_factor.sqrt();
    params.flow.max_substeps = a[4] as u32;
    if std::env::var("EQC").is_ok() {
        params.heat.gas.specific_heat = params.heat.liquid.specific_heat;
    }
    let config = params.validate()?;
    let heat = config.params().heat.clone();
    let mut s = bar_state(case, &config, 1, &water_air())?;
    for m in s.dem.particles.mass.iter_mut() {
        *m *= density_factor;
    }
    for m in s.dem.particles.inertia.iter_mut() {
        *m *= density_factor;
    }
    let rule = CouplingStepParams {
        max_step: interval,
        min_step: 1e-7,
        max_displacement: disp,
        growth: 1.5,
    }
    .validate()?;
    let mut st = PoreScaleStepper::new(config.clone(), water_air(), &s)?;
    let (mq0, mp0) = (s.liquid_mass(), s.gas_mass());
    let start = Instant::now();
    while s.time < t_end - 1e-12 {
        if s.time > a[6] {
            for k in 0..12 {
                let h = 2e-3 / 2f64.powi(k);
                let mut t = s.clone();
                let mut st2 = PoreScaleStepper::new(config.clone(), water_air(), &t)?;
                let w = Instant::now();
                let r = st2.step(&mut t, h);
                println!(
                    "  try h {h:.2e}: {:.2} s wall: {:?}",
                    w.elapsed().as_secs_f64(),
                    r.map(|r| (r.flow_substeps, r.remeshed))
                );
            }
            return Ok(());
        }
        let r = st.advance(&mut s, interval, &rule)?;
        let broken = s
            .dem
            .contacts
            .history
            .iter()
            .filter(|h| matches!(h.bond, thm_dem::BondState::Broken))
            .count();
        let tmax = s.heat.temperature.iter().copied().fold(f64::MIN, f64::max);
        let tmin = s.heat.temperature.iter().copied().fold(f64::MAX, f64::min);
        if tmin < 293.0 {
            println!("UNDERSHOOT t {} tmin {tmin}", s.time);
            return Ok(());
        }
        let pmin = s.flow.pressure.iter().copied().fold(f64::MAX, f64::min);
        println!(
            "t {:.4} tmax {tmax:.12} wall {:.1} steps {} rej {} shortest {:.2e} T [{tmin:.2}, {tmax:.2}] pmin {pmin:.0} broken {broken} remeshes {} dm {:.1e} {:.1e} E {:.6e}",
            s.time,
            start.elapsed().as_secs_f64(),
            r.steps,
            r.rejected,
            r.shortest,
            s.remeshes,
            s.liquid_mass() / mq0 - 1.0,
            s.gas_mass() / mp0 - 1.0,
            s.thermal_energy(&heat)
        );
    }
    Ok(())
}
