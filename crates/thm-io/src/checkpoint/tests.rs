//! Round trips of both forms, and every way a checkpoint file can be damaged.

use super::*;
use std::path::PathBuf;

#[derive(Debug, Serialize, Deserialize, PartialEq)]
struct State {
    step: u64,
    name: String,
    x: Vec<f64>,
    bonds: Vec<(u32, u32, Option<f64>)>,
}

fn state(n: usize) -> State {
    State {
        step: 42,
        name: "bar \"a\"".into(),
        x: (0..n).map(|i| (i as f64 + 0.1) / 3.0).collect(),
        bonds: vec![(0, 1, Some(-0.0)), (1, 2, None)],
    }
}

fn path() -> PathBuf {
    PathBuf::from("test.ckpt")
}

fn bytes_of(encoding: CheckpointEncoding, s: &State) -> Vec<u8> {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("thm-io-ckpt-unit-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("s.ckpt");
    save_checkpoint_as(&p, encoding, "demo", 3, s).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    bytes
}

fn load(bytes: &[u8]) -> Result<State, IoError> {
    checkpoint_from_bytes(&path(), bytes, "demo", 3)
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn both_forms_round_trip_bit_for_bit() {
    let mut s = state(50);
    s.x.extend([5e-324, f64::MAX, -0.0, 1e-310]);
    for encoding in [CheckpointEncoding::Json, CheckpointEncoding::Binary] {
        let b = bytes_of(encoding, &s);
        let back = load(&b).unwrap();
        assert_eq!(bits(&back.x), bits(&s.x));
        assert_eq!(back.bonds[0].2.map(f64::to_bits), Some((-0.0f64).to_bits()));
        assert_eq!(back, s);
        let info = parse(&path(), &b).unwrap().info;
        assert_eq!(info.encoding, encoding);
        assert_eq!(info.kind, "demo");
        assert_eq!(info.writer, WRITER);
    }
    // JSON cannot hold a NaN; the binary form keeps its bits.
    s.x.push(f64::from_bits(0x7ff8_0000_dead_beef));
    let back = load(&bytes_of(CheckpointEncoding::Binary, &s)).unwrap();
    assert_eq!(bits(&back.x), bits(&s.x));
    let err = load(&bytes_of(CheckpointEncoding::Json, &s)).unwrap_err();
    assert!(matches!(err, IoError::CheckpointState { .. }), "{err}");
}

#[test]
fn json_stays_one_readable_line() {
    let b = bytes_of(CheckpointEncoding::Json, &state(3));
    let text = std::str::from_utf8(&b).unwrap();
    assert!(text.starts_with("{\"format\":\"thm-checkpoint\",\"format_version\":2,"));
    assert_eq!(text.matches('\n').count(), 1);
    let value: serde_json::Value = serde_json::from_str(text).unwrap();
    assert_eq!(value["state"]["step"], 42);
}

#[test]
fn auto_writes_json_for_small_states_and_binary_for_large_ones() {
    let small = bytes_of(CheckpointEncoding::Auto, &state(1000));
    assert_eq!(small[0], b'{');
    // 8 bytes per f64: 140 000 values are above the 1 MiB threshold.
    let large = bytes_of(CheckpointEncoding::Auto, &state(140_000));
    assert!(large.starts_with(BINARY_MAGIC));
    assert_eq!(load(&large).unwrap().x.len(), 140_000);
}

/// Every single altered byte, at every position, in every way tried, is refused.
#[test]
fn every_flipped_byte_is_refused() {
    for encoding in [CheckpointEncoding::Json, CheckpointEncoding::Binary] {
        let good = bytes_of(encoding, &state(8));
        for i in 0..good.len() {
            for mask in [0x01u8, 0x20, 0x80, 0xff] {
                let mut bad = good.clone();
                bad[i] ^= mask;
                let result = load(&bad);
                assert!(
                    result.is_err(),
                    "{encoding:?}: byte {i} ^ {mask:#x} was accepted"
                );
            }
        }
        // Inside the state, the checksum is what catches it.
        let mut bad = good.clone();
        let at = good.len() / 2;
        bad[at] ^= 0x01;
        let err = load(&bad).unwrap_err();
        assert!(
            matches!(err, IoError::CheckpointChecksum { .. }),
            "{encoding:?}: {err}"
        );
        assert!(err.to_string().contains("altered or damaged"), "{err}");
    }
}

/// A file cut short anywhere is refused, and named as truncated once its tag is there.
#[test]
fn every_truncation_is_refused() {
    for encoding in [CheckpointEncoding::Json, CheckpointEncoding::Binary] {
        let good = bytes_of(encoding, &state(8));
        for len in 0..good.len() {
            let err = load(&good[..len]).unwrap_err();
            let tagged = match encoding {
                CheckpointEncoding::Binary => len > 0,
                _ => len >= "{\"format\":\"thm-checkpoint\"".len(),
            };
            if tagged {
                assert!(
                    matches!(err, IoError::CheckpointTruncated { .. }),
                    "{encoding:?} cut to {len}: {err}"
                );
            } else {
                assert!(
                    matches!(err, IoError::NotACheckpoint { .. }),
                    "{encoding:?} cut to {len}: {err}"
                );
            }
        }
    }
}

/// Rewrites a JSON checkpoint's container version and seals it with a valid checksum.
fn json_with_version(good: &[u8], version: u32) -> Vec<u8> {
    let text = std::str::from_utf8(good).unwrap();
    let body = &text[..text.len() - JSON_TAIL_LEN];
    let body = body.replace(
        "\"format_version\":2",
        &format!("\"format_version\":{version}"),
    );
    let crc = crc32fast::hash(body.as_bytes());
    format!("{body},\"crc32\":\"{crc:08x}\"}}\n").into_bytes()
}

#[test]
fn other_container_versions_are_refused_naming_both() {
    let good = bytes_of(CheckpointEncoding::Json, &state(4));
    let err = load(&json_with_version(&good, 3)).unwrap_err();
    assert!(
        matches!(
            &err,
            IoError::CheckpointFormatVersion { found: 3, expected: 2, writer, .. } if writer == WRITER
        ),
        "{err}"
    );
    // The previous container (version 1) had no checksum.
    let v1 = br#"{"format":"thm-checkpoint","format_version":1,"kind":"demo","state_version":3,"state":{"step":1}}
"#;
    let err = load(v1).unwrap_err();
    assert!(
        matches!(err, IoError::CheckpointFormatVersion { found: 1, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("version 1"), "{err}");
    // Binary: the version field sits after the magic.
    let mut bin = bytes_of(CheckpointEncoding::Binary, &state(4));
    bin[8..12].copy_from_slice(&7u32.to_le_bytes());
    let n = bin.len();
    let crc = crc32fast::hash(&bin[..n - 4]);
    bin[n - 4..].copy_from_slice(&crc.to_le_bytes());
    let err = load(&bin).unwrap_err();
    assert!(
        matches!(err, IoError::CheckpointFormatVersion { found: 7, .. }),
        "{err}"
    );
}

#[test]
fn kind_and_state_version_are_checked() {
    for encoding in [CheckpointEncoding::Json, CheckpointEncoding::Binary] {
        let good = bytes_of(encoding, &state(4));
        let err = checkpoint_from_bytes::<State>(&path(), &good, "other", 3).unwrap_err();
        assert!(matches!(err, IoError::CheckpointKind { .. }), "{err}");
        let err = checkpoint_from_bytes::<State>(&path(), &good, "demo", 4).unwrap_err();
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
        // A state of another shape is an error, not a misread.
        let err = checkpoint_from_bytes::<(u64, u64)>(&path(), &good, "demo", 3).unwrap_err();
        assert!(matches!(err, IoError::CheckpointState { .. }), "{err}");
    }
}

/// A large file that is not a checkpoint is named with a short excerpt, not quoted whole.
#[test]
fn errors_quote_at_most_a_short_excerpt() {
    let scenario = "kind = \"lumped_cooling\"\n".repeat(3000);
    let err = load(scenario.as_bytes()).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, IoError::NotACheckpoint { .. }), "{message}");
    assert!(
        message.contains("kind = \"lumped_cooling\"\\n"),
        "{message}"
    );
    assert!(message.len() < 200, "{} bytes: {message}", message.len());
    // A 60 KB JSON object that is no checkpoint.
    let json = format!("{{\"a\":[{}0]}}", "1.5,".repeat(15_000));
    let message = load(json.as_bytes()).unwrap_err().to_string();
    assert!(message.len() < 200, "{} bytes: {message}", message.len());
    assert_eq!(
        load(b"").unwrap_err().to_string(),
        "test.ckpt: not a thm checkpoint (the file is empty)"
    );
}

#[test]
fn a_binary_header_with_a_huge_or_invalid_tag_is_refused() {
    let mut b = Vec::from(&BINARY_MAGIC[..]);
    b.extend(2u32.to_le_bytes());
    b.extend(3u32.to_le_bytes());
    b.extend(u16::MAX.to_le_bytes());
    b.extend(vec![b'k'; usize::from(u16::MAX)]);
    b.extend(0u16.to_le_bytes());
    b.extend(0u64.to_le_bytes());
    let crc = crc32fast::hash(&b);
    b.extend(crc.to_le_bytes());
    let err = load(&b).unwrap_err();
    assert!(matches!(err, IoError::NotACheckpoint { .. }), "{err}");
    assert!(err.to_string().len() < 200);
    let long = "k".repeat(MAX_TAG_LEN + 1);
    let dir = std::env::temp_dir();
    let err = save_checkpoint(&dir.join("never.ckpt"), &long, 1, &1u8).unwrap_err();
    assert!(matches!(err, IoError::BadValue { .. }), "{err}");
}

/// The form switches exactly at [`AUTO_BINARY_FROM`] bytes of binary payload (a `Vec<u8>` of
/// `n ≥ 2¹⁶` bytes encodes as a 5-byte length and its bytes).
#[test]
fn auto_switches_at_exactly_the_threshold() {
    let dir = std::env::temp_dir().join(format!("thm-io-ckpt-auto-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("s.ckpt");
    let at = AUTO_BINARY_FROM as usize - 5;
    for (n, binary) in [(at - 1, false), (at, true)] {
        let state = vec![7u8; n];
        save_checkpoint(&p, "bytes", 1, &state).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(bytes.starts_with(BINARY_MAGIC), binary, "{n} bytes");
        let back: Vec<u8> = checkpoint_from_bytes(&p, &bytes, "bytes", 1).unwrap();
        assert_eq!(back, state);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Found by the `checkpoint` fuzz target: a binary payload whose length field claims more
/// than `isize::MAX` elements made the decoder ask for that capacity and panic. It is now a
/// typed error (`fuzz/regressions/checkpoint/capacity-overflow`).
#[test]
fn a_huge_length_in_the_payload_is_an_error_not_a_panic() {
    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    enum Shape {
        Empty,
        Radius(f64),
        Box { side: [f64; 2] },
    }
    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    struct FuzzState {
        step: u64,
        name: String,
        x: Vec<f64>,
        pairs: Vec<(u32, u32)>,
        flag: Option<bool>,
        shape: Shape,
    }
    // The target seals its input with a valid checksum before decoding; so does this test.
    let mut bytes =
        include_bytes!("../../../../fuzz/regressions/checkpoint/capacity-overflow").to_vec();
    let n = bytes.len();
    let crc = crc32fast::hash(&bytes[..n - 4]);
    bytes[n - 4..].copy_from_slice(&crc.to_le_bytes());
    let err = checkpoint_from_bytes::<FuzzState>(&path(), &bytes, "fuzz", 1).unwrap_err();
    assert!(matches!(err, IoError::CheckpointState { .. }), "{err}");
}

/// Found by the `checkpoint` fuzz target (600 s run): a string length of 494 GB, under the
/// former fixed 1 TiB limit, made the decoder allocate it and the failed allocation aborted the
/// process (`fuzz/regressions/checkpoint/crash-f860…`). The limit now scales with the payload:
/// a typed error, and states claiming the most per byte (u128 and u64 zeros, empty strings)
/// still decode.
#[test]
fn a_length_beyond_the_payload_is_an_error_not_an_allocation() {
    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    enum Shape {
        Empty,
        Radius(f64),
        Box { side: [f64; 2] },
    }
    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    struct FuzzState {
        step: u64,
        name: String,
        x: Vec<f64>,
        pairs: Vec<(u32, u32)>,
        flag: Option<bool>,
        shape: Shape,
    }
    let mut bytes = include_bytes!(
        "../../../../fuzz/regressions/checkpoint/crash-f8601f746a2f2e5af754eb790cfe2ff545ece819"
    )
    .to_vec();
    let n = bytes.len();
    let crc = crc32fast::hash(&bytes[..n - 4]);
    bytes[n - 4..].copy_from_slice(&crc.to_le_bytes());
    let err = checkpoint_from_bytes::<FuzzState>(&path(), &bytes, "fuzz", 1).unwrap_err();
    assert!(matches!(err, IoError::CheckpointState { .. }), "{err}");

    type Dense = (Vec<u128>, Vec<u64>, Vec<String>, Vec<Option<u32>>);
    let dense: Dense = (
        vec![0; 5000],
        vec![0; 5000],
        vec![String::new(); 5000],
        vec![None; 5000],
    );
    let dir = std::env::temp_dir().join(format!("thm-io-claim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("dense.ckpt");
    save_checkpoint_as(&p, CheckpointEncoding::Binary, "dense", 1, &dense).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert!(bytes.starts_with(BINARY_MAGIC));
    let back: Dense = checkpoint_from_bytes(&p, &bytes, "dense", 1).unwrap();
    assert_eq!(back, dense);
    std::fs::remove_dir_all(&dir).unwrap();
}
