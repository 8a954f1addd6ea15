//! Drawing the keyboard client's screen: a pure function of [`TeleopState`].
//!
//! ```text
//!  armgate teleop  127.0.0.1:7031  ranger-mk1  mode cartesian  drives running  holding   keys: Cartesian, send on Enter
//! ┌────────────────────────────────────────────────────────────────────────┐
//! │Current Pose     Desired Pose     Joints           Temp(C)              │
//! │x      0.5000    x      0.5010    j1     -1.5838   T1      35.0         │
//! │...                                                                     │
//! └────────────────────────────────────────────────────────────────────────┘
//!  RPY:   current  -0.0007  1.4801  1.7917    desired  -0.0007  1.4801  1.7917
//!  Scale: 4.0000   (step 4.000 mm)
//!  ER/WN: WN12 Joint limit.
//!  sent GT + BG
//!  ←/→ x −/+  ↓/↑ y −/+  PgDn/PgUp z −/+  +/- scale  c desired←current  Enter send
//!  space STOP  o drives on  j joint keys  v jog/step  m mode cartesian  q/Esc quit
//! ```

use ratatui::Frame;
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Paragraph, Row, Table};

use super::state::{TeleopState, Variant};
use crate::status::Name;
use crate::{NO_READING, Pose};

/// The labels of the seven pose values.
const POSE_LABELS: [&str; 7] = ["x", "y", "z", "q1", "q2", "q3", "q4"];

/// `v` without the sign of a negative zero (so that it never shows as `-0.0000`).
fn unsigned_zero(v: f64) -> f64 {
    if v == 0.0 { 0.0 } else { v }
}

/// A value, or dashes while unknown.
fn value(v: Option<f64>) -> String {
    v.map_or_else(
        || format!("{:>9}", "---"),
        |v| format!("{:>9.4}", unsigned_zero(v)),
    )
}

fn pose_values(pose: Option<&Pose>) -> [Option<f64>; 7] {
    match pose {
        Some(p) => {
            let [x, y, z] = p.xyz;
            let q = p.quaternion;
            [x, y, z, q.x, q.y, q.z, q.w].map(Some)
        }
        None => [None; 7],
    }
}

fn rpy(pose: Option<&Pose>) -> String {
    match pose.map(|p| p.rpy().map(unsigned_zero)) {
        Some([r, p, y]) => format!("{r:>8.4} {p:>8.4} {y:>8.4}"),
        None => format!("{:>8} {:>8} {:>8}", "---", "---", "---"),
    }
}

/// Draws the whole screen.
pub fn render(state: &TeleopState, frame: &mut Frame<'_>) {
    let rows = state.joint_count.max(POSE_LABELS.len());
    let table_height = u16::try_from(rows + 3).unwrap_or(u16::MAX);
    let [
        title,
        panel,
        rpy_line,
        scale_line,
        text_line,
        status_line,
        help,
    ] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Length(table_height),
        Constraint::Length(1),
        Constraint::Length(1),
        Constraint::Length(1),
        Constraint::Length(1),
        Constraint::Min(2),
    ])
    .areas(frame.area());

    let mode = match (state.mode, state.mode_pending) {
        (mode, Some(pending)) => format!(
            "{} (-> {}?)",
            mode.map_or("?", |m| m.name()),
            pending.name()
        ),
        (Some(mode), None) => mode.name().to_owned(),
        (None, None) => String::from("?"),
    };
    let keys = match state.variant {
        Variant::Cartesian => "Cartesian",
        Variant::Joint => "joint",
    };
    let send = match (state.jog, state.live) {
        (true, _) => "jog while held",
        (false, true) => "send on every key",
        (false, false) => "send on Enter",
    };
    let controller = state
        .controller
        .as_ref()
        .map_or(String::new(), |c| format!(" {}", c.name));
    let drives = state.controller.as_ref().map_or(String::new(), |c| {
        format!("  drives {}  {}", c.drives_text(), c.motion.name())
    });
    frame.render_widget(
        Line::from(format!(
            " armgate teleop  {}{controller}  mode {mode}{drives}   keys: {keys}, {send}",
            state.addr
        ))
        .style(Style::new().add_modifier(Modifier::BOLD)),
        title,
    );

    frame.render_widget(table(state, rows), panel);

    frame.render_widget(
        Line::from(format!(
            " RPY:   current {}    desired {}",
            rpy(state.current.as_ref()),
            rpy(state.desired.as_ref())
        )),
        rpy_line,
    );
    let step = match state.variant {
        Variant::Cartesian => format!("{:.3} mm", state.step() * 1e3),
        Variant::Joint => format!("{:.4} rad", state.joint_step()),
    };
    frame.render_widget(
        Line::from(format!(" Scale: {:.4}   (step {step})", state.scale)),
        scale_line,
    );
    let text = state
        .recent_text()
        .map_or("none", |t| t.as_str())
        .to_owned();
    frame.render_widget(Line::from(format!(" ER/WN: {text}")), text_line);
    frame.render_widget(Line::from(format!(" {}", state.status)), status_line);

    let help_lines = match state.variant {
        Variant::Cartesian => [
            " ←/→ x −/+  ↓/↑ y −/+  PgDn/PgUp z −/+  +/- scale  c desired←current  Enter send",
            " space STOP  o drives on  j joint keys  v jog/step  m mode cartesian  q/Esc quit",
        ],
        Variant::Joint => [
            " 1-8 or ↑/↓ select joint  ←/→ joint −/+  +/- scale  c desired←current  Enter send",
            " space STOP  o drives on  j Cartesian keys  v jog/step  m mode joint  q/Esc quit",
        ],
    };
    frame.render_widget(
        Paragraph::new(help_lines.map(Line::from).to_vec())
            .style(Style::new().add_modifier(Modifier::DIM)),
        help,
    );
}

