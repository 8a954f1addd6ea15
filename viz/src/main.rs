//! `armgate-viz`: the URDF of a robot file, recordings of a running controller, and the plot
//! of a recording's minimum distances (`armgate urdf` and `armgate record` run it). See
//! docs/visualisation.md.

mod record;

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use armgate_core::MAX_JOINTS;
use armgate_core::config::{ValidRobot, load_file};
use armgate_core::kinematics::Chain;
use armgate_core::math::Frame;
use armgate_core::rng::SplitMix64;
use armgate_viz::body::{self, BodyModel};
use armgate_viz::clearance_plot;
use armgate_viz::urdf;
use clap::{Parser, Subcommand};
use serde_json::json;

/// See the arm: URDF export and MCAP recordings for 3-D viewers such as Foxglove.
#[derive(Debug, Parser)]
// Run as `armgate urdf` and `armgate record` (the client passes the arguments on): their usage
// says so.
#[command(name = "armgate-viz", bin_name = "armgate", version)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Write the URDF of a robot file: its DH chain (with Hayati β), [base], tool, joint
    /// types, limits and speed limits, simple link geometry, and the workspace's exclusion
    /// boxes as fixed links. Every link frame is the frame armgate's kinematics computes.
    #[command(after_help = "Example: armgate urdf robots/ur5.toml --out ur5.urdf")]
    Urdf {
        /// The robot file (TOML; docs/robot-file.md).
        robot: PathBuf,
        /// Write the URDF here instead of to standard output.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
        /// Also write armgate's frames of every link at random joint vectors within the
        /// limits (CSV), for the independent check in python/tests/test_urdf.py.
        #[arg(long, value_name = "FILE", hide = true)]
        fk_csv: Option<PathBuf>,
        /// Also write the body's capsules (core's collision model) placed in the world at
        /// random joint vectors within the limits (JSON), for the same check.
        #[arg(long, value_name = "FILE", hide = true)]
        body_json: Option<PathBuf>,
        /// How many random joint vectors --fk-csv and --body-json hold.
        #[arg(long, default_value_t = 1000, hide = true)]
        samples: usize,
    },
    /// Record a running controller (the firmware, or armgate-sim) into an MCAP file for
    /// Foxglove, from what the protocol reads: jP and PS at --rate, SQ once a second, and every
    /// notice. Stop with Ctrl-C or SIGTERM (the file is completed) or --duration.
    #[command(
        after_help = "Example: armgate record run.mcap --robot robots/ranger-mk1.toml --duration 5"
    )]
    Record(record::RecordArgs),
    /// Plot the minimum distances of a recording (armgate-sim --mcap, armgate record) over
    /// time as an SVG: the least gap to the exclusion boxes, inside the bounds and between
    /// links at every recorded pose (its /clearance channel), the margin, and the warnings
    /// and errors as markers.
    // The client does not pass `clearance` on: its usage names this tool.
    #[command(
        override_usage = "armgate-viz clearance [OPTIONS] <RECORDING>",
        after_help = "Example: armgate-viz clearance run.mcap --out clearance.svg"
    )]
    Clearance {
        /// The MCAP recording.
        recording: PathBuf,
        /// The SVG to write (default: the recording's name with `.clearance.svg`).
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Cmd::Urdf {
            robot,
            out,
            fk_csv,
            body_json,
            samples,
        } => write_urdf(
            &robot,
            out.as_deref(),
            [fk_csv.as_deref(), body_json.as_deref()],
            samples,
        ),
        Cmd::Record(args) => load(args.robot()).and_then(|robot| record::run(&args, &robot)),
        Cmd::Clearance { recording, out } => plot_clearance(&recording, out),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("armgate-viz: {e}");
            ExitCode::from(2)
        }
    }
}

