//! What each fuzz target asserts about arbitrary input: what its crate promises, a typed error
//! with a short message or a valid result, never a panic.
//!
//! Plain functions over bytes, so that the nightly fuzz targets (`fuzz/fuzz_targets/`) and the
//! stable replay of the committed corpus (`crates/thm-scenarios/tests/fuzz_corpus.rs`, which includes
//! this file) run the same checks.

use std::path::Path;

use serde::{Deserialize, Serialize};
use thm_eos::{Branch, EquationOfState, Model, PengRobinson, PoreClosure, water_air_closure};
use thm_vpn_mesh::{Circle, Contact, MeshParams, Outline, mesh_packing};

/// Longest error message any input may produce \[characters\]: messages quote excerpts, never
/// the input whole.
pub const MAX_MESSAGE_CHARS: usize = 1000;

fn short(message: &str) {
    let n = message.chars().count();
    assert!(
        n <= MAX_MESSAGE_CHARS,
        "a {n}-character error message: {}…",
        message.chars().take(200).collect::<String>()
    );
    assert!(!message.is_empty(), "an empty error message");
}

/// Scenario TOML → validated parameters: `thm run`'s reading, the common sections and the
/// kind's `init` (everything checked before a run writes anything).
pub fn scenario(data: &[u8]) {
    use thm_scenarios::registry::{DocError, parse_document};
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match parse_document(text) {
        Ok(doc) => {
            if let Err(e) = thm_scenarios::registry::validate(&doc) {
                short(&e.to_string());
                assert!(!e.key.is_empty());
            }
        }
        Err(DocError::Syntax(message)) => short(&message),
        Err(DocError::Config(e)) => {
            short(&e.to_string());
            assert!(!e.key.is_empty());
        }
    }
}

/// Packing CSV (`thm_dem::packing::Packing::from_csv`): a typed error, or a packing of finite
/// centres, positive finite radii and in-range sorted bonds that writes back to itself.
pub fn packing_csv(data: &[u8]) {
    use thm_dem::packing::Packing;
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Packing::from_csv(text) {
        Ok(p) => {
            assert_eq!(p.centres.len(), p.radii.len());
            for (c, &r) in p.centres.iter().zip(&p.radii) {
                assert!(c.x.is_finite() && c.y.is_finite() && c.z.is_finite());
                assert!(r.is_finite() && r > 0.0, "radius {r}");
            }
            for &(a, b) in &p.bonds {
                assert!(a < b && b < p.centres.len(), "bond ({a}, {b})");
            }
            match Packing::from_csv(&p.to_csv()) {
                Ok(again) => assert_eq!(again, p),
                Err(e) => panic!("a packing read from CSV does not read back: {e}"),
            }
        }
        Err(e) => short(&e.to_string()),
    }
}

/// A state with the shapes checkpoints hold (numbers, text, sequences, options, enums).
#[derive(Debug, PartialEq, Serialize, Deserialize)]
pub struct FuzzState {
    step: u64,
    name: String,
    x: Vec<f64>,
    pairs: Vec<(u32, u32)>,
    flag: Option<bool>,
    shape: Shape,
}

/// An enum in a checkpointed state.
#[derive(Debug, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    /// Unit.
    Empty,
    /// Newtype.
    Radius(f64),
    /// Struct.
    Box {
        /// A field.
        side: [f64; 2],
    },
}

/// CRC-32 (IEEE), bitwise.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// `data` with its checksum made valid (so the decoder behind the checksum is reached).
fn sealed(data: &[u8]) -> Option<Vec<u8>> {
    let mut b = data.to_vec();
    let n = b.len();
    if b.starts_with(thm_io::checkpoint::BINARY_MAGIC) && n >= 4 {
        let crc = crc32(&b[..n - 4]);
        b[n - 4..].copy_from_slice(&crc.to_le_bytes());
        return Some(b);
    }
    let tail = b",\"crc32\":\"";
    if b.first() == Some(&b'{') && n >= tail.len() + 11 && b[n - 21..].starts_with(tail) {
        let crc = format!("{:08x}", crc32(&b[..n - 21]));
        b[n - 11..n - 3].copy_from_slice(crc.as_bytes());
        b[n - 3..].copy_from_slice(b"\"}\n");
        return Some(b);
    }
    None
}

