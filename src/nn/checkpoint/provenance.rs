//! A policy's provenance (issue 32): `manifest.json`'s `provenance` key says which
//! build, run file and machine wrote it (`util::Provenance`). It is stamped into a
//! written manifest afterwards and kept out of the manifest's content digest, so
//! the tensor files of a policy are the same whoever made it; a manifest written
//! before provenance existed simply has none.

use super::MANIFEST_FILE;
use crate::util::{write_atomic, Provenance};
use anyhow::Context;
use std::path::Path;

/// The manifest key that holds the provenance.
pub const PROVENANCE_KEY: &str = "provenance";

/// Adds (or replaces) the provenance of the policy directory `dir`'s manifest, atomically.
pub fn write_provenance(dir: &Path, provenance: &Provenance) -> anyhow::Result<()> {
    let path = dir.join(MANIFEST_FILE);
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut manifest: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not a valid manifest", path.display()))?;
    let map = manifest.as_object_mut().with_context(|| format!("{}: not a JSON object", path.display()))?;
    map.insert(PROVENANCE_KEY.to_string(), serde_json::to_value(provenance)?);
    write_atomic(&path, serde_json::to_string_pretty(&manifest)?.as_bytes())
}

/// The provenance recorded in the policy directory `dir`, if its manifest has one.
pub fn read_provenance(dir: &Path) -> anyhow::Result<Option<Provenance>> {
    let path = dir.join(MANIFEST_FILE);
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let manifest: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not a valid manifest", path.display()))?;
    match manifest.get(PROVENANCE_KEY) {
        None => Ok(None),
        Some(v) => Ok(Some(
            serde_json::from_value(v.clone())
                .with_context(|| format!("{}: key {PROVENANCE_KEY}: not a provenance record", path.display()))?,
        )),
    }
}
