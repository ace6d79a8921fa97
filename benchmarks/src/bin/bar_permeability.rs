//! A-Sect. 3.2's Darcy permeability (A-Eq. 56, Krzaczek et al. 2023) of the meshes the
//! coupled bar cases run on (`thm_coupling::bar::bar_state_sized`, cut or film ends, 32
//! points per circle, A-Table 1's γ = 0.0115) beside the Darcy test's own packings
//! (`thm_vpn_flow::permeability::DarcyTest::paper_a`, the 9-packing ensemble of the
//! verification case `vpn_flow/darcy_permeability`). The paper's κ is 2.47·10⁻¹⁶ m².
//!
//! `cargo run --release -p thm-benchmarks --bin bar_permeability [-- SEEDS]`: SEEDS
//! comma-separated (default `1,…,9`). Prints a Markdown table: κ of every packing and the
//! mean and range of each family, and of the two mesh variants that tell the cut ends' share
//! from that of the Steiner points on the box sides. Then the experiment that tells an end
//! effect from a bulk one: the geometric mean κ of both families on bars 2 and 4 times as
//! long (same width, same recipe). A resistance at the ends weighs less the longer the bar,
//! so the family whose κ rises with the length has ends that throttle the flow; a bulk κ does
//! not depend on the length. (`thm calibrate` calibrates γ on the cut family.)

use thm_coupling::bar::{
    BAR_LENGTH, BAR_WIDTH, BarCase, BarEnds, PAPER_BAR, bar_params_sized, bar_state_sized,
    water_air,
};
use thm_vpn_flow::Network;
use thm_vpn_flow::permeability::{DarcyTest, incompressible_steady_flow};

/// A-Table 1's T2T reduction factor γ (A-Eq. 9).
const GAMMA: f64 = 0.0115;

/// κ of the coupled bar's mesh; `side_points` overrides the mesher's Steiner points on the box
/// sides (on with cut ends, off with film ends), to tell the ends' share from the sides'.
fn coupled_kappa(
    test: &DarcyTest,
    seed: u64,
    ends: BarEnds,
    side_points: Option<bool>,
) -> Result<f64, String> {
    coupled_kappa_at(test, seed, ends, side_points, PAPER_BAR)
}

/// [`coupled_kappa`] on a bar of `[width, length]` \[m\].
fn coupled_kappa_at(
    test: &DarcyTest,
    seed: u64,
    ends: BarEnds,
    side_points: Option<bool>,
    size: [f64; 2],
) -> Result<f64, String> {
    darcy_flow(test, seed, ends, side_points, size).map(|f| f.kappa)
}

/// The steady Darcy flow through one bar: κ, the boundary links, and the share of the head
/// `p_bottom − p_top` lost between the inlet reservoir and the pores of the first
/// `END_BAND`, and between the pores of the last one and the outlet.
struct DarcyFlow {
    kappa: f64,
    links: usize,
    inlet_loss: f64,
    outlet_loss: f64,
}

/// Depth of the end bands of [`DarcyFlow`] \[m\] (half the smallest diameter).
const END_BAND: f64 = 2e-3;

fn darcy_flow(
    test: &DarcyTest,
    seed: u64,
    ends: BarEnds,
    side_points: Option<bool>,
    size: [f64; 2],
) -> Result<DarcyFlow, String> {
    let case = BarCase::Cooling;
    let gamma = GAMMA;
    let mut params = bar_params_sized(case, 32, size, ends);
    params.mesh.t2t_reduction_factor = gamma;
    params.boundary_reduction_factor = gamma;
    if let Some(on) = side_points {
        params.mesh.side_points = on;
    }
    let config = params.validate().map_err(|e| e.to_string())?;
    let s = bar_state_sized(case, &config, seed, &water_air(), size, ends)
        .map_err(|e| e.to_string())?;
    let mesh = &s.mesh.mesh;
    let net = Network::from_mesh(mesh, &test.reservoirs(), gamma).map_err(|e| e.to_string())?;
    let steady = incompressible_steady_flow(&net, test.viscosity).map_err(|e| e.to_string())?;
    let head = test.bottom_pressure - test.top_pressure;
    let band_mean = |lo: f64, hi: f64| {
        let (sum, n) = net
            .pore_cell()
            .iter()
            .zip(&steady.pressure)
            .filter(|(c, p)| {
                let y = mesh.cell_centroid[**c as usize][1];
                p.is_finite() && y >= lo && y < hi
            })
            .fold((0.0, 0usize), |(s, n), (_, p)| (s + p, n + 1));
        sum / n as f64
    };
    Ok(DarcyFlow {
        kappa: test.kappa_of_rate(steady.group_rate[1], size[1], size[0], mesh.thickness),
        links: net.n_links(),
        inlet_loss: (test.bottom_pressure - band_mean(0.0, END_BAND)) / head,
        outlet_loss: (band_mean(size[1] - END_BAND, size[1]) - test.top_pressure) / head,
    })
}

