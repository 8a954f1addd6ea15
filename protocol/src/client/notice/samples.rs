//! A notice of every variant and every reason, for the tests that read texts back and the
//! table for other clients (`table.rs`).

use crate::client::{
    Command, DriveStatus, Hit, Hold, JointBound, Lag, Mode, Notice, Obstacle, PathPoint, Rejection,
    StopCause, WorkspaceReason,
};

/// At least one of every variant and every reason, each distinct in its text.
pub(super) fn samples() -> impl Iterator<Item = Notice> {
    use Command::*;
    let bound = |joint, above, limit, at| JointBound::new(joint, above, limit, at);
    let rejections = DriveStatus::ALL
        .into_iter()
        .map(Rejection::Drives)
        .chain([
            Rejection::Busy,
            Rejection::DriveFault(33),
            Rejection::DriveFault(5),
            Rejection::DrivesSettling,
            Rejection::NoGoal,
            Rejection::NoViaPoint,
            Rejection::NoMeasurement,
            Rejection::HolderChanged,
        ])
        .chain(StopCause::ALL.map(Rejection::Stopped))
        .chain(Mode::ALL.map(Rejection::NeedsMode))
        .map(|why| Notice::Rejected(Begin, why));
    let hit = |link, obstacle| Hit { link, obstacle };
    let reasons = [
        WorkspaceReason::Goal,
        WorkspaceReason::CrossesBox(40),
        WorkspaceReason::Unreachable(PathPoint::Goal),
        WorkspaceReason::Unreachable(PathPoint::Along(99)),
        WorkspaceReason::ArmOutside,
        WorkspaceReason::TooFast(3, PathPoint::Goal),
        WorkspaceReason::TooFast(6, PathPoint::Along(1)),
        WorkspaceReason::NearEdge(PathPoint::Along(37)),
        WorkspaceReason::Hits(hit(3, Obstacle::Box(1)), PathPoint::Along(40)),
        WorkspaceReason::Hits(hit(5, Obstacle::Link(2)), PathPoint::Goal),
        WorkspaceReason::Hits(hit(3, Obstacle::Bounds), PathPoint::Along(99)),
    ]
    .map(|why| Notice::OutsideWorkspace(ViaExecute, why));
    let states = DriveStatus::ALL
        .into_iter()
        .flat_map(|s| [Notice::ArmDidNotStop(s), Notice::ArmDidNotStart(s)]);
    [
        Notice::NotUnderstood(*b"XY"),
        Notice::Undersized(*b"B?"),
        Notice::WorkspaceLimit,
        Notice::Collision(hit(3, Obstacle::Box(1))),
        Notice::Collision(hit(5, Obstacle::Link(2))),
        Notice::Collision(hit(6, Obstacle::Bounds)),
        Notice::JointLimit,
        Notice::IkDivergence,
        Notice::BadNumber(GoalQuaternion),
        Notice::BadIndex(JointVia),
        Notice::BeyondJointLimit(JointGoal, bound(4, false, 0.785, PathPoint::Goal)),
        Notice::BeyondJointLimit(Begin, bound(2, true, -1.6, PathPoint::Along(12))),
        Notice::ViaPointMissed,
        Notice::HeldBy(Twist, Some([192, 168, 100, 200])),
        Notice::HeldBy(Begin, None),
        Notice::ClientSilent(60_000),
        Notice::Cancelled(IkGoal),
        Notice::Held(Hold::JointLimit(bound(5, true, 2.967, PathPoint::Goal))),
        Notice::Held(Hold::Workspace),
        Notice::Held(Hold::Contact(hit(3, Obstacle::Box(1)))),
        Notice::Held(Hold::Contact(hit(5, Obstacle::Link(2)))),
        Notice::Held(Hold::Contact(hit(6, Obstacle::Bounds))),
        Notice::LinkShared(255),
        Notice::FollowingError(Lag::new(2, 4.4)),
        Notice::BranchBeyondLimits(IkGoal),
    ]
    .into_iter()
    .chain(rejections)
    .chain(reasons)
    .chain(states)
}

/// The variant's number: adding a variant fails to compile here until it is numbered, and
/// [`every_variant_is_sampled`] until it has a sample.
fn variant_number(notice: Notice) -> usize {
    match notice {
        Notice::NotUnderstood(_) => 0,
        Notice::Undersized(_) => 1,
        Notice::ArmDidNotStop(_) => 2,
        Notice::ArmDidNotStart(_) => 3,
        Notice::Rejected(..) => 4,
        Notice::WorkspaceLimit => 5,
        Notice::JointLimit => 6,
        Notice::IkDivergence => 7,
        Notice::BadNumber(_) => 8,
        Notice::BadIndex(_) => 9,
        Notice::OutsideWorkspace(..) => 10,
        Notice::BeyondJointLimit(..) => 11,
        Notice::ViaPointMissed => 12,
        Notice::HeldBy(..) => 13,
        Notice::ClientSilent(_) => 14,
        Notice::Cancelled(_) => 15,
        Notice::Held(Hold::JointLimit(_)) => 16,
        Notice::Held(Hold::Workspace) => 17,
        Notice::LinkShared(_) => 18,
        Notice::FollowingError(_) => 19,
        Notice::BranchBeyondLimits(_) => 20,
        Notice::Collision(_) => 21,
        Notice::Held(Hold::Contact(_)) => 22,
    }
}

#[test]
fn every_variant_is_sampled() {
    let mut seen = [false; 23];
    for notice in samples() {
        seen[variant_number(notice)] = true;
    }
    assert!(seen.iter().all(|s| *s), "{seen:?}");
}
