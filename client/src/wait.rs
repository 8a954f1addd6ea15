//! Waiting for the arm: polling `PS` or `jP` until a target is reached, the arm stops, or a
//! notice says the motion ended.
//!
//! The protocol has no "motion done" message, so the client polls (20 Hz by default). A wait
//! ends
//!
//! * with success when the last target is reached (position within [`WaitOptions::tolerance`],
//!   orientation within [`WaitOptions::angle_tolerance`]);
//! * with [`ClientError::Aborted`] when a notice says the motion cannot complete (`ER21`,
//!   `WN22`, `WN27`, drive faults `ER3x`; see [`matching::ends_motion`]);
//! * with [`ClientError::Stalled`] when the arm has not moved for [`WaitOptions::stall`]
//!   (held short of the target without a motion-ending notice, e.g. clamped at a joint limit);
//! * with [`ClientError::WaitTimeout`] after [`WaitOptions::timeout`];
//! * with [`ClientError::Interrupted`] when [`WaitOptions::interrupt`] is set (Ctrl-C).
//!
//! A stall or timeout while the controller reports a stop cause (`SQ` 2) becomes
//! [`ClientError::Stopped`]: the motion was stopped, and the error says why and by whom. Any
//! other ending but arrival sends `ST` as [`WaitOptions::stop`] says (by default always) and
//! is returned as [`ClientError::Ended`], which says so: the wait's owner gave up on the motion,
//! so the arm must not go on alone ([`crate::ended`]).
//!
//! Notices that arrive during a wait are handed to the progress callback (and not left in
//! the client's queue).
//!
//! While it waits the client asks for the controller's client watchdog ([`watchdog_ms`]): its
//! polls feed it, and if the client dies or loses the network, the controller stops the arm
//! (`ER41`). A controller without one (the seed's) or another client holding the arm refuses;
//! the wait goes on without it.

use std::time::{Duration, Instant};

use armgate_protocol::client::Text;

use crate::ended::StopPolicy;
use crate::interrupt::Interrupt;
use crate::matching;
use crate::{Client, ClientError, Pose};

/// How a wait decides that a target is reached, and when it gives up.
#[derive(Clone, Debug, PartialEq)]
pub struct WaitOptions {
    /// The last target is reached within this distance (m for poses, rad or m for joints).
    pub tolerance: f64,
    /// The last pose target is reached only if the orientation is within this angle (rad).
    pub angle_tolerance: f64,
    /// An intermediate target (of a sequence) counts as passed within this distance: the arm
    /// does not dwell at via points, so a 20 Hz poll may never see it within `tolerance`.
    pub pass_tolerance: f64,
    /// Give up after this long.
    pub timeout: Duration,
    /// The polling period.
    pub poll: Duration,
    /// Give up if the arm has not moved for this long (`None`: never).
    pub stall: Option<Duration>,
    /// End the wait when this flag is set (checked at every poll).
    pub interrupt: Option<Interrupt>,
    /// When a wait that does not arrive sends `ST`.
    pub stop: StopPolicy,
}

impl Default for WaitOptions {
    /// 1 mm (or 1 mrad for joints), 0.01 rad, 10 mm to pass a via point, 10 min (the stall
    /// check ends a wait whose arm does not move; long moves must not be cut short), 20 Hz,
    /// stall after 3 s, `ST` on every ending but arrival.
    fn default() -> Self {
        Self {
            tolerance: 0.001,
            angle_tolerance: 0.01,
            pass_tolerance: 0.01,
            timeout: Duration::from_secs(600),
            poll: Duration::from_millis(50),
            stall: Some(Duration::from_secs(3)),
            interrupt: None,
            stop: StopPolicy::Always,
        }
    }
}

/// One poll's view of a wait, for a progress display.
#[derive(Debug)]
pub struct Progress<'a, T: ?Sized> {
    /// The measured pose or joints.
    pub current: &'a T,
    /// The 0-based number of the target being approached.
    pub target: usize,
    /// How many targets there are.
    pub targets: usize,
    /// The distance to the target (m for poses, rad or m for joints).
    pub distance: f64,
    /// For poses: the angle between the orientations (rad).
    pub angle: Option<f64>,
    /// The time since the wait started.
    pub elapsed: Duration,
    /// The notices that arrived since the previous poll.
    pub notices: &'a [Text],
}

