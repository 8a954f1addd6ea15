//! Velocity streaming (docs/protocol.md, "Velocity streaming"): `TW` (a tool twist) and `jW`
//! (joint rates) hold for three control periods, so a client re-sends them faster than that;
//! when it stops, the arm ramps to rest.
//!
//! * [`Client::twist`], [`Client::joint_velocity`]: one request each; the reply says how long
//!   the command holds. [`Client::stream_for`]: a stream for a while, from this thread.
//! * [`VelocityStreamer`]: a thread with a socket of its own that re-sends the latest command
//!   until a deadline, so that the caller (a UI, a control loop) only says what it wants.
//!
//! Every stop latches, a stream's own timeout included (docs/safety.md): a stream started on
//! purpose first sends its command at rest ([`Velocity::at_rest`]), which re-arms it, and a
//! stream ended on purpose ends with it, so that its end is no timeout. A stream refused
//! because of a stop (`ER20 Cmd TW after ST: send 0`) ends there and says so: it never
//! re-arms by itself after a stop it did not ask for.
//!
//! ```no_run
//! use std::time::{Duration, Instant};
//! use armgate_client::{Client, Mode, TwistFrame, Velocity, VelocityStreamer};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let mut arm = Client::connect("127.0.0.1:7031")?;
//! arm.set_mode(Mode::Cartesian)?;
//! let streamer = VelocityStreamer::spawn(Client::connect("127.0.0.1:7031")?)?;
//! // 1 cm/s up for two seconds, then the arm ramps to rest.
//! let up = Velocity::Twist { linear: [0.0, 0.0, 0.01], angular: [0.0; 3], frame: TwistFrame::Base };
//! streamer.stream(up, Instant::now() + Duration::from_secs(2));
//! # Ok(())
//! # }
//! ```

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use armgate_protocol::client::{JointRates, Reply, Twist, TwistFrame};

use crate::banks;
use crate::{Client, ClientError};

/// How often a stream is re-sent until the controller has said how long a command holds.
pub const DEFAULT_INTERVAL: Duration = Duration::from_millis(10);

/// A velocity command.
#[derive(Clone, Debug, PartialEq)]
pub enum Velocity {
    /// `TW`: the tool's linear (m/s) and angular (rad/s) velocity, in the base or tool frame.
    Twist {
        /// vx, vy, vz (m/s).
        linear: [f64; 3],
        /// ωx, ωy, ωz (rad/s).
        angular: [f64; 3],
        /// The frame of both.
        frame: TwistFrame,
    },
    /// `jW`: one rate per joint (rad/s, or m/s for prismatic joints).
    Joints(Vec<f64>),
}

impl Velocity {
    /// The same kind of command at rest: a zero twist in the same frame, or zero rates for
    /// the same joints. Sent first, it re-arms a stream after a stop (which latches: the
    /// controller refuses a moving stream until its holder asks for rest on purpose).
    pub fn at_rest(&self) -> Self {
        match self {
            Self::Twist { frame, .. } => Self::Twist {
                linear: [0.0; 3],
                angular: [0.0; 3],
                frame: *frame,
            },
            Self::Joints(rates) => Self::Joints(vec![0.0; rates.len()]),
        }
    }
}

/// How long the command of an echo holds (its f6), if it says.
fn hold_time(reply: &Reply) -> Option<Duration> {
    let seconds = f64::from(*reply.values.last()?);
    (seconds.is_finite() && seconds > 0.0).then(|| Duration::from_secs_f64(seconds))
}

/// What [`Client::stream_for`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Streamed {
    /// The commands sent.
    pub sent: u32,
    /// A twist beyond the robot's Cartesian speed limits: the twist the controller cut it to
    /// (its echo: vx, vy, vz, ωx, ωy, ωz), all components by one factor.
    pub cut_to: Option<[f64; 6]>,
}

/// The twist `reply` echoes, if it is smaller than `sent` (by more than the wire's rounding):
/// the controller cut it to its Cartesian speed limits.
fn cut_twist(sent: [f64; 6], reply: &Reply) -> Option<[f64; 6]> {
    let mut echo = [0.0; 6];
    for (e, v) in echo.iter_mut().zip(reply.values) {
        *e = f64::from(v);
    }
    let cut = sent
        .iter()
        .zip(echo)
        .any(|(s, e)| e.abs() < s.abs() * (1.0 - 1e-5));
    cut.then_some(echo)
}