/// The panel: Current Pose, Desired Pose, Joints, Temp(C) (and Desired Joints in joint keys).
fn table(state: &TeleopState, rows: usize) -> Table<'static> {
    let current = pose_values(state.current.as_ref());
    let desired = pose_values(state.desired.as_ref());
    let joint_keys = state.variant == Variant::Joint;
    let pose_cell = |values: &[Option<f64>; 7], k: usize| match (POSE_LABELS.get(k), values.get(k))
    {
        (Some(label), Some(v)) => format!("{label:<3}{}", value(*v)),
        _ => String::new(),
    };
    let joint_cell = |values: &[f64], k: usize, mark: bool| {
        if k >= state.joint_count {
            return String::new();
        }
        let marker = if mark && k == state.selected {
            '>'
        } else {
            ' '
        };
        format!("{marker}j{:<2}{}", k + 1, value(values.get(k).copied()))
    };
    let temp_cell = |k: usize| {
        if k >= state.joint_count {
            return String::new();
        }
        match state.temperatures.get(k) {
            Some(t) if *t == NO_READING => format!("T{:<3}{:>7}", k + 1, "--"),
            Some(t) => format!("T{:<3}{t:>7.1}", k + 1),
            None => format!("T{:<3}{:>7}", k + 1, "---"),
        }
    };
    let body = (0..rows).map(|k| {
        let mut cells = vec![
            pose_cell(&current, k),
            pose_cell(&desired, k),
            joint_cell(&state.joints, k, false),
        ];
        if joint_keys {
            cells.push(joint_cell(&state.desired_joints, k, true));
        }
        cells.push(temp_cell(k));
        Row::new(cells)
    });
    // Old readings and refused goals are marked in the column titles.
    let current_title = match state.stale() {
        None => "Current Pose".to_owned(),
        Some(_) if state.no_reply => "Current (no reply)".to_owned(),
        Some(Some(age)) if age.as_secs() < 100 => {
            format!("Current ({:.0} s old)", age.as_secs_f64())
        }
        Some(Some(_)) => "Current (stale)".to_owned(),
        Some(None) => "Current (none yet)".to_owned(),
    };
    let desired_title = |what: &str| match state.refused {
        Some(_) => format!("{what} (refused)"),
        None => format!("Desired {what}"),
    };
    let mut header = vec![current_title, desired_title("Pose"), "Joints".to_owned()];
    if joint_keys {
        header.push(desired_title("Joints"));
    }
    header.push("Temp(C)".to_owned());
    // The pose columns are wider, for the marks in their titles.
    let mut widths = vec![Constraint::Length(16); header.len()];
    for w in widths.iter_mut().take(2) {
        *w = Constraint::Length(18);
    }
    Table::new(body, widths)
        .header(Row::new(header).style(Style::new().add_modifier(Modifier::BOLD)))
        .column_spacing(2)
        .block(Block::bordered())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mode;
    use crate::teleop::state::{Event, Key};
    use ratatui::Terminal;
    use ratatui::backend::TestBackend;

    fn screen(state: &TeleopState) -> String {
        let mut terminal = Terminal::new(TestBackend::new(100, 24)).unwrap();
        terminal.draw(|f| render(state, f)).unwrap();
        let buffer = terminal.backend().buffer();
        let width = buffer.area.width as usize;
        let symbols: Vec<&str> = buffer.content.iter().map(|c| c.symbol()).collect();
        symbols
            .chunks(width)
            .map(|line| line.concat())
            .collect::<Vec<_>>()
            .join("\n")
    }

    fn state() -> TeleopState {
        let mut s = TeleopState::new("127.0.0.1:7031", 6, false);
        s.apply(Event::Pose(Pose {
            xyz: [-0.0543, 0.5242, 0.2138],
            quaternion: crate::pose::tests::GOLDEN_QUATERNION,
        }));
        s.apply(Event::Joints(vec![
            -1.5838, 2.0360, 1.3499, -0.2471, 1.2428, -0.0595,
        ]));
        s.apply(Event::Temperatures(vec![
            35.0, 36.5, NO_READING, 40.0, 41.0, 42.0,
        ]));
        s.apply(Event::Mode(Mode::Cartesian));
        s.apply(Event::Text(crate::fake::parsed_text(
            "ER20 Cmd BG rejected",
        )));
        s.scale = 4.0;
        s
    }

    #[test]
    fn the_header_shows_the_controller_state_and_old_things_are_marked() {
        let mut s = state();
        s.apply(Event::Controller(crate::Status {
            mode: Mode::Joint,
            drives: crate::DriveStatus::Faulted,
            fault: 31,
            joints: 6,
            motion: crate::Motion::Holding,
            refused: 0,
            uptime: 1.0,
            name: "ranger-mk1".into(),
            cause: None,
            session: None,
        }));
        let text = screen(&s);
        assert!(
            text.contains("ranger-mk1  mode joint  drives faulted (ER31)  holding"),
            "{text}"
        );
        assert!(text.contains("Current Pose"), "{text}");
        // Eleven seconds later without a reading: stale, and the ER line has expired.
        s.at(s.now + std::time::Duration::from_secs(11));
        let text = screen(&s);
        assert!(text.contains("Current (11 s old)"), "{text}");
        assert!(text.contains("ER/WN: none"), "{text}");
        s.apply(Event::NoReply("PS: no reply".into()));
        assert!(screen(&s).contains("Current (no reply)"));
        s.apply(Event::Refused(crate::fake::parsed_text(
            "ER25 Cmd GT outside workspace",
        )));
        let text = screen(&s);
        assert!(text.contains("Pose (refused)"), "{text}");
        assert!(text.contains("ER25 Cmd GT outside workspace"), "{text}");
    }

    #[test]
    fn the_panel_shows_labels_values_and_the_latest_text() {
        let mut s = state();
        s.handle_key(Key::Right);
        let text = screen(&s);
        for label in [
            "Current Pose",
            "Desired Pose",
            "Joints",
            "Temp(C)",
            "RPY:",
            "Scale: 4.0000",
            "(step 4.000 mm)",
            "ER20 Cmd BG rejected",
            "mode cart",
            "127.0.0.1:7031",
        ] {
            assert!(text.contains(label), "{label} missing in\n{text}");
        }
        for value in [
            "x    -0.0543", // current x
            "x    -0.0503", // desired x, 4 mm further
            "q4    0.4612", // quaternion, scalar last
            "j1   -1.5838", // joints
            "j6   -0.0595",
            "T1     35.0",               // temperatures
            "T3       --",               // no reading
            "-0.0007   1.4801   1.7917", // RPY of the golden pose
        ] {
            assert!(text.contains(value), "{value} missing in\n{text}");
        }
        assert!(!text.contains("Desired Joints"));
    }

    #[test]
    fn joint_keys_show_the_desired_joints_and_the_selection() {
        let mut s = state();
        s.handle_key(Key::Char('j'));
        s.handle_key(Key::Char('2'));
        s.handle_key(Key::Right);
        let text = screen(&s);
        assert!(text.contains("Desired Joints"), "{text}");
        assert!(text.contains(">j2    2.0760"), "{text}");
        assert!(text.contains("(step 0.0400 rad)"), "{text}");
        assert!(text.contains("1-8 or ↑/↓ select joint"), "{text}");
    }

    #[test]
    fn an_empty_state_renders_placeholders() {
        let mut s = TeleopState::new("10.0.0.2:7031", 8, true);
        s.status = String::from("PS: no reply");
        let text = screen(&s);
        assert!(text.contains("ER/WN: none"), "{text}");
        assert!(text.contains("mode ?"), "{text}");
        assert!(text.contains("send on every key"), "{text}");
        assert!(text.contains("j8"), "{text}");
        assert!(text.contains("PS: no reply"), "{text}");
        assert!(text.contains("---"), "{text}");
    }
}
