//! Checkpoints: any `serde` state saved with a container format version, a kind tag, the
//! state's own layout version and a CRC-32 checksum, as JSON (readable, for small states) or as
//! a compact binary form (for large ones).
//!
//! **JSON** (container version 2) is one line:
//! `{"format":"thm-checkpoint","format_version":2,"writer":"thm-io x.y.z","kind":"…",
//! "state_version":n,"state":…,"crc32":"hhhhhhhh"}` and a newline. The checksum covers every
//! byte before `,"crc32"`; the file must end exactly with the checksum field, `}` and the
//! newline, so a file cut short anywhere is reported as truncated and any altered byte fails the
//! checksum (CRC-32 catches every change confined to 32 consecutive bits, so every flipped
//! byte). Every `f64` is written in its shortest exact decimal form and parsed back exactly
//! (serde_json's `float_roundtrip`), so a resumed run continues bit for bit. Non-finite floats
//! cannot be stored (JSON has no NaN): a state holding one fails to load with
//! [`IoError::CheckpointState`], never silently.
//!
//! **Binary** (same container version), all integers little-endian:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `THMCKPT` and a zero byte |
//! | 4 | container format version (`u32`) |
//! | 4 | state layout version (`u32`) |
//! | 2 + k | kind tag length (`u16`, at most [`MAX_TAG_LEN`]) and UTF-8 text |
//! | 2 + w | writer length (`u16`, at most [`MAX_TAG_LEN`]) and UTF-8 text |
//! | p | the state, `bincode` 2 with its standard configuration (variable-length integers, every `f64` as its 8 bytes) |
//! | 8 | payload length p (`u64`) |
//! | 4 | CRC-32 of every byte before it (`u32`) |
//!
//! A binary state keeps every bit, NaN included.
//!
//! [`save_checkpoint`] picks the form by size: JSON while the binary payload stays below
//! [`AUTO_BINARY_FROM`] bytes, binary above; [`save_checkpoint_as`] forces one. Loading recognises either form by its first bytes and checks, in order: that it
//! is a checkpoint at all, that it is complete, the checksum, the container version, the kind,
//! the state version, and finally decodes the state. Each failure is its own [`IoError`]
//! variant, and no message quotes more than a short excerpt of the file.

use std::io::Write;
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::value::RawValue;

use crate::IoError;
use crate::fsutil::write_atomically;

/// Version of the checkpoint container written by this crate (both forms).
pub const CHECKPOINT_FORMAT_VERSION: u32 = 2;

/// Binary payloads of at least this many bytes are written in the binary form by
/// [`save_checkpoint`]; smaller states are written as JSON.
pub const AUTO_BINARY_FROM: u64 = 1 << 20;

/// Longest kind tag or writer name a checkpoint may carry \[bytes\].
pub const MAX_TAG_LEN: usize = 256;

/// First bytes of a binary checkpoint.
pub const BINARY_MAGIC: &[u8; 8] = b"THMCKPT\0";

const FORMAT_TAG: &str = "thm-checkpoint";
const WRITER: &str = concat!("thm-io ", env!("CARGO_PKG_VERSION"));
const CRC_FIELD: &[u8] = b",\"crc32\":\"";
/// `,"crc32":"` + 8 hex digits + `"}` + newline.
const JSON_TAIL_LEN: usize = CRC_FIELD.len() + 8 + 3;
/// Binary trailer: payload length and checksum.
const TRAILER_LEN: usize = 12;
/// Longest excerpt of a file quoted in an error message \[bytes\].
pub const EXCERPT_LEN: usize = 48;

/// Which form [`save_checkpoint_as`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CheckpointEncoding {
    /// One line of JSON with a checksum field (readable, about 5× the binary size).
    Json,
    /// The compact binary form.
    Binary,
    /// JSON below [`AUTO_BINARY_FROM`] bytes of binary payload, binary from there on.
    Auto,
}

/// What a checkpoint's header says (see [`checkpoint_info`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckpointInfo {
    /// The form of the file.
    pub encoding: CheckpointEncoding,
    /// The kind tag.
    pub kind: String,
    /// The state layout version.
    pub state_version: u32,
    /// The program that wrote it (`thm-io x.y.z`).
    pub writer: String,
}

