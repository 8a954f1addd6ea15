//! Build script of the firmware: linker scripts and the embedded robot description.
//!
//! * copies the workspace's top-level `memory.x` (the STM32H743 memory map) into `OUT_DIR` and
//!   puts it on the linker search path; adds `-Tlink.x` / `-Tdefmt.x` for bare-metal builds;
//! * reads the robot file named by `ROBOT` (default `robots/ranger-mk1.toml`, relative to the
//!   workspace root), validates it and writes its postcard serialisation to
//!   `OUT_DIR/robot.postcard`, which `src/config.rs` embeds. A refused robot file fails the
//!   build with the error naming the field;
//! * parses the network settings (`ARMGATE_IP`, `ARMGATE_GATEWAY`, `ARMGATE_PORT`,
//!   `ARMGATE_ALLOW`) and the signing settings (`ARMGATE_KEY_FILE`, `ARMGATE_ALLOW_UNSIGNED`;
//!   see `docs/firmware.md`) and writes them
//!   as Rust constants to `OUT_DIR/settings.rs`, which `src/settings.rs` includes. A malformed
//!   value fails the build with a message naming the variable;
//! * sets `DEFMT_LOG=info` for this crate unless the user set `DEFMT_LOG`.

use std::fmt::Write as _;
use std::net::{IpAddr, Ipv4Addr};
use std::path::{Path, PathBuf};

use armgate_core::command::{Network, NetworkError};
use armgate_core::cycle::UnsignedAccess;
use armgate_protocol::client::signed::{ControllerId, parse_key};

include!("../tools/embed_robot.rs");

/// The board's address and prefix length when `ARMGATE_IP` is not set.
const DEFAULT_IP: &str = "192.168.1.50/24";
/// The UDP port when `ARMGATE_PORT` is not set (the protocol's port, as `armgate-sim`'s).
const DEFAULT_PORT: u16 = 7031;
/// The allow-list when `ARMGATE_ALLOW` is not set: the board's own network.
const DEFAULT_ALLOW: &str = "local";

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

    match settings() {
        Ok(text) => {
            let path = out_dir.join("settings.rs");
            if let Err(e) = std::fs::write(&path, text) {
                fail_build(&format!("cannot write {}: {e}", path.display()));
            }
        }
        Err(message) => fail_build(&message),
    }
}

/// An environment variable of the build, with its `rerun-if-env-changed` line; unset and empty
/// count as absent.
fn env(name: &str) -> Option<String> {
    println!("cargo:rerun-if-env-changed={name}");
    std::env::var(name).ok().filter(|v| !v.trim().is_empty())
}

/// `a.b.c.d/n` (or a bare `a.b.c.d`, which means `/32`), parsed as the core's allow-list
/// [`Network`] is; the board speaks IPv4 only.
fn parse_network(text: &str) -> Result<(Ipv4Addr, u8), String> {
    let text = text.trim();
    let not_ipv4 = || format!("`{text}` is not an IPv4 address (a.b.c.d or a.b.c.d/n)");
    let network: Network = text.parse().map_err(|e| match e {
        NetworkError::BadPrefix { max: 32 } => {
            format!("`{text}`: the prefix length must be 0..=32")
        }
        _ => not_ipv4(),
    })?;
    match network.addr() {
        IpAddr::V4(address) => Ok((address, network.prefix())),
        IpAddr::V6(_) => Err(not_ipv4()),
    }
}

