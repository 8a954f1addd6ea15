//! The control cycle's policy (docs/architecture.md): request batching, late ticks, notices,
//! bus-off recovery on `ON`.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drives_rig;

use std::net::SocketAddr;

use armgate_core::cycle::{
    CanDrives, Cycle, Datagram, Dropped, Link, MAX_CATCH_UP, Outgoing, REQUESTS_PER_TICK,
};
use armgate_core::drives::{BusState, CanBus, DriveSettings, DriveState, TxError};
use armgate_core::sim::IdealArm;
use armgate_core::sim::VirtualBus;
use armgate_core::sim::{ArmModel, SimulatedDrives};
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::Command;
use drives_rig::{Client, request, robot};

fn simulated_arm() -> Cycle<SimulatedDrives, ()> {
    let config = robot("ranger-mk1");
    let arm = IdealArm::new(config.home());
    Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm)))
}

#[test]
fn at_most_eight_requests_per_tick_each_answered_with_the_ticks_measurement() {
    let mut cycle = simulated_arm();
    let mut client = Client::default();
    for _ in 0..10 {
        client.requests.push_back(request(Command::Pose));
    }
    // The very first tick already answers PS: requests come after the control step.
    cycle.tick(0, &mut client);
    assert_eq!(client.replies.len(), REQUESTS_PER_TICK);
    assert!(
        client
            .replies
            .iter()
            .all(|r| r.payload().starts_with(b"SP"))
    );
    cycle.tick(cycle.next_due_us(), &mut client);
    assert_eq!(client.replies.len(), 10);
    assert_eq!(cycle.counters().requests, 10);
}

#[test]
fn late_ticks_run_at_their_scheduled_times_and_only_far_behind_are_skipped() {
    let mut cycle = simulated_arm();
    let mut client = Client::default();
    let period = cycle.period_us();
    cycle.tick(0, &mut client);
    // Three periods late: the shell calls back to back, each tick at its own time.
    let now = 4 * period;
    let mut times = Vec::new();
    while cycle.next_due_us() <= now {
        times.push(cycle.tick(now, &mut client).time);
    }
    let t = robot("ranger-mk1").control_period;
    assert_eq!(times.len(), 4);
    for (k, time) in times.iter().enumerate() {
        assert!((time - (k + 1) as f64 * t).abs() < 1e-12, "{times:?}");
    }
    assert_eq!(cycle.counters().late_ticks, 3);
    assert_eq!(cycle.counters().skipped_ticks, 0);
    // Far behind: the missed ticks are skipped, the schedule goes on from the present.
    let now = cycle.next_due_us() + (MAX_CATCH_UP + 10) * period;
    let outcome = cycle.tick(now, &mut client);
    assert_eq!(outcome.skipped, MAX_CATCH_UP + 10);
    assert_eq!(cycle.counters().skipped_ticks, MAX_CATCH_UP + 10);
    assert!(cycle.next_due_us() > now);
}

/// The virtual bus behind a bus-off that only `recover` clears, as SocketCAN's latch.
struct LatchingBus {
    bus: VirtualBus,
    bus_off: bool,
    recoveries: u32,
}

impl CanBus for LatchingBus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        if self.bus_off {
            return Err(TxError::BusOff);
        }
        self.bus.try_transmit(frame)
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.bus.try_receive()
    }

    fn state(&self) -> BusState {
        BusState::from_bus_off(self.bus_off)
    }

    fn advance_to(&mut self, now: f64) -> bool {
        self.bus.advance_to(now)
    }

    fn recover(&mut self) {
        self.recoveries += 1;
        self.bus_off = false;
    }
}

/// ranger-mk1 on a bus whose bus-off the test sets, for clients with addresses `P`.
fn latching<P: armgate_core::cycle::Peer>() -> Cycle<CanDrives<LatchingBus>, P> {
    let config = robot("ranger-mk1");
    let bus = LatchingBus {
        bus: VirtualBus::for_robot(&config),
        bus_off: false,
        recoveries: 0,
    };
    let drives = CanDrives::started(&config, &DriveSettings::default(), bus).unwrap();
    Cycle::new(&config, drives)
}

