//! `armgate plot`: SVG figures from armgate-sim's `--log-dir` CSVs: the tool path (three
//! views and over time) and each joint's position and command over time, with the mode
//! changes and the warnings as markers.

mod figures;
pub mod logs;

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;

use logs::{LogError, Logs};

/// `armgate plot` options.
#[derive(Clone, Debug, Args)]
pub struct PlotArgs {
    /// The log directory (armgate-sim --log-dir): state.csv, and warnings.csv and replies.csv
    /// if present.
    pub dir: PathBuf,
    /// Where to write the SVGs (default: the log directory).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
}

/// Why `armgate plot` failed.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Reading the logs.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The logs hold no tick.
    #[error("{0}: state.csv has no rows")]
    Empty(PathBuf),
    /// Writing an SVG.
    #[error("{path}: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// The files `armgate plot` writes, in its output directory.
pub const FILES: [&str; 2] = ["tool-path.svg", "joints.svg"];

/// Reads the logs in `args.dir`, writes the figures and lists the files written on `out`.
pub fn run(args: &PlotArgs, out: &mut impl Write) -> Result<Vec<PathBuf>, PlotError> {
    let logs = Logs::read(&args.dir)?;
    if logs.state.t.is_empty() {
        return Err(PlotError::Empty(args.dir.clone()));
    }
    let target = args.out.as_deref().unwrap_or(&args.dir);
    let title = title(&args.dir);
    let mut written = Vec::new();
    for (name, figure) in FILES.iter().zip([
        figures::tool_path(&logs, &title),
        figures::joints(&logs, &title),
    ]) {
        let path = target.join(name);
        let write_error = |message: String| PlotError::Write {
            path: path.clone(),
            message,
        };
        std::fs::create_dir_all(target).map_err(|e| write_error(e.to_string()))?;
        armgate_plot::write_svg(&path, &figure).map_err(|e| write_error(e.to_string()))?;
        let _ = writeln!(out, "{}", path.display());
        written.push(path);
    }
    Ok(written)
}

/// The figures' title: the log directory as given.
fn title(dir: &Path) -> String {
    format!("armgate-sim log {}", dir.display())
}
