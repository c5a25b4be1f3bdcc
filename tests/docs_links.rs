//! The documentation names only things that exist (issue 36): in `README.md`
//! and every `docs/*.md`,
//! - every relative markdown link resolves (from the page's folder), and its
//!   `#anchor`, when it points into a markdown page, names a heading there;
//! - every path token that starts with a checked folder (`scenes/`,
//!   `scripts/`, `policies/`, `docs/`, `examples/`, `src/`, `tests/`,
//!   `snapshots/`) exists, relative to the repository root;
//! - every command line in a code block that starts with `quadcl ` or
//!   `cargo run --release -- ` names a real subcommand, and every `--flag` on
//!   it appears in that subcommand's `quadcl ... --help`.
//!
//! Skipped by rule: paths with a glob or brace (`*`, `?`, `{`), and paths with
//! a placeholder word in capitals from [`PLACEHOLDERS`] (`src/cl/NAME.rs`,
//! `step-NN-TASK`). A new placeholder word fails the test as a missing path
//! until it is added there, so nothing is skipped by accident.
//!
//! Every failure names the file, the line and the bad path, anchor or flag.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Folders whose paths a page may name and must exist.
const CHECKED_PREFIXES: [&str; 8] =
    ["scenes/", "scripts/", "policies/", "docs/", "examples/", "src/", "tests/", "snapshots/"];