/// Checkpoint bytes (`thm_io::checkpoint_from_bytes`), as read and with the checksum made
/// valid: a typed error with a short message, or a state.
pub fn checkpoint(data: &[u8]) {
    let path = Path::new("fuzz.ckpt");
    let mut inputs = vec![data.to_vec()];
    inputs.extend(sealed(data));
    for bytes in &inputs {
        match thm_io::checkpoint_from_bytes::<FuzzState>(path, bytes, "fuzz", 1) {
            Ok(state) => assert!(state.x.len() <= bytes.len()),
            Err(e) => short(&e.to_string()),
        }
        // Another expected kind and version go through the same header checks.
        if let Err(e) = thm_io::checkpoint_from_bytes::<Vec<f64>>(path, bytes, "lumped", 7) {
            short(&e.to_string());
        }
    }
}

/// `thm eos` CSV: the first byte picks the table and model, the rest is standard input. Rows
/// or an error naming line, row and column; every computed value is a finite number.
pub fn eos_csv(data: &[u8]) {
    use thm_scenarios::eos_csv::{Table, process_csv};
    let Some((&pick, input)) = data.split_first() else {
        return;
    };
    let (table, computed) = match pick % 3 {
        0 => (Table::Pressure, 1),
        1 => (Table::Density, 1),
        _ => (Table::Closure, 4),
    };
    let model = if pick & 4 == 0 {
        Model::PrCorrected
    } else {
        Model::Pr
    };
    let mut out = Vec::new();
    let result = process_csv(table, model, input, &mut out);
    let text = String::from_utf8(out).unwrap_or_else(|e| panic!("output is not UTF-8: {e}"));
    for line in text.lines().skip(1) {
        let fields: Vec<&str> = line.split(',').collect();
        assert!(fields.len() > computed, "{line}");
        for f in &fields[fields.len() - computed..] {
            let x: f64 = f
                .parse()
                .unwrap_or_else(|_| panic!("`{f}` is not a number in `{line}`"));
            assert!(x.is_finite(), "non-finite result in `{line}`");
        }
    }
    if let Err(e) = result {
        short(&e.to_string());
    }
}

/// Reads `f64`s and bytes off the front of the input, zero when it runs out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn byte(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn f64(&mut self) -> f64 {
        let mut b = [0u8; 8];
        for x in &mut b {
            *x = self.byte();
        }
        f64::from_le_bytes(b)
    }

    fn i16(&mut self) -> i16 {
        i16::from_le_bytes([self.byte(), self.byte()])
    }
}

/// The EOS at arbitrary (T, ρ, P) and pore states, each fluid and model: a typed error, or
/// finite values inside their documented ranges.
pub fn eos_state(data: &[u8]) {
    let mut b = Bytes(data);
    let (t, rho, p) = (b.f64(), b.f64(), b.f64());
    let (v, m_l, m_g) = (b.f64(), b.f64(), b.f64());
    for model in [Model::Pr, Model::PrCorrected] {
        for eos in [PengRobinson::water(model), PengRobinson::air()] {
            if let Ok(x) = eos.pressure(t, rho) {
                assert!(x.is_finite(), "P({t}, {rho}) = {x}");
            }
            for branch in [Branch::Liquid, Branch::Gas] {
                if let Ok(d) = eos.density(t, p, branch) {
                    assert!(d.is_finite() && d > 0.0, "rho({t}, {p}, {branch:?}) = {d}");
                }
            }
            for x in [eos.dp_drho(t, rho), eos.dp_dt(t, rho)]
                .into_iter()
                .flatten()
            {
                assert!(x.is_finite(), "derivative at ({t}, {rho}) = {x}");
            }
        }
        match water_air_closure(model).close(t, v, m_l, m_g) {
            Ok(s) => {
                let all = [
                    s.liquid_fraction,
                    s.gas_fraction,
                    s.pressure,
                    s.liquid_density,
                    s.gas_density,
                ];
                assert!(all.iter().all(|x| x.is_finite()), "{s:?}");
                assert!((0.0..=1.0).contains(&s.liquid_fraction), "{s:?}");
                assert!((0.0..=1.0).contains(&s.gas_fraction), "{s:?}");
                assert!(s.liquid_density >= 0.0 && s.gas_density >= 0.0, "{s:?}");
            }
            Err(e) => short(&e.to_string()),
        }
    }
}