#[derive(Serialize)]
struct EnvelopeOut<'a> {
    format: &'a str,
    format_version: u32,
    writer: &'a str,
    kind: &'a str,
    state_version: u32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvelopeIn<'a> {
    format: String,
    format_version: u32,
    writer: String,
    kind: String,
    state_version: u32,
    #[serde(borrow)]
    state: &'a RawValue,
    #[allow(dead_code)]
    crc32: String,
}

/// Only the container tag and version, readable from any earlier container version.
#[derive(Deserialize)]
struct VersionProbe {
    format: String,
    format_version: u32,
}

/// The most a valid binary payload can claim while it is decoded, per payload byte. bincode
/// counts against its limit the in-memory size of every primitive it reads (at most 16 bytes,
/// a `u128`, from at least one encoded byte) and the length of every string or byte buffer
/// (one encoded byte each), before allocating; so a valid state claims at most 16 × its payload,
/// and a length field claiming more is an error before anything is allocated. (A fixed 1 TiB
/// limit let a corrupt string length ask for 494 GB, and the failed allocation aborted the
/// process: `fuzz/regressions/checkpoint/crash-f860…`.)
const CLAIM_PER_PAYLOAD_BYTE: usize = 16;

fn bincode_config() -> bincode::config::Configuration {
    bincode::config::standard()
}

/// Decodes a binary payload under bincode's limit `LIMIT` \[bytes\].
fn decode_limited<T: DeserializeOwned, const LIMIT: usize>(
    payload: &[u8],
) -> Result<(T, usize), bincode::error::DecodeError> {
    bincode::serde::decode_from_slice::<T, _>(
        payload,
        bincode::config::standard().with_limit::<LIMIT>(),
    )
}

/// Decodes a binary payload with a limit of at least [`CLAIM_PER_PAYLOAD_BYTE`] × its length
/// (bincode takes the limit as a constant: the smallest of a few powers of two that is enough,
/// so a corrupt length can make it allocate at most 16 times that, 1 MiB for small payloads).
fn decode_payload<T: DeserializeOwned>(
    payload: &[u8],
) -> Result<(T, usize), bincode::error::DecodeError> {
    let need = payload.len().saturating_mul(CLAIM_PER_PAYLOAD_BYTE);
    if need <= 1 << 20 {
        decode_limited::<T, { 1 << 20 }>(payload)
    } else if need <= 1 << 24 {
        decode_limited::<T, { 1 << 24 }>(payload)
    } else if need <= 1 << 28 {
        decode_limited::<T, { 1 << 28 }>(payload)
    } else if need <= 1 << 32 {
        decode_limited::<T, { 1 << 32 }>(payload)
    } else if need <= 1 << 36 {
        decode_limited::<T, { 1 << 36 }>(payload)
    } else if need <= 1 << 40 {
        decode_limited::<T, { 1 << 40 }>(payload)
    } else {
        decode_limited::<T, { usize::MAX }>(payload)
    }
}

/// A writer that feeds a CRC-32 and counts the bytes it passes on.
struct Summing<W> {
    inner: W,
    crc: crc32fast::Hasher,
    len: u64,
}

impl<W: Write> Write for Summing<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        self.len += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A sink that counts bytes and refuses any beyond `cap`.
struct Capped {
    len: u64,
    cap: u64,
}

