#!/usr/bin/env bash
# The patch quadcl carries on rapier3d (issue 33), as a diff against the crates.io source.
#
#   scripts/rapier_patch.sh            print the diff (vendor/rapier3d against rapier3d-VERSION from crates.io)
#   scripts/rapier_patch.sh --write    write it to vendor/rapier3d/PATCH.diff
#   scripts/rapier_patch.sh --check    fail unless vendor/rapier3d/PATCH.diff is that diff
#
# The pristine source comes from cargo itself: a throwaway package that depends on exactly
# rapier3d VERSION (the version in vendor/rapier3d/Cargo.toml) runs `cargo fetch`, and the
# downloaded .crate file (a tar.gz, checksummed by cargo against the registry index) is unpacked
# in a temporary folder. Offline, a .crate already in cargo's cache is used. Files that exist
# only in the published package's metadata (.cargo_vcs_info.json, .cargo-ok) are left out.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-}
vendor=vendor/rapier3d
version=$(sed -n 's/^version = "\(.*\)"$/\1/p' "$vendor/Cargo.toml" | head -n 1)
[ -n "$version" ] || { echo "$vendor/Cargo.toml: no version line" >&2; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/fetch/src"
cat > "$work/fetch/Cargo.toml" <<EOF
[package]
name = "rapier-patch-fetch"
version = "0.0.0"
edition = "2021"

[dependencies]
rapier3d = "=$version"
EOF
echo 'fn main() {}' > "$work/fetch/src/main.rs"
(cd "$work/fetch" && cargo fetch --quiet 2>/dev/null) || (cd "$work/fetch" && cargo fetch --offline --quiet)
crate=$(ls "${CARGO_HOME:-$HOME/.cargo}"/registry/cache/*/rapier3d-"$version".crate 2>/dev/null | head -n 1)
[ -n "$crate" ] || { echo "rapier3d-$version.crate not found in cargo's cache after cargo fetch" >&2; exit 1; }
mkdir -p "$work/pristine"
tar -xzf "$crate" -C "$work/pristine"

# Relative paths, so the diff applies with `patch -p1` inside a pristine copy.
diff_out() {
  (cd "$work/pristine" && diff -ruN -x .cargo_vcs_info.json -x .cargo-ok -x PATCH.md -x PATCH.diff \
    "rapier3d-$version" "$OLDPWD/$vendor" | sed -e "s|^--- rapier3d-$version/|--- a/|" \
      -e "s|^+++ $OLDPWD/$vendor/|+++ b/|" -e "s|^diff -ruN .*rapier3d-$version/\(.*\) .*|diff -ruN a/\1 b/\1|" \
      -e "/^\(---\|+++\) /s/$(printf '\t').*//") || true
}

case "$mode" in
  "") diff_out ;;
  --write)
    diff_out > "$vendor/PATCH.diff.tmp"
    mv "$vendor/PATCH.diff.tmp" "$vendor/PATCH.diff"
    echo "wrote $vendor/PATCH.diff ($(grep -c '^diff ' "$vendor/PATCH.diff") files, $(wc -l < "$vendor/PATCH.diff") lines)"
    ;;
  --check)
    if diff -q <(diff_out) "$vendor/PATCH.diff" > /dev/null; then
      echo "$vendor/PATCH.diff is the diff against rapier3d $version ($(grep -c '^diff ' "$vendor/PATCH.diff") files)"
    else
      echo "$vendor/PATCH.diff is stale: run scripts/rapier_patch.sh --write" >&2
      exit 1
    fi
    ;;
  *) echo "usage: scripts/rapier_patch.sh [--write | --check]" >&2; exit 2 ;;
esac
