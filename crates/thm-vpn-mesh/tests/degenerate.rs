//! Degenerate input never panics: a valid mesh or a clear typed error.

use thm_vpn_mesh::*;

fn c(x: f64, y: f64, r: f64) -> Circle {
    Circle {
        centre: [x, y],
        radius: r,
        owner: 0,
    }
}

fn mesh_box(cs: &[Circle]) -> Result<PackingMesh, MeshError> {
    let s = MeshParams::new(
        Outline::Box {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
        },
        32,
    )
    .validate()?;
    mesh_packing(cs, &[], &s)
}

fn assert_valid(pm: &PackingMesh) {
    let m = &pm.mesh;
    assert!((m.fluid_area() + m.solid_area() - 1.0).abs() < 1e-12);
    assert!(m.cell_area.iter().all(|&a| a > 0.0));
}

#[test]
fn no_circles_gives_the_empty_box() {
    let pm = mesh_box(&[]).unwrap();
    assert_valid(&pm);
    assert_eq!(pm.mesh.n_cells(), 2);
    assert!((pm.mesh.fluid_area() - 1.0).abs() < 1e-15);
}

#[test]
fn one_circle() {
    let pm = mesh_box(&[c(0.5, 0.5, 0.2)]).unwrap();
    assert_valid(&pm);
    // Inscribed 32-gon.
    let n = 32.0;
    let exact = 0.5 * n * 0.04 * (std::f64::consts::TAU / n).sin();
    assert!((pm.mesh.solid_area() - exact).abs() < 1e-14);
}

#[test]
fn duplicate_centres_keep_one_owner() {
    let pm = mesh_box(&[c(0.5, 0.5, 0.2), c(0.5, 0.5, 0.2), c(0.5, 0.5, 0.1)]).unwrap();
    assert_valid(&pm);
    assert!(pm.circle_solid_area(0) > 0.0);
    assert_eq!(pm.cells_of_circle(1).len(), 0);
    assert_eq!(pm.cells_of_circle(2).len(), 0);
}

#[test]
fn collinear_and_tangent_circles() {
    // Tangent in a row: grid points meet exactly at the tangent points.
    let cs: Vec<Circle> = (0..4).map(|i| c(0.2 + 0.2 * i as f64, 0.5, 0.1)).collect();
    let pm = mesh_box(&cs).unwrap();
    assert_valid(&pm);
    // Collinear overlapping.
    let cs: Vec<Circle> = (0..5).map(|i| c(0.2 + 0.15 * i as f64, 0.5, 0.1)).collect();
    let pm = mesh_box(&cs).unwrap();
    assert_valid(&pm);
    assert_eq!(pm.chords.circles.len(), 4);
}

#[test]
fn deep_overlaps_and_contained_circles() {
    let cs = [
        c(0.5, 0.5, 0.3),
        c(0.52, 0.5, 0.1),   // inside the first
        c(0.55, 0.52, 0.29), // almost coincident with the first
        c(0.9, 0.9, 0.3),    // crosses the box
    ];
    let pm = mesh_box(&cs).unwrap();
    assert_valid(&pm);
    assert_eq!(pm.cells_of_circle(1).len(), 0);
}

#[test]
fn circle_outside_the_box_has_no_cells() {
    let pm = mesh_box(&[c(2.0, 2.0, 0.1), c(0.5, 0.5, 0.1)]).unwrap();
    assert_valid(&pm);
    assert_eq!(pm.cells_of_circle(0).len(), 0);
}

#[test]
fn bad_radius_and_centre_are_typed_errors() {
    for r in [f64::NAN, -1.0, 0.0, f64::INFINITY] {
        let e = mesh_box(&[c(0.5, 0.5, 0.1), c(0.2, 0.2, r)]).unwrap_err();
        assert!(
            matches!(e, MeshError::InvalidRadius { circle: 1, .. }),
            "{e}"
        );
    }
    let e = mesh_box(&[c(f64::NAN, 0.5, 0.1)]).unwrap_err();
    assert!(matches!(e, MeshError::NonFiniteCentre { circle: 0, .. }));
    let s = MeshParams::new(Outline::AlphaShape { alpha: 0.1 }, 16)
        .validate()
        .unwrap();
    assert_eq!(
        mesh_packing(&[], &[], &s).unwrap_err(),
        MeshError::NoCircles
    );
    let e = mesh_packing(
        &[c(0.0, 0.0, 1.0)],
        &[Contact {
            circles: [0, 3],
            normal_stress: 0.0,
        }],
        &s,
    )
    .unwrap_err();
    assert!(matches!(
        e,
        MeshError::ContactOutOfRange {
            contact: 0,
            circle: 3,
            ..
        }
    ));
    let e = MeshParams::new(Outline::AlphaShape { alpha: -1.0 }, 16)
        .validate()
        .unwrap_err();
    assert!(matches!(
        e,
        MeshError::Parameter {
            name: "outline.alpha",
            ..
        }
    ));
    let e = MeshParams::new(Outline::AlphaShape { alpha: 1.0 }, 3)
        .validate()
        .unwrap_err();
    assert!(matches!(
        e,
        MeshError::Parameter {
            name: "segments_per_circle",
            ..
        }
    ));
}

