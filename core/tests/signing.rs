//! Signed datagrams in the cycle (docs/safety.md, "Signing"): with a key, only validly signed,
//! fresh datagrams are served and answered signed; everything else is dropped, counted by
//! cause (`SQ` index 4) and never answered. Without a key, everything works as before.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::approx_constant
)]

mod drives_rig;

use armgate_core::config::ValidRobot;
use std::cell::Cell;
use std::rc::Rc;

use std::net::SocketAddr;

use armgate_core::cycle::{
    Cycle, Datagram, Dropped, Link, Outgoing, ReplayStore, Signing, UnsignedAccess,
};
use armgate_core::kinematics::Joints;
use armgate_core::sim::{ArmModel, IdealArm, SimulatedDrives};
use armgate_protocol::client::signed::{
    CONTROLLER_LINK, ControllerId, IDENTITY_INDEX, IdentityReport, SIGNED_LEN, Signature, Signed,
    SigningKey, SigningPolicy, SigningReport,
};
use armgate_protocol::client::{Command, MESSAGE_LEN, Message, Reply, Request};
use drives_rig::{Client, request, robot};

const KEY: &str = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";
const OTHER_KEY: &str = "ff0102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

/// The controller id of the tests' controller.
const ARM: ControllerId = ControllerId(0x0a4d_0001);

/// The tests' key, for their controller.
fn key() -> SigningKey {
    SigningKey::parse(KEY).unwrap().for_controller(ARM)
}

fn cycle(unsigned: Option<UnsignedAccess>) -> Cycle<SimulatedDrives, ()> {
    cycle_for(robot("ranger-mk1"), unsigned)
}

fn cycle_for(config: ValidRobot, unsigned: Option<UnsignedAccess>) -> Cycle<SimulatedDrives, ()> {
    cycle_at(&config, config.home(), unsigned)
}

fn cycle_at(
    config: &ValidRobot,
    start: Joints,
    unsigned: Option<UnsignedAccess>,
) -> Cycle<SimulatedDrives, ()> {
    let arm = IdealArm::new(start);
    let cycle = Cycle::new(config, SimulatedDrives::new(ArmModel::Ideal(arm)));
    match unsigned {
        None => cycle,
        Some(unsigned) => cycle.with_signing(Signing {
            key: Some(key()),
            unsigned,
        }),
    }
}

fn message(command: Command, values: [f32; 7]) -> [u8; MESSAGE_LEN] {
    Request {
        command,
        values,
        index: 0,
    }
    .to_bytes()
}

fn signed(command: Command, values: [f32; 7], link: u8, timestamp: u64) -> [u8; SIGNED_LEN] {
    Signature { link, timestamp }.emit(&message(command, values), &key())
}

/// Ticks once with `datagrams` waiting; the replies.
fn exchange(cycle: &mut Cycle<SimulatedDrives, ()>, datagrams: &[&[u8]]) -> Vec<Datagram<()>> {
    let mut client = Client::default();
    for d in datagrams {
        client.requests.push_back(Datagram::new(d, ()));
    }
    cycle.tick(cycle.next_due_us(), &mut client);
    client.replies
}

/// The signing report as a client reads it with a signed `SQ` index 4.
fn report(cycle: &mut Cycle<SimulatedDrives, ()>, timestamp: u64) -> SigningReport {
    let mut sq = message(Command::Status, [0.0; 7]);
    sq[30] = 4;
    let request = Signature { link: 9, timestamp }.emit(&sq, &key());
    let replies = exchange(cycle, &[&request]);
    let reply = verified(&replies[0], timestamp);
    SigningReport::from_reply(&reply).unwrap()
}

/// A signed answer, checked as a client checks it: the key's tag, the controller's link, a
/// timestamp no older than the request's.
fn verified<P>(datagram: &Datagram<P>, request_timestamp: u64) -> Reply {
    let bytes = datagram.payload();
    assert_eq!(
        bytes.len(),
        SIGNED_LEN,
        "answers to signed requests are signed"
    );
    let block = Signed::new_checked(bytes).unwrap();
    let signature = Signature::parse(&block, &key()).unwrap();
    assert_eq!(signature.link, CONTROLLER_LINK);
    assert!(signature.timestamp >= request_timestamp);
    Reply::parse(&Message::new_checked(&bytes[..MESSAGE_LEN]).unwrap()).unwrap()
}

