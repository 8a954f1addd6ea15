//! `armgate-sim`: the armgate core on the host.
//!
//! For now it loads a robot description, checks it, and prints the arm's kinematics at its home
//! pose (the drives' zero-count position). The UDP server, the control loop and the simulated
//! drives arrive with the protocol and CAN work.

use std::path::PathBuf;
use std::process::ExitCode;

use armgate_core::config::{RobotConfig, load_file};
use armgate_core::kinematics::Chain;
use armgate_core::math::Quaternion;
use clap::Parser;

/// Run the armgate controller core on this computer.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Robot description file (TOML), e.g. robots/ranger-mk2.toml.
    #[arg(long, default_value = "robots/ranger-mk1.toml")]
    robot: PathBuf,
}

fn main() -> ExitCode {
    let args = Args::parse();
    match load_file(&args.robot) {
        Ok(config) => {
            print_home(&config);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("armgate-sim: {}: {e}", args.robot.display());
            ExitCode::FAILURE
        }
    }
}

/// Prints the tool pose at the drives' home angles, as the PS reply and the client show it.
fn print_home(config: &RobotConfig) {
    let chain = Chain::new(config);
    let home: Vec<f64> = config.joints.iter().map(|j| j.drive.home).collect();
    let (Ok(tool), Ok(w)) = (chain.forward(&home), chain.manipulability(&home)) else {
        eprintln!("armgate-sim: home pose outside the model");
        return;
    };
    let [x, y, z] = tool.pos.to_array();
    let [qx, qy, qz, qw] = Quaternion::from_rotation(&tool.rot).to_array();
    let [roll, pitch, yaw] = tool.rot.to_rpy();
    println!(
        "{}: {} joints, control period {} s",
        config.name,
        chain.dof(),
        config.control_period
    );
    println!("home joints: {home:.4?}");
    println!("tool position (m):           {x:.4} {y:.4} {z:.4}");
    println!("tool quaternion (x y z w):   {qx:.4} {qy:.4} {qz:.4} {qw:.4}");
    println!("tool RPY (rad):              {roll:.4} {pitch:.4} {yaw:.4}");
    println!("manipulability:              {w:.6}");
}
