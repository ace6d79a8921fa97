//! `coupling/bar_packing_family` (A-Sect. 3, quick): the packing family every coupled bar
//! case runs on ([`BarFamily::coupled_cases`]) against the paper's bar and against the
//! parameters the cases use: its strength in uniaxial tension (A-Sect. 3.1) at the cases' bond
//! strength [`CASE_A_BOND_TENSILE_STRENGTH`] within 5 % of the paper's 8.8 MPa; its
//! permeability (A-Sect. 3.2, A-Eq. 56) at the cases' γ [`BAR_T2T_REDUCTION_FACTOR`] within
//! 1 % of the paper's 2.47·10⁻¹⁶ m²; about 10 % porosity, 4–8 mm spheres with d50 ≈ 6 mm
//! (A-Sect. 3); no pore sealed by construction. Reported: the same figures at A-Table 1's
//! T = 30 MPa and γ = 0.0115, against the paper's and the Darcy test's own packings.

use thm_dem::CohesiveFrictionalParams;
use thm_verify::{CaseError, CaseOutput, Row};
use thm_vpn_flow::permeability::DarcyTest;

use crate::bar::{BAR_T2T_REDUCTION_FACTOR, CASE_A_BOND_TENSILE_STRENGTH};
use crate::calibration::BarFamily;

/// The packings of the family's checks (those of case a's ensemble).
const SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
/// The Darcy test's ensemble (`vpn_flow/darcy_permeability`).
const DARCY_SEEDS: std::ops::RangeInclusive<u64> = 1..=12;
/// A-Sect. 3.1: the bar's tensile strength \[Pa\].
const PAPER_STRENGTH: f64 = 8.8e6;
/// A-Sect. 3.2: the bar's permeability \[m²\].
const PAPER_KAPPA: f64 = 2.47e-16;
/// A-Table 1.
const PAPER_T: f64 = 30e6;
const PAPER_GAMMA: f64 = 0.0115;
const PAPER_MODULUS: f64 = 3.5e9;
const PAPER_STRAIN_AT_PEAK: f64 = 0.0028;
const PAPER_COORDINATION: f64 = 6.53;

