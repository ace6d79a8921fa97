//! Verification cases of this crate, collected by `cargo xtask verify`.
//!
//! - `eos/critical_point_water`, `eos/critical_point_air`: the critical-point identities of
//!   A-Eq. 16 (∂P/∂V = ∂²P/∂V² = 0 at T_c, P = P_c, Z_c = 0.3074).
//! - `eos/water_density_0.1MPa`: the corrected liquid water density against IAPWS-95.
//! - `eos/closure_80_20_368K`: the closure of the thermal contraction test's initial pore.
//! - `eos/thermal_pressurisation`: ∂P/∂T at constant density, the paper's model against real
//!   water (IAPWS-IF97).

use crate::{
    Branch, EquationOfState, Iapws97Water, Model, PengRobinson, PoreClosure, water_air_closure,
};
use thm_verify::{Case, CaseError, CaseOutput, Plot, Row, Series, SeriesRole};

/// Liquid water density at 0.1 MPa from IAPWS-95 (Wagner & Pruß 2002, J. Phys. Chem. Ref. Data
/// 31, 387–535), rounded to 0.01 kg/m³: (T (K), ρ (kg/m³)). A unit test checks every entry
/// against IAPWS-IF97 (seuif97), which agrees with IAPWS-95 to better than 0.005 % here.
pub const IAPWS95_WATER_DENSITY_0_1_MPA: [(f64, f64); 12] = [
    (278.15, 999.97),
    (283.15, 999.70),
    (293.15, 998.21),
    (298.15, 997.05),
    (303.15, 995.65),
    (313.15, 992.22),
    (323.15, 988.03),
    (333.15, 983.20),
    (343.15, 977.76),
    (353.15, 971.79),
    (363.15, 965.31),
    (368.15, 961.89),
];

/// Critical compressibility factor of the Peng–Robinson equation, Z_c = 0.3074 (Peng & Robinson
/// 1976; the exact value with unrounded Ω constants is 0.307401).
pub const CRITICAL_COMPRESSIBILITY: f64 = 0.3074;

/// All verification cases of `thm-eos`.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "eos/critical_point_water",
            description: "PR critical-point identities for water: dP/dV = d2P/dV2 = 0, P = P_c, Z_c = 0.3074",
            quick: true,
            run: || critical_point(PengRobinson::water(Model::Pr), "water"),
        },
        Case {
            name: "eos/critical_point_air",
            description: "PR critical-point identities for air: dP/dV = d2P/dV2 = 0, P = P_c, Z_c = 0.3074",
            quick: true,
            run: || critical_point(PengRobinson::air(), "air"),
        },
        Case {
            name: "eos/water_density_0.1MPa",
            description: "corrected PR liquid water density at 0.1 MPa, 278-368 K, against IAPWS-95",
            quick: true,
            run: water_density,
        },
        Case {
            name: "eos/closure_80_20_368K",
            description: "closure of 80 % water / 20 % air at 0.1 MPa, 368.16 K gives back alpha = 0.8, P = 0.1 MPa",
            quick: true,
            run: closure_80_20,
        },
        Case {
            name: "eos/thermal_pressurisation",
            description: "dP/dT at constant density of a sealed water-filled pore: corrected PR against IAPWS-IF97",
            quick: true,
            run: thermal_pressurisation,
        },
    ]
}

fn err(e: impl std::fmt::Display) -> CaseError {
    CaseError::from_display(e)
}

/// `∂P/∂V` (Pa·kmol/m³) at molar volume `v` of an uncorrected fluid, from the analytic ∂P/∂ρ.
fn dp_dv(eos: &PengRobinson, t: f64, v: f64) -> Result<f64, CaseError> {
    let w = eos.molar_mass();
    let rho = w / v;
    // ρ = w/V: ∂P/∂V = ∂P/∂ρ · (−w/V²).
    Ok(-eos.dp_drho(t, rho).map_err(err)? * w / (v * v))
}

