//! Every kind of grid written by `thm-io` is read back by an independent reader (vtkio's XML
//! parser) and must give the same points, cells and values, bit for bit.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use thm_io::{Encoding, FieldValues, IoError, UnstructuredGrid};
use vtkio::model::{Attribute, DataSet, Piece, VertexNumbers};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-io-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// What vtkio finds in a `.vtu` file.
#[derive(Debug, PartialEq)]
struct Read {
    points: Vec<f64>,
    connectivity: Vec<u64>,
    offsets: Vec<u64>,
    types: Vec<u8>,
    point_fields: Vec<(String, Vec<f64>)>,
    cell_fields: Vec<(String, Vec<f64>)>,
}

fn read_with_vtkio(path: &Path) -> Read {
    let vtk =
        vtkio::Vtk::import(path).unwrap_or_else(|e| panic!("vtkio cannot read {path:?}: {e:?}"));
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid")
    };
    assert_eq!(pieces.len(), 1);
    let Piece::Inline(piece) = pieces.into_iter().next().unwrap() else {
        panic!("piece not inline")
    };
    let VertexNumbers::XML {
        connectivity,
        offsets,
    } = piece.cells.cell_verts
    else {
        panic!("legacy cell numbering")
    };
    let fields = |attrs: &[Attribute]| {
        attrs
            .iter()
            .map(|a| match a {
                Attribute::DataArray(d) => (d.name.clone(), d.data.cast_into::<f64>().unwrap()),
                Attribute::Field { .. } => panic!("unexpected field attribute"),
            })
            .collect::<Vec<_>>()
    };
    Read {
        points: piece.points.cast_into::<f64>().unwrap(),
        connectivity,
        offsets,
        types: piece.cells.types.iter().map(|&t| t as u8).collect(),
        point_fields: fields(&piece.data.point),
        cell_fields: fields(&piece.data.cell),
    }
}

fn flat3(v: &[[f64; 3]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

fn flat2(v: &[[f64; 2]]) -> Vec<f64> {
    v.iter().flat_map(|p| [p[0], p[1], 0.0]).collect()
}

fn ints(v: &[i32]) -> Vec<f64> {
    v.iter().map(|&i| f64::from(i)).collect()
}

/// Asserts that `read` holds the expected grid in every readable encoding.
fn check_all_encodings(name: &str, grid: &UnstructuredGrid<'_>, expected: &Read) {
    let dir = scratch(name);
    for (enc, file) in [
        (Encoding::Ascii, "ascii.vtu"),
        (Encoding::Base64, "base64.vtu"),
    ] {
        let path = dir.join(file);
        grid.write_vtu(&path, enc).unwrap();
        let got = read_with_vtkio(&path);
        assert_eq!(&got, expected, "{name} {enc:?}");
    }
    // Raw appended data is not XML, so vtkio cannot parse it; its bytes must equal the
    // base64 payload, block by block at the declared offsets.
    let raw = dir.join("raw.vtu");
    grid.write_vtu(&raw, Encoding::Raw).unwrap();
    assert_eq!(
        appended_blocks(&raw, false),
        appended_blocks(&dir.join("base64.vtu"), true),
        "{name} raw vs base64 payload"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The appended-data blocks (header + data bytes) at each DataArray's declared offset.
fn appended_blocks(path: &Path, base64: bool) -> Vec<Vec<u8>> {
    use base64::Engine as _;
    let bytes = std::fs::read(path).unwrap();
    let marker: &[u8] = if base64 {
        b"<AppendedData encoding=\"base64\">"
    } else {
        b"<AppendedData encoding=\"raw\">"
    };
    let at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .unwrap();
    let start = at
        + marker.len()
        + bytes[at + marker.len()..]
            .iter()
            .position(|&b| b == b'_')
            .unwrap()
        + 1;
    let head = String::from_utf8_lossy(&bytes[..at]).to_string();
    let offsets: Vec<usize> = head
        .split("offset=\"")
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].parse().unwrap())
        .collect();
    offsets
        .iter()
        .map(|&o| {
            let data = &bytes[start + o..];
            if base64 {
                // Each array is its own base64 block: header and data encoded together.
                let header = base64::engine::general_purpose::STANDARD
                    .decode(&data[..12])
                    .unwrap();
                let n = u64::from_le_bytes(header[..8].try_into().unwrap()) as usize;
                let enc_len = (8 + n).div_ceil(3) * 4;
                base64::engine::general_purpose::STANDARD
                    .decode(&data[..enc_len])
                    .unwrap()
            } else {
                let n = u64::from_le_bytes(data[..8].try_into().unwrap()) as usize;
                data[..8 + n].to_vec()
            }
        })
        .collect()
}

#[test]
fn particles_3d_read_back_identical() {
    let n = 57;
    let pos: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let t = i as f64;
            [t * 1e-3, (0.1 * t).sin(), -t / 7.0]
        })
        .collect();
    let radius: Vec<f64> = (0..n)
        .map(|i| 1e-4 * (1.0 + (i % 5) as f64 / 3.0))
        .collect();
    let vel: Vec<[f64; 3]> = (0..n).map(|i| [i as f64 / 3.0, -1e-9, 1e20]).collect();
    let temp: Vec<f64> = (0..n).map(|i| 293.15 + i as f64 * 0.1).collect();
    let id: Vec<i32> = (0..n as i32).map(|i| i * 3 - 5).collect();
    let grid = UnstructuredGrid::particles(&pos)
        .with_point_field("radius [m]", FieldValues::Scalar(&radius))
        .with_point_field("velocity [m/s]", FieldValues::Vector3(&vel))
        .with_point_field("temperature [K]", FieldValues::Scalar(&temp))
        .with_point_field("id", FieldValues::Int(&id));
    let expected = Read {
        points: flat3(&pos),
        connectivity: (0..n as u64).collect(),
        offsets: (1..=n as u64).collect(),
        types: vec![1; n],
        point_fields: vec![
            ("radius [m]".into(), radius.clone()),
            ("velocity [m/s]".into(), flat3(&vel)),
            ("temperature [K]".into(), temp.clone()),
            ("id".into(), ints(&id)),
        ],
        cell_fields: vec![],
    };
    check_all_encodings("particles", &grid, &expected);
}

