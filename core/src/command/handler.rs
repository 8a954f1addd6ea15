//! The command handler: one client datagram in, one reply out.
//!
//! The requests' handling, one concern a file: `handler/cartesian.rs` (Cartesian goals, moves,
//! via points, the twist stream), `handler/joint.rs` (the joint ones), `handler/ik_requests.rs`
//! (`KG`, `KR`, `KS`), `handler/planning.rs` (the requests whose work runs in slices across
//! ticks: `KG`'s search, `BG`'s and `VE`'s line check), `handler/reads.rs` (`PS`, `jP`, `TM`, `SQ`), `handler/power.rs` (`ON`,
//! `OF`, `RC`); `handler/replies.rs` makes the replies and refusal texts.

mod cartesian;
mod handover;
mod ik_requests;
mod joint;
mod planning;
mod power;
mod reads;
mod replies;

use armgate_protocol::client::signed::{IdentityReport, SigningReport};
use core::net::{Ipv4Addr, SocketAddr};

use armgate_protocol::client::{
    Command, MESSAGE_LEN, Message, Motion, NAME_INDEX, Notice, Reply, Request, RobotName,
    SESSION_INDEX, Text,
};

use super::banks::{BankKey, Banks};
use super::drives::Drives;
use super::redundancy::RedundancyChoice;
use super::relay::NoticeRelay;
use super::session::Session;
use super::status::Status;
use crate::config::ValidRobot;
use crate::kinematics::{Joints, KinematicsError};
use crate::math::Frame;
use crate::motion::{Controller, Mode, Refusal, StepOutput, StopCause};
use handover::Cleared;
use planning::Planning;
pub use planning::Slice;
use replies::{operational, refusal_notice, values_reply};

/// Owns the [`Controller`] and the client-facing state: the stored Cartesian and joint goals,
/// staged joint banks and the warning relay.
///
/// Semantics are the ones the seed intended (spec §2.8): BG/jB/VE/jE are refused with `ER20`
/// when there is no goal, in the wrong mode, while something moves or while the drives are not
/// operational. Every refusal names its reason after `ERnn Cmd XX` (docs/protocol.md), and
/// Cartesian moves are refused up front when the arm cannot follow the line to the goal. Its
/// defects are fixed (spec §9): VC answers `CV` and RC `CR`; NaN/Inf values and zero
/// quaternions are refused (`ER23`) instead of poisoning state; via indices ≥ 20 are refused
/// (`ER24`), and so are bank-2 `jP`/`TM` on six joints; jB needs a prior jG; VP no longer
/// overwrites the BG goal; negative durations are clamped to 0.
#[derive(Clone, Debug)]
pub struct CommandHandler {
    controller: Controller,
    /// The BG goal and its minimum duration (GL/GT).
    goal: Option<(Frame, f64)>,
    /// The jB goal (jG).
    joint_goal: Option<Joints>,
    banks: Banks,
    /// The redundancy values a client chose with `KR`.
    redundancy: RedundancyChoice,
    /// What a change of holder cleared (the holder's own state: `handler/handover.rs`).
    cleared: Cleared,
    relay: NoticeRelay,
    session: Session,
    /// The robot's name, for the status request.
    name: RobotName,
    /// Requests answered with an `ER` text so far.
    refused: u32,
    /// The cycle's signing counters, for `SQ` index 4.
    signing: SigningReport,
    /// The controller's id and shared links, for `SQ` index 6.
    identity: IdentityReport,
    /// Time of the last tick (s).
    now: f64,
    /// The client whose request is being handled.
    client: SocketAddr,
    /// The client whose request set the stop cause in force (`SQ` 2 names it).
    stopped_by: Option<SocketAddr>,
    /// `OF` while moving: the drives stop when the arm is at rest, or at this time (s).
    power_off_at: Option<f64>,
    /// The longest a stop from full speed may take (s), with a margin: the bound on `OF`'s wait.
    stop_within: f64,
    /// A planning request whose work runs in slices across ticks (`handler/planning.rs`).
    planning: Option<Planning>,
}

impl CommandHandler {
    /// A handler for a validated robot description.
    // Out of line: built once, at start; inlined, it would sit in the control task's code.
    #[inline(never)]
    pub fn new(config: &ValidRobot) -> Self {
        Self {
            controller: Controller::new(config),
            goal: None,
            joint_goal: None,
            banks: Banks::default(),
            redundancy: RedundancyChoice::default(),
            cleared: Cleared::default(),
            relay: NoticeRelay::default(),
            session: Session::default(),
            name: RobotName::new(&config.name),
            refused: 0,
            signing: SigningReport::default(),
            identity: IdentityReport::default(),
            now: 0.0,
            client: ANONYMOUS,
            stopped_by: None,
            power_off_at: None,
            stop_within: stop_time_bound(config),
            planning: None,
        }
    }

