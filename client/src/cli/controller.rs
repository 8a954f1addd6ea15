//! The options that say how to reach the controller. `armgate --addr A status` and `armgate
//! status --addr A` both work: every subcommand that talks to the controller has them too, and
//! what is typed after the subcommand overrides what is typed before it. The offline
//! subcommands (`plot`, `calibrate`, `urdf`) and `record` (whose tool takes its own) do not
//! list options that mean nothing there.

use std::ffi::OsString;
use std::path::PathBuf;
use std::time::Duration;

use clap::parser::ValueSource;
use clap::{ArgMatches, Args, Command, CommandFactory, FromArgMatches, Parser};

use super::options::{parse_joints, parse_timeout};
use super::{Cli, Cmd, Parsed};
use crate::{DEFAULT_ADDR, DEFAULT_RETRIES};

/// The subcommands without the controller options (options before them are accepted, as
/// before any subcommand; `record` passes on the address and the key typed there).
const WITHOUT: [&str; 4] = ["plot", "calibrate", "urdf", "record"];

/// The subcommands that need the joint count (--joints).
const JOINT_COUNT: [&str; 6] = ["joints", "temps", "jmove", "jog", "run", "teleop"];

/// How to reach the controller.
#[derive(Clone, Debug, Args)]
pub struct ControllerArgs {
    /// The controller's address, host:port.
    #[arg(long, env = "ARMGATE_ADDR", default_value = DEFAULT_ADDR)]
    pub addr: String,
    /// How long to wait for each reply: 200ms, 1s, 1.5s, or a number of milliseconds (> 0).
    #[arg(long, default_value = "200ms", value_parser = parse_timeout)]
    pub timeout: Duration,
    /// How many times a request is sent again when no reply came.
    #[arg(long, default_value_t = DEFAULT_RETRIES)]
    pub retries: u32,
    /// How many joints the arm has, 1 to 8. Default: what the controller's status (SQ) says,
    /// 6 if it is too old to say. Joint lists must have this many values; more than 6 joints
    /// use the two-bank requests.
    #[arg(long, value_parser = parse_joints)]
    pub joints: Option<usize>,
    /// Sign every request with the key in this file (64 hex digits on one line) and accept
    /// only answers signed with it, for a controller that has the key (docs/safety.md).
    #[arg(long, env = "ARMGATE_KEY_FILE", value_name = "FILE")]
    pub key: Option<std::path::PathBuf>,
    /// With --key: the link id to sign with, 1..=255; clients that run at the same time need
    /// their own (teleop also uses the next one, for its jog stream). Default: a free one the
    /// controller sets aside (printed).
    #[arg(long, env = "ARMGATE_LINK_ID")]
    pub link_id: Option<u8>,
    /// With --key: the controller's id (8 hex digits, as armgate-sim and the firmware print it
    /// at start); signatures for one controller are forged to every other. Default: the id the
    /// controller names in its first signed answer (SQ index 6).
    #[arg(long, env = "ARMGATE_CONTROLLER_ID", value_name = "HEX")]
    pub controller_id: Option<armgate_protocol::client::signed::ControllerId>,
}

/// The value of `id` if it was typed on the command line (not from the environment or a
/// default, and not an option this (sub)command lacks).
fn typed<T: Clone + Send + Sync + 'static>(matches: &ArgMatches, id: &str) -> Option<T> {
    let known = matches.try_contains_id(id).unwrap_or(false);
    (known && matches.value_source(id) == Some(ValueSource::CommandLine))
        .then(|| matches.get_one::<T>(id).cloned())
        .flatten()
}

impl ControllerArgs {
    /// Takes over what was typed in `given`, a subcommand's matches.
    fn override_from(&mut self, given: &ArgMatches) {
        if let Some(addr) = typed(given, "addr") {
            self.addr = addr;
        }
        if let Some(timeout) = typed(given, "timeout") {
            self.timeout = timeout;
        }
        if let Some(retries) = typed(given, "retries") {
            self.retries = retries;
        }
        if let Some(joints) = typed(given, "joints") {
            self.joints = Some(joints);
        }
        if let Some(key) = typed(given, "key") {
            self.key = Some(key);
        }
        if let Some(link_id) = typed(given, "link_id") {
            self.link_id = Some(link_id);
        }
        if let Some(id) = typed(given, "controller_id") {
            self.controller_id = Some(id);
        }
    }

