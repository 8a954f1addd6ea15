//! The commands that run a separate tool: `armgate calibrate …` runs `armgate-calibrate`
//! (crate `calibrate/`), `armgate urdf …` and `armgate record …` run `armgate-viz` (crate
//! `viz/`). They need the robot model (and dense algebra, MCAP) this client does not link.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::Command;

/// The calibration tool's file name.
pub const CALIBRATE: &str = "armgate-calibrate";
/// The visualisation tool's file name (URDF export, recording).
pub const VIZ: &str = "armgate-viz";

/// The tool next to the running executable if it is there, else its bare name (found on PATH).
fn locate(tool: &str) -> PathBuf {
    let name = format!("{tool}{}", std::env::consts::EXE_SUFFIX);
    std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(|dir| dir.join(&name)))
        .filter(|path| path.is_file())
        .unwrap_or_else(|| PathBuf::from(name))
}

/// Runs `tool` with `args` and returns its exit status (2 if it cannot be run or was killed).
/// Each tool is built by the cargo package of its own name.
pub fn run(tool: &str, args: &[OsString]) -> u8 {
    match Command::new(locate(tool)).args(args).status() {
        Ok(status) => status
            .code()
            .map_or(2, |code| u8::try_from(code).unwrap_or(2)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            eprintln!(
                "armgate: this command runs `{tool}`, which is neither next to armgate nor on \
                 PATH; build it with `cargo build -p {tool}`"
            );
            2
        }
        Err(e) => {
            eprintln!("armgate: cannot run {tool}: {e}");
            2
        }
    }
}