impl Write for Capped {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.len += buf.len() as u64;
        if self.len > self.cap {
            return Err(std::io::Error::other("cap reached"));
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Whether the binary payload of `state` has at least `cap` bytes. Stops encoding at the cap,
/// so it costs at most `cap` bytes of encoding whatever the state's size.
fn binary_payload_reaches<T: Serialize>(state: &T, cap: u64) -> std::io::Result<bool> {
    let mut sink = Capped {
        len: 0,
        cap: cap.saturating_sub(1),
    };
    match bincode::serde::encode_into_std_write(state, &mut sink, bincode_config()) {
        Ok(_) => Ok(false),
        Err(_) if sink.len > sink.cap => Ok(true),
        Err(e) => Err(std::io::Error::other(e)),
    }
}

fn check_tag(what: &'static str, text: &str) -> Result<(), IoError> {
    if text.len() > MAX_TAG_LEN {
        return Err(IoError::BadValue {
            quantity: what,
            requirement: "at most 256 bytes long",
            value: text.len() as f64,
        });
    }
    Ok(())
}

/// Saves `state` (atomically) under the tag `kind` and layout version `state_version`, as JSON
/// for small states and in the binary form for large ones ([`CheckpointEncoding::Auto`]).
pub fn save_checkpoint<T: Serialize>(
    path: &Path,
    kind: &str,
    state_version: u32,
    state: &T,
) -> Result<(), IoError> {
    save_checkpoint_as(path, CheckpointEncoding::Auto, kind, state_version, state)
}

/// Saves `state` (atomically) in the form `encoding`.
pub fn save_checkpoint_as<T: Serialize>(
    path: &Path,
    encoding: CheckpointEncoding,
    kind: &str,
    state_version: u32,
    state: &T,
) -> Result<(), IoError> {
    check_tag("checkpoint kind tag length [bytes]", kind)?;
    let encoding = match encoding {
        CheckpointEncoding::Auto => {
            let large = binary_payload_reaches(state, AUTO_BINARY_FROM)
                .map_err(|e| IoError::file(path, "encode", e))?;
            if large {
                CheckpointEncoding::Binary
            } else {
                CheckpointEncoding::Json
            }
        }
        e => e,
    };
    write_atomically(path, |w| {
        let mut out = Summing {
            inner: w,
            crc: crc32fast::Hasher::new(),
            len: 0,
        };
        if encoding == CheckpointEncoding::Binary {
            out.write_all(BINARY_MAGIC)?;
            out.write_all(&CHECKPOINT_FORMAT_VERSION.to_le_bytes())?;
            out.write_all(&state_version.to_le_bytes())?;
            for text in [kind, WRITER] {
                let len = u16::try_from(text.len()).map_err(std::io::Error::other)?;
                out.write_all(&len.to_le_bytes())?;
                out.write_all(text.as_bytes())?;
            }
            let start = out.len;
            bincode::serde::encode_into_std_write(state, &mut out, bincode_config())
                .map_err(std::io::Error::other)?;
            let payload = out.len - start;
            out.write_all(&payload.to_le_bytes())?;
            let crc = out.crc.clone().finalize();
            out.inner.write_all(&crc.to_le_bytes())
        } else {
            let header = EnvelopeOut {
                format: FORMAT_TAG,
                format_version: CHECKPOINT_FORMAT_VERSION,
                writer: WRITER,
                kind,
                state_version,
            };
            // The header's closing brace is replaced by the state field.
            let mut head = serde_json::to_vec(&header).map_err(std::io::Error::other)?;
            head.pop();
            out.write_all(&head)?;
            out.write_all(b",\"state\":")?;
            serde_json::to_writer(&mut out, state).map_err(std::io::Error::other)?;
            let crc = out.crc.clone().finalize();
            writeln!(out.inner, ",\"crc32\":\"{crc:08x}\"}}")
        }
    })
}

/// Reads the kind tag of a checkpoint (to dispatch on it before loading the state).
pub fn checkpoint_kind(path: &Path) -> Result<String, IoError> {
    Ok(checkpoint_info(path)?.kind)
}

/// Checks a checkpoint file completely (form, completeness, checksum, container version) and
/// returns its header, without decoding the state.
pub fn checkpoint_info(path: &Path) -> Result<CheckpointInfo, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, "read", e))?;
    Ok(parse(path, &bytes)?.info)
}

/// Loads a state saved by [`save_checkpoint`] with the same `kind` and `state_version`.
pub fn load_checkpoint<T: DeserializeOwned>(
    path: &Path,
    kind: &str,
    state_version: u32,
) -> Result<T, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, "read", e))?;
    checkpoint_from_bytes(path, &bytes, kind, state_version)
}

/// Decodes checkpoint `bytes` (the content of `path`, named in errors) holding a `kind` state
/// of layout version `state_version`. Any input gives a typed error or the state, never a
/// panic.
pub fn checkpoint_from_bytes<T: DeserializeOwned>(
    path: &Path,
    bytes: &[u8],
    kind: &str,
    state_version: u32,
) -> Result<T, IoError> {
    let parsed = parse(path, bytes)?;
    let info = parsed.info;
    if info.kind != kind {
        return Err(IoError::CheckpointKind {
            path: path.to_path_buf(),
            found: excerpt(info.kind.as_bytes()),
            expected: kind.to_string(),
        });
    }
    if info.state_version != state_version {
        return Err(IoError::CheckpointStateVersion {
            path: path.to_path_buf(),
            kind: info.kind,
            found: info.state_version,
            expected: state_version,
            writer: excerpt(info.writer.as_bytes()),
        });
    }
    let state_error = |message: String| IoError::CheckpointState {
        path: path.to_path_buf(),
        message,
    };
    match parsed.state {
        StateBytes::Json(text) => {
            serde_json::from_str(text).map_err(|e| state_error(clip(&e.to_string())))
        }
        StateBytes::Binary(payload) => {
            let (state, used) =
                decode_payload::<T>(payload).map_err(|e| state_error(clip(&e.to_string())))?;
            if used != payload.len() {
                return Err(state_error(format!(
                    "the state uses {used} of the payload's {} bytes",
                    payload.len()
                )));
            }
            Ok(state)
        }
    }
}

