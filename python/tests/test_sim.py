"""The client against the real armgate-sim (simulated Whistles on a virtual CAN bus)."""

from __future__ import annotations

import dataclasses
import math
import time
from typing import List

import pytest

import armgate

# A comfortable, non-singular pose of ranger-mk1 (docs/drives.md, tracking experiments). The
# home pose is at a wrist singularity, where Cartesian moves diverge.
COMFORTABLE = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1]


def close(a, b, tol=1e-3):  # type: ignore[no-untyped-def]
    return len(a) == len(b) and all(abs(x - y) <= tol for x, y in zip(a, b))


def wait_running(arm: armgate.Arm) -> None:
    deadline = time.monotonic() + 5
    try:
        while arm.get_status().drive_state != armgate.DriveState.RUNNING:
            assert time.monotonic() < deadline
            time.sleep(0.05)
    except armgate.ControllerTooOld:
        time.sleep(1.0)  # the start takes 12 cycles, 0.23 s at 51 Hz


def test_pose_and_joints_at_home_match_the_simulator(mk1) -> None:  # type: ignore[no-untyped-def]
    home = mk1.home()
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        pose = arm.get_tcp_pose()
        assert close(pose.xyz, home["xyz"])
        assert close(pose.quaternion, home["quaternion"])
        assert close(pose.rpy, home["rpy"])
        assert arm.joint_count == 6
        assert close(arm.get_joints(), home["joints"])


