//! The files quadcl ships under `scenes/` that programs name without a path:
//! the robots' descriptions and the run files whose `[env]` sets their gains
//! and pose. They are compiled into the library, so that a binary or a Python
//! wheel used away from this source tree (installed into another environment,
//! copied to a cluster) still loads them. A file present beside the sources is
//! read from there, so an edited description takes effect; the compiled copy
//! stands in only where it is absent.

use anyhow::Context;
use std::path::{Path, PathBuf};

/// (path from the crate's root, the file's text as built).
pub const SHIPPED_FILES: [(&str, &str); 5] = [
    ("scenes/a1.urdf", include_str!("../../scenes/a1.urdf")),
    ("scenes/aliengo.urdf", include_str!("../../scenes/aliengo.urdf")),
    ("scenes/anymal_c.urdf", include_str!("../../scenes/anymal_c.urdf")),
    ("scenes/aliengo.toml", include_str!("../../scenes/aliengo.toml")),
    ("scenes/anymal_c.toml", include_str!("../../scenes/anymal_c.toml")),
];

/// `relative` under the crate's root, where the sources were built.
pub fn crate_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// Whether `relative` (a path from the crate's root, `scenes/a1.urdf`) is a shipped file.
pub fn is_shipped(relative: &Path) -> bool {
    SHIPPED_FILES.iter().any(|(p, _)| Path::new(p) == relative)
}

/// The text of the crate file `relative`: from disk beside the sources, or the compiled
/// copy of a shipped file when the sources are not there. Errors name the file.
pub fn read_crate_file(relative: &str) -> anyhow::Result<String> {
    read_under(Path::new(env!("CARGO_MANIFEST_DIR")), relative)
}

fn read_under(root: &Path, relative: &str) -> anyhow::Result<String> {
    let path = root.join(relative);
    if path.exists() {
        return std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()));
    }
    match SHIPPED_FILES.iter().find(|(p, _)| *p == relative) {
        Some((_, text)) => Ok((*text).to_string()),
        None => anyhow::bail!("{}: no such file", path.display()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shipped_file_is_its_compiled_copy_where_the_sources_are_absent() {
        let elsewhere = tempfile::tempdir().unwrap();
        for (relative, _) in SHIPPED_FILES {
            let on_disk = read_crate_file(relative).unwrap();
            assert_eq!(read_under(elsewhere.path(), relative).unwrap(), on_disk, "{relative}");
        }
        let err = format!("{:#}", read_under(elsewhere.path(), "scenes/nothing.urdf").unwrap_err());
        assert!(err.contains("scenes/nothing.urdf") && err.contains("no such file"), "{err}");
    }

    #[test]
    fn a_file_beside_the_sources_is_read_from_disk_first() {
        let root = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(root.path().join("scenes")).unwrap();
        std::fs::write(root.path().join("scenes/a1.urdf"), "edited").unwrap();
        assert_eq!(read_under(root.path(), "scenes/a1.urdf").unwrap(), "edited");
    }
}
