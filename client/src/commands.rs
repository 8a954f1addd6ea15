//! Typed helpers: one method per protocol command (docs/protocol.md, "Commands").

use armgate_protocol::client::{
    BlendTolerance, Command, Reply, Request, UNKNOWN_TEMPERATURE, VALUES, ViaKind,
};

use std::time::Duration;

use crate::banks;
use crate::{Client, ClientError, Mode, Pose, Quaternion};

/// The planned duration a motion start's reply reports in f6 (0, as the seed's null reply:
/// none).
fn planned(reply: &Reply) -> Option<Duration> {
    let [.., f6] = reply.values;
    Some(f64::from(f6))
        .filter(|t| *t > 0.0)
        .and_then(|t| Duration::try_from_secs_f64(t).ok())
}
use armgate_protocol::client::banks::BANK_2;

/// The temperature a drive that never answered reports (°C).
pub const NO_READING: f64 = UNKNOWN_TEMPERATURE as f64;

fn request(command: Command, values: [f32; VALUES], index: u8) -> Request {
    Request {
        command,
        values,
        index,
    }
}

fn cartesian_values(xyz: [f64; 3], rpy: [f64; 3], time: f64) -> [f32; VALUES] {
    let [x, y, z] = xyz;
    let [r, p, w] = rpy;
    [x, y, z, r, p, w, time].map(|v| v as f32)
}

impl Client {
    /// Sends a command without values and index 0, and returns its reply.
    pub fn simple(&mut self, command: Command) -> Result<Reply, ClientError> {
        self.request(request(command, [0.0; VALUES], 0))
    }

    /// `PS`: the measured tool pose.
    pub fn pose(&mut self) -> Result<Pose, ClientError> {
        let [x, y, z, qx, qy, qz, qw] = self.simple(Command::Pose)?.values.map(f64::from);
        Ok(Pose {
            xyz: [x, y, z],
            quaternion: Quaternion::new(qx, qy, qz, qw),
        })
    }

    /// `jP`: the `n` measured joints (rad, or m for prismatic joints). The reply does not say
    /// how many joints the arm has, so the caller does; for more than seven a second `jP` with
    /// index 0x80 reads joints 7.. (bank 2).
    pub fn joints(&mut self, n: usize) -> Result<Vec<f64>, ClientError> {
        self.read_banks(Command::JointPosition, n)
    }

    /// `TM`: the `n` drive temperatures (°C; [`NO_READING`] for a drive not heard from yet),
    /// with the same bank rule as [`joints`](Self::joints).
    pub fn temperatures(&mut self, n: usize) -> Result<Vec<f64>, ClientError> {
        self.read_banks(Command::Temperature, n)
    }

    fn read_banks(&mut self, command: Command, n: usize) -> Result<Vec<f64>, ClientError> {
        banks::check_count(n)?;
        let bank1 = self.request(request(command, [0.0; VALUES], 0))?.values;
        let bank2 = if banks::needs_bank2_read(n) {
            Some(
                self.request(request(command, [0.0; VALUES], BANK_2))?
                    .values,
            )
        } else {
            None
        };
        Ok(banks::merge_read(n, &bank1, bank2.as_ref()))
    }

    /// `CM`: changes the control mode; returns the mode the controller reports.
    pub fn set_mode(&mut self, mode: Mode) -> Result<Mode, ClientError> {
        let mut values = [0.0; VALUES];
        if let Some(first) = values.first_mut() {
            *first = f32::from(mode.value());
        }
        let reply = self.request(request(Command::ChangeMode, values, 0))?;
        let reported = reply.values.first().copied().unwrap_or_default();
        Mode::from_value(reported).ok_or_else(|| {
            ClientError::InvalidArgument(format!("the controller reports mode {reported}"))
        })
    }

    /// `ON`: starts the drives (`ER11 Arm did not start` is a rejection).
    pub fn on(&mut self) -> Result<(), ClientError> {
        self.simple(Command::On).map(drop)
    }

