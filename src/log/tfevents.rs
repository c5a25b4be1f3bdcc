//! TensorBoard event files (`events.out.tfevents.*`): TFRecord framing around
//! `tensorflow.Event` protobuf messages, written and read by hand (a few
//! fields of two messages; no protobuf or TensorFlow dependency).
//!
//! A record: `u64` length (little-endian), its masked CRC-32C, the bytes, their
//! masked CRC-32C. The messages written, with their field numbers from
//! `tensorflow/core/util/event.proto` and `summary.proto`:
//! - `Event { double wall_time = 1; int64 step = 2; string file_version = 3;
//!   Summary summary = 5; SessionLog session_log = 6; }`
//! - `Summary { repeated Value value = 1; }`, `Value { string tag = 1; float simple_value = 2; }`
//! - `SessionLog { SessionStatus status = 1; }` with START = 1: TensorBoard drops
//!   the events of earlier files at this step and later (a resumed run's redone part).

use anyhow::{bail, Context};
use std::path::Path;

/// CRC-32C (Castagnoli, reflected polynomial 0x82F63B78) of `bytes`.
pub fn crc32c(bytes: &[u8]) -> u32 {
    const TABLE: [u32; 256] = {
        let mut table = [0u32; 256];
        let mut i = 0;
        while i < 256 {
            let mut c = i as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 { 0x82F6_3B78 ^ (c >> 1) } else { c >> 1 };
                k += 1;
            }
            table[i] = c;
            i += 1;
        }
        table
    };
    !bytes.iter().fold(!0u32, |crc, &b| TABLE[((crc ^ u32::from(b)) & 0xff) as usize] ^ (crc >> 8))
}

/// TFRecord's masked CRC: the CRC rotated right by 15 bits plus a constant.
pub fn masked_crc(bytes: &[u8]) -> u32 {
    crc32c(bytes).rotate_right(15).wrapping_add(0xa282_ead8)
}

/// `data` framed as one TFRecord.
pub fn record(data: &[u8]) -> Vec<u8> {
    let len = (data.len() as u64).to_le_bytes();
    let mut out = Vec::with_capacity(data.len() + 16);
    out.extend_from_slice(&len);
    out.extend_from_slice(&masked_crc(&len).to_le_bytes());
    out.extend_from_slice(data);
    out.extend_from_slice(&masked_crc(data).to_le_bytes());
    out
}

fn varint(mut v: u64, out: &mut Vec<u8>) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// A length-delimited field (wire type 2).
fn bytes_field(field: u64, bytes: &[u8], out: &mut Vec<u8>) {
    varint(field << 3 | 2, out);
    varint(bytes.len() as u64, out);
    out.extend_from_slice(bytes);
}

/// What an event carries besides its time and step.
#[derive(Debug, Clone, PartialEq)]
pub enum EventBody<'a> {
    /// The first event of a file: `brain.Event:2`.
    FileVersion,
    /// A session (re)started at this step.
    SessionStart,
    /// Scalars by tag.
    Scalars(&'a [(String, f32)]),
}

/// One `Event` message.
pub fn event(wall_time: f64, step: i64, body: EventBody) -> Vec<u8> {
    let mut out = Vec::new();
    out.push(1 << 3 | 1); // wall_time: double
    out.extend_from_slice(&wall_time.to_le_bytes());
    varint(2 << 3, &mut out); // step: int64 varint (two's complement for negatives)
    varint(step as u64, &mut out);
    match body {
        EventBody::FileVersion => bytes_field(3, b"brain.Event:2", &mut out),
        EventBody::SessionStart => bytes_field(6, &[1 << 3, 1], &mut out),
        EventBody::Scalars(values) => {
            let mut summary = Vec::new();
            for (tag, v) in values {
                let mut value = Vec::new();
                bytes_field(1, tag.as_bytes(), &mut value);
                value.push(2 << 3 | 5); // simple_value: float
                value.extend_from_slice(&v.to_le_bytes());
                bytes_field(1, &value, &mut summary);
            }
            bytes_field(5, &summary, &mut out);
        }
    }
    out
}