impl Client {
    /// `TW`: streams a tool twist (Cartesian mode). Returns how long it holds (three control
    /// periods, from the echo); send the next one before then.
    pub fn twist(
        &mut self,
        linear: [f64; 3],
        angular: [f64; 3],
        frame: TwistFrame,
    ) -> Result<Option<Duration>, ClientError> {
        self.twist_reply(linear, angular, frame)
            .map(|r| hold_time(&r))
    }

    /// `TW`, its reply: the twist within the Cartesian speed limits and the hold time.
    fn twist_reply(
        &mut self,
        linear: [f64; 3],
        angular: [f64; 3],
        frame: TwistFrame,
    ) -> Result<Reply, ClientError> {
        let twist = Twist {
            linear: linear.map(|v| v as f32),
            angular: angular.map(|v| v as f32),
            frame,
        };
        self.request(twist.to_request())
    }

    /// `jW`: streams joint rates (joint mode); for more than six joints bank 2 is sent first.
    /// Returns how long they hold, as [`twist`](Self::twist).
    pub fn joint_velocity(&mut self, rates: &[f64]) -> Result<Option<Duration>, ClientError> {
        let mut hold = None;
        for bank in banks::split(rates, 0, 0.0)? {
            let mut values = [0.0f32; banks::WRITE_JOINTS];
            for (v, b) in values.iter_mut().zip(bank.values) {
                *v = b;
            }
            let request = JointRates {
                bank_2: bank.index != 0,
                rates: values,
            };
            hold = hold_time(&self.request(request.to_request())?);
        }
        Ok(hold)
    }

    /// Streams `velocity` from this thread for `duration`, once per control period (a third
    /// of the hold time the controller echoes), or until `interrupted()` says so; then the arm
    /// ramps to rest. A stream started here is started and ended on purpose: it first sends
    /// the command at rest ([`Velocity::at_rest`]), which re-arms streaming after a stop, and
    /// ends with it (interrupted too); a refusal ends it with no more sent. Returns the number
    /// of commands sent between the two.
    pub fn stream_for(
        &mut self,
        velocity: &Velocity,
        duration: Duration,
        interrupted: impl Fn() -> bool,
    ) -> Result<Streamed, ClientError> {
        // None: a duration beyond the clock's range, streamed until interrupted.
        let end = Instant::now().checked_add(duration);
        let rest = velocity.at_rest();
        self.velocity(&rest)?;
        let mut sent = 0u32;
        let mut cut_to = None;
        while end.is_none_or(|end| Instant::now() < end) {
            if interrupted() {
                self.velocity(&rest)?;
                return Err(ClientError::Interrupted);
            }
            let sent_at = Instant::now();
            let hold = match velocity {
                Velocity::Twist {
                    linear,
                    angular,
                    frame,
                } => {
                    let reply = self.twist_reply(*linear, *angular, *frame)?;
                    let [x, y, z] = *linear;
                    let [a, b, c] = *angular;
                    cut_to = cut_to.or(cut_twist([x, y, z, a, b, c], &reply));
                    hold_time(&reply)
                }
                Velocity::Joints(rates) => self.joint_velocity(rates)?,
            };
            let interval = hold.map_or(DEFAULT_INTERVAL, |h| h / 3);
            sent = sent.saturating_add(1);
            // Once per period from send to send, the reply's wait included.
            let next = end.map_or(sent_at + interval, |end| (sent_at + interval).min(end));
            std::thread::sleep(next.saturating_duration_since(Instant::now()));
        }
        self.velocity(&rest)?;
        Ok(Streamed { sent, cut_to })
    }

    /// Sends one velocity command ([`twist`](Self::twist) or
    /// [`joint_velocity`](Self::joint_velocity)).
    pub fn velocity(&mut self, velocity: &Velocity) -> Result<Option<Duration>, ClientError> {
        match velocity {
            Velocity::Twist {
                linear,
                angular,
                frame,
            } => self.twist(*linear, *angular, *frame),
            Velocity::Joints(rates) => self.joint_velocity(rates),
        }
    }
}