    /// `OF`: stops the drives (`ER10 Arm did not stop` is a rejection).
    pub fn off(&mut self) -> Result<(), ClientError> {
        self.simple(Command::Off).map(drop)
    }

    /// `ST`: stops every motion and sequence; the arm holds its commanded position.
    pub fn stop(&mut self) -> Result<(), ClientError> {
        self.simple(Command::Stop).map(drop)
    }

    /// `WD`: the client watchdog: while the arm moves and this client (holding the arm) is
    /// silent for longer than `ms`, the controller stops it (`ER41`); 0 turns it off.
    pub fn watchdog(&mut self, ms: u16) -> Result<(), ClientError> {
        let mut values = [0.0; VALUES];
        values[0] = f32::from(ms);
        self.request(request(Command::Watchdog, values, 0))
            .map(drop)
    }

    /// `jR`: stops a joint motion.
    pub fn joint_reset(&mut self) -> Result<(), ClientError> {
        self.simple(Command::JointReset).map(drop)
    }

    /// `GT`: stores the Cartesian goal: position (m), roll/pitch/yaw (rad) and a minimum
    /// duration `time` (s). Returns the echo (T clamped at 0). Does not move: see
    /// [`begin`](Self::begin).
    pub fn goal_rpy(
        &mut self,
        xyz: [f64; 3],
        rpy: [f64; 3],
        time: f64,
    ) -> Result<Reply, ClientError> {
        self.request(request(
            Command::GoalRpy,
            cartesian_values(xyz, rpy, time),
            0,
        ))
    }

    /// `GL`: stores the Cartesian goal as position and quaternion (x, y, z, w), duration 0 (as
    /// fast as the limits allow). Returns the echo with the normalised quaternion.
    pub fn goal_quat(&mut self, pose: &Pose) -> Result<Reply, ClientError> {
        let [x, y, z] = pose.xyz;
        let q = pose.quaternion;
        let values = [x, y, z, q.x, q.y, q.z, q.w].map(|v| v as f32);
        self.request(request(Command::GoalQuaternion, values, 0))
    }

    /// `BG`: starts the Cartesian motion to the stored goal (Cartesian mode; refused while a
    /// motion runs). Returns the planned duration the controller reports (`None` from one that
    /// reports none, as the seed's).
    pub fn begin(&mut self) -> Result<Option<Duration>, ClientError> {
        self.simple(Command::Begin).map(|reply| planned(&reply))
    }

    /// `jG`: stores the joint goal; for more than six joints bank 2 is sent first.
    pub fn joint_goal(&mut self, q: &[f64]) -> Result<(), ClientError> {
        self.write_banks(Command::JointGoal, q, 0, 0.0)
    }

    /// `jB`: starts the joint motion to the stored joint goal (joint mode). Returns the planned
    /// duration, as [`begin`](Self::begin).
    pub fn joint_begin(&mut self) -> Result<Option<Duration>, ClientError> {
        self.simple(Command::JointBegin)
            .map(|reply| planned(&reply))
    }

    /// `VP`: stores Cartesian via point `slot` (0..19) with a minimum duration `time` (s).
    /// Returns the echo (roll/pitch/yaw re-extracted by the controller).
    pub fn via_cartesian(
        &mut self,
        slot: u8,
        xyz: [f64; 3],
        rpy: [f64; 3],
        time: f64,
    ) -> Result<Reply, ClientError> {
        if slot & BANK_2 != 0 {
            return Err(ClientError::InvalidArgument(format!("via slot {slot}")));
        }
        self.request(request(
            Command::ViaPoint,
            cartesian_values(xyz, rpy, time),
            slot,
        ))
    }