/// Circle sets for the mesher: each circle is one opcode byte and its data. Opcodes make the
/// degenerate sets likely: a copy of the previous circle (coincident), the previous moved along
/// x by its diameter (tangent, collinear), a concentric smaller one, or free centre and radius
/// over twelve decades (tiny to huge against the unit box).
fn circles_from(b: &mut Bytes<'_>, n: usize) -> Vec<Circle> {
    let mut circles: Vec<Circle> = Vec::with_capacity(n);
    for k in 0..n {
        let op = b.byte();
        let prev = circles.last().copied();
        let c = match (op % 8, prev) {
            (0, Some(p)) => p,
            (1, Some(p)) => Circle {
                centre: [p.centre[0] + 2.0 * p.radius, p.centre[1]],
                ..p
            },
            (2, Some(p)) => Circle {
                radius: p.radius * 0.5,
                ..p
            },
            _ => {
                let x = f64::from(b.i16()) / 16384.0;
                let y = f64::from(b.i16()) / 16384.0;
                let decade = f64::from(b.byte() % 13) - 9.0;
                let mantissa = 1.0 + f64::from(b.byte()) / 32.0;
                Circle {
                    centre: [x, y],
                    radius: mantissa * 10f64.powf(decade),
                    owner: 0,
                }
            }
        };
        circles.push(Circle {
            owner: k as u32,
            ..c
        });
    }
    circles
}

/// The mesher on an arbitrary circle set in the unit box: a typed error, or a valid
/// triangulation whose fluid and solid areas add up to the box (the crate's area identity),
/// every cell positively oriented with the area it reports, faces and cells consistent, and
/// every solid cell inside its circle.
pub fn mesher(data: &[u8]) {
    let mut b = Bytes(data);
    let segments = 6 + u32::from(b.byte() % 58);
    let n = usize::from(b.byte() % 48);
    let circles = circles_from(&mut b, n);
    let n_contacts = usize::from(b.byte() % 8);
    let contacts: Vec<Contact> = (0..n_contacts)
        .map(|_| Contact {
            circles: [u32::from(b.byte() % 50), u32::from(b.byte() % 50)],
            normal_stress: f64::from(b.i16()) * 1e3,
        })
        .collect();
    let settings = match MeshParams::new(
        Outline::Box {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
        },
        segments,
    )
    .validate()
    {
        Ok(s) => s,
        Err(e) => panic!("the unit box with {segments} segments was refused: {e}"),
    };
    let pm = match mesh_packing(&circles, &contacts, &settings) {
        Ok(pm) => pm,
        Err(e) => {
            short(&e.to_string());
            return;
        }
    };
    let m = &pm.mesh;
    let total = m.fluid_area() + m.solid_area();
    assert!(
        (total - 1.0).abs() < 1e-12,
        "fluid + solid area = {total}, the box is 1"
    );
    let nv = m.vertices.len();
    for (c, tri) in m.cell_vertices.iter().enumerate() {
        assert!(tri.iter().all(|&v| (v as usize) < nv), "cell {c}: {tri:?}");
        let [a, b, d] = tri.map(|v| m.vertices[v as usize]);
        let signed = 0.5 * ((b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1]));
        assert!(m.cell_area[c] > 0.0, "cell {c} has area {}", m.cell_area[c]);
        assert!(
            (signed - m.cell_area[c]).abs() <= 1e-9 * m.cell_area[c].max(1e-300),
            "cell {c}: vertices span {signed}, area {}",
            m.cell_area[c]
        );
        for &f in &m.cell_faces[c] {
            assert!(
                m.face_cells[f as usize].contains(&(c as u32)),
                "cell {c} lists face {f}, which does not list it"
            );
        }
    }
    // Vertices closer than the snap tolerance × the radius of their smallest circle (at most
    // the mean radius, at least 8 ulps of the coordinates) are merged, and put on a box side
    // when that close to it: a solid vertex may lie that far outside its circle. The bound
    // stays absolute (the mean radius): what a circle many decades below the mean may not do
    // is lose its shape to merges at the mean's scale, as `mesher/crash-147f…` did.
    let mean_radius = circles.iter().map(|c| c.radius).sum::<f64>() / circles.len().max(1) as f64;
    let snap = 2.0 * settings.params().snap_tolerance * mean_radius;
    for (i, circle) in pm.circles.iter().enumerate() {
        for &cell in pm.cells_of_circle(i) {
            for v in m.cell_vertices[cell as usize] {
                let p = m.vertices[v as usize];
                let d =
                    ((p[0] - circle.centre[0]).powi(2) + (p[1] - circle.centre[1]).powi(2)).sqrt();
                let round_off = 16.0 * f64::EPSILON * p[0].abs().max(p[1].abs());
                assert!(
                    d <= circle.radius * (1.0 + 1e-9) + snap + round_off,
                    "solid cell {cell} of circle {i} has a vertex {d} from its centre, radius {}",
                    circle.radius
                );
            }
        }
    }
}
