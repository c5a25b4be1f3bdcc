//! A bit-packed binary mask (one bit per weight element, row-major, least
//! significant bit first): how each finished task's mask M_t is stored and
//! written to checkpoints (as u8 tensors).

/// A fixed-length bit vector.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BitMask {
    len: usize,
    bytes: Vec<u8>,
}

impl BitMask {
    /// All zeros.
    pub fn zeros(len: usize) -> Self {
        Self { len, bytes: vec![0; len.div_ceil(8)] }
    }

    /// Packs a slice of booleans.
    pub fn from_bools(bits: &[bool]) -> Self {
        let mut m = Self::zeros(bits.len());
        for (i, &b) in bits.iter().enumerate() {
            if b {
                m.set(i, true);
            }
        }
        m
    }

    /// Rebuilds a mask from its packed bytes; errors if the byte count does not fit `len` or padding bits are set.
    pub fn from_bytes(len: usize, bytes: Vec<u8>) -> anyhow::Result<Self> {
        anyhow::ensure!(
            bytes.len() == len.div_ceil(8),
            "a mask of {len} bits needs {} bytes, got {}",
            len.div_ceil(8),
            bytes.len()
        );
        if len % 8 != 0 {
            let last = bytes[bytes.len() - 1];
            anyhow::ensure!(last >> (len % 8) == 0, "padding bits of the mask are set");
        }
        Ok(Self { len, bytes })
    }

    /// The number of bits.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the mask has no bits at all.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The packed bytes.
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Bit `i`.
    pub fn get(&self, i: usize) -> bool {
        assert!(i < self.len, "bit {i} out of {}", self.len);
        self.bytes[i / 8] >> (i % 8) & 1 == 1
    }

    /// Sets bit `i`.
    pub fn set(&mut self, i: usize, value: bool) {
        assert!(i < self.len, "bit {i} out of {}", self.len);
        if value {
            self.bytes[i / 8] |= 1 << (i % 8);
        } else {
            self.bytes[i / 8] &= !(1 << (i % 8));
        }
    }

    /// The number of set bits.
    pub fn count_ones(&self) -> usize {
        self.bytes.iter().map(|b| b.count_ones() as usize).sum()
    }

    /// The number of bits set in both masks.
    pub fn overlap(&self, other: &BitMask) -> usize {
        assert_eq!(self.len, other.len);
        self.bytes.iter().zip(&other.bytes).map(|(a, b)| (a & b).count_ones() as usize).sum()
    }

    /// The mask as 0.0 / 1.0 values (for building W * M).
    pub fn to_f32(&self) -> Vec<f32> {
        (0..self.len).map(|i| if self.get(i) { 1.0 } else { 0.0 }).collect()
    }

    /// The mask as booleans.
    pub fn to_bools(&self) -> Vec<bool> {
        (0..self.len).map(|i| self.get(i)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_round_trips_and_counts() {
        let bits: Vec<bool> = (0..37).map(|i| i % 3 == 0 || i == 36).collect();
        let m = BitMask::from_bools(&bits);
        assert_eq!(m.as_bytes().len(), 5);
        assert_eq!(m.to_bools(), bits);
        assert_eq!(m.count_ones(), bits.iter().filter(|b| **b).count());
        let back = BitMask::from_bytes(37, m.as_bytes().to_vec()).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn overlap_counts_common_bits() {
        let a = BitMask::from_bools(&[true, true, false, true]);
        let b = BitMask::from_bools(&[true, false, false, true]);
        assert_eq!(a.overlap(&b), 2);
    }

    #[test]
    fn wrong_byte_count_or_padding_is_an_error() {
        assert!(BitMask::from_bytes(9, vec![0]).is_err());
        assert!(BitMask::from_bytes(4, vec![0b1_0000]).is_err());
    }
}
