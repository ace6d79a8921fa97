//! PVD collections, CSV histories, checkpoints and plots.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use thm_io::{
    Column, CsvHistory, Encoding, FieldValues, IoError, PvdCollection, UnstructuredGrid, VtuSeries,
    load_checkpoint, save_checkpoint,
};
use thm_verify::{Plot, Series, SeriesRole};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-io-files-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The `(timestep, file)` pairs of a `.pvd`, in file order, read with plain string scanning.
fn pvd_entries(path: &std::path::Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let attr = |e: &str, k: &str| {
        let s = e.find(&format!("{k}=\"")).unwrap() + k.len() + 2;
        e[s..s + e[s..].find('"').unwrap()].to_string()
    };
    text.split("<DataSet")
        .skip(1)
        .map(|e| (attr(e, "timestep").parse().unwrap(), attr(e, "file")))
        .collect()
}

#[test]
fn pvd_lists_frames_in_time_order_whatever_the_insertion_order() {
    let dir = scratch("pvd");
    let path = dir.join("run.pvd");
    let mut pvd = PvdCollection::new(&path);
    for (t, f) in [
        (0.3, "c.vtu"),
        (0.1, "a.vtu"),
        (0.2, "b.vtu"),
        (1e-7, "first.vtu"),
    ] {
        pvd.add(t, 0, f).unwrap();
        let entries = pvd_entries(&path);
        assert!(entries.windows(2).all(|w| w[0].0 < w[1].0), "{entries:?}");
    }
    assert_eq!(
        pvd_entries(&path),
        vec![
            (1e-7, "first.vtu".into()),
            (0.1, "a.vtu".into()),
            (0.2, "b.vtu".into()),
            (0.3, "c.vtu".into())
        ]
    );
    // Same time replaces; reopening finds the same frames; truncation on resume.
    pvd.add(0.2, 0, "b2.vtu").unwrap();
    let mut again = PvdCollection::open(&path).unwrap();
    assert_eq!(again.frames(), pvd.frames());
    assert_eq!(again.frames()[2].file, "b2.vtu");
    again.retain_until(0.2).unwrap();
    assert_eq!(pvd_entries(&path).len(), 3);
    assert!(matches!(
        pvd.add(f64::NAN, 0, "x.vtu"),
        Err(IoError::BadValue { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vtu_series_writes_frames_and_index() {
    let dir = scratch("series");
    let mut series = VtuSeries::new(&dir, "particles", Encoding::Raw).unwrap();
    let pts = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
    for step in [0u64, 10, 20] {
        let t = step as f64 * 1e-3;
        let temp = vec![t, 2.0 * t];
        let grid =
            UnstructuredGrid::particles(&pts).with_point_field("T", FieldValues::Scalar(&temp));
        series.write_frame(step, t, &grid).unwrap();
    }
    let entries = pvd_entries(&dir.join("particles.pvd"));
    assert_eq!(entries.len(), 3);
    for (k, (t, f)) in entries.iter().enumerate() {
        assert_eq!(*t, (10 * k) as f64 * 1e-3);
        assert!(dir.join(f).is_file(), "{f}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn csv_header_names_columns_with_units_and_rows_round_trip() {
    let dir = scratch("csv");
    let path = dir.join("history.csv");
    let cols = [
        Column::new("time", "s"),
        Column::new("axial_stress", "Pa"),
        Column::new("coordination_number", ""),
    ];
    let mut h = CsvHistory::create(&path, &cols).unwrap();
    let rows = [
        [0.0, 1.0e6, 4.5],
        [1e-4, -2.5e-300, 3.0],
        [2e-4, 0.1 + 0.2, 2.0],
    ];
    for r in &rows {
        h.push(r).unwrap();
    }
    assert!(matches!(
        h.push(&[1.0]),
        Err(IoError::RowLength {
            len: 1,
            expected: 3,
            ..
        })
    ));
    h.flush().unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time [s],axial_stress [Pa],coordination_number"
    );
    for r in &rows {
        let got: Vec<f64> = lines
            .next()
            .unwrap()
            .split(',')
            .map(|c| c.parse().unwrap())
            .collect();
        assert_eq!(
            got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            r.map(f64::to_bits)
        );
    }
    drop(h);
    // Resuming at t = 1e-4 keeps the first two rows and appends after them.
    let mut h = CsvHistory::resume(&path, &cols, 1e-4).unwrap();
    h.push(&[5.0, 6.0, 7.0]).unwrap();
    h.flush().unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text.lines().count(), 4);
    assert!(text.ends_with("5.0,6.0,7.0\n"), "{text}");
    // A history with another header is not silently appended to.
    let err = CsvHistory::resume(&path, &cols[..2], 1.0).unwrap_err();
    assert!(matches!(err, IoError::Malformed { .. }), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run killed while appending leaves a last row without its newline; its leading digits
/// (`10` of `100.5`) must not be read back as a row at an earlier time.
#[test]
fn csv_resume_drops_a_row_cut_short_by_a_kill() {
    let dir = scratch("csv-cut");
    let path = dir.join("history.csv");
    let cols = [Column::new("time", "s"), Column::new("x", "m")];
    std::fs::write(&path, "time [s],x [m]\n99.5,1.0\n100.0,2.0\n10").unwrap();
    let mut h = CsvHistory::resume(&path, &cols, 100.0).unwrap();
    h.push(&[100.5, 3.0]).unwrap();
    h.flush().unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "time [s],x [m]\n99.5,1.0\n100.0,2.0\n100.5,3.0\n"
    );
    // A complete line with too few values ends the kept rows too.
    std::fs::write(&path, "time [s],x [m]\n99.5,1.0\n100.0\n").unwrap();
    drop(h);
    CsvHistory::resume(&path, &cols, 100.0).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "time [s],x [m]\n99.5,1.0\n"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[derive(Debug, Serialize, Deserialize, PartialEq)]
struct State {
    step: u64,
    x: Vec<f64>,
    v: Vec<[f64; 2]>,
}

#[test]
fn checkpoint_round_trips_bitwise_and_rejects_other_versions_and_kinds() {
    let dir = scratch("ckpt");
    let path = dir.join("state.ckpt");
    let state = State {
        step: 42,
        x: vec![0.1 + 0.2, 1.0 / 3.0, -0.0, 5e-324, f64::MAX, 1e-310],
        v: vec![[std::f64::consts::PI, -std::f64::consts::E]],
    };
    save_checkpoint(&path, "demo", 3, &state).unwrap();
    let back: State = load_checkpoint(&path, "demo", 3).unwrap();
    assert_eq!(back.step, state.step);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&back.x), bits(&state.x));
    assert_eq!(back.v[0].map(f64::to_bits), state.v[0].map(f64::to_bits));

    let err = load_checkpoint::<State>(&path, "demo", 4).unwrap_err();
    assert!(
        matches!(
            err,
            IoError::CheckpointStateVersion {
                found: 3,
                expected: 4,
                ..
            }
        ),
        "{err}"
    );
    let err = load_checkpoint::<State>(&path, "other", 3).unwrap_err();
    assert!(matches!(err, IoError::CheckpointKind { .. }), "{err}");

    // Another container version: rewrite the header's version number and seal it with a
    // checksum that matches, as another program version would.
    let text = std::fs::read_to_string(&path).unwrap();
    let body = &text[..text.rfind(",\"crc32\"").unwrap()];
    let body = body.replace("\"format_version\":2", "\"format_version\":3");
    let bumped = dir.join("future.ckpt");
    let crc = crc32fast::hash(body.as_bytes());
    std::fs::write(&bumped, format!("{body},\"crc32\":\"{crc:08x}\"}}\n")).unwrap();
    let err = load_checkpoint::<State>(&bumped, "demo", 3).unwrap_err();
    assert!(
        matches!(
            err,
            IoError::CheckpointFormatVersion {
                found: 3,
                expected: 2,
                ..
            }
        ),
        "{err}"
    );
    // A state of another shape under the right header is an error, not a misread.
    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Other {
        step: u64,
        y: Vec<f64>,
    }
    let err = load_checkpoint::<Other>(&path, "demo", 3).unwrap_err();
    assert!(matches!(err, IoError::CheckpointState { .. }), "{err}");
    // Not a checkpoint at all; truncated file.
    let junk = dir.join("junk.ckpt");
    std::fs::write(&junk, "time,x\n1,2\n").unwrap();
    assert!(matches!(
        load_checkpoint::<State>(&junk, "demo", 3),
        Err(IoError::NotACheckpoint { .. })
    ));
    std::fs::write(&junk, &text[..text.len() / 2]).unwrap();
    assert!(matches!(
        load_checkpoint::<State>(&junk, "demo", 3),
        Err(IoError::CheckpointTruncated { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn plot_renders_a_png_and_its_csv() {
    let x: Vec<f64> = (0..=20).map(|i| i as f64 * 0.05).collect();
    let plot = Plot {
        name: "decay".into(),
        title: "Exponential decay".into(),
        x_label: "t [s]".into(),
        y_label: "T [K]".into(),
        series: vec![
            Series {
                label: "analytical".into(),
                role: SeriesRole::Reference,
                x: x.clone(),
                y: x.iter().map(|t| 300.0 + 50.0 * (-t).exp()).collect(),
            },
            Series {
                label: "measured".into(),
                role: SeriesRole::Measured,
                x: x.clone(),
                y: x.iter().map(|t| 300.0 + 50.0 * (-t).exp() + 0.3).collect(),
            },
        ],
    };
    let png = thm_io::render_plot_png(&plot).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let dir = scratch("plot");
    thm_io::write_plot_png(&plot, &dir.join("decay.png")).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(dir.join("decay.png")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), thm_io::plot::PLOT_SIZE);
    // Something besides the white background was drawn: curves, axes and text.
    let non_white = buf[..info.buffer_size()]
        .chunks(3)
        .filter(|p| p != &[255, 255, 255])
        .count();
    assert!(non_white > 5_000, "{non_white} drawn pixels");
    // Both blue (first series) and red (second series) pixels are present.
    let has = |c: [u8; 3]| buf.chunks(3).any(|p| p == c);
    assert!(has([0, 90, 181]) && has([220, 50, 32]));

    thm_io::write_plot_csv(&plot, &dir.join("decay.csv")).unwrap();
    let csv = std::fs::read_to_string(dir.join("decay.csv")).unwrap();
    assert_eq!(csv.lines().next().unwrap(), "series,role,t [s],T [K]");
    assert_eq!(csv.lines().count(), 1 + 2 * x.len());

    let empty = Plot {
        series: vec![],
        ..plot
    };
    assert!(matches!(
        thm_io::render_plot_png(&empty),
        Err(IoError::Plot { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// Whatever the order frames are added in, the collection lists each (time, part) once,
        /// in time order, and reads back identical.
        #[test]
        fn pvd_is_sorted_and_unique(times in proptest::collection::vec(0u32..50, 1..30)) {
            let dir = scratch(&format!("pvd-prop-{}", times.len()));
            let path = dir.join("p.pvd");
            let mut pvd = PvdCollection::new(&path);
            for (k, &t) in times.iter().enumerate() {
                pvd.add(f64::from(t) * 0.1, 0, format!("f{k}.vtu")).unwrap();
            }
            let entries = pvd_entries(&path);
            let mut unique: Vec<u32> = times.clone();
            unique.sort_unstable();
            unique.dedup();
            prop_assert_eq!(entries.len(), unique.len());
            prop_assert!(entries.windows(2).all(|w| w[0].0 < w[1].0));
            // The last frame added at a time is the one listed.
            for (t, f) in &entries {
                let k = times.iter().rposition(|&x| f64::from(x) * 0.1 == *t).unwrap();
                prop_assert_eq!(f, &format!("f{k}.vtu"));
            }
            let reopened = PvdCollection::open(&path).unwrap();
            prop_assert_eq!(reopened.frames(), pvd.frames());
            std::fs::remove_dir_all(&dir).unwrap();
        }

        /// Any finite f64 (subnormals, extremes, negative zero) survives a checkpoint bit for bit.
        #[test]
        fn checkpoint_is_bitwise(bits in proptest::collection::vec(any::<u64>(), 0..64)) {
            let x: Vec<f64> = bits.iter().map(|&b| f64::from_bits(b)).filter(|v| v.is_finite()).collect();
            let dir = scratch(&format!("ckpt-prop-{}", bits.len()));
            let path = dir.join("s.ckpt");
            save_checkpoint(&path, "p", 1, &x).unwrap();
            let back: Vec<f64> = load_checkpoint(&path, "p", 1).unwrap();
            prop_assert_eq!(
                back.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
