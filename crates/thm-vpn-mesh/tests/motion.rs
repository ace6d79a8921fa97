//! Motion between remeshes: exact volume rates, conservation of the box area, the remesh
//! trigger, and save/restore.

use thm_vpn_mesh::motion::vertex_kinematics;
use thm_vpn_mesh::packing::{PackingSpec, overlap_contacts, random_packing};
use thm_vpn_mesh::*;

struct State {
    centre: Vec<[f64; 2]>,
    radius: Vec<f64>,
    rotation: Vec<f64>,
    velocity: Vec<[f64; 2]>,
    angular_velocity: Vec<f64>,
    radius_rate: Vec<f64>,
}

impl State {
    fn motion(&self) -> CircleMotion<'_> {
        CircleMotion {
            centre: &self.centre,
            radius: &self.radius,
            rotation: &self.rotation,
            velocity: &self.velocity,
            angular_velocity: &self.angular_velocity,
            radius_rate: &self.radius_rate,
        }
    }

    /// The state at time `t` of circles moving with constant rates from `circles`.
    fn at(circles: &[Circle], rates: &[([f64; 2], f64, f64)], t: f64) -> Self {
        Self {
            centre: circles
                .iter()
                .zip(rates)
                .map(|(c, r)| [c.centre[0] + r.0[0] * t, c.centre[1] + r.0[1] * t])
                .collect(),
            radius: circles
                .iter()
                .zip(rates)
                .map(|(c, r)| c.radius + r.2 * t)
                .collect(),
            rotation: rates.iter().map(|r| r.1 * t).collect(),
            velocity: rates.iter().map(|r| r.0).collect(),
            angular_velocity: rates.iter().map(|r| r.1).collect(),
            radius_rate: rates.iter().map(|r| r.2).collect(),
        }
    }
}

fn bar() -> (Vec<Circle>, PackingMesh) {
    let spec = PackingSpec::paper_bar(3);
    let cs = random_packing(&spec);
    let s = MeshParams::new(
        Outline::Box {
            min: spec.box_min,
            max: spec.box_max,
        },
        32,
    )
    .validate()
    .unwrap();
    let pm = mesh_packing(&cs, &overlap_contacts(&cs, 1e7), &s).unwrap();
    (cs, pm)
}

fn rates(n: usize) -> Vec<([f64; 2], f64, f64)> {
    (0..n)
        .map(|i| {
            let a = i as f64 * 0.7;
            (
                [1e-3 * a.sin(), 1e-3 * a.cos()],
                0.3 * (a * 1.3).sin(),
                1e-5 * (a * 0.9).cos(),
            )
        })
        .collect()
}

/// dV/dt equals the central difference of the cell volumes to O(h²) (the rate is the exact
/// derivative of the moved geometry).
#[test]
fn volume_rate_matches_finite_difference() {
    let (cs, mut pm) = bar();
    let r = rates(cs.len());
    let mut mm = MeshMotion::new();
    mm.update(&mut pm, &State::at(&cs, &r, 0.0).motion())
        .unwrap();
    let rate: Vec<f64> = mm.volume_rate().to_vec();
    let vol = |pm: &PackingMesh| -> Vec<f64> {
        (0..pm.mesh.n_cells())
            .map(|c| pm.mesh.cell_volume(c))
            .collect()
    };
    let mut errs = Vec::new();
    for h in [1e-3, 5e-4] {
        let mut p1 = pm.clone();
        mm.update(&mut p1, &State::at(&cs, &r, h).motion()).unwrap();
        let mut p0 = pm.clone();
        mm.update(&mut p0, &State::at(&cs, &r, -h).motion())
            .unwrap();
        let (v1, v0) = (vol(&p1), vol(&p0));
        let scale = rate.iter().map(|x| x.abs()).fold(0.0, f64::max);
        let e = (0..rate.len())
            .map(|c| ((v1[c] - v0[c]) / (2.0 * h) - rate[c]).abs())
            .fold(0.0, f64::max)
            / scale;
        errs.push(e);
    }
    assert!(errs[0] < 1e-4, "{errs:?}");
    // Second order: halving h divides the error by ≈ 4.
    assert!(errs[0] / errs[1] > 3.5, "{errs:?}");
}

