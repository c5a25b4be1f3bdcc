//! User-given text as it may appear in what quadcl writes and says:
//!
//! - [`one_line`]: control characters (a line break, a tab, an escape) shown as escapes, so
//!   that a value written into a comment, a script, a log line or a table cell cannot start
//!   a new line there (and with it a new key, directive or row);
//! - [`clip`]: a value quoted in a message at most [`QUOTE_MAX`] characters, with its length
//!   when cut;
//! - [`error_text`]: an error's chain of causes for the terminal, each line at most 400
//!   characters and each cause at most a thousand, and a context that only repeats its
//!   cause's words said once.

/// The most characters of a value a message quotes.
pub const QUOTE_MAX: usize = 200;

/// The most characters one line of an error's cause keeps in [`error_text`] (quadcl's own
/// sentences fit; a value echoed by a parser does not).
const LINE_MAX: usize = 400;

/// The most characters one cause of an error takes in [`error_text`].
const CAUSE_MAX: usize = 1000;

/// `text` with every control character escaped (`\n`, `\t`, `\u{1b}`); other characters as
/// they are.
pub fn one_line(text: &str) -> String {
    if !text.chars().any(char::is_control) {
        return text.to_string();
    }
    text.chars().map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() }).collect()
}

/// `text` on one line ([`one_line`]) and at most [`QUOTE_MAX`] characters: a longer one is cut
/// and says how long it was (`aaaa… (5242880 characters)`).
pub fn clip(text: &str) -> String {
    clip_to(&one_line(text), QUOTE_MAX)
}

fn clip_to(text: &str, max: usize) -> String {
    let count = text.chars().count();
    if count <= max {
        return text.to_string();
    }
    let head: String = text.chars().take(max).collect();
    format!("{head}… ({count} characters)")
}

/// `err` and its causes as one line of text (`context: cause: root cause`): a context whose
/// text its cause already says (`writing F` above `writing F: no space`) is left out, and
/// each part is cut at a thousand characters with its length, so no value given to quadcl,
/// however long, is echoed whole.
pub fn error_text(err: &anyhow::Error) -> String {
    let parts: Vec<String> = err.chain().map(|e| e.to_string()).collect();
    let mut kept: Vec<String> = Vec::new();
    for (i, part) in parts.iter().enumerate() {
        if parts.get(i + 1).is_some_and(|next| next.contains(part.as_str())) {
            continue;
        }
        if kept.last().is_some_and(|last| last.contains(part.as_str())) {
            continue;
        }
        kept.push(clip_lines(part));
    }
    kept.join(": ")
}

/// Each line of `text` cut at [`LINE_MAX`] characters and the whole at [`CAUSE_MAX`].
fn clip_lines(text: &str) -> String {
    let lines: Vec<String> = text.lines().map(|l| clip_to(l, LINE_MAX)).collect();
    clip_to(&lines.join("\n"), CAUSE_MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_break_in_a_value_cannot_start_a_new_line() {
        let value = "a.urdf\nrun = { keep_last_checkpoint_only = true }";
        assert_eq!(one_line(value), "a.urdf\\nrun = { keep_last_checkpoint_only = true }");
        assert_eq!(one_line("tab\there \u{1b}[31m"), "tab\\there \\u{1b}[31m");
        assert_eq!(one_line("crash:FL é"), "crash:FL é");
    }

    #[test]
    fn a_long_value_is_quoted_clipped_with_its_length() {
        let long = "x".repeat(5 << 20);
        let quoted = clip(&long);
        assert!(quoted.chars().count() < QUOTE_MAX + 40, "{}", quoted.len());
        assert!(quoted.ends_with(&format!("({} characters)", 5 << 20)), "{quoted}");
        assert_eq!(clip("short"), "short");
    }

    #[test]
    fn an_error_names_a_path_once_and_never_echoes_a_huge_value() {
        let root = std::io::Error::other("writing /x/metrics.json: No space left on device");
        let err = anyhow::Error::new(root).context("writing /x/metrics.json").context("saving step 2");
        assert_eq!(error_text(&err), "saving step 2: writing /x/metrics.json: No space left on device");
        let huge = anyhow::anyhow!("unknown task {:?}", "y".repeat(5 << 20)).context("in run file r.toml");
        let text = error_text(&huge);
        assert!(text.len() < 2 * CAUSE_MAX, "{}", text.len());
        assert!(text.starts_with("in run file r.toml: unknown task \"yyy") && text.contains("characters)"), "{text}");
    }
}
