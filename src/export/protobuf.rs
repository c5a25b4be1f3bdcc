//! The protocol-buffer wire format, writing only: just what an ONNX model
//! needs (varints, 64-bit integers, floats, strings, bytes, packed repeated
//! fields and nested messages). A [`Message`] collects its fields in the order
//! they are added; a reader accepts any order, so nothing is sorted.
//!
//! Wire types: 0 varint, 2 length-delimited, 5 fixed 32-bit.

/// One message being written: its encoded fields.
#[derive(Debug, Default, Clone)]
pub struct Message {
    bytes: Vec<u8>,
}

/// The varint encoding of `value` appended to `out` (7 bits a byte, low first).
fn put_varint(out: &mut Vec<u8>, mut value: u64) {
    while value >= 0x80 {
        out.push((value as u8 & 0x7f) | 0x80);
        value >>= 7;
    }
    out.push(value as u8);
}

impl Message {
    pub fn new() -> Self {
        Self::default()
    }

    fn key(&mut self, field: u32, wire_type: u8) {
        put_varint(&mut self.bytes, (u64::from(field) << 3) | u64::from(wire_type));
    }

    /// An `int64` or `int32` field (negative values as ten-byte varints, as protobuf does).
    pub fn int(mut self, field: u32, value: i64) -> Self {
        self.key(field, 0);
        put_varint(&mut self.bytes, value as u64);
        self
    }

    /// A `float` field.
    pub fn float(mut self, field: u32, value: f32) -> Self {
        self.key(field, 5);
        self.bytes.extend_from_slice(&value.to_le_bytes());
        self
    }

    /// A `bytes` field.
    pub fn bytes(mut self, field: u32, value: &[u8]) -> Self {
        self.key(field, 2);
        put_varint(&mut self.bytes, value.len() as u64);
        self.bytes.extend_from_slice(value);
        self
    }

    /// A `string` field.
    pub fn string(self, field: u32, value: &str) -> Self {
        self.bytes(field, value.as_bytes())
    }

    /// A nested message field (one element of a repeated message field per call).
    pub fn message(self, field: u32, value: &Message) -> Self {
        self.bytes(field, &value.bytes)
    }

    /// A packed repeated `int64` field.
    pub fn packed_ints(self, field: u32, values: &[i64]) -> Self {
        let mut packed = Vec::with_capacity(values.len());
        for &v in values {
            put_varint(&mut packed, v as u64);
        }
        self.bytes(field, &packed)
    }

    /// The encoded message.
    pub fn encode(&self) -> &[u8] {
        &self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varints_follow_the_protobuf_examples() {
        // The protobuf encoding guide's examples: 1 -> 01, 150 -> 96 01, field 1 = 150 -> 08 96 01.
        let mut out = Vec::new();
        put_varint(&mut out, 1);
        put_varint(&mut out, 150);
        assert_eq!(out, [0x01, 0x96, 0x01]);
        assert_eq!(Message::new().int(1, 150).encode(), [0x08, 0x96, 0x01]);
        // A negative int64 is ten bytes.
        assert_eq!(Message::new().int(1, -1).encode().len(), 11);
    }

    #[test]
    fn strings_and_nested_messages_are_length_delimited() {
        // The guide's example: field 2 = "testing" -> 12 07 74 65 73 74 69 6e 67.
        let m = Message::new().string(2, "testing");
        assert_eq!(m.encode(), [0x12, 0x07, b't', b'e', b's', b't', b'i', b'n', b'g']);
        // Field 3 holding that message: 1a 09 + its bytes.
        let outer = Message::new().message(3, &m);
        assert_eq!(&outer.encode()[..2], [0x1a, 0x09]);
        assert_eq!(&outer.encode()[2..], m.encode());
    }

    #[test]
    fn packed_ints_and_floats_have_their_wire_types() {
        // The guide's packed example: field 4 = [3, 270, 86942] -> 22 06 03 8e 02 9e a7 05.
        let m = Message::new().packed_ints(4, &[3, 270, 86942]);
        assert_eq!(m.encode(), [0x22, 0x06, 0x03, 0x8e, 0x02, 0x9e, 0xa7, 0x05]);
        let f = Message::new().float(2, 1.0);
        assert_eq!(f.encode(), [0x15, 0x00, 0x00, 0x80, 0x3f]);
    }
}
