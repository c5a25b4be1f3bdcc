//! The crate's layering, as `src/lib.rs`'s module table states it, holds in
//! the code: no module refers to a layer its row of the table does not list.
//! The table is read from `src/lib.rs` itself, so the documentation and this
//! check cannot drift apart.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Per module of the table: the layers it may import.
fn allowed_imports(lib_rs: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut table = BTreeMap::new();
    for line in lib_rs.lines().filter_map(|l| l.strip_prefix("//! |")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let first = cells.first().copied().unwrap_or_default();
        let Some(module) =
            first.trim_start_matches('[').trim_end_matches(']').strip_prefix('`').and_then(|c| c.strip_suffix('`'))
        else {
            continue;
        };
        let may_import = cells.get(2).copied().unwrap_or_default();
        let names: BTreeSet<String> = may_import.split('`').skip(1).step_by(2).map(str::to_string).collect();
        table.insert(module.to_string(), names);
    }
    table
}

/// The `.rs` files at or under `path` (a module folder may hold other files: src/plot's font).
fn rust_files(path: &Path) -> Vec<PathBuf> {
    if path.is_file() {
        return if path.extension().is_some_and(|e| e == "rs") { vec![path.to_path_buf()] } else { Vec::new() };
    }
    let mut files = Vec::new();
    for entry in std::fs::read_dir(path).unwrap() {
        files.extend(rust_files(&entry.unwrap().path()));
    }
    files.sort();
    files
}

/// Every top-level module named as `crate::NAME` in the code of `text` (comments skipped).
fn referenced_layers(text: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for line in text.lines().filter(|l| !l.trim_start().starts_with("//")) {
        for (i, _) in line.match_indices("crate::") {
            let rest = &line[i + "crate::".len()..];
            let name: String = rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            if modules.contains(&name) {
                found.insert(name);
            }
        }
    }
    found
}

#[test]
fn no_module_imports_a_layer_the_lib_table_forbids() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib_rs = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let table = allowed_imports(&lib_rs);
    let modules: BTreeSet<String> = table.keys().cloned().collect();
    for expected in ["config", "sim", "nn", "rl", "cl", "engine", "util"] {
        assert!(modules.contains(expected), "src/lib.rs's table has no row for `{expected}`: {modules:?}");
    }
    let mut violations = Vec::new();
    for (module, allowed) in &table {
        let dir = src.join(module);
        let path = if dir.is_dir() { dir } else { src.join(format!("{module}.rs")) };
        assert!(path.exists(), "the table names `{module}`, but neither {} nor its folder exists", path.display());
        for file in rust_files(&path) {
            let text = std::fs::read_to_string(&file).unwrap();
            for layer in referenced_layers(&text, &modules) {
                if &layer != module && !allowed.contains(&layer) {
                    violations.push(format!("{} uses `{layer}`, which `{module}` may not import", file.display()));
                }
            }
        }
    }
    assert!(violations.is_empty(), "layering violations (see src/lib.rs):\n{}", violations.join("\n"));
}

#[test]
fn the_check_sees_a_forbidden_import() {
    let lib = "//! | [`sim`] | the robot | `config`, `util` |\n//! | [`nn`] | networks | `config` |\n";
    let table = allowed_imports(lib);
    assert_eq!(table["sim"], ["config", "util"].iter().map(|s| s.to_string()).collect());
    let modules: BTreeSet<String> = table.keys().cloned().collect();
    let code = "use crate::nn::MaskedMlp;\n// crate::sim in a comment does not count\nfn f() { crate::sim::x(); }\n";
    let found = referenced_layers(code, &modules);
    assert_eq!(found, ["nn", "sim"].iter().map(|s| s.to_string()).collect());
    assert!(!table["sim"].contains("nn"), "sim importing nn is a violation the main test reports");
}