    /// What the controller and the drives are doing (what `SQ` reports).
    pub fn status(&self, drives: &(impl Drives + ?Sized)) -> Status {
        Status {
            mode: self.controller.mode(),
            drives: drives.status(),
            fault: drives.fault_code(),
            joints: self.controller.chain().dof(),
            motion: self.controller.motion(),
            refused: self.refused,
            uptime: self.now,
        }
    }

    /// The signing counters `SQ` index 4 reports (kept by the cycle, which checks signatures
    /// before a datagram reaches the handler).
    pub fn set_signing_report(&mut self, report: SigningReport) {
        self.signing = report;
    }

    /// Who the controller is and what it saw of shared link ids, for `SQ` index 6 (kept by the
    /// cycle, as the signing counters).
    pub fn set_identity(&mut self, identity: IdentityReport) {
        self.identity = identity;
    }

    /// The controller.
    pub fn controller(&self) -> &Controller {
        &self.controller
    }

    /// The controller, mutable: for test rigs and benches that command it directly instead of
    /// through client requests.
    pub fn controller_mut(&mut self) -> &mut Controller {
        &mut self.controller
    }

    /// One control tick (see [`Controller::step`]); its events feed the warning relay.
    /// While the drives take no commands (starting, stopped, or stopped by a fault, when they
    /// hold their last point) the controller holds the measured position, so motion resumes
    /// from where the arm is; motion requests are refused meanwhile
    /// ([`Drives::is_operational`]).
    ///
    /// An `OF` that came while the arm moved stops the drives here, once the supervisor has
    /// brought the arm to rest (or the bound on a stop's time has passed).
    pub fn tick(
        &mut self,
        now: f64,
        measured: &[f64],
        drives: &mut (impl Drives + ?Sized),
    ) -> Result<StepOutput, KinematicsError> {
        let faulted = drives.has_fault();
        self.now = now;
        if !matches!(self.controller.motion(), Motion::Holding | Motion::Stopping)
            && let Some(ms) = self.session.silent(now)
        {
            self.stop(StopCause::ClientSilent);
            self.relay.announce(Notice::ClientSilent(ms).text());
        }
        // The step's result is returned as it is, not unwrapped and wrapped again: the
        // Cortex-M7 would copy the 296-byte output twice, unaligned (≈ 2,100 instructions a
        // tick in qemu-bench).
        let out = self.controller.step(now, measured);
        let Ok(step) = &out else {
            return out;
        };
        if let Some(deadline) = self.power_off_at
            && (!self.controller.is_moving() || now >= deadline)
        {
            self.power_off_at = None;
            let _ = drives.stop();
        }
        if !drives.is_operational() {
            self.controller.release();
        }
        self.relay.observe(now, &step.events);
        self.relay.observe_fault(faulted, || drives.fault());
        self.relay.observe_drive_notice(drives.notice());
        out
    }

    /// Queues an unsolicited notice the cycle observed (a link id shared by two clients).
    pub fn announce(&mut self, notice: Notice) {
        self.relay.announce(notice.text());
    }

    /// The next unsolicited warning for the client, if any.
    pub fn next_notice(&mut self) -> Option<Text> {
        self.relay.pop()
    }

    /// Warnings dropped because too many were waiting.
    pub fn dropped_notices(&self) -> u32 {
        self.relay.dropped()
    }

    /// Handles one datagram of any length from a client that gives no address (tests, the
    /// recorded exchange): [`handle_from`](Self::handle_from) the unspecified address.
    pub fn handle(
        &mut self,
        datagram: &[u8],
        drives: &mut (impl Drives + ?Sized),
    ) -> [u8; MESSAGE_LEN] {
        self.handle_at_once(datagram, ANONYMOUS, drives)
    }

    /// [`handle_from`](Self::handle_from), with the work of a planning request (a `KG`'s
    /// global search, a `BG`'s line check) run to its end at once (callers outside the cycle's
    /// ticks: tests, protocol checks between ticks).
    pub fn handle_at_once(
        &mut self,
        datagram: &[u8],
        client: SocketAddr,
        drives: &mut (impl Drives + ?Sized),
    ) -> [u8; MESSAGE_LEN] {
        let reply = self.handle_from(datagram, client, drives);
        if !self.planning_started() {
            return reply;
        }
        self.continue_planning(Slice::WHOLE, datagram, drives)
            .unwrap_or(reply)
    }

