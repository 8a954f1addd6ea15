//! What to do about a refusal: from the reason in the refusal's text (`ER20 Cmd BG drives off`,
//! docs/protocol.md), else from the controller's state (`SQ`), else a list of what the command
//! needs (a controller that gives neither).
//!
//! The reason and the state cannot guess wrong: with the drives off or faulted no motion
//! starts whatever the mode, so the hint is `armgate on`; while they start, waiting is.

use armgate_protocol::client::{Command, Header, Notice, Rejection};

use crate::status::{DriveStatus, Motion, Name, Status};
use crate::{Mode, Text};

/// The code of `ER20`, the refusals with a reason.
const REJECTED: u8 = 20;

/// The code of `ER40`: another client holds the moving arm.
const HELD_BY_OTHER: u8 = 40;

/// The hint for `ER40`: the holder with its port (the text has no room for it), and what to do.
fn holder_hint(status: &Status) -> Option<String> {
    let holder = status.holder_text()?;
    Some(format!(
        "{holder} holds the arm while it moves: wait until its motion ends (`armgate status` \
         shows it), or stop it with `armgate stop` (obeyed from any client); then the next \
         request takes control"
    ))
}

/// A hint for a refusal, if there is one to give.
pub fn hint(text: &Text, status: Option<&Status>) -> Option<String> {
    let header = Header::parse(text).ok()?;
    let command = header.command.and_then(Command::from_chars);
    if let Ok(Notice::Rejected(_, why)) = Notice::parse(text)
        && let Some(h) = reason_hint(why)
    {
        return Some(h);
    }
    if let Some(status) = status {
        if header.code == HELD_BY_OTHER {
            return holder_hint(status);
        }
        if let Some(h) = drive_hint(status, header.code) {
            return Some(h);
        }
        if header.code == REJECTED {
            return state_hint(command, status);
        }
        return None;
    }
    text_hint(&header, command)
}

/// The hint when the drives are the reason (any refusal but ON's and OF's own).
fn drive_hint(status: &Status, code: u8) -> Option<String> {
    match (status.drives, code) {
        (DriveStatus::Running, _) | (_, 10 | 11) => None,
        (DriveStatus::Off, _) => Some("the drives are off: start them with `armgate on`".into()),
        (DriveStatus::Faulted, _) => Some(format!(
            "the drives stopped on a fault ({}): `armgate on` clears it and restarts them",
            status.drives_text()
        )),
        (DriveStatus::Starting, _) => {
            Some("the drives are still starting: try again in a moment (`armgate on` waits)".into())
        }
        (DriveStatus::Stopping, _) => {
            Some("the drives are stopping: `armgate on` restarts them".into())
        }
    }
}

/// The request's two characters, for a message.
fn chars(command: Command) -> String {
    String::from_utf8_lossy(&command.chars()).into_owned()
}

/// The hint for `ER20` with the drives running: the mode, a running motion, a missing goal.
fn state_hint(command: Option<Command>, status: &Status) -> Option<String> {
    let busy = || {
        (status.motion != Motion::Holding).then(|| {
            format!(
                "a {} is running: wait for it or `armgate stop`",
                status.motion.name()
            )
        })
    };
    let Some(command) = command else {
        return busy();
    };
    let needs = |mode: Mode| {
        (status.mode != mode).then(|| {
            format!(
                "{} needs mode {1}, the mode is {2}: `armgate mode {1}`",
                chars(command),
                mode.name(),
                status.mode.name()
            )
        })
    };
    let goal = || match command {
        Command::Begin | Command::ViaExecute => {
            Some("no goal or via point 0 stored (GT / VP 0 first)".into())
        }
        Command::JointBegin | Command::JointExecute => {
            Some("no joint goal or via point 0 stored (jG / jV 0 first)".into())
        }
        _ => None,
    };
    match Mode::required_by(command) {
        Some(mode) => needs(mode).or_else(busy).or_else(goal),
        None => busy(),
    }
}

