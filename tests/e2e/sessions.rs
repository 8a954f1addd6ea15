//! Who is talking: one controlling client, notices to it, a stop from anyone, clients that leave
//! stopping what they started, and a network path that cannot wedge (spoofed sources, floods).

use super::*;

/// An address inside the firmware's default allow-list (its own /24) that nobody owns: nothing
/// answers the firmware's ARP requests for it.
const NOBODY: [u8; 4] = [192, 168, 1, 77];

/// Sends `payload` as a UDP datagram from `source` (forged) to `to`, through a raw IPv4 socket
/// (root inside the test's network namespace). The UDP checksum is left 0 (none, for IPv4); the
/// kernel fills in the IP header's checksum.
fn send_spoofed(source: std::net::SocketAddrV4, to: std::net::SocketAddrV4, payload: &[u8]) {
    use socket2::{Domain, Protocol, SockAddr, Socket, Type};
    const IPPROTO_RAW: i32 = 255;
    let raw = Socket::new(Domain::IPV4, Type::RAW, Some(Protocol::from(IPPROTO_RAW)))
        .expect("a raw socket (root in the namespace)");
    let total = 20 + 8 + payload.len();
    let mut packet = Vec::with_capacity(total);
    packet.extend_from_slice(&[
        0x45,
        0,
        (total >> 8) as u8,
        total as u8,
        0,
        0,
        0,
        0,
        64,
        17,
        0,
        0,
    ]);
    packet.extend_from_slice(&source.ip().octets());
    packet.extend_from_slice(&to.ip().octets());
    packet.extend_from_slice(&source.port().to_be_bytes());
    packet.extend_from_slice(&to.port().to_be_bytes());
    packet.extend_from_slice(&((8 + payload.len()) as u16).to_be_bytes());
    packet.extend_from_slice(&[0, 0]);
    packet.extend_from_slice(payload);
    raw.send_to(&packet, &SockAddr::from(SocketAddr::V4(to)))
        .unwrap();
}

/// A second client's own address (a source address other than the test's: the controller
/// shares its queue per source address): 127.0.0.2, or for the firmware 192.168.1.2, which
/// tools/firmware-e2e.sh adds to the namespace's TAP device.
fn second_client_address() -> SocketAddr {
    let ip: [u8; 4] = if firmware().is_some() {
        [192, 168, 1, 2]
    } else {
        [127, 0, 0, 2]
    };
    SocketAddr::from((ip, 0))
}

/// How many of `n` PS requests get their reply (each waited for up to the socket's timeout,
/// never resent).
fn answered_of(sim: &Sim, n: usize) -> usize {
    (0..n)
        .filter(|_| {
            sim.socket.send(&datagram("PS", [0.0; 7], 0)).unwrap();
            let mut buf = [0u8; 64];
            loop {
                match sim.socket.recv(&mut buf) {
                    Ok(_) => match decode(&buf) {
                        Answer::Reply(c, _, _) if &c == b"SP" => return true,
                        _ => continue,
                    },
                    Err(_) => return false,
                }
            }
        })
        .count()
}

#[test]
fn replies_to_a_source_nobody_owns_do_not_silence_the_controller() {
    if firmware().is_none() {
        // armgate-sim sends through the host's socket, which never waits on a neighbour, and a
        // forged source needs the firmware's namespace (root, a raw socket): here the nearest
        // case, replies to a client that has gone (its port closed: ICMP port unreachable).
        let sim = Sim::start("ranger-mk1");
        assert!(knows_status(&sim));
        let gone = UdpSocket::bind("127.0.0.77:0").unwrap();
        gone.connect(sim.socket.peer_addr().unwrap()).unwrap();
        for _ in 0..40 {
            gone.send(&datagram("PS", [0.0; 7], 0)).unwrap();
        }
        drop(gone);
        assert_eq!(answered_of(&sim, 40), 40, "after a client that left");
        return;
    }
    let sim = Sim::start("ranger-mk1");
    assert!(knows_status(&sim));
    assert_eq!(answered_of(&sim, 4), 4, "before the forged datagrams");
    let std::net::SocketAddr::V4(to) = sim.socket.peer_addr().unwrap() else {
        panic!("the firmware listens on IPv4");
    };
    let forged = std::net::SocketAddrV4::new(NOBODY.into(), 40_000);
    for _ in 0..40 {
        send_spoofed(forged, to, &datagram("PS", [0.0; 7], 0));
    }
    // Every request of the real client is answered, at once (no resend), for longer than the
    // neighbour cache's retry interval (1 s) several times over.
    let started = Instant::now();
    let answered = answered_of(&sim, 40);
    eprintln!(
        "after 40 PS from {forged}: {answered} of 40 PS answered in {:.1} s",
        started.elapsed().as_secs_f32()
    );
    assert_eq!(answered, 40);
    // And again while the forged source keeps sending.
    for _ in 0..40 {
        send_spoofed(forged, to, &datagram("ST", [0.0; 7], 0));
        assert_eq!(answered_of(&sim, 1), 1);
    }
}

