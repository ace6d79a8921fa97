//! Independent numerical reference solutions for the verification cases (feature
//! `verification`): staggered-grid finite-difference solvers of the 1D dynamic thermo-elastic
//! bar (Danilovskaya problem, B-Sect. 5.1.1) and of the plate heated on two sides
//! (B-Sect. 5.1.2). The closed forms they are checked with are in [`crate::analytical`].

use crate::analytical::{heated_insulated_profile, semi_infinite_temperature};

/// Samples of the 1D dynamic thermo-elastic bar.
#[derive(Debug, Clone, PartialEq)]
pub struct BarHistory {
    /// Sample times (s).
    pub time: Vec<f64>,
    /// Axial stress at the probe (Pa).
    pub stress: Vec<f64>,
    /// Axial displacement at the probe (m).
    pub displacement: Vec<f64>,
}

/// Staggered-grid, second-order finite differences of the uncoupled dynamic thermo-elastic
/// bar `ρ ü = ∂σ/∂x`, `σ = M (∂u/∂x − β (T − T0))`, on `[0, length]` with both ends free
/// (`σ = 0`), temperature from B-Eq. 52. Velocities at nodes `i dx`, stresses at cell centres,
/// leapfrog in time with `dt = courant · dx / √(M/ρ)`. Returns σ and u at `probe` (a node:
/// `probe / dx` must be an integer) at the `sample_times`.
#[allow(clippy::too_many_arguments)]
pub fn thermoelastic_bar_fd(
    length: f64,
    cells: usize,
    modulus: f64,
    density: f64,
    expansion: f64,
    diffusivity: f64,
    t_heat: f64,
    courant: f64,
    probe: f64,
    sample_times: &[f64],
) -> BarHistory {
    let dx = length / cells as f64;
    let c = (modulus / density).sqrt();
    let t_end = sample_times.iter().fold(0.0f64, |a, &b| a.max(b));
    let steps_per_unit = 1.0 / (courant * dx / c);
    let nsteps = (t_end * steps_per_unit).ceil() as usize;
    let dt = t_end / nsteps as f64;
    let ip = (probe / dx).round() as usize;
    let mut u = vec![0.0; cells + 1];
    let mut v = vec![0.0; cells + 1];
    let mut sig = vec![0.0; cells];
    let stress_at = |u: &[f64], sig: &mut [f64], t: f64| {
        for i in 0..cells {
            let xc = (i as f64 + 0.5) * dx;
            let th = semi_infinite_temperature(xc, t, diffusivity, 0.0, t_heat);
            sig[i] = modulus * ((u[i + 1] - u[i]) / dx - expansion * th);
        }
    };
    stress_at(&u, &mut sig, 0.0);
    // Half step for v: v^{1/2} = v^0 + dt/2 a^0.
    let accel = |sig: &[f64], i: usize| -> f64 {
        if i == 0 {
            2.0 * sig[0] / (density * dx)
        } else if i == cells {
            -2.0 * sig[cells - 1] / (density * dx)
        } else {
            (sig[i] - sig[i - 1]) / (density * dx)
        }
    };
    for (i, vi) in v.iter_mut().enumerate() {
        *vi += 0.5 * dt * accel(&sig, i);
    }
    let mut out = BarHistory {
        time: Vec::new(),
        stress: Vec::new(),
        displacement: Vec::new(),
    };
    let mut next = 0;
    let probe_values = |u: &[f64], sig: &[f64]| (0.5 * (sig[ip - 1] + sig[ip]), u[ip]);
    let mut prev = (0.0, probe_values(&u, &sig));
    for n in 1..=nsteps {
        let t = n as f64 * dt;
        for i in 0..=cells {
            u[i] += dt * v[i];
        }
        stress_at(&u, &mut sig, t);
        for (i, vi) in v.iter_mut().enumerate() {
            *vi += dt * accel(&sig, i);
        }
        let now = probe_values(&u, &sig);
        // Linear interpolation in time between steps onto the sample times.
        while next < sample_times.len() && sample_times[next] <= t + 1e-12 * dt {
            let ts = sample_times[next];
            let f = ((ts - prev.0) / dt).clamp(0.0, 1.0);
            out.time.push(ts);
            out.stress.push((1.0 - f) * prev.1.0 + f * now.0);
            out.displacement.push((1.0 - f) * prev.1.1 + f * now.1);
            next += 1;
        }
        prev = (t, now);
    }
    out
}

/// Stress histories `[probe][sample]` of the 2D plate FD solver.
#[derive(Debug, Clone, PartialEq)]
pub struct PlateHistory {
    /// Sample times (s).
    pub time: Vec<f64>,
    /// σxx (Pa).
    pub sxx: Vec<Vec<f64>>,
    /// σyy (Pa).
    pub syy: Vec<Vec<f64>>,
}

