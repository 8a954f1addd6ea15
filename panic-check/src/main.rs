//! Link-time proof that no panic path survives optimisation in what the firmware runs every
//! cycle and on every datagram: the control cycle `Cycle::tick` (drive manager receive, command
//! handler tick with the controller, IK and limiter, drive manager transmit, request handling,
//! notices) and request parsing.
//!
//! The technique of the `panic-never` crate: the panic handler calls a function that exists
//! nowhere, so the release build (LTO, as the firmware's) links only if the optimiser removed
//! every call to the panic handler. Every input comes through `black_box`, so nothing is
//! constant-folded away that a real input could reach. A failed link names the symbol
//! `armgate_panic_path_survived_optimisation`; `cargo build` in debug (no optimisation) is
//! expected to fail and is not the check.
//!
//! ```text
//! cargo build -p armgate-panic-check --target thumbv7em-none-eabihf --release
//! ```
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod proof;

/// On the host there is nothing to prove: the binary is empty.
#[cfg(not(target_os = "none"))]
fn main() {}
