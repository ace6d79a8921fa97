//! ParaView series of the RVEs of tracked material points (the disks and contact-force
//! network of B-Fig. 17 of Zhao et al. 2022): per tracked point `NAME`, the series
//! `NAME_disks` (disk centres with radius, fluctuating velocity and temperature),
//! `NAME_contacts` (one segment per listed contact from disk `a` along its branch vector, with
//! the normal force, compression positive, and whether a bond holds it) and `NAME_cell` (the
//! periodic cell's outline, the columns of **H** from the origin).

use thm_dem::BondState;
use thm_io::{FieldValues, IoError, UnstructuredGrid};
use thm_rve::RveState;

use crate::scenario::FrameSink;

/// Scratch for writing RVE frames (reused between frames).
#[derive(Debug, Default)]
pub struct RveFrames {
    centre: Vec<[f64; 2]>,
    velocity: Vec<[f64; 2]>,
    ends: Vec<[f64; 2]>,
    lines: Vec<[u32; 2]>,
    normal_force: Vec<f64>,
    bonded: Vec<i32>,
}

impl RveFrames {
    /// Writes the three series of `rve` under the name `name`.
    pub fn write(
        &mut self,
        name: &str,
        rve: &RveState,
        sink: &mut FrameSink<'_>,
    ) -> Result<(), IoError> {
        let d = &rve.disks;
        self.centre.clear();
        self.centre.extend(d.position.iter().map(|x| [x.x, x.y]));
        self.velocity.clear();
        self.velocity.extend(d.velocity.iter().map(|v| [v.x, v.y]));
        let disks = UnstructuredGrid::particles(&self.centre)
            .with_point_field("radius [m]", FieldValues::Scalar(&d.radius))
            .with_point_field(
                "fluctuating_velocity [m/s]",
                FieldValues::Vector2(&self.velocity),
            )
            .with_point_field("temperature [K]", FieldValues::Scalar(&d.temperature));
        sink(&format!("{name}_disks"), &disks)?;

        let c = &rve.contacts;
        self.ends.clear();
        self.lines.clear();
        self.normal_force.clear();
        self.bonded.clear();
        for k in 0..c.len() {
            let [a, _] = c.pair[k];
            let Some(&xa) = self.centre.get(a as usize) else {
                continue;
            };
            let b = c.branch[k];
            let l = (b.x * b.x + b.y * b.y).sqrt();
            let f = c.force_on_b[k];
            let intact = c.history[k].bond == BondState::Intact;
            if l <= 0.0 || (f.x == 0.0 && f.y == 0.0 && !intact) {
                continue;
            }
            let first = self.ends.len() as u32;
            self.ends.push(xa);
            self.ends.push([xa[0] + b.x, xa[1] + b.y]);
            self.lines.push([first, first + 1]);
            self.normal_force.push((f.x * b.x + f.y * b.y) / l);
            self.bonded.push(i32::from(intact));
        }
        let contacts = UnstructuredGrid::lines(&self.ends, &self.lines)
            .with_cell_field(
                "normal_force [N] (compression > 0)",
                FieldValues::Scalar(&self.normal_force),
            )
            .with_cell_field("bonded", FieldValues::Int(&self.bonded));
        sink(&format!("{name}_contacts"), &contacts)?;

        let h = rve.cell.matrix().0;
        let (a1, a2) = ([h[0][0], h[1][0]], [h[0][1], h[1][1]]);
        let corners = [[0.0, 0.0], a1, [a1[0] + a2[0], a1[1] + a2[1]], a2];
        let edges: [[u32; 2]; 4] = [[0, 1], [1, 2], [2, 3], [3, 0]];
        let cell = UnstructuredGrid::lines(&corners[..], &edges[..]);
        sink(&format!("{name}_cell"), &cell)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use thm_rve::measure;
    use thm_rve::verification::consolidated_packing;

    #[test]
    fn the_written_network_carries_the_rve_stress() {
        // tr σ = (1/V) Σ_c f·b = (1/V) Σ_c f_n |b| (B-Eq. 49, contact part): the segments and
        // normal forces written give back the trace of thm-rve's contact stress.
        let (config, state, _) = consolidated_packing(60, 3, 0.5).expect("packing");
        let z = config.params().thickness;
        let mut frames = RveFrames::default();
        let mut written = Vec::new();
        let mut sink = |name: &str, grid: &UnstructuredGrid<'_>| {
            written.push((name.to_string(), grid.n_cells()));
            Ok(())
        };
        frames.write("rve_0", &state, &mut sink).expect("write");
        assert_eq!(
            written,
            vec![
                ("rve_0_disks".to_string(), state.disks.len()),
                ("rve_0_contacts".to_string(), frames.lines.len()),
                ("rve_0_cell".to_string(), 4),
            ]
        );
        assert!(frames.lines.len() > state.disks.len());
        let trace: f64 = frames
            .lines
            .iter()
            .zip(&frames.normal_force)
            .map(|(l, f)| {
                let (a, b) = (frames.ends[l[0] as usize], frames.ends[l[1] as usize]);
                f * (b[0] - a[0]).hypot(b[1] - a[1])
            })
            .sum::<f64>()
            / state.volume(z);
        let s = measure::contact_stress(&state, z).0;
        let expected = s[0][0] + s[1][1];
        assert!(
            expected > 1.9e5,
            "consolidated to 100 kPa: tr σ = {expected}"
        );
        assert!(
            (trace - expected).abs() <= 1e-12 * expected,
            "{trace} vs {expected}"
        );
    }
}