/// Staggered-grid (Virieux) velocity–strain finite differences of the dynamic thermo-elastic
/// plate of B-Sect. 5.1.2: `[−0.5, 0.5]²`, plane strain, `σ = λ tr ε I + 2G ε − 2(λ+G) β T I`
/// (the 2D reading of B-Eq. 51 used by the crate), `u_x = 0` and `σxy = 0` on the left,
/// `u_y = 0` and `σxy = 0` at the bottom, traction-free top and right. The temperature is the
/// exact series `T = 1 − θ(x)θ(y)` (heated left and bottom, insulated top and right).
/// Normal stresses at cell centres, shear at nodes, `v_x` on vertical and `v_y` on horizontal
/// faces; leapfrog with `dt = courant · d / c_p`. Probes must sit on nodes; their normal
/// stresses are the average of the four adjacent cells. `cells` must be even.
#[allow(clippy::too_many_arguments)]
pub fn thermoelastic_plate_fd(
    cells: usize,
    youngs_modulus: f64,
    poisson_ratio: f64,
    density: f64,
    expansion: f64,
    diffusivity: f64,
    courant: f64,
    probes: &[[f64; 2]],
    sample_times: &[f64],
) -> PlateHistory {
    let n = cells;
    let d = 1.0 / n as f64;
    let e = youngs_modulus;
    let nu = poisson_ratio;
    let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let g = e / (2.0 * (1.0 + nu));
    let cp = ((lam + 2.0 * g) / density).sqrt();
    let t_end = sample_times.iter().fold(0.0f64, |a, &b| a.max(b));
    let nsteps = (t_end / (courant * d / cp)).ceil() as usize;
    let dt = t_end / nsteps as f64;
    // Cell-centred strains, node shear strain, face velocities.
    let c = |i: usize, j: usize| j * n + i;
    let nd = |i: usize, j: usize| j * (n + 1) + i;
    let mut exx = vec![0.0; n * n];
    let mut eyy = vec![0.0; n * n];
    let mut exy = vec![0.0; (n + 1) * (n + 1)];
    // vx at (i d, (j+1/2) d): index j*(n+1)+i; vy at ((i+1/2) d, j d): index j*n+i.
    let mut vx = vec![0.0; (n + 1) * n];
    let mut vy = vec![0.0; n * (n + 1)];
    let mut sxx = vec![0.0; n * n];
    let mut syy = vec![0.0; n * n];
    let mut sxy = vec![0.0; (n + 1) * (n + 1)];
    let mut theta = vec![0.0; n];
    let thermal = 2.0 * (lam + g) * expansion;
    let stresses = |t: f64,
                    exx: &[f64],
                    eyy: &[f64],
                    exy: &[f64],
                    theta: &mut [f64],
                    sxx: &mut [f64],
                    syy: &mut [f64],
                    sxy: &mut [f64]| {
        for (k, th) in theta.iter_mut().enumerate() {
            *th = heated_insulated_profile((k as f64 + 0.5) * d, 1.0, diffusivity, t);
        }
        for j in 0..n {
            for i in 0..n {
                let temp = 1.0 - theta[i] * theta[j];
                let tr = exx[c(i, j)] + eyy[c(i, j)];
                sxx[c(i, j)] = lam * tr + 2.0 * g * exx[c(i, j)] - thermal * temp;
                syy[c(i, j)] = lam * tr + 2.0 * g * eyy[c(i, j)] - thermal * temp;
            }
        }
        for (k, s) in sxy.iter_mut().enumerate() {
            *s = 2.0 * g * exy[k];
        }
    };
    let accelerate =
        |h: f64, sxx: &[f64], syy: &[f64], sxy: &[f64], vx: &mut [f64], vy: &mut [f64]| {
            for j in 0..n {
                for i in 1..=n {
                    let k = j * (n + 1) + i;
                    let a = if i < n {
                        (sxx[c(i, j)] - sxx[c(i - 1, j)]) / d
                            + (sxy[nd(i, j + 1)] - sxy[nd(i, j)]) / d
                    } else {
                        // Free right face: σxx = 0 on the boundary, half cell.
                        (0.0 - sxx[c(n - 1, j)]) / (0.5 * d)
                    };
                    vx[k] += h * a / density;
                }
            }
            for j in 1..=n {
                for i in 0..n {
                    let k = j * n + i;
                    let a = if j < n {
                        (syy[c(i, j)] - syy[c(i, j - 1)]) / d
                            + (sxy[nd(i + 1, j)] - sxy[nd(i, j)]) / d
                    } else {
                        (0.0 - syy[c(i, n - 1)]) / (0.5 * d)
                    };
                    vy[k] += h * a / density;
                }
            }
        };
    stresses(
        0.0, &exx, &eyy, &exy, &mut theta, &mut sxx, &mut syy, &mut sxy,
    );
    accelerate(0.5 * dt, &sxx, &syy, &sxy, &mut vx, &mut vy);
    let probe_idx: Vec<(usize, usize)> = probes
        .iter()
        .map(|p| {
            (
                ((p[0] + 0.5) / d).round() as usize,
                ((p[1] + 0.5) / d).round() as usize,
            )
        })
        .collect();
    let sample = |sxx: &[f64], syy: &[f64]| -> Vec<(f64, f64)> {
        probe_idx
            .iter()
            .map(|&(i, j)| {
                let avg = |s: &[f64]| {
                    0.25 * (s[c(i - 1, j - 1)] + s[c(i, j - 1)] + s[c(i - 1, j)] + s[c(i, j)])
                };
                (avg(sxx), avg(syy))
            })
            .collect()
    };
    let mut out = PlateHistory {
        time: Vec::new(),
        sxx: vec![Vec::new(); probes.len()],
        syy: vec![Vec::new(); probes.len()],
    };
    let mut prev = (0.0, sample(&sxx, &syy));
    let mut next = 0;
    for step in 1..=nsteps {
        let t = step as f64 * dt;
        for j in 0..n {
            for i in 0..n {
                exx[c(i, j)] += dt * (vx[j * (n + 1) + i + 1] - vx[j * (n + 1) + i]) / d;
                eyy[c(i, j)] += dt * (vy[(j + 1) * n + i] - vy[j * n + i]) / d;
            }
        }
        for j in 1..n {
            for i in 1..n {
                let dvx_dy = (vx[j * (n + 1) + i] - vx[(j - 1) * (n + 1) + i]) / d;
                let dvy_dx = (vy[j * n + i] - vy[j * n + i - 1]) / d;
                exy[nd(i, j)] += dt * 0.5 * (dvx_dy + dvy_dx);
            }
        }
        stresses(
            t, &exx, &eyy, &exy, &mut theta, &mut sxx, &mut syy, &mut sxy,
        );
        accelerate(dt, &sxx, &syy, &sxy, &mut vx, &mut vy);
        let now = sample(&sxx, &syy);
        while next < sample_times.len() && sample_times[next] <= t + 1e-12 * dt {
            let ts = sample_times[next];
            let f = ((ts - prev.0) / dt).clamp(0.0, 1.0);
            out.time.push(ts);
            for (k, (p, q)) in prev.1.iter().zip(&now).enumerate() {
                out.sxx[k].push((1.0 - f) * p.0 + f * q.0);
                out.syy[k].push((1.0 - f) * p.1 + f * q.1);
            }
            next += 1;
        }
        prev = (t, now);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Prints the convergence of the FD bar at Courant numbers 0.5 and 1 (development aid).
    #[test]
    #[ignore]
    fn print_bar_fd_convergence() {
        let ts: Vec<f64> = (1..=300).map(|k| k as f64 * 0.01).collect();
        for courant in [0.5, 1.0] {
            let r: Vec<_> = [300, 600, 1200, 2400, 4800]
                .iter()
                .map(|&c| {
                    thermoelastic_bar_fd(6.0, c, 1.0, 1.0, 1e-6, 1.0, 100.0, courant, 1.0, &ts)
                })
                .collect();
            for k in 0..4 {
                let d = r[k]
                    .stress
                    .iter()
                    .zip(&r[4].stress)
                    .zip(&ts)
                    .filter(|(_, t)| (**t - 1.0).abs() > 0.2)
                    .map(|((a, b), _)| (a - b).abs())
                    .fold(0.0f64, f64::max);
                println!("courant {courant} level {k}: {:.3e}", d / 1e-4);
            }
        }
    }

    /// Prints the convergence of the FD plate (development aid).
    #[test]
    #[ignore]
    fn print_plate_fd_convergence() {
        let ts: Vec<f64> = (1..=50).map(|k| k as f64 * 0.01).collect();
        let probes = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1]];
        let r: Vec<_> = [40, 80, 160, 320]
            .iter()
            .map(|&c| thermoelastic_plate_fd(c, 1.0, 0.25, 1.0, 1e-6, 0.1, 0.5, &probes, &ts))
            .collect();
        for k in 0..3 {
            let d = r[k].sxx[0]
                .iter()
                .zip(&r[3].sxx[0])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f64, f64::max);
            println!("level {k}: max dσxx(A) = {d:.3e}");
        }
        for (i, t) in ts.iter().enumerate().step_by(5) {
            println!(
                "t {t:.2}: A sxx {:.4e} syy {:.4e} | B {:.4e} {:.4e} | C {:.4e} {:.4e}",
                r[3].sxx[0][i],
                r[3].syy[0][i],
                r[3].sxx[1][i],
                r[3].syy[1][i],
                r[3].sxx[2][i],
                r[3].syy[2][i]
            );
        }
    }
}