#[test]
fn triangle_mesh_with_cell_data_read_back_identical() {
    // Two triangles sharing an edge, 2D points.
    let pts = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let tris: Vec<[usize; 3]> = vec![[0, 1, 2], [0, 2, 3]];
    let kind = vec![0, 1];
    let area = vec![0.5, 0.5];
    let pressure = vec![1.0e5, 2.5e6];
    let liquid_fraction = vec![0.25, 1.0];
    let temperature = vec![300.0, 350.5];
    let node_temp = vec![1.0, 2.0, 3.0, 4.0];
    let grid = UnstructuredGrid::triangles(&pts, &tris)
        .with_point_field("T_node [K]", FieldValues::Scalar(&node_temp))
        .with_cell_field("cell_type", FieldValues::Int(&kind))
        .with_cell_field("area [m^2]", FieldValues::Scalar(&area))
        .with_cell_field("pressure [Pa]", FieldValues::Scalar(&pressure))
        .with_cell_field("liquid_fraction", FieldValues::Scalar(&liquid_fraction))
        .with_cell_field("temperature [K]", FieldValues::Scalar(&temperature));
    let expected = Read {
        points: flat2(&pts),
        connectivity: vec![0, 1, 2, 0, 2, 3],
        offsets: vec![3, 6],
        types: vec![5, 5],
        point_fields: vec![("T_node [K]".into(), node_temp.clone())],
        cell_fields: vec![
            ("cell_type".into(), ints(&kind)),
            ("area [m^2]".into(), area.clone()),
            ("pressure [Pa]".into(), pressure.clone()),
            ("liquid_fraction".into(), liquid_fraction.clone()),
            ("temperature [K]".into(), temperature.clone()),
        ],
    };
    check_all_encodings("triangles", &grid, &expected);
}

