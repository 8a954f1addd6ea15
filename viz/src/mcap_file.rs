//! An MCAP file as a recorder's sink: one JSON channel per [`Topic`] with its schema, the URDF
//! as an attachment (`robot.urdf`) besides its `/robot_description` channel, and the robot's
//! name and the recording program in a metadata record.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter};
use std::path::Path;

use armgate_core::config::ValidRobot;
use mcap::records::MessageHeader;

use crate::foxglove::Topic;
use crate::recorder::Sink;
use crate::translate::Message;
use crate::urdf;

/// An MCAP file being written.
pub struct McapFile {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    channels: Vec<(Topic, u16)>,
    sequence: u32,
}

fn error(e: mcap::McapError) -> io::Error {
    io::Error::other(e)
}

impl McapFile {
    /// Creates `path` for a recording of `robot` made by `program` (e.g. `armgate-sim`).
    pub fn create(path: &Path, robot: &ValidRobot, program: &str) -> io::Result<Self> {
        let file = BufWriter::new(File::create(path)?);
        let mut writer = mcap::WriteOptions::new()
            .compression(None)
            .profile("")
            .library(format!("armgate-viz {}", env!("CARGO_PKG_VERSION")))
            .create(file)
            .map_err(error)?;
        let mut channels = Vec::new();
        for topic in Topic::ALL {
            let schema = writer
                .add_schema(topic.schema_name(), "jsonschema", topic.schema().as_bytes())
                .map_err(error)?;
            let id = writer
                .add_channel(schema, topic.name(), "json", &BTreeMap::new())
                .map_err(error)?;
            channels.push((topic, id));
        }
        writer
            .attach(&mcap::Attachment {
                log_time: 0,
                create_time: 0,
                name: "robot.urdf".into(),
                media_type: "application/xml".into(),
                data: urdf::urdf(robot).into_bytes().into(),
            })
            .map_err(error)?;
        writer
            .write_metadata(&mcap::records::Metadata {
                name: "armgate".into(),
                metadata: BTreeMap::from([
                    ("robot".to_owned(), robot.name.as_str().to_owned()),
                    ("program".to_owned(), program.to_owned()),
                ]),
            })
            .map_err(error)?;
        Ok(Self {
            writer: Some(writer),
            channels,
            sequence: 0,
        })
    }
}

impl Sink for McapFile {
    fn write(&mut self, message: &Message) -> io::Result<()> {
        let (Some(writer), Some((_, channel_id))) = (
            self.writer.as_mut(),
            self.channels.iter().find(|(t, _)| *t == message.topic),
        ) else {
            return Ok(());
        };
        self.sequence = self.sequence.wrapping_add(1);
        writer
            .write_to_known_channel(
                &MessageHeader {
                    channel_id: *channel_id,
                    sequence: self.sequence,
                    log_time: message.log_time,
                    publish_time: message.log_time,
                },
                &message.data,
            )
            .map_err(error)
    }

    fn flush(&mut self) -> io::Result<()> {
        match self.writer.as_mut() {
            Some(writer) => writer.flush().map_err(error),
            None => Ok(()),
        }
    }

    fn finish(&mut self) -> io::Result<()> {
        match self.writer.take() {
            Some(mut writer) => writer.finish().map(drop).map_err(error),
            None => Ok(()),
        }
    }
}
