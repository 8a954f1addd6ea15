//! `armgate teleop`: the keyboard client of the seed thesis (Fig. 3.3, spec §7.3).
//!
//! The screen shows four columns, *Current Pose* (x, y, z, q1..q4 from PS), *Desired Pose*,
//! *Joints* (jP) and *Temp(C)* (TM), then the `RPY:` of the current and desired pose, the
//! `Scale:`, the latest ER/WN text and the key help.
//!
//! | Key | Cartesian keys | Joint keys (`j`) |
//! |---|---|---|
//! | ← / → | desired x − / + | selected joint − / + |
//! | ↓ / ↑ | desired y − / + | select the next / previous joint |
//! | PgDn / PgUp | desired z − / + | — |
//! | 1..8 | — | select joint 1..8 |
//! | + / − | double / halve the scale | same |
//! | space | **stop** (ST) | same |
//! | o | drives on (ON) | same |
//! | c | desired pose ← current pose | desired joints ← current joints |
//! | Enter | GT (desired position, current RPY, T = 0) + BG | jG + jB |
//! | j | switch to joint keys | switch to Cartesian keys |
//! | m | CM to the mode the keys need (cartesian / joint); there, on along off → joint → cart | same |
//! | v | jog keys ↔ step keys | same |
//! | q, Esc, Ctrl-C | stop (ST) and quit (the terminal is restored) | same |
//!
//! **Jog keys** (the default; `v` toggles, `--step` starts without them): a held arrow or page
//! key streams a velocity — `TW` in the base frame for the Cartesian keys, 5 mm/s × scale
//! along the axis; `jW` for the joint keys, 0.02 rad/s × scale on the selected joint — through
//! a [`VelocityStreamer`] on a socket of its own, re-sent every control period until shortly
//! after the key's last auto-repeat ([`jog`]) or its release; then the command at rest ends the
//! stream on purpose (a stream that just stops sending times out, which latches like any
//! stop) and the arm ramps to rest. A fresh press re-arms the stream with a command at rest
//! first; a stream refused because of a stop (`after ST: send 0`, `after idle: send 0`, a
//! network stall) ends, the refusal is shown, and only the next fresh press re-arms it. The
//! mode must match the keys (cartesian / joint), else the controller's refusal is shown.
//!
//! **Step keys** (the seed's): a Cartesian step is 1 mm × scale, a joint step 0.01 rad ×
//! scale. Keys edit the desired values; Enter sends them (`--live`: every key press sends). If
//! BG (jB) is refused `busy` (this client's motion is still running), the client sends ST and
//! then BG (jB) once more; any other refusal (another client holding the arm, `ER40`) is shown.
//!
//! Leaving stops what teleop started, and only that: `q`, Esc, Ctrl-C, SIGTERM, a closed
//! terminal (SIGHUP) or an error of the terminal all send `ST` (on a socket of its own,
//! [`StopOnExit`]) before the process ends, as `armgate move` does on Ctrl-C — unless the
//! controller's session report (`SQ` 3) names another client as the holder of the arm: a
//! teleop opened to watch leaves another operator's motion alone ([`StopSender::stop`]). On
//! SIGTERM and SIGHUP a thread of its own does so at once ([`stop_on_signal`]): a closed
//! terminal leaves the keyboard loop stuck.
//!
//! The stop key (space) stops the jog stream at once as well as the arm, and a jog key still
//! held (its auto-repeats) does not restart it: the operator releases it and presses again
//! ([`state`]).
//!
//! The header shows the robot, mode, drives and motion from the status request (SQ); with a
//! controller too old for it the mode is unknown until the first `m`, and `m` from an unknown
//! mode selects joint mode.
//!
//! The desired pose and joints follow the measured ones until a key changes them, and again
//! whenever the arm moves for another reason (this client's motion ended, the mode changed,
//! another client moved it): a key press moves the arm by one step from where it is, never
//! back to old values. Readings older than a second are marked in the Current column, a
//! refused goal in the Desired column; an ER/WN line is shown for 10 s.
//!
//! Structure: [`state`] holds the screen's data and the key handling (no I/O), [`render`] draws
//! it (a pure function), [`io`] is the thread that owns the socket and polls PS/jP/TM at
//! `--rate` Hz, so the UI never blocks on the network.

pub mod io;
pub mod jog;
pub mod render;
pub mod state;

use std::time::Duration;

