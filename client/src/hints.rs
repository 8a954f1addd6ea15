//! What to do about a refusal: a hint from the controller's state (`SQ`) when it can say,
//! else from the reason in the refusal's text.
//!
//! The state decides first because it cannot guess wrong: with the drives off or faulted no
//! motion starts whatever the mode, so the hint is `armgate on`; while they start, waiting is.

use crate::status::{DriveState, Motion, Status};
use crate::{Mode, Text, matching};

/// The commands that start or load a Cartesian motion, and those of joint mode.
const CARTESIAN: [&str; 4] = ["BG", "VE", "GT", "GL"];
const JOINT: [&str; 3] = ["jB", "jE", "jG"];

/// The two command characters a refusal names (`ER20 Cmd BG rejected: …` → `BG`).
fn named_command(text: &str) -> Option<&str> {
    text.get(5..)?.strip_prefix("Cmd ")?.get(..2)
}

/// A hint for a refusal, if there is one to give.
pub fn hint(text: &Text, status: Option<&Status>) -> Option<String> {
    let code = matching::code(text)?;
    let s = text.as_str();
    let command = named_command(s).unwrap_or_default();
    if let Some(status) = status {
        if let Some(h) = drive_hint(status, code) {
            return Some(h);
        }
        if code == 20 {
            return state_hint(command, status);
        }
        return None;
    }
    text_hint(code, command, &s.to_ascii_lowercase())
}

/// The hint when the drives are the reason (any refusal but ON's and OF's own).
fn drive_hint(status: &Status, code: u8) -> Option<String> {
    match (status.drives, code) {
        (DriveState::Running, _) | (_, 10 | 11) => None,
        (DriveState::Off, _) => Some("the drives are off: start them with `armgate on`".into()),
        (DriveState::Faulted, _) => Some(format!(
            "the drives stopped on a fault ({}): `armgate on` clears it and restarts them",
            status.drives_text()
        )),
        (DriveState::Starting, _) => {
            Some("the drives are still starting: try again in a moment (`armgate on` waits)".into())
        }
        (DriveState::Stopping, _) => {
            Some("the drives are stopping: `armgate on` restarts them".into())
        }
    }
}

/// The hint for `ER20` with the drives running: the mode, a running motion, a missing goal.
fn state_hint(command: &str, status: &Status) -> Option<String> {
    let needs = |mode: Mode| {
        (status.mode != mode).then(|| {
            format!(
                "{command} needs mode {0}, the mode is {1}: `armgate mode {0}`",
                mode.name(),
                status.mode.name()
            )
        })
    };
    let busy = || {
        (status.motion != Motion::Idle).then(|| {
            format!(
                "a {} is running: wait for it or `armgate stop`",
                status.motion.name()
            )
        })
    };
    if CARTESIAN.contains(&command) {
        needs(Mode::Cartesian)
            .or_else(busy)
            .or_else(|| Some("no goal or via point 0 stored (GT / VP 0 first)".into()))
    } else if JOINT.contains(&command) {
        needs(Mode::Joint)
            .or_else(busy)
            .or_else(|| Some("no joint goal or via point 0 stored (jG / jV 0 first)".into()))
    } else if command == "RC" {
        needs(Mode::Off).or_else(busy)
    } else {
        busy()
    }
}

