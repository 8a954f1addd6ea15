//! The live view: the recorder's messages served over the Foxglove WebSocket protocol
//! (subprotocol `foxglove.websocket.v1`), so that Foxglove's "Open connection" shows the arm
//! as it moves. Read-only: the server advertises no client publishing or services, so a viewer
//! can never command the arm.
//!
//! One thread accepts connections; each viewer has a thread and a bounded queue of its own, so
//! a slow viewer loses messages (counted) but never slows the recorder, let alone the control
//! loop. The URDF, the workspace and the body's last scene are sent again to every new
//! subscriber (they are sent at the start, before a viewer may be there, or rarely).

use std::collections::HashMap;
use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use serde_json::{Value, json};
use tungstenite::handshake::server::{ErrorResponse, Request, Response};
use tungstenite::http::HeaderValue;
use tungstenite::{Message as Frame, WebSocket};

use crate::foxglove::Topic;
use crate::recorder::Sink;
use crate::translate::Message;

/// The WebSocket subprotocol of the Foxglove protocol.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";

/// Messages waiting for one viewer at most.
const VIEWER_QUEUE: usize = 4096;

/// How long a viewer's thread waits for the viewer before sending what is queued.
const POLL: Duration = Duration::from_millis(5);

/// The channel id of a topic (1.., in [`Topic::ALL`] order).
pub fn channel_id(topic: Topic) -> u32 {
    Topic::ALL
        .iter()
        .position(|t| *t == topic)
        .map_or(0, |i| u32::try_from(i + 1).unwrap_or(0))
}

/// Topics whose last message is sent again to each new subscriber (each holds its whole
/// picture: the URDF, the workspace, the body).
fn latched(topic: Topic) -> bool {
    matches!(
        topic,
        Topic::RobotDescription | Topic::Workspace | Topic::Body
    )
}

/// One connected viewer, as the sink sees it.
struct Viewer {
    queue: SyncSender<Arc<Message>>,
    /// channel id → subscription id.
    subscriptions: Arc<Mutex<HashMap<u32, u32>>>,
}

#[derive(Default)]
struct Shared {
    viewers: Mutex<Vec<Viewer>>,
    latched: Mutex<Vec<Arc<Message>>>,
    dropped: AtomicU64,
}

/// The server, as a recorder's sink.
pub struct LiveServer {
    shared: Arc<Shared>,
    local: SocketAddr,
}

impl LiveServer {
    /// Listens on `addr` and accepts viewers from now on; `name` is the server's name they see.
    pub fn bind(addr: SocketAddr, name: &str) -> io::Result<Self> {
        let listener = TcpListener::bind(addr)?;
        let local = listener.local_addr()?;
        let shared = Arc::new(Shared::default());
        let accepting = shared.clone();
        let name = name.to_owned();
        std::thread::Builder::new()
            .name("foxglove-accept".into())
            .spawn(move || {
                for stream in listener.incoming().flatten() {
                    let shared = accepting.clone();
                    let name = name.clone();
                    // A viewer that fails its handshake or goes away ends only its own thread.
                    let _ = std::thread::Builder::new()
                        .name("foxglove-viewer".into())
                        .spawn(move || serve(stream, &shared, &name));
                }
            })?;
        Ok(Self { shared, local })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// Messages not sent because a viewer's queue was full.
    pub fn dropped(&self) -> u64 {
        self.shared.dropped.load(Ordering::Relaxed)
    }
}

impl Sink for LiveServer {
    fn write(&mut self, message: &Message) -> io::Result<()> {
        let message = Arc::new(message.clone());
        if latched(message.topic) {
            let mut latched = self
                .shared
                .latched
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            latched.retain(|m| m.topic != message.topic);
            latched.push(message.clone());
        }
        let channel = channel_id(message.topic);
        let mut viewers = self
            .shared
            .viewers
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        viewers.retain(|viewer| {
            let subscribed = viewer
                .subscriptions
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .contains_key(&channel);
            if !subscribed {
                return true;
            }
            match viewer.queue.try_send(message.clone()) {
                Ok(()) => true,
                Err(TrySendError::Full(_)) => {
                    self.shared.dropped.fetch_add(1, Ordering::Relaxed);
                    true
                }
                // The viewer's thread has ended: forget it.
                Err(TrySendError::Disconnected(_)) => false,
            }
        });
        Ok(())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }

    fn finish(&mut self) -> io::Result<()> {
        // Dropping the queues ends every viewer's thread.
        self.shared
            .viewers
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clear();
        Ok(())
    }
}

/// The handshake answer: the Foxglove subprotocol, or a refusal if the viewer does not offer it.
// The signature is tungstenite's callback's.
#[allow(clippy::result_large_err)]
fn choose_subprotocol(
    request: &Request,
    mut response: Response,
) -> Result<Response, ErrorResponse> {
    let offered = request
        .headers()
        .get_all("Sec-WebSocket-Protocol")
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .any(|p| p.trim() == SUBPROTOCOL);
    if !offered {
        let mut refusal = ErrorResponse::new(Some(format!("use the {SUBPROTOCOL} subprotocol")));
        *refusal.status_mut() = tungstenite::http::StatusCode::BAD_REQUEST;
        return Err(refusal);
    }
    response.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        HeaderValue::from_static(SUBPROTOCOL),
    );
    Ok(response)
}

