//! Linux SocketCAN as the drive manager's [`CanBus`], through the `socketcan` crate: a raw CAN
//! socket on an interface such as `can0` (for example a PCAN-USB adapter through the kernel's
//! `peak_usb` driver) or `vcan0`. One adapter for the shells that run on Linux: `armgate-sim
//! --can socketcan:IFACE` and its Whistle simulator (`--whistles`), and the firmware's Linux
//! build with `ARMGATE_CAN=socketcan:IFACE` (its FDCAN seam).
//!
//! What it does with what the kernel hands over ([`classify`]):
//!
//! * standard-identifier data frames go to the drive manager;
//! * extended-identifier and remote frames are ignored and counted (the drive protocol uses
//!   neither; an extended frame whose low 11 bits look like a drive's reply is not one);
//! * error frames: bus-off latches [`BusState::BusOff`] until the client's `ON`
//!   ([`CanBus::recover`]); the others are counted.
//!
//! Every socket call's error is handled: a full transmit queue (`ENOBUFS`, `EAGAIN`: Linux CAN
//! interfaces default to `txqueuelen` 10, less than one cycle of a 6-drive arm) is
//! [`TxError::QueueFull`], which the drive manager turns into the fault `ER35 CAN send queue
//! full` (it stops the drives; nothing is lost silently); `ENETDOWN` is bus-off; any other
//! error is counted and reported as a full queue.
//!
//! On a bus without bit timing (`vcan`, QEMU's emulated CAN bus) a cycle's burst of frames
//! arrives at once, and an emulated SJA1000's 64-byte receive FIFO (five 8-byte frames)
//! overruns. Opened [`paced`](SocketCan::open) with the robot file's bit rate, writes are held
//! to what a real bus of that rate carries: each frame waits until the previous one would have
//! left, by its exact stuffed length ([`exact_bits_on_wire`]).

use std::io::{self, ErrorKind};
use std::os::fd::AsFd;
use std::time::{Duration, Instant, SystemTime};

use armgate_core::drives::{BusState, CanBus, TxError};
use armgate_protocol::can::{CanFrame, exact_bits_on_wire};
use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::time::TimeSpec;
use socketcan::{CanSocket, EmbeddedFrame, Frame, Socket, SocketOptions, StandardId};

/// Frames read per [`CanBus::try_receive`] call at most while skipping frames of no interest.
const MAX_SKIPPED: usize = 64;

/// What the adapter ignored or could not do, since it was opened.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Extended-identifier and remote frames received (ignored).
    pub foreign_frames: u64,
    /// Error frames received other than bus-off (ignored).
    pub error_frames: u64,
    /// Bus-off reports (error frames or `ENETDOWN`).
    pub bus_offs: u64,
    /// Frames refused because the transmit queue was full (each one a drive fault).
    pub queue_full: u64,
    /// Other failed reads and writes.
    pub socket_errors: u64,
}

/// A received frame, sorted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Received {
    /// A standard data frame: for the drive manager.
    Data(CanFrame),
    /// An extended or remote frame: not for us.
    Foreign,
    /// An error frame reporting bus-off.
    BusOff,
    /// Another error frame.
    Error,
}

/// Sorts one frame from the socket.
pub fn classify(frame: &socketcan::CanFrame) -> Received {
    match frame {
        socketcan::CanFrame::Data(data) if !data.is_extended() => {
            let id = u16::try_from(data.raw_id()).unwrap_or(u16::MAX);
            CanFrame::new(id, data.data()).map_or(Received::Foreign, Received::Data)
        }
        socketcan::CanFrame::Data(_) | socketcan::CanFrame::Remote(_) => Received::Foreign,
        socketcan::CanFrame::Error(error) if error.error_bits() & libc::CAN_ERR_BUSOFF != 0 => {
            Received::BusOff
        }
        socketcan::CanFrame::Error(_) => Received::Error,
    }
}

/// The adapter's state apart from the socket: the bus-off latch and the counters.
#[derive(Debug, Default)]
struct Tally {
    bus_off: bool,
    counters: Counters,
}

impl Tally {
    /// Takes one sorted frame into account; the frame for the drive manager, if it is one.
    fn take(&mut self, received: Received) -> Option<CanFrame> {
        match received {
            Received::Data(frame) => return Some(frame),
            Received::Foreign => self.counters.foreign_frames += 1,
            Received::BusOff => self.went_bus_off(),
            Received::Error => self.counters.error_frames += 1,
        }
        None
    }

