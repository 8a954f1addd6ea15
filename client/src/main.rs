//! `armgate`: command an armgate controller from the command line. See `armgate --help`.

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(armgate_client::cli::main())
}