/// What the streaming thread reports.
#[derive(Debug)]
pub enum StreamEvent {
    /// A command was refused or failed; the stream stopped (the arm ramps to rest).
    Failed(ClientError),
    /// Unsolicited notices that arrived on the stream's socket.
    Notice(crate::Text),
}

/// Re-sends the latest velocity command from a thread of its own, once per control period
/// (a third of the hold time the controller echoes), until its deadline; then sends the
/// command at rest once and nothing more, and the arm ramps to rest. A refused or failed
/// command ends the stream (reported in `events`) until the next [`start`](Self::start) or
/// [`stream`](Self::stream). Dropping it ends the thread.
#[derive(Debug)]
pub struct VelocityStreamer {
    commands: Sender<Control>,
    /// Failures and notices.
    pub events: Receiver<StreamEvent>,
    /// The thread.
    pub thread: JoinHandle<()>,
}

impl VelocityStreamer {
    /// Starts the thread with `client` (use a client of its own: requests wait for their
    /// replies one at a time, and the stream must not wait behind other requests).
    pub fn spawn(client: Client) -> std::io::Result<Self> {
        let (commands, command_rx) = mpsc::channel();
        let (event_tx, events) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("armgate-velocity".into())
            .spawn(move || run(client, &command_rx, &event_tx))?;
        Ok(Self {
            commands,
            events,
            thread,
        })
    }

    /// Streams `velocity` until `until` (it replaces what was streamed before). After a stop
    /// the controller refuses it until a stream is started on purpose ([`start`](Self::start)).
    pub fn stream(&self, velocity: Velocity, until: Instant) {
        // A send fails only if the thread has ended, which `events` has told.
        let _ = self.commands.send(Control::Stream(Order {
            velocity,
            until,
            rearm: false,
        }));
    }

    /// Starts a stream on purpose (an operator's fresh key press, not its auto-repeat): sends
    /// the command at rest first, which re-arms streaming after a stop, then streams as
    /// [`stream`](Self::stream).
    pub fn start(&self, velocity: Velocity, until: Instant) {
        let _ = self.commands.send(Control::Stream(Order {
            velocity,
            until,
            rearm: true,
        }));
    }

    /// Ends the stream on purpose (a key released, the program quitting): if one is being
    /// sent, its command at rest goes out once and the arm ramps to rest; then nothing.
    pub fn stop(&self) {
        let _ = self.commands.send(Control::End { at_rest: true });
    }

    /// Stops sending at once, without the command at rest: after this client's own `ST`, which
    /// that command would re-arm. The stream times out and the arm stays stopped.
    pub fn halt(&self) {
        let _ = self.commands.send(Control::End { at_rest: false });
    }
}

/// What the streaming thread is told.
#[derive(Debug)]
enum Control {
    /// Stream this.
    Stream(Order),
    /// End the stream; `at_rest`: with its command at rest.
    End { at_rest: bool },
}

/// What the streaming thread is told: a velocity until a deadline, re-armed first or not.
#[derive(Debug)]
struct Order {
    velocity: Velocity,
    until: Instant,
    rearm: bool,
}