    fn went_bus_off(&mut self) {
        if !self.bus_off {
            self.counters.bus_offs += 1;
        }
        self.bus_off = true;
    }
}

/// Receive buffer asked of the kernel (it caps it at `net.core.rmem_max`): room for a few
/// hundred frames where a process is not scheduled for a while (each costs about 1 KiB there).
const RECEIVE_BUFFER: usize = 1 << 20;

/// Frames a paced writer may send back to back after falling behind: four 8-byte frames fit the
/// receive FIFO of an emulated SJA1000 (64 bytes, 11 to 13 a frame) with room to spare.
const BURST: u32 = 4;

/// Writes held to a bus's bit rate: when the bus is next free, on the wall clock.
#[derive(Debug)]
pub struct Pacer {
    bit_time: Duration,
    free_at: Instant,
}

impl Pacer {
    /// Frames as a bus of `bitrate` bit/s carries them.
    pub fn new(bitrate: u32) -> Self {
        Self {
            bit_time: Duration::from_secs(1) / bitrate.max(1),
            free_at: Instant::now(),
        }
    }

    /// Waits until the bus is free for `frame`.
    fn wait(&self) {
        let now = Instant::now();
        if self.free_at > now {
            std::thread::sleep(self.free_at - now);
        }
    }

    /// `frame` went out (a refused frame took no time): the bus is busy for its length. A
    /// writer that slept too long (a sleep overshoots by milliseconds in an emulated machine)
    /// may send up to [`BURST`] frames at once, as the bus would have carried them meanwhile;
    /// it never gets further ahead of the bit rate than that.
    fn sent(&mut self, frame: &CanFrame) {
        let length = self.bit_time * exact_bits_on_wire(frame);
        let now = Instant::now();
        let start = self
            .free_at
            .max(now.checked_sub(length * BURST).unwrap_or(now));
        self.free_at = start + length;
    }
}

/// A raw CAN socket bound to one interface, non-blocking.
pub struct SocketCan {
    socket: CanSocket,
    tally: Tally,
    pacer: Option<Pacer>,
}

impl SocketCan {
    /// Opens interface `name`, its writes held to `pacer`'s bit rate if given (a bus without
    /// bit timing). Fails with `EAFNOSUPPORT` where the kernel has no CAN support and `ENODEV`
    /// where the interface does not exist.
    pub fn open(name: &str, pacer: Option<Pacer>) -> io::Result<Self> {
        let socket = CanSocket::open(name)?;
        socket.set_nonblocking(true)?;
        // Bus-off and restart reports arrive as error frames.
        socket.set_error_filter(libc::CAN_ERR_BUSOFF | libc::CAN_ERR_RESTARTED)?;
        socket2::SockRef::from(&socket).set_recv_buffer_size(RECEIVE_BUFFER)?;
        // Each frame carries the time the kernel received it (`SO_TIMESTAMPNS`), for a reader
        // that was not scheduled when it came (the Whistle simulator).
        socket.set_recv_timestamp(true)?;
        Ok(Self {
            socket,
            tally: Tally::default(),
            pacer,
        })
    }

    /// Waits up to `timeout` for a frame to read (the Whistle simulator: woken by the frame
    /// itself, not by a sleep that ends later). A `ppoll`, timed to the microsecond: a socket's
    /// read timeout is rounded up to the kernel's tick (4 ms at 250 Hz), and a blocking read
    /// loop would not stop reading while frames keep coming.
    pub fn wait_readable(&self, timeout: Duration) -> io::Result<()> {
        let mut fds = [PollFd::new(self.socket.as_fd(), PollFlags::POLLIN)];
        match ppoll(&mut fds, Some(TimeSpec::from_duration(timeout)), None) {
            Ok(_) | Err(Errno::EINTR) => Ok(()),
            Err(e) => Err(e.into()),
        }
    }