#[test]
fn without_a_key_everything_is_served_unsigned_as_before() {
    let mut cycle = cycle(None);
    let replies = exchange(&mut cycle, &[request(Command::Pose).payload()]);
    assert_eq!(replies[0].payload().len(), MESSAGE_LEN);
    assert!(replies[0].payload().starts_with(b"SP"));
    // A signed datagram to a controller without a key: its message is served, unsigned.
    let replies = exchange(&mut cycle, &[&signed(Command::Pose, [0.0; 7], 1, 5)]);
    assert_eq!(replies[0].payload().len(), MESSAGE_LEN);
    let mut sq = message(Command::Status, [0.0; 7]);
    sq[30] = 4;
    let replies = exchange(&mut cycle, &[&sq]);
    let reply = Reply::parse(&Message::new_checked(replies[0].payload()).unwrap()).unwrap();
    let report = SigningReport::from_reply(&reply).unwrap();
    assert_eq!(report.policy, Some(SigningPolicy::Off));
    // Both PS, and the SQ itself.
    assert_eq!((report.unsigned, report.dropped()), (3, 0));
}

#[test]
fn with_a_key_signed_requests_are_answered_signed_and_the_rest_dropped_by_cause() {
    let mut cycle = cycle(Some(UnsignedAccess::Refused));
    let t = 1_000_000;
    let good = signed(Command::Pose, [0.0; 7], 1, t);
    let replies = exchange(&mut cycle, &[&good]);
    assert_eq!(verified(&replies[0], t).command, Command::Pose);

    let mut forged = signed(Command::Pose, [0.0; 7], 1, t + 1);
    forged[40] ^= 0x20;
    let mut altered = signed(Command::Pose, [0.0; 7], 1, t + 2);
    altered[3] ^= 0x01;
    let wrong_key = Signature {
        link: 1,
        timestamp: t + 3,
    }
    .emit(
        &message(Command::Pose, [0.0; 7]),
        &SigningKey::parse(OTHER_KEY).unwrap(),
    );
    // The controller's own link: a reflected answer.
    let reflected = signed(Command::Pose, [0.0; 7], CONTROLLER_LINK, t + 4);
    let truncated = &good[..SIGNED_LEN - 1];
    let unsigned = message(Command::Pose, [0.0; 7]);
    let older = signed(Command::Pose, [0.0; 7], 1, t - 1);
    let replies = exchange(
        &mut cycle,
        &[
            &forged, &altered, &wrong_key, &reflected, truncated, &unsigned, &good, &older,
        ],
    );
    assert!(replies.is_empty(), "dropped datagrams are never answered");
    let report = report(&mut cycle, t + 10);
    assert_eq!(
        report,
        SigningReport {
            policy: Some(SigningPolicy::Required),
            // The first PS, and the SQ just sent.
            signed: 2,
            unsigned: 0,
            dropped_unsigned: 1,
            dropped_truncated: 1,
            dropped_forged: 4,
            dropped_replayed: 2,
        }
    );
    assert_eq!(cycle.signing(), report);
}

#[test]
fn timestamps_count_per_link_and_every_link_has_its_own() {
    let mut cycle = cycle(Some(UnsignedAccess::Refused));
    // Link 2 far ahead does not make link 3's earlier timestamps old.
    let replies = exchange(
        &mut cycle,
        &[
            &signed(Command::Pose, [0.0; 7], 2, 500),
            &signed(Command::Pose, [0.0; 7], 3, 100),
            &signed(Command::Pose, [0.0; 7], 3, 101),
            &signed(Command::Pose, [0.0; 7], 255, 7),
        ],
    );
    assert_eq!(replies.len(), 4);
    // Answers carry increasing timestamps, none older than a request served.
    let stamps: Vec<u64> = replies
        .iter()
        .map(|r| Signed::new_checked(r.payload()).unwrap().timestamp())
        .collect();
    assert!(stamps.windows(2).all(|w| w[0] < w[1]), "{stamps:?}");
    assert!(stamps[0] >= 500);
    // Equal is not newer.
    let replies = exchange(&mut cycle, &[&signed(Command::Pose, [0.0; 7], 3, 101)]);
    assert!(replies.is_empty());
    assert_eq!(cycle.signing().dropped_replayed, 1);
}