/// What [`read_scalars`] found in one file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EventFile {
    pub file_version: Option<String>,
    /// Steps of the `SessionLog` START events.
    pub session_starts: Vec<i64>,
    /// (step, tag, value) of every scalar, in file order.
    pub scalars: Vec<(i64, String, f32)>,
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn varint(&mut self) -> anyhow::Result<u64> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = *self.bytes.get(self.at).context("a varint runs past the end")?;
            self.at += 1;
            v |= u64::from(b & 0x7f) << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        bail!("a varint longer than 10 bytes")
    }

    fn take(&mut self, n: usize) -> anyhow::Result<&'a [u8]> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).context("a field runs past the end")?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    /// The next field: its number and, for length-delimited ones, its bytes; fixed-size and
    /// varint values come back as their little-endian bytes.
    fn field(&mut self) -> anyhow::Result<(u64, Vec<u8>)> {
        let key = self.varint()?;
        let value = match key & 7 {
            0 => self.varint()?.to_le_bytes().to_vec(),
            1 => self.take(8)?.to_vec(),
            2 => {
                let n = self.varint()? as usize;
                self.take(n)?.to_vec()
            }
            5 => self.take(4)?.to_vec(),
            w => bail!("wire type {w} is not used by these messages"),
        };
        Ok((key >> 3, value))
    }

    fn done(&self) -> bool {
        self.at >= self.bytes.len()
    }
}

fn fields(bytes: &[u8]) -> anyhow::Result<Vec<(u64, Vec<u8>)>> {
    let mut r = Reader { bytes, at: 0 };
    let mut out = Vec::new();
    while !r.done() {
        out.push(r.field()?);
    }
    Ok(out)
}

/// Reads an event file back, checking every record's CRCs; errors name the file and the record.
pub fn read_scalars(path: &Path) -> anyhow::Result<EventFile> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let mut out = EventFile::default();
    let (mut at, mut n) = (0usize, 0usize);
    while at < bytes.len() {
        let ctx = || format!("{}: record {n} at byte {at}", path.display());
        let head = bytes.get(at..at + 12).with_context(|| format!("{}: cut short", ctx()))?;
        let len = u64::from_le_bytes(head[..8].try_into().expect("8 bytes")) as usize;
        anyhow::ensure!(masked_crc(&head[..8]).to_le_bytes() == head[8..12], "{}: bad length CRC", ctx());
        let data = bytes.get(at + 12..at + 12 + len).with_context(|| format!("{}: cut short", ctx()))?;
        let crc = bytes.get(at + 12 + len..at + 16 + len).with_context(|| format!("{}: cut short", ctx()))?;
        anyhow::ensure!(masked_crc(data).to_le_bytes() == crc, "{}: bad data CRC", ctx());
        let mut step = 0i64;
        for (field, value) in fields(data).with_context(ctx)? {
            match field {
                2 => step = u64::from_le_bytes(value[..8].try_into()?) as i64,
                3 => out.file_version = Some(String::from_utf8_lossy(&value).into_owned()),
                5 => {
                    for (_, v) in fields(&value).with_context(ctx)?.into_iter().filter(|(f, _)| *f == 1) {
                        let (mut tag, mut x) = (String::new(), f32::NAN);
                        for (f, b) in fields(&v).with_context(ctx)? {
                            match f {
                                1 => tag = String::from_utf8_lossy(&b).into_owned(),
                                2 => x = f32::from_le_bytes(b[..4].try_into()?),
                                _ => {}
                            }
                        }
                        out.scalars.push((step, tag, x));
                    }
                }
                6 => out.session_starts.push(step),
                _ => {}
            }
        }
        at += 16 + len;
        n += 1;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32c_matches_the_published_check_value() {
        // The CRC-32C of "123456789" (RFC 3720's check value).
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
        assert_eq!(crc32c(b""), 0);
    }

    #[test]
    fn an_event_of_scalars_reads_back_with_its_step_tags_and_values() {
        let values = vec![("charts/performance".to_string(), 0.5f32), ("losses/value_loss".to_string(), -2.25)];
        let mut bytes = record(&event(1.5, 7, EventBody::FileVersion));
        bytes.extend(record(&event(2.0, 300, EventBody::Scalars(&values))));
        bytes.extend(record(&event(3.0, 40, EventBody::SessionStart)));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("events.out.tfevents.test");
        std::fs::write(&path, &bytes).unwrap();
        let read = read_scalars(&path).unwrap();
        assert_eq!(read.file_version.as_deref(), Some("brain.Event:2"));
        assert_eq!(read.session_starts, vec![40]);
        assert_eq!(read.scalars, vec![(300, values[0].0.clone(), 0.5), (300, values[1].0.clone(), -2.25)]);
        // A flipped byte is caught by the CRC and named.
        let mut bad = bytes.clone();
        let last = bad.len() - 6;
        bad[last] ^= 1;
        std::fs::write(&path, &bad).unwrap();
        let err = format!("{:#}", read_scalars(&path).unwrap_err());
        assert!(err.contains("record 2") && err.contains("CRC"), "{err}");
    }
}