use ratatui::crossterm::event::{self, KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

use armgate_protocol::client::signed::link_identity;

use crate::velocity::{StreamEvent, VelocityStreamer};
use crate::{Client, ClientError};
use jog::{FIRST_HOLD, HeldKey};
use state::{Action, Event, Key, TeleopState};

/// How the keyboard client runs.
#[derive(Clone, Debug, PartialEq)]
pub struct TeleopOptions {
    /// The arm's number of joints.
    pub joints: usize,
    /// Send on every key press instead of on Enter.
    pub live: bool,
    /// Start with jogging keys (held keys stream velocities) rather than step keys.
    pub jog: bool,
    /// The polling period of PS, jP and TM.
    pub poll: Duration,
    /// The controller's address, for the title.
    pub addr: String,
}

/// The teleop key for a terminal key event (Ctrl-C is Esc): presses, and the repeats of a held
/// key that terminals reporting event types send.
pub fn key(event: &KeyEvent) -> Option<Key> {
    if event.kind == KeyEventKind::Release {
        return None;
    }
    if event.modifiers.contains(KeyModifiers::CONTROL) {
        return (event.code == KeyCode::Char('c')).then_some(Key::Esc);
    }
    Some(match event.code {
        KeyCode::Left => Key::Left,
        KeyCode::Right => Key::Right,
        KeyCode::Up => Key::Up,
        KeyCode::Down => Key::Down,
        KeyCode::PageUp => Key::PageUp,
        KeyCode::PageDown => Key::PageDown,
        KeyCode::Enter => Key::Enter,
        KeyCode::Esc => Key::Esc,
        KeyCode::Char(c) => Key::Char(c),
        _ => return None,
    })
}

/// Where and how to send `ST`, and for whom.
struct StopSender {
    peer: std::net::SocketAddr,
    config: crate::ClientConfig,
    /// Signs the stop for a controller that wants signed requests.
    signer: Option<crate::Signer>,
    /// This teleop's sockets (polls and moves, the jog stream): the holders it may stop.
    own: Vec<std::net::SocketAddr>,
}

/// What [`StopSender::stop`] did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ExitStop {
    /// Sent `ST` (this teleop holds the arm, nobody does, or the controller cannot say).
    Sent,
    /// Another client holds the arm: its motion is not this teleop's to stop.
    Left(std::net::SocketAddrV4),
    /// `ST` was due but got no answer.
    Failed,
}

impl StopSender {
    /// Sends `ST` unless the controller names another client as the holder (`SQ` 3). It is
    /// obeyed from any client: a socket of its own, so that it never waits behind the I/O
    /// thread's request. A controller that cannot say (too old, no answer) is stopped.
    fn stop(self) -> ExitStop {
        let Ok(mut client) = Client::connect_with(self.peer, self.config) else {
            return ExitStop::Failed;
        };
        client.set_signer(self.signer);
        if let Ok(Some(session)) = client.session()
            && session.holder == crate::status::Holder::Other
            && let Some(holder) = session.address
            && !self.own.contains(&std::net::SocketAddr::V4(holder))
        {
            return ExitStop::Left(holder);
        }
        match client.stop() {
            Ok(()) => ExitStop::Sent,
            Err(_) => ExitStop::Failed,
        }
    }

    /// The same destination and link: a signed stop is obeyed even when its timestamp races
    /// another's on the link (docs/protocol.md, "Signed datagrams").
    fn next(&self) -> Self {
        Self {
            peer: self.peer,
            config: self.config.clone(),
            signer: self.signer.clone(),
            own: self.own.clone(),
        }
    }
}

/// Sends `ST` when dropped — on every way out of [`run`], an error return included — so that
/// leaving teleop never leaves the arm moving.
struct StopOnExit(Option<StopSender>);

impl Drop for StopOnExit {
    fn drop(&mut self) {
        if let Some(stopper) = self.0.take()
            && let ExitStop::Left(holder) = stopper.stop()
        {
            // After the terminal is restored (dropped later than `Restore`).
            eprintln!("armgate: teleop: {holder} holds the arm; its motion was left alone");
        }
    }
}

/// How long the keyboard loop has after SIGTERM or SIGHUP to end by itself before the process
/// is ended.
const SIGNAL_GRACE: Duration = Duration::from_secs(1);

