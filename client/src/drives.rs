//! The drives' side of a session: starting them and waiting until they run, and waiting until
//! a motion has ended. Both poll the status request `SQ`; with a controller too old for it they
//! do what can be done without.

use std::time::{Duration, Instant};

use armgate_protocol::client::Notice;

use crate::status::{DriveStatus, Name};
use crate::{Client, ClientError, Motion, Text, WaitOptions, matching};

/// The state named by an `OF` refused because the drives already are where it would take them
/// (`ER10 Arm already off` → `off`, `already stopping` → `stopping`).
pub fn already_stopped(text: &Text) -> Option<&'static str> {
    match Notice::parse(text) {
        Ok(Notice::ArmDidNotStop(state @ (DriveStatus::Off | DriveStatus::Stopping))) => {
            Some(state.name())
        }
        _ => None,
    }
}

/// How often the status is polled.
const POLL: Duration = Duration::from_millis(50);

/// Without `SQ`, how long a refused ON is sent again (the drives may still be stopping).
const RETRY_WITHOUT_STATUS: Duration = Duration::from_secs(1);

/// How ON ended.
#[derive(Debug)]
pub enum DrivesOn {
    /// The drives started and run, after this long.
    Started(Duration),
    /// They were running or starting already, and run (after this long).
    AlreadyRunning(Duration),
    /// ON was accepted, but the controller cannot report the drives (the `TooOld` error).
    Unconfirmed(ClientError),
}

impl Client {
    /// `ON`, then polls `SQ` until the drives run ([`ClientError::NotStarted`] if they fault,
    /// stay off, or do not run within `timeout`).
    ///
    /// ON while they run or start is refused (`ER11`) but is no failure if they end up running.
    /// While they stop (just after `OF`) ON is refused too: it is sent again once they have.
    pub fn start_drives(&mut self, timeout: Duration) -> Result<DrivesOn, ClientError> {
        let started = Instant::now();
        let already = loop {
            match self.on() {
                Ok(()) => break false,
                Err(ClientError::Rejected(text)) if matching::code(&text) == Some(11) => {
                    let retry = match self.status() {
                        Ok(s)
                            if matches!(s.drives, DriveStatus::Running | DriveStatus::Starting) =>
                        {
                            break true;
                        }
                        // Stopping, or stopped since ON was refused.
                        Ok(_) => started.elapsed() < timeout,
                        Err(ClientError::TooOld { .. }) => started.elapsed() < RETRY_WITHOUT_STATUS,
                        Err(e) => return Err(e),
                    };
                    if !retry {
                        return Err(ClientError::Rejected(text));
                    }
                    std::thread::sleep(POLL);
                }
                Err(e) => return Err(e),
            }
        };
        loop {
            let status = match self.status() {
                Ok(status) => status,
                Err(e @ ClientError::TooOld { .. }) => return Ok(DrivesOn::Unconfirmed(e)),
                Err(e) => return Err(e),
            };
            match status.drives {
                DriveStatus::Running if already => {
                    return Ok(DrivesOn::AlreadyRunning(started.elapsed()));
                }
                DriveStatus::Running => return Ok(DrivesOn::Started(started.elapsed())),
                DriveStatus::Faulted | DriveStatus::Off => {
                    return Err(ClientError::NotStarted(status.drives_text()));
                }
                DriveStatus::Starting | DriveStatus::Stopping => {}
            }
            if started.elapsed() > timeout {
                return Err(ClientError::NotStarted(format!(
                    "still {} after {timeout:?}",
                    status.drives_text()
                )));
            }
            std::thread::sleep(POLL);
        }
    }

    /// Polls `SQ` until no motion runs, for at most `timeout` (then returns as well).
    ///
    /// A wait for a pose ends within its tolerance while the motion may still be ending (the
    /// last millimetre of a deceleration); the next motion request would be refused as busy.
    /// A controller without `SQ`: until the pose has not changed for three polls.
    pub fn wait_motion_ended(&mut self, timeout: Duration) -> Result<(), ClientError> {
        let started = Instant::now();
        loop {
            match self.status() {
                Ok(status) if status.motion == Motion::Holding => return Ok(()),
                Ok(_) if started.elapsed() < timeout => std::thread::sleep(POLL),
                Ok(_) => return Ok(()),
                Err(ClientError::TooOld { .. }) => {
                    let options = WaitOptions {
                        timeout,
                        ..WaitOptions::default()
                    };
                    return match self.wait_idle(3, &options) {
                        Ok(_) | Err(ClientError::WaitTimeout { .. }) => Ok(()),
                        Err(e) => Err(e),
                    };
                }
                Err(e) => return Err(e),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::parsed_text;

    #[test]
    fn an_off_refused_because_the_drives_already_stop_names_their_state() {
        assert_eq!(
            already_stopped(&parsed_text("ER10 Arm already off")),
            Some("off")
        );
        assert_eq!(
            already_stopped(&parsed_text("ER10 Arm already stopping")),
            Some("stopping")
        );
        assert_eq!(
            already_stopped(&parsed_text("ER10 Arm stopped by fault")),
            None
        );
        assert_eq!(already_stopped(&parsed_text("ER10 Arm did not stop")), None);
        assert_eq!(already_stopped(&parsed_text("ER11 Arm already on")), None);
    }
}