    /// The options typed before `record`, as `armgate-viz record` takes them (it reads the
    /// same environment variables itself, and the options typed after `record`).
    fn for_record(matches: &ArgMatches) -> Vec<OsString> {
        let mut args = Vec::new();
        if let Some(addr) = typed::<String>(matches, "addr") {
            args.extend(["--addr".into(), addr.into()]);
        }
        if let Some(key) = typed::<PathBuf>(matches, "key") {
            args.extend(["--key".into(), key.into_os_string()]);
        }
        if let Some(link_id) = typed::<u8>(matches, "link_id") {
            args.extend(["--link-id".into(), link_id.to_string().into()]);
        }
        if let Some(id) =
            typed::<armgate_protocol::client::signed::ControllerId>(matches, "controller_id")
        {
            args.extend(["--controller-id".into(), id.to_string().into()]);
        }
        args
    }
}

impl CommandFactory for Cli {
    fn command() -> Command {
        Parsed::command().mut_subcommands(|sub| {
            if WITHOUT.contains(&sub.get_name()) {
                sub
            } else {
                // The arguments only: augmenting `sub` itself would replace its description.
                let options = ControllerArgs::augment_args(Command::new("armgate"));
                let uses_joints = JOINT_COUNT.contains(&sub.get_name());
                let options = options
                    .get_arguments()
                    .filter(|a| uses_joints || a.get_id() != "joints")
                    .cloned()
                    .collect::<Vec<_>>();
                sub.args(options)
            }
        })
    }

    fn command_for_update() -> Command {
        Self::command()
    }
}

impl FromArgMatches for Cli {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let Parsed {
            mut controller,
            command,
        } = Parsed::from_arg_matches(matches)?;
        let mut command = command;
        match (matches.subcommand(), &mut command) {
            (_, Cmd::Record { args }) => {
                args.splice(0..0, ControllerArgs::for_record(matches));
            }
            (Some((_, sub)), _) => controller.override_from(sub),
            _ => {}
        }
        Ok(Self {
            controller,
            command,
        })
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl Parser for Cli {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_subcommands_that_talk_to_the_controller_take_its_options() {
        let command = Cli::command();
        for name in WITHOUT {
            let sub = command.find_subcommand(name).expect(name);
            assert!(sub.get_arguments().all(|a| a.get_id() != "addr"), "{name}");
        }
        let with = command
            .get_subcommands()
            .filter(|sub| sub.get_arguments().any(|a| a.get_id() == "addr"))
            .count();
        assert_eq!(with + WITHOUT.len(), command.get_subcommands().count());
        // --joints only where the joint count matters.
        for sub in command.get_subcommands() {
            let joints = sub.get_arguments().any(|a| a.get_id() == "joints");
            assert_eq!(
                joints,
                JOINT_COUNT.contains(&sub.get_name()),
                "{}",
                sub.get_name()
            );
        }
    }

    #[test]
    fn options_after_the_subcommand_override_those_before_it() {
        let parse = |argv: &[&str]| Cli::try_parse_from(argv).unwrap().controller;
        let before = [
            "armgate",
            "--addr",
            "10.0.0.1:7031",
            "--retries",
            "5",
            "pose",
        ];
        let c = parse(&before);
        assert_eq!((c.addr.as_str(), c.retries), ("10.0.0.1:7031", 5));
        let c = parse(&[&before[..], &["--addr", "10.0.0.2:7031"]].concat());
        assert_eq!((c.addr.as_str(), c.retries), ("10.0.0.2:7031", 5));
        let c = parse(&["armgate", "joints", "--timeout", "1s", "--joints", "7"]);
        assert_eq!((c.timeout, c.joints), (Duration::from_secs(1), Some(7)));
        assert_eq!(c.addr, DEFAULT_ADDR);
        // The offline subcommands refuse them after their name.
        assert!(Cli::try_parse_from(["armgate", "plot", "logs", "--addr", "a:1"]).is_err());
        assert!(Cli::try_parse_from(["armgate", "pose", "--joints", "7"]).is_err());
        assert!(Cli::try_parse_from(["armgate", "--joints", "7", "pose"]).is_ok());
        assert!(Cli::try_parse_from(["armgate", "--addr", "a:1", "plot", "logs"]).is_ok());
        // `record` gets those typed before it, and its own after it.
        let cli = Cli::try_parse_from([
            "armgate",
            "--addr",
            "a:1",
            "--retries",
            "1",
            "record",
            "x.mcap",
            "--rate",
            "5",
        ])
        .unwrap();
        let Cmd::Record { args } = cli.command else {
            panic!()
        };
        assert_eq!(args, ["--addr", "a:1", "x.mcap", "--rate", "5"]);
    }
}