#[test]
fn material_points_and_regular_grid_read_back_identical() {
    let mp = vec![[0.25, 0.25], [0.75, 0.25], [0.5, 0.8]];
    let vel = vec![[1.0, -2.0], [0.0, 0.5], [3.0, 4.0]];
    let stress_xx = vec![-1e6, 0.0, 2e5];
    let mps = UnstructuredGrid::particles(&mp)
        .with_point_field("velocity [m/s]", FieldValues::Vector2(&vel))
        .with_point_field("stress_xx [Pa]", FieldValues::Scalar(&stress_xx));
    check_all_encodings(
        "material_points",
        &mps,
        &Read {
            points: flat2(&mp),
            connectivity: vec![0, 1, 2],
            offsets: vec![1, 2, 3],
            types: vec![1, 1, 1],
            point_fields: vec![
                ("velocity [m/s]".into(), flat2(&vel)),
                ("stress_xx [Pa]".into(), stress_xx.clone()),
            ],
            cell_fields: vec![],
        },
    );

    // 3 × 2 cells of 0.5 m × 0.25 m from (1, 2).
    let node_mass: Vec<f64> = (0..12).map(|i| i as f64 * 0.5).collect();
    let cell_temp: Vec<f64> = (0..6).map(|i| 300.0 + i as f64).collect();
    let grid = UnstructuredGrid::regular_grid_2d([1.0, 2.0], [0.5, 0.25], [3, 2])
        .unwrap()
        .with_point_field("mass [kg]", FieldValues::Scalar(&node_mass))
        .with_cell_field("temperature [K]", FieldValues::Scalar(&cell_temp));
    let mut pts = Vec::new();
    for j in 0..3 {
        for i in 0..4 {
            pts.extend([1.0 + 0.5 * i as f64, 2.0 + 0.25 * j as f64, 0.0]);
        }
    }
    let mut conn = Vec::new();
    for j in 0..2u64 {
        for i in 0..3u64 {
            let n = 4 * j + i;
            conn.extend([n, n + 1, n + 5, n + 4]);
        }
    }
    check_all_encodings(
        "regular_grid",
        &grid,
        &Read {
            points: pts,
            connectivity: conn,
            offsets: (1..=6).map(|c| 4 * c).collect(),
            types: vec![9; 6],
            point_fields: vec![("mass [kg]".into(), node_mass.clone())],
            cell_fields: vec![("temperature [K]".into(), cell_temp.clone())],
        },
    );
}

#[test]
fn bad_grids_are_typed_errors() {
    let pts = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
    let tris: Vec<[usize; 3]> = vec![[0, 1, 3]];
    let err = UnstructuredGrid::triangles(&pts, &tris)
        .validate()
        .unwrap_err();
    assert!(
        matches!(
            err,
            IoError::CellIndex {
                cell: 0,
                index: 3,
                n_points: 3
            }
        ),
        "{err}"
    );

    let short = vec![1.0, 2.0];
    let err = UnstructuredGrid::particles(&pts)
        .with_point_field("radius", FieldValues::Scalar(&short))
        .validate()
        .unwrap_err();
    assert!(
        matches!(&err, IoError::FieldLength { field, len: 2, expected: 3, .. } if field == "radius"),
        "{err}"
    );
    assert!(err.to_string().contains("radius"));

    let ok = vec![1.0; 3];
    let err = UnstructuredGrid::particles(&pts)
        .with_point_field("r", FieldValues::Scalar(&ok))
        .with_point_field("r", FieldValues::Scalar(&ok))
        .validate()
        .unwrap_err();
    assert!(matches!(err, IoError::DuplicateField { .. }), "{err}");

    let err = UnstructuredGrid::regular_grid_2d([0.0, 0.0], [0.0, 1.0], [2, 2]).unwrap_err();
    assert!(
        matches!(err, IoError::BadValue { value, .. } if value == 0.0),
        "{err}"
    );

    let missing = std::env::temp_dir().join("thm-io-no-such-dir/x/y.vtu");
    let err = UnstructuredGrid::particles(&pts)
        .write_vtu(&missing, Encoding::Raw)
        .unwrap_err();
    assert!(err.to_string().contains("thm-io-no-such-dir"), "{err}");
}