/// Capitalised words that stand for a value in a path (`src/cl/NAME.rs`).
const PLACEHOLDERS: [&str; 17] = [
    "DIR", "RUN", "NAME", "TASK", "NN", "LAYER", "NET", "FILE", "OUT", "BIN", "CONFIG", "URL", "HOST", "PKG", "I", "N",
    "T",
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `README.md` and every `docs/*.md`, as paths relative to the root.
fn doc_files() -> Vec<PathBuf> {
    let mut files = vec![PathBuf::from("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .map(|p| p.strip_prefix(root()).unwrap().to_path_buf())
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// One line of a page, with whether it is inside a fenced code block.
struct Line<'a> {
    number: usize,
    text: &'a str,
    in_code: bool,
}

fn lines(text: &str) -> Vec<Line<'_>> {
    let mut in_code = false;
    let mut out = Vec::new();
    for (i, text) in text.lines().enumerate() {
        if text.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        out.push(Line { number: i + 1, text, in_code });
    }
    out
}

/// The targets of `[text](target)` and `![alt](target)` on a line.
fn link_targets(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        let Some(end) = after.find(')') else { break };
        // A title (`(path "title")`) is not part of the target.
        let target = after[..end].split_whitespace().next().unwrap_or("").to_string();
        out.push(target);
        rest = &after[end..];
    }
    out
}

fn is_external(target: &str) -> bool {
    target.contains("://") || target.starts_with("mailto:")
}

/// GitHub's anchor of a heading: lower case, spaces to hyphens, other punctuation dropped.
fn anchor_of(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of every heading of a markdown page.
fn anchors(text: &str) -> Vec<String> {
    lines(text)
        .iter()
        .filter(|l| !l.in_code && l.text.starts_with('#'))
        .map(|l| anchor_of(l.text.trim_start_matches('#')))
        .collect()
}

/// The tokens of a line that start with a checked folder, trailing punctuation removed.
fn path_tokens(line: &str) -> Vec<String> {
    let separators = |c: char| c.is_whitespace() || "`()[]<>\"',;|=".contains(c);
    line.split(separators)
        .map(|t| t.trim_end_matches(['.', ':', '!', '?']))
        .map(|t| t.strip_prefix("./").unwrap_or(t))
        .map(|t| t.split('#').next().unwrap_or(t))
        .filter(|t| CHECKED_PREFIXES.iter().any(|p| t.starts_with(p)))
        .map(str::to_string)
        .collect()
}

/// Whether a path stands for many files or for a value (see the module header).
fn is_pattern(path: &str) -> bool {
    path.contains(['*', '?', '{', '}'])
        || path.split(|c: char| !c.is_ascii_alphanumeric()).any(|word| PLACEHOLDERS.contains(&word))
}

/// The problems of one page's links and paths: `file:line: what`.
fn path_problems(file: &Path, text: &str) -> Vec<String> {
    let folder = root().join(file.parent().unwrap_or(Path::new("")));
    let mut problems = Vec::new();
    for line in lines(text) {
        let at = format!("{}:{}", file.display(), line.number);
        for target in link_targets(line.text) {
            if target.is_empty() || is_external(&target) {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() { root().join(file) } else { folder.join(path) };
            if !resolved.exists() {
                problems.push(format!("{at}: the link target {target} does not exist"));
                continue;
            }
            if let Some(anchor) = anchor {
                if resolved.extension().is_some_and(|e| e == "md") {
                    let page = std::fs::read_to_string(&resolved).unwrap();
                    if !anchors(&page).iter().any(|a| a == anchor) {
                        problems.push(format!("{at}: the link {target} names no heading of {}", resolved.display()));
                    }
                }
            }
        }
        for path in path_tokens(line.text) {
            if !is_pattern(&path) && !root().join(&path).exists() {
                problems.push(format!("{at}: the path {path} does not exist"));
            }
        }
    }
    problems
}

/// The command lines of a page's code blocks (continuations joined), with their line numbers.
fn command_lines(text: &str) -> Vec<(usize, String)> {
    let mut out: Vec<(usize, String)> = Vec::new();
    let mut continuing = false;
    for line in lines(text).into_iter().filter(|l| l.in_code) {
        let t = line.text.trim();
        if continuing {
            let last = out.last_mut().unwrap();
            last.1.push(' ');
            last.1.push_str(t.trim_end_matches('\\'));
        } else {
            let t = t.strip_prefix("$ ").unwrap_or(t);
            let Some(args) = t.strip_prefix("quadcl ").or_else(|| t.strip_prefix("cargo run --release -- ")) else {
                continue;
            };
            out.push((line.number, args.trim_end_matches('\\').to_string()));
        }
        continuing = t.ends_with('\\');
    }
    // A shell comment ends the command.
    for (_, args) in &mut out {
        if let Some(at) = args.find(" #") {
            args.truncate(at);
        }
    }
    out
}

/// The subcommand names of a `--help` text's `Commands:` section.
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| l.trim() != "Commands:")
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

/// Whether `help` lists `flag` (`--json`) as an option (not as the prefix of a longer one).
fn lists_flag(help: &str, flag: &str) -> bool {
    help.match_indices(flag)
        .any(|(at, _)| !help[at + flag.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-'))
}

/// The problems of one command line (its arguments after `quadcl`): an unknown subcommand, a
/// `--help` that fails, or a flag its subcommand does not have. `help` runs `quadcl ARGS --help`.
fn command_problems(args: &str, help: &mut impl FnMut(&[String]) -> Result<String, String>) -> Vec<String> {
    let words: Vec<&str> = args.split_whitespace().collect();
    let mut path: Vec<String> = Vec::new();
    let mut text = match help(&path) {
        Ok(t) => t,
        Err(e) => return vec![format!("`quadcl --help` failed: {e}")],
    };
    for word in &words {
        let commands = subcommands(&text);
        if commands.is_empty() {
            break;
        }
        if !commands.iter().any(|c| c == word) {
            if path.is_empty() && !word.starts_with('-') {
                return vec![format!("`{word}` is not a subcommand of quadcl")];
            }
            break;
        }
        path.push(word.to_string());
        text = match help(&path) {
            Ok(t) => t,
            Err(e) => return vec![format!("`quadcl {} --help` failed: {e}", path.join(" "))],
        };
    }
    let mut problems = Vec::new();
    let mut rest = args;
    while let Some(at) = rest.find("--") {
        let flag: String = rest[at..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
        rest = &rest[at + flag.len().max(2)..];
        if flag.len() > 2 && !lists_flag(&text, &flag) {
            problems.push(format!("`quadcl {}` has no flag {flag}", path.join(" ")));
        }
    }
    problems
}

/// `quadcl ARGS --help` of the binary under test, each subcommand run once.
fn real_help() -> impl FnMut(&[String]) -> Result<String, String> {
    let mut cache: HashMap<Vec<String>, Result<String, String>> = HashMap::new();
    move |path: &[String]| {
        cache
            .entry(path.to_vec())
            .or_insert_with(|| {
                let out = Command::new(env!("CARGO_BIN_EXE_quadcl"))
                    .args(path)
                    .arg("--help")
                    .output()
                    .map_err(|e| e.to_string())?;
                if out.status.success() {
                    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
                } else {
                    Err(String::from_utf8_lossy(&out.stderr).trim().to_string())
                }
            })
            .clone()
    }
}

fn read(file: &Path) -> String {
    std::fs::read_to_string(root().join(file)).unwrap_or_else(|e| panic!("{}: {e}", file.display()))
}

#[test]
fn every_path_named_in_the_docs_exists() {
    let problems: Vec<String> = doc_files().iter().flat_map(|f| path_problems(f, &read(f))).collect();
    assert!(problems.is_empty(), "{} bad links or paths:\n{}", problems.len(), problems.join("\n"));
}

#[test]
fn every_command_line_in_the_docs_names_real_subcommands_and_flags() {
    let mut help = real_help();
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in doc_files() {
        for (line, args) in command_lines(&read(&file)) {
            checked += 1;
            for p in command_problems(&args, &mut help) {
                problems.push(format!("{}:{line}: {p}", file.display()));
            }
        }
    }
    assert!(checked >= 10, "only {checked} command lines found: is the parser broken?");
    assert!(problems.is_empty(), "{} bad command lines:\n{}", problems.len(), problems.join("\n"));
}

#[test]
fn the_readme_starts_with_the_two_commands() {
    let readme = read(Path::new("README.md"));
    let first_code = first_code_block(&readme);
    assert!(first_code.contains("cargo run --release"), "README.md's first code block: {first_code}");
    assert!(first_code.contains("cargo test"), "README.md's first code block: {first_code}");
}

/// The first fenced code block of a page.
fn first_code_block(text: &str) -> String {
    lines(text)
        .iter()
        .skip_while(|l| !l.in_code)
        .take_while(|l| l.in_code)
        .map(|l| l.text)
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_made_up_flag_or_subcommand_is_caught() {
    let page = "```sh\nquadcl run --config scenes/smoke.toml --out runs/x --made-up-flag\n\
                quadcl frobnicate --json\ncargo run --release -- sweep plan \\\n    --out runs/s --jobs 2\n```\n";
    let mut help = real_help();
    let found: Vec<(usize, Vec<String>)> =
        command_lines(page).into_iter().map(|(n, args)| (n, command_problems(&args, &mut help))).collect();
    assert_eq!(found.len(), 3, "{found:?}");
    assert_eq!(found[0], (2, vec!["`quadcl run` has no flag --made-up-flag".to_string()]));
    assert_eq!(found[1], (3, vec!["`frobnicate` is not a subcommand of quadcl".to_string()]));
    // The continuation line's flag is checked against `sweep plan`, which has --out but not --jobs.
    assert_eq!(found[2], (4, vec!["`quadcl sweep plan` has no flag --jobs".to_string()]));
    // A real line with bracketed options and a trailing comment passes.
    let ok = command_problems("eval --policy DIR --task T [--episodes N] --json", &mut help);
    assert!(ok.is_empty(), "{ok:?}");
    // A flag that is only the prefix of a real one is not taken for it.
    let prefix = command_problems("view --policy DIR --con", &mut help);
    assert_eq!(prefix, vec!["`quadcl view` has no flag --con".to_string()]);
}

#[test]
fn a_missing_path_a_broken_link_and_a_bad_anchor_are_caught() {
    let page = "See `scenes/no-such-scene.toml` and [the method](method.md#no-such-heading).\n\
                [gone](no-such-page.md) `src/cl/NAME.rs` `scenes/fig11-*.toml` `scenes/smoke.toml`.\n\
                [fine](method.md#the-two-regimes-of-the-shipped-runs) [web](https://rerun.io)\n";
    let problems = path_problems(Path::new("docs/example.md"), page);
    assert_eq!(problems.len(), 3, "{problems:#?}");
    assert!(problems[0].starts_with("docs/example.md:1: the link method.md#no-such-heading names no heading"));
    assert_eq!(problems[1], "docs/example.md:1: the path scenes/no-such-scene.toml does not exist");
    assert_eq!(problems[2], "docs/example.md:2: the link target no-such-page.md does not exist");
}

#[test]
fn headings_become_githubs_anchors() {
    assert_eq!(anchor_of(" One task: `quadcl train`"), "one-task-quadcl-train");
    assert_eq!(anchor_of("Recall, repeats, transfer and fine-tuning"), "recall-repeats-transfer-and-fine-tuning");
    assert_eq!(anchor_of("Files (`quadcl record`)"), "files-quadcl-record");
}
