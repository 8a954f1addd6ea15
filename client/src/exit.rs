//! The exit statuses of the `armgate` tool: one table, the same for every subcommand.
//!
//! [`TABLE`] is what `armgate --help` prints and what the README's "Exit status" table must
//! list (a test reads the README); [`ClientError::exit_code`](crate::ClientError::exit_code)
//! and [`CliError::exit_code`](crate::cli::CliError::exit_code) map every failure to one row.

/// Everything went as asked.
pub const SUCCESS: u8 = 0;
/// The controller refused a request (the `ER` text is printed).
pub const REFUSED: u8 = 1;
/// No reply, an I/O error, bad arguments or a bad run file: nothing says what the arm did.
pub const NO_CONTACT: u8 = 2;
/// The motion was stopped before its goal: by the controller (`ER21`, `WN22`, `WN27`, `ER3x`,
/// `ER41`) or by a client's `ST`, `CM` or `OF`; the cause and who are printed.
pub const STOPPED: u8 = 3;
/// The arm did not arrive although nothing stopped it: it stalled short of the goal, or
/// `--wait-timeout` passed; `ST` was sent.
pub const NOT_ARRIVED: u8 = 4;
/// `armgate ik`: the pose has no IK solution within the joint limits.
pub const NO_SOLUTION: u8 = 5;
/// Interrupted by Ctrl-C (128 + SIGINT, as a shell reports it); `ST` was sent unless
/// `--no-stop-on-interrupt`.
pub const INTERRUPTED: u8 = 130;

/// Every status with its meaning, as the README's table lists them.
pub const TABLE: [(u8, &str); 7] = [
    (SUCCESS, "success"),
    (
        REFUSED,
        "the controller refused a request (its ER text is printed)",
    ),
    (
        NO_CONTACT,
        "no reply, I/O error, bad arguments or a bad run file",
    ),
    (
        STOPPED,
        "the motion was stopped before its goal, by the controller (ER21, WN22, WN27, ER3x, \
         ER41, ER43) or by a client's ST, CM or OF; the cause and who are printed",
    ),
    (
        NOT_ARRIVED,
        "the arm stalled short of the goal or --wait-timeout passed, nothing having stopped \
         it; ST was sent",
    ),
    (NO_SOLUTION, "ik: no IK solution within the joint limits"),
    (
        INTERRUPTED,
        "interrupted by Ctrl-C (ST sent unless --no-stop-on-interrupt)",
    ),
];

/// The table as `armgate --help` prints it.
pub fn help() -> String {
    let mut text = String::from("Exit status (every subcommand):\n");
    for (code, meaning) in TABLE {
        text.push_str(&format!("  {code:>3}  {meaning}\n"));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The README's "Exit status" table: its rows, code and meaning.
    fn readme_rows() -> Vec<(u8, String)> {
        let readme = include_str!("../../README.md");
        let start = readme
            .find("| Exit status | Meaning |")
            .expect("the README has the exit status table");
        readme[start..]
            .lines()
            .skip(2)
            .take_while(|l| l.starts_with('|'))
            .map(|l| {
                let cells: Vec<&str> = l.split('|').map(str::trim).collect();
                (cells[1].parse().unwrap(), cells[2].to_owned())
            })
            .collect()
    }

    #[test]
    fn the_readme_lists_every_exit_status_as_the_tool_does() {
        let rows = readme_rows();
        assert_eq!(
            rows.iter().map(|r| r.0).collect::<Vec<_>>(),
            TABLE.iter().map(|r| r.0).collect::<Vec<_>>()
        );
        for ((code, readme), (_, meaning)) in rows.iter().zip(TABLE) {
            // The README may quote names in backticks.
            assert_eq!(readme.replace('`', ""), meaning, "exit status {code}");
        }
        let codes: std::collections::BTreeSet<u8> = TABLE.iter().map(|r| r.0).collect();
        assert_eq!(codes.len(), TABLE.len(), "one meaning per status");
    }
}