    /// Handles one datagram of any length from `client` and returns the reply datagram. A
    /// datagram that does not parse is answered and changes nothing else; a valid one is
    /// admitted by the session first (who may command the arm, [`Session`]).
    pub fn handle_from(
        &mut self,
        datagram: &[u8],
        client: SocketAddr,
        drives: &mut (impl Drives + ?Sized),
    ) -> [u8; MESSAGE_LEN] {
        let request = match Message::new_checked(datagram).and_then(|m| Request::parse(&m)) {
            Ok(request) => request,
            Err(e) => return self.refuse(Notice::from(e)),
        };
        if let Some(reply) = self.session.resent(client, datagram, self.now) {
            return reply;
        }
        let busy = self.controller.motion() != Motion::Holding;
        self.client = client;
        let holder = self.session.holder();
        let admitted = self.session.admit(request.command, client, self.now, busy);
        if self.session.holder() != holder {
            self.hand_over();
        }
        let cause = self.controller.stop_cause().0;
        let reply = admitted
            .and_then(|()| self.answer(&request, client, drives))
            .unwrap_or_else(|notice| self.refuse(notice));
        if self.controller.stop_cause().0 != cause {
            self.stopped_by = Some(client);
        }
        if self.planning.as_ref().is_some_and(Planning::is_fresh) {
            // Not the answer: that comes when the work ends, and is recorded then.
            return reply;
        }
        self.session
            .answered(client, request.command, datagram, &reply, self.now);
        reply
    }

    /// Counts a refusal the cycle answered itself (a request cancelled by a stop).
    pub fn count_refusal(&mut self) {
        self.refused = self.refused.saturating_add(1);
    }

    /// The text of a refusal, counted.
    fn refuse(&mut self, notice: Notice) -> [u8; MESSAGE_LEN] {
        self.refused = self.refused.saturating_add(1);
        notice.text().to_bytes()
    }

    /// Where the notices go: the client that holds the arm, or the last one that sent a valid
    /// request.
    pub fn notice_recipient(&self) -> Option<SocketAddr> {
        self.session.notice_recipient()
    }

    /// The client that holds the arm.
    pub fn holder(&self) -> Option<SocketAddr> {
        self.session.holder()
    }

    /// The shell's count of replies and notices it could not send (`SQ` index 3 reports it).
    pub fn set_send_drops(&mut self, drops: u64) {
        self.session.set_send_drops(drops);
    }

    /// The reply datagram to a request from `client`: the name reply to `SQ` index 1 is the
    /// one that is not seven floats; the session report depends on who asks.
    fn answer(
        &mut self,
        req: &Request,
        client: SocketAddr,
        drives: &mut (impl Drives + ?Sized),
    ) -> Result<[u8; MESSAGE_LEN], Notice> {
        match (req.command, req.index) {
            (Command::Status, NAME_INDEX) => Ok(self.name.to_bytes()),
            (Command::Status, SESSION_INDEX) => {
                Ok(self.session.report(client).to_reply().to_bytes())
            }
            _ => self.execute(req, drives).map(|reply| reply.to_bytes()),
        }
    }