/// Scratch for the per-point RVE fields of the material-point frames of the MPM×DEM kinds:
/// `ε_q` of B-Eq. 48 (n = 2) from the point's accumulated small strain, the RVE's void ratio
/// (void over solid area), coordination number and intact bonds.
#[derive(Debug, Default)]
pub struct PointRveFields {
    /// `ε_q` per point.
    pub deviatoric_strain: Vec<f64>,
    /// Void ratio per point.
    pub void_ratio: Vec<f64>,
    /// Coordination number per point.
    pub coordination: Vec<f64>,
    /// Intact bonds per point.
    pub intact_bonds: Vec<f64>,
}

impl PointRveFields {
    /// Fills the fields from the points' strains and their RVEs.
    pub fn fill(
        &mut self,
        strain: &[thm_mpm::points::Sym2],
        material: &[thm_coupling::multiscale::RvePoint],
    ) {
        self.deviatoric_strain.clear();
        self.deviatoric_strain.extend(strain.iter().map(|e| {
            let half = 0.5 * (e[0] - e[1]);
            (2.0 * (half * half + e[2] * e[2])).sqrt()
        }));
        self.void_ratio.clear();
        self.void_ratio
            .extend(material.iter().map(|p| p.rve.void_ratio()));
        self.coordination.clear();
        self.coordination
            .extend(material.iter().map(|p| p.rve.coordination_number()));
        self.intact_bonds.clear();
        self.intact_bonds.extend(
            material
                .iter()
                .map(|p| p.rve.contacts.intact_bond_count() as f64),
        );
    }

    /// Adds the four fields to `grid`.
    pub fn add_to<'a>(&'a self, grid: UnstructuredGrid<'a>) -> UnstructuredGrid<'a> {
        self.add_rve_to(grid.with_point_field(
            "deviatoric_strain",
            FieldValues::Scalar(&self.deviatoric_strain),
        ))
    }

    /// Adds the three RVE fields (void ratio, coordination, intact bonds) to `grid`.
    pub fn add_rve_to<'a>(&'a self, grid: UnstructuredGrid<'a>) -> UnstructuredGrid<'a> {
        grid.with_point_field("rve_void_ratio", FieldValues::Scalar(&self.void_ratio))
            .with_point_field("rve_coordination", FieldValues::Scalar(&self.coordination))
            .with_point_field("rve_intact_bonds", FieldValues::Scalar(&self.intact_bonds))
    }
}