/// The hint for the reason an `ER20` gives (docs/protocol.md).
fn reason_hint(why: Rejection) -> Option<String> {
    Some(match why {
        Rejection::Drives(DriveStatus::Off | DriveStatus::Stopping | DriveStatus::Faulted)
        | Rejection::DriveFault(_) => {
            "start the drives with `armgate on` (it also clears a fault)".into()
        }
        Rejection::Drives(DriveStatus::Starting) => {
            "the drives are still starting: try again in a moment (`armgate on` waits for them)"
                .into()
        }
        Rejection::DrivesSettling => {
            "the drives still follow the last set-points: try again in a moment".into()
        }
        Rejection::NeedsMode(mode) => {
            format!("switch the mode first: `armgate mode {}`", mode.name())
        }
        Rejection::Busy => "a motion is running: wait for it or `armgate stop`".into(),
        Rejection::NoGoal => {
            "store a goal first (`armgate send GT ...` / jG), or use `armgate move` / `jmove`"
                .into()
        }
        Rejection::NoViaPoint => "store via point 0 first (VP / jV), or use `armgate run`".into(),
        Rejection::HolderChanged => {
            "another client took control since your goal or via points: send them again".into()
        }
        Rejection::Stopped(_) => {
            "the arm was stopped: send a zero velocity to resume streaming (`armgate jog` does)"
                .into()
        }
        Rejection::Drives(DriveStatus::Running) | Rejection::NoMeasurement => return None,
    })
}

