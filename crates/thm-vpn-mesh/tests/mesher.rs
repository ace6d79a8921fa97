//! Mesher: area identities, convergence, degenerate input.

use thm_vpn_mesh::*;

fn circle(x: f64, y: f64, r: f64, owner: u32) -> Circle {
    Circle {
        centre: [x, y],
        radius: r,
        owner,
    }
}

fn box_params(min: [f64; 2], max: [f64; 2], n: u32) -> MeshSettings {
    MeshParams::new(Outline::Box { min, max }, n)
        .validate()
        .unwrap()
}

/// Area of the part of a disc of radius `r` beyond a line at distance `a` from its centre.
fn segment_area(r: f64, a: f64) -> f64 {
    let a = a.clamp(-r, r);
    r * r * (a / r).acos() - a * (r * r - a * a).sqrt()
}

#[test]
fn two_overlapping_circles_in_a_box() {
    let cs = [circle(0.4, 0.5, 0.2, 7), circle(0.65, 0.5, 0.1, 9)];
    let ct = [Contact {
        circles: [0, 1],
        normal_stress: 1e6,
    }];
    let pm = mesh_packing(&cs, &ct, &box_params([0.0, 0.0], [1.0, 1.0], 64)).unwrap();
    let m = &pm.mesh;
    let total = m.fluid_area() + m.solid_area();
    assert!((total - 1.0).abs() < 1e-13, "{total}");
    assert_eq!(pm.chords.circles.len(), 1);
    assert_ne!(pm.chords.face[0], NONE);
    assert_ne!(pm.contact_channel[0], NONE);
    println!("{:?} cells {}", pm.chords, m.n_cells());
    for (i, c) in cs.iter().enumerate() {
        let o = &cs[1 - i];
        let d = ((c.centre[0] - o.centre[0]).powi(2) + (c.centre[1] - o.centre[1]).powi(2)).sqrt();
        let a = (d * d + c.radius * c.radius - o.radius * o.radius) / (2.0 * d);
        let exact = std::f64::consts::PI * c.radius * c.radius - segment_area(c.radius, a);
        let got = pm.circle_solid_area(i);
        println!(
            "circle {i}: {got} vs {exact}: rel {}",
            (got - exact) / exact
        );
        assert!(((got - exact) / exact).abs() < 5e-3);
    }
}

/// Convergence table on the paper's bar: the meshed solid area against the exact area of the
/// union of the discs, and the worst circle against its exact cut area; doubling the boundary
/// resolution divides both errors by ≈ 4 (second order). Run with `--nocapture` for the table.
#[test]
fn bar_solid_area_converges_at_second_order() {
    use thm_vpn_mesh::packing::{
        PackingSpec, cut_circle_area, overlap_contacts, random_packing, union_area,
    };
    let spec = PackingSpec::paper_bar(1);
    let cs = random_packing(&spec);
    let ct = overlap_contacts(&cs, 1e7);
    let u = union_area(&cs);
    let mut prev: Option<(f64, f64)> = None;
    println!(
        "segments | cells | solid-area rel. error | ratio | worst cut circle rel. error | ratio"
    );
    for n in [16u32, 32, 64, 128] {
        let pm = mesh_packing(&cs, &ct, &box_params(spec.box_min, spec.box_max, n)).unwrap();
        let e_u = (pm.mesh.solid_area() - u).abs() / u;
        let e_c = (0..cs.len())
            .filter_map(|i| {
                cut_circle_area(&cs, i).map(|a| (pm.circle_solid_area(i) - a).abs() / a)
            })
            .fold(0.0, f64::max);
        let (ru, rc) = prev.map_or((f64::NAN, f64::NAN), |(pu, pc)| (pu / e_u, pc / e_c));
        println!(
            "{n:8} | {:5} | {e_u:.3e} | {ru:.2} | {e_c:.3e} | {rc:.2}",
            pm.mesh.n_cells()
        );
        if prev.is_some() {
            assert!(ru > 3.5 && ru < 4.5, "union error ratio {ru}");
            assert!(rc > 3.5 && rc < 4.5, "circle error ratio {rc}");
        }
        prev = Some((e_u, e_c));
    }
}

