//! The TM-MPM problems of Zhao et al. (2022), B-Sects. 5.1–5.2, as models ready to step:
//! the semi-infinite bar (B-Sect. 5.1.1), the plate heated on two sides (B-Sect. 5.1.2) and
//! the heated square with the TM-MPM properties (B-Sect. 5.2.2). The scenario kind
//! `mpm_semi_infinite_bar` and the multiscale square's pure-MPM twin run them; the
//! verification cases (feature `verification`) check them against [`crate::analytical`] and
//! finite-difference references.

use crate::boundary::{NodeSet, Side, TemperatureCondition, VelocityCondition};
use crate::config::{MpmConfig, MpmParameters};
use crate::error::MpmError;
use crate::grid::GridParameters;
use crate::material::{LinearThermoElastic, ThermoElasticParameters};
use crate::points::{MaterialPoints, PointProperties};
use crate::stepper::{Mpm, MpmState};

/// A model ready to step: stepper, state, material.
#[derive(Debug)]
pub struct Model {
    /// Stepper.
    pub mpm: Mpm,
    /// State.
    pub state: MpmState<()>,
    /// Material.
    pub material: LinearThermoElastic,
}

/// Semi-infinite bar of B-Sect. 5.1.1 on `cells` cells of a 6 m bar (one point per cell),
/// unit ρ, c, E, k, ν = 0, β = 1e-6, heated to 100 at x = 0 from 0, α_PIC = 1e-4. The grid
/// has two padding cells left of x = 0 (the free heated end expands into them) and is two
/// cells high, with `v_y = 0` on every node (uniaxial strain).
pub fn semi_infinite_bar(cells: usize) -> Result<Model, MpmError> {
    let length = 6.0;
    let h = length / cells as f64;
    let pad = 2;
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [-(pad as f64) * h, 0.0],
        cell_size: h,
        cells: [cells + 2 * pad, 2],
    });
    params.pic_fraction = 1e-4;
    params.velocity_conditions.push(VelocityCondition {
        nodes: NodeSet::All,
        fix_x: false,
        fix_y: true,
    });
    params.temperature_conditions.push(TemperatureCondition {
        nodes: NodeSet::Region {
            lower: [-1.0, -1.0],
            upper: [1e-9 * h, 1.0],
        },
        temperature: 100.0,
    });
    let config = MpmConfig::new(params)?;
    let material = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1.0,
        poisson_ratio: 0.0,
        thermal_expansion: 1e-6,
        conductivity: [1.0, 1.0, 0.0],
    })?;
    let mut points = MaterialPoints::new();
    points.fill_rectangle(
        config.grid(),
        [0.0, 0.0],
        [length, h],
        1,
        &PointProperties {
            density: 1.0,
            specific_heat: 1.0,
            conductivity: [1.0, 1.0, 0.0],
            temperature: 0.0,
            velocity: [0.0; 2],
        },
    )?;
    let state = MpmState::new(points, &material);
    Ok(Model {
        mpm: Mpm::new(config),
        state,
        material,
    })
}

/// The 2D plate of B-Sect. 5.1.2 on `cells × cells` cells with `per_cell²` points per cell:
/// plate `[−0.5, 0.5]²`, ρ = c = E = 1, k = 0.1, ν = 0.25, β = 1e-6, `u_x = 0` on the left,
/// `u_y = 0` at the bottom, T = 1 on both; grid padded by one cell right and top.
pub fn heated_plate(cells: usize, per_cell: usize) -> Result<Model, MpmError> {
    let h = 1.0 / cells as f64;
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [-0.5, -0.5],
        cell_size: h,
        cells: [cells + 1, cells + 1],
    });
    params.velocity_conditions = vec![
        VelocityCondition {
            nodes: NodeSet::Side(Side::Left),
            fix_x: true,
            fix_y: false,
        },
        VelocityCondition {
            nodes: NodeSet::Side(Side::Bottom),
            fix_x: false,
            fix_y: true,
        },
    ];
    params.temperature_conditions = vec![
        TemperatureCondition {
            nodes: NodeSet::Side(Side::Left),
            temperature: 1.0,
        },
        TemperatureCondition {
            nodes: NodeSet::Side(Side::Bottom),
            temperature: 1.0,
        },
    ];
    let config = MpmConfig::new(params)?;
    let material = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1.0,
        poisson_ratio: 0.25,
        thermal_expansion: 1e-6,
        conductivity: [0.1, 0.1, 0.0],
    })?;
    let mut points = MaterialPoints::new();
    points.fill_rectangle(
        config.grid(),
        [-0.5, -0.5],
        [0.5, 0.5],
        per_cell,
        &PointProperties {
            density: 1.0,
            specific_heat: 1.0,
            conductivity: [0.1, 0.1, 0.0],
            temperature: 0.0,
            velocity: [0.0; 2],
        },
    )?;
    let state = MpmState::new(points, &material);
    Ok(Model {
        mpm: Mpm::new(config),
        state,
        material,
    })
}

/// The TM-MPM square of B-Sect. 5.2.2: `[0, 1]²`, 40 × 40 cells, one point per cell,
/// ρ = 2650, c = 1/2650, k = 0.1, E = 12 MPa, ν = 0.18, β = 1e-4, T = 100 on all sides from 0,
/// normal velocity fixed on all sides. The grid is padded by one cell on every side.
pub fn heated_square(cells: usize) -> Result<Model, MpmError> {
    let h = 1.0 / cells as f64;
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [-h, -h],
        cell_size: h,
        cells: [cells + 2, cells + 2],
    });
    let eps = 1e-9 * h;
    let band = |lo: [f64; 2], hi: [f64; 2]| NodeSet::Region {
        lower: lo,
        upper: hi,
    };
    let left = band([-1.0, -1.0], [eps, 2.0]);
    let right = band([1.0 - eps, -1.0], [2.0, 2.0]);
    let bottom = band([-1.0, -1.0], [2.0, eps]);
    let top = band([-1.0, 1.0 - eps], [2.0, 2.0]);
    for (nodes, fx, fy) in [
        (left, true, false),
        (right, true, false),
        (bottom, false, true),
        (top, false, true),
    ] {
        params.velocity_conditions.push(VelocityCondition {
            nodes,
            fix_x: fx,
            fix_y: fy,
        });
        params.temperature_conditions.push(TemperatureCondition {
            nodes,
            temperature: 100.0,
        });
    }
    let config = MpmConfig::new(params)?;
    let material = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 12e6,
        poisson_ratio: 0.18,
        thermal_expansion: 1e-4,
        conductivity: [0.1, 0.1, 0.0],
    })?;
    let mut points = MaterialPoints::new();
    points.fill_rectangle(
        config.grid(),
        [0.0, 0.0],
        [1.0, 1.0],
        1,
        &PointProperties {
            density: 2650.0,
            specific_heat: 1.0 / 2650.0,
            conductivity: [0.1, 0.1, 0.0],
            temperature: 0.0,
            velocity: [0.0; 2],
        },
    )?;
    let state = MpmState::new(points, &material);
    Ok(Model {
        mpm: Mpm::new(config),
        state,
        material,
    })
}
