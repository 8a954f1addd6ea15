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
//!
//! The pcapng blocks are pcap-file's, the IP and UDP headers etherparse's. pcap-file 2 writes
//! packet timestamps in nanoseconds whatever the interface's resolution says, so both interfaces
//! declare nanoseconds (`if_tsresol` 9).

use std::borrow::Cow;
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
use etherparse::PacketBuilder;
use pcap_file::pcapng::PcapNgWriter;
use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketBlock;
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use pcap_file::pcapng::blocks::section_header::{SectionHeaderBlock, SectionHeaderOption};
use pcap_file::{DataLink, Endianness};

/// Records queued for the writer at most (at most 192 bytes each, so about 1.5 MiB).
const QUEUE: usize = 8192;
/// The writer flushes after the queue has been empty this long.
const IDLE_FLUSH: Duration = Duration::from_millis(200);
/// The largest UDP payload captured whole (the protocol's datagrams are 31 bytes).
const MAX_PAYLOAD: usize = 64;

/// The file's interfaces, in order: raw IP packets (`LINKTYPE_RAW`) and SocketCAN frames.
const INTERFACES: [(DataLink, &str); 2] =
    [(DataLink::RAW, "udp"), (DataLink::CAN_SOCKETCAN, "can")];
/// Interface numbers in this file.
const IP_INTERFACE: u32 = 0;
const CAN_INTERFACE: u32 = 1;
/// `if_tsresol` 9: timestamps in nanoseconds, as pcap-file writes them.
const NANOSECONDS: u8 = 9;

/// The capture file.
type Writer = PcapNgWriter<BufWriter<File>>;

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
        let mut out = header(BufWriter::new(File::create(path)?))?;
        out.get_mut().flush()?;
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
fn write_records(mut out: Writer, receiver: &Receiver<Record>) -> io::Result<u64> {
    let mut written = 0;
    loop {
        let record = match receiver.recv_timeout(IDLE_FLUSH) {
            Ok(record) => record,
            Err(RecvTimeoutError::Timeout) => {
                out.get_mut().flush()?;
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
                let packet = ip_udp_packet(from, to, payload.get(..len).unwrap_or_default())?;
                write_packet(&mut out, IP_INTERFACE, at, &packet)?;
            }
            Record::Can { at, frame } => {
                write_packet(&mut out, CAN_INTERFACE, at, &socketcan_frame(&frame))?;
            }
            Record::Finish => {
                out.get_mut().flush()?;
                return Ok(written);
            }
        }
        written += 1;
    }
}

/// The section header and the two interface descriptions, written to `out`.
fn header<W: Write>(out: W) -> io::Result<PcapNgWriter<W>> {
    let section = SectionHeaderBlock {
        endianness: Endianness::Little,
        options: vec![SectionHeaderOption::UserApplication("armgate-sim".into())],
        ..SectionHeaderBlock::default()
    };
    let mut writer = PcapNgWriter::with_section_header(out, section).map_err(io::Error::other)?;
    for (linktype, name) in INTERFACES {
        let interface = InterfaceDescriptionBlock {
            linktype,
            snaplen: 0,
            options: vec![
                InterfaceDescriptionOption::IfName(name.into()),
                InterfaceDescriptionOption::IfTsResol(NANOSECONDS),
            ],
        };
        writer
            .write_pcapng_block(interface)
            .map_err(io::Error::other)?;
    }
    Ok(writer)
}

