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

#[test]
fn paper_bar_packing() {
    let spec = thm_vpn_mesh::packing::PackingSpec::paper_bar(1);
    let cs = thm_vpn_mesh::packing::random_packing(&spec);
    let ct = thm_vpn_mesh::packing::overlap_contacts(&cs, 1e7);
    let u = thm_vpn_mesh::packing::union_area(&cs);
    println!("n {} porosity exact {}", cs.len(), 1.0 - u / 1.6e-3);
    for n in [16u32, 32, 64, 128] {
        let pm = mesh_packing(&cs, &ct, &box_params([0.0, 0.0], [0.02, 0.08], n)).unwrap();
        let m = &pm.mesh;
        let s2s = m
            .channels
            .kind
            .iter()
            .filter(|k| **k == ChannelKind::S2S)
            .count();
        println!(
            "n {n}: cells {} fluid area {} solid {} err {} s2s {} of {} contacts",
            m.n_cells(),
            m.fluid_area() / 1.6e-3,
            m.solid_area(),
            (m.solid_area() - u) / u,
            s2s,
            ct.len()
        );
    }
}
