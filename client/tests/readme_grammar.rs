//! The README against the protocol (issue 37: it was behind the code): its command list is the
//! protocol crate's commands, its error table has a row for every code of
//! `protocol/grammar.json` (the table the protocol crate generates from its texts), it names
//! every `SQ` index the controller answers, and its Python section names only methods the
//! Python client has.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::collections::BTreeSet;

use armgate_client::Command;

fn repo_file(path: &str) -> String {
    std::fs::read_to_string(format!("{}/../{path}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// The text of the README's section `## heading`, up to the next.
fn section(readme: &str, heading: &str) -> String {
    let start = readme
        .find(&format!("\n## {heading}\n"))
        .unwrap_or_else(|| panic!("no section {heading}"));
    let rest = &readme[start + 1..];
    let end = rest[3..].find("\n## ").map_or(rest.len(), |e| e + 3);
    rest[..end].to_owned()
}

#[test]
fn the_command_list_is_the_protocols() {
    let readme = repo_file("README.md");
    let protocol = section(&readme, "Protocol");
    let start = protocol.find("Commands: `").expect("a command list") + "Commands: `".len();
    let list = &protocol[start..start + protocol[start..].find('`').unwrap()];
    let listed: BTreeSet<String> = list.split_whitespace().map(str::to_owned).collect();
    let known: BTreeSet<String> = Command::ALL
        .iter()
        .map(|c| String::from_utf8_lossy(&c.chars()).into_owned())
        .collect();
    assert_eq!(listed, known);
}

/// The (severity, code) pairs of `protocol/grammar.json`'s `codes`, and whether each is a
/// drive fault.
fn grammar_codes() -> Vec<(String, u8, bool)> {
    let grammar = repo_file("protocol/grammar.json");
    let start = grammar.find("\"codes\"").unwrap();
    let end = grammar.find("\"texts\"").unwrap();
    grammar[start..end]
        .lines()
        .filter(|l| l.contains("\"severity\""))
        .map(|l| {
            let field = |name: &str| {
                let at = l.find(&format!("\"{name}\": ")).unwrap() + name.len() + 4;
                l[at..]
                    .split([',', '}'])
                    .next()
                    .unwrap()
                    .trim()
                    .trim_matches('"')
                    .to_owned()
            };
            (
                field("severity"),
                field("code").parse().unwrap(),
                field("drive_fault") == "true",
            )
        })
        .collect()
}

#[test]
fn the_error_table_has_a_row_for_every_code_of_the_grammar() {
    let readme = repo_file("README.md");
    let protocol = section(&readme, "Protocol");
    let rows: Vec<&str> = protocol.lines().filter(|l| l.starts_with("| `")).collect();
    let codes = grammar_codes();
    assert!(codes.len() > 20, "{codes:?}");
    for (severity, code, drive_fault) in codes {
        let prefix = if drive_fault {
            "| `ER3x".to_owned()
        } else {
            format!("| `{severity}{code:02}")
        };
        assert!(
            rows.iter().any(|r| r.starts_with(&prefix)),
            "no README row for {severity}{code:02} (looked for `{prefix}`)"
        );
    }
}

#[test]
fn every_status_index_is_named() {
    let readme = repo_file("README.md");
    let protocol = section(&readme, "Protocol");
    // The indices the controller answers: those of the protocol crate's reports.
    let indices = [
        armgate_protocol::client::STATUS_INDEX,
        armgate_protocol::client::NAME_INDEX,
        armgate_protocol::client::CAUSE_INDEX,
        armgate_protocol::client::SESSION_INDEX,
        armgate_protocol::client::signed::SIGNING_INDEX,
        armgate_protocol::client::branch::BRANCH_INDEX,
        armgate_protocol::client::signed::IDENTITY_INDEX,
        armgate_protocol::client::NEAREST_INDEX,
    ];
    for index in indices {
        assert!(
            protocol.contains(&format!("with index {index},"))
                || protocol.contains(&format!("with index {index}:")),
            "the README's SQ paragraph does not name index {index}"
        );
    }
    let max = indices.iter().max().unwrap();
    assert!(
        protocol.contains(&format!("`SQ` index above {max}")),
        "ER24's row"
    );
}

#[test]
fn the_python_section_names_only_methods_the_client_has() {
    let readme = repo_file("README.md");
    let python = section(&readme, "Python client");
    assert!(!python.contains("will follow"), "{python}");
    // armgate.Arm and the classes it is built from (waits, streams).
    let client = ["client.py", "waiting.py", "streaming.py"]
        .map(|file| repo_file(&format!("python/armgate/{file}")))
        .concat();
    let errors = repo_file("python/armgate/errors.py");
    // Every `name` in backticks that looks like a method or a class of the package.
    for name in python.split('`').skip(1).step_by(2) {
        let word = name.trim_end_matches("()");
        if word.chars().all(|c| c.is_ascii_lowercase() || c == '_') && word.contains('_') {
            assert!(
                client.contains(&format!("def {word}(")),
                "README names {word}, which armgate.Arm does not have"
            );
        } else if word.chars().next().is_some_and(|c| c.is_ascii_uppercase())
            && word.chars().all(char::is_alphanumeric)
            && !matches!(word, "ER" | "WN" | "ST")
        {
            assert!(
                errors.contains(&format!("class {word}(")),
                "README names {word}, which armgate does not raise"
            );
        }
    }
}