/// A start where ranger-mk1 can move its first joint a long way (as in the full session).
pub(super) const START: &str = "1.5708,0.6,-0.4,0.2,1.8,0.1";

/// ranger-mk1 from [`START`] in joint mode, `before_move` done, then moving its first joint by
/// `by` rad (the move accepted); the goal's joints.
fn moving(by: f32, before_move: impl FnOnce(&Sim)) -> (Sim, [f32; 7]) {
    let sim = Sim::start_with("ranger-mk1", &["--start", START]);
    assert!(knows_status(&sim));
    assert_eq!(sim.ok("CM", [1.0, 0., 0., 0., 0., 0., 0.], 0)[0], 1.0);
    before_move(&sim);
    let mut goal = sim.ok("jP", [0.0; 7], 0);
    goal[0] += by;
    goal[6] = 0.0;
    sim.ok("jG", goal, 0);
    sim.start_motion("jB");
    (sim, goal)
}

#[test]
fn a_stop_gets_through_while_another_client_floods() {
    let period = 0.01944;
    // A long joint move (half a radian on the first joint).
    let (sim, goal) = moving(0.5, |_| {});
    assert_eq!(status(&sim)[4], 1.0, "a joint move");

    // Another allowed client floods PS, never reading its replies: 10,000 at about 2,000 a
    // second, five times what the controller handles (8 a tick) and less than the TAP queue
    // drops when the firmware runs on Linux (that loss, before the controller, would hit the
    // stop as much as the flood).
    let flooder = UdpSocket::bind(second_client_address()).unwrap();
    flooder.connect(sim.socket.peer_addr().unwrap()).unwrap();
    let progress = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let flood = std::thread::spawn({
        let progress = progress.clone();
        move || {
            let ps = datagram("PS", [0.0; 7], 0);
            (0..10_000)
                .filter(|k| {
                    progress.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    if k % 20 == 19 {
                        std::thread::sleep(Duration::from_millis(10));
                    }
                    flooder.send(&ps).is_ok()
                })
                .count()
        }
    });
    while progress.load(std::sync::atomic::Ordering::Relaxed) < 2_000 {
        std::thread::yield_now();
    }
    // The controlling client's ST, resent every 200 ms as the armgate client does (a datagram
    // can be lost before it reaches the controller: a full TAP queue, a full receive ring):
    // answered, and in force at the next request.
    let sent = Instant::now();
    let sends = stop_resending(&sim);
    let answered = sent.elapsed().as_secs_f64();
    let s = status(&sim);
    let flood_running = !flood.is_finished();
    eprintln!(
        "ST answered in {:.1} ms ({:.1} periods, {sends} sent) while another client flooded PS \
         (flood still sending: {flood_running}); then SQ motion {}",
        answered * 1e3,
        answered / period,
        s[4]
    );
    assert_eq!(sends, 1, "the first ST was not answered within 200 ms");
    assert_ne!(s[4], 1.0, "the joint move was not stopped");
    let sent = flood.join().unwrap();
    eprintln!("flood: {sent} PS sent");
    assert_eq!(sent, 10_000);
    // The arm comes to rest (the drives play out the points they hold), and stays there.
    std::thread::sleep(Duration::from_millis(300));
    let a = sim.ok("jP", [0.0; 7], 0);
    std::thread::sleep(Duration::from_millis(300));
    let b = sim.ok("jP", [0.0; 7], 0);
    assert!((a[0] - b[0]).abs() < 1e-4, "{a:?} -> {b:?}");
    assert!(
        (b[0] - goal[0]).abs() > 0.1,
        "the move ran to its end: {b:?}"
    );
}