enum StateBytes<'a> {
    Json(&'a str),
    Binary(&'a [u8]),
}

struct Parsed<'a> {
    info: CheckpointInfo,
    state: StateBytes<'a>,
}

fn parse<'a>(path: &Path, bytes: &'a [u8]) -> Result<Parsed<'a>, IoError> {
    if bytes.starts_with(BINARY_MAGIC) {
        parse_binary(path, bytes)
    } else if bytes.first() == Some(&b'{') {
        parse_json(path, bytes)
    } else if !bytes.is_empty() && BINARY_MAGIC.starts_with(bytes) {
        Err(truncated(path, bytes.len(), "ends inside its first bytes"))
    } else {
        Err(IoError::NotACheckpoint {
            path: path.to_path_buf(),
            message: if bytes.is_empty() {
                "the file is empty".into()
            } else {
                format!("it begins `{}`", excerpt(bytes))
            },
        })
    }
}

fn truncated(path: &Path, len: usize, message: &str) -> IoError {
    IoError::CheckpointTruncated {
        path: path.to_path_buf(),
        len: len as u64,
        message: message.to_string(),
    }
}

fn checksum_error(path: &Path, stored: u32, computed: u32) -> IoError {
    IoError::CheckpointChecksum {
        path: path.to_path_buf(),
        stored,
        computed,
    }
}

fn version_error(path: &Path, found: u32, writer: Option<String>) -> IoError {
    IoError::CheckpointFormatVersion {
        path: path.to_path_buf(),
        found,
        expected: CHECKPOINT_FORMAT_VERSION,
        writer: writer.map_or_else(|| "an earlier version".into(), |w| excerpt(w.as_bytes())),
    }
}

fn parse_json<'a>(path: &Path, bytes: &'a [u8]) -> Result<Parsed<'a>, IoError> {
    let not_json = |message: String| IoError::NotACheckpoint {
        path: path.to_path_buf(),
        message,
    };
    // A checkpoint of an earlier container version has no checksum: recognise it by its tag.
    let tail_at = bytes.len().saturating_sub(JSON_TAIL_LEN);
    let tail = &bytes[tail_at..];
    let complete = bytes.len() >= JSON_TAIL_LEN
        && tail.starts_with(CRC_FIELD)
        && tail.ends_with(b"\"}\n")
        && tail[CRC_FIELD.len()..CRC_FIELD.len() + 8]
            .iter()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(b));
    if !complete {
        if let Ok(probe) = serde_json::from_slice::<VersionProbe>(bytes)
            && probe.format == FORMAT_TAG
            && probe.format_version != CHECKPOINT_FORMAT_VERSION
        {
            return Err(version_error(path, probe.format_version, None));
        }
        let format_tag = format!("{{\"format\":\"{FORMAT_TAG}\"");
        if bytes.starts_with(format_tag.as_bytes()) {
            return Err(truncated(
                path,
                bytes.len(),
                "does not end with its checksum field",
            ));
        }
        return Err(not_json(format!(
            "not the JSON of a checkpoint: it begins `{}`",
            excerpt(bytes)
        )));
    }
    let hex = &tail[CRC_FIELD.len()..CRC_FIELD.len() + 8];
    let stored = std::str::from_utf8(hex)
        .ok()
        .and_then(|h| u32::from_str_radix(h, 16).ok())
        .ok_or_else(|| not_json("the checksum field is not hexadecimal".into()))?;
    let computed = crc32fast::hash(&bytes[..tail_at]);
    if stored != computed {
        return Err(checksum_error(path, stored, computed));
    }
    let envelope: EnvelopeIn<'a> =
        serde_json::from_slice(bytes).map_err(|e| not_json(clip(&e.to_string())))?;
    if envelope.format != FORMAT_TAG {
        return Err(not_json(format!(
            "format tag `{}`",
            excerpt(envelope.format.as_bytes())
        )));
    }
    if envelope.format_version != CHECKPOINT_FORMAT_VERSION {
        return Err(version_error(
            path,
            envelope.format_version,
            Some(envelope.writer),
        ));
    }
    Ok(Parsed {
        info: CheckpointInfo {
            encoding: CheckpointEncoding::Json,
            kind: envelope.kind,
            state_version: envelope.state_version,
            writer: envelope.writer,
        },
        state: StateBytes::Json(envelope.state.get()),
    })
}