#[test]
fn verification_cases_pass() {
    for case in thm_vpn_mesh::verification::cases() {
        let out = (case.run)().unwrap();
        for r in &out.rows {
            println!(
                "{:60} {:.6e} vs {:.6e} err {:.2e} tol {:.2e} {}",
                r.quantity, r.measured, r.reference, r.error, r.tolerance, r.pass
            );
        }
        for n in &out.notes {
            println!("note: {n}");
        }
        assert!(out.passed(), "{}", case.name);
    }
}

/// The exported arrays describe the same mesh, and the interface and contact faces are the
/// faces between a fluid and a solid cell and between two spheres.
#[test]
fn export_arrays_and_face_sets() {
    let cs = [circle(0.4, 0.5, 0.2, 7), circle(0.65, 0.5, 0.1, 9)];
    let pm = mesh_packing(&cs, &[], &box_params([0.0, 0.0], [1.0, 1.0], 32)).unwrap();
    let m = &pm.mesh;
    let tris = m.triangles_usize();
    let types = m.cell_type_labels();
    let owners = m.cell_owner_labels();
    assert_eq!(tris.len(), m.n_cells());
    for c in 0..m.n_cells() {
        assert_eq!(types[c] == 0, m.cell_kind[c].is_fluid());
        assert_eq!(owners[c] == -1, m.cell_kind[c].is_fluid());
        assert!(owners[c] == -1 || owners[c] == 7 || owners[c] == 9);
    }
    // The contact faces form the cut: their total length is the chord length.
    let chord: f64 = m.contact_faces().map(|f| m.face_length[f]).sum();
    let d = 0.25f64;
    let a = (d * d + 0.04 - 0.01) / (2.0 * d);
    let exact = 2.0 * (0.04 - a * a).sqrt();
    assert!((chord - exact).abs() < 1e-14, "{chord} vs {exact}");
    // Interface faces: the polygon outlines minus the cut, a closed loop around the pair.
    let perimeter: f64 = m.fluid_solid_faces().map(|f| m.face_length[f]).sum();
    assert!(perimeter > 0.0 && perimeter < std::f64::consts::TAU * 0.3);
}

/// A-Eq. 8: the S2S aperture falls from β h_0 at zero stress towards β h_inf, e-fold per
/// 1/(1.5e-7) Pa; tension is clamped to zero stress.
#[test]
fn s2s_aperture_law() {
    let law = S2sApertureParams::default();
    let (b, hi, h0) = (1.2, 5.75e-7, 3.25e-6);
    assert!((law.aperture(0.0) - b * h0).abs() < 1e-20);
    assert!((law.aperture(-5e6) - b * h0).abs() < 1e-20);
    let s = 1.0 / 1.5e-7;
    let expect = b * (hi + (h0 - hi) * (-1.0f64).exp());
    assert!((law.aperture(s) - expect).abs() < 1e-18);
    assert!((law.aperture(1e12) - b * hi).abs() < 1e-18);
    // Updating a meshed pair's stress changes its channel's aperture.
    let cs = [circle(0.4, 0.5, 0.2, 7), circle(0.65, 0.5, 0.1, 9)];
    let ct = [Contact {
        circles: [0, 1],
        normal_stress: 0.0,
    }];
    let mut pm = mesh_packing(&cs, &ct, &box_params([0.0, 0.0], [1.0, 1.0], 32)).unwrap();
    let ch = pm.contact_channel[0] as usize;
    assert_eq!(pm.mesh.channels.aperture[ch], law.aperture(0.0));
    pm.update_s2s_apertures(&[s], &law).unwrap();
    assert_eq!(pm.mesh.channels.aperture[ch], law.aperture(s));
    assert!(pm.update_s2s_apertures(&[], &law).is_err());
}

