//! `armgate calibrate …`: runs the separate `armgate-calibrate` tool (crate `calibrate/`), which
//! needs the robot model and dense algebra this client does not link.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::Command;

/// The calibration tool's file name.
pub const TOOL: &str = "armgate-calibrate";

/// The tool next to the running executable if it is there, else its bare name (found on PATH).
fn tool() -> PathBuf {
    let name = format!("{TOOL}{}", std::env::consts::EXE_SUFFIX);
    std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(|dir| dir.join(&name)))
        .filter(|path| path.is_file())
        .unwrap_or_else(|| PathBuf::from(name))
}

/// Runs the tool with `args` and returns its exit status (2 if it cannot be run or was killed).
pub fn run(args: &[OsString]) -> u8 {
    match Command::new(tool()).args(args).status() {
        Ok(status) => status
            .code()
            .map_or(2, |code| u8::try_from(code).unwrap_or(2)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            eprintln!(
                "armgate: `armgate calibrate` runs `{TOOL}`, which is neither next to armgate nor \
                 on PATH; build it with `cargo build -p armgate-calibrate`"
            );
            2
        }
        Err(e) => {
            eprintln!("armgate: cannot run {TOOL}: {e}");
            2
        }
    }
}
