//! What the subcommands' tests share: running a command line against a fake controller.

use super::{Cli, CliError, run};
use crate::fake::FakeController;
use crate::status::tests::status_reply;
use armgate_protocol::client::{Message, Reply, Request};
use clap::Parser;

/// SQ numbers: Cartesian mode, drives running, no fault, 6 joints, idle.
pub(super) const RUNNING_CART: [f32; 7] = [2.0, 2.0, 0.0, 6.0, 0.0, 0.0, 1.0];

pub(super) fn run_with(fake: &FakeController, args: &[&str]) -> (Result<(), CliError>, String) {
    let addr = fake.addr().to_string();
    let mut argv = vec!["armgate", "--addr", addr.as_str(), "--timeout", "1s"];
    argv.extend_from_slice(args);
    let cli = Cli::try_parse_from(argv).unwrap();
    let mut out = Vec::new();
    let result = run(&cli, &mut out);
    (result, String::from_utf8(out).unwrap())
}

/// A ranger-mk1 running in Cartesian mode: the status `RUNNING_CART`, and to any other
/// request the null reply with the request's index, as `answer` fills it in.
pub(super) fn cartesian_controller(
    answer: impl Fn(&Request, &mut Reply) + Send + 'static,
) -> FakeController {
    FakeController::spawn(move |d| {
        if &d[..2] == b"SQ" {
            return vec![status_reply(d, RUNNING_CART, "ranger-mk1")];
        }
        let m = Message::new_checked(d).unwrap();
        let r = Request::parse(&m).unwrap();
        let mut reply = Reply::null(r.command);
        reply.index = r.index;
        answer(&r, &mut reply);
        vec![reply.to_bytes().to_vec()]
    })
}
