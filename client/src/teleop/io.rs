//! The keyboard client's I/O thread: it owns the [`Client`], performs the [`Action`]s the keys
//! produce, polls SQ, PS, jP and TM between them, and reports [`Event`]s. The UI never waits
//! for the network.

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::state::{Action, Event};
use crate::{Client, ClientError};
use armgate_protocol::client::{Notice, Rejection};

/// The channels to a running I/O thread.
#[derive(Debug)]
pub struct Io {
    /// Requests to perform; dropping it ends the thread.
    pub actions: Sender<Action>,
    /// Reports.
    pub events: Receiver<Event>,
    /// The thread.
    pub thread: JoinHandle<()>,
}

/// Starts the I/O thread for an arm with `joints` joints, polling every `poll`.
pub fn spawn(client: Client, joints: usize, poll: Duration) -> std::io::Result<Io> {
    let (actions, action_rx) = mpsc::channel();
    let (event_tx, events) = mpsc::channel();
    let thread = std::thread::Builder::new()
        .name("armgate-teleop-io".into())
        .spawn(move || run(client, joints, poll, &action_rx, &event_tx))?;
    Ok(Io {
        actions,
        events,
        thread,
    })
}

fn run(
    mut client: Client,
    joints: usize,
    poll: Duration,
    actions: &Receiver<Action>,
    events: &Sender<Event>,
) {
    let mut next_poll = Instant::now();
    let mut with_status = true;
    loop {
        let wait = next_poll.saturating_duration_since(Instant::now());
        let reports = match actions.recv_timeout(wait) {
            Ok(action) => perform(&mut client, action),
            Err(RecvTimeoutError::Timeout) => {
                next_poll = Instant::now() + poll;
                read_state(&mut client, joints, &mut with_status)
            }
            Err(RecvTimeoutError::Disconnected) => return,
        };
        let notices = client.take_notices().into_iter().map(Event::Text);
        for event in notices.chain(reports) {
            if events.send(event).is_err() {
                return;
            }
        }
    }
}

/// The event for a failed request: the ER text itself, or a status line.
fn failure(what: &str, error: ClientError) -> Event {
    match error {
        ClientError::Rejected(text) => Event::Text(text),
        other => Event::Status(format!("{what}: {other}")),
    }
}

/// The event for a failed poll: the ER text, or no reply.
fn poll_failure(what: &str, error: ClientError) -> Event {
    match error {
        ClientError::Rejected(text) => Event::Text(text),
        other => Event::NoReply(format!("{what}: {other}")),
    }
}

/// The event for a failed motion request: the refusal, or a status line.
fn move_failure(what: &str, error: ClientError) -> Event {
    match error {
        ClientError::Rejected(text) => Event::Refused(text),
        other => Event::Status(format!("{what}: {other}")),
    }
}

/// SQ (while the controller knows it), PS, jP, TM; stops at the first failure so that an
/// absent controller costs one timeout.
fn read_state(client: &mut Client, joints: usize, with_status: &mut bool) -> Vec<Event> {
    let mut events = Vec::with_capacity(4);
    if *with_status {
        match client.status() {
            Ok(status) => events.push(Event::Controller(status)),
            Err(e @ ClientError::TooOld { .. }) => {
                *with_status = false;
                events.push(Event::Status(format!("{e}: mode and drives unknown")));
            }
            Err(e) => return vec![poll_failure("SQ", e)],
        }
    }
    match client.pose() {
        Ok(pose) => events.push(Event::Pose(pose)),
        Err(e) => {
            events.push(poll_failure("PS", e));
            return events;
        }
    }
    match client.joints(joints) {
        Ok(q) => events.push(Event::Joints(q)),
        Err(e) => {
            events.push(poll_failure("jP", e));
            return events;
        }
    }
    match client.temperatures(joints) {
        Ok(t) => events.push(Event::Temperatures(t)),
        Err(e) => events.push(poll_failure("TM", e)),
    }
    events
}

/// Sends a begin command; if it is refused `busy` (this client's motion is running), sends ST
/// and tries once more. Any other refusal — another client holding the arm (`ER40`) among
/// them — is reported, never stopped through.
fn begin_or_restart(
    client: &mut Client,
    begin: fn(&mut Client) -> Result<Option<Duration>, ClientError>,
) -> Result<bool, ClientError> {
    match begin(client) {
        Ok(_) => Ok(false),
        Err(ClientError::Rejected(text))
            if matches!(
                Notice::parse(&text),
                Ok(Notice::Rejected(_, Rejection::Busy))
            ) =>
        {
            client.stop()?;
            begin(client).map(|_| true)
        }
        Err(e) => Err(e),
    }
}

