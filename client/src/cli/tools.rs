//! Starting the separate tools: `armgate calibrate`, `urdf` and `record` pass their arguments
//! on unchanged (crate::tools finds and runs the tool); `record` also the controller options
//! typed before it (see `controller`).

use std::ffi::OsString;

use super::Cmd;
use crate::tools::{CALIBRATE, VIZ};

/// The exit status of the tool the command runs, or `None` for a command of this client.
pub(super) fn run(command: &Cmd) -> Option<u8> {
    Some(match command {
        Cmd::Calibrate { args } => crate::tools::run(CALIBRATE, args),
        Cmd::Urdf { args } => {
            let args = [&[OsString::from("urdf")], args.as_slice()].concat();
            crate::tools::run(VIZ, &args)
        }
        Cmd::Record { args } => {
            let args = [&[OsString::from("record")], args.as_slice()].concat();
            crate::tools::run(VIZ, &args)
        }
        _ => return None,
    })
}