/// Below this a measurement counts as unchanged (m, rad, or quaternion components).
const STILL: f64 = 1e-6;

/// The watchdog a wait asks for: twenty polls, at least a second (a loaded machine or a lost
/// datagram must not stop the arm).
pub fn watchdog_ms(poll: Duration) -> u16 {
    let ms = (poll * 20).as_millis().max(1000);
    u16::try_from(ms).unwrap_or(u16::MAX).min(60_000)
}

fn joint_distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn pose_moved(a: &Pose, b: &Pose) -> bool {
    a.distance(b) > STILL || a.angle_to(b) > STILL
}

impl Client {
    /// Polls `PS` until the pose is within the tolerances of `goal`. `progress` is called after
    /// every poll.
    pub fn wait_until_pose(
        &mut self,
        goal: &Pose,
        options: &WaitOptions,
        progress: impl FnMut(&Progress<'_, Pose>),
    ) -> Result<Pose, ClientError> {
        self.wait_through_poses(std::slice::from_ref(goal), options, progress)
    }

    /// Polls `PS` until the arm has passed `goals` in order (each but the last within
    /// [`WaitOptions::pass_tolerance`], position only) and reached the last one.
    pub fn wait_through_poses(
        &mut self,
        goals: &[Pose],
        options: &WaitOptions,
        progress: impl FnMut(&Progress<'_, Pose>),
    ) -> Result<Pose, ClientError> {
        self.wait_through(
            goals,
            options,
            Self::pose,
            |pose, goal, last| {
                let d = pose.distance(goal);
                let angle = pose.angle_to(goal);
                let reached = if last {
                    d <= options.tolerance && angle <= options.angle_tolerance
                } else {
                    d <= options.pass_tolerance
                };
                (d, Some(angle), reached)
            },
            pose_moved,
            progress,
        )
    }

    /// Polls `jP` (`goal.len()` joints) until the joints are within [`WaitOptions::tolerance`]
    /// (Euclidean norm) of `goal`.
    pub fn wait_until_joints(
        &mut self,
        goal: &[f64],
        options: &WaitOptions,
        progress: impl FnMut(&Progress<'_, [f64]>),
    ) -> Result<Vec<f64>, ClientError> {
        self.wait_through_joints(&[goal.to_vec()], options, progress)
    }

    /// Polls `jP` until the arm has passed the joint vectors `goals` in order and reached the
    /// last one.
    pub fn wait_through_joints(
        &mut self,
        goals: &[Vec<f64>],
        options: &WaitOptions,
        mut progress: impl FnMut(&Progress<'_, [f64]>),
    ) -> Result<Vec<f64>, ClientError> {
        let n = goals.first().map_or(0, Vec::len);
        self.wait_through(
            goals,
            options,
            |client| client.joints(n),
            |q: &Vec<f64>, goal: &Vec<f64>, last| {
                let d = joint_distance(q, goal);
                let tol = if last {
                    options.tolerance
                } else {
                    options.pass_tolerance
                };
                (d, None, d <= tol)
            },
            |a: &Vec<f64>, b: &Vec<f64>| a.iter().zip(b).any(|(x, y)| (x - y).abs() > STILL),
            |p: &Progress<'_, Vec<f64>>| {
                progress(&Progress {
                    current: p.current.as_slice(),
                    target: p.target,
                    targets: p.targets,
                    distance: p.distance,
                    angle: p.angle,
                    elapsed: p.elapsed,
                    notices: p.notices,
                })
            },
        )
    }

    /// Polls `PS` until the pose has not changed for `polls` consecutive polls (the arm is idle),
    /// within [`WaitOptions::timeout`].
    pub fn wait_idle(&mut self, polls: u32, options: &WaitOptions) -> Result<Pose, ClientError> {
        let started = Instant::now();
        let mut previous = self.pose()?;
        let mut still = 0;
        while still < polls {
            if started.elapsed() > options.timeout {
                return Err(ClientError::WaitTimeout {
                    target: 0,
                    distance: f64::NAN,
                    angle: None,
                    timeout: options.timeout,
                });
            }
            std::thread::sleep(options.poll);
            let pose = self.pose()?;
            still = if pose_moved(&pose, &previous) {
                0
            } else {
                still + 1
            };
            previous = pose;
        }
        Ok(previous)
    }

    /// The shared polling loop, with the controller's watchdog on while it runs; a wait that
    /// does not arrive is explained and ended ([`Client::end_wait`]).
    fn wait_through<T, F, M, P>(
        &mut self,
        goals: &[T],
        options: &WaitOptions,
        read: impl FnMut(&mut Self) -> Result<T, ClientError>,
        measure: F,
        moved: M,
        progress: P,
    ) -> Result<T, ClientError>
    where
        F: FnMut(&T, &T, bool) -> (f64, Option<f64>, bool),
        M: Fn(&T, &T) -> bool,
        P: FnMut(&Progress<'_, T>),
    {
        let watched = self.watchdog(watchdog_ms(options.poll)).is_ok();
        let result = self
            .poll_through(goals, options, read, measure, moved, progress)
            .map_err(|e| self.explain(e));
        if watched {
            // Best effort: a lost reply leaves it on, which only matters once the client is
            // silent while the arm moves.
            let _ = self.watchdog(0);
        }
        result.map_err(|e| self.end_wait(e, options.stop))
    }

    fn poll_through<T, F, M, P>(
        &mut self,
        goals: &[T],
        options: &WaitOptions,
        mut read: impl FnMut(&mut Self) -> Result<T, ClientError>,
        mut measure: F,
        moved: M,
        mut progress: P,
    ) -> Result<T, ClientError>
    where
        F: FnMut(&T, &T, bool) -> (f64, Option<f64>, bool),
        M: Fn(&T, &T) -> bool,
        P: FnMut(&Progress<'_, T>),
    {
        let started = Instant::now();
        let mut target = 0;
        let mut last_move = started;
        let mut previous: Option<T> = None;
        loop {
            let current = read(self)?;
            let notices = self.take_notices();
            let now = Instant::now();
            if previous.as_ref().is_none_or(|p| moved(p, &current)) {
                last_move = now;
            }
            // Advance over every target reached by this sample.
            let (mut distance, mut angle) = (f64::INFINITY, None);
            let mut arrived = goals.is_empty();
            while let Some(goal) = goals.get(target) {
                let last = target + 1 == goals.len();
                let (d, a, reached) = measure(&current, goal, last);
                (distance, angle) = (d, a);
                if !reached {
                    break;
                }
                if last {
                    arrived = true;
                    break;
                }
                target += 1;
            }
            progress(&Progress {
                current: &current,
                target,
                targets: goals.len(),
                distance,
                angle,
                elapsed: now - started,
                notices: &notices,
            });
            if arrived {
                return Ok(current);
            }
            if let Some(text) = notices.iter().find(|t| matching::ends_motion(t)) {
                return Err(ClientError::Aborted(*text));
            }
            if options.interrupt.as_ref().is_some_and(Interrupt::is_set) {
                return Err(ClientError::Interrupted);
            }
            if let Some(stall) = options.stall
                && now - last_move > stall
            {
                return Err(ClientError::Stalled {
                    target,
                    distance,
                    angle,
                    after: stall,
                });
            }
            if now - started > options.timeout {
                return Err(ClientError::WaitTimeout {
                    target,
                    distance,
                    angle,
                    timeout: options.timeout,
                });
            }
            previous = Some(current);
            std::thread::sleep(options.poll);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ClientConfig;
    use crate::fake::{FakeController, text};
    use armgate_protocol::client::{Command, Message, Reply, Request};
    use std::sync::{Arc, Mutex};

    /// A fake arm that moves 10 mm along x per PS poll towards `target` once BG is received,
    /// optionally sending a notice when it is at `notice_at` steps.
    fn arm(start: f64, target: f64, notice: Option<(usize, &'static str)>) -> FakeController {
        stopped_arm(start, target, notice, None)
    }

    /// [`arm`], stopped after `stop.0` steps with the `SQ` 2 report `stop.1` (f0..f4).
    fn stopped_arm(
        start: f64,
        target: f64,
        notice: Option<(usize, &'static str)>,
        stop: Option<(usize, [f32; 5])>,
    ) -> FakeController {
        let state = Arc::new(Mutex::new((start, false, 0usize)));
        FakeController::spawn(move |datagram| {
            let message = Message::new_checked(datagram).unwrap();
            let request = Request::parse(&message).unwrap();
            let mut s = state.lock().unwrap();
            let mut out = vec![];
            match request.command {
                Command::Begin => s.1 = true,
                Command::Pose => {
                    if stop.is_some_and(|(at, _)| s.2 >= at) {
                        s.1 = false;
                    }
                    if s.1 {
                        s.0 = if (target - s.0).abs() < 0.01 {
                            target
                        } else {
                            s.0 + 0.01 * (target - s.0).signum()
                        };
                        s.2 += 1;
                    }
                    if let Some((at, t)) = notice
                        && s.2 == at
                    {
                        out.push(text(t));
                    }
                    let mut reply = Reply::null(Command::Pose);
                    reply.values = [s.0 as f32, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
                    out.push(reply.to_bytes().to_vec());
                    return out;
                }
                Command::Status => {
                    let mut reply = Reply::null(Command::Status);
                    reply.index = request.index;
                    if let Some((at, report)) = stop
                        && s.2 >= at
                    {
                        reply.values[..5].copy_from_slice(&report);
                    }
                    out.push(reply.to_bytes().to_vec());
                    return out;
                }
                _ => {}
            }
            out.push(Reply::null(request.command).to_bytes().to_vec());
            out
        })
    }

    /// The requests' characters the fake received.
    fn sent(fake: &FakeController) -> Vec<String> {
        fake.received()
            .iter()
            .map(|d| String::from_utf8_lossy(&d[..2]).into_owned())
            .collect()
    }

    fn options() -> WaitOptions {
        WaitOptions {
            poll: Duration::from_millis(1),
            timeout: Duration::from_secs(5),
            stall: Some(Duration::from_millis(200)),
            ..WaitOptions::default()
        }
    }

    /// Why a wait ended, and whether it sent ST ([`ClientError::Ended`]).
    fn ended(err: ClientError) -> (ClientError, Option<crate::ended::EndStop>) {
        match err {
            ClientError::Ended { error, stop } => (*error, Some(stop)),
            other => (other, None),
        }
    }

    fn client(fake: &FakeController) -> Client {
        Client::connect_with(fake.addr(), ClientConfig::default()).unwrap()
    }

    #[test]
    fn waits_until_the_pose_is_reached_reporting_progress() {
        let fake = arm(0.0, 0.1, None);
        let mut c = client(&fake);
        c.begin().unwrap();
        let goal = Pose::from_xyz_rpy([0.1, 0.0, 0.0], [0.0; 3]);
        let mut distances = vec![];
        let pose = c
            .wait_until_pose(&goal, &options(), |p| distances.push(p.distance))
            .unwrap();
        assert!(pose.distance(&goal) <= 0.001);
        assert!(distances.len() >= 10, "{distances:?}");
        assert!(distances.windows(2).all(|w| w[1] <= w[0] + 1e-9));
    }

    #[test]
    fn passes_intermediate_targets_in_order() {
        // Two targets at one point: the first is passed, then the last is reached.
        let fake = arm(0.0, 0.05, None);
        let mut c = client(&fake);
        c.begin().unwrap();
        let goals = [
            Pose::from_xyz_rpy([0.05, 0.0, 0.0], [0.0; 3]),
            Pose::from_xyz_rpy([0.05, 0.0, 0.0], [0.0; 3]),
        ];
        let mut targets = vec![];
        c.wait_through_poses(&goals, &options(), |p| targets.push(p.target))
            .unwrap();
        assert_eq!(targets.first(), Some(&0));
        assert_eq!(targets.last(), Some(&1));
    }

    #[test]
    fn a_motion_ending_notice_aborts_and_is_reported() {
        let fake = arm(0.0, 0.1, Some((3, "WN27 Via point missed.")));
        let mut c = client(&fake);
        c.begin().unwrap();
        let goal = Pose::from_xyz_rpy([0.1, 0.0, 0.0], [0.0; 3]);
        let mut seen = vec![];
        let err = c
            .wait_until_pose(&goal, &options(), |p| {
                seen.extend(p.notices.iter().map(|t| t.as_str().to_owned()))
            })
            .unwrap_err();
        assert!(matches!(err, ClientError::Aborted(t) if t.as_str() == "WN27 Via point missed."));
        assert_eq!(seen, ["WN27 Via point missed."]);
    }

    #[test]
    fn a_warning_that_does_not_end_the_motion_is_only_reported() {
        let fake = arm(0.0, 0.05, Some((2, "WN12 Joint limit.")));
        let mut c = client(&fake);
        c.begin().unwrap();
        let goal = Pose::from_xyz_rpy([0.05, 0.0, 0.0], [0.0; 3]);
        let mut seen = 0;
        c.wait_until_pose(&goal, &options(), |p| seen += p.notices.len())
            .unwrap();
        assert_eq!(seen, 1);
    }

    #[test]
    fn an_arm_that_does_not_move_stalls() {
        let fake = arm(0.0, 0.1, None);
        let mut c = client(&fake);
        // No BG: the arm never moves.
        let goal = Pose::from_xyz_rpy([0.1, 0.0, 0.0], [0.0; 3]);
        let err = c.wait_until_pose(&goal, &options(), |_| {}).unwrap_err();
        assert!(
            err.to_string()
                .ends_with("; sent ST: the arm stops and holds")
        );
        let (err, stop) = ended(err);
        assert!(
            matches!(err, ClientError::Stalled { target: 0, distance, .. } if (distance - 0.1).abs() < 1e-6),
            "{err:?}"
        );
        assert_eq!(stop, Some(crate::ended::EndStop::Sent));
        // No stop cause in force (SQ 2 asked first), then this client's ST.
        let sent = sent(&fake);
        assert_eq!(sent[sent.len() - 3..], ["SQ", "WD", "ST"]);
        let mut opts = options();
        opts.stall = None;
        opts.timeout = Duration::from_millis(100);
        let (err, _) = ended(c.wait_until_pose(&goal, &opts, |_| {}).unwrap_err());
        assert!(matches!(err, ClientError::WaitTimeout { .. }));
        assert_eq!(
            ClientError::Ended {
                error: Box::new(err),
                stop: crate::ended::EndStop::Sent
            }
            .exit_code(),
            crate::exit::NOT_ARRIVED
        );
    }

    #[test]
    fn a_motion_another_client_stopped_says_why_and_who_and_is_not_stopped_again() {
        // Cause 1 (ST) set by 127.0.0.1:40001 after three steps.
        let report = [1.0, 0.0, 32512.0, 1.0, 40001.0];
        let fake = stopped_arm(0.0, 0.1, None, Some((3, report)));
        let mut c = client(&fake);
        c.begin().unwrap();
        let goal = Pose::from_xyz_rpy([0.1, 0.0, 0.0], [0.0; 3]);
        let err = c.wait_until_pose(&goal, &options(), |_| {}).unwrap_err();
        assert_eq!(
            err.to_string(),
            "the motion was stopped by client 127.0.0.1:40001: ST (target 1 not reached)"
        );
        let ClientError::Stopped { cause, by, .. } = err else {
            panic!("{err:?}")
        };
        assert_eq!(cause, crate::status::StopCause::Stop);
        assert_eq!(
            by,
            crate::ended::Stopper::Client("127.0.0.1:40001".parse().unwrap())
        );
        assert!(!sent(&fake).contains(&"ST".to_owned()));
        // The workspace: the controller's own cause.
        let fake = stopped_arm(0.0, 0.1, None, Some((2, [4.0, 0.0, 0.0, 0.0, 0.0])));
        let mut c = client(&fake);
        c.begin().unwrap();
        let err = c.wait_until_pose(&goal, &options(), |_| {}).unwrap_err();
        assert!(
            matches!(
                err,
                ClientError::Stopped {
                    by: crate::ended::Stopper::Controller,
                    ..
                }
            ),
            "{err:?}"
        );
        assert_eq!(err.exit_code(), crate::exit::STOPPED);
    }

    #[test]
    fn wrong_orientation_is_not_arrival() {
        let fake = arm(0.1, 0.1, None);
        let mut c = client(&fake);
        let goal = Pose::from_xyz_rpy([0.1, 0.0, 0.0], [0.0, 0.0, 0.5]);
        let (err, _) = ended(c.wait_until_pose(&goal, &options(), |_| {}).unwrap_err());
        assert!(matches!(err, ClientError::Stalled { .. }));
        let goal = Pose::from_xyz_rpy([0.1, 0.0, 0.0], [0.0, 0.0, 0.005]);
        c.wait_until_pose(&goal, &options(), |_| {}).unwrap();
    }

    /// A wait through a fake arm, interrupted at the third poll under `policy`.
    fn interrupted(policy: StopPolicy) -> (ClientError, Vec<Vec<u8>>) {
        let fake = arm(0.0, 0.1, None);
        let mut c = client(&fake);
        c.begin().unwrap();
        let goal = Pose::from_xyz_rpy([0.1, 0.0, 0.0], [0.0; 3]);
        let mut opts = options();
        opts.stop = policy;
        let flag = Interrupt::new();
        opts.interrupt = Some(flag.clone());
        let mut polls = 0;
        let err = c
            .wait_until_pose(&goal, &opts, |_| {
                polls += 1;
                if polls == 3 {
                    flag.set();
                }
            })
            .unwrap_err();
        assert_eq!(polls, 3);
        (err, fake.received())
    }

    #[test]
    fn an_interrupt_ends_the_wait_and_stops_the_arm_unless_told_not_to() {
        let (err, sent) = interrupted(StopPolicy::Always);
        assert_eq!(
            err.to_string(),
            "interrupted; sent ST: the arm stops and holds"
        );
        assert_eq!(err.exit_code(), crate::exit::INTERRUPTED);
        // The watchdog, PS polls, the watchdog off, then ST.
        assert_eq!(&sent[1][..2], b"WD");
        assert_eq!(&sent[sent.len() - 2][..6], b"WD\0\0\0\0");
        assert_eq!(&sent[sent.len() - 1][..2], b"ST");
        assert!(sent[2..sent.len() - 2].iter().all(|d| &d[..2] == b"PS"));
        let (err, sent) = interrupted(StopPolicy::ExceptInterrupt);
        assert_eq!(
            err.to_string(),
            "interrupted; no ST sent, as asked: the arm goes on moving"
        );
        assert!(sent.iter().all(|d| &d[..2] != b"ST"));
        let (err, sent) = interrupted(StopPolicy::Never);
        assert!(matches!(err, ClientError::Interrupted));
        assert!(sent.iter().all(|d| &d[..2] != b"ST"));
    }

    #[test]
    fn idle_after_consecutive_unchanged_polls() {
        let fake = arm(0.0, 0.03, None);
        let mut c = client(&fake);
        c.begin().unwrap();
        let pose = c.wait_idle(3, &options()).unwrap();
        assert!((pose.xyz[0] - 0.03).abs() < 1e-6);
    }

    #[test]
    fn joints_wait() {
        let fake = FakeController::spawn(|datagram| {
            let m = Message::new_checked(datagram).unwrap();
            let command = Request::parse(&m).unwrap().command;
            let mut reply = Reply::null(command);
            if command == Command::JointPosition {
                reply.values = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.0];
            }
            reply.index = m.index();
            vec![reply.to_bytes().to_vec()]
        });
        let mut c = client(&fake);
        let q = c
            .wait_until_joints(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6], &options(), |_| {})
            .unwrap();
        assert_eq!(q.len(), 6);
        let err = c
            .wait_until_joints(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.7], &options(), |_| {})
            .unwrap_err();
        assert!(matches!(ended(err), (ClientError::Stalled { .. }, Some(_))));
    }
}
