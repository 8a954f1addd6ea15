//! `--pcap FILE`: a capture of the client's UDP datagrams and of every CAN frame the controller
//! sends or receives, as pcapng, for Wireshark (`tools/wireshark/armgate.lua` decodes both).
//!
//! The file has two interfaces: 0 carries raw IP packets (`LINKTYPE_RAW`; the IPv4/IPv6 and UDP
//! headers are synthesised from the socket addresses, so Wireshark dispatches the payload on the
//! UDP port), 1 carries CAN frames (`LINKTYPE_CAN_SOCKETCAN`). Timestamps are wall-clock
//! microseconds taken when the controller handed the datagram or frame over or took it: for a
//! transmitted CAN frame that is when it was queued, not when it went on the wire.
//!
//! The control loop never waits for the disk: records go through a bounded queue to a writer
//! thread, and a record that finds the queue full is dropped and counted. The writer flushes
//! whenever the queue runs empty for a moment, and at [`Capture::finish`].
//!
//! The capture is process-wide (like a logger), so that the bus and the socket code only make
//! one call each: [`udp`] and [`can`] do nothing until [`Capture::start`].

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::net::{IpAddr, SocketAddr};
use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use armgate_protocol::can::CanFrame;

/// Records queued for the writer at most (at most 192 bytes each, so about 1.5 MiB).
const QUEUE: usize = 8192;
/// The writer flushes after the queue has been empty this long.
const IDLE_FLUSH: Duration = Duration::from_millis(200);
/// The largest UDP payload captured whole (the protocol's datagrams are 31 bytes).
const MAX_PAYLOAD: usize = 64;

/// pcapng block types and link types.
const SECTION_HEADER: u32 = 0x0A0D_0D0A;
const INTERFACE_DESCRIPTION: u32 = 1;
const ENHANCED_PACKET: u32 = 6;
const BYTE_ORDER_MAGIC: u32 = 0x1A2B_3C4D;
const LINKTYPE_RAW: u16 = 101;
const LINKTYPE_CAN_SOCKETCAN: u16 = 227;
/// Interface numbers in this file.
const IP_INTERFACE: u32 = 0;
const CAN_INTERFACE: u32 = 1;

/// One thing to write.
enum Record {
    Udp {
        at: SystemTime,
        from: SocketAddr,
        to: SocketAddr,
        len: usize,
        payload: [u8; MAX_PAYLOAD],
    },
    Can {
        at: SystemTime,
        frame: CanFrame,
    },
    /// Flush and end the writer.
    Finish,
}

/// The queue to the writer and its drop counter.
struct Queue {
    sender: SyncSender<Record>,
    dropped: AtomicU64,
}

static QUEUE_TO_WRITER: OnceLock<Queue> = OnceLock::new();

/// The running capture; [`finish`](Self::finish) it to flush the file (dropping it flushes
/// too, for the early returns of an error).
pub struct Capture {
    writer: Option<JoinHandle<io::Result<u64>>>,
}

impl Capture {
    /// Creates `path`, writes the file header and starts the writer thread. Only one capture
    /// per process.
    pub fn start(path: &Path) -> io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        write_header(&mut out)?;
        out.flush()?;
        let (sender, receiver) = sync_channel(QUEUE);
        QUEUE_TO_WRITER
            .set(Queue {
                sender,
                dropped: AtomicU64::new(0),
            })
            .map_err(|_| io::Error::other("a capture is already running"))?;
        let writer = std::thread::Builder::new()
            .name("pcap".into())
            .spawn(move || write_records(out, &receiver))?;
        Ok(Self {
            writer: Some(writer),
        })
    }

    /// Writes what is queued, closes the file, and returns how many records were written and
    /// how many were dropped because the queue was full.
    pub fn finish(mut self) -> io::Result<(u64, u64)> {
        self.stop()
    }

    fn stop(&mut self) -> io::Result<(u64, u64)> {
        let Some(writer) = self.writer.take() else {
            return Ok((0, 0));
        };
        let dropped = QUEUE_TO_WRITER.get().map_or(0, |q| {
            // A blocking send: the end marker must not be dropped.
            let _ = q.sender.send(Record::Finish);
            q.dropped.load(Ordering::Relaxed)
        });
        let written = writer
            .join()
            .map_err(|_| io::Error::other("the pcap writer panicked"))??;
        Ok((written, dropped))
    }
}