/// The hint from the refusal alone (an older controller: `ER20 Cmd XX rejected`, no `SQ`).
fn text_hint(header: &Header<'_>, command: Option<Command>) -> Option<String> {
    if header.code != REJECTED || header.detail != "rejected" {
        return None;
    }
    let mode = match Mode::required_by(command?)? {
        Mode::Cartesian => "Cartesian mode (`armgate mode cart`)",
        Mode::Joint => "joint mode (`armgate mode joint`)",
        Mode::Off => "mode off (`armgate mode off`)",
    };
    Some(format!(
        "needs {mode}, running drives (`armgate on`), a goal, and no motion running (`armgate stop`)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::parsed_text;

    fn status(mode: Mode, drives: DriveStatus, fault: u8, motion: Motion) -> Status {
        Status {
            mode,
            drives,
            fault,
            joints: 6,
            motion,
            refused: 1,
            uptime: 3.0,
            name: "ranger-mk1".into(),
            cause: None,
            session: None,
        }
    }

    fn hint_for(text: &str, s: Option<Status>) -> String {
        hint(&parsed_text(text), s.as_ref()).unwrap_or_default()
    }

    #[test]
    fn drives_off_or_faulted_hint_at_on_whatever_the_mode() {
        let off = status(Mode::Off, DriveStatus::Off, 0, Motion::Holding);
        let faulted = status(Mode::Cartesian, DriveStatus::Faulted, 31, Motion::Holding);
        for text in [
            "ER20 Cmd BG rejected",
            "ER20 Cmd RC rejected",
            "ER20 Cmd jB rejected",
        ] {
            assert!(hint_for(text, Some(off.clone())).contains("`armgate on`"));
            let h = hint_for(text, Some(faulted.clone()));
            assert!(h.contains("`armgate on`") && h.contains("ER31"), "{h}");
        }
        let starting = status(Mode::Off, DriveStatus::Starting, 0, Motion::Holding);
        assert!(hint_for("ER20 Cmd RC rejected", Some(starting)).contains("still starting"));
    }

    #[test]
    fn with_the_drives_running_the_mode_motion_and_goal_decide() {
        let s = status(Mode::Joint, DriveStatus::Running, 0, Motion::Holding);
        assert_eq!(
            hint_for("ER20 Cmd BG rejected", Some(s.clone())),
            "BG needs mode cartesian, the mode is joint: `armgate mode cartesian`"
        );
        assert!(hint_for("ER20 Cmd jB rejected", Some(s.clone())).contains("no joint goal"));
        assert!(hint_for("ER20 Cmd RC rejected", Some(s)).contains("`armgate mode off`"));
        let busy = status(
            Mode::Cartesian,
            DriveStatus::Running,
            0,
            Motion::CartesianMove,
        );
        assert!(hint_for("ER20 Cmd BG rejected", Some(busy)).contains("`armgate stop`"));
        // RC in mode off with idle, running drives: nothing to suggest.
        let idle_off = status(Mode::Off, DriveStatus::Running, 0, Motion::Holding);
        assert_eq!(
            hint(&parsed_text("ER20 Cmd RC rejected"), Some(&idle_off)),
            None
        );
        // Other refusals say enough by themselves.
        let idle = status(Mode::Cartesian, DriveStatus::Running, 0, Motion::Holding);
        assert_eq!(
            hint(&parsed_text("ER25 Cmd GT outside workspace"), Some(&idle)),
            None
        );
    }

    #[test]
    fn the_mode_a_request_needs_is_the_controllers_rule() {
        let s = status(Mode::Off, DriveStatus::Running, 0, Motion::Holding);
        let tw = hint_for("ER20 Cmd TW rejected", Some(s.clone()));
        assert_eq!(
            tw,
            "TW needs mode cartesian, the mode is off: `armgate mode cartesian`"
        );
        assert!(hint_for("ER20 Cmd KG rejected", Some(s.clone())).contains("`armgate mode joint`"));
        // GT and jG only store a goal: they need no mode.
        assert_eq!(hint(&parsed_text("ER20 Cmd GT rejected"), Some(&s)), None);
        assert_eq!(hint(&parsed_text("ER20 Cmd jG rejected"), None), None);
    }

    #[test]
    fn without_status_the_reason_text_decides() {
        // Texts are at most 30 characters on the wire (docs/protocol.md lists the reasons).
        assert!(hint_for("ER20 Cmd BG drives off", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd BG drives stopping", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd BG drive fault 31", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd RC drives starting", None).contains("starting"));
        assert!(hint_for("ER20 Cmd RC drives settling", None).contains("in a moment"));
        assert!(hint_for("ER20 Cmd BG needs mode 2", None).contains("`armgate mode cartesian`"));
        assert!(hint_for("ER20 Cmd RC needs mode 0", None).contains("`armgate mode off`"));
        assert!(hint_for("ER20 Cmd jE busy", None).contains("`armgate stop`"));
        assert!(hint_for("ER20 Cmd BG no goal", None).contains("goal"));
        assert!(hint_for("ER20 Cmd VE no via point 0", None).contains("via point 0"));
        // The reason wins over the state: it is what the controller checked.
        let running = status(Mode::Off, DriveStatus::Running, 0, Motion::Holding);
        assert!(hint_for("ER20 Cmd RC drives settling", Some(running)).contains("in a moment"));
        let old = hint_for("ER20 Cmd BG rejected", None);
        assert!(
            old.contains("mode cart") && old.contains("armgate on"),
            "{old}"
        );
        assert_eq!(hint(&parsed_text("ER11 Arm did not start"), None), None);
        assert_eq!(hint(&parsed_text("ER26 Cmd jG j5 < 0.785"), None), None);
    }

    #[test]
    fn another_holder_is_named_with_its_port_and_what_to_do() {
        let mut s = status(Mode::Joint, DriveStatus::Running, 0, Motion::JointMove);
        s.session = Some(armgate_protocol::client::SessionReport {
            holder: crate::status::Holder::Other,
            address: Some("127.0.0.1:40001".parse().unwrap()),
            watchdog_ms: 0,
            send_drops: 0,
            clients: 2,
        });
        let h = hint_for("ER40 Cmd jB by 127.0.0.1", Some(s));
        assert!(
            h.starts_with("127.0.0.1:40001 holds the arm while it moves: wait")
                && h.contains("`armgate stop`"),
            "{h}"
        );
    }
}
