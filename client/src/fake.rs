//! A scripted fake controller for the tests: a thread on a UDP socket bound to 127.0.0.1:0
//! that records every datagram and answers with whatever the script returns.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use armgate_protocol::client::MESSAGE_LEN;

/// A text message, NUL-filled to 31 bytes.
pub fn text(s: &str) -> Vec<u8> {
    let mut b = vec![0; MESSAGE_LEN];
    b[..s.len()].copy_from_slice(s.as_bytes());
    b
}

/// The normal reply to `request`: its 31 bytes with the command characters reversed.
pub fn echo(request: &[u8]) -> Vec<u8> {
    let mut reply = request[..MESSAGE_LEN].to_vec();
    reply.swap(0, 1);
    reply
}

/// A text as the client receives it.
pub fn parsed_text(s: &str) -> armgate_protocol::client::Text {
    let bytes = text(s);
    armgate_protocol::client::Text::parse(
        &armgate_protocol::client::Message::new_checked(&bytes[..]).unwrap(),
    )
    .unwrap()
}

/// The fake; dropping it stops the thread.
pub struct FakeController {
    addr: SocketAddr,
    received: Arc<Mutex<Vec<Vec<u8>>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeController {
    /// Starts the fake. `script` gets each datagram and returns the datagrams to send back to
    /// its sender, in order.
    pub fn spawn(mut script: impl FnMut(&[u8]) -> Vec<Vec<u8>> + Send + 'static) -> Self {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        socket
            .set_read_timeout(Some(Duration::from_millis(10)))
            .unwrap();
        let addr = socket.local_addr().unwrap();
        let received = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let received = Arc::clone(&received);
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || {
                let mut buf = [0; 256];
                while !stop.load(Ordering::Relaxed) {
                    let Ok((n, from)) = socket.recv_from(&mut buf) else {
                        continue;
                    };
                    let datagram = buf[..n].to_vec();
                    received.lock().unwrap().push(datagram.clone());
                    for reply in script(&datagram) {
                        let _ = socket.send_to(&reply, from);
                    }
                }
            })
        };
        Self {
            addr,
            received,
            stop,
            thread: Some(thread),
        }
    }

    /// The fake's address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// A client of the fake that waits long enough (1 s) never to resend on a loaded machine.
    pub fn client(&self) -> crate::Client {
        crate::Client::connect_with(
            self.addr,
            crate::ClientConfig {
                timeout: Duration::from_secs(1),
                ..crate::ClientConfig::default()
            },
        )
        .unwrap()
    }

    /// The datagrams received so far.
    pub fn received(&self) -> Vec<Vec<u8>> {
        self.received.lock().unwrap().clone()
    }

    /// The datagrams received, after waiting (at most 1 s) until there are at least `n`.
    pub fn wait_for(&self, n: usize) -> Vec<Vec<u8>> {
        let deadline = Instant::now() + Duration::from_secs(1);
        loop {
            let received = self.received();
            if received.len() >= n || Instant::now() > deadline {
                return received;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

impl Drop for FakeController {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}
