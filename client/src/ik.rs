//! The closed-form IK requests (`KS`, `KG`, `KR`): a pose's solutions, and a joint move to
//! one, each with the redundancy values of a 7–8 joint arm chosen or the present ones.

use armgate_protocol::client::banks::BANK_2;
use armgate_protocol::client::branch::{NEAREST_BRANCH, NO_SOLUTION};
use armgate_protocol::client::redundancy::{CHOSEN, Redundancy};
use armgate_protocol::client::{Command, Request, VALUES};

use crate::{Client, ClientError};

/// One IK solution: its configuration branch (bits 1 shoulder, 2 elbow, 4 wrist) and joints.
#[derive(Clone, Debug, PartialEq)]
pub struct IkSolution {
    /// The branch bits.
    pub branch: u8,
    /// The joints (rad).
    pub q: Vec<f64>,
}

fn pose_values(xyz: [f64; 3], rpy: [f64; 3], f6: f64) -> [f32; VALUES] {
    let [x, y, z] = xyz;
    let [r, p, w] = rpy;
    [x, y, z, r, p, w, f6].map(|v| v as f32)
}

impl Client {
    /// `KR`: the values of the redundancy parameters (θ3, and θ5 on eight joints) for this
    /// client's next `KG` and its `KS` reads that ask for them; a value not given keeps the
    /// present one. Refused (`ER24`) on an arm without them, `ER26` beyond a joint's limits.
    pub fn choose_redundancy(&mut self, choice: Redundancy) -> Result<(), ClientError> {
        let (values, index) = choice.emit();
        self.request(Request {
            command: Command::IkRedundancy,
            values,
            index,
        })?;
        Ok(())
    }

    /// The `KR` before a `KG` or `KS` with `choice`, and the index bit that asks for it.
    fn with_choice(&mut self, choice: Option<Redundancy>) -> Result<u8, ClientError> {
        match choice {
            Some(choice) => self.choose_redundancy(choice).map(|()| CHOSEN),
            None => Ok(0),
        }
    }

    /// `KS`: every closed-form IK solution of the pose within the joint limits, or `None` if
    /// the robot has no closed form (docs/kinematics.md). An arm of more than six `joints`
    /// also reads each solution's joints 7.. (bank 2). On a 7–8 joint arm the solutions are
    /// those for the present θ3 (θ5), or for `choice` (sent first with `KR`).
    pub fn ik_solutions(
        &mut self,
        xyz: [f64; 3],
        rpy: [f64; 3],
        joints: usize,
        choice: Option<Redundancy>,
    ) -> Result<Option<Vec<IkSolution>>, ClientError> {
        let values = pose_values(xyz, rpy, 0.0);
        let chosen = self.with_choice(choice)?;
        let mut solutions = Vec::new();
        // The count arrives with every reply; at most eight solutions.
        for k in 0..8u8 {
            let reply = self.request(Request {
                command: Command::IkSolution,
                values,
                index: k | chosen,
            })?;
            let count = reply.values[VALUES - 1];
            if count < 0.0 {
                return Ok(None);
            }
            if reply.index == NO_SOLUTION || f32::from(k) >= count {
                break;
            }
            let mut q: Vec<f64> = reply.values[..6].iter().map(|v| f64::from(*v)).collect();
            if joints > 6 {
                let upper = self.request(Request {
                    command: Command::IkSolution,
                    values,
                    index: k | BANK_2 | chosen,
                })?;
                q.extend(upper.values.iter().take(joints - 6).map(|v| f64::from(*v)));
            }
            solutions.push(IkSolution {
                branch: reply.index,
                q,
            });
        }
        Ok(Some(solutions))
    }

    /// `KG`: a joint move (joint mode) to the IK solution of the pose on `branch`, or without
    /// one the solution nearest the present joints, in at least `time` s; on a 7–8 joint arm
    /// with the redundancy values of `choice` (sent first with `KR`; no solution for them:
    /// refused, no other values are tried). Returns the goal's joints 1–6 (the branch is
    /// [`NEAREST_BRANCH`] on a robot without a closed form).
    pub fn ik_move(
        &mut self,
        xyz: [f64; 3],
        rpy: [f64; 3],
        (branch, choice): (Option<u8>, Option<Redundancy>),
        time: f64,
    ) -> Result<IkSolution, ClientError> {
        let chosen = self.with_choice(choice)?;
        let reply = self.request(Request {
            command: Command::IkGoal,
            values: pose_values(xyz, rpy, time),
            index: branch.unwrap_or(NEAREST_BRANCH) | chosen,
        })?;
        let q = reply.values[..6].iter().map(|v| f64::from(*v)).collect();
        Ok(IkSolution {
            branch: reply.index,
            q,
        })
    }
}
