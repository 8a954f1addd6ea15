//! The commands that run a separate tool: `armgate calibrate …` runs `armgate-calibrate`
//! (crate `calibrate/`), `armgate urdf …` and `armgate record …` run `armgate-viz` (crate
//! `viz/`). They need the robot model (and dense algebra, MCAP) this client does not link.
//!
//! The tool is found next to `armgate`, else on PATH; `armgate` started by `cargo run -p
//! armgate-client` in the repository finds neither on a fresh clone, so it runs the tool with
//! `cargo run -p TOOL` of the same workspace (built on first use).

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

/// Under `cargo run -p armgate-client`: `cargo run -q -p TOOL --manifest-path …/Cargo.toml
/// --`, the same workspace's package of the tool's name (the arguments keep their paths
/// relative to where `armgate` was started).
fn through_cargo(tool: &str) -> Option<Command> {
    let cargo = std::env::var_os("CARGO")?;
    if std::env::var_os("CARGO_PKG_NAME")? != "armgate-client" {
        return None;
    }
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR")?).join("Cargo.toml");
    if !manifest.is_file() {
        return None;
    }
    let mut command = Command::new(cargo);
    command
        .args(["run", "-q", "-p", tool, "--manifest-path"])
        .arg(manifest)
        .arg("--");
    Some(command)
}

/// Runs `tool` with `args` and returns its exit status (2 if it cannot be run or was killed).
/// Each tool is built by the cargo package of its own name.
pub fn run(tool: &str, args: &[OsString]) -> u8 {
    let found = locate(tool);
    let mut command = match through_cargo(tool) {
        Some(cargo) if found.is_relative() && which(&found).is_none() => cargo,
        _ => Command::new(found),
    };
    match command.args(args).status() {
        Ok(status) => status
            .code()
            .map_or(2, |code| u8::try_from(code).unwrap_or(2)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            eprintln!(
                "armgate: this command runs `{tool}`, which is neither next to armgate nor on \
                 PATH; build it with `cargo build -p {tool}` (every tool at once: `cargo build \
                 -p armgate-client -p armgate-calibrate -p armgate-viz -p armgate-sim`)"
            );
            2
        }
        Err(e) => {
            eprintln!("armgate: cannot run {tool}: {e}");
            2
        }
    }
}

/// The program a bare name runs from PATH, if any.
fn which(name: &std::path::Path) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|dir| dir.join(name))
        .find(|path| path.is_file())
}
