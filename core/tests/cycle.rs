//! The control cycle's policy (docs/architecture.md): request batching, late ticks, notices,
//! bus-off recovery on `ON`.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drives_rig;

use armgate_core::cycle::{CanDrives, Cycle, MAX_CATCH_UP, REQUESTS_PER_TICK};
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

#[test]
fn bus_off_faults_until_the_clients_on_recovers_the_bus() {
    let config = robot("ranger-mk1");
    let bus = LatchingBus {
        bus: VirtualBus::for_robot(&config),
        bus_off: false,
        recoveries: 0,
    };
    let drives = CanDrives::started(&config, &DriveSettings::default(), bus).unwrap();
    let mut cycle: Cycle<_, ()> = Cycle::new(&config, drives);
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