fn law(tensile_strength: f64) -> CohesiveFrictionalParams {
    CohesiveFrictionalParams {
        tensile_strength,
        cohesion: 5.0 * tensile_strength,
        ..CohesiveFrictionalParams::paper_a_table_1()
    }
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

fn list(v: &[f64], scale: f64) -> String {
    v.iter()
        .map(|x| format!("{:.2}", x / scale))
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The case (module docs).
pub fn packing_family_case() -> Result<CaseOutput, CaseError> {
    let family = BarFamily::coupled_cases();
    let mut out = CaseOutput::default();

    // A-Sect. 3.1 at the cases' T and at A-Table 1's.
    let tension = |t: f64| -> Result<Vec<thm_dem::tension::TensionResult>, CaseError> {
        SEEDS
            .iter()
            .map(|&seed| {
                family
                    .tension(seed, &law(t))
                    .map_err(CaseError::from_display)
            })
            .collect()
    };
    let cases_t = tension(CASE_A_BOND_TENSILE_STRENGTH)?;
    let paper_t = tension(PAPER_T)?;
    let strengths: Vec<f64> = cases_t.iter().map(|r| r.strength).collect();
    out.rows.push(Row::relative(
        format!(
            "mean tensile strength of seeds 1-5 at the cases' T = {:.2} MPa (C = 5 T) vs A-Sect. 3.1",
            CASE_A_BOND_TENSILE_STRENGTH / 1e6
        ),
        "MPa",
        mean(strengths.iter().copied()) / 1e6,
        PAPER_STRENGTH / 1e6,
        0.05,
    ));
    out.rows.push(Row::reported(
        "mean tensile strength at A-Table 1's T = 30 MPa vs A-Sect. 3.1",
        "MPa",
        mean(paper_t.iter().map(|r| r.strength)) / 1e6,
        PAPER_STRENGTH / 1e6,
    ));
    out.rows.push(Row::reported(
        "mean Young's modulus of the bar vs A-Sect. 3.1",
        "GPa",
        mean(cases_t.iter().map(|r| r.young_modulus)) / 1e9,
        PAPER_MODULUS / 1e9,
    ));
    out.rows.push(Row::reported(
        "mean strain at the peak vs A-Sect. 3.1",
        "%",
        100.0 * mean(cases_t.iter().map(|r| r.strain_at_peak)),
        100.0 * PAPER_STRAIN_AT_PEAK,
    ));
    out.rows.push(Row::reported(
        "mean coordination number (bonds per sphere) vs A-Sect. 3.1",
        "",
        mean(cases_t.iter().map(|r| r.coordination_initial)),
        PAPER_COORDINATION,
    ));

    // The recipe: about 10 % porosity, 4-8 mm, d50 about 6 mm.
    let porosity = mean(cases_t.iter().map(|r| r.area_porosity));
    out.rows.push(Row::absolute(
        "mean area porosity inside the bar vs A-Sect. 3's 'roughly 10 %'",
        "",
        porosity,
        0.10,
        0.02,
    ));
    let diameters: Vec<[f64; 3]> = SEEDS.iter().map(|&s| family.diameters(s)).collect();
    out.rows.push(Row::absolute(
        "mean d50 (by number) vs A-Sect. 6's 6.032 mm",
        "mm",
        1e3 * mean(diameters.iter().map(|d| d[0])),
        6.032,
        0.3,
    ));
    // Diameters are drawn in 4-8 mm and then scaled together to reach the porosity target
    // (`thm_vpn_mesh::random_packing`): the ratio stays at most 2, the range moves by the
    // scale factor.
    out.rows.push(Row::at_most(
        "largest over smallest diameter, most over seeds 1-5 (A-Sect. 3: 4-8 mm)",
        "",
        diameters.iter().map(|d| d[2] / d[1]).fold(0.0, f64::max),
        2.0 * (1.0 + 1e-12),
    ));
    out.rows.push(Row::reported(
        "smallest diameter over seeds 1-5 vs A-Sect. 3's 4 mm",
        "mm",
        1e3 * diameters.iter().map(|d| d[1]).fold(f64::INFINITY, f64::min),
        4.0,
    ));
    out.rows.push(Row::reported(
        "largest diameter over seeds 1-5 vs A-Sect. 3's 8 mm",
        "mm",
        1e3 * diameters
            .iter()
            .map(|d| d[2])
            .fold(f64::NEG_INFINITY, f64::max),
        8.0,
    ));

    // A-Sect. 3.2 at the cases' γ and at A-Table 1's, beside the Darcy test's packings.
    let test = DarcyTest::paper_a();
    let kappas = |gamma: f64| -> Result<Vec<f64>, CaseError> {
        SEEDS
            .iter()
            .map(|&seed| {
                let k = family
                    .permeability(seed, gamma, &test)
                    .map_err(CaseError::from_display)?;
                Ok(if k.percolates { k.kappa } else { 0.0 })
            })
            .collect()
    };
    let cases_kappa = kappas(BAR_T2T_REDUCTION_FACTOR)?;
    let geometric = |v: &[f64]| mean(v.iter().map(|k| k.ln())).exp();
    out.rows.push(Row::relative(
        format!(
            "geometric mean permeability of seeds 1-5 at the cases' gamma = {BAR_T2T_REDUCTION_FACTOR} vs A-Sect. 3.2"
        ),
        "m^2",
        geometric(&cases_kappa),
        PAPER_KAPPA,
        0.01,
    ));
    let paper_kappa = kappas(PAPER_GAMMA)?;
    let darcy: Vec<f64> = DARCY_SEEDS
        .map(|seed| {
            test.bar_permeability(seed, PAPER_GAMMA)
                .map(|k| if k.percolates { k.kappa } else { 0.0 })
                .map_err(CaseError::from_display)
        })
        .collect::<Result<_, _>>()?;
    let darcy_log: Vec<f64> = darcy
        .iter()
        .filter(|k| **k > 0.0)
        .map(|k| k.log10())
        .collect();
    let darcy_median = median(darcy_log.clone());
    let darcy_sigma = 1.4826 * median(darcy_log.iter().map(|l| (l - darcy_median).abs()).collect());
    out.rows.push(Row::reported(
        "geometric mean permeability at A-Table 1's gamma = 0.0115 vs A-Sect. 3.2",
        "m^2",
        geometric(&paper_kappa),
        PAPER_KAPPA,
    ));
    out.rows.push(Row::reported(
        format!(
            "median log10 permeability at gamma = 0.0115 minus the Darcy test's ensemble median \
             (its 2 robust standard deviations: {:.3})",
            2.0 * darcy_sigma
        ),
        "",
        median(paper_kappa.iter().map(|k| k.log10()).collect()) - darcy_median,
        0.0,
    ));

    // No pore sealed by construction.
    let mut sealed = Vec::new();
    for &seed in &SEEDS {
        sealed.push(family.sealed_pores(seed).map_err(CaseError::from_display)? as f64);
    }
    out.rows.push(Row::at_most(
        "pores joined to no boundary link, most over seeds 1-5 (every pore either connected or an enclosed void: none of the latter in these packings)",
        "",
        sealed.iter().copied().fold(0.0, f64::max),
        0.0,
    ));

    out.notes.push(format!(
        "strength by seed at T = {:.2} MPa: {} MPa; at 30 MPa: {} MPa",
        CASE_A_BOND_TENSILE_STRENGTH / 1e6,
        list(&strengths, 1e6),
        list(&paper_t.iter().map(|r| r.strength).collect::<Vec<_>>(), 1e6)
    ));
    out.notes.push(format!(
        "permeability by seed [1e-16 m^2] at gamma = {BAR_T2T_REDUCTION_FACTOR}: {}; at 0.0115: {}; \
         the Darcy test's packings 1-12 at 0.0115 (0: no pore path): {}, median {:.3}",
        list(&cases_kappa, 1e-16),
        list(&paper_kappa, 1e-16),
        list(&darcy, 1e-16),
        10f64.powf(darcy_median) / 1e-16
    ));
    out.notes.push(format!(
        "d50 / smallest / largest diameter by seed [mm]: {}",
        diameters
            .iter()
            .map(|d| format!("{:.2}/{:.2}/{:.2}", 1e3 * d[0], 1e3 * d[1], 1e3 * d[2]))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    Ok(out)
}
