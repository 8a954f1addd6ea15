//! Build script of the firmware: linker scripts and the embedded robot description.
//!
//! * copies the workspace's top-level `memory.x` (the STM32H743 memory map) into `OUT_DIR` and
//!   puts it on the linker search path; adds `-Tlink.x` / `-Tdefmt.x` for bare-metal builds;
//! * reads the robot file named by `ROBOT` (default `robots/ranger-mk1.toml`, relative to the
//!   workspace root), validates it and writes its postcard serialisation to
//!   `OUT_DIR/robot.postcard`, which `src/config.rs` embeds. A refused robot file fails the
//!   build with the error naming the field;
//! * sets `DEFMT_LOG=info` for this crate unless the user set `DEFMT_LOG`.

use std::path::{Path, PathBuf};

include!("../tools/embed_robot.rs");

/// The robot embedded when `ROBOT` is not set.
const DEFAULT_ROBOT: &str = "robots/ranger-mk1.toml";

fn main() {
    let manifest_dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let workspace_root = manifest_dir.parent().unwrap_or(&manifest_dir).to_path_buf();
    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../tools/embed_robot.rs");

    copy_memory_x(&workspace_root, &out_dir);

    if std::env::var("CARGO_CFG_TARGET_OS").is_ok_and(|os| os == "none") {
        println!("cargo:rustc-link-arg-bins=--nmagic");
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }

    // defmt shows only errors unless DEFMT_LOG says otherwise: default this crate's own log
    // statements to `info` (the defmt macros read DEFMT_LOG from rustc's environment). A
    // DEFMT_LOG set by the user applies unchanged, to every crate.
    println!("cargo:rerun-if-env-changed=DEFMT_LOG");
    if std::env::var_os("DEFMT_LOG").is_none() {
        println!("cargo:rustc-env=DEFMT_LOG=info");
    }

    println!("cargo:rerun-if-env-changed=ROBOT");
    let robot = std::env::var("ROBOT").unwrap_or_else(|_| DEFAULT_ROBOT.to_owned());
    if let Err(message) = embed_robot(&workspace_root, &robot, &out_dir.join("robot.postcard")) {
        fail_build(&message);
    }
}

/// `memory.x` lives at the workspace root (one memory map for the one board). rust-lld looks for
/// `INCLUDE memory.x` in its working directory, which cargo sets to the workspace root, before the
/// search path; the copy in `OUT_DIR` keeps the link independent of that.
fn copy_memory_x(workspace_root: &Path, out_dir: &Path) {
    let source = workspace_root.join("memory.x");
    println!("cargo:rerun-if-changed={}", source.display());
    if let Err(e) = std::fs::copy(&source, out_dir.join("memory.x")) {
        fail_build(&format!("cannot copy {}: {e}", source.display()));
    }
    println!("cargo:rustc-link-search={}", out_dir.display());
}