#[test]
fn field_names_with_xml_characters_survive() {
    let pts = vec![[0.0, 0.0, 0.0]];
    let v = vec![1.5];
    let grid =
        UnstructuredGrid::particles(&pts).with_point_field("a<b & \"c\"", FieldValues::Scalar(&v));
    let dir = scratch("escape");
    let path = dir.join("e.vtu");
    grid.write_vtu(&path, Encoding::Ascii).unwrap();
    let got = read_with_vtkio(&path);
    assert_eq!(got.point_fields, vec![("a<b & \"c\"".to_string(), v)]);
    std::fs::remove_dir_all(&dir).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Any finite particle data reads back bit for bit, in ASCII and in base64.
    #[test]
    fn random_particles_round_trip_bitwise(
        data in proptest::collection::vec(
            (proptest::array::uniform3(-1e12f64..1e12), 1e-9f64..1.0, proptest::num::f64::NORMAL),
            0..40,
        ),
    ) {
        let pos: Vec<[f64; 3]> = data.iter().map(|d| d.0).collect();
        let radius: Vec<f64> = data.iter().map(|d| d.1).collect();
        let other: Vec<f64> = data.iter().map(|d| d.2).collect();
        let grid = UnstructuredGrid::particles(&pos)
            .with_point_field("radius", FieldValues::Scalar(&radius))
            .with_point_field("other", FieldValues::Scalar(&other));
        let dir = scratch("prop");
        for enc in [Encoding::Ascii, Encoding::Base64] {
            let path = dir.join("p.vtu");
            grid.write_vtu(&path, enc).unwrap();
            let got = read_with_vtkio(&path);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            prop_assert_eq!(bits(&got.points), bits(&flat3(&pos)));
            prop_assert_eq!(bits(&got.point_fields[0].1), bits(&radius));
            prop_assert_eq!(bits(&got.point_fields[1].1), bits(&other));
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// The binary encodings stay within twice the bytes of the data they hold.
#[test]
fn binary_frames_use_at_most_twice_the_raw_bytes() {
    let n = 10_000;
    let pos: Vec<[f64; 3]> = (0..n).map(|i| [i as f64, 0.0, 0.0]).collect();
    let s: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let v: Vec<[f64; 3]> = (0..n).map(|i| [i as f64; 3]).collect();
    let grid = UnstructuredGrid::particles(&pos)
        .with_point_field("radius", FieldValues::Scalar(&s))
        .with_point_field("velocity", FieldValues::Vector3(&v))
        .with_point_field("angular_velocity", FieldValues::Vector3(&v))
        .with_point_field("temperature", FieldValues::Scalar(&s))
        .with_point_field("mass", FieldValues::Scalar(&s));
    let raw_data = n * 8 * 12;
    let dir = scratch("size");
    for (enc, limit) in [(Encoding::Raw, 1.25), (Encoding::Base64, 1.6)] {
        let path = dir.join("f.vtu");
        grid.write_vtu(&path, enc).unwrap();
        let ratio = std::fs::metadata(&path).unwrap().len() as f64 / raw_data as f64;
        // Raw: 1 + 17/96 for vertex cells; base64: 4/3 of that.
        assert!(ratio <= limit && ratio <= 2.0, "{enc:?}: {ratio}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Meshes indexed with `u32` (as pore meshes are) and line networks (channels).
#[test]
fn u32_triangles_and_line_networks_read_back_identical() {
    let pts = vec![[0.0, 0.0], [2.0, 0.0], [1.0, 1.5], [3.0, 1.5]];
    let tris: Vec<[u32; 3]> = vec![[0, 1, 2], [1, 3, 2]];
    let pressure = vec![1e5, 2e5];
    let mesh = UnstructuredGrid::triangles(&pts, &tris)
        .with_cell_field("pressure [Pa]", FieldValues::Scalar(&pressure));
    check_all_encodings(
        "u32_triangles",
        &mesh,
        &Read {
            points: flat2(&pts),
            connectivity: vec![0, 1, 2, 1, 3, 2],
            offsets: vec![3, 6],
            types: vec![5, 5],
            point_fields: vec![],
            cell_fields: vec![("pressure [Pa]".into(), pressure.clone())],
        },
    );
    let channels: Vec<[u32; 2]> = vec![[0, 1], [1, 2], [2, 3]];
    let aperture = vec![1e-6, 2e-6, 3e-6];
    let net = UnstructuredGrid::lines(&pts, &channels)
        .with_cell_field("aperture [m]", FieldValues::Scalar(&aperture));
    check_all_encodings(
        "lines",
        &net,
        &Read {
            points: flat2(&pts),
            connectivity: vec![0, 1, 1, 2, 2, 3],
            offsets: vec![2, 4, 6],
            types: vec![3, 3, 3],
            point_fields: vec![],
            cell_fields: vec![("aperture [m]".into(), aperture.clone())],
        },
    );
    let bad: Vec<[u32; 2]> = vec![[0, 9]];
    let err = UnstructuredGrid::lines(&pts, &bad).validate().unwrap_err();
    assert!(
        matches!(
            err,
            IoError::CellIndex {
                cell: 0,
                index: 9,
                n_points: 4
            }
        ),
        "{err}"
    );
}