#[test]
fn alpha_shape_outline_of_a_chain() {
    // Three overlapping circles in a row and one apart: the outline keeps the inner cusps
    // narrower than α and drops the open outside.
    let cs = [
        c(0.0, 0.0, 1.0),
        c(1.8, 0.0, 1.0),
        c(3.6, 0.0, 1.0),
        c(1.8, 1.9, 1.0),
    ];
    let s = MeshParams::new(Outline::AlphaShape { alpha: 0.5 }, 48)
        .validate()
        .unwrap();
    let pm = mesh_packing(&cs, &[], &s).unwrap();
    let m = &pm.mesh;
    let u = thm_vpn_mesh::packing::union_area(&cs);
    // All solid is kept; the specimen's fluid is the pore enclosed by the circles plus the
    // narrow cusps: far less than the convex hull's empty part.
    assert!((m.solid_area() - u).abs() / u < 0.01);
    assert!(m.fluid_area() > 0.0 && m.fluid_area() < 0.2 * u);
    assert!(
        m.face_kind
            .iter()
            .any(|k| matches!(k, FaceKind::Boundary(BoundarySide::Outline)))
    );
}

#[test]
fn single_circle_alpha_shape_is_all_solid() {
    let s = MeshParams::new(Outline::AlphaShape { alpha: 0.5 }, 16)
        .validate()
        .unwrap();
    let pm = mesh_packing(&[c(0.0, 0.0, 1.0)], &[], &s).unwrap();
    assert_eq!(pm.mesh.fluid_area(), 0.0);
    assert_eq!(pm.mesh.channels.len(), 0);
}

/// The fuzz finding `mesher/crash-147f…`: a row of tangent circles of radius 8.2e-9 m among
/// circles up to 4.7e-2 m (mean radius 3.1e-3 m), 16 grid points per circle. Snapping by
/// `snap_tolerance × mean radius` (3.1e-9 m, about the grid step 2πr/16 = 3.2e-9 m of the small
/// circles) merged their grid points in chains and left a solid vertex 1.5e-8 m from its
/// centre; scaled by each vertex's own circle, no solid vertex leaves its circle by more than
/// `snap_tolerance × r`.
#[test]
fn radii_many_decades_below_the_mean_keep_their_shape() {
    let tiny = (1.0 + 230.0 / 32.0) * 10f64.powf(-9.0);
    let (x0, y0) = (15490.0 / 16384.0, 253.0 / 16384.0);
    let mut cs = Vec::new();
    for k in [0.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 3.0, 3.0] {
        cs.push(c(x0 + k * 2.0 * tiny, y0, tiny));
    }
    let big = (1.0 + 118.0 / 32.0) * 10f64.powf(-2.0);
    cs.extend([c(-0.498046875, 1.8602294921875, big); 2]);
    let mid = (1.0 + 51.0 / 32.0) * 10f64.powf(-4.0);
    cs.extend([c(0.180908203125, -0.7352294921875, mid); 18]);
    for (k, circle) in cs.iter_mut().enumerate() {
        circle.owner = k as u32;
    }
    let s = MeshParams::new(
        Outline::Box {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
        },
        16,
    )
    .validate()
    .unwrap();
    let pm = mesh_packing(&cs, &[], &s).unwrap();
    assert_valid(&pm);
    let m = &pm.mesh;
    let mut solid_cells = 0;
    for (i, circle) in pm.circles.iter().enumerate() {
        for &cell in pm.cells_of_circle(i) {
            solid_cells += 1;
            for v in m.cell_vertices[cell as usize] {
                let p = m.vertices[v as usize];
                let d = (p[0] - circle.centre[0]).hypot(p[1] - circle.centre[1]);
                assert!(
                    d <= circle.radius * (1.0 + 1e-6),
                    "circle {i}: a solid vertex {d} m from the centre, radius {}",
                    circle.radius
                );
            }
        }
    }
    // The small circles are meshed, not snapped away.
    assert!(
        pm.cells_of_circle(0).len() >= 8,
        "{solid_cells} solid cells"
    );
}