fn plot_clearance(recording: &Path, out: Option<PathBuf>) -> Result<(), String> {
    let run = clearance_plot::read(recording)?;
    let out = out.unwrap_or_else(|| recording.with_extension("clearance.svg"));
    let title = format!("recording {}", recording.display());
    armgate_plot::write_svg(&out, &clearance_plot::figure(&run, &title))
        .map_err(|e| format!("{}: {e}", out.display()))?;
    println!("{}", out.display());
    Ok(())
}

fn load(path: &Path) -> Result<ValidRobot, String> {
    load_file(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The URDF, and the hidden checks' tables: `[--fk-csv, --body-json]`.
fn write_urdf(
    robot: &Path,
    out: Option<&Path>,
    [fk_csv, body_json]: [Option<&Path>; 2],
    samples: usize,
) -> Result<(), String> {
    let config = load(robot)?;
    let text = urdf::urdf(&config);
    match out {
        Some(path) => std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?,
        None => std::io::stdout()
            .write_all(text.as_bytes())
            .map_err(|e| e.to_string())?,
    }
    let tables = [
        fk_csv.map(|path| (path, fk_table(&config, samples))),
        body_json.map(|path| (path, body_table(&config, samples))),
    ];
    for (path, text) in tables.into_iter().flatten() {
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

/// `{"capsules": [{"link", "urdf_link", "radius"}..], "poses": [{"q", "ends": [[a, b]..]}..]}`:
/// the body's capsules (core's order; `capsule_K` of the URDF is the K-th) and, at random
/// joint vectors (seed 2), their ends in the world as the control tick places them.
fn body_table(config: &ValidRobot, samples: usize) -> String {
    let model = BodyModel::new(config);
    let chain = Chain::new(config);
    let capsules: Vec<_> = body::link_capsules(config)
        .iter()
        .map(|c| {
            let urdf_link = match usize::from(c.link) {
                0 => urdf::BASE.to_owned(),
                l => urdf::link_name(l - 1),
            };
            json!({ "link": c.link, "urdf_link": urdf_link, "radius": c.radius })
        })
        .collect();
    let mut rng = SplitMix64::new(2);
    let poses: Vec<_> = (0..samples)
        .filter_map(|_| {
            let q = chain.random_joints(&mut rng);
            let ends: Vec<_> = model
                .placed(&q)?
                .iter()
                .map(|c| {
                    let (a, b) = (c.segment.a, c.segment.b);
                    json!([[a.x, a.y, a.z], [b.x, b.y, b.z]])
                })
                .collect();
            let q: Vec<f64> = q.iter().take(chain.dof()).copied().collect();
            Some(json!({ "q": q, "ends": ends }))
        })
        .collect();
    json!({ "capsules": capsules, "poses": poses }).to_string()
}

/// `q1..qn` then, for each link of the chain and the tool, its 4×4 frame in the world (row
/// major) as armgate's FK computes it; one line per random joint vector (seed 1).
fn fk_table(config: &ValidRobot, samples: usize) -> String {
    let chain = Chain::new(config);
    let n = chain.dof();
    let mut names: Vec<String> = (0..n).map(urdf::link_name).collect();
    names.push(urdf::TOOL.to_owned());
    let mut header: Vec<String> = (1..=n).map(|k| format!("q{k}")).collect();
    for name in &names {
        header.extend((0..16).map(|k| format!("{name}.{k}")));
    }
    let mut text = header.join(",") + "\n";
    let mut rng = SplitMix64::new(1);
    for _ in 0..samples {
        let q = chain.random_joints(&mut rng);
        let mut links = [Frame::identity(); MAX_JOINTS];
        let Ok(tool) = chain.link_frames(&q, &mut links) else {
            continue;
        };
        let mut row: Vec<String> = q.iter().map(f64::to_string).collect();
        for frame in links.iter().take(n).chain([&tool]) {
            let m = frame.to_homogeneous();
            row.extend(m.transpose().iter().map(f64::to_string));
        }
        text += &row.join(",");
        text.push('\n');
    }
    text
}