/// The generated constants of `src/settings.rs`, or the error naming the variable.
fn settings() -> Result<String, String> {
    let ip = env("ARMGATE_IP").unwrap_or_else(|| DEFAULT_IP.to_owned());
    let (address, prefix) = parse_network(&ip).map_err(|e| format!("ARMGATE_IP: {e}"))?;
    if prefix == 0 || prefix == 32 {
        return Err(format!(
            "ARMGATE_IP: `{ip}`: give the board's address with its network prefix, e.g. {DEFAULT_IP}"
        ));
    }
    let gateway = match env("ARMGATE_GATEWAY") {
        None => None,
        Some(g) if g.trim() == "none" => None,
        Some(g) => Some(
            g.trim()
                .parse::<Ipv4Addr>()
                .map_err(|_| format!("ARMGATE_GATEWAY: `{g}` is not an IPv4 address"))?,
        ),
    };
    let port = match env("ARMGATE_PORT") {
        None => DEFAULT_PORT,
        Some(p) => match p.trim().parse::<u16>() {
            Ok(p) if p > 0 => p,
            _ => {
                return Err(format!(
                    "ARMGATE_PORT: `{p}` is not a port number (1..=65535)"
                ));
            }
        },
    };
    let allow_text = env("ARMGATE_ALLOW").unwrap_or_else(|| DEFAULT_ALLOW.to_owned());
    let mut allow_local = false;
    let mut allow = Vec::new();
    for entry in allow_text
        .split(',')
        .map(str::trim)
        .filter(|e| !e.is_empty())
    {
        if entry == "local" {
            allow_local = true;
        } else {
            allow.push(parse_network(entry).map_err(|e| format!("ARMGATE_ALLOW: {e}"))?);
        }
    }
    if !allow_local && allow.is_empty() {
        return Err("ARMGATE_ALLOW: empty: no client could command the arm".to_owned());
    }
    let ipv4 = |a: Ipv4Addr| {
        let [a, b, c, d] = a.octets();
        format!("Ipv4Addr::new({a}, {b}, {c}, {d})")
    };
    let mut out = String::from("// Generated by firmware/build.rs from the ARMGATE_* variables.\n");
    // With DHCP the static address is not used.
    let unused_with_dhcp = "#[cfg_attr(feature = \"dhcp\", allow(dead_code))]";
    let _ = writeln!(
        out,
        "/// The board's IPv4 address (`ARMGATE_IP`; unused with `dhcp`)."
    );
    let _ = writeln!(out, "{unused_with_dhcp}");
    let _ = writeln!(out, "pub const ADDRESS: Ipv4Addr = {};", ipv4(address));
    let _ = writeln!(out, "/// Its network prefix length (`ARMGATE_IP`).");
    let _ = writeln!(out, "{unused_with_dhcp}");
    let _ = writeln!(out, "pub const PREFIX_LEN: u8 = {prefix};");
    let _ = writeln!(out, "/// The default gateway (`ARMGATE_GATEWAY`), if any.");
    let _ = writeln!(out, "{unused_with_dhcp}");
    match gateway {
        Some(g) => {
            let _ = writeln!(
                out,
                "pub const GATEWAY: Option<Ipv4Addr> = Some({});",
                ipv4(g)
            );
        }
        None => {
            let _ = writeln!(out, "pub const GATEWAY: Option<Ipv4Addr> = None;");
        }
    }
    let _ = writeln!(
        out,
        "/// The UDP port of the command protocol (`ARMGATE_PORT`)."
    );
    let _ = writeln!(out, "pub const PORT: u16 = {port};");
    let _ = writeln!(
        out,
        "/// Whether the board's own network may command the arm (`local` in `ARMGATE_ALLOW`)."
    );
    let _ = writeln!(out, "pub const ALLOW_LOCAL: bool = {allow_local};");
    let _ = writeln!(
        out,
        "/// Further networks that may command the arm (`ARMGATE_ALLOW`)."
    );
    let _ = writeln!(out, "pub const ALLOW: &[Network] = &[");
    for (a, p) in &allow {
        let _ = writeln!(
            out,
            "    Network::new(core::net::IpAddr::V4({}), {p}),",
            ipv4(*a)
        );
    }
    let _ = writeln!(out, "];");
    let robot = std::env::var("ROBOT").unwrap_or_else(|_| DEFAULT_ROBOT.to_owned());
    out.push_str(&signing_settings(&robot, &format!("{address}:{port}"))?);
    Ok(out)
}

/// The signing constants: the key of the file `ARMGATE_KEY_FILE` names (none: unsigned, as
/// the seed; set but empty or unreadable fails the build), the controller's id
/// (`ARMGATE_CONTROLLER_ID`, default derived from the robot file's name and `address`, as
/// `armgate-sim` derives its own) and what unsigned datagrams may do (`ARMGATE_ALLOW_UNSIGNED`:
/// no, read, all).
fn signing_settings(robot: &str, address: &str) -> Result<String, String> {
    // Set but empty is a mistake (an unset variable in a script), not a wish to sign nothing.
    println!("cargo:rerun-if-env-changed=ARMGATE_KEY_FILE");
    if std::env::var_os("ARMGATE_KEY_FILE").is_some_and(|v| v.to_string_lossy().trim().is_empty()) {
        return Err(
            "ARMGATE_KEY_FILE is set but empty: name the key file, or unset it to \
                    build a firmware that signs nothing"
                .to_owned(),
        );
    }
    let key = match env("ARMGATE_KEY_FILE") {
        None => None,
        Some(path) => {
            println!("cargo:rerun-if-changed={path}");
            let text = std::fs::read_to_string(&path)
                .map_err(|e| format!("ARMGATE_KEY_FILE: {path}: {e}"))?;
            Some(parse_key(&text).map_err(|e| format!("ARMGATE_KEY_FILE: {path}: {e}"))?)
        }
    };
    let robot_name = Path::new(robot)
        .file_name()
        .unwrap_or_default()
        .to_string_lossy();
    let controller = match env("ARMGATE_CONTROLLER_ID") {
        None => ControllerId::derive(&[&robot_name, address]),
        Some(text) => text
            .parse()
            .map_err(|e| format!("ARMGATE_CONTROLLER_ID: `{text}`: {e}"))?,
    };
    let unsigned: UnsignedAccess = match env("ARMGATE_ALLOW_UNSIGNED") {
        None => UnsignedAccess::default(),
        Some(text) => text
            .parse()
            .map_err(|e| format!("ARMGATE_ALLOW_UNSIGNED: `{text}`: {e}"))?,
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "/// The signing key (`ARMGATE_KEY_FILE`): only datagrams signed with it are served."
    );
    match key {
        Some(bytes) => {
            let _ = writeln!(
                out,
                "pub const SIGNING_KEY: Option<[u8; 32]> = Some({bytes:?});"
            );
        }
        None => {
            let _ = writeln!(out, "pub const SIGNING_KEY: Option<[u8; 32]> = None;");
        }
    }
    let _ = writeln!(
        out,
        "/// This controller's id (`ARMGATE_CONTROLLER_ID`; default from the robot file's name \
         and the address): every signature covers it."
    );
    let _ = writeln!(
        out,
        "pub const CONTROLLER_ID: ControllerId = ControllerId({:#010x});",
        controller.0
    );
    let variant = match unsigned {
        UnsignedAccess::Refused => "Refused",
        UnsignedAccess::Read => "Read",
        UnsignedAccess::All => "All",
    };
    let _ = writeln!(
        out,
        "/// What unsigned datagrams may do while a key is set (`ARMGATE_ALLOW_UNSIGNED`)."
    );
    let _ = writeln!(
        out,
        "pub const ALLOW_UNSIGNED: UnsignedAccess = UnsignedAccess::{variant};"
    );
    Ok(out)
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
