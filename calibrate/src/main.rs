//! `armgate-calibrate`: fit a robot file to measured tool positions, or plan the poses to
//! measure. `armgate calibrate …` runs this binary. See `docs/calibration.md`.

mod measure;

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use armgate_calibrate::calibration::{self, Calibration, Validation};
use armgate_calibrate::instrument::Placement;
use armgate_calibrate::model::{self, FitSet, MeasuredIn, Param};
use armgate_calibrate::{measurements, plan, robot_file, sim, world};
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
    after_help = "Example: armgate calibrate --robot robots/ur5.toml --measurements m.csv \
--out robots/ur5-calibrated.toml --instrument-out tracker.toml --noise-mm 0.05

The measurements are in the instrument's frame; its placement is fitted with the robot and \
written apart (--instrument-out). The calibrated file keeps the robot's own base frame and its \
workspace unless --world-base. Exit status: 0 written, 1 refused (worse than nominal, a \
residual far above --noise-mm, too many outliers; --force writes anyway), 2 bad input."
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
    /// Poses to check the result on (same format, same instrument in the same place: they are
    /// predicted through the fitted instrument frame); without them, 5-fold cross-validation.
    #[arg(long)]
    held_out: Option<PathBuf>,
    /// Where to write the calibrated robot file.
    #[arg(long, required = true)]
    out: Option<PathBuf>,
    /// Where to write the instrument's fitted frame (TOML: its pose in the robot's base frame
    /// with σ; `simulate --instrument` reads it).
    #[arg(long)]
    instrument_out: Option<PathBuf>,
    /// The instrument's noise per coordinate (mm, 1σ): a fit whose residual is more than 3
    /// times this is refused, and outliers are judged against at least this.
    #[arg(long)]
    noise_mm: Option<f64>,
    /// Write the files even if the result is refused (worse than nominal, residual far above
    /// the noise, too many outliers).
    #[arg(long)]
    force: bool,
    /// Make the instrument's frame the robot file's world frame: write a `[base]` placing the
    /// robot in it, and carry the workspace into it (exclusion boxes enlarged, bounds shrunk
    /// where the turn is not a quarter turn). Default: the robot's own frames, unchanged.
    #[arg(long)]
    world_base: bool,
    /// Which parameters to fit (the instrument's frame always is, when measured in it).
    #[arg(long, value_enum, default_value_t = FitSet::All)]
    fit: FitSet,
    /// The frame of the measured positions: the instrument's own (its placement is fitted, the
    /// robot file keeps its frames), or the robot file's world frame (an instrument registered
    /// to it beforehand; joint 1's constants and the [base] are fitted).
    #[arg(long, value_enum, default_value_t = MeasuredIn::Instrument)]
    measured_in: MeasuredIn,
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
        /// The frame the positions will be measured in: an instrument's own frame is six more
        /// parameters to determine.
        #[arg(long, value_enum, default_value_t = MeasuredIn::Instrument)]
        measured_in: MeasuredIn,
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
        /// Measure with an instrument placed as this file states (the format of
        /// `--instrument-out`); without it, in the robot's world frame.
        #[arg(long)]
        instrument: Option<PathBuf>,
        /// Where to write the measurements.
        #[arg(long)]
        out: PathBuf,
    },
    /// The measuring run: move the arm (armgate-sim or a controller, `--addr`) through a
    /// plan's poses, let it settle, record the joints it reports and the instrument's reading
    /// (a prompt, a hook command, or none), and write the fit's measurement file; a pose that
    /// is refused or not reached is skipped with its reason.
    Measure(measure::MeasureArgs),
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
            measured_in,
            out,
        }) => run_plan(
            &robot,
            poses,
            candidates,
            seed,
            (fit, measured_in),
            out.as_deref(),
        ),
        Some(Cmd::Simulate {
            truth,
            poses,
            noise_mm,
            seed,
            perturb,
            instrument,
            out,
        }) => run_simulate(
            &truth,
            &poses,
            noise_mm * 1e-3,
            seed,
            perturb,
            instrument.as_deref(),
            &out,
        ),
        Some(Cmd::Measure(args)) => {
            robot(&args.robot).and_then(|config| measure::run(&args, &config).map_err(Into::into))
        }
        None => run_fit(&cli.fit),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("armgate-calibrate: {e}");
            ExitCode::from(if e.is::<Refused>() { 1 } else { 2 })
        }
    }
}

/// A calibration whose result is not to be used (`Calibration::problems`); nothing written.
#[derive(Debug)]
struct Refused(Vec<String>);

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "result refused, nothing written (--force writes it): {}",
            self.0.join("; ")
        )
    }
}