def test_refusals_raise_typed_exceptions(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        with pytest.raises(armgate.CommandRejected) as rejected:
            arm.request("BG")  # mode off
        # "ER20 Cmd BG rejected", or with the refusal's reason ("ER20 Cmd BG needs mode 2").
        assert rejected.value.code == 20 and rejected.value.text.startswith("ER20 Cmd BG ")
        assert rejected.value.command == "BG"
        assert rejected.value.reason == rejected.value.text[5:]
        assert rejected.value.detail == rejected.value.text[12:]
        with pytest.raises(armgate.BadNumber) as bad:
            arm.set_mode(7)
        assert bad.value.code == 23
        with pytest.raises(armgate.NotUnderstood) as unknown:
            arm.request("XX")
        assert unknown.value.text == "ER00 Cmd XX not understood"
        assert unknown.value.code == 0
        with pytest.raises(armgate.BadIndex):
            arm.request("VP", [0.5, 0.0, 0.5, 0.0, 0.0, 0.0, 1.0], index=25)
        with pytest.raises(armgate.BeyondJointLimit) as beyond:
            arm.recalibrate([0.0, 5.0, 0.0, 0.0, 1.5, 0.0])
        assert beyond.value.text.startswith("ER26 Cmd RC ")
        # All refusals are typed, and all are ArmErrors.
        assert isinstance(beyond.value, armgate.ControllerError)
        assert isinstance(beyond.value, armgate.ArmError)
        assert arm.take_notices() == []


def test_recalibrate_then_a_cartesian_move_arrives(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        arm.recalibrate(COMFORTABLE)
        assert close(arm.get_joints(), COMFORTABLE, 1e-4)
        assert arm.set_mode("cartesian") == armgate.Mode.CARTESIAN
        start = arm.get_tcp_pose()
        goal = armgate.Pose.from_rpy(start.x, start.y, start.z - 0.02, *start.rpy)
        reached = arm.move_l(goal, time=1.0)
        assert reached is not None
        assert reached.distance(goal) <= 0.001
        assert reached.angle_to(goal) <= 0.01
        assert close(arm.get_tcp_pose().rpy, start.rpy, 0.01)
        # The move has ended when move_l returns: the next one is not refused as "moving".
        back = arm.move_l(start)
        assert back is not None and back.distance(start) <= 0.001


def test_the_nearest_gap_names_the_pair(mk1) -> None:  # type: ignore[no-untyped-def]
    """``SQ`` 7 at the comfortable pose: the forearm (link 3) 33.8 cm from the column (box 1),
    as the core's capsules place it; the margin is the robot file's (0)."""
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        arm.recalibrate(COMFORTABLE)
        near = arm.get_nearest()
        assert near is not None
        assert (near.link, near.obstacle, near.number, near.pair) == (3, "box", 1, "L3 B1")
        assert near.gap == pytest.approx(0.3378, abs=1e-3)
        assert near.margin == 0.0


def test_streamed_twist_and_joint_rates_move_the_arm(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        arm.recalibrate(COMFORTABLE)
        arm.set_mode("cartesian")
        start = arm.get_tcp_pose()
        # 1 cm/s down for 0.5 s, re-sent more often than once per control period (a third of
        # the hold time): a stream that goes quiet for its hold time is stopped, and stays so.
        deadline = time.monotonic() + 0.5
        with arm.velocity_stream() as stream:
            while time.monotonic() < deadline:
                hold = stream.twist([0.0, 0.0, -0.01])
                time.sleep(hold / 4)
        assert hold == pytest.approx(3 * 0.01944, abs=1e-6)
        time.sleep(0.5)  # the ramp to rest
        assert arm.get_status().motion == armgate.Motion.IDLE
        # Ended on purpose with a zero twist: no stop.
        assert arm.get_stop_cause() == (None, None)
        moved = arm.get_tcp_pose()
        # At most 0.5 s at 1 cm/s; at least some of it.
        assert -0.0055 < moved.z - start.z < -0.001
        assert math.hypot(moved.x - start.x, moved.y - start.y) < 2e-5
        with pytest.raises(armgate.CommandRejected):
            arm.joint_velocity([0.0, 0.0, 0.05, 0.0, 0.0, 0.0])  # needs joint mode
        arm.set_mode("joint")
        q0 = arm.get_joints()
        deadline = time.monotonic() + 0.5
        with arm.velocity_stream() as stream:
            while time.monotonic() < deadline:
                hold = stream.joint_velocity([0.0, 0.0, 0.05, 0.0, 0.0, 0.0])
                time.sleep(hold / 4)
        time.sleep(0.5)
        q = arm.get_joints()
        assert 0.005 < q[2] - q0[2] < 0.0275  # at most 0.5 s at 0.05 rad/s (plus the ramp)
        assert close(q[:2] + q[3:], q0[:2] + q0[3:], 1e-9)


def test_a_stopped_stream_stays_stopped_until_started_again(mk1) -> None:  # type: ignore[no-untyped-def]
    """A stream that stalls for longer than its hold time (a network stall), or that another
    client stops, is refused with the stop's reason; the stream ends there without re-arming
    (the cause stays in force), and a new stream started on purpose moves the arm again."""
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm, armgate.Arm(
        "127.0.0.1", port=mk1.port
    ) as other:
        arm.recalibrate(COMFORTABLE)
        arm.set_mode("cartesian")
        down = [0.0, 0.0, -0.01]
        with pytest.raises(armgate.CommandRejected) as idle:
            with arm.velocity_stream() as stream:
                for _ in range(10):
                    time.sleep(stream.twist(down) / 4)
                time.sleep(0.3)  # the stall
                stream.twist(down)
        assert idle.value.text == "ER20 Cmd TW after idle: send 0"
        time.sleep(0.2)
        assert arm.get_stop_cause() == (armgate.StopCause.STREAM_TIMEOUT, None)
        rest = arm.get_tcp_pose()
        with pytest.raises(armgate.CommandRejected) as stopped:
            with arm.velocity_stream() as stream:
                for _ in range(10):
                    time.sleep(stream.twist(down) / 4)
                other.stop()
                for _ in range(10):
                    time.sleep(stream.twist(down) / 4)
        assert stopped.value.text == "ER20 Cmd TW after ST: send 0"
        time.sleep(0.3)
        assert arm.get_stop_cause()[0] == armgate.StopCause.STOP
        held = arm.get_tcp_pose()
        assert rest.z - held.z > 0.0001  # the second stream moved the arm before the ST
        time.sleep(0.3)
        assert arm.get_tcp_pose().distance(held) < 2e-6  # and nothing since
        with arm.velocity_stream() as stream:
            for _ in range(10):
                time.sleep(stream.twist(down) / 4)
        assert arm.get_stop_cause() == (None, None)
        assert held.z - arm.get_tcp_pose().z > 0.0001


def test_joint_moves_arrive(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        assert arm.set_mode(armgate.Mode.JOINT) == armgate.Mode.JOINT
        q = arm.get_joints()
        q[0] += 0.05
        reached = arm.move_j(q)
        assert reached is not None and math.dist(reached, q) <= 0.001
        # With a duration: a one-point joint sequence.
        q[5] -= 0.05
        started = time.monotonic()
        reached = arm.move_j(q, time=1.0)
        assert reached is not None and math.dist(reached, q) <= 0.001
        assert time.monotonic() - started >= 0.9


def test_ik_solutions_and_a_joint_move_on_a_chosen_branch(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        assert arm.set_mode(armgate.Mode.JOINT) == armgate.Mode.JOINT
        pose = arm.get_tcp_pose()
        q = arm.get_joints()
        solutions = arm.ik_solutions(pose)
        assert solutions is not None and len(solutions) >= 1
        branches = [b for b, _ in solutions]
        assert len(set(branches)) == len(branches)
        present = [b for b, s in solutions if math.dist(s, q) < 1e-3]
        assert len(present) == 1
        goal = dataclasses.replace(pose, z=pose.z + 0.02)
        # By name, as ik-move's --branch reads it: shoulder-left,elbow-up,wrist-noflip.
        name = armgate.branch.branch_name(present[0])
        target, branch = arm.move_j_to_pose(goal, branch=name)
        assert branch == present[0]
        assert math.dist(arm.get_joints(), target) <= 0.001


def test_ik_solutions_of_a_seven_joint_arm_are_whole(sim_factory) -> None:  # type: ignore[no-untyped-def]
    iiwa = sim_factory("iiwa14")
    with armgate.Arm("127.0.0.1", port=iiwa.port) as arm:
        q = arm.get_joints()
        solutions = arm.ik_solutions(arm.get_tcp_pose())
        assert solutions is not None and len(solutions) >= 1
        assert all(len(s) == 7 for _, s in solutions)
        # The solutions for the present θ3 (the redundancy parameter): the present joints too.
        assert any(math.dist(s, q) < 1e-3 for _, s in solutions)


def test_a_chosen_theta3_lists_and_moves_on_a_seven_joint_arm(sim_factory) -> None:  # type: ignore[no-untyped-def]
    iiwa = sim_factory("iiwa14", "--start", "0.1,0.5,0.3,-1.0,0.2,0.8,0.1")
    with armgate.Arm("127.0.0.1", port=iiwa.port) as arm:
        pose = arm.get_tcp_pose()
        # The same pose with θ3 = -0.2 instead of the present 0.3 (KR, then KS with its bit).
        solutions = arm.ik_solutions(pose, theta3=-0.2)
        assert solutions is not None and len(solutions) >= 1
        assert all(abs(q[2] + 0.2) < 1e-5 for _, q in solutions)
        with pytest.raises(armgate.BadIndex):
            arm.choose_redundancy(theta5=0.1)  # seven joints: no θ5
        with pytest.raises(armgate.BeyondJointLimit):
            arm.choose_redundancy(theta3=3.0)
        assert arm.set_mode(armgate.Mode.JOINT) == armgate.Mode.JOINT
        target, _ = arm.move_j_to_pose(pose, theta3=-0.2)
        assert abs(target[2] + 0.2) < 1e-5
        assert abs(arm.get_joints()[2] + 0.2) < 1e-3
        assert math.dist(arm.get_tcp_pose().xyz, pose.xyz) < 1e-3


@pytest.mark.parametrize(
    "robot,start",
    [
        ("iiwa14", [0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1]),
        ("ranger-mk2", [0.1, 0.5, 0.3, 1.0, 0.2, 0.8, 0.1, 0.2]),
        # Its pretend joints start at home whatever --start says, and home is singular: moved.
        ("hybrid", [0.0, 0.0, 0.0, 0.2, -0.3, 0.1]),
    ],
)
def test_configurations_are_named_and_taken_by_name_on_every_robot(  # type: ignore[no-untyped-def]
    sim_factory, robot: str, start: List[float]
) -> None:
    """Issue 37: each solution of a pose has a configuration of its own (on a 7–8 joint arm for
    the present θ3, θ5), the present one among them; a move by its short name takes it; hybrid
    has no wrist bit."""
    sim = sim_factory(robot, "--start", ",".join(map(str, start)))
    with armgate.Arm("127.0.0.1", port=sim.port) as arm:
        assert arm.set_mode(armgate.Mode.JOINT) == armgate.Mode.JOINT
        if math.dist(arm.get_joints(), start) > 1e-3:
            arm.move_j(start)
        q = arm.get_joints()
        pose = arm.get_tcp_pose()
        solutions = arm.ik_solutions(pose)
        assert solutions is not None and len(solutions) >= 2
        branches = [b for b, _ in solutions]
        assert len(set(branches)) == len(branches), solutions
        present = arm.get_configuration()
        assert [b for b, s in solutions if math.dist(s, q) < 1e-3] == [present], solutions
        if robot == "hybrid":
            assert all(b & 4 == 0 for b in branches)
            with pytest.raises(armgate.BadIndex):
                arm.move_j_to_pose(pose, branch=armgate.branch.short_name(present | 4))
        # The present configuration by name: the arm is there already.
        short = armgate.branch.short_name(present)
        target, branch = arm.move_j_to_pose(pose, branch=short, wait=False)
        assert branch == present
        assert math.dist(target, q[:6]) < 1e-3


def test_joint_via_points_are_passed_in_order(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        arm.set_mode("joint")
        q0 = arm.get_joints()
        a = [q0[0] + 0.03] + q0[1:]
        b = [q0[0] + 0.06] + q0[1:]
        reached = arm.run_via([(a, 0.5), (b, 0.5)])
        assert isinstance(reached, list) and math.dist(reached, b) <= 0.001


def test_blended_via_points_and_their_tolerances(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        arm.set_mode("joint")
        assert arm.set_via_tolerance(False, 4, 0.05) == pytest.approx(0.05)
        assert arm.set_via_tolerance(False, 4, None) == 0.0  # the robot file's default
        with pytest.raises(armgate.BadIndex) as bad:
            arm.set_via_tolerance(False, 20, 0.05)
        assert bad.value.text == "ER24 Cmd jT bad index"
        q0 = arm.get_joints()
        a = [q0[0] + 0.05] + q0[1:]
        b = [a[0], a[1], a[2] - 0.05] + a[3:]
        reached = arm.run_via([(a, 0.0), (b, 0.0)], blend=0.02)
        assert isinstance(reached, list) and math.dist(reached, b) <= 0.001


def test_temperatures_of_every_drive(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        temperatures = arm.get_temperatures()
        assert len(temperatures) == 6
        # The simulated Whistle starts at 25 degC; a drive not read yet has no reading.
        assert all(t is None or 24.0 <= t <= 45.0 for t in temperatures)


def test_off_and_on_and_their_refusals(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        arm.off()
        with pytest.raises(armgate.ArmDidNotStop) as stop:
            arm.off()
        assert stop.value.text.startswith("ER10 ")
        # The drives take a few cycles to stop; ON is refused until they have.
        deadline = time.monotonic() + 5
        while True:
            try:
                arm.on()
                break
            except armgate.ArmDidNotStart:
                assert time.monotonic() < deadline
                time.sleep(0.05)
        # ON while starting asks for what is under way (or, on an older controller, is
        # refused); once the drives run it is refused.
        wait_running(arm)
        with pytest.raises(armgate.ArmDidNotStart):
            arm.on()


def test_status_or_a_clear_error_from_an_older_controller(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        try:
            status = arm.get_status()
        except armgate.ControllerTooOld as e:
            assert "SQ" in str(e)
            return
        assert status.name == "ranger-mk1"
        assert status.joint_count == 6
        assert status.mode == armgate.Mode.OFF
        assert status.motion == armgate.Motion.IDLE
        assert status.drive_fault == 0
        assert status.uptime > 0


def test_an_eight_joint_arm_uses_both_banks(mk2) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk2.port) as arm:
        assert arm.joint_count == 8
        assert close(arm.get_joints(), mk2.home()["joints"])
        q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8]
        arm.recalibrate(q)
        assert close(arm.get_joints(), q, 1e-4)
        assert len(arm.get_temperatures()) == 8
        arm.set_mode("joint")
        q[6] += 0.04
        q[7] -= 0.04
        reached = arm.move_j(q)
        assert reached is not None and close(reached, q, 1e-3)
        with pytest.raises(ValueError):
            arm.move_j(q[:6])


def test_nothing_listening_is_reported(sim_factory) -> None:  # type: ignore[no-untyped-def]
    from conftest import free_port

    with armgate.Arm("127.0.0.1", port=free_port(), timeout=0.05) as arm:
        with pytest.raises((armgate.ControllerUnreachable, armgate.ReplyTimeout)):
            arm.get_tcp_pose()


def _far_joint_goal(arm: armgate.Arm) -> list:  # type: ignore[type-arg]
    """A joint goal 0.3 rad along joint 1: about 5 s on ranger-mk1."""
    arm.recalibrate(COMFORTABLE)
    assert arm.set_mode("joint") == armgate.Mode.JOINT
    goal = arm.get_joints()
    goal[0] += 0.3
    return goal


def _at_rest(arm: armgate.Arm, within: float = 3.0) -> bool:
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        if arm.get_status(details=False).motion == armgate.Motion.IDLE:
            return True
        time.sleep(0.05)
    return False


def test_a_move_interrupted_by_ctrl_c_is_stopped(mk1) -> None:  # type: ignore[no-untyped-def]
    """Issue 33: Ctrl-C (KeyboardInterrupt) in ``move_j`` sends ST; the arm comes to rest
    short of the goal instead of running on."""
    import _thread
    import threading

    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        goal = _far_joint_goal(arm)
        timer = threading.Timer(1.0, _thread.interrupt_main)
        timer.start()
        with pytest.raises(KeyboardInterrupt) as interrupted:
            arm.move_j(goal)
        timer.join()
        assert interrupted.value.stop == "sent ST: the arm stops and holds"  # type: ignore[attr-defined]
        assert _at_rest(arm)
        status = arm.get_status()
        assert status.stop_cause == armgate.StopCause.STOP
        assert status.stopped_by == "127.0.0.1:{}".format(arm._socket.getsockname()[1])
        rest = arm.get_joints()
        time.sleep(0.5)
        assert close(arm.get_joints(), rest, 1e-6), "the arm moves on"
        assert goal[0] - rest[0] > 0.1


def test_a_wait_that_times_out_stops_the_arm_and_says_so(mk1) -> None:  # type: ignore[no-untyped-def]
    options = armgate.WaitOptions(timeout=0.5)
    with armgate.Arm("127.0.0.1", port=mk1.port, wait_options=options) as arm:
        goal = _far_joint_goal(arm)
        with pytest.raises(armgate.WaitTimeout) as timeout:
            arm.move_j(goal)
        assert timeout.value.stop == "sent ST: the arm stops and holds"
        assert str(timeout.value).endswith("; sent ST: the arm stops and holds")
        assert _at_rest(arm)
        assert goal[0] - arm.get_joints()[0] > 0.1


def test_a_move_another_client_stops_raises_stopped_with_the_cause_and_who(mk1) -> None:  # type: ignore[no-untyped-def]
    import threading

    with armgate.Arm("127.0.0.1", port=mk1.port) as arm, armgate.Arm(
        "127.0.0.1", port=mk1.port
    ) as other:
        goal = _far_joint_goal(arm)
        timer = threading.Timer(1.0, other.stop)
        timer.start()
        with pytest.raises(armgate.Stopped) as stopped:
            arm.move_j(goal)
        timer.join()
        by = "client 127.0.0.1:{}".format(other._socket.getsockname()[1])
        assert stopped.value.cause == armgate.StopCause.STOP
        assert stopped.value.by == by
        assert str(stopped.value) == f"the motion was stopped by {by}: ST (target 1 not reached)"
        assert stopped.value.stop is None  # the controller had stopped it: no ST of its own
        status = arm.get_status()
        assert status.holder == armgate.Holder.YOU
        assert status.holder_address == "127.0.0.1:{}".format(arm._socket.getsockname()[1])
        assert status.clients is not None and status.clients >= 2  # the fixture's probe too


def test_a_refusal_by_another_holder_names_it_with_its_port(mk1) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm, armgate.Arm(
        "127.0.0.1", port=mk1.port
    ) as other:
        goal = _far_joint_goal(arm)
        arm.move_j(goal, wait=False)
        with pytest.raises(armgate.HeldByOther) as held:
            other.set_mode("cartesian")
        holder = "127.0.0.1:{}".format(arm._socket.getsockname()[1])
        assert held.value.holder == holder
        assert held.value.text.startswith("ER40 Cmd CM by 127.0.0.1")
        assert f"({holder} holds the arm while it moves" in str(held.value)
        arm.stop()


def test_a_move_start_reports_its_planned_duration(mk1) -> None:  # type: ignore[no-untyped-def]
    """``jB``'s reply carries the planned duration (f6), which sizes the wait's timeout."""
    with armgate.Arm("127.0.0.1", port=mk1.port) as arm:
        goal = _far_joint_goal(arm)  # 0.3 rad on joint 1, at most 0.07 rad/s
        arm._write_banks("jG", goal, 0, 0.0)
        planned = arm.request("jB").values[6]
        assert 0.3 / 0.07 <= planned < 60.0
        assert arm._options(0.0, planned).timeout == pytest.approx(2 * planned + 30.0)
        arm.stop()
