//! A line's check in slices: [`LineCheck`] carries the check of [`Reach`] from one point of
//! the line to the next, so that the cycle runs a bounded work of it a tick (the tick that
//! handles a `BG` stays within its budget) and answers the request when the check ends. Run to
//! its end in one call it gives the same answer.

use armgate_protocol::client::{Hit, PathPoint};
use heapless::Vec;

use super::{
    Checked, FULL_STEP, Fault, MIN_JUMP_STEP, MIN_STEP, RATE_SHARE, Reach, Reached,
    SOLVES_PER_LINE, Shape, fault, planned_duration,
};
use crate::MAX_JOINTS;
use crate::kinematics::{Joints, SeedAngles};
use crate::math::{self, Frame, Rotation3, Vector3};
use crate::motion::Refusal;
use crate::motion::body::PRESENT;

/// The work of one point of a line's check besides its solve's Newton iterations (each 1): its
/// closed-form solve or Newton's start, and the whole arm's check there, about two Newton
/// iterations' worth on the Cortex-M7 (`cycle::budget::LINE_SLICE` counts in these units).
pub const POINT_WORK: usize = 2;

/// A line's check in progress: what the check carries from one point to the next, so that it
/// runs in slices of a few points, one slice a tick ([`Reach::continue_line`]). Fixed size.
#[derive(Clone, Debug)]
pub struct LineCheck {
    start: Frame,
    goal: Frame,
    /// The generator's turn: the rotation vector of R_goal · R_startᵀ (as `math::diff`).
    turn: Vector3<f64>,
    min_duration: f64,
    /// The time the whole line takes at cruise speed (s): the slowest component.
    cruise: f64,
    /// The longer of `cruise` and `min_duration` (s).
    duration: f64,
    shape: Shape,
    /// The largest rate and acceleration needs of the steps so far ([`Shape::needs`]).
    needs: f64,
    accelerates: f64,
    /// The joints' rates of change along the line (per fraction of the way) at the last
    /// step, none before the first.
    slope: Option<[f64; MAX_JOINTS]>,
    /// The fraction of the way followed, and the step being tried.
    done: f64,
    step: f64,
    /// A probe of the shortest step at the start runs; one ran; steps followed so far.
    probing: bool,
    probed: bool,
    followed: u8,
    /// The start (joints, pose): where the check starts again after a probe.
    reached: Reached,
    /// The last point reached and the step being tried (index `last`): the two swap roles,
    /// never copied (on the Cortex-M7 each copy of a point costs a few hundred instructions).
    points: [Reached; 2],
    last: usize,
    /// A joint too fast somewhere: the refusal if nothing further along refuses the line.
    too_fast: Option<Refusal>,
    /// What the arm already touches at the start (it does not count: the arm may move out).
    present: Vec<Hit, PRESENT>,
    /// Tracking solves spent (at most [`SOLVES_PER_LINE`]).
    solves: usize,
}

impl LineCheck {
    /// True once the check has followed the whole line, spent its solves or the request's
    /// IK budget (`iterations_left`).
    fn ended(&self, iterations_left: u32) -> bool {
        self.done >= 1.0 || iterations_left == 0 || self.solves >= SOLVES_PER_LINE
    }

    /// The answer of an ended check (one that ran out of budget gives the move the benefit of
    /// the doubt, with the joints reached so far).
    fn outcome(&self) -> Result<Checked, Refusal> {
        let q = self.points.get(self.last).map_or(self.reached.q, |r| r.q);
        let checked = Checked {
            q,
            duration: planned_duration(self.min_duration, self.cruise, self.needs)
                .max(math::sqrt(self.accelerates / RATE_SHARE)),
        };
        self.too_fast.map_or(Ok(checked), Err)
    }

    /// The pose `s` of the way along the line.
    fn point(&self, s: f64) -> Frame {
        if s >= 1.0 {
            return self.goal;
        }
        let (from, to) = (
            &self.start.translation.vector,
            &self.goal.translation.vector,
        );
        Frame::from_parts(
            (from + (to - from) * s).into(),
            Rotation3::new(self.turn * s) * self.start.rotation,
        )
    }
}