/// One viewer's connection: handshake, server info and channels, then its subscriptions and
/// messages until either side ends.
fn serve(stream: TcpStream, shared: &Shared, name: &str) -> Result<(), tungstenite::Error> {
    let _ = stream.set_nodelay(true);
    let mut socket = tungstenite::accept_hdr(stream, choose_subprotocol)
        .map_err(|e| tungstenite::Error::Io(io::Error::other(e.to_string())))?;
    socket.get_ref().set_read_timeout(Some(POLL))?;
    socket.send(Frame::text(server_info(name).to_string()))?;
    socket.send(Frame::text(advertise().to_string()))?;
    let (queue, messages) = sync_channel(VIEWER_QUEUE);
    let subscriptions = Arc::new(Mutex::new(HashMap::new()));
    shared
        .viewers
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .push(Viewer {
            queue,
            subscriptions: subscriptions.clone(),
        });
    loop {
        match socket.read() {
            Ok(Frame::Text(text)) => {
                let new = handle_request(&text, &subscriptions);
                let latched: Vec<Arc<Message>> = shared
                    .latched
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .clone();
                for (channel, subscription) in new {
                    for m in latched.iter().filter(|m| channel_id(m.topic) == channel) {
                        socket.write(message_frame(subscription, m))?;
                    }
                }
            }
            Ok(Frame::Close(_)) => return Ok(()),
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) => {}
            Err(e) => return Err(e),
        }
        if !send_queued(&mut socket, &messages, &subscriptions)? {
            return socket.close(None);
        }
    }
}

/// Sends what the sink queued for this viewer; false once the server has finished.
fn send_queued(
    socket: &mut WebSocket<TcpStream>,
    messages: &Receiver<Arc<Message>>,
    subscriptions: &Mutex<HashMap<u32, u32>>,
) -> Result<bool, tungstenite::Error> {
    loop {
        match messages.try_recv() {
            Ok(m) => {
                let subscription = subscriptions
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .get(&channel_id(m.topic))
                    .copied();
                if let Some(subscription) = subscription {
                    socket.write(message_frame(subscription, &m))?;
                }
            }
            Err(std::sync::mpsc::TryRecvError::Empty) => {
                socket.flush()?;
                return Ok(true);
            }
            Err(std::sync::mpsc::TryRecvError::Disconnected) => return Ok(false),
        }
    }
}

/// Applies a `subscribe` or `unsubscribe` request; returns the new (channel, subscription)
/// pairs. Anything else is ignored, as the protocol allows.
fn handle_request(text: &str, subscriptions: &Mutex<HashMap<u32, u32>>) -> Vec<(u32, u32)> {
    let Ok(request) = serde_json::from_str::<Value>(text) else {
        return Vec::new();
    };
    let mut subscriptions = subscriptions.lock().unwrap_or_else(PoisonError::into_inner);
    let number = |v: &Value| v.as_u64().and_then(|n| u32::try_from(n).ok());
    let mut new = Vec::new();
    match request.get("op").and_then(Value::as_str) {
        Some("subscribe") => {
            let list = request.get("subscriptions").and_then(Value::as_array);
            for s in list.into_iter().flatten() {
                let (Some(id), Some(channel)) = (
                    s.get("id").and_then(number),
                    s.get("channelId").and_then(number),
                ) else {
                    continue;
                };
                if Topic::ALL.iter().any(|t| channel_id(*t) == channel) {
                    subscriptions.insert(channel, id);
                    new.push((channel, id));
                }
            }
        }
        Some("unsubscribe") => {
            let ids: Vec<u32> = request
                .get("subscriptionIds")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .filter_map(number)
                .collect();
            subscriptions.retain(|_, id| !ids.contains(id));
        }
        _ => {}
    }
    new
}

/// A message data frame: opcode 1, subscription id, log time (ns), payload.
fn message_frame(subscription: u32, message: &Message) -> Frame {
    let mut bytes = Vec::with_capacity(13 + message.data.len());
    bytes.push(1);
    bytes.extend_from_slice(&subscription.to_le_bytes());
    bytes.extend_from_slice(&message.log_time.to_le_bytes());
    bytes.extend_from_slice(&message.data);
    Frame::binary(bytes)
}

fn server_info(name: &str) -> Value {
    json!({
        "op": "serverInfo",
        "name": name,
        "capabilities": [],
        "supportedEncodings": [],
        "metadata": {},
    })
}

fn advertise() -> Value {
    let channels: Vec<Value> = Topic::ALL
        .iter()
        .map(|topic| {
            json!({
                "id": channel_id(*topic),
                "topic": topic.name(),
                "encoding": "json",
                "schemaName": topic.schema_name(),
                "schema": topic.schema(),
                "schemaEncoding": "jsonschema",
            })
        })
        .collect();
    json!({ "op": "advertise", "channels": channels })
}
