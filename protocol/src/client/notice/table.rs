//! The grammar as one table for the clients in other languages (python/armgate/errors.py):
//! every code with its severity, the notices it carries and whether it ends a motion, and a
//! text of every form with the parts a client reads back (command, detail); the names of
//! the IK branch bits and of the obstacle kinds of `SQ` index 7.
//!
//! Committed as `protocol/grammar.json`. This test fails when the file is stale
//! (`ARMGATE_BLESS=1 cargo test -p armgate-protocol grammar_table` rewrites it); Python's
//! `test_grammar.py` checks errors.py against it.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::samples::samples;
use crate::client::{DRIVE_FAULT_CODES, Header, Message, Notice, Severity, Text};

/// Texts that are no notice of this grammar but that clients read all the same: an older
/// controller's refusals and the drive faults (formed by the core, docs/drives.md).
const OTHER_TEXTS: [&str; 4] = [
    "ER20 Cmd BG rejected",
    "ER33 J4 PT buffer underflow",
    "ER35 CAN bus off",
    "WN39 J1 map 1A01:00 read back",
];

/// The variant's name: `Rejected(Begin, Busy)` → `Rejected`.
fn variant(notice: &Notice) -> String {
    let debug = std::format!("{notice:?}");
    debug.split('(').next().unwrap_or_default().to_string()
}

/// A JSON string (the texts are printable ASCII).
fn string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        if matches!(c, '"' | '\\') {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

fn received(s: &str) -> Text {
    let mut datagram = [0; crate::client::MESSAGE_LEN];
    datagram[..s.len()].copy_from_slice(s.as_bytes());
    Text::parse(&Message::new_checked(&datagram[..]).unwrap()).unwrap()
}

/// One row of `texts`.
fn text_row(text: &Text) -> String {
    let header = Header::parse(text).unwrap();
    let command = header
        .command
        .map_or("null".to_string(), |c| string(&String::from_utf8_lossy(&c)));
    let refuses = header
        .refuses()
        .map_or("null".to_string(), |c| string(&String::from_utf8_lossy(&c)));
    let notice = Notice::parse(text).map_or("null".to_string(), |n| string(&variant(&n)));
    std::format!(
        "{{\"text\": {}, \"severity\": \"{}\", \"code\": {}, \"command\": {command}, \"detail\": {}, \"refuses\": {refuses}, \"notice\": {notice}, \"ends_motion\": {}}}",
        string(text.as_str()),
        header.severity.prefix(),
        header.code,
        string(header.detail),
        header.ends_motion(),
    )
}

/// The whole table.
fn table() -> String {
    // (prefix, code) → the notices it carries.
    let mut codes: BTreeMap<(&str, u8), Vec<String>> = BTreeMap::new();
    for notice in samples() {
        let names = codes
            .entry((notice.severity().prefix(), notice.code()))
            .or_default();
        let name = variant(&notice);
        if !names.contains(&name) {
            names.push(name);
        }
    }
    for code in DRIVE_FAULT_CODES {
        codes.entry((Severity::Error.prefix(), code)).or_default();
    }
    let mut out = String::from("{\n  \"codes\": [\n");
    let rows: Vec<String> = codes
        .iter()
        .map(|((prefix, code), names)| {
            let text = received(&std::format!("{prefix}{code:02}"));
            let header = Header::parse(&text).unwrap();
            let names: Vec<String> = names.iter().map(|n| string(n)).collect();
            std::format!(
                "    {{\"severity\": \"{prefix}\", \"code\": {code}, \"notices\": [{}], \"drive_fault\": {}, \"ends_motion\": {}}}",
                names.join(", "),
                header.is_drive_fault(),
                header.ends_motion(),
            )
        })
        .collect();
    out.push_str(&rows.join(",\n"));
    out.push_str("\n  ],\n  \"texts\": [\n");
    let mut texts: Vec<Text> = Vec::new();
    for text in samples().map(|n| n.text()).chain(OTHER_TEXTS.map(received)) {
        // A text that stands for several notices once.
        if !texts.contains(&text) {
            texts.push(text);
        }
    }
    let rows: Vec<String> = texts
        .iter()
        .map(|t| std::format!("    {}", text_row(t)))
        .collect();
    out.push_str(&rows.join(",\n"));
    // The names of the IK branch bits (`branch::NAMES`), for Python's `armgate.branch`.
    out.push_str("\n  ],\n  \"branches\": [\n");
    let rows: Vec<String> = crate::client::branch::NAMES
        .iter()
        .map(|(bit, [(clear, c), (set, s)])| {
            std::format!(
                "    {{\"bit\": {bit}, \"clear\": [{}, \"{c}\"], \"set\": [{}, \"{s}\"]}}",
                string(clear),
                string(set)
            )
        })
        .collect();
    out.push_str(&rows.join(",\n"));
    // The kinds of obstacle of `SQ` 7's f2 (`OBSTACLE_KINDS`), for Python's `Nearest`.
    out.push_str("\n  ],\n  \"obstacles\": [\n");
    let rows: Vec<String> = crate::client::OBSTACLE_KINDS
        .iter()
        .map(|(kind, name, short)| {
            std::format!(
                "    {{\"kind\": {kind}, \"name\": {}, \"short\": {}}}",
                string(name),
                string(short)
            )
        })
        .collect();
    out.push_str(&rows.join(",\n"));
    // The signing figures a client's resends follow (`signed::RESERVE_AHEAD` in
    // `TIMESTAMP_UNIT_US` steps), for Python's `armgate.signing`.
    let _ = writeln!(
        out,
        "\n  ],\n  \"signing\": {{\"timestamp_unit_us\": {}, \"reserve_ahead\": {}}}\n}}",
        crate::client::signed::TIMESTAMP_UNIT_US,
        crate::client::signed::RESERVE_AHEAD
    );
    out
}

#[test]
fn grammar_table_is_committed_as_generated() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("grammar.json");
    let generated = table();
    if std::env::var_os("ARMGATE_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "{} is stale: ARMGATE_BLESS=1 cargo test -p armgate-protocol grammar_table",
        path.display()
    );
}
