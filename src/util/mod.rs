//! The base layer every other module may use (it imports none of them):
//! atomic writes ([`write_atomic`], [`replace_dir`]), content hashes
//! ([`sha256_hex`]), the derivation of every random stream ([`derive_seed`]),
//! a stream's exact position for checkpoints ([`RngState`]), where a result
//! came from ([`Provenance`]), one process at a time in a folder ([`FolderLock`]),
//! and user-given text made safe to write and to quote ([`text`]).

mod fs;
mod lock;
mod provenance;
mod rng_state;
mod seed;
pub mod text;

pub use fs::{recover_replaced_dir, replace_dir, write_atomic};
pub use lock::{hostname, process_exists, FolderLock, Holder};
pub use provenance::Provenance;
pub use rng_state::{RngState, RNG_STATE_BYTES};
pub use seed::{derive_seed, Stream};

use sha2::{Digest, Sha256};

/// Hex SHA-256 of `bytes`, used for the content hashes in manifests.
pub fn sha256_hex(bytes: &[u8]) -> String {
    let digest = Sha256::digest(bytes);
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_hex_matches_known_digest() {
        assert_eq!(sha256_hex(b"abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }
}