/// After a move, the T2T apertures are those of A-Eq. 9 on the moved triangles (the same as
/// rebuilding the channels), and the channel order is unchanged.
#[test]
fn t2t_apertures_follow_the_motion() {
    let (cs, mut pm) = bar();
    let r = rates(cs.len());
    let kinds = pm.mesh.channels.kind.clone();
    let mut mm = MeshMotion::new();
    mm.update(&mut pm, &State::at(&cs, &r, 2.0).motion())
        .unwrap();
    assert_eq!(pm.mesh.channels.kind, kinds);
    let mut rebuilt = pm.mesh.clone();
    rebuilt.build_t2t_channels(pm.t2t_reduction_factor);
    let by_face: std::collections::HashMap<u32, f64> = (0..rebuilt.channels.len())
        .filter(|&c| rebuilt.channels.kind[c] == ChannelKind::T2T)
        .map(|c| (rebuilt.channels.face[c], rebuilt.channels.aperture[c]))
        .collect();
    let mut changed = 0;
    for c in 0..pm.mesh.channels.len() {
        if pm.mesh.channels.kind[c] == ChannelKind::T2T {
            let h = by_face[&pm.mesh.channels.face[c]];
            assert_eq!(pm.mesh.channels.aperture[c], h);
            changed += 1;
        }
    }
    assert!(changed > 0);
}

/// The narrow-gap floor (`MeshParams::narrow_gap_length`): on the bar, a T2T face shorter
/// than the length carries `max(A-Eq. 9, β h₀)`, every other channel is the mesh without the
/// floor to the bit; after a move the apertures are still the law's on the moved faces.
#[test]
fn narrow_gaps_carry_the_zero_stress_s2s_aperture() {
    let spec = PackingSpec::paper_bar(3);
    let cs = random_packing(&spec);
    let mesh = |narrow_gap_length: f64| {
        let mut p = MeshParams::new(
            Outline::Box {
                min: spec.box_min,
                max: spec.box_max,
            },
            32,
        );
        p.narrow_gap_length = narrow_gap_length;
        mesh_packing(&cs, &overlap_contacts(&cs, 1e7), &p.validate().unwrap()).unwrap()
    };
    let (plain, mut pm) = (mesh(0.0), mesh(100e-6));
    let floor = S2sApertureParams::default().aperture(0.0);
    assert_eq!(pm.narrow_gap, [100e-6, floor]);
    assert_eq!(plain.narrow_gap, [0.0, 0.0]);
    assert_eq!(pm.mesh.channels.kind, plain.mesh.channels.kind);
    let face_length = |m: &PoreMesh, c: usize| {
        let [a, b] = m.face_vertices[m.channels.face[c] as usize];
        let (pa, pb) = (m.vertices[a as usize], m.vertices[b as usize]);
        ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2)).sqrt()
    };
    let mut raised = 0;
    for c in 0..pm.mesh.channels.len() {
        let (h, h_plain) = (
            pm.mesh.channels.aperture[c],
            plain.mesh.channels.aperture[c],
        );
        if pm.mesh.channels.kind[c] == ChannelKind::T2T && face_length(&pm.mesh, c) < 100e-6 {
            assert_eq!(h, h_plain.max(floor), "channel {c}");
            raised += usize::from(h_plain < floor);
        } else {
            assert_eq!(h, h_plain, "channel {c}");
        }
    }
    assert!(raised >= 1, "{raised} narrow faces raised");
    let r = rates(cs.len());
    MeshMotion::new()
        .update(&mut pm, &State::at(&cs, &r, 2.0).motion())
        .unwrap();
    let mut rebuilt = pm.mesh.clone();
    rebuilt.build_t2t_channels(pm.t2t_law());
    let by_face: std::collections::HashMap<u32, f64> = (0..rebuilt.channels.len())
        .filter(|&c| rebuilt.channels.kind[c] == ChannelKind::T2T)
        .map(|c| (rebuilt.channels.face[c], rebuilt.channels.aperture[c]))
        .collect();
    for c in 0..pm.mesh.channels.len() {
        if pm.mesh.channels.kind[c] == ChannelKind::T2T {
            assert_eq!(
                pm.mesh.channels.aperture[c],
                by_face[&pm.mesh.channels.face[c]]
            );
        }
    }
    let bad = MeshParams {
        narrow_gap_length: -1e-6,
        ..MeshParams::new(
            Outline::Box {
                min: [0.0; 2],
                max: [1.0; 2],
            },
            16,
        )
    };
    let e = bad.validate().unwrap_err().to_string();
    assert!(e.contains("narrow_gap_length"), "{e}");
}

