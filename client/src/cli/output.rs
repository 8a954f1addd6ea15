//! What the motion commands print while and after they wait: the progress line on stderr,
//! joint and position values, and the start and end of a motion's wait (ST when a command
//! leaves before the motion it started has ended).

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

use super::CliError;
use crate::{Client, ClientError, Pose, Progress, StopPolicy, Text};

/// A command that leaves before it saw the motion it started end (a wait that timed out,
/// stalled or was interrupted; a controller that stopped answering) sends ST first, and says so
/// ([`Client::end_wait`]): otherwise the arm goes on alone, and the next client is refused
/// (`ER40`) until it ends. A wait of the library has done so already.
pub(super) fn stop_started(client: &mut Client, error: ClientError) -> CliError {
    finish_progress();
    CliError::Client(client.end_wait(error, StopPolicy::Always))
}

/// Sends the request(s) that start a motion. When the starting request's replies are all lost,
/// the motion may have started: [`stop_started`].
pub(super) fn start<T>(
    client: &mut Client,
    request: impl FnOnce(&mut Client) -> Result<T, ClientError>,
) -> Result<T, CliError> {
    request(client).map_err(|e| match e {
        ClientError::Timeout { .. } | ClientError::Unverified { .. } => stop_started(client, e),
        e => e.into(),
    })
}

/// Waits for the motion this command started (`wait`, whose progress goes to the progress
/// line), then until it has ended ([`settle`]); on any failure [`stop_started`].
pub(super) fn follow<T>(
    client: &mut Client,
    wait: impl FnOnce(&mut Client) -> Result<T, ClientError>,
) -> Result<T, CliError> {
    let result = wait(client).and_then(|reached| {
        finish_progress();
        client.wait_motion_ended(SETTLE).map(|()| reached)
    });
    result.map_err(|e| stop_started(client, e))
}

/// After a wait: how long to wait until the motion has ended (see [`Client::wait_motion_ended`]).
const SETTLE: Duration = Duration::from_secs(5);

/// After a wait: until the motion has ended.
pub(super) fn settle(client: &mut Client) -> Result<(), CliError> {
    Ok(client.wait_motion_ended(SETTLE)?)
}

pub(super) fn fmt_values(values: &[f64], decimals: usize) -> String {
    let parts: Vec<String> = values.iter().map(|v| format!("{v:.decimals$}")).collect();
    parts.join(" ")
}

/// The state of the progress line on stderr.
struct ProgressLine {
    tty: bool,
    last: Option<Instant>,
}

thread_local! {
    static PROGRESS: std::cell::RefCell<ProgressLine> = std::cell::RefCell::new(ProgressLine {
        tty: std::io::stderr().is_terminal(),
        last: None,
    });
}

/// Prints a progress line: rewritten in place on a terminal, once a second otherwise.
fn progress_line(line: &str, notices: &[Text]) {
    PROGRESS.with_borrow_mut(|p| {
        let mut err = std::io::stderr().lock();
        for notice in notices {
            if p.tty && p.last.is_some() {
                let _ = writeln!(err);
            }
            let _ = writeln!(err, "notice: {notice}");
        }
        if p.tty {
            let _ = write!(err, "\r\x1b[2K{line}");
            let _ = err.flush();
            p.last = Some(Instant::now());
        } else if p.last.is_none_or(|t| t.elapsed() >= Duration::from_secs(1)) {
            let _ = writeln!(err, "{line}");
            p.last = Some(Instant::now());
        }
    });
}

/// Ends the progress line.
fn finish_progress() {
    PROGRESS.with_borrow_mut(|p| {
        if p.tty && p.last.is_some() {
            eprintln!();
        }
        p.last = None;
    });
}

pub(super) fn pose_progress(p: &Progress<'_, Pose>) {
    let [x, y, z] = p.current.xyz;
    let point = if p.targets > 1 {
        format!("point {}/{}: ", p.target + 1, p.targets)
    } else {
        String::new()
    };
    let angle = p.angle.map_or(String::new(), |a| format!(", {a:.3} rad"));
    progress_line(
        &format!(
            "{point}{:8.1} mm{angle} to go   at x {x:.4} y {y:.4} z {z:.4}   {:.1} s",
            p.distance * 1e3,
            p.elapsed.as_secs_f64()
        ),
        p.notices,
    );
}

pub(super) fn joint_progress(p: &Progress<'_, [f64]>) {
    let point = if p.targets > 1 {
        format!("point {}/{}: ", p.target + 1, p.targets)
    } else {
        String::new()
    };
    progress_line(
        &format!(
            "{point}{:8.1} mrad to go   at {}   {:.1} s",
            p.distance * 1e3,
            fmt_values(p.current, 3),
            p.elapsed.as_secs_f64()
        ),
        p.notices,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::{FakeController, echo};

    #[test]
    fn a_wait_that_fails_sends_st_and_keeps_its_exit_status() {
        let fake = FakeController::spawn(|d| vec![echo(d)]);
        let mut client = Client::connect(fake.addr()).unwrap();
        let err = stop_started(&mut client, ClientError::Interrupted);
        assert_eq!(
            err.to_string(),
            "interrupted; sent ST: the arm stops and holds"
        );
        assert_eq!(err.exit_code(), 130);
        assert_eq!(&fake.received()[0][..2], b"ST");
        let timeout = ClientError::WaitTimeout {
            target: 0,
            distance: 0.25,
            angle: None,
            timeout: Duration::from_secs(1),
        };
        let err = stop_started(&mut client, timeout);
        assert_eq!(
            err.to_string(),
            "target 1 not reached within 1s (still 0.2500 (joint norm) from it); sent ST: the arm \
             stops and holds"
        );
        assert_eq!(err.exit_code(), crate::exit::NOT_ARRIVED);
        // The controller ended it: not stopped again.
        let err = stop_started(
            &mut client,
            ClientError::Aborted(crate::fake::parsed_text("WN22 Inv Kin Divergence.")),
        );
        assert_eq!(err.exit_code(), crate::exit::STOPPED);
        assert_eq!(fake.received().len(), 2);
        assert!(fake.received().iter().all(|d| &d[..2] == b"ST"));
    }
}