#[test]
fn bus_off_faults_until_the_clients_on_recovers_the_bus() {
    let mut cycle: Cycle<_, ()> = latching();
    let mut client = Client::default();
    let tick = |cycle: &mut Cycle<CanDrives<LatchingBus>, ()>, client: &mut Client| {
        let due = cycle.next_due_us();
        cycle.tick(due, client);
    };
    for _ in 0..200 {
        tick(&mut cycle, &mut client);
    }
    assert!(cycle.drives().manager().is_operational());

    // Bus-off before any client spoke: the fault notice has nobody to go to, and is counted.
    cycle.drives_mut().bus_mut().bus_off = true;
    for _ in 0..5 {
        tick(&mut cycle, &mut client);
    }
    assert_eq!(cycle.drives().manager().state(), DriveState::Faulted);
    assert_eq!(cycle.counters().notices_unaddressed, 1);
    assert!(client.notices.is_empty());

    // ON: the bus recovers, the drives start again and run.
    client.requests.push_back(request(Command::On));
    tick(&mut cycle, &mut client);
    assert!(client.replies[0].payload().starts_with(b"NO"));
    assert_eq!(cycle.drives().bus().recoveries, 1);
    for _ in 0..200 {
        tick(&mut cycle, &mut client);
    }
    assert!(
        cycle.drives().manager().is_operational(),
        "{:?}",
        cycle.drives().manager().fault()
    );
}

#[test]
fn a_replay_offers_each_datagram_to_the_first_tick_due_after_it_arrives() {
    use armgate_core::sim::replay::Replay;
    let ps = request(Command::Pose);
    let hex: String = ps.payload().iter().map(|b| format!("{b:02x}")).collect();
    let mut text = String::from("# ten PS in one tick, then an undersized one\n");
    for _ in 0..10 {
        text.push_str(&format!("30000 {hex}\n"));
    }
    text.push_str("100000 5053  # `PS`, 2 bytes\n");
    let mut cycle = simulated_arm();
    let transcript = Replay::parse(&text)
        .unwrap()
        .run(&mut cycle, 8, |_| "arm".into());
    let replies: Vec<usize> = transcript
        .lines()
        .map(|line| line.matches("reply:").count())
        .collect();
    // ranger-mk1's period is 19.44 ms: tick 2 (38.88 ms) is the first after 30 ms, tick 6
    // (116.64 ms) the first after 100 ms.
    assert_eq!(replies, [0, 0, 8, 2, 0, 0, 1, 0]);
    let er01: String = b"ER01".iter().map(|b| format!("{b:02x}")).collect();
    assert!(
        transcript.lines().nth(6).unwrap().contains(&er01),
        "{transcript}"
    );
    assert!(Replay::parse("12 zz\n").is_err());
    assert!(Replay::parse("x 00\n").is_err());
}

/// Two clients with their own addresses.
#[derive(Default)]
struct Clients {
    requests: std::collections::VecDeque<Datagram<SocketAddr>>,
    replies: Vec<Datagram<SocketAddr>>,
    notices: Vec<Datagram<SocketAddr>>,
}

impl Link<SocketAddr> for Clients {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        self.requests.pop_front()
    }

    fn send(&mut self, datagram: &Datagram<SocketAddr>, kind: Outgoing) -> Result<(), Dropped> {
        match kind {
            Outgoing::Reply => self.replies.push(*datagram),
            Outgoing::Notice => self.notices.push(*datagram),
        }
        Ok(())
    }
}

/// The bus-off fault's notice, after `requests` from their clients: to whom it went.
fn bus_off_notice_after(requests: &[(SocketAddr, &[u8])]) -> Vec<SocketAddr> {
    let mut cycle: Cycle<_, SocketAddr> = latching();
    let mut clients = Clients::default();
    for _ in 0..200 {
        cycle.tick(cycle.next_due_us(), &mut clients);
    }
    for (from, bytes) in requests {
        clients.requests.push_back(Datagram::new(bytes, *from));
    }
    cycle.tick(cycle.next_due_us(), &mut clients);
    cycle.drives_mut().bus_mut().bus_off = true;
    for _ in 0..5 {
        cycle.tick(cycle.next_due_us(), &mut clients);
    }
    clients.notices.iter().map(|n| n.peer).collect()
}

