//! The command handler: one client datagram in, one reply out.

use armgate_protocol::client::banks::READ_JOINTS;
use armgate_protocol::client::branch::BRANCH_INDEX;
use armgate_protocol::client::signed::{SIGNING_INDEX, SigningReport};
use core::net::{Ipv4Addr, SocketAddr};

use armgate_protocol::client::{
    BlendTolerance, CAUSE_INDEX, CauseReport, Command, DriveStatus, JointRates, MESSAGE_LEN,
    Message, Motion, NAME_INDEX, NO_JOINT_TEMPERATURE, Notice, Rejection, Reply, Request,
    RobotName, SESSION_INDEX, STATUS_INDEX, Text, Twist as TwistRequest, VALUES, WorkspaceReason,
};

use super::banks::{BANK_2, BANK_LEN, BankKey, Banks};
use super::drives::Drives;
use super::ik::{self, IkRequestError};
use super::relay::NoticeRelay;
use super::session::Session;
use super::status::Status;
use crate::config::ValidRobot;
use crate::kinematics::{Joints, KinematicsError};
use crate::math::{self, Frame, Quaternion, Rotation3, Twist, Vector3};
use crate::motion::{Controller, Mode, Refusal, StepOutput, StopCause};

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
    relay: NoticeRelay,
    session: Session,
    /// The robot's name, for the status request.
    name: RobotName,
    /// Requests answered with an `ER` text so far.
    refused: u32,
    /// The cycle's signing counters, for `SQ` index 4.
    signing: SigningReport,
    /// Time of the last tick (s).
    now: f64,
    /// The client whose request is being handled.
    client: SocketAddr,
    /// `OF` while moving: the drives stop when the arm is at rest, or at this time (s).
    power_off_at: Option<f64>,
    /// The longest a stop from full speed may take (s), with a margin: the bound on `OF`'s wait.
    stop_within: f64,
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
            relay: NoticeRelay::default(),
            session: Session::default(),
            name: RobotName::new(&config.name),
            refused: 0,
            signing: SigningReport::default(),
            now: 0.0,
            client: ANONYMOUS,
            power_off_at: None,
            stop_within: stop_time_bound(config),
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
        self.handle_from(datagram, ANONYMOUS, drives)
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
        let reply = self
            .session
            .admit(request.command, client, self.now, busy)
            .and_then(|()| self.answer(&request, client, drives))
            .unwrap_or_else(|notice| self.refuse(notice));
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

    fn execute(
        &mut self,
        req: &Request,
        drives: &mut (impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        let v = req.values.map(f64::from);
        let slot = usize::from(req.index & !BANK_2);
        let bank_2 = req.index & BANK_2 != 0;
        let refused = |r: Refusal| refusal_notice(cmd, r);
        let null = Reply::null(cmd);
        let n = self.controller.chain().dof();
        match cmd {
            Command::Begin => {
                let (goal, duration) = self.goal.ok_or(Notice::Rejected(cmd, Rejection::NoGoal))?;
                self.in_mode(cmd)?;
                operational(drives, cmd)?;
                self.controller
                    .move_cartesian(goal, duration)
                    .map_err(refused)?;
                Ok(null)
            }
            Command::ChangeMode => {
                self.banks.clear();
                // The seed accepted any value, e.g. 3, then forced mode 0 (spec §9 item 17).
                let mode = Mode::from_value(req.values[0]).ok_or(Notice::BadNumber(cmd))?;
                self.controller.set_mode(mode).map_err(refused)?;
                Ok(values_reply(cmd, &[f64::from(mode.value())], 0))
            }
            Command::GoalQuaternion => {
                let [x, y, z, qx, qy, qz, qw] = v;
                let q = Quaternion::new(qx, qy, qz, qw)
                    .normalized()
                    .ok_or(Notice::BadNumber(cmd))?;
                let goal = Frame::from_parts(Vector3::new(x, y, z).into(), q.to_rotation());
                self.controller
                    .check_cartesian_goal(&goal)
                    .map_err(refused)?;
                self.goal = Some((goal, 0.0));
                let [a, b, c, d] = q.to_array();
                Ok(values_reply(cmd, &[x, y, z, a, b, c, d], 0))
            }
            Command::GoalRpy => {
                let [x, y, z, roll, pitch, yaw, t] = v;
                let duration = non_negative(t).ok_or(Notice::BadNumber(cmd))?;
                let rotation = Rotation3::from_euler_angles(roll, pitch, yaw);
                let goal = Frame::from_parts(Vector3::new(x, y, z).into(), rotation);
                self.controller
                    .check_cartesian_goal(&goal)
                    .map_err(refused)?;
                self.goal = Some((goal, duration));
                Ok(values_reply(cmd, &[x, y, z, roll, pitch, yaw, duration], 0))
            }
            Command::IkGoal => {
                let duration = non_negative(v[6]).ok_or(Notice::BadNumber(cmd))?;
                self.in_mode(cmd)?;
                operational(drives, cmd)?;
                let (present, _) = self.controller.measured().ok_or(no_measurement(cmd))?;
                let chain = self.controller.chain();
                let ik = self.controller.ik_config();
                let (goal, branch) =
                    ik::goal(chain, ik, &present, &v, req.index).map_err(|e| ik_notice(cmd, e))?;
                self.controller
                    .move_joints(&goal, duration)
                    .map_err(refused)?;
                let mut values = [0.0; VALUES];
                for (o, q) in values.iter_mut().zip(goal.iter()) {
                    *o = *q;
                }
                values[VALUES - 1] = duration;
                Ok(values_reply(cmd, &values, branch))
            }
            Command::IkSolution => {
                let reference = self
                    .controller
                    .measured()
                    .map_or_else(|| self.controller.chain().mid_range(), |(q, _)| q);
                ik::solution(self.controller.chain(), &reference, &v, req.index)
                    .map_err(|e| ik_notice(cmd, e))
            }
            Command::JointBegin => {
                let goal = self
                    .joint_goal
                    .ok_or(Notice::Rejected(cmd, Rejection::NoGoal))?;
                self.in_mode(cmd)?;
                operational(drives, cmd)?;
                self.controller.move_joints(&goal, 0.0).map_err(refused)?;
                Ok(null)
            }
            Command::JointClear => {
                self.controller.clear_joint_via();
                Ok(null)
            }
            Command::JointExecute => {
                self.in_mode(cmd)?;
                operational(drives, cmd)?;
                self.controller.start_joint_sequence().map_err(refused)?;
                Ok(null)
            }
            Command::JointGoal => {
                let joints = bank_values(&v, cmd)?;
                if bank_2 {
                    self.stage(BankKey::Goal, joints, cmd)?;
                } else {
                    let q = self.complete(BankKey::Goal, joints, cmd)?;
                    self.joint_goal = Some(self.controller.check_joint_goal(&q).map_err(refused)?);
                }
                // The seed's f6 was stale (spec §9 item 9).
                Ok(values_reply(cmd, joints, req.index & BANK_2))
            }
            Command::JointPosition => {
                let (q, _) = self.controller.measured().ok_or(no_measurement(cmd))?;
                joint_reply(cmd, &q, bank_2, n, 0.0)
            }
            Command::JointVelocity => {
                let rates = JointRates::parse(req).map_err(|_| Notice::BadIndex(cmd))?;
                let joints = bank_values(&v, cmd)?;
                self.in_mode(cmd)?;
                operational(drives, cmd)?;
                if rates.bank_2 {
                    self.stage(BankKey::Rates, joints, cmd)?;
                } else {
                    let q = self.complete(BankKey::Rates, joints, cmd)?;
                    self.controller.stream_joint_rates(&q).map_err(refused)?;
                }
                // The echo: the rates as sent, and in f6 how long they hold.
                let mut values = v;
                values[BANK_LEN] = self.controller.stream_timeout();
                Ok(values_reply(cmd, &values, req.index))
            }
            Command::JointReset | Command::Stop => {
                self.stop(StopCause::Stop);
                Ok(null)
            }
            Command::Watchdog => {
                let ms = v[0];
                if !(0.0..=f64::from(MAX_WATCHDOG_MS)).contains(&ms) {
                    return Err(Notice::BadNumber(cmd));
                }
                let ms = libm::round(ms) as u16;
                self.session.set_watchdog(ms);
                Ok(values_reply(cmd, &[f64::from(ms)], 0))
            }
            Command::JointVia => {
                let joints = bank_values(&v, cmd)?;
                let duration = non_negative(v[6]).ok_or(Notice::BadNumber(cmd))?;
                if bank_2 {
                    self.stage(BankKey::Via(slot), joints, cmd)?;
                } else {
                    let q = self.complete(BankKey::Via(slot), joints, cmd)?;
                    self.controller
                        .set_joint_via(slot, &q, duration)
                        .map_err(refused)?;
                }
                // The echo: the joints as sent (`joints` is `v`'s first BANK_LEN values), then
                // the clamped duration. No slice copy that could panic on a length mismatch.
                let mut values = v;
                values[BANK_LEN] = duration;
                Ok(values_reply(cmd, &values, req.index))
            }
            Command::On => {
                self.banks.clear();
                // Already starting (e.g. at power-up): ON asks for what is under way.
                if drives.status() == DriveStatus::Starting {
                    return Ok(null);
                }
                if drives.start().is_err() {
                    return Err(Notice::ArmDidNotStart(drives.status()));
                }
                self.power_off_at = None;
                self.controller.release();
                Ok(null)
            }
            Command::Off => {
                self.banks.clear();
                // Decelerate, then stop the drives (in `tick`); they hold under servo, motors on.
                if self.controller.is_moving() && drives.is_operational() {
                    self.controller.stop(StopCause::PowerOff);
                    self.power_off_at = Some(self.now + self.stop_within);
                    return Ok(null);
                }
                if drives.stop().is_err() {
                    return Err(Notice::ArmDidNotStop(drives.status()));
                }
                self.controller.release();
                Ok(null)
            }
            Command::Pose => {
                let (_, pose) = self.controller.measured().ok_or(no_measurement(cmd))?;
                let [x, y, z]: [f64; 3] = pose.translation.vector.into();
                let [a, b, c, d] = Quaternion::from_rotation(&pose.rotation).to_array();
                Ok(values_reply(cmd, &[x, y, z, a, b, c, d], 0))
            }
            Command::Recalibrate => {
                let joints = bank_values(&v, cmd)?;
                if bank_2 {
                    self.stage(BankKey::Recalibrate, joints, cmd)?;
                    return Ok(values_reply(cmd, joints, BANK_2));
                }
                // Only with the arm off: the measured angles jump (spec §6.8).
                self.in_mode(cmd)?;
                let q = self.complete(BankKey::Recalibrate, joints, cmd)?;
                // Declaring the arm outside its range would make the measured pose illegal
                // and the limiter ease commands back from there (the seed did not check).
                let q = self.controller.check_joint_goal(&q).map_err(refused)?;
                drives
                    .recalibrate(&q)
                    .map_err(|r| recalibration_refused(r, drives.status()))?;
                Ok(null)
            }
            Command::Status => match req.index {
                STATUS_INDEX => Ok(self.status(drives).report().to_reply()),
                CAUSE_INDEX => {
                    let (cause, joint) = self.controller.stop_cause();
                    Ok(CauseReport { cause, joint }.to_reply())
                }
                SIGNING_INDEX => Ok(self.signing.to_reply()),
                BRANCH_INDEX => {
                    let present = self.controller.measured().map(|(q, _)| q);
                    Ok(ik::present_branch(
                        self.controller.chain(),
                        present.as_ref(),
                    ))
                }
                _ => Err(Notice::BadIndex(cmd)),
            },
            Command::Temperature => {
                let t = drives.temperatures();
                joint_reply(cmd, &t, bank_2, n, NO_JOINT_TEMPERATURE)
            }
            Command::Twist => {
                let twist = TwistRequest::parse(req).map_err(|_| Notice::BadIndex(cmd))?;
                let [vx, vy, vz] = twist.linear.map(f64::from);
                let [wx, wy, wz] = twist.angular.map(f64::from);
                let xi = Twist::new(vx, vy, vz, wx, wy, wz);
                if !xi.iter().all(|v| v.is_finite()) {
                    return Err(Notice::BadNumber(cmd));
                }
                self.in_mode(cmd)?;
                operational(drives, cmd)?;
                self.controller
                    .stream_twist(xi, twist.frame)
                    .map_err(refused)?;
                let timeout = self.controller.stream_timeout();
                Ok(values_reply(
                    cmd,
                    &[vx, vy, vz, wx, wy, wz, timeout],
                    req.index,
                ))
            }
            Command::ViaClear => {
                self.controller.clear_cartesian_via();
                Ok(null)
            }
            Command::ViaExecute => {
                self.in_mode(cmd)?;
                operational(drives, cmd)?;
                self.controller
                    .start_cartesian_sequence()
                    .map_err(refused)?;
                Ok(null)
            }
            Command::ViaTolerance | Command::JointViaTolerance => {
                // The slot is the whole index byte: 20 and above (bank bit included) are
                // refused with ER24, as for VP.
                let tolerance = BlendTolerance::parse(req)
                    .ok()
                    .and_then(|t| t.tolerance)
                    .map(f64::from);
                let slot = usize::from(req.index);
                let in_effect = if cmd == Command::ViaTolerance {
                    self.controller.set_cartesian_blend(slot, tolerance)
                } else {
                    self.controller.set_joint_blend(slot, tolerance)
                }
                .map_err(refused)?;
                Ok(values_reply(cmd, &[in_effect], req.index))
            }
            Command::ViaPoint => {
                if bank_2 {
                    return Err(Notice::BadIndex(cmd));
                }
                let [x, y, z, roll, pitch, yaw, t] = v;
                let duration = non_negative(t).ok_or(Notice::BadNumber(cmd))?;
                let rotation = Rotation3::from_euler_angles(roll, pitch, yaw);
                let pose = Frame::from_parts(Vector3::new(x, y, z).into(), rotation);
                self.controller
                    .set_cartesian_via(slot, pose, duration)
                    .map_err(refused)?;
                let [r, p, w] = math::rpy(&pose.rotation);
                Ok(values_reply(cmd, &[x, y, z, r, p, w, duration], req.index))
            }
        }
    }

    /// Stops the arm: `ST`, `jR`, and the client watchdog (one path for all of them).
    /// Every stop from the command layer: the staged banks go, the supervisor brings the arm
    /// to rest.
    fn stop(&mut self, cause: StopCause) {
        self.banks.clear();
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

/// The client text for a refused request, with its reason. (Out of line: eleven callers, all
/// answering requests.)
#[inline(never)]
fn refusal_notice(cmd: Command, refusal: Refusal) -> Notice {
    let rejected = |why| Notice::Rejected(cmd, why);
    let workspace = |why| Notice::OutsideWorkspace(cmd, why);
    match refusal {
        Refusal::InvalidNumber | Refusal::WrongJointCount => Notice::BadNumber(cmd),
        Refusal::IndexOutOfRange => Notice::BadIndex(cmd),
        Refusal::OutsideWorkspace => workspace(WorkspaceReason::Goal),
        Refusal::CrossesBox(percent) => workspace(WorkspaceReason::CrossesBox(percent)),
        Refusal::Unreachable(at) => workspace(WorkspaceReason::Unreachable(at)),
        Refusal::ArmOutsideWorkspace => workspace(WorkspaceReason::ArmOutside),
        Refusal::TooFast(joint, at) => workspace(WorkspaceReason::TooFast(joint, at)),
        Refusal::OutsideJointLimits(bound) => Notice::BeyondJointLimit(cmd, bound),
        Refusal::NoGoal => rejected(match cmd {
            Command::ViaExecute | Command::JointExecute => Rejection::NoViaPoint,
            _ => Rejection::NoGoal,
        }),
        // Only the requests that need a mode are refused for the wrong one.
        Refusal::WrongMode => rejected(Rejection::NeedsMode(
            Mode::required_by(cmd).unwrap_or_default(),
        )),
        Refusal::Busy => rejected(Rejection::Busy),
        Refusal::NotReady => rejected(Rejection::NoMeasurement),
    }
}

/// The client text for a refused `KG`/`KS`.
fn ik_notice(cmd: Command, error: IkRequestError) -> Notice {
    match error {
        IkRequestError::BadNumber => Notice::BadNumber(cmd),
        IkRequestError::BadIndex => Notice::BadIndex(cmd),
        IkRequestError::Refused(r) => refusal_notice(cmd, r),
    }
}

fn no_measurement(cmd: Command) -> Notice {
    Notice::Rejected(cmd, Rejection::NoMeasurement)
}

/// Motion needs running drives; otherwise the reason is their state, or their fault.
fn operational(drives: &(impl Drives + ?Sized), cmd: Command) -> Result<(), Notice> {
    let why = match (drives.status(), drives.fault_code()) {
        (DriveStatus::Running, _) => return Ok(()),
        (_, Some(code)) => Rejection::DriveFault(code),
        (status, None) => Rejection::Drives(status),
    };
    Err(Notice::Rejected(cmd, why))
}

/// Why the drives refused `RC`: busy means starting, stopping, or still executing the last
/// set-points after the mode was switched off (settling).
fn recalibration_refused(refusal: Refusal, status: DriveStatus) -> Notice {
    let cmd = Command::Recalibrate;
    match (refusal, status) {
        (Refusal::Busy, DriveStatus::Starting | DriveStatus::Stopping) => {
            Notice::Rejected(cmd, Rejection::Drives(status))
        }
        (Refusal::Busy, _) => Notice::Rejected(cmd, Rejection::DrivesSettling),
        (other, _) => refusal_notice(cmd, other),
    }
}

/// The six joint values of a joint request, all finite.
fn bank_values(v: &[f64; VALUES], cmd: Command) -> Result<&[f64], Notice> {
    let joints = v.get(..BANK_LEN).unwrap_or(&[]);
    if joints.iter().all(|x| x.is_finite()) {
        Ok(joints)
    } else {
        Err(Notice::BadNumber(cmd))
    }
}

/// A duration: finite, negative ones clamped to 0 (the seed left jV/VP unclamped, §9 item 12).
fn non_negative(t: f64) -> Option<f64> {
    t.is_finite().then_some(t.max(0.0))
}

/// A reply carrying `values` in f0.. (the rest zero).
fn values_reply(cmd: Command, values: &[f64], index: u8) -> Reply {
    let mut out = [0.0f32; VALUES];
    for (o, v) in out.iter_mut().zip(values) {
        *o = *v as f32;
    }
    Reply {
        command: cmd,
        values: out,
        index,
    }
}

/// jP/TM: joints 1–7 in f0..f6, or joints 7.. for bank 2 (refused on an arm without them,
/// as docs/protocol.md says); unused slots hold `pad`.
fn joint_reply(cmd: Command, q: &[f64], bank_2: bool, n: usize, pad: f32) -> Result<Reply, Notice> {
    if bank_2 && n <= BANK_LEN {
        return Err(Notice::BadIndex(cmd));
    }
    let skip = if bank_2 { BANK_LEN } else { 0 };
    let mut values = [pad; VALUES];
    for (o, v) in values
        .iter_mut()
        .zip(q.iter().take(n).skip(skip))
        .take(READ_JOINTS)
    {
        *o = *v as f32;
    }
    Ok(Reply {
        command: cmd,
        values,
        index: if bank_2 { BANK_2 } else { 0 },
    })
}

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
