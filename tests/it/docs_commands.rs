//! The docs' command lines work with this binary: every `fieldhouse …` a reader can copy
//! from the README, PROTOCOL.md, BENCHMARKS.md, the Python client's README or `docs/`
//! (in a code block or an inline code span) names a subcommand that exists, every
//! `--flag` it passes is one that subcommand's `--help` lists, and, where it has no
//! placeholders (`FILE`, `…`, `[--json]`), it parses: clap checks each value as it reads
//! it, before the `--help` appended at the end stops the command from running.

use std::path::Path;
use std::process::{Command, Output};

const DOCS: [&str; 4] = [
    "README.md",
    "PROTOCOL.md",
    "BENCHMARKS.md",
    "clients/python/README.md",
];

/// Where a command line ends in a shell line: a comment, a pipe, a redirection, the next
/// command.
const ENDS: [&str; 7] = [" #", " |", " >", " 2>", ";", " &&", " &"];

/// Every `fieldhouse …` command line of a Markdown text, joined across `\` line ends.
fn command_lines(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    // Inline code spans that start with the binary's name.
    for span in text.split('`').skip(1).step_by(2) {
        if span.starts_with("fieldhouse ") {
            found.push(span.replace('\n', " "));
        }
    }
    // Lines of code blocks, from the binary's name to where the shell command ends.
    let mut in_block = false;
    let mut pending = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            pending.clear();
            continue;
        }
        let line = line.trim();
        let line = if pending.is_empty() {
            let line = line
                .trim_start_matches("$ ")
                .trim_start_matches("target/release/");
            if !in_block || !line.starts_with("fieldhouse ") {
                continue;
            }
            line
        } else {
            line
        };
        let end = ENDS
            .iter()
            .filter_map(|e| line.find(e))
            .min()
            .unwrap_or(line.len());
        let part = line[..end].trim_end();
        match part.strip_suffix('\\') {
            Some(head) => pending.push_str(&format!("{} ", head.trim_end())),
            None => {
                found.push(format!("{pending}{part}"));
                pending.clear();
            }
        }
    }
    found
}

/// Shell words, with single and double quotes.
fn words(line: &str) -> Vec<String> {
    let (mut words, mut word, mut quote, mut started) = (Vec::new(), String::new(), None, false);
    for c in line.chars() {
        match (quote, c) {
            (None, '\'' | '"') => {
                quote = Some(c);
                started = true;
            }
            (Some(q), c) if c == q => quote = None,
            (None, c) if c.is_whitespace() => {
                if started {
                    words.push(std::mem::take(&mut word));
                    started = false;
                }
            }
            (_, c) => {
                word.push(c);
                started = true;
            }
        }
    }
    if started {
        words.push(word);
    }
    words
}

/// A word a reader replaces: `FILE`, `X,Z,HEADING_DEG`, `a41c…`, `[--json]`, `<FILE>`.
fn placeholder(word: &str) -> bool {
    let caps = word
        .split([',', '=', ':', '/', '.'])
        .any(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_uppercase() || c == '_'));
    caps || word.contains(['…', '[', ']', '<', '>', '{', '}', '$', '*']) || word.contains("...")
}

fn fieldhouse(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(args)
        .env_remove("FIELDHOUSE_LOG")
        .output()
        .expect("the binary runs")
}

#[test]
fn every_command_line_in_the_docs_names_real_subcommands_and_flags_and_parses() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut docs: Vec<_> = DOCS.iter().map(|d| root.join(d)).collect();
    let mut in_docs: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    in_docs.sort();
    docs.extend(in_docs);
    let (mut checked, mut parsed, mut problems) = (0, 0, Vec::new());
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        let shown = doc.strip_prefix(root).unwrap().display().to_string();
        for line in command_lines(&text) {
            let words = words(&line);
            let args: Vec<&str> = words[1..].iter().map(String::as_str).collect();
            // The subcommand (and a replay's own): the words before the first flag.
            let path: Vec<&str> = args
                .iter()
                .take_while(|w| !w.starts_with('-') && !placeholder(w))
                .take(if args.first() == Some(&"replay") {
                    2
                } else {
                    1
                })
                .copied()
                .collect();
            if args.first().is_some_and(|w| placeholder(w)) {
                continue; // `fieldhouse <subcommand> --help`
            }
            checked += 1;
            let help = fieldhouse(&[&path[..], &["--help"]].concat());
            if !help.status.success() {
                problems.push(format!(
                    "{shown}: `{line}`: no subcommand `{}`",
                    path.join(" ")
                ));
                continue;
            }
            let help = String::from_utf8_lossy(&help.stdout);
            for flag in args.iter().filter(|w| w.starts_with("--")) {
                let name = flag.split('=').next().unwrap();
                let listed = help.match_indices(name).any(|(at, _)| {
                    !help[at + name.len()..]
                        .starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-')
                });
                if !listed {
                    problems.push(format!(
                        "{shown}: `{line}`: `{name}` is not a flag of `fieldhouse {}`",
                        path.join(" ")
                    ));
                }
            }
            if args.iter().any(|w| placeholder(w)) {
                continue;
            }
            parsed += 1;
            let out = fieldhouse(&[&args[..], &["--help"]].concat());
            if !out.status.success() {
                let err = String::from_utf8_lossy(&out.stderr);
                problems.push(format!(
                    "{shown}: `{line}`: {}",
                    err.lines().next().unwrap_or("")
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The check reads what it should: the docs quote many commands, most without
    // placeholders.
    assert!(
        checked >= 80 && parsed >= 40,
        "{checked} command lines, {parsed} parsed"
    );
}

#[test]
fn command_lines_are_found_in_spans_and_blocks_and_split_as_a_shell_would() {
    let text = "Run `fieldhouse catch --json` or:\n\n```sh\n$ fieldhouse run a.toml \\\n    --out b.jsonl  # then\ncurl x | fieldhouse replay info -\n```\n";
    assert_eq!(
        command_lines(text),
        [
            "fieldhouse catch --json",
            "fieldhouse run a.toml --out b.jsonl"
        ]
    );
    assert_eq!(words("a 'b c' \"d\" e=f"), ["a", "b c", "d", "e=f"]);
    assert!(placeholder("FILE") && placeholder("X,Z,HEADING_DEG") && placeholder("a41c…"));
    assert!(!placeholder("9,2,180") && !placeholder("chapman"));
}
