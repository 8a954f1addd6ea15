//! One minute of a 200 Hz controller's recording (ranger-mk1 moving all six joints): each
//! tick its joint states, the transforms world → base → link 1 … link 6 → tool, and the tool
//! pose; written uncompressed to MCAP twice, by armgate-viz's hand-written JSON channels
//! (what `armgate-sim --mcap` and `armgate record` write) and by the official `foxglove`
//! crate's protobuf schemas. Prints each one's CPU time (the loop is single-threaded and
//! CPU-bound; the SDK's writer runs in the logging thread too) and bytes per second of
//! recording.

use std::path::Path;
use std::time::Instant;

use armgate_core::config::load_file;
use armgate_core::kinematics::Chain;
use armgate_core::math::Frame;
use armgate_viz::foxglove::{Topic, frame_transforms, joint_states, nanos, pose_in_frame};
use armgate_viz::mcap_file::McapFile;
use armgate_viz::recorder::Sink;
use armgate_viz::translate::Message;
use foxglove::schemas::{
    FrameTransform, FrameTransforms, JointState, JointStates, Pose, PoseInFrame, Quaternion,
    Timestamp, Vector3,
};
use nalgebra::UnitQuaternion;

const RATE: f64 = 200.0;
const SECONDS: f64 = 60.0;

/// The tick's joints, transforms (parent, child, child in parent) and tool pose.
struct Tick {
    t: f64,
    q: Vec<f64>,
    transforms: Vec<(String, String, Frame)>,
    tool: Frame,
}

fn ticks(chain: &Chain) -> Vec<Tick> {
    let n = chain.dof();
    let names: Vec<String> = std::iter::once("base_link".to_owned())
        .chain((1..=n).map(|i| format!("link_{i}")))
        .chain(std::iter::once("tool".to_owned()))
        .collect();
    let mid = chain.mid_range();
    (0..(RATE * SECONDS) as usize)
        .map(|k| {
            let t = k as f64 / RATE;
            let q: Vec<f64> = (0..n)
                .map(|j| mid[j] + 0.3 * (0.2 * t + j as f64).sin())
                .collect();
            let mut links = [Frame::identity(); armgate_core::MAX_JOINTS];
            let tool = chain.link_frames(&q, &mut links).unwrap();
            let mut absolute = vec![Frame::identity()];
            absolute.extend(links[..n].iter().copied());
            absolute.push(tool);
            let mut transforms = vec![(
                "world".to_owned(),
                "base_link".to_owned(),
                Frame::identity(),
            )];
            for i in 1..absolute.len() {
                let relative = absolute[i - 1].inverse() * absolute[i];
                transforms.push((names[i - 1].clone(), names[i].clone(), relative));
            }
            Tick {
                t,
                q,
                transforms,
                tool,
            }
        })
        .collect()
}

fn hand_written(path: &Path, robot: &armgate_core::config::ValidRobot, ticks: &[Tick]) {
    let names: Vec<String> = (1..=ticks[0].q.len())
        .map(|i| format!("joint_{i}"))
        .collect();
    let mut file = McapFile::create(path, robot, "foxglove-compare").unwrap();
    for tick in ticks {
        let transforms: Vec<(&str, &str, Frame)> = tick
            .transforms
            .iter()
            .map(|(p, c, f)| (p.as_str(), c.as_str(), *f))
            .collect();
        for (topic, value) in [
            (Topic::JointStates, joint_states(tick.t, &names, &tick.q)),
            (Topic::Transforms, frame_transforms(tick.t, &transforms)),
            (Topic::ToolPose, pose_in_frame(tick.t, &tick.tool)),
        ] {
            let message = Message {
                topic,
                log_time: nanos(tick.t),
                data: serde_json::to_vec(&value).unwrap(),
            };
            file.write(&message).unwrap();
        }
    }
    file.finish().unwrap();
}

fn timestamp(t: f64) -> Option<Timestamp> {
    let ns = nanos(t);
    Some(Timestamp::new(
        (ns / 1_000_000_000) as u32,
        (ns % 1_000_000_000) as u32,
    ))
}

fn parts(frame: &Frame) -> (Option<Vector3>, Option<Quaternion>) {
    let p = frame.translation.vector;
    let q = UnitQuaternion::from_rotation_matrix(&frame.rotation);
    (
        Some(Vector3 {
            x: p.x,
            y: p.y,
            z: p.z,
        }),
        Some(Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        }),
    )
}

fn sdk(path: &Path, ticks: &[Tick]) {
    // It creates the file new.
    let _ = std::fs::remove_file(path);
    let options = foxglove::McapWriteOptions::new().compression(None);
    let writer = foxglove::McapWriter::with_options(options)
        .create_new_buffered_file(path)
        .unwrap();
    let joints = foxglove::Channel::<JointStates>::new("/joint_states");
    let tf = foxglove::Channel::<FrameTransforms>::new("/tf");
    let tool = foxglove::Channel::<PoseInFrame>::new("/tool_pose");
    for tick in ticks {
        let time = nanos(tick.t);
        joints.log_with_time(
            &JointStates {
                timestamp: timestamp(tick.t),
                joints: tick
                    .q
                    .iter()
                    .enumerate()
                    .map(|(i, q)| JointState {
                        name: format!("joint_{}", i + 1),
                        position: Some(*q),
                        ..Default::default()
                    })
                    .collect(),
            },
            time,
        );
        let transforms = tick
            .transforms
            .iter()
            .map(|(p, c, f)| {
                let (translation, rotation) = parts(f);
                FrameTransform {
                    timestamp: timestamp(tick.t),
                    parent_frame_id: p.clone(),
                    child_frame_id: c.clone(),
                    translation,
                    rotation,
                }
            })
            .collect();
        tf.log_with_time(&FrameTransforms { transforms }, time);
        let (position, orientation) = parts(&tick.tool);
        tool.log_with_time(
            &PoseInFrame {
                timestamp: timestamp(tick.t),
                frame_id: "world".to_owned(),
                pose: Some(Pose {
                    position,
                    orientation,
                }),
            },
            time,
        );
    }
    writer.close().unwrap();
}

fn main() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let robot = load_file(repo.join("robots/ranger-mk1.toml")).unwrap();
    let chain = Chain::new(&robot);
    let ticks = ticks(&chain);
    let dir = std::env::temp_dir();
    for (name, path) in [
        ("armgate-viz (JSON)", dir.join("foxglove-compare-viz.mcap")),
        (
            "foxglove 0.30 (protobuf)",
            dir.join("foxglove-compare-sdk.mcap"),
        ),
    ] {
        let mut best = f64::INFINITY;
        for _ in 0..5 {
            let started = Instant::now();
            if name.starts_with("armgate") {
                hand_written(&path, &robot, &ticks);
            } else {
                sdk(&path, &ticks);
            }
            best = best.min(started.elapsed().as_secs_f64());
        }
        let bytes = std::fs::metadata(&path).unwrap().len();
        println!(
            "{name:26} {:7.1} ms CPU per minute of recording ({:.2} % of one core), {:8.0} bytes/s",
            best * 1e3,
            best / SECONDS * 100.0,
            bytes as f64 / SECONDS
        );
        let _ = std::fs::remove_file(&path);
    }
}