/// The box does not move: the cell volume rates sum to zero to round-off, and the total
/// volume stays the box volume.
#[test]
fn volume_rates_sum_to_zero_in_a_fixed_box() {
    let (cs, mut pm) = bar();
    let r = rates(cs.len());
    let mut mm = MeshMotion::new();
    mm.update(&mut pm, &State::at(&cs, &r, 2e-3).motion())
        .unwrap();
    let sum: f64 = mm.volume_rate().iter().sum();
    let scale: f64 = mm.volume_rate().iter().map(|x| x.abs()).sum();
    assert!(sum.abs() < 1e-13 * scale, "{sum} vs {scale}");
    let total = pm.mesh.fluid_area() + pm.mesh.solid_area();
    assert!((total - 0.02 * 0.08).abs() < 1e-12 * total);
}

/// A lone circle turning and growing: its cells turn rigidly (zero area rate from rotation)
/// and its area grows as 2 A ṙ / r; its boundary vertices stay on the circle.
#[test]
fn lone_circle_rotation_and_growth() {
    let cs = [Circle {
        centre: [0.5, 0.5],
        radius: 0.2,
        owner: 4,
    }];
    let s = MeshParams::new(
        Outline::Box {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
        },
        24,
    )
    .validate()
    .unwrap();
    let mut pm = mesh_packing(&cs, &[], &s).unwrap();
    let a0 = pm.circle_solid_area(0);
    let st = State {
        centre: vec![[0.51, 0.49]],
        radius: vec![0.21],
        rotation: vec![0.1],
        velocity: vec![[0.3, -0.2]],
        angular_velocity: vec![5.0],
        radius_rate: vec![0.01],
    };
    let mut mm = MeshMotion::new();
    mm.update(&mut pm, &st.motion()).unwrap();
    let a = pm.circle_solid_area(0);
    assert!((a - a0 * (0.21f64 / 0.2).powi(2)).abs() < 1e-14);
    let rate: f64 = pm
        .cells_of_circle(0)
        .iter()
        .map(|&c| mm.volume_rate()[c as usize])
        .sum();
    let expected = 2.0 * a * 0.01 / 0.21 * pm.mesh.thickness;
    assert!(
        (rate - expected).abs() < 1e-12 * expected,
        "{rate} vs {expected}"
    );
    for (v, p) in pm.mesh.vertices.iter().enumerate() {
        if pm.mesh.vertex_sphere[v] == 4 {
            let d = ((p[0] - 0.51).powi(2) + (p[1] - 0.49).powi(2)).sqrt();
            assert!((d - 0.21).abs() < 1e-15);
        }
    }
    // Rotation only: every solid cell keeps its area rate at zero.
    let st2 = State {
        radius_rate: vec![0.0],
        ..st
    };
    mm.update(&mut pm, &st2.motion()).unwrap();
    for &c in pm.cells_of_circle(0) {
        assert!(mm.volume_rate()[c as usize].abs() < 1e-14);
    }
}

