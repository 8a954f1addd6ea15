//! `armgate send`: any request, and its reply printed raw (the seed's text client).

use std::io::Write;

use clap::Args;

use super::CliError;
use crate::Client;

/// `armgate send` arguments.
#[derive(Debug, Args)]
pub struct SendArgs {
    /// The two command characters, case-sensitive (PS, GT, jV, ...).
    pub chars: String,
    /// f0..f6; missing values are sent as 0.
    #[arg(num_args = 0..=7, allow_negative_numbers = true)]
    pub values: Vec<f32>,
    /// The index byte (via slot; bit 7 = joint bank 2).
    #[arg(long, short, default_value_t = 0)]
    pub index: u8,
}

/// Sends the request and prints the reply, or fails with the ER/WN text.
pub(super) fn send(
    args: &SendArgs,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let SendArgs {
        chars,
        values,
        index,
    } = args;
    let index = *index;
    let pair: [u8; 2] = chars
        .as_bytes()
        .try_into()
        .ok()
        .filter(|p: &[u8; 2]| p.iter().all(u8::is_ascii_graphic))
        .ok_or_else(|| CliError::Usage(format!("`{chars}`: give two command characters")))?;
    let mut all = [0.0; 7];
    all.iter_mut().zip(values).for_each(|(a, v)| *a = *v);
    let reply = client.send_raw(pair, all, index)?;
    let values: Vec<String> = reply.values.iter().map(|v| format!("{v:.6}")).collect();
    writeln!(
        out,
        "{}  {}  index {}",
        String::from_utf8_lossy(&reply.chars),
        values.join(" "),
        reply.index
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::testing::run_with;
    use crate::fake::{FakeController, text};
    use armgate_protocol::client::{Command, Reply};

    #[test]
    fn send_prints_the_reply_or_the_text() {
        let fake = FakeController::spawn(|d| {
            if &d[..2] == b"PS" {
                let mut r = Reply::null(Command::Pose);
                r.values = [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 1.0];
                vec![r.to_bytes().to_vec()]
            } else {
                vec![text("ER00 Cmd XY not understood")]
            }
        });
        let (result, out) = run_with(&fake, &["send", "PS"]);
        result.unwrap();
        assert_eq!(
            out,
            "SP  0.500000 0.200000 0.100000 0.000000 0.000000 0.000000 1.000000  index 0\n"
        );
        let (result, _) = run_with(&fake, &["send", "XY"]);
        let err = result.unwrap_err();
        assert_eq!(err.to_string(), "ER00 Cmd XY not understood");
        assert_eq!(err.exit_code(), 1);
    }
}
