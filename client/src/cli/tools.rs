//! Starting the separate tools: `armgate calibrate`, `urdf` and `record` pass their arguments
//! on unchanged (crate::tools finds and runs the tool).

use std::ffi::OsString;

use super::{Cli, Cmd};
use crate::tools::{CALIBRATE, VIZ};

/// The exit status of the tool the command runs, or `None` for a command of this client.
pub(super) fn run(cli: &Cli) -> Option<u8> {
    Some(match &cli.command {
        Cmd::Calibrate { args } => crate::tools::run(CALIBRATE, args),
        Cmd::Urdf { args } => {
            let args = [&[OsString::from("urdf")], args.as_slice()].concat();
            crate::tools::run(VIZ, &args)
        }
        Cmd::Record { args } => {
            let head = ["record", "--addr", cli.addr.as_str()].map(OsString::from);
            crate::tools::run(VIZ, &[&head[..], args].concat())
        }
        _ => return None,
    })
}