/// The trigger fires exactly when a tracked change crosses its threshold.
#[test]
fn remesh_trigger_thresholds() {
    let (cs, pm) = bar();
    let crit = RemeshCriteriaParams::default().validate().unwrap();
    let n = cs.len();
    let zero = vec![0.0; n];
    let zero2 = vec![[0.0; 2]; n];
    let mut centre: Vec<[f64; 2]> = cs.iter().map(|c| c.centre).collect();
    let radius: Vec<f64> = cs.iter().map(|c| c.radius).collect();
    let ct = overlap_contacts(&cs, 1e7);
    let motion = |centre: &Vec<[f64; 2]>, radius: &Vec<f64>, rot: &Vec<f64>| {
        let m = CircleMotion {
            centre,
            radius,
            rotation: rot,
            velocity: &zero2,
            angular_velocity: &zero,
            radius_rate: &zero,
        };
        remesh_needed(&pm, &m, &ct, 32, &crit).unwrap()
    };
    assert_eq!(motion(&centre, &radius, &zero), None);
    // Displacement alone (overlap threshold out of the way): fires between 0.049 r and 0.051 r.
    let loose = RemeshCriteriaParams {
        max_overlap_change: 1.0,
        ..RemeshCriteriaParams::default()
    }
    .validate()
    .unwrap();
    let trig = |centre: &Vec<[f64; 2]>, crit: &RemeshCriteria| {
        let m = CircleMotion {
            centre,
            radius: &radius,
            rotation: &zero,
            velocity: &zero2,
            angular_velocity: &zero,
            radius_rate: &zero,
        };
        remesh_needed(&pm, &m, &ct, 32, crit).unwrap()
    };
    centre[0][0] += 0.049 * cs[0].radius;
    assert_eq!(trig(&centre, &loose), None);
    centre[0][0] += 0.002 * cs[0].radius;
    assert!(matches!(
        trig(&centre, &loose),
        Some(RemeshReason::Displacement { circle: 0, .. })
    ));
    centre[0] = cs[0].centre;
    // Overlap change of a cut pair: move one circle along the line of centres.
    let [a, b] = pm.chords.circles[0];
    let (a, b) = (a as usize, b as usize);
    let d = [
        cs[b].centre[0] - cs[a].centre[0],
        cs[b].centre[1] - cs[a].centre[1],
    ];
    let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let rmin = cs[a].radius.min(cs[b].radius);
    let loose_disp = RemeshCriteriaParams {
        max_displacement: 1.0,
        ..RemeshCriteriaParams::default()
    }
    .validate()
    .unwrap();
    for (dist, fires) in [(0.019 * rmin, false), (0.021 * rmin, true)] {
        centre[b] = [
            cs[b].centre[0] + dist * d[0] / len,
            cs[b].centre[1] + dist * d[1] / len,
        ];
        let r = trig(&centre, &loose_disp);
        assert_eq!(
            matches!(r, Some(RemeshReason::OverlapChange { .. })),
            fires,
            "{r:?}"
        );
    }
    centre[b] = cs[b].centre;
    let mut rot = zero.clone();
    rot[2] = 0.24 * std::f64::consts::TAU / 32.0;
    assert_eq!(motion(&centre, &radius, &rot), None);
    rot[2] = 0.26 * std::f64::consts::TAU / 32.0;
    assert!(matches!(
        motion(&centre, &radius, &rot),
        Some(RemeshReason::Rotation { circle: 2, .. })
    ));
    let mut r2 = radius.clone();
    r2[1] *= 1.011;
    assert!(matches!(
        motion(&centre, &r2, &zero),
        Some(RemeshReason::RadiusChange { circle: 1, .. })
    ));
}

/// Save/restore: a mesh survives a serde round trip bit for bit.
#[test]
fn packing_mesh_round_trip() {
    let (_, pm) = bar();
    let s = serde_json::to_string(&pm).unwrap();
    let back: PackingMesh = serde_json::from_str(&s).unwrap();
    assert!(back == pm, "round trip changed the mesh");
}

/// A full cycle: move, trigger, remesh, remap: fluid mass and solid energy totals conserved.
#[test]
fn move_remesh_remap_cycle() {
    let (cs, mut pm) = bar();
    let r = rates(cs.len());
    let fluid_mass: Vec<f64> = (0..pm.mesh.n_cells())
        .map(|c| {
            if pm.mesh.cell_kind[c].is_fluid() {
                1000.0 * pm.mesh.cell_volume(c)
            } else {
                0.0
            }
        })
        .collect();
    let mut mm = MeshMotion::new();
    let st = State::at(&cs, &r, 5.0);
    mm.update(&mut pm, &st.motion()).unwrap();
    let crit = RemeshCriteriaParams::default().validate().unwrap();
    let reason = remesh_needed(&pm, &st.motion(), &[], 32, &crit).unwrap();
    assert!(reason.is_some());
    let moved: Vec<Circle> = cs
        .iter()
        .enumerate()
        .map(|(i, c)| Circle {
            centre: st.centre[i],
            radius: st.radius[i],
            owner: c.owner,
        })
        .collect();
    let s = MeshParams::new(
        Outline::Box {
            min: [0.0, 0.0],
            max: [0.02, 0.08],
        },
        32,
    )
    .validate()
    .unwrap();
    let new = mesh_packing(&moved, &overlap_contacts(&moved, 1e7), &s).unwrap();
    let op = RemapOperator::new(&pm.mesh, &new.mesh).unwrap();
    let mut out = vec![0.0; new.mesh.n_cells()];
    op.apply(CellFilter::Fluid, &fluid_mass, &mut out).unwrap();
    let (a, b): (f64, f64) = (fluid_mass.iter().sum(), out.iter().sum());
    assert!((a - b).abs() <= 1e-12 * a);
}