/// Reads little-endian fields off the front of a byte slice.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.at.checked_add(n)?;
        let out = self.bytes.get(self.at..end)?;
        self.at = end;
        Some(out)
    }

    fn u16(&mut self) -> Option<u16> {
        self.take(2)?.try_into().ok().map(u16::from_le_bytes)
    }

    fn u32(&mut self) -> Option<u32> {
        self.take(4)?.try_into().ok().map(u32::from_le_bytes)
    }

    fn text(&mut self) -> Option<Result<&'a str, ()>> {
        let n = usize::from(self.u16()?);
        let raw = self.take(n)?;
        Some(if n > MAX_TAG_LEN {
            Err(())
        } else {
            std::str::from_utf8(raw).map_err(|_| ())
        })
    }
}

fn parse_binary<'a>(path: &Path, bytes: &'a [u8]) -> Result<Parsed<'a>, IoError> {
    let short = || truncated(path, bytes.len(), "ends inside its header");
    let mut c = Cursor {
        bytes,
        at: BINARY_MAGIC.len(),
    };
    let format_version = c.u32().ok_or_else(short)?;
    let state_version = c.u32().ok_or_else(short)?;
    let kind = c.text().ok_or_else(short)?;
    let writer = c.text().ok_or_else(short)?;
    let body_end = c.at;
    if bytes.len() < body_end + TRAILER_LEN {
        return Err(short());
    }
    let trailer_at = bytes.len() - TRAILER_LEN;
    let mut t = Cursor {
        bytes,
        at: trailer_at,
    };
    let payload_len = t
        .take(8)
        .and_then(|b| b.try_into().ok())
        .map(u64::from_le_bytes)
        .ok_or_else(short)?;
    let stored = t.u32().ok_or_else(short)?;
    let computed = crc32fast::hash(&bytes[..bytes.len() - 4]);
    let actual = (trailer_at - body_end) as u64;
    if stored != computed {
        if payload_len != actual {
            return Err(truncated(
                path,
                bytes.len(),
                "its trailer does not match its length",
            ));
        }
        return Err(checksum_error(path, stored, computed));
    }
    let header_error = |what: &str| IoError::NotACheckpoint {
        path: path.to_path_buf(),
        message: format!("the {what} in its header is not UTF-8 text of at most 256 bytes"),
    };
    let kind = kind.map_err(|()| header_error("kind tag"))?;
    let writer = writer.map_err(|()| header_error("writer name"))?;
    if format_version != CHECKPOINT_FORMAT_VERSION {
        return Err(version_error(path, format_version, Some(writer.into())));
    }
    if payload_len != actual {
        return Err(truncated(
            path,
            bytes.len(),
            "its payload length does not match the file",
        ));
    }
    Ok(Parsed {
        info: CheckpointInfo {
            encoding: CheckpointEncoding::Binary,
            kind: kind.to_string(),
            state_version,
            writer: writer.to_string(),
        },
        state: StateBytes::Binary(&bytes[body_end..trailer_at]),
    })
}

/// At most [`EXCERPT_LEN`] bytes of `bytes` as printable text (control characters and invalid
/// UTF-8 escaped), with `…` when cut.
pub fn excerpt(bytes: &[u8]) -> String {
    let cut = bytes.len() > EXCERPT_LEN;
    let head = &bytes[..bytes.len().min(EXCERPT_LEN)];
    let mut out: String = String::from_utf8_lossy(head)
        .chars()
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect();
    if cut {
        out.push('…');
    }
    out
}

/// A decoder's message cut to a few hundred characters (a message may quote the input).
fn clip(message: &str) -> String {
    const MAX: usize = 200;
    if message.chars().count() <= MAX {
        return message.to_string();
    }
    let mut out: String = message.chars().take(MAX).collect();
    out.push('…');
    out
}

#[cfg(test)]
mod tests;