    /// The next frame for the drive manager and when the kernel received it (the wall
    /// clock's time; `None` if the kernel gave none): [`CanBus::try_receive`] with the frame's
    /// arrival, which a reader that was not scheduled for a while needs to put it at its time.
    pub fn try_receive_stamped(&mut self) -> Option<(CanFrame, Option<SystemTime>)> {
        for _ in 0..MAX_SKIPPED {
            match self.socket.read_frame_with_timestamps() {
                Ok((frame, stamps)) => {
                    if let Some(frame) = self.tally.take(classify(&frame)) {
                        return Some((frame, stamps.socket));
                    }
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => return None,
                Err(e) if e.raw_os_error() == Some(libc::ENETDOWN) => {
                    self.tally.went_bus_off();
                    return None;
                }
                Err(_) => {
                    self.tally.counters.socket_errors += 1;
                    return None;
                }
            }
        }
        None
    }

    /// What was ignored or failed so far.
    pub fn counters(&self) -> Counters {
        self.tally.counters
    }
}

impl CanBus for SocketCan {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        if self.tally.bus_off {
            return Err(TxError::BusOff);
        }
        let id = StandardId::new(frame.id()).ok_or(TxError::QueueFull)?;
        let raw = socketcan::CanFrame::new(id, frame.data()).ok_or(TxError::QueueFull)?;
        if let Some(pacer) = &self.pacer {
            pacer.wait();
        }
        match self.socket.write_frame(&raw) {
            Ok(()) => {
                if let Some(pacer) = &mut self.pacer {
                    pacer.sent(frame);
                }
                Ok(())
            }
            Err(e) if e.raw_os_error() == Some(libc::ENETDOWN) => {
                self.tally.went_bus_off();
                Err(TxError::BusOff)
            }
            Err(e) => {
                if e.kind() == ErrorKind::WouldBlock || e.raw_os_error() == Some(libc::ENOBUFS) {
                    self.tally.counters.queue_full += 1;
                } else {
                    self.tally.counters.socket_errors += 1;
                }
                Err(TxError::QueueFull)
            }
        }
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.try_receive_stamped().map(|(frame, _)| frame)
    }

    fn state(&self) -> BusState {
        BusState::from_bus_off(self.tally.bus_off)
    }

    /// The latch is cleared; if the interface is still off (no `restart-ms` configured, see
    /// the README), the next frame finds out.
    fn recover(&mut self) {
        self.tally.bus_off = false;
    }
}

/// The drive manager's bus in a shell on Linux, chosen at run time: simulated drives (`V`, the
/// shell's `VirtualBus`) or a SocketCAN interface (armgate-sim's `--can`, the firmware's
/// `ARMGATE_CAN`).
pub enum LinuxBus<V> {
    /// Simulated Whistles; their time advances with the control loop ([`CanBus::advance_to`]).
    Simulated(V),
    /// A real interface (or vcan): the drives keep their own time.
    SocketCan(SocketCan),
}

impl<V: CanBus> CanBus for LinuxBus<V> {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        match self {
            Self::Simulated(bus) => bus.try_transmit(frame),
            Self::SocketCan(bus) => bus.try_transmit(frame),
        }
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        match self {
            Self::Simulated(bus) => bus.try_receive(),
            Self::SocketCan(bus) => bus.try_receive(),
        }
    }

    fn state(&self) -> BusState {
        match self {
            Self::Simulated(bus) => bus.state(),
            Self::SocketCan(bus) => bus.state(),
        }
    }

    fn advance_to(&mut self, now: f64) -> bool {
        match self {
            Self::Simulated(bus) => bus.advance_to(now),
            Self::SocketCan(bus) => bus.advance_to(now),
        }
    }

    fn recover(&mut self) {
        match self {
            Self::Simulated(bus) => bus.recover(),
            Self::SocketCan(bus) => bus.recover(),
        }
    }
}

/// What to tell the user when opening interface `name` failed.
pub fn explain(name: &str, error: &io::Error) -> String {
    match error.raw_os_error() {
        Some(libc::EAFNOSUPPORT) => format!(
            "cannot open SocketCAN interface {name}: this kernel has no CAN support \
             (socket(PF_CAN) failed: {error}); use --can sim for simulated drives"
        ),
        Some(libc::ENODEV) => format!(
            "cannot open SocketCAN interface {name}: no such network interface ({error}); \
             list interfaces with `ip link`, or create a virtual one with \
             `ip link add dev vcan0 type vcan && ip link set up vcan0`"
        ),
        _ => format!("cannot open SocketCAN interface {name}: {error}"),
    }
}

#[cfg(test)]
mod tests {
    use socketcan::{CanErrorFrame, CanRemoteFrame, ExtendedId, Id};