/// On SIGTERM or SIGHUP (`signalled`), stops the arm from a thread of its own, and ends the
/// process if the keyboard loop has not ended (`done`) within [`SIGNAL_GRACE`]: once the
/// terminal is gone (a closed window, a dropped SSH session), crossterm's event poll (0.29)
/// spins on the dead terminal and never returns, so the loop would never reach its own `ST`.
fn stop_on_signal(
    signalled: crate::interrupt::Interrupt,
    done: std::sync::Arc<std::sync::atomic::AtomicBool>,
    stopper: StopSender,
) -> std::io::Result<()> {
    use std::sync::atomic::Ordering;
    let tick = Duration::from_millis(20);
    std::thread::Builder::new()
        .name("armgate-teleop-signals".into())
        .spawn(move || {
            while !signalled.is_set() {
                if done.load(Ordering::SeqCst) {
                    return;
                }
                std::thread::sleep(tick);
            }
            let _ = stopper.stop();
            let deadline = std::time::Instant::now() + SIGNAL_GRACE;
            while std::time::Instant::now() < deadline {
                if done.load(Ordering::SeqCst) {
                    return;
                }
                std::thread::sleep(tick);
            }
            // stderr may be the terminal that is gone: a failed write is no reason to panic.
            let _ = std::io::Write::write_all(
                &mut std::io::stderr(),
                b"armgate: teleop: ended by a signal, its terminal unresponsive; sent ST\n",
            );
            std::process::exit(1);
        })
        .map(drop)
}

/// Restores the terminal when dropped, also on an error return.
struct Restore {
    /// Key releases were asked for ([`report_releases`]).
    releases: bool,
}

impl Drop for Restore {
    fn drop(&mut self) {
        if self.releases {
            let _ = ratatui::crossterm::execute!(
                std::io::stdout(),
                ratatui::crossterm::event::PopKeyboardEnhancementFlags
            );
        }
        ratatui::restore();
    }
}

/// Asks the terminal to report key releases and repeats (the kitty keyboard protocol), where
/// it can: a released jog key then stops the stream at once rather than at its deadline.
fn report_releases() -> bool {
    use ratatui::crossterm::event::{KeyboardEnhancementFlags, PushKeyboardEnhancementFlags};
    ratatui::crossterm::terminal::supports_keyboard_enhancement().unwrap_or(false)
        && ratatui::crossterm::execute!(
            std::io::stdout(),
            PushKeyboardEnhancementFlags(KeyboardEnhancementFlags::REPORT_EVENT_TYPES)
        )
        .is_ok()
}

/// How the keyboard client ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// `q` or Esc.
    Quit,
    /// Ctrl-C, SIGTERM or SIGHUP (the `armgate` tool exits 130).
    Interrupted,
}

