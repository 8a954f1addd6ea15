//! Build script of the QEMU benchmark: its own linker memory map and the embedded robots.
//!
//! * copies `qemu-bench/memory.x` (QEMU mps2-an500: code at 0, RAM at 0x2000_0000) into
//!   `OUT_DIR` as `memory.x`, on the linker search path; adds `-Tlink.x` for bare-metal builds;
//! * serialises every `robots/*.toml` of the workspace with postcard (the same conversion as the
//!   firmware's, `tools/embed_robot.rs`) and writes `OUT_DIR/robots.rs`, the list of
//!   `(name, bytes)` that `src/bench.rs` includes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

include!("../tools/embed_robot.rs");

fn main() {
    let manifest_dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let workspace_root = manifest_dir.parent().unwrap_or(&manifest_dir).to_path_buf();
    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=../tools/embed_robot.rs");

    if let Err(e) = std::fs::copy(manifest_dir.join("memory.x"), out_dir.join("memory.x")) {
        fail_build(&format!("cannot copy qemu-bench/memory.x: {e}"));
    }
    println!("cargo:rustc-link-search={}", out_dir.display());
    if std::env::var("CARGO_CFG_TARGET_OS").is_ok_and(|os| os == "none") {
        // cortex-m-rt's link.x says `INCLUDE memory.x`, and the linker looks in its working
        // directory, the workspace root, before the search path: it would take the firmware's
        // STM32 map. `--remap-inputs` (rust-lld) redirects that name to this crate's map.
        println!(
            "cargo:rustc-link-arg-bins=--remap-inputs=memory.x={}",
            out_dir.join("memory.x").display()
        );
        println!("cargo:rustc-link-arg-bins=--nmagic");
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
    }

    if let Err(message) = embed_all(&workspace_root, &out_dir) {
        fail_build(&message);
    }
}

/// Embeds every robot file of `robots/`, sorted by name, and writes the list `robots.rs`.
fn embed_all(workspace_root: &Path, out_dir: &Path) -> Result<(), String> {
    let robots_dir = workspace_root.join("robots");
    println!("cargo:rerun-if-changed={}", robots_dir.display());
    let entries = std::fs::read_dir(&robots_dir)
        .map_err(|e| format!("cannot list {}: {e}", robots_dir.display()))?;
    let mut stems: Vec<String> = entries
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|path| path.extension().is_some_and(|ext| ext == "toml"))
        .filter_map(|path| path.file_stem().and_then(|s| s.to_str()).map(str::to_owned))
        .collect();
    stems.sort();
    let mut list = String::from("/// Every robot of `robots/`: file stem and postcard bytes.\n");
    list.push_str("static ROBOTS: &[(&str, &[u8])] = &[\n");
    for stem in &stems {
        let out = out_dir.join(format!("{stem}.postcard"));
        embed_robot(workspace_root, &format!("robots/{stem}.toml"), &out)?;
        // `{:?}` quotes and escapes both the name and the path.
        let _ = writeln!(
            list,
            "    ({stem:?}, include_bytes!({:?})),",
            out.display().to_string()
        );
    }
    list.push_str("];\n");
    let path = out_dir.join("robots.rs");
    std::fs::write(&path, list).map_err(|e| format!("cannot write {}: {e}", path.display()))
}