/// How many source addresses flood at once in
/// [`a_flood_from_many_addresses_silences_neither_the_holder_nor_a_stop`].
const FLOOD_SOURCES: u8 = 32;

/// A flood from [`FLOOD_SOURCES`] addresses, one datagram from each in turn, `rounds` times:
/// `PS`, and every fourth round `CM 2` (a command from a client that does not hold the arm),
/// about 2,000 a second. From 127.0.1.k on loopback (a socket bound to each), or for the
/// firmware from 192.168.1.(100 + k), forged through a raw socket in its namespace (nobody owns
/// them: their replies do not resolve). Returns the datagrams sent and, on loopback, the
/// flood's sockets (their replies are still in them).
fn flood_from_many(
    to: SocketAddr,
    rounds: usize,
    progress: &std::sync::atomic::AtomicUsize,
) -> (usize, Vec<UdpSocket>) {
    let sockets: Vec<UdpSocket> = if firmware().is_some() {
        Vec::new()
    } else {
        (1..=FLOOD_SOURCES)
            .map(|k| {
                let socket = UdpSocket::bind(SocketAddr::from(([127, 0, 1, k], 0))).unwrap();
                socket.connect(to).unwrap();
                socket
            })
            .collect()
    };
    let mut sent = 0;
    for round in 0..rounds {
        let request = if round % 4 == 3 {
            datagram("CM", [2.0, 0., 0., 0., 0., 0., 0.], 0)
        } else {
            datagram("PS", [0.0; 7], 0)
        };
        for k in 1..=FLOOD_SOURCES {
            match (&to, sockets.get(usize::from(k) - 1)) {
                (_, Some(socket)) => {
                    if socket.send(&request).is_ok() {
                        sent += 1;
                    }
                }
                (SocketAddr::V4(to), None) => {
                    let forged = std::net::SocketAddrV4::new([192, 168, 1, 100 + k].into(), 40_000);
                    send_spoofed(forged, *to, &request);
                    sent += 1;
                }
                (SocketAddr::V6(_), None) => panic!("the firmware listens on IPv4"),
            }
            let n = progress.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n.is_multiple_of(20) {
                std::thread::sleep(Duration::from_millis(10));
            }
        }
    }
    (sent, sockets)
}

