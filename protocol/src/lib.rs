//! armgate wire formats: the client's UDP messages and the CAN frames to the Elmo drives.
//!
//! Both follow the pattern of smoltcp's `wire` module: bytes are decoded into validated
//! high-level values (`parse`), and values are encoded back into bytes (`emit`, `to_frame`).
//! Nothing here allocates, panics or judges meaning (a NaN coordinate is a valid float on the
//! wire; rejecting it is the core's job).
//!
//! # Client messages ([`client`])
//!
//! Every UDP datagram, in both directions, is 31 bytes:
//!
//! | Bytes  | Content                                                   |
//! |--------|-----------------------------------------------------------|
//! | 0–1    | two ASCII command characters, case-sensitive (`GT`, `jV`)  |
//! | 2–29   | seven IEEE-754 binary32 values f0..f6, little-endian       |
//! | 30     | index, unsigned                                           |
//!
//! A reply carries the request's characters reversed (`GT` → `TG`). Errors and warnings are
//! instead an ASCII text from byte 0 (`ER20 Cmd BG busy`: code, command, reason),
//! NUL-terminated and zero-filled.
//!
//! # CAN frames ([`can`])
//!
//! Standard 11-bit identifiers; the COB-ID is a CANopen function code plus the node ID (1..=127).
//! The drives are commanded through the Elmo SimplIQ binary interpreter, carried in RPDO2
//! (`0x300 + node`) and answered in TPDO2 (`0x280 + node`): two command letters, a 14-bit array
//! index, a type/error byte and an optional 32-bit value. The CANopen services the controller
//! also needs are NMT commands, emergency messages, heartbeats and expedited SDO transfers.
#![cfg_attr(not(any(test, feature = "std")), no_std)]

pub mod can;
pub mod client;