/// The hint from the refusal's text alone (a controller without `SQ`).
fn text_hint(code: u8, command: &str, reason: &str) -> Option<String> {
    if reason.contains("drives off")
        || reason.contains("fault")
        || (reason.contains("stopping") && code != 10)
    {
        return Some("start the drives with `armgate on`".into());
    }
    if reason.contains("starting") {
        return Some("the drives are still starting: try again in a moment".into());
    }
    if code != 20 {
        return None;
    }
    let mode = if CARTESIAN.contains(&command) {
        "Cartesian mode (`armgate mode cart`)"
    } else if JOINT.contains(&command) {
        "joint mode (`armgate mode joint`)"
    } else if command == "RC" {
        "mode off (`armgate mode off`)"
    } else {
        return None;
    };
    if reason.contains("mode") {
        return Some(format!("needs {mode}"));
    }
    if reason.contains("busy") || reason.contains("running") || reason.contains("moving") {
        return Some("a motion is running: wait for it or `armgate stop`".into());
    }
    Some(format!(
        "needs {mode}, running drives (`armgate on`), a goal, and no motion running (`armgate stop`)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::parsed_text;

    fn status(mode: Mode, drives: DriveState, fault: u8, motion: Motion) -> Status {
        Status {
            mode,
            drives,
            fault,
            joints: 6,
            motion,
            refused: 1,
            uptime: 3.0,
            name: "ranger-mk1".into(),
        }
    }

    fn hint_for(text: &str, s: Option<Status>) -> String {
        hint(&parsed_text(text), s.as_ref()).unwrap_or_default()
    }

    #[test]
    fn drives_off_or_faulted_hint_at_on_whatever_the_mode() {
        let off = status(Mode::Off, DriveState::Off, 0, Motion::Idle);
        let faulted = status(Mode::Cartesian, DriveState::Faulted, 31, Motion::Idle);
        for text in [
            "ER20 Cmd BG rejected",
            "ER20 Cmd RC rejected",
            "ER20 Cmd jB rejected",
        ] {
            assert!(hint_for(text, Some(off.clone())).contains("`armgate on`"));
            let h = hint_for(text, Some(faulted.clone()));
            assert!(h.contains("`armgate on`") && h.contains("ER31"), "{h}");
        }
        let starting = status(Mode::Off, DriveState::Starting, 0, Motion::Idle);
        assert!(hint_for("ER20 Cmd RC rejected", Some(starting)).contains("still starting"));
    }

    #[test]
    fn with_the_drives_running_the_mode_motion_and_goal_decide() {
        let s = status(Mode::Joint, DriveState::Running, 0, Motion::Idle);
        assert_eq!(
            hint_for("ER20 Cmd BG rejected", Some(s.clone())),
            "BG needs mode cart, the mode is joint: `armgate mode cart`"
        );
        assert!(hint_for("ER20 Cmd jB rejected", Some(s.clone())).contains("no joint goal"));
        assert!(hint_for("ER20 Cmd RC rejected", Some(s)).contains("`armgate mode off`"));
        let busy = status(
            Mode::Cartesian,
            DriveState::Running,
            0,
            Motion::CartesianMove,
        );
        assert!(hint_for("ER20 Cmd BG rejected", Some(busy)).contains("`armgate stop`"));
        // RC in mode off with idle, running drives: nothing to suggest.
        let idle_off = status(Mode::Off, DriveState::Running, 0, Motion::Idle);
        assert_eq!(
            hint(&parsed_text("ER20 Cmd RC rejected"), Some(&idle_off)),
            None
        );
        // Other refusals say enough by themselves.
        let idle = status(Mode::Cartesian, DriveState::Running, 0, Motion::Idle);
        assert_eq!(
            hint(&parsed_text("ER25 Cmd GT outside workspace"), Some(&idle)),
            None
        );
    }

    #[test]
    fn without_status_the_reason_text_decides() {
        // Texts are at most 30 characters on the wire.
        assert!(hint_for("ER20 Cmd BG drives off", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd BG drive fault ER31", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd RC drives starting", None).contains("starting"));
        assert!(hint_for("ER20 Cmd BG wrong mode", None).contains("mode cart"));
        assert!(hint_for("ER20 Cmd jE busy", None).contains("`armgate stop`"));
        let old = hint_for("ER20 Cmd BG rejected", None);
        assert!(
            old.contains("mode cart") && old.contains("armgate on"),
            "{old}"
        );
        assert_eq!(hint(&parsed_text("ER11 Arm did not start"), None), None);
        assert_eq!(hint(&parsed_text("ER26 Cmd jG j5 < 0.785"), None), None);
    }
}