/// Vertex kinematics with no motion leaves every vertex in place.
#[test]
fn rest_state_is_the_reference() {
    let (cs, pm) = bar();
    let st = State::at(&cs, &vec![([0.0; 2], 0.0, 0.0); cs.len()], 0.0);
    let n = pm.anchors.len();
    let (mut p, mut v) = (vec![[0.0; 2]; n], vec![[0.0; 2]; n]);
    vertex_kinematics(&pm.anchors, cs.len(), &st.motion(), &mut p, &mut v).unwrap();
    assert!(matches!(
        vertex_kinematics(&pm.anchors, cs.len() + 1, &st.motion(), &mut p, &mut v),
        Err(MeshError::LengthMismatch { .. })
    ));
    for (a, b) in p.iter().zip(&pm.mesh.vertices) {
        assert!((a[0] - b[0]).abs() < 1e-17 && (a[1] - b[1]).abs() < 1e-17);
    }
}

/// The fused update (one pass per entity) gives the same geometry, apertures and dV/dt, bit
/// for bit, as the stages called one by one: vertex kinematics, `update_geometry`,
/// `update_t2t_apertures`, `cell_area_rate` × thickness.
#[test]
fn fused_update_equals_the_separate_stages() {
    let (cs, pm) = bar();
    let r = rates(cs.len());
    let st = State::at(&cs, &r, 2e-3);
    let mut fused = pm.clone();
    let mut mm = MeshMotion::new();
    mm.update(&mut fused, &st.motion()).unwrap();

    let mut staged = pm.clone();
    let n = staged.anchors.len();
    let mut vel = vec![[0.0; 2]; n];
    vertex_kinematics(
        &staged.anchors,
        cs.len(),
        &st.motion(),
        &mut staged.mesh.vertices,
        &mut vel,
    )
    .unwrap();
    staged.mesh.update_geometry();
    staged
        .mesh
        .update_t2t_apertures(staged.t2t_reduction_factor);
    let mut rate = vec![0.0; staged.mesh.n_cells()];
    thm_vpn_mesh::motion::cell_area_rate(&staged.mesh, &vel, &mut rate).unwrap();
    let thickness = staged.mesh.thickness;
    rate.iter_mut().for_each(|x| *x *= thickness);

    assert_eq!(fused.mesh, staged.mesh);
    assert_eq!(mm.vertex_velocity(), &vel[..]);
    assert_eq!(mm.volume_rate(), &rate[..]);
    // The mesh did move.
    assert_ne!(fused.mesh.vertices, pm.mesh.vertices);
}

/// Inconsistent anchor rows (a hand-edited or truncated saved mesh) are a typed error, not a
/// panic.
#[test]
fn broken_anchor_rows_are_a_typed_error() {
    let (cs, pm) = bar();
    let st = State::at(&cs, &rates(cs.len()), 0.0);
    let mut mm = MeshMotion::new();
    let mut bad = pm.clone();
    bad.anchors.start.pop();
    assert!(matches!(
        mm.update(&mut bad, &st.motion()),
        Err(MeshError::LengthMismatch { .. })
    ));
    let mut bad = pm.clone();
    let last = bad.anchors.start.len() - 1;
    bad.anchors.start.swap(1, last);
    assert!(matches!(
        mm.update(&mut bad, &st.motion()),
        Err(MeshError::LengthMismatch { .. })
    ));
    // Decreasing rows and vertices beyond the rows have no anchor, without a panic.
    assert!(matches!(bad.anchors.kinematics_group(1), 0 | 4));
    assert_eq!(bad.anchors.kinematics_group(bad.anchors.len() + 5), 0);
    let mut bad = pm;
    bad.anchors.circle[0] = cs.len() as u32;
    assert!(matches!(
        mm.update(&mut bad, &st.motion()),
        Err(MeshError::LengthMismatch { .. })
    ));
}