#[test]
fn a_replayed_or_forged_motion_request_does_not_move_the_arm() {
    let mut cycle = cycle(Some(UnsignedAccess::Refused));
    let goal = [1.7, 0.1, 1.5, 0.1, 1.2, 0.1, 0.0];
    let jb = signed(Command::JointBegin, [0.0; 7], 1, 13);
    let replies = exchange(
        &mut cycle,
        &[
            &signed(
                Command::ChangeMode,
                [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                1,
                10,
            ),
            &signed(Command::JointGoal, goal, 1, 11),
            &jb,
        ],
    );
    assert_eq!(replies.len(), 3);
    assert_eq!(verified(&replies[2], 13).command, Command::JointBegin);
    assert!(cycle.handler().controller().is_moving());
    let replies = exchange(&mut cycle, &[&signed(Command::Stop, [0.0; 7], 1, 14)]);
    assert_eq!(verified(&replies[0], 14).command, Command::Stop);
    for _ in 0..200 {
        exchange(&mut cycle, &[]);
    }
    assert!(!cycle.handler().controller().is_moving());
    let mut forged = signed(Command::JointBegin, [0.0; 7], 1, 20);
    forged[SIGNED_LEN - 1] ^= 1;
    let unsigned = message(Command::JointBegin, [0.0; 7]);
    // The captured jB, sent again.
    let replies = exchange(&mut cycle, &[&jb, &forged, &unsigned]);
    assert!(replies.is_empty());
    for _ in 0..10 {
        exchange(&mut cycle, &[]);
        assert!(!cycle.handler().controller().is_moving());
    }
    let report = cycle.signing();
    assert_eq!(
        (
            report.dropped_replayed,
            report.dropped_forged,
            report.dropped_unsigned
        ),
        (1, 1, 1)
    );
}

#[test]
fn unsigned_clients_may_read_and_stop_or_do_everything_as_configured() {
    let mut cycle = cycle(Some(UnsignedAccess::Read));
    // The reads and the stops; not KS, which plans (the planning slot is the signed clients').
    let reads = [
        Command::Pose,
        Command::JointPosition,
        Command::IkSolution,
        Command::Stop,
    ];
    let datagrams: Vec<_> = reads.iter().map(|c| message(*c, [0.0; 7])).collect();
    let mut waiting: Vec<&[u8]> = datagrams.iter().map(|d| &d[..]).collect();
    let mode = message(Command::ChangeMode, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    waiting.push(&mode);
    let replies = exchange(&mut cycle, &waiting);
    assert_eq!(replies.len(), 3, "KS plans, CM is not a read");
    assert!(replies.iter().all(|r| r.payload().len() == MESSAGE_LEN));
    assert_eq!(cycle.signing().dropped_unsigned, 2);
    assert_eq!(cycle.signing().policy, Some(SigningPolicy::UnsignedRead));
    // A signed client beside it is answered signed.
    let replies = exchange(&mut cycle, &[&signed(Command::Pose, [0.0; 7], 4, 1)]);
    verified(&replies[0], 1);

    let mut cycle = cycle_all();
    let replies = exchange(&mut cycle, &[&mode]);
    assert!(replies[0].payload().starts_with(b"MC"));
    assert_eq!(cycle.signing().policy, Some(SigningPolicy::UnsignedAll));
}

fn cycle_all() -> Cycle<SimulatedDrives, ()> {
    cycle(Some(UnsignedAccess::All))
}

#[test]
fn notices_to_a_signed_client_are_signed() {
    // Bounds that end at x = 0.3 m: with the base turned to q1 = 0.5 the tool is outside (a
    // joint move there is refused now, so the arm starts there, as after a recalibration),
    // and ER21 follows, to the last (signed) sender.
    let config = robot("ranger-mk1")
        .edit(|config| config.workspace.bounds[1] = 0.3)
        .unwrap();
    let outside = [0.5, 0.6, -0.4, 0.2, 1.8, 0.1];
    let start = Joints::from_slice(&outside).unwrap();
    let mut cycle = cycle_at(&config, start, Some(UnsignedAccess::Refused));
    let mode = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let replies = exchange(&mut cycle, &[&signed(Command::ChangeMode, mode, 1, 12)]);
    assert_eq!(verified(&replies[0], 12).command, Command::ChangeMode);
    let mut client = Client::default();
    for _ in 0..3000 {
        cycle.tick(cycle.next_due_us(), &mut client);
    }
    assert!(!client.notices.is_empty());
    for notice in &client.notices {
        let block = Signed::new_checked(notice.payload()).unwrap();
        let signature = Signature::parse(&block, &key()).unwrap();
        assert!(signature.timestamp > 12);
        assert!(notice.payload().starts_with(b"ER21"));
    }
}

/// 10 µs steps in a day; a timestamp in 2024.
const DAY: u64 = 86_400 * 100_000;
const NOW: u64 = 3_300 * DAY;

/// A cycle with the key for `controller` (unsigned datagrams refused).
fn cycle_of(controller: ControllerId) -> Cycle<SimulatedDrives, ()> {
    let config = robot("ranger-mk1");
    let arm = IdealArm::new(config.home());
    Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm))).with_signing(Signing {
        key: Some(key().for_controller(controller)),
        unsigned: UnsignedAccess::Refused,
    })
}

