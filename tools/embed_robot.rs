// Shared by the build scripts of `firmware/` and `qemu-bench/` through `include!`: turns a robot
// TOML file into the postcard bytes that a bare-metal binary embeds with `include_bytes!`.
// The including build script needs the build-dependencies `armgate-core` (feature `std`) and
// `postcard` (feature `use-std`).

/// Reads `workspace_root/relative`, parses and validates it with `armgate_core::config::parse_toml`,
/// checks that the drive manager accepts it with the default drive settings (which the firmware
/// uses: a refusal there would otherwise stop the board at boot), and writes the postcard
/// serialisation of the `RobotConfig` to `out`. Prints the `rerun-if-changed` line for the robot
/// file. The error names the file and, for a refused robot, the field or the drive setting.
fn embed_robot(
    workspace_root: &std::path::Path,
    relative: &str,
    out: &std::path::Path,
) -> Result<armgate_core::config::ValidRobot, String> {
    let path = workspace_root.join(relative);
    println!("cargo:rerun-if-changed={}", path.display());
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read robot file {}: {e}", path.display()))?;
    let config =
        armgate_core::config::parse_toml(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let settings = armgate_core::drives::DriveSettings::default();
    armgate_core::drives::DriveManager::new(&config, &settings)
        .map_err(|e| format!("{}: the drive manager refuses this robot: {e}", path.display()))?;
    let bytes = postcard::to_stdvec(config.config())
        .map_err(|e| format!("{}: cannot serialise with postcard: {e}", path.display()))?;
    std::fs::write(out, bytes).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    Ok(config)
}

/// Reports a build-script error on stderr (cargo shows it under the failing build script) and
/// fails the build.
fn fail_build(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1)
}
