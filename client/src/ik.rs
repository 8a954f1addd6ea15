//! The closed-form IK requests (`KS`, `KG`): a pose's solutions, and a joint move to one.

use armgate_protocol::client::banks::BANK_2;
use armgate_protocol::client::branch::{NEAREST_BRANCH, NO_SOLUTION};
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
    /// `KS`: every closed-form IK solution of the pose within the joint limits, or `None` if
    /// the robot has no closed form (docs/kinematics.md). An arm of more than six `joints`
    /// also reads each solution's joints 7.. (bank 2).
    pub fn ik_solutions(
        &mut self,
        xyz: [f64; 3],
        rpy: [f64; 3],
        joints: usize,
    ) -> Result<Option<Vec<IkSolution>>, ClientError> {
        let values = pose_values(xyz, rpy, 0.0);
        let mut solutions = Vec::new();
        // The count arrives with every reply; at most eight solutions.
        for k in 0..8u8 {
            let reply = self.request(Request {
                command: Command::IkSolution,
                values,
                index: k,
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
                    index: k | BANK_2,
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
    /// one the solution nearest the present joints, in at least `time` s. Returns the goal
    /// (the branch is [`NEAREST_BRANCH`] on a robot without a closed form).
    pub fn ik_move(
        &mut self,
        xyz: [f64; 3],
        rpy: [f64; 3],
        branch: Option<u8>,
        time: f64,
    ) -> Result<IkSolution, ClientError> {
        let reply = self.request(Request {
            command: Command::IkGoal,
            values: pose_values(xyz, rpy, time),
            index: branch.unwrap_or(NEAREST_BRANCH),
        })?;
        let q = reply.values[..6].iter().map(|v| f64::from(*v)).collect();
        Ok(IkSolution {
            branch: reply.index,
            q,
        })
    }
}