/// `CM 1`, `jG` a little away from home, `jB`: a sequence that moves the arm, signed on `link`
/// from `timestamp` on.
fn move_sequence(link: u8, timestamp: u64) -> [[u8; SIGNED_LEN]; 3] {
    let goal = [1.7, 0.1, 1.5, 0.1, 1.2, 0.1, 0.0];
    [
        signed(
            Command::ChangeMode,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            link,
            timestamp,
        ),
        signed(Command::JointGoal, goal, link, timestamp + 1),
        signed(Command::JointBegin, [0.0; 7], link, timestamp + 2),
    ]
}

/// Sends `datagrams` one a tick; how many were answered, and whether the arm then moves.
fn run(cycle: &mut Cycle<SimulatedDrives, ()>, datagrams: &[[u8; SIGNED_LEN]]) -> (usize, bool) {
    let answered = datagrams.iter().map(|d| exchange(cycle, &[d]).len()).sum();
    for _ in 0..5 {
        exchange(cycle, &[]);
    }
    (answered, cycle.handler().controller().is_moving())
}

#[test]
fn a_datagram_signed_for_another_controller_is_forged_there_and_the_identity_request_names_it() {
    let (a, b) = (ControllerId(0x0a4d_0001), ControllerId(0x0b4d_0002));
    let mut arm_b = cycle_of(b);
    // Arm A's sequence (the tests' key is A's) moves nothing on B: forged there.
    assert_eq!(run(&mut arm_b, &move_sequence(1, NOW)), (0, false));
    assert_eq!(arm_b.signing().dropped_forged, 3);
    // Signed for any controller, only the identity request is served; its answer names B,
    // signed for B.
    let any = key().for_controller(ControllerId::ANY);
    let mut sq = message(Command::Status, [0.0; 7]);
    sq[30] = IDENTITY_INDEX;
    let identity = Signature {
        link: 1,
        timestamp: NOW + 10,
    }
    .emit(&sq, &any);
    let mode = Signature {
        link: 1,
        timestamp: NOW + 11,
    }
    .emit(
        &message(Command::ChangeMode, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        &any,
    );
    let replies = exchange(&mut arm_b, &[&identity, &mode]);
    assert_eq!(replies.len(), 1, "CM for any controller is forged");
    let block = Signed::new_checked(replies[0].payload()).unwrap();
    assert!(Signature::parse(&block, &key().for_controller(a)).is_err());
    assert!(Signature::parse(&block, &key().for_controller(b)).is_ok());
    let reply = Reply::parse(&Message::new_checked(block.message()).unwrap()).unwrap();
    assert_eq!(IdentityReport::from_reply(&reply).unwrap().controller, b);
    assert_eq!(arm_b.signing().dropped_forged, 4);
    // Signed for B, the same sequence moves B.
    let for_b = key().for_controller(b);
    let sequence = move_sequence(1, NOW + 20).map(|d| {
        let block = Signed::new_checked(&d[..]).unwrap();
        let mut m = [0; MESSAGE_LEN];
        m.copy_from_slice(block.message());
        Signature {
            link: 1,
            timestamp: block.timestamp(),
        }
        .emit(&m, &for_b)
    });
    assert_eq!(run(&mut arm_b, &sequence), (3, true));
}

#[test]
fn a_day_old_sequence_on_an_unused_link_is_dropped_as_replayed() {
    let mut cycle = cycle(Some(UnsignedAccess::Refused));
    assert_eq!(
        exchange(&mut cycle, &[&signed(Command::Pose, [0.0; 7], 1, NOW)]).len(),
        1
    );
    assert_eq!(run(&mut cycle, &move_sequence(2, NOW - DAY)), (0, false));
    assert_eq!(cycle.signing().dropped_replayed, 3);
    // A minute behind is the limit for a link's first timestamp (a client's clock slightly
    // behind another's still works).
    let behind = NOW - armgate_core::cycle::FIRST_WINDOW;
    assert_eq!(run(&mut cycle, &move_sequence(3, behind)), (3, true));
}

/// A store shared with the test: what it keeps outlives the cycle (the file, the flash).
#[derive(Clone, Default)]
struct Kept(Rc<Cell<u64>>, Rc<Cell<u32>>);

impl ReplayStore for Kept {
    fn load(&mut self) -> u64 {
        self.0.get()
    }
    fn keep(&mut self, reserved: u64) -> bool {
        self.0.set(reserved);
        self.1.set(self.1.get() + 1);
        true
    }
}

#[test]
fn after_a_restart_with_the_kept_reservation_nothing_served_before_is_served_again() {
    let store = Kept::default();
    let start = |store: &Kept| {
        let config = robot("ranger-mk1");
        let arm = IdealArm::new(config.home());
        Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm)))
            .with_store(store.clone())
            .with_signing(Signing {
                key: Some(key()),
                unsigned: UnsignedAccess::Refused,
            })
    };
    let mut first = start(&store);
    let sequence = move_sequence(1, NOW);
    let mut client = Client::default();
    for d in &sequence {
        client.requests.push_back(Datagram::new(d, ()));
        first.tick(first.next_due_us(), &mut client);
    }
    assert_eq!(client.replies.len(), 3);
    assert!(first.handler().controller().is_moving());
    // Three requests within 2 s: one write.
    assert_eq!(store.1.get(), 1);
    drop(first);
    let mut second = start(&store);
    let mut client = Client::default();
    for d in &sequence {
        client.requests.push_back(Datagram::new(d, ()));
    }
    for _ in 0..10 {
        second.tick(second.next_due_us(), &mut client);
    }
    assert!(client.replies.is_empty());
    assert!(!second.handler().controller().is_moving());
    assert_eq!(second.signing().dropped_replayed, 3);
    // Nor on another link; a client whose clock has passed the reservation is served.
    let reserved = store.0.get();
    let mut client = Client::default();
    for d in move_sequence(2, NOW + 3)
        .iter()
        .chain(&move_sequence(3, reserved + 1))
    {
        client.requests.push_back(Datagram::new(d, ()));
    }
    for _ in 0..10 {
        second.tick(second.next_due_us(), &mut client);
    }
    assert_eq!(client.replies.len(), 3);
    assert!(second.handler().controller().is_moving());
}

