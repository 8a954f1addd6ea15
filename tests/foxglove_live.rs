//! `armgate-sim --foxglove ADDR`: a WebSocket client speaking the Foxglove protocol connects,
//! sees the channels advertised, subscribes, and receives joint states at the tick rate and
//! the URDF and the body's scene (sent again to each new subscriber).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use std::net::{TcpListener, TcpStream, UdpSocket};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

const SUBPROTOCOL: &str = "foxglove.websocket.v1";
/// ranger-mk1's control period.
const PERIOD_NS: u64 = 19_440_000;

struct Sim(Child);

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_ports() -> (u16, u16) {
    let tcp = TcpListener::bind("127.0.0.1:0").unwrap();
    let udp = UdpSocket::bind("127.0.0.1:0").unwrap();
    (
        tcp.local_addr().unwrap().port(),
        udp.local_addr().unwrap().port(),
    )
}

fn start() -> (Sim, String) {
    let (ws, udp) = free_ports();
    let robot = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
    let child = Command::new(env!("CARGO_BIN_EXE_armgate-sim"))
        .args(["--quiet", "--robot", robot, "--duration", "30"])
        .args(["--listen", &format!("127.0.0.1:{udp}")])
        .args(["--foxglove", &format!("127.0.0.1:{ws}")])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    (Sim(child), format!("ws://127.0.0.1:{ws}"))
}

fn connect(
    url: &str,
    subprotocol: bool,
) -> tungstenite::Result<WebSocket<MaybeTlsStream<TcpStream>>> {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let mut request = url.into_client_request().unwrap();
        if subprotocol {
            request
                .headers_mut()
                .insert("Sec-WebSocket-Protocol", SUBPROTOCOL.parse().unwrap());
        }
        match tungstenite::connect(request) {
            Ok((socket, response)) => {
                let chosen = response.headers().get("Sec-WebSocket-Protocol").unwrap();
                assert_eq!(chosen, SUBPROTOCOL);
                return Ok(socket);
            }
            // Not listening yet.
            Err(tungstenite::Error::Io(_) | tungstenite::Error::Url(_))
                if Instant::now() < deadline =>
            {
                std::thread::sleep(Duration::from_millis(50));
            }
            Err(e) => return Err(e),
        }
    }
}

fn text(socket: &mut WebSocket<MaybeTlsStream<TcpStream>>) -> Value {
    match socket.read().unwrap() {
        Message::Text(text) => serde_json::from_str(&text).unwrap(),
        other => panic!("expected a JSON text, got {other:?}"),
    }
}

#[test]
fn a_viewer_subscribes_and_receives_joint_states() {
    let (_sim, url) = start();
    let mut socket = connect(&url, true).unwrap();
    let info = text(&mut socket);
    assert_eq!(info["op"], "serverInfo");
    assert_eq!(info["name"], "armgate-sim");
    let advertise = text(&mut socket);
    assert_eq!(advertise["op"], "advertise");
    let channels = advertise["channels"].as_array().unwrap();
    let find = |topic: &str| {
        channels
            .iter()
            .find(|c| c["topic"] == topic)
            .unwrap_or_else(|| panic!("{topic} not advertised"))
    };
    let joints = find("/joint_states");
    assert_eq!(joints["schemaName"], "foxglove.JointStates");
    assert_eq!(joints["encoding"], "json");
    let schema: Value = serde_json::from_str(joints["schema"].as_str().unwrap()).unwrap();
    assert_eq!(schema["title"], "foxglove.JointStates");
    let description = find("/robot_description");
    let body = find("/body");
    socket
        .send(Message::text(
            json!({"op": "subscribe", "subscriptions": [
                {"id": 7, "channelId": joints["id"]},
                {"id": 8, "channelId": description["id"]},
                {"id": 9, "channelId": body["id"]},
            ]})
            .to_string(),
        ))
        .unwrap();

    let mut times = Vec::new();
    let mut urdf = None;
    let mut scene = None;
    let deadline = Instant::now() + Duration::from_secs(20);
    while times.len() < 20 || urdf.is_none() || scene.is_none() {
        assert!(
            Instant::now() < deadline,
            "{} joint states, urdf {}, body {}",
            times.len(),
            urdf.is_some(),
            scene.is_some()
        );
        let Message::Binary(bytes) = socket.read().unwrap() else {
            continue;
        };
        assert_eq!(bytes[0], 1, "message data opcode");
        let subscription = u32::from_le_bytes(bytes[1..5].try_into().unwrap());
        let log_time = u64::from_le_bytes(bytes[5..13].try_into().unwrap());
        let payload: Value = serde_json::from_slice(&bytes[13..]).unwrap();
        match subscription {
            7 => {
                let names: Vec<&str> = payload["joints"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|j| j["name"].as_str().unwrap())
                    .collect();
                assert_eq!(
                    names,
                    [
                        "joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"
                    ]
                );
                times.push(log_time);
            }
            8 => {
                assert_eq!(payload["format"], "urdf");
                urdf = Some(payload);
            }
            // The body's last scene, sent again to a late subscriber: every link's capsules,
            // frame-locked, the nearest pair in a colour of its own.
            9 => {
                let entities = payload["entities"].as_array().unwrap();
                assert!(entities.iter().any(|e| e["frame_locked"] == true));
                let colours: std::collections::HashSet<String> = entities
                    .iter()
                    .filter_map(|e| e["spheres"].get(0))
                    .map(|s| s["color"].to_string())
                    .collect();
                assert!(colours.len() >= 2, "{payload}");
                scene = Some(payload);
            }
            other => panic!("subscription {other}"),
        }
    }
    // One message per tick, on the simulation's clock.
    for pair in times.windows(2) {
        assert_eq!((pair[1] - pair[0]) % PERIOD_NS, 0, "{times:?}");
        assert!(pair[1] > pair[0]);
    }

    // Unsubscribed: the joint states stop (what was in flight may still come).
    socket
        .send(Message::text(
            json!({"op": "unsubscribe", "subscriptionIds": [7]}).to_string(),
        ))
        .unwrap();
    let mut late = 0;
    let quiet_from = Instant::now() + Duration::from_millis(200);
    if let MaybeTlsStream::Plain(stream) = socket.get_ref() {
        stream
            .set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
    }
    while Instant::now() < quiet_from + Duration::from_millis(500) {
        match socket.read() {
            Ok(Message::Binary(_)) if Instant::now() > quiet_from => late += 1,
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => panic!("{e}"),
        }
    }
    assert_eq!(late, 0);
}

#[test]
fn a_client_without_the_foxglove_subprotocol_is_refused() {
    let (_sim, url) = start();
    // Wait until the server listens (a connection with the subprotocol works).
    drop(connect(&url, true).unwrap());
    match tungstenite::connect(url.as_str()) {
        Err(tungstenite::Error::Http(response)) => assert_eq!(response.status(), 400),
        other => panic!("expected a refusal, got {:?}", other.map(|_| ())),
    }
}
