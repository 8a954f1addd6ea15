//! `armgate-calibrate`: fit a robot file to measured tool positions, or plan the poses to
//! measure. `armgate calibrate …` runs this binary. See `docs/calibration.md`.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use armgate_calibrate::calibration::{self, Calibration, Validation};
use armgate_calibrate::model::{self, FitSet};
use armgate_calibrate::{measurements, plan, robot_file, sim};
use armgate_core::config::{ValidRobot, load_file};
use clap::{Args, Parser, Subcommand, ValueEnum};

/// Kinematic calibration: fit a robot file's geometry to measured tool positions.
#[derive(Debug, Parser)]
#[command(
    name = "armgate-calibrate",
    // Run as `armgate calibrate` (the client passes the arguments on): its usage says so.
    bin_name = "armgate calibrate",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    after_help = "Example: armgate calibrate --robot robots/ur5.toml --measurements m.csv --out robots/ur5-calibrated.toml"
)]
struct Cli {
    #[command(flatten)]
    fit: FitArgs,
    #[command(subcommand)]
    command: Option<Cmd>,
}

/// Fit a robot file to measurements.
#[derive(Debug, Args)]
struct FitArgs {
    /// The robot file to calibrate.
    #[arg(long, required = true)]
    robot: Option<PathBuf>,
    /// Measured poses: `q1,…,qn,x,y,z[,weight]` per line (rad, m).
    #[arg(long, required = true)]
    measurements: Option<PathBuf>,
    /// Poses to check the result on (same format); without them, 5-fold cross-validation.
    #[arg(long)]
    held_out: Option<PathBuf>,
    /// Where to write the calibrated robot file.
    #[arg(long, required = true)]
    out: Option<PathBuf>,
    /// Which parameters to fit.
    #[arg(long, value_enum, default_value_t = FitSet::All)]
    fit: FitSet,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Propose joint configurations to measure: reachable, within the joint limits and the
    /// workspace, chosen to maximise the observability of the parameters.
    Plan {
        /// The robot file.
        #[arg(long)]
        robot: PathBuf,
        /// How many poses.
        #[arg(long, default_value_t = 50)]
        poses: usize,
        /// How many random candidates to choose from.
        #[arg(long, default_value_t = 1000)]
        candidates: usize,
        /// Seed of the random candidates.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Which parameters the poses should determine.
        #[arg(long, value_enum, default_value_t = FitSet::All)]
        fit: FitSet,
        /// Write the poses here (CSV, one per line) instead of to standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Simulate measurements: the tool positions of a "true" robot file at the given poses,
    /// with Gaussian noise (to try calibration without an instrument).
    Simulate {
        /// The robot file of the simulated real arm.
        #[arg(long)]
        truth: PathBuf,
        /// Joint configurations (CSV, as `plan` writes them).
        #[arg(long)]
        poses: PathBuf,
        /// Noise standard deviation per coordinate (mm).
        #[arg(long, default_value_t = 0.05)]
        noise_mm: f64,
        /// Seed of the noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// First perturb the truth with random errors of typical size (offsets ±0.5°, lengths,
        /// base and tool ±1 mm, twists ±0.05°) drawn with this seed.
        #[arg(long)]
        perturb: Option<u64>,
        /// Where to write the measurements.
        #[arg(long)]
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Cmd::Plan {
            robot,
            poses,
            candidates,
            seed,
            fit,
            out,
        }) => run_plan(&robot, poses, candidates, seed, fit, out.as_deref()),
        Some(Cmd::Simulate {
            truth,
            poses,
            noise_mm,
            seed,
            perturb,
            out,
        }) => run_simulate(&truth, &poses, noise_mm * 1e-3, seed, perturb, &out),
        None => run_fit(&cli.fit),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("armgate-calibrate: {e}");
            ExitCode::from(2)
        }
    }
}

/// Prints to standard output; a closed pipe (`| head`) is not an error.
fn say(text: &str) {
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()).into())
}

fn robot(path: &Path) -> Result<ValidRobot> {
    load_file(path).map_err(|e| format!("{}: {e}", path.display()).into())
}