/// An enhanced packet block on `interface`, stamped `at`.
fn write_packet<W: Write>(
    out: &mut PcapNgWriter<W>,
    interface: u32,
    at: SystemTime,
    packet: &[u8],
) -> io::Result<()> {
    let block = EnhancedPacketBlock {
        interface_id: interface,
        timestamp: at.duration_since(UNIX_EPOCH).unwrap_or_default(),
        original_len: u32::try_from(packet.len()).map_err(io::Error::other)?,
        data: Cow::Borrowed(packet),
        options: vec![],
    };
    out.write_pcapng_block(block).map_err(io::Error::other)?;
    Ok(())
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

/// An IPv4 or IPv6 packet with a UDP header around `payload`, checksums included. Mixed
/// address families (which a socket never produces) are written as IPv4 with unspecified
/// addresses.
fn ip_udp_packet(from: SocketAddr, to: SocketAddr, payload: &[u8]) -> io::Result<Vec<u8>> {
    let ip = match (from.ip(), to.ip()) {
        (IpAddr::V6(src), IpAddr::V6(dst)) => PacketBuilder::ipv6(src.octets(), dst.octets(), 64),
        (src, dst) => {
            let v4 = |ip: IpAddr| match ip {
                IpAddr::V4(a) => a.octets(),
                IpAddr::V6(_) => [0; 4],
            };
            PacketBuilder::ipv4(v4(src), v4(dst), 64)
        }
    };
    let udp = ip.udp(from.port(), to.port());
    let mut packet = Vec::with_capacity(udp.size(payload.len()));
    udp.write(&mut packet, payload).map_err(io::Error::other)?;
    Ok(packet)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcap_file::pcapng::{Block, PcapNgReader};

    /// The Internet checksum (RFC 1071) over the concatenation of `parts`, each even-length:
    /// 0 over a header (or pseudo header and datagram) whose checksum is right.
    fn checksum(parts: &[&[u8]]) -> u16 {
        let mut sum: u32 = parts
            .iter()
            .flat_map(|p| p.chunks(2))
            .map(|pair| u32::from(u16::from_be_bytes([pair[0], *pair.get(1).unwrap_or(&0)])))
            .sum();
        while sum > 0xFFFF {
            sum = (sum & 0xFFFF) + (sum >> 16);
        }
        !(sum as u16)
    }

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
        )
        .unwrap();
        assert_eq!(packet.len(), 20 + 8 + 2);
        assert_eq!(packet[0], 0x45);
        assert_eq!(packet[9], 17);
        assert_eq!(checksum(&[&packet[..20]]), 0);
        assert_eq!(&packet[20..24], &[0x9C, 0x40, 0x1B, 0x77]);
        // The UDP checksum verifies over the pseudo header too.
        let pseudo = [&packet[12..20], &[0, 17, 0, 10]].concat();
        assert_eq!(checksum(&[&pseudo, &packet[20..]]), 0);
        assert_eq!(&packet[28..], b"PS");
    }

    #[test]
    fn ipv6_packets_carry_the_addresses() {
        let packet = ip_udp_packet(
            "[::1]:7031".parse().unwrap(),
            "[::1]:5000".parse().unwrap(),
            &[1, 2, 3, 4],
        )
        .unwrap();
        assert_eq!(packet.len(), 40 + 8 + 4);
        assert_eq!(packet[0] >> 4, 6);
        assert_eq!(packet[6], 17);
        assert_eq!(packet[39], 1);
        let pseudo = [&packet[8..40], &[0, 0, 0, 12, 0, 0, 0, 17]].concat();
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
        let mut out = header(Vec::new()).unwrap();
        let at = UNIX_EPOCH + Duration::from_micros(1_700_000_000_000_005);
        write_packet(&mut out, CAN_INTERFACE, at, &[9; 5]).unwrap();
        let out = out.into_inner();
        // Walk the blocks by their lengths: both length fields agree, every block is aligned.
        let mut offset = 0;
        let mut kinds = vec![];
        while offset < out.len() {
            let word = |i: usize| u32::from_le_bytes(out[i..i + 4].try_into().unwrap());
            let len = word(offset + 4) as usize;
            assert_eq!(len % 4, 0);
            assert_eq!(word(offset + len - 4) as usize, len);
            kinds.push(word(offset));
            offset += len;
        }
        // Section header, two interface descriptions, an enhanced packet.
        assert_eq!(kinds, [0x0A0D_0D0A, 1, 1, 6]);
        assert_eq!(offset, out.len());
        // Read back: the interfaces, the packet on the CAN one at its time (nanoseconds, as
        // its interface declares).
        let mut reader = PcapNgReader::new(&out[..]).unwrap();
        let mut links = vec![];
        while let Some(block) = reader.next_block() {
            match block.unwrap() {
                Block::InterfaceDescription(i) => {
                    assert!(
                        i.options
                            .contains(&InterfaceDescriptionOption::IfTsResol(9))
                    );
                    links.push(i.linktype);
                }
                Block::EnhancedPacket(p) => {
                    assert_eq!((p.interface_id, &p.data[..]), (1, &[9; 5][..]));
                    assert_eq!(p.timestamp, at.duration_since(UNIX_EPOCH).unwrap());
                }
                _ => {}
            }
        }
        assert_eq!(links, [DataLink::RAW, DataLink::CAN_SOCKETCAN]);
    }
}