#[test]
fn a_signed_stop_is_obeyed_and_answered_even_when_it_is_not_newer() {
    let mut cycle = cycle(Some(UnsignedAccess::Refused));
    assert_eq!(run(&mut cycle, &move_sequence(1, NOW)), (3, true));
    // Another operator on the same link, its clock 5 s behind: its ST is obeyed, answered.
    let stop = signed(Command::Stop, [0.0; 7], 1, NOW - 500_000);
    let replies = exchange(&mut cycle, &[&stop]);
    assert_eq!(verified(&replies[0], NOW - 500_000).command, Command::Stop);
    for _ in 0..200 {
        exchange(&mut cycle, &[]);
    }
    assert!(!cycle.handler().controller().is_moving());
    // A replayed stop only stops: the link's floor did not move, the sequence goes on.
    let replies = exchange(&mut cycle, &[&stop]);
    assert_eq!(verified(&replies[0], NOW).command, Command::Stop);
    assert_eq!(
        run(
            &mut cycle,
            &[signed(Command::JointBegin, [0.0; 7], 1, NOW + 3)]
        ),
        (1, true)
    );
    assert_eq!(cycle.signing().dropped_replayed, 0);
}

/// A network of several source addresses: requests in, everything sent out with its kind.
#[derive(Default)]
struct Net {
    requests: std::collections::VecDeque<Datagram<SocketAddr>>,
    sent: Vec<(Datagram<SocketAddr>, Outgoing)>,
}

impl Link<SocketAddr> for Net {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        self.requests.pop_front()
    }
    fn send(&mut self, datagram: &Datagram<SocketAddr>, kind: Outgoing) -> Result<(), Dropped> {
        self.sent.push((*datagram, kind));
        Ok(())
    }
}