#[test]
fn notices_go_to_the_holder_or_the_last_valid_sender_never_to_garbage() {
    let a = SocketAddr::from(([192, 168, 1, 2], 5000));
    let b = SocketAddr::from(([192, 168, 1, 3], 6000));
    let mode = request(Command::ChangeMode);
    let poll = request(Command::Pose);
    let garbage = [b'X'; 31];
    // Nobody holds the arm: the last valid sender gets it, not the sender of garbage.
    assert_eq!(
        bus_off_notice_after(&[(a, poll.payload()), (b, &garbage)]),
        [a]
    );
    // A holds the arm (CM): B's polls do not take its notices.
    assert_eq!(
        bus_off_notice_after(&[(a, mode.payload()), (b, poll.payload()), (b, &garbage)]),
        [a]
    );
}

#[test]
fn one_planning_request_a_tick_the_rest_wait_and_a_stop_cancels_them() {
    let a = SocketAddr::from(([192, 168, 1, 2], 5000));
    let b = SocketAddr::from(([192, 168, 1, 3], 6000));
    let mut cycle: Cycle<SimulatedDrives, SocketAddr> = {
        let config = robot("ranger-mk1");
        let arm = IdealArm::new(config.home());
        Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm)))
    };
    let mut clients = Clients::default();
    let tick = |cycle: &mut Cycle<_, _>, clients: &mut Clients| {
        clients.replies.clear();
        cycle.tick(cycle.next_due_us(), clients);
        clients
            .replies
            .iter()
            .map(|r| {
                (
                    r.peer,
                    String::from_utf8_lossy(&r.payload()[..2]).into_owned(),
                )
            })
            .collect::<Vec<_>>()
    };
    tick(&mut cycle, &mut clients);
    // A: three goals (each checked with the IK) and a poll; B: a poll.
    for (from, command) in [
        (a, Command::GoalRpy),
        (a, Command::GoalRpy),
        (a, Command::Pose),
        (b, Command::Pose),
        (a, Command::GoalRpy),
    ] {
        clients
            .requests
            .push_back(Datagram::new(request(command).payload(), from));
    }
    // One planning request this tick; A's later requests wait behind its second, B's poll
    // does not.
    let first = tick(&mut cycle, &mut clients);
    assert_eq!(first[0].0, a);
    assert_eq!(first[1..], [(b, "SP".to_owned())]);
    let second = tick(&mut cycle, &mut clients);
    assert_eq!(second.iter().map(|r| r.0).collect::<Vec<_>>(), [a, a]);
    assert_eq!(second[1].1, "SP");
    let third = tick(&mut cycle, &mut clients);
    assert_eq!(third.iter().map(|r| r.0).collect::<Vec<_>>(), [a]);
    // Three begins from A and B's ST in one tick: the first begin is handled, the two that
    // wait are cancelled by the stop, which arrived after them.
    for (from, command) in [
        (a, Command::JointBegin),
        (a, Command::JointBegin),
        (a, Command::JointBegin),
        (b, Command::Stop),
    ] {
        clients
            .requests
            .push_back(Datagram::new(request(command).payload(), from));
    }
    clients.replies.clear();
    cycle.tick(cycle.next_due_us(), &mut clients);
    let texts: Vec<String> = clients
        .replies
        .iter()
        .map(|r| {
            String::from_utf8_lossy(r.payload())
                .trim_end_matches('\0')
                .to_owned()
        })
        .collect();
    assert_eq!(texts[0], "ER20 Cmd jB no goal");
    assert_eq!(
        texts[1..],
        [
            "ER42 Cmd jB cancelled by ST",
            "ER42 Cmd jB cancelled by ST",
            "TS"
        ]
    );
    assert!(tick(&mut cycle, &mut clients).is_empty());
}