fn run_fit(args: &FitArgs) -> Result<()> {
    let (Some(robot_path), Some(data), Some(out)) = (&args.robot, &args.measurements, &args.out)
    else {
        return Err("--robot, --measurements and --out are required".into());
    };
    let config = robot(robot_path)?;
    let dof = config.dof();
    let measured =
        measurements::parse(&read(data)?, dof).map_err(|e| format!("{}: {e}", data.display()))?;
    let held_out = match &args.held_out {
        Some(path) => measurements::parse(&read(path)?, dof)
            .map_err(|e| format!("{}: {e}", path.display()))?,
        None => Vec::new(),
    };
    let result = calibration::calibrate(&config, &measured, &held_out, args.fit)?;
    let report = result.report();
    say(&report);
    let comment = comment_block(&result, args, &report);
    let text = robot_file::edit(
        &read(robot_path)?,
        &result.fit.geometry,
        &result.fit.params,
        &comment,
    )?;
    armgate_core::config::parse_toml(&text)
        .map_err(|e| format!("the calibrated file does not load ({e}); not written"))?;
    std::fs::write(out, text).map_err(|e| format!("{}: {e}", out.display()))?;
    say(&format!("\nwrote {}\n", out.display()));
    Ok(())
}

/// The comment block of the calibrated file: where the data came from, then the report.
fn comment_block(result: &Calibration, args: &FitArgs, report: &str) -> String {
    let show = |p: &Option<PathBuf>| p.as_deref().unwrap_or(Path::new("?")).display().to_string();
    let check = match &result.validation {
        Validation::HeldOut { .. } => format!("the held-out poses {}", show(&args.held_out)),
        Validation::CrossValidation { folds, .. } => format!("{folds}-fold cross-validation"),
        Validation::Unavailable => "nothing (too few poses)".to_string(),
    };
    let fit = args
        .fit
        .to_possible_value()
        .map(|v| v.get_name().to_string());
    format!(
        "Calibrated by armgate-calibrate (--fit {}) from {} with the measurements {} ({} \
         poses); checked by {check}.\nOnly the fitted values below differ from {}.\n\n{report}",
        fit.unwrap_or_default(),
        show(&args.robot),
        show(&args.measurements),
        result.before.count,
        show(&args.robot),
    )
}

fn run_plan(
    robot_path: &Path,
    poses: usize,
    candidates: usize,
    seed: u64,
    fit: FitSet,
    out: Option<&Path>,
) -> Result<()> {
    if poses == 0 {
        return Err("--poses must be at least 1".into());
    }
    let config = robot(robot_path)?;
    let plan = plan::plan(&config, fit, poses, candidates, seed)?;
    let a = &plan.analysis;
    let mut text = format!(
        "# {} poses for {} chosen from {} random candidates (seed {seed}) for observability\n\
         # O1 {:.4} m, condition number {:.1}; {} parameters identifiable; not identifiable: {}\n\
         # measure the tool position at each and append x,y,z (m) to its line\n",
        plan.poses.len(),
        robot_path.display(),
        plan.candidates,
        a.observability,
        a.condition,
        a.identified.len(),
        model::list(&a.unidentifiable)
    );
    text += &measurements::format_poses(&plan.poses, config.dof());
    match out {
        Some(path) => {
            std::fs::write(path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
            eprintln!(
                "wrote {} poses to {} (O1 {:.4} m, condition number {:.1})",
                plan.poses.len(),
                path.display(),
                a.observability,
                a.condition
            );
        }
        None => say(&text),
    }
    Ok(())
}

fn run_simulate(
    truth: &Path,
    poses: &Path,
    noise: f64,
    seed: u64,
    perturb: Option<u64>,
    out: &Path,
) -> Result<()> {
    let mut config = robot(truth)?;
    if let Some(seed) = perturb {
        config = sim::perturb(&config, &sim::Errors::TYPICAL, seed)?;
    }
    let poses = measurements::parse_poses(&read(poses)?, config.dof())
        .map_err(|e| format!("{}: {e}", poses.display()))?;
    let measured = sim::measure(&config, &poses, noise, seed);
    std::fs::write(out, measurements::format(&measured, config.dof()))
        .map_err(|e| format!("{}: {e}", out.display()))?;
    eprintln!(
        "wrote {} simulated measurements to {}",
        measured.len(),
        out.display()
    );
    Ok(())
}