fn main() {
    let seeds: Vec<u64> = match std::env::args().nth(1) {
        None => (1..=9).collect(),
        Some(list) => match list.split(',').map(str::parse).collect() {
            Ok(s) => s,
            Err(e) => {
                eprintln!("SEEDS: comma-separated packing seeds (u64), got `{list}`: {e}");
                std::process::exit(2);
            }
        },
    };
    let test = DarcyTest::paper_a();
    let mut columns: Vec<(&str, Vec<f64>)> = vec![
        ("Darcy test's packings", Vec::new()),
        ("coupled bar, cut ends", Vec::new()),
        ("coupled bar, film ends", Vec::new()),
        ("film ends with side points", Vec::new()),
        ("cut ends without side points", Vec::new()),
    ];
    for &seed in &seeds {
        let kappas = [
            test.bar_permeability(seed, GAMMA)
                .map(|b| b.kappa)
                .map_err(|e| e.to_string()),
            coupled_kappa(&test, seed, BarEnds::Cut, None),
            coupled_kappa(&test, seed, BarEnds::Film, None),
            coupled_kappa(&test, seed, BarEnds::Film, Some(true)),
            coupled_kappa(&test, seed, BarEnds::Cut, Some(false)),
        ];
        for (col, k) in columns.iter_mut().zip(kappas) {
            match k {
                Ok(k) => col.1.push(k),
                Err(e) => eprintln!("{} seed {seed}: {e}", col.0),
            }
        }
    }
    println!("| packings | κ at γ = 0.0115 per seed [1e-16 m²] | mean | range |");
    println!("| --- | --- | --- | --- |");
    for (name, k) in &columns {
        let each: Vec<String> = k.iter().map(|k| format!("{:.2}", k / 1e-16)).collect();
        let mean = k.iter().sum::<f64>() / k.len() as f64;
        let lo = k.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = k.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        println!(
            "| {name} | {} | {:.2} | {:.2}–{:.2} |",
            each.join(" / "),
            mean / 1e-16,
            lo / 1e-16,
            hi / 1e-16
        );
    }
    println!("| paper (A-Sect. 3.2) | | 2.47 | |");
    // Where the head is lost: a homogeneous bar loses 2.5 % of it in each 2 mm end band.
    println!();
    println!(
        "| packing | ends | boundary links | κ [1e-16 m²] | head lost to the first {:.0} mm | to the last {:.0} mm |",
        END_BAND * 1e3,
        END_BAND * 1e3
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for &seed in &seeds {
        for ends in [BarEnds::Film, BarEnds::Cut] {
            match darcy_flow(&test, seed, ends, None, PAPER_BAR) {
                Ok(f) => println!(
                    "| {seed} | {ends:?} | {} | {:.2} | {:.0} % | {:.0} % |",
                    f.links,
                    f.kappa / 1e-16,
                    100.0 * f.inlet_loss,
                    100.0 * f.outlet_loss
                ),
                Err(e) => eprintln!("{ends:?} seed {seed}: {e}"),
            }
        }
    }
    // End effect or bulk: the same recipe on longer and wider bars. The median over the
    // seeds (a packing whose only path crosses a nearly closed channel, or none, would set a
    // mean), and how many percolate.
    println!();
    println!(
        "| bar width × length [mm] | film ends (the Darcy test's meshes): median κ [1e-16 m²] | percolating | cut ends: median κ | percolating | cut / film |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for (w, l) in [
        (1.0, 1.0),
        (1.0, 2.0),
        (1.0, 4.0),
        (2.0, 1.0),
        (2.0, 2.0),
        (4.0, 4.0),
    ] {
        let size = [w * BAR_WIDTH, l * BAR_LENGTH];
        let mut cells = Vec::new();
        let mut medians = Vec::new();
        for ends in [BarEnds::Film, BarEnds::Cut] {
            let mut k: Vec<f64> = seeds
                .iter()
                .filter_map(
                    |&seed| match coupled_kappa_at(&test, seed, ends, None, size) {
                        Ok(k) => Some(k.max(0.0)),
                        Err(e) => {
                            eprintln!("{ends:?} seed {seed}, {size:?}: {e}");
                            None
                        }
                    },
                )
                .collect();
            k.sort_by(f64::total_cmp);
            let n = k.len();
            let median = if n == 0 {
                f64::NAN
            } else if n % 2 == 1 {
                k[n / 2]
            } else {
                0.5 * (k[n / 2 - 1] + k[n / 2])
            };
            medians.push(median);
            cells.push(format!("{:.2}", median / 1e-16));
            cells.push(format!("{} of {n}", k.iter().filter(|k| **k > 0.0).count()));
        }
        println!(
            "| {:.0} × {:.0} | {} | {:.2} |",
            1e3 * size[0],
            1e3 * size[1],
            cells.join(" | "),
            medians[1] / medians[0]
        );
    }
}