#[test]
fn a_flood_from_many_addresses_silences_neither_the_holder_nor_a_stop() {
    // A holds the arm in a long joint move (a radian on the first joint, about 15 s).
    let (sim, goal) = moving(1.0, |_| {});
    let to = sim.socket.peer_addr().unwrap();
    // 9,600 datagrams, about 5 s: past the point where armgate-sim's inbox is full (4,096
    // waiting, 8 served a tick) before A asks anything.
    let rounds = 300;
    let progress = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let flood = std::thread::spawn({
        let progress = progress.clone();
        move || flood_from_many(to, rounds, &progress)
    });
    let total = rounds * usize::from(FLOOD_SOURCES);
    let under_way = |share: usize| {
        while progress.load(std::sync::atomic::Ordering::Relaxed) < total * share / 8 {
            std::thread::yield_now();
        }
    };
    under_way(5);
    // While it lasts, A's reads and commands are answered (resent every 200 ms as the armgate
    // client does) and A still holds the arm.
    let mut holder_sends = Vec::new();
    for _ in 0..4 {
        let (session, sends) = ask_resending(&sim.socket, "SQ", [0.0; 7], 3);
        assert_eq!(session[0], 1.0, "A no longer holds the arm: {session:?}");
        holder_sends.push(sends);
        let (watchdog, sends) = ask_resending(&sim.socket, "WD", [0.0; 7], 0);
        assert_eq!(watchdog[0], 0.0);
        holder_sends.push(sends);
    }
    let (status_now, sends) = ask_resending(&sim.socket, "SQ", [0.0; 7], 0);
    holder_sends.push(sends);
    assert_eq!(status_now[0], 1.0, "a flooding non-holder changed the mode");
    assert_eq!(status_now[4], 1.0, "the joint move runs on");
    // A third client's ST stops the arm, still during the flood.
    under_way(6);
    let c = second_client(&sim);
    let (_, stop_sends) = ask_resending(&c, "ST", [0.0; 7], 0);
    let flood_running = !flood.is_finished();
    let (cause, _) = ask_resending(&sim.socket, "SQ", [0.0; 7], 2);
    let (status_then, _) = ask_resending(&sim.socket, "SQ", [0.0; 7], 0);
    let (sent, flood_sockets) = flood.join().unwrap();
    // (By now the arm may be at rest, and a CM of the flood's may have taken control.)
    let (session, _) = ask_resending(&sim.socket, "SQ", [0.0; 7], 3);
    // What the flood got back (loopback): its CM refused while the arm moved; once the arm is
    // at rest, a CM still waiting takes control, as any client's may.
    let mut answers = std::collections::BTreeMap::<String, usize>::new();
    for socket in &flood_sockets {
        socket.set_nonblocking(true).unwrap();
        let mut buf = [0u8; 64];
        while socket.recv(&mut buf).is_ok() {
            let key = match decode(&buf) {
                Answer::Reply(c, ..) => String::from_utf8_lossy(&c).into_owned(),
                Answer::Text(t) => t.split(' ').take(2).collect::<Vec<_>>().join(" "),
            };
            *answers.entry(key).or_default() += 1;
        }
    }
    eprintln!(
        "flood from {FLOOD_SOURCES} addresses: {sent} datagrams sent (PS, every fourth round CM 2); \
         the flood got back {answers:?}; A's {} requests answered after {holder_sends:?} sends; \
         C's ST answered after {stop_sends} send(s), flood still sending: {flood_running}; \
         SQ 2 cause {}, SQ f4 {}; SQ 3: holder {}, send drops {}, clients {}",
        holder_sends.len(),
        cause[0],
        status_then[4],
        session[0],
        session[5],
        session[6],
    );
    assert_eq!(sent, total);
    if firmware().is_none() {
        assert!(
            answers.get("ER40 Cmd").is_some_and(|n| *n > 0),
            "{answers:?}"
        );
    }
    assert_eq!(cause[0], 1.0, "stopped by ST");
    assert_ne!(status_then[4], 1.0, "the joint move was not stopped");
    // The arm comes to rest short of the goal (resent requests may leave late replies behind:
    // each is matched by its characters and index).
    let started = Instant::now();
    while ask_resending(&sim.socket, "SQ", [0.0; 7], 0).0[4] != 0.0 {
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "the arm came to rest"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let (rest, _) = ask_resending(&sim.socket, "jP", [0.0; 7], 0);
    assert!(
        (rest[0] - goal[0]).abs() > 0.1,
        "the move ran to its end: {rest:?}"
    );
    let mut sim = sim;
    if firmware().is_none() {
        let kill = Command::new("kill")
            .args(["-TERM", &sim.child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        sim.child.wait().unwrap();
        eprintln!("armgate-sim: {}", sim.stderr_rest().trim());
    }
}

/// Sends ST every 200 ms until its reply comes (at most 10 times); how many were sent.
fn stop_resending(sim: &Sim) -> usize {
    ask_resending(&sim.socket, "ST", [0.0; 7], 0).1
}

/// Sends a request on `socket` every 200 ms, as the armgate client does, until its reply
/// (the command reversed) comes, at most 10 times: the reply's values and how many were sent.
fn ask_resending(socket: &UdpSocket, cmd: &str, values: [f32; 7], index: u8) -> ([f32; 7], usize) {
    let reversed = [cmd.as_bytes()[1], cmd.as_bytes()[0]];
    let timeout = socket.read_timeout().unwrap();
    socket
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let mut reply = None;
    let sends = (1..=10)
        .find(|_| {
            socket.send(&datagram(cmd, values, index)).unwrap();
            let mut buf = [0u8; 64];
            while socket.recv(&mut buf).is_ok() {
                if let Answer::Reply(c, v, i) = decode(&buf)
                    && c == reversed
                    && i == index
                {
                    reply = Some(v);
                    return true;
                }
            }
            false
        })
        .unwrap_or_else(|| panic!("{cmd} {index} never answered in 10 sends"));
    socket.set_read_timeout(timeout).unwrap();
    (reply.unwrap(), sends)
}

/// A second client, from [`second_client_address`], talking to the same controller.
pub(super) fn second_client(sim: &Sim) -> UdpSocket {
    let socket = UdpSocket::bind(second_client_address()).unwrap();
    socket.connect(sim.socket.peer_addr().unwrap()).unwrap();
    socket
        .set_read_timeout(sim.socket.read_timeout().unwrap())
        .unwrap();
    socket
}

/// Sends a request on `socket` and returns the next answer that is not an unsolicited notice.
pub(super) fn ask(socket: &UdpSocket, cmd: &str, values: [f32; 7], index: u8) -> Answer {
    socket.send(&datagram(cmd, values, index)).unwrap();
    loop {
        let mut buf = [0u8; 64];
        let n = socket.recv(&mut buf).expect("no reply");
        assert_eq!(n, 31);
        match decode(&buf) {
            Answer::Text(t) if is_unsolicited(&t) => continue,
            answer => return answer,
        }
    }
}

/// `SQ` index 3: holder (0 nobody, 1 you, 2 another), its IPv4 address in two 16-bit halves,
/// its port, the watchdog (ms), send drops, clients.
fn session(socket: &UdpSocket) -> [f32; 7] {
    match ask(socket, "SQ", [0.0; 7], 3) {
        Answer::Reply(chars, v, 3) if &chars == b"QS" => v,
        other => panic!("SQ 3: {other:?}"),
    }
}

#[test]
fn one_client_commands_the_moving_arm_and_any_client_stops_it() {
    // A long joint move by A: A holds the arm.
    let (sim, _) = moving(0.5, |_| {});
    let b = second_client(&sim);
    let a_ip = match sim.socket.local_addr().unwrap().ip() {
        std::net::IpAddr::V4(ip) if !ip.is_unspecified() => ip,
        _ if firmware().is_some() => std::net::Ipv4Addr::new(192, 168, 1, 1),
        _ => std::net::Ipv4Addr::LOCALHOST,
    };
    let held = |cmd: &str| format!("ER40 Cmd {cmd} by {a_ip}");
    let [high, low] = [
        (u32::from(a_ip) >> 16) as f32,
        (u32::from(a_ip) & 0xffff) as f32,
    ];
    let mine = session(&sim.socket);
    assert_eq!(mine[..3], [1.0, high, low], "{mine:?}");
    let port = f32::from(sim.socket.local_addr().unwrap().port());
    assert_eq!(mine[3], port);
    // B may read, but not command, while the arm moves.
    assert!(matches!(ask(&b, "PS", [0.0; 7], 0), Answer::Reply(c, ..) if &c == b"SP"));
    for cmd in ["CM", "jG", "jB", "OF", "RC", "GT"] {
        assert_eq!(
            ask(&b, cmd, [1.0, 0., 0., 0., 0., 0., 0.], 0),
            Answer::Text(held(cmd)),
            "{cmd} from the second client"
        );
    }
    let theirs = session(&b);
    assert_eq!(theirs[..4], [2.0, high, low, port], "{theirs:?}");
    assert_eq!(status(&sim)[4], 1.0, "A's move runs on");
    // A datagram that does not parse, from B, changes nothing (and is answered).
    assert!(matches!(ask(&b, "XY", [0.0; 7], 0), Answer::Text(t) if t.starts_with("ER00")));
    // B's ST is obeyed at once; A still holds the arm.
    assert!(matches!(ask(&b, "ST", [0.0; 7], 0), Answer::Reply(c, ..) if &c == b"TS"));
    assert_ne!(status(&sim)[4], 1.0, "the move was stopped");
    assert_eq!(session(&sim.socket)[0], 1.0);
    // The arm decelerates (SQ f4 = 6) and then holds (0).
    let start = Instant::now();
    while status(&sim)[4] != 0.0 {
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "the arm came to rest"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // At rest, B takes control with its next command request.
    match ask(&b, "CM", [2.0, 0., 0., 0., 0., 0., 0.], 0) {
        Answer::Reply(c, v, 0) if &c == b"MC" => assert_eq!(v[0], 2.0),
        other => panic!("CM from the second client at rest: {other:?}"),
    }
    assert_eq!(session(&b)[0], 1.0);
    assert_eq!(session(&sim.socket)[0], 2.0);
}

#[test]
fn a_begin_whose_reply_was_lost_is_answered_again_not_refused_busy() {
    // jB until the drives take it; its reply is "lost" (read and ignored), and the client
    // resends the same datagram 200 ms later.
    let (sim, goal) = moving(0.3, |_| {});
    std::thread::sleep(Duration::from_millis(200));
    match sim.request("jB", [0.0; 7], 0) {
        // The first reply again: f6 the move's planned duration (0.3 rad at 0.07 rad/s and more).
        Answer::Reply(c, v, 0) if &c == b"Bj" => {
            assert_eq!(v[..6], [0.0; 6]);
            assert!((0.3 / 0.07..60.0).contains(&v[6]), "{v:?}");
        }
        other => panic!("the resent jB: {other:?}"),
    }
    // Carried out once: the move runs on to its goal (not restarted, not refused).
    assert_eq!(status(&sim)[4], 1.0);
    sim.wait_joints(&goal[..6], 20.0);
}

#[test]
fn a_silent_client_with_a_watchdog_has_its_motion_stopped() {
    let (sim, _) = moving(0.5, |sim| {
        // Out of range: refused; 300 ms: in force, SQ 3 f4 reports it.
        assert_eq!(
            sim.text("WD", [-1.0, 0., 0., 0., 0., 0., 0.], 0),
            "ER23 Cmd WD bad number"
        );
        assert_eq!(sim.ok("WD", [300.0, 0., 0., 0., 0., 0., 0.], 0)[0], 300.0);
        assert_eq!(session(&sim.socket)[4], 300.0);
    });
    // Polling feeds it: the move runs on.
    for _ in 0..8 {
        std::thread::sleep(Duration::from_millis(100));
        assert_eq!(status(&sim)[4], 1.0);
    }
    // Silent (another client's polls do not count): the arm is stopped, with the notice.
    let b = second_client(&sim);
    let silent_from = Instant::now();
    while silent_from.elapsed() < Duration::from_millis(700) {
        assert!(matches!(ask(&b, "PS", [0.0; 7], 0), Answer::Reply(..)));
        std::thread::sleep(Duration::from_millis(50));
    }
    let mut notice = None;
    let mut buf = [0u8; 64];
    while let Ok(n) = sim.socket.recv(&mut buf) {
        assert_eq!(n, 31);
        if let Answer::Text(t) = decode(&buf) {
            notice = Some(t);
            break;
        }
    }
    assert_eq!(notice.as_deref(), Some("ER41 client silent 300 ms"));
    assert_ne!(status(&sim)[4], 1.0, "the move was stopped");
}

/// ranger-mk1 from `start` (joint angles) in mode `mode` (1 joint, 2 Cartesian), the drives
/// running.
pub(super) fn ready(start: &str, mode: f32) -> Sim {
    let sim = Sim::start_with("ranger-mk1", &["--start", start]);
    assert!(knows_status(&sim));
    assert_eq!(sim.ok("CM", [mode, 0., 0., 0., 0., 0., 0.], 0)[0], mode);
    wait_drives(&sim, 2.0);
    sim
}

#[test]
fn a_cli_move_that_outlasts_its_wait_is_stopped_and_the_next_client_takes_control() {
    // `armgate jmove` of 0.3 rad on the first joint (about 5 s at 0.07 rad/s), waiting 500 ms.
    let sim = ready(START, 1.0);
    let mut goal = sim.ok("jP", [0.0; 7], 0);
    goal[0] += 0.3;
    let q: Vec<String> = goal[..6].iter().map(f32::to_string).collect();
    let mut args = vec!["jmove"];
    args.extend(q.iter().map(String::as_str));
    args.extend(["--wait-timeout", "500ms"]);
    let (result, out) = armgate(&sim, &args);
    assert_eq!(out, "moving\n");
    let err = result.unwrap_err();
    let message = err.to_string();
    assert_eq!(
        err.exit_code(),
        armgate_client::exit::NOT_ARRIVED,
        "{message}"
    );
    assert!(
        message.starts_with("target 1 not reached within 500ms")
            && message.ends_with("; sent ST: the arm stops and holds"),
        "{message}"
    );
    // Stopped at once (no longer a joint move), and soon at rest, well short of the goal.
    assert_ne!(status(&sim)[4], 1.0, "the move runs on");
    assert!(poll_status(&sim, Duration::from_secs(3), |s| s[4] == 0.0));
    let rest = sim.ok("jP", [0.0; 7], 0);
    assert!(goal[0] - rest[0] > 0.2, "{rest:?} (goal {goal:?})");
    // Another client takes control with its next request.
    let b = second_client(&sim);
    match ask(&b, "CM", [2.0, 0., 0., 0., 0., 0., 0.], 0) {
        Answer::Reply(c, v, 0) if &c == b"MC" => assert_eq!(v[0], 2.0),
        other => panic!("CM from the next client: {other:?}"),
    }
    assert_eq!(session(&b)[0], 1.0);
}

/// Every ER/WN text among the datagrams waiting on `socket` (read until none comes within
/// 20 ms); the rest are replies.
fn texts_waiting(socket: &UdpSocket) -> Vec<String> {
    let timeout = socket.read_timeout().unwrap();
    socket
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let mut texts = Vec::new();
    let mut buf = [0u8; 64];
    while let Ok(n) = socket.recv(&mut buf) {
        assert_eq!(n, 31);
        if let Answer::Text(t) = decode(&buf) {
            texts.push(t);
        }
    }
    socket.set_read_timeout(timeout).unwrap();
    texts
}

#[test]
fn notices_of_a_motion_go_to_the_client_that_holds_the_arm_not_to_a_poller() {
    // Joint 6 52 mrad short of its 3.142 limit; A streams it towards the limit at 0.1 rad/s
    // (a jW every 20 ms for 1.2 s) while B polls PS and SQ as often: the stream reaches the
    // limit after about 0.5 s and is held there with `WN12 j6 at limit 3.142`.
    let sim = ready("1.5708,0.6,-0.4,0.2,1.8,3.09", 1.0);
    let b = second_client(&sim);
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let poller = std::thread::spawn({
        let stop = stop.clone();
        move || {
            let mut texts = Vec::new();
            let mut polls = 0;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                for cmd in ["PS", "SQ"] {
                    b.send(&datagram(cmd, [0.0; 7], 0)).unwrap();
                    texts.extend(texts_waiting(&b));
                    polls += 1;
                }
            }
            (texts, polls)
        }
    });
    let rate = [0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.0];
    let started = Instant::now();
    let mut notices = Vec::new();
    while started.elapsed() < Duration::from_millis(1200) {
        sim.socket.send(&datagram("jW", rate, 0)).unwrap();
        notices.extend(texts_waiting(&sim.socket));
    }
    // The stream ends; the arm ramps to rest.
    std::thread::sleep(Duration::from_millis(500));
    notices.extend(texts_waiting(&sim.socket));
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let (theirs, polls) = poller.join().unwrap();
    eprintln!("A got {notices:?}; B got {theirs:?} in {polls} polls");
    assert!(
        notices.iter().any(|t| t == "WN12 j6 at limit 3.142"),
        "{notices:?}"
    );
    assert!(polls > 20, "{polls}");
    assert_eq!(theirs, Vec::<String>::new(), "notices sent to the poller");
}

/// A UDP relay between one client (on loopback) and the controller that drops the first
/// answer whose characters are `lost`; it runs until `stop` is set and returns the commands
/// it passed on, in order.
fn relay_losing_first(
    sim: &Sim,
    lost: [u8; 2],
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> (SocketAddr, std::thread::JoinHandle<Vec<String>>) {
    let front = UdpSocket::bind("127.0.0.1:0").unwrap();
    let back = UdpSocket::bind((sim.socket.local_addr().unwrap().ip(), 0)).unwrap();
    back.connect(sim.socket.peer_addr().unwrap()).unwrap();
    for socket in [&front, &back] {
        socket
            .set_read_timeout(Some(Duration::from_millis(2)))
            .unwrap();
    }
    let addr = front.local_addr().unwrap();
    let relay = std::thread::spawn(move || {
        let mut client = None;
        let mut dropped = false;
        let mut passed = Vec::new();
        let mut buf = [0u8; 64];
        while !stop.load(std::sync::atomic::Ordering::Relaxed) {
            if let Ok((n, from)) = front.recv_from(&mut buf) {
                client = Some(from);
                passed.push(String::from_utf8_lossy(&buf[..2]).into_owned());
                back.send(&buf[..n]).unwrap();
            }
            if let (Ok(n), Some(client)) = (back.recv(&mut buf), client) {
                if !dropped && buf[..2] == lost {
                    dropped = true;
                    continue;
                }
                front.send_to(&buf[..n], client).unwrap();
            }
        }
        passed
    });
    (addr, relay)
}

#[test]
fn armgate_move_whose_begin_reply_is_lost_gets_it_again_and_arrives() {
    // ranger-mk1 from a well-conditioned pose, in Cartesian mode: `armgate move` by 3 cm in z,
    // through a relay that loses the first reply to BG.
    let sim = ready("1.5708,0.8,0.5,0.5,1.5,0.5", 2.0);
    let ps = sim.ok("PS", [0.0; 7], 0);
    let [roll, pitch, yaw] = rpy_of(&ps[3..]);
    let goal = [ps[0], ps[1], ps[2] + 0.03, roll, pitch, yaw].map(|v| v.to_string());
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (addr, relay) = relay_losing_first(&sim, *b"GB", stop.clone());
    let mut args = vec!["move"];
    args.extend(goal.iter().map(String::as_str));
    args.extend(["--timeout", "300ms"]);
    let (result, out) = armgate_at(addr, &args);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let passed = relay.join().unwrap();
    let begins = passed.iter().filter(|c| *c == "BG").count();
    eprintln!("{out}; the client sent {passed:?}");
    // The resend got the reply again (not `ER20 Cmd BG busy`), and the move arrived.
    result.unwrap();
    assert!(out.starts_with("moving\narrived: "), "{out}");
    assert_eq!(begins, 2, "{passed:?}");
    assert!(!passed.iter().any(|c| c == "ST"), "{passed:?}");
    let now = sim.ok("PS", [0.0; 7], 0);
    assert!((now[2] - ps[2] - 0.03).abs() < 0.002, "{now:?}");
}

#[test]
fn a_cli_move_another_client_stops_says_who_stopped_it_and_exits_3() {
    // `armgate jmove` of 0.3 rad on the first joint (about 5 s); client B sends ST after 1 s.
    let sim = ready(START, 1.0);
    let mut goal = sim.ok("jP", [0.0; 7], 0);
    goal[0] += 0.3;
    let q: Vec<String> = goal[..6].iter().map(f32::to_string).collect();
    let addr = sim.socket.peer_addr().unwrap();
    let mover = std::thread::spawn(move || {
        let mut args = vec!["jmove"];
        args.extend(q.iter().map(String::as_str));
        let (result, _) = armgate_at(addr, &args);
        result.unwrap_err()
    });
    assert!(poll_status(&sim, Duration::from_secs(3), |s| s[4] == 1.0));
    std::thread::sleep(Duration::from_secs(1));
    let b = second_client(&sim);
    assert!(matches!(ask(&b, "ST", [0.0; 7], 0), Answer::Reply(c, ..) if &c == b"TS"));
    let err = mover.join().unwrap();
    let message = err.to_string();
    assert_eq!(err.exit_code(), armgate_client::exit::STOPPED, "{message}");
    let by = b.local_addr().unwrap();
    assert_eq!(
        message,
        format!("the motion was stopped by client {by}: ST (target 1 not reached)")
    );
    // Short of the goal, at rest: the CLI did not send an ST of its own (the cause is B's).
    let rest = sim.ok("jP", [0.0; 7], 0);
    assert!(goal[0] - rest[0] > 0.1, "{rest:?} (goal {goal:?})");
    let SocketAddr::V4(v4) = by else {
        panic!("{by}")
    };
    let ip = u32::from(*v4.ip());
    let halves = [(ip >> 16) as f32, (ip & 0xffff) as f32];
    assert_eq!(
        stop_cause_of(&b)[..5],
        [1.0, 0.0, halves[0], halves[1], f32::from(by.port())]
    );
    // `armgate status` shows the cause with who set it, the holder (the mover) with its port,
    // the clients and the watchdog.
    let (result, shown) = armgate(&sim, &["status"]);
    result.unwrap();
    assert!(
        shown.contains(&format!("stopped by ST from {by}\n")),
        "{shown}"
    );
    let holder = shown
        .lines()
        .find_map(|l| l.strip_prefix("holder     "))
        .unwrap_or_else(|| panic!("{shown}"));
    assert!(holder.parse::<SocketAddr>().is_ok(), "{shown}");
    assert!(shown.contains("watchdog   off\n"), "{shown}");
}

/// `SQ` index 2 from `socket`: the stop cause, the joint, who set it.
fn stop_cause_of(socket: &UdpSocket) -> [f32; 7] {
    match ask(socket, "SQ", [0.0; 7], 2) {
        Answer::Reply(chars, v, 2) if &chars == b"QS" => v,
        other => panic!("SQ 2: {other:?}"),
    }
}