/// Runs the keyboard client until q / Esc / Ctrl-C or a signal; sends ST on the way out
/// (unless another client holds the arm).
pub fn run(client: Client, options: TeleopOptions) -> std::io::Result<Ended> {
    // The jog stream has a socket of its own: it must not wait behind the polls.
    let config = crate::ClientConfig {
        retries: 0,
        ..client.config().clone()
    };
    // Signed on a link of its own: its timestamps would race the polls' on one link.
    let signer = client.signer().map(crate::Signer::next_link);
    let stream_client = Client::connect_with(client.peer(), config)
        .and_then(|mut streamer| {
            streamer.set_signer(signer);
            if let (Some(polls), true) = (client.signer(), streamer.signer().is_some()) {
                // The jog stream's link, set aside by the controller: said before the screen
                // is taken over.
                streamer.identify()?;
                let jogs = streamer.signer().map_or(0, crate::Signer::link);
                eprintln!(
                    "armgate teleop: signing for controller {}, polls on link {}, jogs on link {jogs}",
                    polls.controller(),
                    polls.link()
                );
            }
            Ok(streamer)
        })
        .map_err(|e| std::io::Error::other(e.to_string()))?;
    // Who this teleop is to the controller: its sockets' addresses, or with a key its links
    // (a signed client's session is its link, reported as 0.0.0.N port 0).
    let own = [&client, &stream_client]
        .into_iter()
        .flat_map(|c| {
            [
                c.local_addr().ok(),
                c.signer().map(|s| link_identity(s.link())),
            ]
        })
        .flatten()
        .collect();
    let stopper = StopSender {
        peer: client.peer(),
        config: client.config().clone(),
        // The polls' link: a stop is obeyed however its timestamp races (and it must not wait
        // for an identity request).
        signer: client.signer().cloned(),
        own,
    };
    // SIGTERM and SIGHUP (a closed terminal) end the loop as `q` does; Ctrl-C is a key here.
    let signalled = crate::interrupt::ctrl_c().map_err(std::io::Error::other)?;
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    stop_on_signal(signalled.clone(), done.clone(), stopper.next())?;
    let _stop = StopOnExit(Some(stopper));
    let streamer = VelocityStreamer::spawn(stream_client)?;
    let io = io::spawn(client, options.joints, options.poll)?;
    let mut state = TeleopState::new(options.addr, options.joints, options.live);
    state.jog = options.jog;
    let mut held = HeldKey::default();
    let mut terminal = ratatui::try_init()?;
    let _restore = Restore {
        releases: report_releases(),
    };
    // The terminal key that streams, to stop on its release.
    let mut jog_key = None;
    let mut ctrl_c = false;
    while !state.quit && !signalled.is_set() {
        let now = std::time::Instant::now();
        state.at(now);
        while let Ok(event) = io.events.try_recv() {
            state.apply(event);
        }
        while let Ok(event) = streamer.events.try_recv() {
            state.apply(match event {
                StreamEvent::Failed(ClientError::Rejected(text)) => Event::Refused(text),
                StreamEvent::Failed(other) => Event::Status(format!("jog: {other}")),
                StreamEvent::Notice(text) => Event::Text(text),
            });
        }
        terminal.draw(|frame| render::render(&state, frame))?;
        if !event::poll(Duration::from_millis(30))? {
            continue;
        }
        let event::Event::Key(k) = event::read()? else {
            continue;
        };
        if k.kind == KeyEventKind::Release && jog_key == Some(k.code) {
            jog_key = None;
            held = HeldKey::default();
            streamer.stop();
        }
        ctrl_c |= k.modifiers.contains(KeyModifiers::CONTROL) && k.code == KeyCode::Char('c');
        if let Some(key) = key(&k) {
            let sent = match state.handle_key(key) {
                Some(Action::Jog(velocity)) => {
                    let until = held.press(velocity.clone(), now);
                    // A fresh press moves on purpose and re-arms the stream after a stop;
                    // the terminal's auto-repeat of a key held through a stop does not.
                    if until == now + FIRST_HOLD {
                        streamer.start(velocity, until);
                    } else {
                        streamer.stream(velocity, until);
                    }
                    jog_key = Some(k.code);
                    true
                }
                Some(Action::Stop) => {
                    // The jog stream stops with the arm: a held key must not drive it on,
                    // and no command at rest may re-arm the stream after the ST.
                    jog_key = None;
                    held = HeldKey::default();
                    streamer.halt();
                    io.actions.send(Action::Stop).is_ok()
                }
                Some(action) => io.actions.send(action).is_ok(),
                None => true,
            };
            if !sent {
                state.status = String::from("the I/O thread has ended");
            }
        }
    }
    // Silently: the ST on exit must not meet a command at rest that re-arms after it.
    streamer.halt();
    done.store(true, std::sync::atomic::Ordering::SeqCst);
    // Dropping the sender ends the I/O thread after its current request; it is not joined, so
    // that quitting never waits for a timeout.
    Ok(if ctrl_c || signalled.is_set() {
        Ended::Interrupted
    } else {
        Ended::Quit
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::crossterm::event::KeyEventState;

    fn press(code: KeyCode, modifiers: KeyModifiers) -> KeyEvent {
        KeyEvent {
            code,
            modifiers,
            kind: KeyEventKind::Press,
            state: KeyEventState::NONE,
        }
    }

    #[test]
    fn terminal_keys_map_to_teleop_keys() {
        let none = KeyModifiers::NONE;
        assert_eq!(key(&press(KeyCode::Left, none)), Some(Key::Left));
        assert_eq!(key(&press(KeyCode::PageDown, none)), Some(Key::PageDown));
        assert_eq!(
            key(&press(KeyCode::Char('+'), KeyModifiers::SHIFT)),
            Some(Key::Char('+'))
        );
        assert_eq!(
            key(&press(KeyCode::Char('c'), KeyModifiers::CONTROL)),
            Some(Key::Esc)
        );
        assert_eq!(key(&press(KeyCode::Char('x'), KeyModifiers::CONTROL)), None);
        assert_eq!(key(&press(KeyCode::F(1), none)), None);
        let mut release = press(KeyCode::Left, none);
        release.kind = KeyEventKind::Release;
        assert_eq!(key(&release), None);
    }
}