/// Cells follow a space-filling curve: consecutive cells are neighbours in space (their
/// centroids lie a few cell sides apart on average, against a third of the box side for a
/// random order), and vertices are numbered in order of first use by the cells within groups
/// of the same kinematics.
#[test]
fn cells_and_vertices_are_in_locality_order() {
    let spec = thm_vpn_mesh::packing::PackingSpec::paper_bar(3);
    let cs = thm_vpn_mesh::packing::random_packing(&spec);
    let contacts = thm_vpn_mesh::packing::overlap_contacts(&cs, 1e7);
    let pm = mesh_packing(&cs, &contacts, &box_params(spec.box_min, spec.box_max, 24)).unwrap();
    let m = &pm.mesh;
    let n = m.n_cells();
    let mean_side = (m.cell_area.iter().sum::<f64>() / n as f64).sqrt();
    let step: f64 = m
        .cell_centroid
        .windows(2)
        .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
        .sum::<f64>()
        / (n - 1) as f64;
    assert!(
        step < 3.0 * mean_side,
        "mean step {step:e} m, cell side {mean_side:e} m"
    );
    // Vertices come in groups of the same kinematics, the simple ones (free, one anchor)
    // first and most numerous; each group is numbered in order of first use by the cells.
    let nv = m.vertices.len();
    let group: Vec<u8> = (0..nv).map(|v| pm.anchors.kinematics_group(v)).collect();
    assert_eq!(pm.anchors.kinematics_group(0), 1);
    let mut first = vec![usize::MAX; 8];
    for (v, &g) in group.iter().enumerate() {
        first[usize::from(g)] = first[usize::from(g)].min(v);
    }
    // Contiguous groups: as many changes of group along the vertices as groups less one.
    let changes = group.windows(2).filter(|w| w[0] != w[1]).count();
    let n_groups = first.iter().filter(|&&f| f != usize::MAX).count();
    assert_eq!(changes, n_groups - 1, "groups are not contiguous");
    let n_simple = group.iter().filter(|&&g| g == 1).count();
    assert!(n_simple > nv / 2, "{n_simple} simple vertices of {nv}");
    let mut next = first.clone();
    for t in &m.cell_vertices {
        for &v in t {
            let g = usize::from(group[v as usize]);
            assert!(
                v as usize <= next[g],
                "vertex {v} used before vertex {}",
                next[g]
            );
            if v as usize == next[g] {
                next[g] += 1;
            }
        }
    }
    for g in 0..8 {
        if first[g] != usize::MAX {
            let len = group.iter().filter(|&&h| usize::from(h) == g).count();
            assert_eq!(next[g], first[g] + len, "group {g}");
        }
    }
}

/// With `side_points`, a circle 0.1 µm from a box side and the seeded bar (circles clamped
/// inside its box, several close to a side but not on it): no fluid cell runs along a side
/// farther than the Steiner spacing (`2π r̄ / segments`), and no cell has its three corners
/// on one side. Without them the bar holds fluid triangles nearly flat along a side (seed 1:
/// corners at x = 0 and y = 70.3, 76 and 80 mm).
#[test]
fn no_fluid_cell_runs_along_a_box_side() {
    let near = [circle(0.3, 0.5, 0.2, 0), circle(0.7, 0.3, 0.2999999, 1)];
    let bar = packing::random_packing(&packing::PackingSpec::paper_bar(1));
    for (circles, [w, h]) in [(near.to_vec(), [1.0, 1.0]), (bar, [0.020, 0.080])] {
        let segments = 32;
        let mut params = MeshParams::new(
            Outline::Box {
                min: [0.0, 0.0],
                max: [w, h],
            },
            segments,
        );
        params.side_points = true;
        let pm = mesh_packing(&circles, &[], &params.validate().unwrap()).unwrap();
        let m = &pm.mesh;
        let r_mean = circles.iter().map(|c| c.radius).sum::<f64>() / circles.len() as f64;
        let spacing = std::f64::consts::TAU * r_mean / f64::from(segments);
        let sides = [(0, 0.0), (0, w), (1, 0.0), (1, h)];
        for c in 0..m.n_cells() {
            let v = m.cell_vertices[c].map(|k| m.vertices[k as usize]);
            for (axis, value) in sides {
                let on = v.iter().filter(|p| p[axis] == value).count();
                assert!(on < 3, "cell {c} has its three corners on a side: {v:?}");
                if on == 2 && m.cell_kind[c].is_fluid() {
                    let along: Vec<f64> = v
                        .iter()
                        .filter(|p| p[axis] == value)
                        .map(|p| p[1 - axis])
                        .collect();
                    let len = (along[0] - along[1]).abs();
                    assert!(
                        len <= spacing * (1.0 + 1e-9),
                        "fluid cell {c} runs {len} m along a side (spacing {spacing} m): {v:?}"
                    );
                }
            }
        }
        let total = m.fluid_area() + m.solid_area();
        assert!((total - w * h).abs() < 1e-12 * w * h, "{total}");
    }
}