fn run(mut client: Client, commands: &Receiver<Control>, events: &Sender<StreamEvent>) {
    let mut current: Option<(Velocity, Instant)> = None;
    let mut interval = DEFAULT_INTERVAL;
    let mut next_send = Instant::now();
    // A failure to report; the stream has ended.
    let failed = |error| events.send(StreamEvent::Failed(error)).is_ok();
    loop {
        let received = match &current {
            None => commands.recv().map_err(|_| RecvTimeoutError::Disconnected),
            Some(_) => commands.recv_timeout(next_send.saturating_duration_since(Instant::now())),
        };
        // The stream ends on purpose now: with its command at rest, or (`None`) silently.
        let mut end = None;
        match received {
            Ok(Control::Stream(order)) => {
                // A new command goes out at once, after the re-arming one if asked for.
                let rearm = order
                    .rearm
                    .then(|| client.velocity(&order.velocity.at_rest()));
                current = Some((order.velocity, order.until));
                next_send = Instant::now();
                if let Some(Err(error)) = rearm {
                    current = None;
                    if !failed(error) {
                        return;
                    }
                }
            }
            Ok(Control::End { at_rest }) => end = Some(at_rest),
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return,
        }
        let now = Instant::now();
        let Some((velocity, until)) = &current else {
            continue;
        };
        if now >= *until {
            end = Some(true);
        }
        if let Some(at_rest) = end {
            let sent = at_rest.then(|| client.velocity(&velocity.at_rest()));
            current = None;
            if let Some(Err(error)) = sent
                && !failed(error)
            {
                return;
            }
            continue;
        }
        if now < next_send {
            continue;
        }
        match client.velocity(velocity) {
            Ok(hold) => {
                // One control period: two more sends fit in the hold time.
                interval = hold.map_or(interval, |h| h / 3);
                next_send = now + interval;
            }
            Err(error) => {
                current = None;
                if !failed(error) {
                    return;
                }
            }
        }
        for notice in client.take_notices() {
            if events.send(StreamEvent::Notice(notice)).is_err() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::{FakeController, echo};
    use armgate_protocol::client::VALUES;

    /// Echoes every request reversed, with a hold time of 30 ms in f6.
    fn controller() -> FakeController {
        FakeController::spawn(|request| {
            let mut reply = echo(request);
            reply[2 + 4 * (VALUES - 1)..2 + 4 * VALUES].copy_from_slice(&0.03f32.to_le_bytes());
            vec![reply]
        })
    }

    #[test]
    fn twist_and_joint_rates_go_out_as_tw_and_banked_jw() {
        let fake = controller();
        let mut c = fake.client();
        let hold = c.twist([0.5, 0.0, 0.0], [0.0, 0.0, -1.0], TwistFrame::Tool);
        assert_eq!(
            hold.unwrap(),
            Some(Duration::from_secs_f64(f64::from(0.03f32)))
        );
        c.joint_velocity(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8])
            .unwrap();
        let sent = fake.received();
        assert_eq!(sent.len(), 3);
        assert_eq!(&sent[0][..2], b"TW");
        assert_eq!(sent[0][30], 0x01);
        assert_eq!(&sent[0][2..6], &0.5f32.to_le_bytes());
        assert_eq!((&sent[1][..2], sent[1][30]), (&b"jW"[..], 0x80));
        assert_eq!(&sent[1][2..6], &0.7f32.to_le_bytes());
        assert_eq!((&sent[2][..2], sent[2][30]), (&b"jW"[..], 0x00));
    }

    #[test]
    fn stream_for_resends_each_period_and_stops_when_interrupted() {
        let fake = controller();
        let mut c = fake.client();
        let rates = Velocity::Joints(vec![0.0, 0.1]);
        let streamed = c
            .stream_for(&rates, Duration::from_millis(200), || false)
            .unwrap();
        let sent = streamed.sent;
        assert_eq!(streamed.cut_to, None);
        // Every 10 ms (a third of the 30 ms hold) for 200 ms, between the zero that re-arms
        // and the zero that ends the stream on purpose.
        assert!((10..=21).contains(&sent), "{sent}");
        let received = fake.received();
        assert_eq!(received.len(), sent as usize + 2);
        assert_eq!(&received[0][2..30], &[0; 28], "rates at rest first");
        assert_eq!(&received[1][6..10], &0.1f32.to_le_bytes());
        assert_eq!(&received[sent as usize + 1][2..30], &[0; 28], "and last");
        let stopped = c.stream_for(&rates, Duration::from_secs(5), || true);
        assert!(matches!(stopped, Err(ClientError::Interrupted)));
        // Interrupted on purpose: at rest, then at rest again.
        let received = fake.received();
        assert_eq!(received.len(), sent as usize + 4);
        assert!(
            received[sent as usize + 2..]
                .iter()
                .all(|r| r[2..30] == [0; 28])
        );
        // A duration beyond the clock's range streams (until interrupted) instead of panicking.
        let endless = c.stream_for(&rates, Duration::MAX, || true);
        assert!(matches!(endless, Err(ClientError::Interrupted)));
    }

    #[test]
    fn the_streamer_resends_each_period_until_its_deadline() {
        let fake = controller();
        let streamer = VelocityStreamer::spawn(fake.client()).unwrap();
        let up = Velocity::Twist {
            linear: [0.0, 0.0, 0.01],
            angular: [0.0; 3],
            frame: TwistFrame::Base,
        };
        streamer.stream(up, Instant::now() + Duration::from_millis(200));
        std::thread::sleep(Duration::from_millis(400));
        // Every 10 ms (a third of the 30 ms hold) for 200 ms, then the twist at rest once
        // (the stream's end on purpose, no timeout), then nothing.
        let received = fake.received();
        assert!(
            (10..=25).contains(&received.len()),
            "{} sends",
            received.len()
        );
        assert_eq!(&received[0][10..14], &0.01f32.to_le_bytes());
        assert_eq!(&received.last().unwrap()[2..30], &[0; 28]);
        std::thread::sleep(Duration::from_millis(100));
        assert_eq!(fake.received().len(), received.len());
    }

    /// `stop` ends a stream with the command at rest, `halt` (after the client's own `ST`)
    /// without; a refusal (a stop that latched) ends the stream, is reported, and nothing is
    /// sent after it: the streamer never re-arms by itself.
    #[test]
    fn the_streamer_ends_at_rest_on_purpose_and_never_rearms_after_a_refusal() {
        let up = Velocity::Joints(vec![0.1, 0.0]);
        let long = || Instant::now() + Duration::from_secs(10);
        let at_rest = |r: &Vec<u8>| r[2..30] == [0; 28];
        for (halt, rests) in [(false, 1), (true, 0)] {
            let fake = controller();
            let streamer = VelocityStreamer::spawn(fake.client()).unwrap();
            streamer.stream(up.clone(), long());
            std::thread::sleep(Duration::from_millis(50));
            if halt {
                streamer.halt();
            } else {
                streamer.stop();
            }
            std::thread::sleep(Duration::from_millis(50));
            let received = fake.received();
            assert_eq!(received.iter().filter(|r| at_rest(r)).count(), rests);
            assert_eq!(at_rest(received.last().unwrap()), !halt);
            std::thread::sleep(Duration::from_millis(50));
            assert_eq!(fake.received().len(), received.len(), "nothing after");
            // Not streaming: nothing to end.
            streamer.stop();
            std::thread::sleep(Duration::from_millis(30));
            assert_eq!(fake.received().len(), received.len());
        }
        let refusing = FakeController::spawn(|request| {
            if request[2..30] == [0; 28] {
                vec![echo(request)]
            } else {
                vec![crate::fake::text("ER20 Cmd jW after ST: send 0")]
            }
        });
        let streamer = VelocityStreamer::spawn(refusing.client()).unwrap();
        streamer.stream(up, long());
        let event = streamer.events.recv_timeout(Duration::from_secs(2));
        assert!(
            matches!(&event, Ok(StreamEvent::Failed(ClientError::Rejected(t))) if t.to_string().contains("after ST")),
            "{event:?}"
        );
        std::thread::sleep(Duration::from_millis(50));
        streamer.stop();
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(refusing.received().len(), 1, "no retry, no command at rest");
    }

    #[test]
    fn a_stream_started_on_purpose_sends_the_twist_at_rest_first() {
        let fake = controller();
        let streamer = VelocityStreamer::spawn(fake.client()).unwrap();
        let up = Velocity::Twist {
            linear: [0.0, 0.0, 0.01],
            angular: [0.0; 3],
            frame: TwistFrame::Tool,
        };
        streamer.start(up, Instant::now() + Duration::from_millis(50));
        std::thread::sleep(Duration::from_millis(150));
        let sent = fake.received();
        assert!(sent.len() >= 2, "{} sends", sent.len());
        assert_eq!((&sent[0][..2], sent[0][30]), (&b"TW"[..], 0x01));
        assert_eq!(
            &sent[0][2..30],
            &[0; 28],
            "the twist at rest, in the tool frame"
        );
        assert_eq!(&sent[1][10..14], &0.01f32.to_le_bytes());
    }
}