    /// `jV`: stores joint via point `slot` (0..19) with a minimum duration `time` (s); for more
    /// than six joints bank 2 is sent first.
    pub fn via_joint(&mut self, slot: u8, q: &[f64], time: f64) -> Result<(), ClientError> {
        self.write_banks(Command::JointVia, q, slot, time as f32)
    }

    /// `VT` (Cartesian slots, m + rad) or `jT` (joint slots, rad): the blend tolerance of via
    /// point `slot` (0..19): the sequence passes it within this distance without stopping; 0
    /// stops there; `None` gives the slot back the robot file's default. Returns the tolerance
    /// now in effect for the slot. `VC`/`jC` reset every slot to the default.
    pub fn via_tolerance(
        &mut self,
        kind: ViaKind,
        slot: u8,
        tolerance: Option<f64>,
    ) -> Result<f64, ClientError> {
        if let Some(t) = tolerance.filter(|t| !(t.is_finite() && *t >= 0.0)) {
            return Err(ClientError::InvalidArgument(format!(
                "blend tolerance {t} must be a finite number ≥ 0"
            )));
        }
        let request = BlendTolerance {
            kind,
            slot,
            tolerance: tolerance.map(|t| t as f32),
        }
        .to_request();
        let [in_effect, ..] = self.request(request)?.values;
        Ok(f64::from(in_effect))
    }

    /// `VC`: clears the Cartesian via points (answered `CV`).
    pub fn via_clear(&mut self) -> Result<(), ClientError> {
        self.simple(Command::ViaClear).map(drop)
    }

    /// `jC`: clears the joint via points.
    pub fn joint_via_clear(&mut self) -> Result<(), ClientError> {
        self.simple(Command::JointClear).map(drop)
    }

    /// `VE`: runs the Cartesian via points 0.. up to the first gap (Cartesian mode).
    pub fn run_sequence(&mut self) -> Result<(), ClientError> {
        self.simple(Command::ViaExecute).map(drop)
    }

    /// `jE`: runs the joint via points 0.. up to the first gap (joint mode).
    pub fn run_joint_sequence(&mut self) -> Result<(), ClientError> {
        self.simple(Command::JointExecute).map(drop)
    }

    /// `RC`: recalibrates: the arm's current position becomes `q` (mode 0 only; answered `CR`).
    /// For more than six joints bank 2 is sent first.
    pub fn recalibrate(&mut self, q: &[f64]) -> Result<(), ClientError> {
        self.write_banks(Command::Recalibrate, q, 0, 0.0)
    }

