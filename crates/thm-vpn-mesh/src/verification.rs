//! Verification cases of this crate, collected by `cargo xtask verify`.

use std::path::{Path, PathBuf};

use thm_verify::{Case, CaseError, CaseOutput, Row};

use crate::error::MeshError;
use crate::picture::{PictureStyle, write_mesh_png};

use crate::mesher::{Circle, MeshParams, Outline, PackingMesh, mesh_packing};
use crate::motion::{CircleMotion, MeshMotion};
use crate::packing::{PackingSpec, overlap_contacts, random_packing, union_area};
use crate::remap::{CellFilter, RemapOperator};

/// All verification cases of this crate.
pub fn cases() -> Vec<Case> {
    vec![Case {
        name: "vpn_mesh/paper_bar",
        description: "mesh of the 20 x 80 mm bar (paper A, Sect. 3): porosity against the exact \
                      union of discs, area identities, second-order convergence, motion and remap \
                      conservation",
        quick: true,
        run: paper_bar,
    }]
}

fn err(e: impl std::fmt::Display) -> CaseError {
    CaseError::from_display(e)
}

fn mesh_bar(cs: &[Circle], spec: &PackingSpec, n: u32) -> Result<PackingMesh, CaseError> {
    let s = MeshParams::new(
        Outline::Box {
            min: spec.box_min,
            max: spec.box_max,
        },
        n,
    )
    .validate()
    .map_err(err)?;
    mesh_packing(cs, &overlap_contacts(cs, 1e7), &s).map_err(err)
}

