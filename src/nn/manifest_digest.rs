//! The manifest bound to the weights: `model.safetensors` carries, in its
//! safetensors metadata, the sha256 of the manifest's content (everything but
//! the tensor-file hashes, which cannot include themselves, and the provenance,
//! stamped after the policy is written). A manifest edited
//! after it was written (task names, sizes, mask settings, the config) no
//! longer matches, and loading it is an error rather than a silently
//! different policy. Files written before the digest existed carry none and
//! load unchecked.

use anyhow::Context;
use std::collections::HashMap;
use std::path::Path;

/// The metadata key of the digest in `model.safetensors`.
pub(super) const METADATA_KEY: &str = "quadcl.manifest_sha256";

/// The digest of a manifest given as JSON: its canonical text without `files` and without
/// `provenance` (which build and machine wrote it: the same policy made elsewhere has the
/// same digest and byte-identical tensor files).
pub(super) fn manifest_digest(manifest: &serde_json::Value) -> String {
    let mut body = manifest.clone();
    if let Some(map) = body.as_object_mut() {
        map.remove("files");
        map.remove(super::checkpoint::PROVENANCE_KEY);
    }
    crate::util::sha256_hex(body.to_string().as_bytes())
}

/// The safetensors metadata that records `digest`.
pub(super) fn metadata(digest: String) -> HashMap<String, String> {
    HashMap::from([(METADATA_KEY.to_string(), digest)])
}

/// Errors when `model_bytes` records a digest other than `manifest`'s.
pub(super) fn check(model_bytes: &[u8], manifest: &serde_json::Value, manifest_path: &Path) -> anyhow::Result<()> {
    let (_, header) = safetensors::SafeTensors::read_metadata(model_bytes)
        .map_err(|e| anyhow::anyhow!("{e:?}"))
        .with_context(|| format!("{}: reading the tensor header", manifest_path.display()))?;
    let Some(want) = header.metadata().as_ref().and_then(|m| m.get(METADATA_KEY)) else { return Ok(()) };
    let got = manifest_digest(manifest);
    anyhow::ensure!(
        &got == want,
        "{}: the manifest was changed after it was written (its content digest {got} is not the {want} recorded in \
         the model file): edited task names, sizes or settings would silently change the policy",
        manifest_path.display()
    );
    Ok(())
}