    use super::*;

    fn data(id: impl Into<Id>, bytes: &[u8]) -> socketcan::CanFrame {
        socketcan::CanFrame::new(id, bytes).unwrap()
    }

    #[test]
    fn only_standard_data_frames_reach_the_drive_manager() {
        // Node 1's SDO reply (0x581) and interpreter reply (0x281), and look-alikes.
        let reply = StandardId::new(0x281).unwrap();
        let stream = [
            data(reply, &[0x50, 0x58, 0, 0, 0x10, 0, 0, 0]),
            // Extended: its low 11 bits are 0x281, but it is not node 1's reply.
            data(ExtendedId::new(0x1000_0281).unwrap(), &[1, 2, 3]),
            data(ExtendedId::new(0x281).unwrap(), &[1]),
            socketcan::CanFrame::Remote(CanRemoteFrame::new_remote(reply, 8).unwrap()),
            socketcan::CanFrame::Error(
                CanErrorFrame::new_error(libc::CAN_ERR_BUSOFF, &[]).unwrap(),
            ),
            socketcan::CanFrame::Error(
                CanErrorFrame::new_error(libc::CAN_ERR_RESTARTED, &[]).unwrap(),
            ),
            data(
                StandardId::new(0x581).unwrap(),
                &[0x60, 0x17, 0x10, 0, 0, 0, 0, 0],
            ),
        ];
        let sorted: Vec<Received> = stream.iter().map(classify).collect();
        assert_eq!(
            sorted,
            [
                Received::Data(CanFrame::new(0x281, &[0x50, 0x58, 0, 0, 0x10, 0, 0, 0]).unwrap()),
                Received::Foreign,
                Received::Foreign,
                Received::Foreign,
                Received::BusOff,
                Received::Error,
                Received::Data(CanFrame::new(0x581, &[0x60, 0x17, 0x10, 0, 0, 0, 0, 0]).unwrap()),
            ]
        );
    }

    #[test]
    fn ignored_frames_are_counted_and_bus_off_latches_until_recovered() {
        let mut tally = Tally::default();
        let frame = CanFrame::new(0x701, &[5]).unwrap();
        let stream = [
            Received::Foreign,
            Received::Error,
            Received::BusOff,
            Received::Data(frame),
            Received::BusOff,
            Received::Foreign,
        ];
        let taken: Vec<CanFrame> = stream.into_iter().filter_map(|r| tally.take(r)).collect();
        assert_eq!(taken, [frame]);
        assert_eq!(
            tally.counters,
            Counters {
                foreign_frames: 2,
                error_frames: 1,
                bus_offs: 1,
                ..Counters::default()
            }
        );
        assert!(tally.bus_off);
    }

    #[test]
    fn a_paced_bus_is_busy_for_each_frame_by_its_exact_length() {
        // 500 kbit/s: 2 µs a bit. A bus busy for another second: each frame adds its length.
        let mut pacer = Pacer::new(500_000);
        let busy = Instant::now() + Duration::from_secs(1);
        pacer.free_at = busy;
        let sync = CanFrame::new(0x80, &[]).unwrap();
        let point = CanFrame::new(0x301, &[0x51, 0x50, 3, 0, 0x10, 0x27, 0, 0]).unwrap();
        pacer.sent(&sync);
        pacer.sent(&point);
        let bits = exact_bits_on_wire(&sync) + exact_bits_on_wire(&point);
        assert_eq!(
            pacer.free_at - busy,
            Duration::from_micros(2 * u64::from(bits))
        );
        // A SYNC is 47 bits and some stuffing; an 8-byte frame under 135 bits.
        assert!((47..=55).contains(&exact_bits_on_wire(&sync)));
        assert!((111..=135).contains(&exact_bits_on_wire(&point)));
    }

    #[test]
    fn opening_without_kernel_support_or_interface_explains_what_to_do() {
        // This kernel may have no CAN support (EAFNOSUPPORT); either way the error says why.
        let Err(error) = SocketCan::open("armgate-no-such-can", None) else {
            panic!("an interface that does not exist opened");
        };
        let text = explain("armgate-no-such-can", &error);
        assert!(text.contains("armgate-no-such-can"), "{text}");
        assert!(
            text.contains("no CAN support") || text.contains("no such network interface"),
            "{text}"
        );
    }
}