impl Reach<'_> {
    /// Starts the check of the straight line from `start`, where the arm is commanded to
    /// joints `seed`, to `goal`, planned to last at least `min_duration` (s): the exclusion
    /// boxes along the whole segment (a crossing refuses at once) and the body's contacts at
    /// the start; no point of the line yet ([`continue_line`](Self::continue_line) follows it).
    ///
    /// The check's answer is the joints at the goal and the duration to plan the line for
    /// ([`planned_duration`]: longer than `min_duration` where the joints need the line
    /// slower than the Cartesian limits, so that the tick follows the line without losing
    /// it, issue 33). (If the budget runs out the move gets the benefit of the doubt, and the
    /// joints reached so far are returned.) Between two samples no joint may move more than
    /// [`MAX_JOINT_STEP`] (at the shortest step) or need more than `ik.line_slowdown` times
    /// its rate limit at the line's cruise speed: a line on which the IK solution jumps to
    /// another branch, or swings a joint through a near-singularity, is refused with the joint
    /// and where, rather than started and aborted halfway.
    pub(in crate::motion) fn begin_line(
        &self,
        start: &Frame,
        goal: &Frame,
        seed: &Joints,
        min_duration: f64,
    ) -> Result<LineCheck, Refusal> {
        let (from, to) = (&start.translation.vector, &goal.translation.vector);
        if let Some(entry) = self.workspace.first_box_crossing(from, to) {
            return match PathPoint::at(entry) {
                PathPoint::Along(percent) => Err(Refusal::CrossesBox(percent)),
                PathPoint::Goal => Err(Refusal::OutsideWorkspace),
            };
        }
        let delta: [f64; 6] = math::diff(start, goal).into();
        let min_duration = min_duration.max(0.0);
        let cruise = delta
            .iter()
            .zip(self.speed.iter())
            .map(|(d, v)| libm::fabs(*d) / v)
            .fold(0.0, f64::max);
        let reached = Reached {
            q: *seed,
            pose: *start,
            angles: SeedAngles::default(),
        };
        Ok(LineCheck {
            start: *start,
            goal: *goal,
            turn: math::rotation_vector(&start.rotation.rotation_to(&goal.rotation)),
            min_duration,
            cruise,
            duration: cruise.max(min_duration),
            shape: Shape::of(&delta, self.speed, self.acceleration),
            needs: 0.0,
            accelerates: 0.0,
            slope: None,
            done: 0.0,
            step: FULL_STEP,
            probing: false,
            probed: false,
            followed: 0,
            reached,
            points: [reached; 2],
            last: 0,
            too_fast: None,
            present: self.body.present_at(self.chain, seed),
            solves: 0,
        })
    }

    /// Runs `check` on while `work` lasts (each point takes [`POINT_WORK`] and one more per
    /// Newton iteration its solve took, from `work`; a point is begun while any is left); its
    /// answer once it has ended, `None` while it goes on.
    pub(in crate::motion) fn continue_line(
        &mut self,
        check: &mut LineCheck,
        work: &mut usize,
    ) -> Option<Result<Checked, Refusal>> {
        for _ in 0..SOLVES_PER_LINE {
            if check.ended(self.iterations_left) {
                return Some(check.outcome());
            }
            if *work == 0 {
                return None;
            }
            check.solves = check.solves.saturating_add(1);
            let before = self.iterations_left;
            let point = self.next_point(check);
            let iterations = before.saturating_sub(self.iterations_left);
            let spent =
                POINT_WORK.saturating_add(usize::try_from(iterations).unwrap_or(usize::MAX));
            *work = work.saturating_sub(spent);
            if let Err(refusal) = point {
                return Some(Err(refusal));
            }
        }
        check.ended(self.iterations_left).then(|| check.outcome())
    }

    /// One tracking solve of the check: the next point of the line, or a shorter step.
    ///
    /// Where a joint's rate along the line falls by more than half from the first step to
    /// the second (as `√s` does, from a singularity), the line is followed again from its
    /// start after a probe of the shortest step: the tick starts from rest, in short steps,
    /// and from an exact singularity (hybrid's home) a sixteenth of the way hid a joint the
    /// tick cannot move fast enough there (issue 33). Probing every line cost ranger-mk1's
    /// BG tick 12,000 instructions, following it up from the probe's step 80,000.
    fn next_point(&mut self, c: &mut LineCheck) -> Result<(), Refusal> {
        let next = (c.done + c.step).min(1.0);
        let at = PathPoint::at(next);
        let pose = c.point(next);
        let [first, second] = &mut c.points;
        let (here, tried) = if c.last == 0 {
            (&*first, second)
        } else {
            (&*second, first)
        };
        tried.pose = pose;
        match self.solve(here, tried, at) {
            Ok(()) => {}
            Err(refusal) if c.step <= MIN_STEP => return Err(refusal),
            Err(_) => {
                c.step *= 0.5;
                return Ok(());
            }
        };
        match fault(
            &here.q,
            &tried.q,
            self.max_rate,
            (next - c.done) * c.duration,
            self.ik.line_slowdown,
        ) {
            // From afar the nearest solution may lie on another branch: retried shorter,
            // as the tick would follow the line.
            Some(Fault::Jump(_)) if c.step > MIN_JUMP_STEP => {
                c.step *= 0.5;
                return Ok(());
            }
            Some(Fault::Jump(joint)) => return Err(Refusal::TooFast(joint, at)),
            // A line that also fails for another reason further along (a joint limit,
            // out of reach) is refused for that: it says more.
            Some(Fault::Rate(joint)) => {
                c.too_fast.get_or_insert(Refusal::TooFast(joint, at));
            }
            None => {}
        }
        // The whole arm at each point of the line (between points the tick's check
        // stands guard: it stops the motion before a link arrives).
        if let Some(hit) = self.body.new_hit(self.chain, &tried.q, &c.present) {
            return Err(Refusal::Hits(hit, at));
        }
        let limits = (self.max_rate, self.max_acceleration);
        let (rate, acceleration, slowed) =
            c.shape
                .needs(&mut c.slope, (&here.q, &tried.q), next - c.done, limits);
        c.needs = c.needs.max(rate);
        if c.probing {
            // The probe passed: the line is followed from its start in sixteenths.
            (c.probing, c.step, c.slope) = (false, FULL_STEP, None);
            return Ok(());
        }
        c.accelerates = c.accelerates.max(acceleration);
        (c.done, c.last) = (next, 1 - c.last);
        c.step = (c.step * 2.0).min(FULL_STEP);
        c.followed = c.followed.saturating_add(1);
        if c.followed == 2 && slowed && !c.probed {
            (c.probing, c.probed, c.done, c.step, c.last) = (true, true, 0.0, MIN_JUMP_STEP, 0);
            (c.points, c.slope) = ([c.reached; 2], None);
        }
        Ok(())
    }
}