/// Performs one action.
pub fn perform(client: &mut Client, action: Action) -> Vec<Event> {
    let status = |restarted: bool, what: &str| {
        Event::Started(if restarted {
            format!("{what} (was refused: sent ST and retried)")
        } else {
            what.to_owned()
        })
    };
    match action {
        Action::MoveCartesian { xyz, rpy } => {
            if let Err(e) = client.goal_rpy(xyz, rpy, 0.0) {
                return vec![move_failure("GT", e)];
            }
            match begin_or_restart(client, Client::begin) {
                Ok(restarted) => vec![status(restarted, "sent GT + BG")],
                Err(e) => vec![move_failure("BG", e)],
            }
        }
        Action::MoveJoints(q) => {
            if let Err(e) = client.joint_goal(&q) {
                return vec![move_failure("jG", e)];
            }
            match begin_or_restart(client, Client::joint_begin) {
                Ok(restarted) => vec![status(restarted, "sent jG + jB")],
                Err(e) => vec![move_failure("jB", e)],
            }
        }
        Action::SetMode(mode) => match client.set_mode(mode) {
            Ok(reported) => vec![Event::Mode(reported)],
            Err(e) => vec![failure("CM", e), Event::ModeFailed],
        },
        Action::Stop => match client.stop() {
            Ok(()) => vec![status(false, "stopped (ST)")],
            Err(e) => vec![failure("ST", e)],
        },
        Action::DrivesOn => match client.on() {
            Ok(()) => vec![status(false, "drives on (ON)")],
            Err(e) => vec![failure("ON", e)],
        },
        // One command; a held key's stream is the UI's (`VelocityStreamer`).
        Action::Jog(velocity) => match client.velocity(&velocity) {
            Ok(_) => vec![status(false, "jog")],
            Err(e) => vec![move_failure("jog", e)],
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::{FakeController, echo, text};
    use crate::{ClientConfig, Command, Mode, Reply};
    use std::sync::{Arc, Mutex};

    fn client(fake: &FakeController) -> Client {
        client_with(fake, Duration::from_secs(1))
    }

    fn client_with(fake: &FakeController, timeout: Duration) -> Client {
        Client::connect_with(
            fake.addr(),
            ClientConfig {
                timeout,
                retries: 0,
                ..ClientConfig::default()
            },
        )
        .unwrap()
    }

    /// Refuses the first BG/jB, accepts the rest, echoes everything else.
    fn busy_arm() -> FakeController {
        let refused = Arc::new(Mutex::new(false));
        FakeController::spawn(move |d| {
            let chars = &d[..2];
            if (chars == b"BG" || chars == b"jB")
                && !std::mem::replace(&mut *refused.lock().unwrap(), true)
            {
                return vec![text(&format!(
                    "ER20 Cmd {} busy",
                    String::from_utf8_lossy(chars)
                ))];
            }
            vec![echo(d)]
        })
    }

    fn sent(fake: &FakeController) -> Vec<String> {
        fake.received()
            .iter()
            .map(|d| String::from_utf8_lossy(&d[..2]).into_owned())
            .collect()
    }

    #[test]
    fn a_refused_begin_is_retried_once_after_st() {
        let fake = busy_arm();
        let mut c = client(&fake);
        let events = perform(
            &mut c,
            Action::MoveCartesian {
                xyz: [0.5, 0.2, 0.1],
                rpy: [0.0; 3],
            },
        );
        assert_eq!(sent(&fake), ["GT", "BG", "ST", "BG"]);
        assert_eq!(
            events,
            [Event::Started(
                "sent GT + BG (was refused: sent ST and retried)".into()
            )]
        );
        let events = perform(&mut c, Action::MoveJoints(vec![0.0; 6]));
        assert_eq!(sent(&fake)[4..], ["jG", "jB"]);
        assert_eq!(events, [Event::Started("sent jG + jB".into())]);
    }

    /// A Cartesian move against a controller that refuses every BG with `refusal`: what was
    /// sent, and the events.
    fn move_refused_with(refusal: &'static str) -> (Vec<String>, Vec<Event>) {
        let fake = FakeController::spawn(move |d| {
            if &d[..2] == b"BG" {
                vec![text(refusal)]
            } else {
                vec![echo(d)]
            }
        });
        let mut c = client(&fake);
        let events = perform(
            &mut c,
            Action::MoveCartesian {
                xyz: [0.5, 0.2, 0.1],
                rpy: [0.0; 3],
            },
        );
        (sent(&fake), events)
    }

    #[test]
    fn a_second_refusal_is_shown_as_the_text() {
        let (sent, events) = move_refused_with("ER20 Cmd BG busy");
        assert_eq!(sent, ["GT", "BG", "ST", "BG"]);
        assert!(matches!(&events[..], [Event::Refused(t)] if t.as_str() == "ER20 Cmd BG busy"));
    }

    #[test]
    fn another_clients_arm_is_never_stopped_through() {
        let (sent, events) = move_refused_with("ER40 Cmd BG by 192.168.1.2");
        assert_eq!(sent, ["GT", "BG"]);
        assert!(
            matches!(&events[..], [Event::Refused(t)] if t.as_str() == "ER40 Cmd BG by 192.168.1.2")
        );
    }

    #[test]
    fn polling_reports_pose_joints_and_temperatures_and_notices() {
        let fake = FakeController::spawn(|d| {
            let mut out = vec![];
            let reply = match &d[..2] {
                b"SQ" => {
                    let numbers = [2.0, 2.0, 0.0, 6.0, 0.0, 0.0, 1.0];
                    return vec![crate::status::tests::status_reply(d, numbers, "r")];
                }
                b"PS" => {
                    out.push(text("WN12 Joint limit."));
                    let mut r = Reply::null(Command::Pose);
                    r.values = [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 1.0];
                    r
                }
                b"jP" => Reply::null(Command::JointPosition),
                b"CM" => {
                    let mut r = Reply::null(Command::ChangeMode);
                    r.values[0] = 2.0;
                    r
                }
                _ => Reply::null(Command::Temperature),
            };
            out.push(reply.to_bytes().to_vec());
            out
        });
        let io = spawn(client(&fake), 6, Duration::from_millis(20)).unwrap();
        let mut seen = (false, false, false, false);
        let deadline = Instant::now() + Duration::from_secs(2);
        while Instant::now() < deadline && seen != (true, true, true, true) {
            match io.events.recv_timeout(Duration::from_millis(100)) {
                Ok(Event::Pose(p)) => seen.0 = (p.xyz[0] - 0.5).abs() < 1e-6,
                Ok(Event::Joints(q)) => seen.1 = q.len() == 6,
                Ok(Event::Temperatures(t)) => seen.2 = t.len() == 6,
                Ok(Event::Text(t)) => seen.3 = t.as_str() == "WN12 Joint limit.",
                _ => {}
            }
        }
        assert_eq!(seen, (true, true, true, true));
        io.actions.send(Action::SetMode(Mode::Cartesian)).unwrap();
        let deadline = Instant::now() + Duration::from_secs(2);
        let mut mode = None;
        while Instant::now() < deadline && mode.is_none() {
            if let Ok(Event::Mode(m)) = io.events.recv_timeout(Duration::from_millis(100)) {
                mode = Some(m);
            }
        }
        assert_eq!(mode, Some(Mode::Cartesian));
        drop(io.actions);
        io.thread.join().unwrap();
    }

    #[test]
    fn an_absent_controller_is_a_status_line() {
        let fake = FakeController::spawn(|_| vec![]);
        let mut c = client_with(&fake, Duration::from_millis(50));
        let mut with_status = true;
        let events = read_state(&mut c, 6, &mut with_status);
        assert!(matches!(&events[..], [Event::NoReply(s)] if s.starts_with("SQ: no reply")));
        // A controller without SQ is polled without it.
        let old = FakeController::spawn(|d| match &d[..2] {
            b"SQ" => vec![text("ER00 Cmd SQ not understood")],
            _ => vec![],
        });
        let mut c = client_with(&old, Duration::from_millis(50));
        let mut fresh = true;
        let events = read_state(&mut c, 6, &mut fresh);
        assert!(!fresh);
        assert!(
            matches!(&events[..], [Event::Status(s), Event::NoReply(p)] if s.contains("too old") && p.starts_with("PS: no reply")),
            "{events:?}"
        );
    }
}