/// The equation's own critical point: `θ(T) = 2a(T)/(R T b)` equals `L(x_m)` (see
/// `BRANCH_SPLIT`), found by bisection on T, at `V = x_m b`. There `∂P/∂V = ∂²P/∂V² = 0`; the
/// rows check these identities to round-off and compare (T, P, Z) with (T_c, P_c, 0.3074).
fn critical_point(eos: PengRobinson, fluid: &str) -> Result<CaseOutput, CaseError> {
    use crate::peng_robinson::{BRANCH_SPLIT, CRITICAL_THETA};
    let p = eos.parameters();
    let (tc, pc) = (p.critical_temperature, p.critical_pressure);
    let b = eos.covolume();
    let theta = |t: f64| 2.0 * eos.attraction(t) / (crate::GAS_CONSTANT * t * b);
    // θ decreases with T: bisect θ(T) = L(x_m) on [0.9 T_c, 1.1 T_c].
    let (mut lo, mut hi) = (0.9 * tc, 1.1 * tc);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if theta(mid) > CRITICAL_THETA {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t_star = 0.5 * (lo + hi);
    let v_star = BRANCH_SPLIT * b;
    let p_star = eos.pressure_at_molar_volume(t_star, v_star);
    let z = p_star * v_star / (crate::GAS_CONSTANT * t_star);
    // Second derivative by a central difference of the analytic first derivative
    // (truncation O(h²) ≈ 1e-8 in the scaled value).
    let h = 1e-4 * v_star;
    let d2 = (dp_dv(&eos, t_star, v_star + h)? - dp_dv(&eos, t_star, v_star - h)?) / (2.0 * h);
    Ok(CaseOutput {
        rows: vec![
            Row::absolute(
                format!("{fluid}: (V_c/P_c) dP/dV at the critical point"),
                "",
                v_star / p_star * dp_dv(&eos, t_star, v_star)?,
                0.0,
                1e-10,
            ),
            Row::absolute(
                format!("{fluid}: (V_c^2/P_c) d2P/dV2 at the critical point"),
                "",
                v_star * v_star / p_star * d2,
                0.0,
                1e-6,
            ),
            Row::relative(
                format!("{fluid}: critical temperature"),
                "K",
                t_star,
                tc,
                1e-4,
            ),
            Row::relative(
                format!("{fluid}: critical pressure"),
                "Pa",
                p_star,
                pc,
                1e-4,
            ),
            Row::absolute(
                format!("{fluid}: Z_c = P_c V_c / (R T_c)"),
                "",
                z,
                CRITICAL_COMPRESSIBILITY,
                1e-4,
            ),
        ],
        plots: Vec::new(),
        notes: vec![
            "The identities dP/dV = d2P/dV2 = 0 hold to round-off at the equation's own critical \
             point. A-Eqs. 20-21 print Omega_a = 0.457247 and Omega_b = 0.07780, rounded from the \
             exact 0.4572355 and 0.0777961 (relative 2.5e-5 and 5e-5), so that point differs \
             from (T_c, P_c) of Table 1 and Z_c from 0.3074 by a few 1e-5: tolerance 1e-4."
                .into(),
        ],
    })
}

/// Corrected density at 0.1 MPa against IAPWS-95, and the rejected reading of the sign.
fn water_density() -> Result<CaseOutput, CaseError> {
    let corrected = PengRobinson::water(Model::PrCorrected);
    let plain = PengRobinson::water(Model::Pr);
    let p = 1.0e5;
    let mut rows = Vec::new();
    let mut measured = Series {
        label: "PR corrected (A-Eqs. 16, 23, 28)".into(),
        role: SeriesRole::Measured,
        x: Vec::new(),
        y: Vec::new(),
    };
    let mut reference = Series {
        label: "IAPWS-95".into(),
        role: SeriesRole::Reference,
        x: Vec::new(),
        y: Vec::new(),
    };
    let mut worst_in_claim: f64 = 0.0;
    for (t, rho_ref) in IAPWS95_WATER_DENSITY_0_1_MPA {
        let rho = corrected.density(t, p, Branch::Liquid).map_err(err)?;
        rows.push(Row::relative(
            format!("rho_liquid(T = {t} K, 0.1 MPa)"),
            "kg/m3",
            rho,
            rho_ref,
            0.03,
        ));
        if (303.0..=364.0).contains(&t) {
            worst_in_claim = worst_in_claim.max((rho / rho_ref - 1.0).abs());
        }
        measured.x.push(t);
        measured.y.push(rho);
        reference.x.push(t);
        reference.y.push(rho_ref);
    }
    rows.push(Row::at_most(
        "largest |rho/rho_IAPWS95 - 1| over 303-363 K",
        "",
        worst_in_claim,
        0.013,
    ));
    // The other reading of the sign (V_corr = V - s, i.e. the correction applied with the
    // opposite sign) is far from real water: it is rejected.
    let t = 293.15;
    let v = plain.molar_mass() / plain.density(t, p, Branch::Liquid).map_err(err)?;
    let rho_other = plain.molar_mass() / (v - crate::WATER_VOLUME_SHIFT);
    rows.push(Row::at_least(
        "other sign reading: |rho/rho_IAPWS95 - 1| at 293.15 K",
        "",
        (rho_other / 998.21 - 1.0).abs(),
        0.2,
    ));
    Ok(CaseOutput {
        rows,
        plots: vec![Plot {
            name: "water_density_0.1MPa".into(),
            title: "Liquid water density at 0.1 MPa".into(),
            x_label: "T [K]".into(),
            y_label: "rho [kg/m3]".into(),
            series: vec![measured, reference],
        }],
        notes: vec![
            "Sign convention: V_corr = V + s (A-Eq. 23) with s = -0.0034 m3/kmol, i.e. the cubic's \
             molar volume is V = w/rho - s (A-Eq. 28). The plain PR liquid is ~15 % too light; \
             this reading brings it within 3 %, the opposite one makes it ~27 % too light."
                .into(),
            "Paper A claims an error below 1.3 %. That holds from about 299 K to 363 K only: the \
             corrected density is 2.6 % too high at 278 K, 1.6 % at 293 K, 1.34 % at 298 K, and \
             1.4 % too low at 368 K. Tolerance per row: 3 %, what the model can do over 278-368 K."
                .into(),
        ],
    })
}

/// The thermal contraction test's initial pore (paper A, Sect. 6): 80 % water, 20 % air at
/// 0.1 MPa and 368.16 K, masses from the model's own densities.
fn closure_80_20() -> Result<CaseOutput, CaseError> {
    let (t, p, alpha, volume) = (368.16, 1.0e5, 0.8, 1.0e-9);
    let water = PengRobinson::water(Model::PrCorrected);
    let air = PengRobinson::air();
    let m_l = alpha * volume * water.density(t, p, Branch::Liquid).map_err(err)?;
    let m_g = (1.0 - alpha) * volume * air.density(t, p, Branch::Gas).map_err(err)?;
    let s = water_air_closure(Model::PrCorrected)
        .close(t, volume, m_l, m_g)
        .map_err(err)?;
    let p_l = water.pressure(t, s.liquid_density).map_err(err)?;
    let p_g = air.pressure(t, s.gas_density).map_err(err)?;
    Ok(CaseOutput {
        rows: vec![
            Row::absolute("liquid fraction alpha", "", s.liquid_fraction, alpha, 1e-12),
            Row::relative("pressure", "Pa", s.pressure, p, 1e-10),
            Row::at_most("|P_liquid - P_gas| / P", "", (p_l - p_g).abs() / p, 1e-10),
            Row::relative(
                "liquid mass alpha rho_l V",
                "kg",
                s.liquid_fraction * s.liquid_density * volume,
                m_l,
                1e-15,
            ),
            Row::relative(
                "gas mass (1 - alpha) rho_g V",
                "kg",
                s.gas_fraction * s.gas_density * volume,
                m_g,
                1e-15,
            ),
        ],
        plots: Vec::new(),
        notes: Vec::new(),
    })
}

/// ∂P/∂T at constant density of a water-filled pore sealed at 0.1 MPa: the corrected PR
/// against IAPWS-IF97, each at its own density.
fn thermal_pressurisation() -> Result<CaseOutput, CaseError> {
    let water = PengRobinson::water(Model::PrCorrected);
    let real = Iapws97Water;
    let p = 1.0e5;
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    for t in [278.15, 293.15, 323.15, 368.15] {
        let rho = water.density(t, p, Branch::Liquid).map_err(err)?;
        let rho_real = real.density(t, p, Branch::Liquid).map_err(err)?;
        let model = water.dp_dt(t, rho).map_err(err)?;
        let reference = real.dp_dt(t, rho_real).map_err(err)?;
        // The IF97 derivative itself, against a central difference of IF97's P(T, rho).
        let dt = 0.01;
        let fd = (real.pressure(t + dt, rho_real).map_err(err)?
            - real.pressure(t - dt, rho_real).map_err(err)?)
            / (2.0 * dt);
        rows.push(Row::relative(
            format!("IF97 dP/dT|rho at {t} K vs central difference"),
            "Pa/K",
            reference,
            fd,
            1e-4,
        ));
        rows.push(Row::at_least(
            format!("PR-corrected dP/dT|rho at {t} K >= real water {reference:.4e} Pa/K"),
            "Pa/K",
            model,
            reference,
        ));
        notes.push(format!(
            "T = {t} K: PR-corrected {:.3} MPa/K, IAPWS-IF97 {:.4} MPa/K, ratio {:.1}",
            model * 1e-6,
            reference * 1e-6,
            model / reference
        ));
    }
    notes.push(
        "The cubic overstates the pressure rise of a sealed liquid-filled pore per kelvin; use \
         Iapws97Water as the liquid where thermal pressurisation matters."
            .into(),
    );
    Ok(CaseOutput {
        rows,
        plots: Vec::new(),
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_passes() {
        for case in cases() {
            let out = (case.run)().unwrap();
            for row in &out.rows {
                assert!(row.pass, "{}: {row:?}", case.name);
            }
            assert!(out.passed(), "{}", case.name);
        }
    }

    /// The IAPWS-95 table agrees with IAPWS-IF97 to 3e-5 (the formulations differ by less than
    /// 0.005 % in liquid density here), which guards the table against transcription errors.
    #[test]
    fn iapws95_table_agrees_with_if97() {
        for (t, rho) in IAPWS95_WATER_DENSITY_0_1_MPA {
            let if97 = Iapws97Water.density(t, 1.0e5, Branch::Liquid).unwrap();
            assert!(
                (if97 / rho - 1.0).abs() < 3e-5,
                "T = {t}: IF97 {if97} vs {rho}"
            );
        }
    }
}
