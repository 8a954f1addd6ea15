//! Unsolicited warnings to the client (spec §2.6), with a rate limit that cannot skip.

use armgate_protocol::client::{Hold, Notice, Text};
use heapless::Deque;

use crate::motion::Events;

/// While a condition lasts, its warning is repeated at most this often (s).
pub const NOTICE_INTERVAL: f64 = 0.2;
/// Warnings waiting to be sent at most; more are dropped and counted.
pub const NOTICE_CAPACITY: usize = 8;

/// Turns per-tick conditions into client warnings: on the first occurrence, then at most once
/// per [`NOTICE_INTERVAL`] while the condition lasts. (The seed's mod-11 counters could skip a
/// message when two events fell between handler cycles, spec §9 item 15.) A drive fault is sent
/// once, when it appears.
#[derive(Clone, Debug)]
pub struct NoticeRelay {
    channels: [Channel; 4],
    fault_reported: bool,
    drive_notice_reported: bool,
    /// The stream's hold last told (a new cause is told once, when it begins).
    hold: Option<Hold>,
    outbox: Deque<Text, NOTICE_CAPACITY>,
    dropped: u32,
}

#[derive(Clone, Copy, Debug)]
struct Channel {
    notice: Notice,
    active: bool,
    last_sent: f64,
}

impl Default for NoticeRelay {
    fn default() -> Self {
        let channel = |notice| Channel {
            notice,
            active: false,
            last_sent: f64::NEG_INFINITY,
        };
        Self {
            channels: [
                channel(Notice::WorkspaceLimit),
                channel(Notice::JointLimit),
                channel(Notice::IkDivergence),
                channel(Notice::ViaPointMissed),
            ],
            fault_reported: false,
            drive_notice_reported: false,
            hold: None,
            outbox: Deque::new(),
            dropped: 0,
        }
    }
}

impl NoticeRelay {
    /// Takes note of one tick's events at time `now` (s).
    pub fn observe(&mut self, now: f64, events: &Events) {
        let raised = [
            events.workspace_limit,
            events.joint_limit,
            events.ik_divergence,
            events.sequence_aborted,
        ];
        for (channel, raised) in self.channels.iter_mut().zip(raised) {
            if raised && (!channel.active || now - channel.last_sent >= NOTICE_INTERVAL) {
                channel.last_sent = now;
                if self.outbox.push_back(channel.notice.text()).is_err() {
                    self.dropped = self.dropped.saturating_add(1);
                }
            }
            channel.active = raised;
        }
        if let Some(lag) = events.following_error {
            self.announce(Notice::FollowingError(lag).text());
        }
        if let Some(hit) = events.collision {
            self.announce(Notice::Collision(hit).text());
        }
        if events.hold != self.hold {
            self.hold = events.hold;
            if let Some(hold) = events.hold
                && self.outbox.push_back(Notice::Held(hold).text()).is_err()
            {
                self.dropped = self.dropped.saturating_add(1);
            }
        }
    }

    /// Takes note of whether the drives are faulted; `text` is asked for only when a fault
    /// appears, so a lasting fault is not formatted again every tick.
    pub fn observe_fault(&mut self, faulted: bool, text: impl FnOnce() -> Option<Text>) {
        if !faulted {
            self.fault_reported = false;
        } else if !self.fault_reported {
            self.fault_reported = true;
            if let Some(text) = text()
                && self.outbox.push_back(text).is_err()
            {
                self.dropped = self.dropped.saturating_add(1);
            }
        }
    }

    /// Takes note of the drives' lasting warning, if any: sent once, when it appears.
    pub fn observe_drive_notice(&mut self, notice: Option<Text>) {
        match notice {
            None => self.drive_notice_reported = false,
            Some(_) if self.drive_notice_reported => {}
            Some(text) => {
                self.drive_notice_reported = true;
                self.announce(text);
            }
        }
    }

    /// Sends `text` once (an event the caller reports once, such as the client watchdog's).
    pub fn announce(&mut self, text: Text) {
        if self.outbox.push_back(text).is_err() {
            self.dropped = self.dropped.saturating_add(1);
        }
    }

    /// The next warning to send, oldest first.
    pub fn pop(&mut self) -> Option<Text> {
        self.outbox.pop_front()
    }

    /// Warnings dropped because the outbox was full.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain(relay: &mut NoticeRelay) -> Vec<String> {
        core::iter::from_fn(|| relay.pop())
            .map(|t| t.as_str().to_string())
            .collect()
    }

    #[test]
    fn first_occurrence_then_at_most_every_interval() {
        let mut relay = NoticeRelay::default();
        let limit = Events {
            joint_limit: true,
            ..Events::default()
        };
        let mut sent = Vec::new();
        // A condition raised every 19.44 ms for one second.
        for k in 0..52 {
            relay.observe(k as f64 * 0.01944, &limit);
            sent.extend(drain(&mut relay).into_iter().map(|t| (k, t)));
        }
        let ticks: Vec<_> = sent.iter().map(|(k, _)| *k).collect();
        assert_eq!(ticks, vec![0, 11, 22, 33, 44]);
        assert!(sent.iter().all(|(_, t)| t == "WN12 Joint limit."));
        // The condition ends and comes back: reported at once.
        relay.observe(1.02, &Events::default());
        relay.observe(1.04, &limit);
        assert_eq!(drain(&mut relay), vec!["WN12 Joint limit."]);
    }

    #[test]
    fn a_fault_is_reported_once_per_appearance() {
        let mut relay = NoticeRelay::default();
        let fault = Notice::ArmDidNotStart(armgate_protocol::client::DriveStatus::Off).text();
        let mut formatted = 0;
        for _ in 0..10 {
            relay.observe_fault(true, || {
                formatted += 1;
                Some(fault)
            });
        }
        assert_eq!(drain(&mut relay).len(), 1);
        assert_eq!(formatted, 1, "a lasting fault is formatted once");
        relay.observe_fault(false, || None);
        relay.observe_fault(true, || Some(fault));
        assert_eq!(drain(&mut relay).len(), 1);
    }

    #[test]
    fn a_full_outbox_drops_and_counts() {
        let mut relay = NoticeRelay::default();
        let all = Events {
            workspace_limit: true,
            joint_limit: true,
            ik_divergence: true,
            sequence_aborted: true,
            ..Events::default()
        };
        for k in 0..3 {
            relay.observe(k as f64, &all);
        }
        assert_eq!(relay.dropped(), 4);
        assert_eq!(drain(&mut relay).len(), 8);
    }

    #[test]
    fn a_hold_is_told_once_per_cause() {
        use armgate_protocol::client::{JointBound, PathPoint};
        let mut relay = NoticeRelay::default();
        let at_limit = Hold::JointLimit(JointBound::new(5, true, 2.967, PathPoint::Goal));
        let mut texts = Vec::new();
        for (k, hold) in [
            None,
            Some(at_limit),
            Some(at_limit),
            Some(Hold::Workspace),
            None,
        ]
        .into_iter()
        .enumerate()
        {
            let events = Events {
                hold,
                ..Events::default()
            };
            relay.observe(k as f64, &events);
            texts.extend(drain(&mut relay));
        }
        assert_eq!(
            texts,
            ["WN12 j6 at limit 2.967", "WN13 Held at workspace edge."]
        );
    }
}