    /// Every request but the two `SQ` reports that are not seven floats: one method a request,
    /// grouped by concern in `handler/` (cartesian, joint, ik_requests, reads, power).
    fn execute(
        &mut self,
        req: &Request,
        drives: &mut (impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        match cmd {
            Command::Begin => self.begin(req, drives),
            Command::ChangeMode => {
                self.banks.clear();
                // The seed accepted any value, e.g. 3, then forced mode 0 (spec §9 item 17).
                let mode = Mode::from_value(req.values[0]).ok_or(Notice::BadNumber(cmd))?;
                self.controller
                    .set_mode(mode)
                    .map_err(|r| refusal_notice(cmd, r))?;
                Ok(values_reply(cmd, &[f64::from(mode.value())], 0))
            }
            Command::GoalQuaternion => self.goal_quaternion(req),
            Command::GoalRpy => self.goal_rpy(req),
            Command::IkGoal => self.ik_goal(req, drives),
            Command::IkRedundancy => self.choose_redundancy(req),
            Command::IkSolution => self.ik_solution(req),
            Command::JointBegin => self.joint_begin(req, drives),
            Command::JointClear => {
                self.controller.clear_joint_via();
                self.cleared.joint_via = false;
                Ok(Reply::null(cmd))
            }
            Command::JointExecute => self.run_sequence(req, drives),
            Command::JointGoal => self.joint_goal(req),
            Command::JointPosition => self.joint_position(req),
            Command::JointVelocity => self.joint_velocity(req, drives),
            Command::JointReset | Command::Stop => {
                self.stop(StopCause::Stop);
                Ok(Reply::null(cmd))
            }
            Command::Watchdog => {
                let ms = f64::from(req.values[0]);
                if !(0.0..=f64::from(MAX_WATCHDOG_MS)).contains(&ms) {
                    return Err(Notice::BadNumber(cmd));
                }
                let ms = libm::round(ms) as u16;
                self.session.set_watchdog(ms);
                Ok(values_reply(cmd, &[f64::from(ms)], 0))
            }
            Command::JointVia => self.joint_via(req),
            Command::On => self.power_on(req, drives),
            Command::Off => self.power_off(req, drives),
            Command::Pose => self.pose(req),
            Command::Recalibrate => self.recalibrate(req, drives),
            Command::Status => self.status_report(req, drives),
            Command::Temperature => self.temperature(req, drives),
            Command::Twist => self.twist(req, drives),
            Command::ViaClear => {
                self.controller.clear_cartesian_via();
                self.cleared.cartesian_via = false;
                Ok(Reply::null(cmd))
            }
            Command::ViaExecute => self.run_sequence(req, drives),
            Command::ViaTolerance | Command::JointViaTolerance => self.blend_tolerance(req),
            Command::ViaPoint => self.via_point(req),
        }
    }

    /// Stops the arm: `ST`, `jR`, and the client watchdog (one path for all of them).
    /// Every stop from the command layer: the staged banks and the `KR` choice go, the
    /// supervisor brings the arm to rest.
    fn stop(&mut self, cause: StopCause) {
        self.banks.clear();
        self.redundancy.clear();
        self.controller.stop(cause);
    }

    /// A wrong mode is reported before the drives' state: it outlasts it.
    fn in_mode(&self, cmd: Command) -> Result<(), Notice> {
        if Mode::required_by(cmd) == Some(self.controller.mode()) {
            Ok(())
        } else {
            Err(refusal_notice(cmd, Refusal::WrongMode))
        }
    }

    /// A motion request needs its mode, then running drives.
    fn ready_to_move(&self, cmd: Command, drives: &(impl Drives + ?Sized)) -> Result<(), Notice> {
        self.in_mode(cmd)?;
        operational(drives, cmd)
    }

    fn stage(&mut self, key: BankKey, values: &[f64], cmd: Command) -> Result<(), Notice> {
        let n = self.controller.chain().dof();
        self.banks
            .stage(key, values, n, self.client, self.now)
            .map_err(|_| Notice::BadIndex(cmd))
    }

    fn complete(&mut self, key: BankKey, values: &[f64], cmd: Command) -> Result<Joints, Notice> {
        let n = self.controller.chain().dof();
        self.banks
            .complete(key, values, n, self.client, self.now)
            .map_err(|_| Notice::BadIndex(cmd))
    }
}

/// The longest client watchdog (ms): a minute.
const MAX_WATCHDOG_MS: u16 = 60_000;

/// The address of a client that gives none.
const ANONYMOUS: SocketAddr = SocketAddr::new(core::net::IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0);

/// The longest a stop from full speed may take (s): every joint from its top speed at its
/// acceleration (plus the jerk ramp), and the Cartesian components likewise, doubled, plus
/// half a second.
fn stop_time_bound(config: &ValidRobot) -> f64 {
    let ramp = |v: f64, a: f64, j: Option<f64>| v / a + j.map_or(0.0, |j| a / j);
    let joints = config.joints.iter().map(|j| {
        ramp(
            j.max_velocity.min(j.max_rate),
            j.max_acceleration,
            j.max_jerk,
        )
    });
    let c = &config.cartesian;
    let cartesian = (0..6).map(|k| {
        let at = |v: &[f64; 6]| v.get(k).copied().unwrap_or(0.0);
        let jerk = c.max_jerk.as_ref().map(at);
        ramp(at(&c.max_velocity), at(&c.max_acceleration), jerk)
    });
    2.0 * joints.chain(cartesian).fold(0.0, f64::max) + 0.5
}
