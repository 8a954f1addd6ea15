//! The session report: who holds the arm, the client watchdog, and what could not be sent —
//! the reply to `SQ` index 3.

use core::net::{Ipv4Addr, SocketAddrV4};

use super::{Command, DecodeError, Reply};

/// `SQ` index of the session report.
pub const SESSION_INDEX: u8 = 3;

/// Who holds the arm, as the asking client sees it (f0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Holder {
    /// Nobody: the next motion, mode, power or recalibration request takes control.
    Nobody = 0,
    /// The client that asked.
    You = 1,
    /// Another client.
    Other = 2,
}

/// The session, as `SQ` index 3 reports it (`QS`, index 3):
/// f0 [`Holder`], f1/f2 the holder's IPv4 address (upper and lower 16 bits; 0 for none or
/// IPv6), f3 its port, f4 the client watchdog (ms, 0 off), f5 replies and notices the
/// controller could not send since it started, f6 the clients it knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SessionReport {
    /// Who holds the arm.
    pub holder: Holder,
    /// The holder's address, if it is an IPv4 one.
    pub address: Option<SocketAddrV4>,
    /// The client watchdog (ms), 0 when off.
    pub watchdog_ms: u32,
    /// Replies and notices dropped since the start (full queues, destinations that did not
    /// resolve).
    pub send_drops: u32,
    /// Clients in the controller's table.
    pub clients: u8,
}

impl SessionReport {
    /// The reply, index 3. (Counts above 2²⁴ round; the 16-bit halves are exact.)
    pub fn to_reply(&self) -> Reply {
        let ip = self.address.map_or(0, |a| u32::from(*a.ip()));
        let values = [
            f32::from(self.holder as u8),
            f32::from((ip >> 16) as u16),
            f32::from(ip as u16),
            f32::from(self.address.map_or(0, |a| a.port())),
            self.watchdog_ms as f32,
            self.send_drops as f32,
            f32::from(self.clients),
        ];
        Reply {
            command: Command::Status,
            values,
            index: SESSION_INDEX,
        }
    }

    /// Decodes a `QS` index-3 reply (on the client side).
    pub fn from_reply(reply: &Reply) -> Result<Self, DecodeError> {
        if reply.command != Command::Status || reply.index != SESSION_INDEX {
            return Err(DecodeError::WrongCommand);
        }
        let [holder, high, low, port, watchdog, drops, clients] = reply.values;
        let holder = [Holder::Nobody, Holder::You, Holder::Other]
            .into_iter()
            .find(|h| f32::from(*h as u8) == holder)
            .ok_or(DecodeError::BadField)?;
        let ip = (u32::from(high as u16) << 16) | u32::from(low as u16);
        Ok(Self {
            holder,
            address: (ip != 0).then(|| SocketAddrV4::new(Ipv4Addr::from(ip), port as u16)),
            watchdog_ms: watchdog as u32,
            send_drops: drops as u32,
            clients: clients as u8,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_report_round_trips_with_known_bytes() {
        let report = SessionReport {
            holder: Holder::Other,
            address: Some("192.168.1.2:40001".parse().unwrap()),
            watchdog_ms: 500,
            send_drops: 39,
            clients: 2,
        };
        let reply = report.to_reply();
        assert_eq!(
            reply.values,
            [2.0, 49320.0, 258.0, 40001.0, 500.0, 39.0, 2.0]
        );
        let bytes = reply.to_bytes();
        assert_eq!((&bytes[..2], bytes[30]), (&b"QS"[..], 3));
        assert_eq!(SessionReport::from_reply(&reply), Ok(report));
        let nobody = SessionReport {
            holder: Holder::Nobody,
            address: None,
            watchdog_ms: 0,
            send_drops: 0,
            clients: 0,
        };
        assert_eq!(SessionReport::from_reply(&nobody.to_reply()), Ok(nobody));
    }
}