#[test]
fn with_a_key_the_session_follows_the_link_id_and_each_answer_is_signed_for_its_recipient() {
    let config = robot("ranger-mk1");
    let arm = IdealArm::new(config.home());
    let mut cycle: Cycle<SimulatedDrives, SocketAddr> =
        Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm))).with_signing(Signing {
            key: Some(key()),
            unsigned: UnsignedAccess::Read,
        });
    let a: SocketAddr = "192.168.1.2:5000".parse().unwrap();
    let b: SocketAddr = "192.168.1.3:6000".parse().unwrap();
    let mut net = Net::default();
    let tick = |cycle: &mut Cycle<SimulatedDrives, SocketAddr>,
                net: &mut Net,
                from: &[(&[u8], SocketAddr)]| {
        for (bytes, peer) in from {
            net.requests.push_back(Datagram::new(bytes, *peer));
        }
        cycle.tick(cycle.next_due_us(), net);
    };
    // Link 1 from A takes the arm, with a 300 ms watchdog, and moves it.
    let goal = [1.7, 0.1, 1.5, 0.1, 1.2, 0.1, 0.0];
    let mut t = NOW;
    let mut next = |command, values| {
        t += 1;
        signed(command, values, 1, t)
    };
    let start = [
        next(Command::ChangeMode, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        next(Command::Watchdog, [300.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        next(Command::JointGoal, goal),
        next(Command::JointBegin, [0.0; 7]),
    ];
    for d in &start {
        tick(&mut cycle, &mut net, &[(d, a)]);
    }
    assert!(cycle.handler().controller().is_moving());
    // The same link from B (the client on a new port): the same client, the holder.
    let mut sq = message(Command::Status, [0.0; 7]);
    sq[30] = 3;
    let session = Signature {
        link: 1,
        timestamp: NOW + 10,
    }
    .emit(&sq, &key());
    net.sent.clear();
    tick(&mut cycle, &mut net, &[(&session, b)]);
    let (reply, _) = net.sent[0];
    assert_eq!((reply.peer, reply.payload().len()), (b, SIGNED_LEN));
    assert_eq!(verified(&reply, NOW + 10).values[0], 1.0, "holder: you");
    // An unsigned poller from A's very address, every tick: answered unsigned, another client
    // (the holder is someone else to it), and it does not feed link 1's watchdog.
    let ps = message(Command::Pose, [0.0; 7]);
    net.sent.clear();
    tick(&mut cycle, &mut net, &[(&sq, a)]);
    let (reply, _) = net.sent[0];
    assert_eq!(reply.payload().len(), MESSAGE_LEN);
    assert_eq!(
        Reply::parse(&Message::new_checked(reply.payload()).unwrap())
            .unwrap()
            .values[0],
        2.0
    );
    net.sent.clear();
    for _ in 0..40 {
        tick(&mut cycle, &mut net, &[(&ps, a)]);
    }
    assert!(
        !cycle.handler().controller().is_moving(),
        "the watchdog stopped the arm"
    );
    let notices: Vec<_> = net
        .sent
        .iter()
        .filter(|(_, k)| *k == Outgoing::Notice)
        .collect();
    assert!(!notices.is_empty());
    for (notice, _) in notices {
        // To link 1, where it was last heard from, signed; never to the unsigned poller.
        assert_eq!((notice.peer, notice.payload().len()), (b, SIGNED_LEN));
        let block = Signed::new_checked(notice.payload()).unwrap();
        assert!(Signature::parse(&block, &key()).is_ok());
    }
    assert!(
        net.sent
            .iter()
            .any(|(d, _)| d.payload().starts_with(b"ER41")
                || Signed::new_checked(d.payload())
                    .is_ok_and(|b| b.message().starts_with(b"ER41")))
    );
    // Two sources interleaved on link 1 are counted (SQ index 6).
    let identity = cycle.identity();
    assert_eq!(
        (identity.shared_links, identity.last_shared),
        (0, 0),
        "A, then B: a move"
    );
    let ps1 = Signature {
        link: 1,
        timestamp: NOW + 20,
    }
    .emit(&ps, &key());
    net.sent.clear();
    tick(&mut cycle, &mut net, &[(&ps1, a)]);
    assert_eq!(cycle.identity().last_shared, 1);
    // And said: WN14, to link 1 (where it was last heard from), signed.
    let shared = net
        .sent
        .iter()
        .find(|(_, k)| *k == Outgoing::Notice)
        .expect("a notice");
    assert_eq!(shared.0.peer, a);
    let block = Signed::new_checked(shared.0.payload()).unwrap();
    assert!(block.message().starts_with(b"WN14 link 1 shared"));
}