impl Drop for Capture {
    fn drop(&mut self) {
        // Nobody is left to report an error to.
        let _ = self.stop();
    }
}

fn enqueue(record: impl FnOnce() -> Record) {
    if let Some(queue) = QUEUE_TO_WRITER.get() {
        match queue.sender.try_send(record()) {
            Ok(()) => {}
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                queue.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

/// Captures a UDP datagram from `from` to `to` (nothing without a running capture).
pub fn udp(from: SocketAddr, to: SocketAddr, payload: &[u8]) {
    enqueue(|| {
        let mut bytes = [0; MAX_PAYLOAD];
        bytes.iter_mut().zip(payload).for_each(|(b, p)| *b = *p);
        Record::Udp {
            at: SystemTime::now(),
            from,
            to,
            len: payload.len().min(MAX_PAYLOAD),
            payload: bytes,
        }
    });
}

/// Captures a CAN frame sent or received by the controller (nothing without a running capture).
pub fn can(frame: &CanFrame) {
    enqueue(|| Record::Can {
        at: SystemTime::now(),
        frame: *frame,
    });
}

/// The writer thread: writes records until [`Record::Finish`] or until every sender is gone.
fn write_records(mut out: BufWriter<File>, receiver: &Receiver<Record>) -> io::Result<u64> {
    let mut written = 0;
    loop {
        let record = match receiver.recv_timeout(IDLE_FLUSH) {
            Ok(record) => record,
            Err(RecvTimeoutError::Timeout) => {
                out.flush()?;
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => Record::Finish,
        };
        match record {
            Record::Udp {
                at,
                from,
                to,
                len,
                payload,
            } => {
                let packet = ip_udp_packet(from, to, payload.get(..len).unwrap_or_default());
                write_packet(&mut out, IP_INTERFACE, at, &packet)?;
            }
            Record::Can { at, frame } => {
                write_packet(&mut out, CAN_INTERFACE, at, &socketcan_frame(&frame))?;
            }
            Record::Finish => {
                out.flush()?;
                return Ok(written);
            }
        }
        written += 1;
    }
}

/// Section header and the two interface descriptions.
fn write_header(out: &mut impl Write) -> io::Result<()> {
    let mut shb = Vec::new();
    shb.extend_from_slice(&BYTE_ORDER_MAGIC.to_le_bytes());
    shb.extend_from_slice(&1u16.to_le_bytes()); // major version
    shb.extend_from_slice(&0u16.to_le_bytes()); // minor version
    shb.extend_from_slice(&(-1i64).to_le_bytes()); // section length unknown
    push_option(&mut shb, 4, b"armgate-sim"); // shb_userappl
    push_option(&mut shb, 0, b""); // opt_endofopt
    write_block(out, SECTION_HEADER, &shb)?;
    for (link, name) in [
        (LINKTYPE_RAW, &b"udp"[..]),
        (LINKTYPE_CAN_SOCKETCAN, &b"can"[..]),
    ] {
        let mut idb = Vec::new();
        idb.extend_from_slice(&link.to_le_bytes());
        idb.extend_from_slice(&0u16.to_le_bytes()); // reserved
        idb.extend_from_slice(&0u32.to_le_bytes()); // snap length: unlimited
        push_option(&mut idb, 2, name); // if_name
        push_option(&mut idb, 0, b"");
        write_block(out, INTERFACE_DESCRIPTION, &idb)?;
    }
    Ok(())
}

/// An enhanced packet block; timestamps in microseconds (the default `if_tsresol`).
fn write_packet(
    out: &mut impl Write,
    interface: u32,
    at: SystemTime,
    packet: &[u8],
) -> io::Result<()> {
    let micros = at
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_micros()).unwrap_or(u64::MAX));
    let len = u32::try_from(packet.len()).map_err(io::Error::other)?;
    let mut body = Vec::with_capacity(20 + packet.len() + 3);
    body.extend_from_slice(&interface.to_le_bytes());
    body.extend_from_slice(&((micros >> 32) as u32).to_le_bytes());
    body.extend_from_slice(&(micros as u32).to_le_bytes());
    body.extend_from_slice(&len.to_le_bytes()); // captured
    body.extend_from_slice(&len.to_le_bytes()); // original
    body.extend_from_slice(packet);
    pad(&mut body);
    write_block(out, ENHANCED_PACKET, &body)
}

/// A block: type, total length, body (already padded to 4 bytes), total length again.
fn write_block(out: &mut impl Write, kind: u32, body: &[u8]) -> io::Result<()> {
    let total = u32::try_from(body.len() + 12).map_err(io::Error::other)?;
    out.write_all(&kind.to_le_bytes())?;
    out.write_all(&total.to_le_bytes())?;
    out.write_all(body)?;
    out.write_all(&total.to_le_bytes())
}

/// An option: code, length, value padded to 4 bytes.
fn push_option(block: &mut Vec<u8>, code: u16, value: &[u8]) {
    block.extend_from_slice(&code.to_le_bytes());
    block.extend_from_slice(&(value.len() as u16).to_le_bytes());
    block.extend_from_slice(value);
    pad(block);
}

fn pad(bytes: &mut Vec<u8>) {
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
}

/// The 16-byte SocketCAN `struct can_frame` as pcap stores it: the identifier big-endian, the
/// length, three reserved bytes, eight data bytes.
fn socketcan_frame(frame: &CanFrame) -> [u8; 16] {
    let mut out = [0; 16];
    let [i0, i1, i2, i3] = u32::from(frame.id()).to_be_bytes();
    let mut header = [i0, i1, i2, i3, frame.dlc(), 0, 0, 0].into_iter();
    let data = frame.data().iter().copied();
    out.iter_mut()
        .zip(header.by_ref().chain(data))
        .for_each(|(o, b)| *o = b);
    out
}

/// An IPv4 or IPv6 packet with a UDP header around `payload`. Mixed address families (which
/// a socket never produces) are written as IPv4 with unspecified addresses.
fn ip_udp_packet(from: SocketAddr, to: SocketAddr, payload: &[u8]) -> Vec<u8> {
    let udp_len = (8 + payload.len()) as u16;
    let mut udp = Vec::with_capacity(usize::from(udp_len));
    udp.extend_from_slice(&from.port().to_be_bytes());
    udp.extend_from_slice(&to.port().to_be_bytes());
    udp.extend_from_slice(&udp_len.to_be_bytes());
    udp.extend_from_slice(&[0, 0]); // checksum, filled in below
    udp.extend_from_slice(payload);
    let mut packet = Vec::with_capacity(40 + udp.len());
    let pseudo_header: Vec<u8> = match (from.ip(), to.ip()) {
        (IpAddr::V6(src), IpAddr::V6(dst)) => {
            packet.extend_from_slice(&[0x60, 0, 0, 0]); // version 6
            packet.extend_from_slice(&udp_len.to_be_bytes()); // payload length
            packet.extend_from_slice(&[17, 64]); // next header UDP, hop limit
            packet.extend_from_slice(&src.octets());
            packet.extend_from_slice(&dst.octets());
            [
                &src.octets()[..],
                &dst.octets()[..],
                &[0, 0],
                &udp_len.to_be_bytes(),
                &[0, 17],
            ]
            .concat()
        }
        (src, dst) => {
            let v4 = |ip: IpAddr| match ip {
                IpAddr::V4(a) => a.octets(),
                IpAddr::V6(_) => [0; 4],
            };
            let (src, dst) = (v4(src), v4(dst));
            let total = 20 + udp_len;
            let mut header = [0u8; 20];
            let fields = [
                &[0x45, 0][..],           // version 4, 20-byte header; DSCP
                &total.to_be_bytes(),     // total length
                &[0, 0, 0x40, 0, 64, 17], // id 0, don't fragment, TTL 64, UDP
                &[0, 0],                  // header checksum, filled in below
                &src,
                &dst,
            ];
            header
                .iter_mut()
                .zip(fields.concat())
                .for_each(|(h, b)| *h = b);
            let sum = checksum(&[&header]);
            put(&mut header, 10, sum);
            packet.extend_from_slice(&header);
            [&src[..], &dst[..], &[0, 17], &udp_len.to_be_bytes()].concat()
        }
    };
    let sum = match checksum(&[&pseudo_header, &udp]) {
        0 => 0xFFFF, // 0 means "no checksum" in UDP
        sum => sum,
    };
    put(&mut udp, 6, sum);
    packet.extend_from_slice(&udp);
    packet
}

/// Writes `value` big-endian at `at` (a checksum field inside a header built above).
fn put(bytes: &mut [u8], at: usize, value: u16) {
    if let Some(field) = bytes.get_mut(at..at + 2) {
        field
            .iter_mut()
            .zip(value.to_be_bytes())
            .for_each(|(f, v)| *f = v);
    }
}

/// The Internet checksum (RFC 1071) over the concatenation of `parts` (each even-length but
/// the last).
fn checksum(parts: &[&[u8]]) -> u16 {
    let mut sum: u32 = parts
        .iter()
        .flat_map(|p| p.chunks(2))
        .map(|pair| match *pair {
            [a, b] => u32::from(u16::from_be_bytes([a, b])),
            [a] => u32::from(a) << 8,
            _ => 0,
        })
        .sum();
    while sum > 0xFFFF {
        sum = (sum & 0xFFFF) + (sum >> 16);
    }
    !(sum as u16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_queue_is_bounded_in_bytes() {
        assert!(std::mem::size_of::<Record>() <= 192);
    }

    #[test]
    fn ipv4_header_checksum_verifies() {
        let packet = ip_udp_packet(
            "127.0.0.1:40000".parse().unwrap(),
            "127.0.0.1:7031".parse().unwrap(),
            b"PS",
        );
        assert_eq!(packet.len(), 20 + 8 + 2);
        assert_eq!(packet[0], 0x45);
        assert_eq!(packet[9], 17);
        // A header with a correct checksum sums to zero.
        assert_eq!(checksum(&[&packet[..20]]), 0);
        assert_eq!(&packet[20..24], &[0x9C, 0x40, 0x1B, 0x77]);
        // The UDP checksum verifies over the pseudo header too.
        let pseudo = [&packet[12..20], &[0, 17, 0, 10]].concat();
        assert_eq!(checksum(&[&pseudo, &packet[20..]]), 0);
    }

    #[test]
    fn ipv6_packets_carry_the_addresses() {
        let packet = ip_udp_packet(
            "[::1]:7031".parse().unwrap(),
            "[::1]:5000".parse().unwrap(),
            &[1, 2, 3],
        );
        assert_eq!(packet.len(), 40 + 8 + 3);
        assert_eq!(packet[0] >> 4, 6);
        assert_eq!(packet[6], 17);
        assert_eq!(packet[39], 1);
        let pseudo = [&packet[8..40], &[0, 0, 0, 11, 0, 0, 0, 17]].concat();
        assert_eq!(checksum(&[&pseudo, &packet[40..]]), 0);
    }

    #[test]
    fn can_frames_use_the_socketcan_layout() {
        let frame = CanFrame::new(0x301, b"PX\0\0").unwrap();
        assert_eq!(
            socketcan_frame(&frame),
            [0, 0, 3, 1, 4, 0, 0, 0, b'P', b'X', 0, 0, 0, 0, 0, 0]
        );
    }

    #[test]
    fn blocks_are_padded_and_framed() {
        let mut out = Vec::new();
        write_header(&mut out).unwrap();
        write_packet(&mut out, 1, UNIX_EPOCH + Duration::from_micros(5), &[9; 5]).unwrap();
        // Walk the blocks by their lengths: both length fields agree, every block is aligned.
        let mut at = 0;
        let mut kinds = vec![];
        while at < out.len() {
            let word = |i: usize| u32::from_le_bytes(out[i..i + 4].try_into().unwrap());
            let len = word(at + 4) as usize;
            assert_eq!(len % 4, 0);
            assert_eq!(word(at + len - 4) as usize, len);
            kinds.push(word(at));
            at += len;
        }
        assert_eq!(kinds, [SECTION_HEADER, 1, 1, ENHANCED_PACKET]);
        assert_eq!(at, out.len());
    }
}
