//! Linux SocketCAN as the drive manager's [`CanBus`]: a raw CAN socket on an interface such as
//! `can0` (for example a PCAN-USB adapter through the kernel's `peak_usb` driver) or `vcan0`.
//!
//! The few system calls are made through `libc`; the frame and address layouts are the kernel's
//! (`linux/can.h`), declared here so that nothing depends on libc's private padding fields.
// System calls on a file descriptor this module owns; every buffer passed is a local of the
// exact size given.
#![allow(unsafe_code)]

use std::ffi::CString;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};

use armgate_core::drives::{BusState, CanBus, TxError};
use armgate_protocol::can::CanFrame;

/// `struct can_frame` (classic CAN, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Default)]
struct RawFrame {
    can_id: u32,
    len: u8,
    pad: u8,
    res0: u8,
    len8_dlc: u8,
    data: [u8; 8],
}

/// `struct sockaddr_can` (24 bytes on Linux).
#[repr(C)]
struct SockAddrCan {
    family: libc::sa_family_t,
    ifindex: libc::c_int,
    addr: [u8; 16],
}

/// A raw CAN socket bound to one interface, non-blocking.
pub struct SocketCan {
    fd: OwnedFd,
    bus_off: bool,
}

impl SocketCan {
    /// Opens interface `name`. Fails with `EAFNOSUPPORT` where the kernel has no CAN support
    /// and `ENODEV` where the interface does not exist.
    pub fn open(name: &str) -> io::Result<Self> {
        let fd = unsafe {
            libc::socket(
                libc::PF_CAN,
                libc::SOCK_RAW | libc::SOCK_NONBLOCK,
                libc::CAN_RAW,
            )
        };
        if fd < 0 {
            return Err(io::Error::last_os_error());
        }
        let fd = unsafe { OwnedFd::from_raw_fd(fd) };
        let c_name = CString::new(name).map_err(|_| io::Error::from_raw_os_error(libc::ENODEV))?;
        let index = unsafe { libc::if_nametoindex(c_name.as_ptr()) };
        if index == 0 {
            return Err(io::Error::from_raw_os_error(libc::ENODEV));
        }
        // Ask for bus-off error frames, so that `state` can report it.
        let filter: u32 = libc::CAN_ERR_BUSOFF;
        unsafe {
            libc::setsockopt(
                fd.as_raw_fd(),
                libc::SOL_CAN_RAW,
                libc::CAN_RAW_ERR_FILTER,
                (&raw const filter).cast(),
                size_of::<u32>() as libc::socklen_t,
            )
        };
        let addr = SockAddrCan {
            family: libc::AF_CAN as libc::sa_family_t,
            ifindex: index as libc::c_int,
            addr: [0; 16],
        };
        let bound = unsafe {
            libc::bind(
                fd.as_raw_fd(),
                (&raw const addr).cast(),
                size_of::<SockAddrCan>() as libc::socklen_t,
            )
        };
        if bound < 0 {
            return Err(io::Error::last_os_error());
        }
        Ok(Self { fd, bus_off: false })
    }
}

impl CanBus for SocketCan {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        if self.bus_off {
            return Err(TxError::BusOff);
        }
        let mut raw = RawFrame {
            can_id: u32::from(frame.id()),
            len: frame.dlc(),
            ..RawFrame::default()
        };
        raw.data = *frame.raw_data();
        let n = unsafe {
            libc::write(
                self.fd.as_raw_fd(),
                (&raw const raw).cast(),
                size_of::<RawFrame>(),
            )
        };
        if n == size_of::<RawFrame>() as isize {
            return Ok(());
        }
        match io::Error::last_os_error().raw_os_error() {
            Some(libc::ENETDOWN) => {
                self.bus_off = true;
                Err(TxError::BusOff)
            }
            _ => Err(TxError::QueueFull),
        }
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        // Bounded: a socket delivers at most what the bus carried since the last cycle, and
        // error frames are skipped a bounded number of times.
        for _ in 0..64 {
            let mut raw = RawFrame::default();
            let n = unsafe {
                libc::read(
                    self.fd.as_raw_fd(),
                    (&raw mut raw).cast(),
                    size_of::<RawFrame>(),
                )
            };
            if n != size_of::<RawFrame>() as isize {
                return None;
            }
            if raw.can_id & libc::CAN_ERR_FLAG != 0 {
                self.bus_off |= raw.can_id & libc::CAN_ERR_BUSOFF != 0;
                continue;
            }
            let id = u16::try_from(raw.can_id & libc::CAN_SFF_MASK).ok()?;
            let data = raw.data.get(..usize::from(raw.len.min(8)))?;
            return CanFrame::new(id, data).ok();
        }
        None
    }

    fn state(&self) -> BusState {
        BusState::from_bus_off(self.bus_off)
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
