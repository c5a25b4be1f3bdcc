//! The exact position of a ChaCha random stream (seed, stream, word offset),
//! so a checkpoint can hand a resumed run the very next number the
//! interrupted one would have drawn.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Where a [`ChaCha8Rng`] stands: 32 bytes of seed, the stream id and the
/// offset in 32-bit words from the stream's start (buffered words included).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RngState {
    pub seed: [u8; 32],
    pub stream: u64,
    pub word_pos: u128,
}

/// Bytes of one [`RngState`] as [`RngState::to_bytes`] writes it.
pub const RNG_STATE_BYTES: usize = 32 + 8 + 16;

impl RngState {
    /// The state of `rng`.
    pub fn of(rng: &ChaCha8Rng) -> Self {
        Self { seed: rng.get_seed(), stream: rng.get_stream(), word_pos: rng.get_word_pos() }
    }

    /// A generator at exactly this state.
    pub fn rng(&self) -> ChaCha8Rng {
        let mut rng = ChaCha8Rng::from_seed(self.seed);
        rng.set_stream(self.stream);
        rng.set_word_pos(self.word_pos);
        rng
    }

    /// Seed, stream and word offset, little-endian.
    pub fn to_bytes(&self) -> [u8; RNG_STATE_BYTES] {
        let mut out = [0u8; RNG_STATE_BYTES];
        out[..32].copy_from_slice(&self.seed);
        out[32..40].copy_from_slice(&self.stream.to_le_bytes());
        out[40..].copy_from_slice(&self.word_pos.to_le_bytes());
        out
    }

    /// Reads [`Self::to_bytes`]; None unless `bytes` has exactly [`RNG_STATE_BYTES`].
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        if bytes.len() != RNG_STATE_BYTES {
            return None;
        }
        let mut seed = [0u8; 32];
        seed.copy_from_slice(&bytes[..32]);
        let stream = u64::from_le_bytes(bytes[32..40].try_into().ok()?);
        let word_pos = u128::from_le_bytes(bytes[40..].try_into().ok()?);
        Some(Self { seed, stream, word_pos })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn a_restored_stream_draws_what_the_original_would_have_drawn_next() {
        let mut rng = ChaCha8Rng::seed_from_u64(42);
        // An odd number of 32-bit words, so the position falls inside a buffered block.
        for _ in 0..37 {
            let _: u32 = rng.gen();
        }
        let _: f64 = rng.gen();
        let saved = RngState::from_bytes(&RngState::of(&rng).to_bytes()).unwrap();
        let mut restored = saved.rng();
        let next: Vec<u32> = (0..100).map(|_| rng.gen()).collect();
        let again: Vec<u32> = (0..100).map(|_| restored.gen()).collect();
        assert_eq!(next, again);
        assert!(RngState::from_bytes(&[0u8; 10]).is_none());
    }
}