fn paper_bar() -> Result<CaseOutput, CaseError> {
    let spec = PackingSpec::paper_bar(1);
    let cs = random_packing(&spec);
    let box_area = (spec.box_max[0] - spec.box_min[0]) * (spec.box_max[1] - spec.box_min[1]);
    let union = union_area(&cs);
    let porosity_exact = 1.0 - union / box_area;
    let n = 32u32;
    let pm = mesh_bar(&cs, &spec, n)?;
    let m = &pm.mesh;
    let mut out = CaseOutput::default();
    let porosity = m.fluid_area() / box_area;
    // Inscribed polygons lose at most (2π/n)²/6 of each disc's area (leading order).
    let polygon_bound = (std::f64::consts::TAU / n as f64).powi(2) / 6.0 * (1.0 - porosity_exact);
    out.rows.push(Row::absolute(
        "porosity (32 segments) vs exact union of discs",
        "",
        porosity,
        porosity_exact,
        polygon_bound,
    ));
    out.rows.push(Row::absolute(
        "porosity vs paper A (about 10 %)",
        "",
        porosity,
        0.10,
        0.01,
    ));
    out.rows.push(Row::relative(
        "fluid + solid area vs box area",
        "m^2",
        m.fluid_area() + m.solid_area(),
        box_area,
        1e-12,
    ));
    let per_circle: f64 = (0..cs.len()).map(|i| pm.circle_solid_area(i)).sum();
    out.rows.push(Row::relative(
        "sum of per-circle solid areas vs solid area",
        "m^2",
        per_circle,
        m.solid_area(),
        1e-12,
    ));
    let n_edges = m.n_faces() as f64;
    let euler = m.vertices.len() as f64 - n_edges + m.n_cells() as f64;
    out.rows.push(Row::absolute(
        "Euler characteristic V - E + F of the box",
        "",
        euler,
        1.0,
        0.0,
    ));
    // Convergence of the solid area to the exact union.
    let fine = mesh_bar(&cs, &spec, 128)?;
    let mid = mesh_bar(&cs, &spec, 64)?;
    let e128 = (fine.mesh.solid_area() - union).abs() / union;
    let e64 = (mid.mesh.solid_area() - union).abs() / union;
    out.rows.push(Row::relative(
        "solid area (128 segments) vs exact union of discs",
        "m^2",
        fine.mesh.solid_area(),
        union,
        (std::f64::consts::TAU / 128.0).powi(2) / 6.0,
    ));
    out.rows.push(Row::absolute(
        "observed order of the solid-area error (64 -> 128 segments)",
        "",
        (e64 / e128).log2(),
        2.0,
        0.2,
    ));
    // Motion: every circle translates, turns and grows a little; the box stays.
    let k = cs.len();
    let vel: Vec<[f64; 2]> = (0..k)
        .map(|i| {
            let a = i as f64 * 0.7;
            [1e-3 * a.sin(), 1e-3 * a.cos()]
        })
        .collect();
    let omega: Vec<f64> = (0..k).map(|i| 0.3 * (i as f64 * 0.9).sin()).collect();
    let rdot: Vec<f64> = (0..k).map(|i| 1e-5 * (i as f64 * 1.1).cos()).collect();
    let t = 2.0;
    let centre: Vec<[f64; 2]> = cs
        .iter()
        .zip(&vel)
        .map(|(c, v)| [c.centre[0] + v[0] * t, c.centre[1] + v[1] * t])
        .collect();
    let radius: Vec<f64> = cs
        .iter()
        .zip(&rdot)
        .map(|(c, r)| c.radius + r * t)
        .collect();
    let rotation: Vec<f64> = omega.iter().map(|w| w * t).collect();
    let motion = CircleMotion {
        centre: &centre,
        radius: &radius,
        rotation: &rotation,
        velocity: &vel,
        angular_velocity: &omega,
        radius_rate: &rdot,
    };
    let mut moved = pm.clone();
    let mut mm = MeshMotion::new();
    mm.update(&mut moved, &motion).map_err(err)?;
    out.rows.push(Row::relative(
        "moved mesh: fluid + solid area vs box area",
        "m^2",
        moved.mesh.fluid_area() + moved.mesh.solid_area(),
        box_area,
        1e-12,
    ));
    let rate_sum: f64 = mm.volume_rate().iter().sum();
    let rate_scale: f64 = mm.volume_rate().iter().map(|r| r.abs()).sum();
    out.rows.push(Row::at_most(
        "moved mesh: |sum dV/dt| / sum |dV/dt| (fixed box)",
        "",
        rate_sum.abs() / rate_scale,
        1e-12,
    ));
    // Remesh of the moved packing and remap of a fluid mass and a solid energy.
    let moved_circles: Vec<Circle> = cs
        .iter()
        .enumerate()
        .map(|(i, c)| Circle {
            centre: centre[i],
            radius: radius[i],
            owner: c.owner,
        })
        .collect();
    let new = mesh_bar(&moved_circles, &spec, n)?;
    let op = RemapOperator::new(&moved.mesh, &new.mesh).map_err(err)?;
    for (label, filter, per_volume) in [
        ("liquid mass", CellFilter::Fluid, 998.0),
        ("solid energy", CellFilter::SameOwner, 2.0e9),
    ] {
        let q: Vec<f64> = (0..moved.mesh.n_cells())
            .map(|c| {
                let fluid = moved.mesh.cell_kind[c].is_fluid();
                if fluid == (filter == CellFilter::Fluid) {
                    per_volume * moved.mesh.cell_volume(c)
                } else {
                    0.0
                }
            })
            .collect();
        let mut r = vec![0.0; new.mesh.n_cells()];
        op.apply(filter, &q, &mut r).map_err(err)?;
        let (a, b): (f64, f64) = (q.iter().sum(), r.iter().sum());
        out.rows.push(Row::relative(
            format!("remap after remesh: total {label}"),
            if filter == CellFilter::Fluid {
                "kg"
            } else {
                "J"
            },
            b,
            a,
            1e-12,
        ));
    }
    let n_fluid = m.cell_kind.iter().filter(|k| k.is_fluid()).count();
    let n_t2t = m
        .channels
        .kind
        .iter()
        .filter(|k| **k == crate::ChannelKind::T2T)
        .count();
    let (dmin, dmax) = cs.iter().fold((f64::MAX, 0.0f64), |(a, b), c| {
        (a.min(2.0 * c.radius), b.max(2.0 * c.radius))
    });
    out.notes.push(format!(
        "seeded packing: {} circles, diameters {:.2}-{:.2} mm (4-8 mm drawn, radii scaled to \
         the target porosity), {} overlapping pairs",
        cs.len(),
        dmin * 1e3,
        dmax * 1e3,
        pm.chords.circles.len()
    ));
    out.notes.push(format!(
        "mesh with {n} segments per circle: {} vertices, {} cells ({} fluid, {} solid), {} \
         faces, {} T2T and {} S2S channels",
        m.vertices.len(),
        m.n_cells(),
        n_fluid,
        m.n_cells() - n_fluid,
        m.n_faces(),
        n_t2t,
        m.channels.len() - n_t2t
    ));
    out.notes.push(
        "contacts whose cut ends inside the solid (three or more circles meeting) get no S2S \
         channel: no pore touches them"
            .into(),
    );
    // The picture of the mesh for the documentation (docs/images/vpn_mesh_bar.png is a copy).
    let path = case_dir().join("mesh.png");
    let style = PictureStyle {
        title: format!("20 x 80 mm bar, {n} segments"),
        width_px: 420,
        channels: true,
    };
    let written = thm_io::fsutil::create_dir_all(&case_dir())
        .map_err(|e| MeshError::Output {
            path: case_dir().display().to_string(),
            message: e.to_string(),
        })
        .and_then(|()| write_mesh_png(m, &style, &path));
    out.notes.push(match written {
        Ok(()) => format!(
            "picture of the mesh (fluid cells blue, solid cells shaded by sphere, channels as \
             lines): {}",
            path.display()
        ),
        Err(e) => format!("picture of the mesh not written: {e}"),
    });
    Ok(out)
}

/// Where `cargo xtask verify` puts this case's files by default: `target/verify/<case name>`
/// (`$CARGO_TARGET_DIR` if set, else the workspace's `target`).
fn case_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    target.join("verify").join("vpn_mesh").join("paper_bar")
}
