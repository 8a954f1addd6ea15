//! The simulated Whistle's binary interpreter: one command runs, one waits, a third arriving
//! meanwhile replaces the waiting one (spec §6.5); what each command does to the drive.

use super::*;

impl SimWhistle {
    /// An interpreter command arrives: it runs at once if the interpreter is idle, else waits;
    /// a waiting command is replaced, and lost.
    pub(super) fn command(&mut self, request: Request) {
        self.commands_received = self.commands_received.wrapping_add(1);
        if nth(self.commands_received, self.faults.drop_every_command) {
            return;
        }
        if self.running.is_none() {
            let done = self.now + seconds_to_ns(self.config.interpreter_time).max(1);
            self.running = Some((request, done));
        } else if self.waiting.replace(request).is_some() {
            self.stats.commands_lost += 1;
            self.inject(DriveEmergency::MessageLost);
        }
    }

    /// The running command completes now: its effect, its reply, and the next command starts.
    pub(super) fn complete(&mut self, request: Request) {
        let reply = self.execute(request);
        self.replies_made = self.replies_made.wrapping_add(1);
        if !nth(self.replies_made, self.faults.drop_every_reply) {
            let ready = self.now + seconds_to_ns(self.faults.reply_delay);
            self.emit(reply.to_frame(self.config.node), ready);
        }
        self.running = self.waiting.take().map(|next| {
            let done = self.now + seconds_to_ns(self.config.interpreter_time).max(1);
            (next, done)
        });
    }

    /// Executes an interpreter command.
    pub(super) fn execute(&mut self, request: Request) -> Reply {
        let (command, index, assigned) = match request {
            Request::Query { command, index } => (command, index, None),
            Request::Set {
                command,
                index,
                value,
            } => (command, index, Some(value)),
        };
        let answer = |value: i32| Reply::Value {
            command,
            index,
            value: Value::Int(value),
        };
        let refuse = |code: u8| Reply::Error {
            command,
            index,
            code,
        };
        if self.faults.error_on == Some(command) {
            return refuse(error_code::INJECTED);
        }
        let value = match assigned {
            Some(Value::Int(v)) => Some(v),
            Some(Value::Float(_)) => return refuse(error_code::BAD_VALUE),
            None => None,
        };
        let i = index.get();
        let result = match (command, value) {
            (Mnemonic::UM, None) => Ok(self.unit_mode),
            (Mnemonic::UM, Some(_)) if self.motor_on => Err(error_code::MOTOR_ON),
            (Mnemonic::UM, Some(mode @ 1..=5)) => {
                if !self.faults.stuck_unit_mode {
                    self.unit_mode = mode;
                }
                Ok(mode)
            }
            (Mnemonic::MO, None) => Ok(i32::from(self.motor_on)),
            (Mnemonic::MO, Some(on @ 0..=1)) => {
                self.motor_on = on == 1;
                self.reference = self.servo.position();
                self.table.stop();
                Ok(on)
            }
            (Mnemonic::PX, None) => Ok(self.position()),
            (Mnemonic::VX, None) => Ok(round_i32(self.servo.velocity())),
            (Mnemonic::TI, None) if i == 1 => Ok(round_i32(self.servo.temperature())),
            (Mnemonic::TI, None) => Err(error_code::BAD_INDEX),
            (Mnemonic::PT, None) => Ok(i32::from(self.table.read_index())),
            (Mnemonic::PT, Some(k)) if self.table.arm(k) => Ok(k),
            (Mnemonic::PT, Some(_)) => Err(error_code::BAD_INDEX),
            (Mnemonic::MP, None) => self.table.mp(i).ok_or(error_code::BAD_INDEX),
            (Mnemonic::MP, Some(v)) if self.table.set_mp(i, v) => Ok(v),
            (Mnemonic::MP, Some(_)) => Err(error_code::BAD_INDEX),
            (Mnemonic::QP, None) => self.table.qp(i).ok_or(error_code::BAD_INDEX),
            (Mnemonic::QP, Some(v)) => match self.table.write(i, v, self.now) {
                Ok(()) => Ok(v),
                Err(WriteError::BadIndex) => Err(error_code::BAD_INDEX),
                Err(WriteError::QueueFull) => {
                    self.stats.overflows += 1;
                    self.inject(DriveEmergency::QueueFull { index: i });
                    Ok(v)
                }
            },
            (Mnemonic::BG, None) if !self.motor_on => Err(error_code::MOTOR_OFF),
            (Mnemonic::BG, None) if self.unit_mode != POSITION_MODE => Err(error_code::BAD_SETUP),
            (Mnemonic::BG, None) => self
                .table
                .begin(self.now)
                .map(|()| 0)
                .map_err(|_| error_code::BAD_SETUP),
            (Mnemonic::ST, None) => {
                self.table.stop();
                Ok(0)
            }
            (Mnemonic::UM | Mnemonic::MO, Some(_)) => Err(error_code::BAD_VALUE),
            (Mnemonic::PX | Mnemonic::VX | Mnemonic::TI | Mnemonic::BG | Mnemonic::ST, _) => {
                Err(error_code::BAD_ACCESS)
            }
            _ => Err(error_code::BAD_COMMAND),
        };
        match result {
            Ok(v) => answer(v),
            Err(code) => refuse(code),
        }
    }
}