    fn write_banks(
        &mut self,
        command: Command,
        q: &[f64],
        slot: u8,
        f6: f32,
    ) -> Result<(), ClientError> {
        for bank in banks::split(q, slot, f6)? {
            self.request(request(command, bank.values, bank.index))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::{FakeController, echo};
    use armgate_protocol::client::Message;

    /// A fake that echoes every request with reversed characters.
    fn echoing() -> FakeController {
        FakeController::spawn(|request| vec![echo(request)])
    }

    fn client(fake: &FakeController) -> Client {
        fake.client()
    }

    fn datagram(chars: &[u8; 2], values: [f32; 7], index: u8) -> Vec<u8> {
        let mut out = chars.to_vec();
        for v in values {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.push(index);
        out
    }

    #[test]
    fn eight_joint_goal_sends_bank_two_then_bank_one() {
        let fake = echoing();
        let mut c = client(&fake);
        let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8];
        c.joint_goal(&q).unwrap();
        let sent = fake.received();
        assert_eq!(sent.len(), 2);
        let mut bank2 = b"jG".to_vec();
        for v in [0.7f32, 0.8, 0.0, 0.0, 0.0, 0.0, 0.0] {
            bank2.extend_from_slice(&v.to_le_bytes());
        }
        bank2.push(0x80);
        assert_eq!(sent[0], bank2);
        assert_eq!(sent[0][30], 0x80);
        assert_eq!(
            sent[1],
            datagram(b"jG", [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.0], 0x00)
        );
    }

    #[test]
    fn eight_joint_via_point_keeps_the_slot_in_both_banks() {
        let fake = echoing();
        let mut c = client(&fake);
        let q = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        c.via_joint(3, &q, 2.0).unwrap();
        let sent = fake.received();
        assert_eq!(
            sent,
            [
                datagram(b"jV", [7.0, 8.0, 0.0, 0.0, 0.0, 0.0, 2.0], 0x83),
                datagram(b"jV", [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 2.0], 0x03),
            ]
        );
    }

    #[test]
    fn seven_joint_recalibration_uses_banks_and_six_joints_do_not() {
        let fake = echoing();
        let mut c = client(&fake);
        c.recalibrate(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]).unwrap();
        c.recalibrate(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
        let sent = fake.received();
        assert_eq!(
            sent,
            [
                datagram(b"RC", [7.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0x80),
                datagram(b"RC", [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0], 0x00),
                datagram(b"RC", [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0], 0x00),
            ]
        );
    }

    #[test]
    fn eight_joints_are_read_with_two_jp() {
        let fake = FakeController::spawn(|request| {
            let message = Message::new_checked(request).unwrap();
            let mut reply = Reply::null(Command::JointPosition);
            reply.index = message.index();
            reply.values = if message.index() & BANK_2 == 0 {
                [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]
            } else {
                [7.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            };
            vec![reply.to_bytes().to_vec()]
        });
        let mut c = client(&fake);
        assert_eq!(
            c.joints(8).unwrap(),
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]
        );
        assert_eq!(c.joints(6).unwrap(), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let sent = fake.received();
        assert_eq!(sent.len(), 3);
        assert_eq!(sent[0], datagram(b"jP", [0.0; 7], 0x00));
        assert_eq!(sent[1], datagram(b"jP", [0.0; 7], 0x80));
        assert_eq!(sent[2], datagram(b"jP", [0.0; 7], 0x00));
    }

    #[test]
    #[allow(clippy::approx_constant)] // −1.5708: the spec's §2.9 VP example
    fn typed_values_go_where_the_protocol_says() {
        let fake = echoing();
        let mut c = client(&fake);
        c.goal_rpy([0.5, 0.2, 0.1], [0.0, 0.0, 0.0], 5.0).unwrap();
        let sent = fake.received();
        // Spec §2.9, the worked GT example, byte for byte.
        let expected: [u8; 31] = [
            0x47, 0x54, 0x00, 0x00, 0x00, 0x3F, 0xCD, 0xCC, 0x4C, 0x3E, 0xCD, 0xCC, 0xCC, 0x3D, 0,
            0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x00, 0xA0, 0x40, 0x00,
        ];
        assert_eq!(sent[0], expected);
        assert_eq!(c.set_mode(Mode::Cartesian).unwrap(), Mode::Cartesian);
        assert_eq!(
            fake.received()[1],
            datagram(b"CM", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0)
        );
        c.via_cartesian(3, [0.5, -0.2, 0.4], [0.0, 0.0, -1.5708], 2.0)
            .unwrap();
        assert_eq!(
            fake.received()[2],
            datagram(b"VP", [0.5, -0.2, 0.4, 0.0, 0.0, -1.5708, 2.0], 3)
        );
    }

    #[test]
    fn pose_reads_the_quaternion_scalar_last() {
        let fake = FakeController::spawn(|_| {
            let mut reply = Reply::null(Command::Pose);
            reply.values = [0.1, 0.2, 0.3, 0.0, 0.0, 0.6, 0.8];
            vec![reply.to_bytes().to_vec()]
        });
        let pose = client(&fake).pose().unwrap();
        assert!((pose.xyz[2] - 0.3).abs() < 1e-7);
        assert!((pose.quaternion.z - 0.6).abs() < 1e-7);
        assert!((pose.quaternion.w - 0.8).abs() < 1e-7);
    }
}
