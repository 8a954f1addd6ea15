//! Drive faults over a real CAN stack (`ARMGATE_E2E_CAN`, tools/socketcan-vm.sh): the Whistles
//! are a process of their own on the other side of the bus, so a fault is injected there (on
//! its standard input) or the process is killed, and the controller must stop the arm and say
//! why. Without `ARMGATE_E2E_CAN` these tests have nothing to act on and return at once.

use std::io::Write;

use super::*;

/// ranger-mk1 at a well-conditioned start, on, in joint mode, moving joint 1 by 0.5 rad.
fn moving(sim: &Sim) {
    let ready = [1.5708f32, 0.6, -0.4, 0.2, 1.8, 0.1];
    armgate(sim, &["on"]).0.unwrap();
    wait_drives(sim, 2.0);
    sim.ok("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let mut goal = ready;
    goal[0] += 0.5;
    sim.ok("jG", with_joints(&goal, 0.0), 0);
    sim.start_motion("jB");
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(status(sim)[4], 1.0, "moving");
}

/// Polls `SQ` until the drives are faulted with `code`, and the arm is at rest.
fn wait_fault(sim: &Sim, code: f32) -> [f32; 7] {
    assert!(
        poll_status(sim, Duration::from_secs(5), |s| s[1] == 4.0
            && s[2] == code
            && s[4] == 0.0),
        "never faulted with ER{code} at rest: {:?}",
        status(sim)
    );
    status(sim)
}

#[test]
fn an_emergency_from_a_drive_on_the_bus_stops_the_arm_and_on_starts_it_again() {
    if can_pair().is_none() {
        return;
    }
    let mut sim = Sim::start_with("ranger-mk1", &["--start", "1.5708,0.6,-0.4,0.2,1.8,0.1"]);
    moving(&sim);
    let whistles = sim.whistles.as_mut().unwrap();
    writeln!(whistles.stdin.as_mut().unwrap(), "emcy 103").unwrap();
    let s = wait_fault(&sim, 32.0);
    eprintln!("after `emcy 103`: SQ {s:?}");
    // The stop cause names the drive's joint (J3, index 2).
    let cause = stop_cause(&sim);
    eprintln!("SQ 2: {cause:?}");
    armgate(&sim, &["on"]).0.unwrap();
    wait_drives(&sim, 2.0);
}

#[test]
fn the_whistles_killed_mid_move_stop_the_arm_as_drives_not_answering() {
    if can_pair().is_none() {
        return;
    }
    let mut sim = Sim::start_with("ranger-mk1", &["--start", "1.5708,0.6,-0.4,0.2,1.8,0.1"]);
    moving(&sim);
    let whistles = sim.whistles.as_mut().unwrap();
    whistles.kill().unwrap();
    whistles.wait().unwrap();
    let s = wait_fault(&sim, 30.0);
    eprintln!("after the Whistles were killed: SQ {s:?}");
    // ON cannot bring drives that are gone back: it faults again.
    let _ = armgate(&sim, &["on"]);
    assert!(
        poll_status(&sim, Duration::from_secs(5), |s| s[1] == 4.0),
        "{:?}",
        status(&sim)
    );
}