impl std::error::Error for Refused {}

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
    let noise = match args.noise_mm {
        Some(mm) if mm.is_finite() && mm > 0.0 => Some(mm * 1e-3),
        Some(_) => return Err("--noise-mm must be a positive number".into()),
        None => None,
    };
    let options = calibration::Options {
        set: args.fit,
        measured_in: args.measured_in,
        noise,
    };
    if args.world_base && args.measured_in == MeasuredIn::World {
        return Err("--world-base needs measurements in the instrument's frame".into());
    }
    let result = calibration::calibrate(&config, &measured, &held_out, &options)?;
    let mut report = result.report();
    let problems = result.problems();
    if !problems.is_empty() && !args.force {
        say(&report);
        return Err(Refused(problems).into());
    }
    let fitted = &result.fit;
    let (geometry, mut params, workspace) = if args.world_base {
        let carried = world::carry(&config.workspace, &fitted.geometry.instrument());
        let world = fitted.geometry.instrument() * fitted.geometry.base();
        report += &format!(
            "\n[base] written: the instrument's frame is the robot file's world frame; the \
             workspace is carried into it {}\n",
            if carried.exact {
                "exactly"
            } else {
                "(exclusion boxes enlarged, bounds shrunk: the turn is not a quarter turn)"
            }
        );
        let base = (0..3).map(Param::BaseXyz).chain((0..3).map(Param::BaseRpy));
        let params: Vec<Param> = fitted.params.iter().copied().chain(base).collect();
        let geometry = fitted.geometry.with_base(&world);
        (geometry, params, Some(carried.workspace))
    } else {
        (fitted.geometry.clone(), fitted.params.clone(), None)
    };
    params.retain(|p| !p.is_instrument());
    say(&report);
    let comment = comment_block(&result, args, &report);
    let text = robot_file::edit(
        &read(robot_path)?,
        &geometry,
        &params,
        workspace.as_ref(),
        &comment,
    )?;
    armgate_core::config::parse_toml(&text)
        .map_err(|e| format!("the calibrated file does not load ({e}); not written"))?;
    std::fs::write(out, text).map_err(|e| format!("{}: {e}", out.display()))?;
    say(&format!("\nwrote {}\n", out.display()));
    if let Some(path) = &args.instrument_out {
        std::fs::write(path, result.instrument.to_toml())
            .map_err(|e| format!("{}: {e}", path.display()))?;
        say(&format!("wrote {}\n", path.display()));
    }
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
    let instrument = match (&args.instrument_out, args.measured_in) {
        (_, MeasuredIn::World) => "; measured in the world frame".to_string(),
        (Some(path), _) => format!("; the instrument's frame is in {}", path.display()),
        (None, _) => String::new(),
    };
    format!(
        "Calibrated by armgate-calibrate (--fit {}) from {} with the measurements {} ({} \
         poses, {} set aside); checked by {check}{instrument}.\nOnly the fitted values below \
         differ from {}.\n\n{report}",
        fit.unwrap_or_default(),
        show(&args.robot),
        show(&args.measurements),
        result.before.count + result.rejected.len(),
        result.rejected.len(),
        show(&args.robot),
    )
}

fn run_plan(
    robot_path: &Path,
    poses: usize,
    candidates: usize,
    seed: u64,
    (fit, measured_in): (FitSet, MeasuredIn),
    out: Option<&Path>,
) -> Result<()> {
    if poses == 0 {
        return Err("--poses must be at least 1".into());
    }
    let config = robot(robot_path)?;
    let plan = plan::plan(&config, fit, measured_in, poses, candidates, seed)?;
    let a = &plan.analysis;
    let mut text = format!(
        "# {} poses for {} chosen from {} random candidates (seed {seed}) for observability\n\
         # O1 {:.4} m, condition number {:.1}; {} parameters identifiable ({} of the robot, the \
         rest the instrument's frame); not identifiable: {}\n\
         # measure the tool position at each and append x,y,z (m) to its line\n",
        plan.poses.len(),
        robot_path.display(),
        plan.candidates,
        a.observability,
        a.condition,
        a.identified.len(),
        a.identified.iter().filter(|p| !p.is_instrument()).count(),
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
    instrument: Option<&Path>,
    out: &Path,
) -> Result<()> {
    let mut config = robot(truth)?;
    if let Some(seed) = perturb {
        config = sim::perturb(&config, &sim::Errors::TYPICAL, seed)?;
    }
    let poses = measurements::parse_poses(&read(poses)?, config.dof())
        .map_err(|e| format!("{}: {e}", poses.display()))?;
    let measured = match instrument {
        Some(path) => {
            let placement =
                Placement::parse(&read(path)?).map_err(|e| format!("{}: {e}", path.display()))?;
            sim::measure_from(&config, &placement.pose, &poses, noise, seed)
        }
        None => sim::measure(&config, &poses, noise, seed),
    };
    std::fs::write(out, measurements::format(&measured, config.dof()))
        .map_err(|e| format!("{}: {e}", out.display()))?;
    eprintln!(
        "wrote {} simulated measurements to {}",
        measured.len(),
        out.display()
    );
    Ok(())
}
