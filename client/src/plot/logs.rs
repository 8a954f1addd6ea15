//! Reading armgate-sim's `--log-dir` CSVs (host-sim/src/log.rs) by their header names, so
//! that added or reordered columns and quoted fields do no harm.

use std::fs::File;
use std::path::{Path, PathBuf};

use armgate_protocol::client::Severity;

/// What went wrong reading the logs.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// A file could not be opened.
    #[error("{path}: {source}")]
    Open {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A file is not CSV as expected.
    #[error("{path}: {source}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// Why.
        source: csv::Error,
    },
    /// A column the plots need is missing.
    #[error("{path}: no column `{column}` in the header")]
    Column {
        /// The file.
        path: PathBuf,
        /// Its name.
        column: &'static str,
    },
}

/// The tick log, `state.csv`: one row per control tick.
#[derive(Clone, Debug, Default)]
pub struct StateLog {
    /// Time of each row (s).
    pub t: Vec<f64>,
    /// Control mode of each row.
    pub mode: Vec<String>,
    /// Measured tool position (m).
    pub tool: [Vec<f64>; 3],
    /// Cartesian set-point position (m); NaN where the row has none.
    pub setpoint: [Vec<f64>; 3],
    /// Measured position of each joint (rad, m for prismatic joints).
    pub q: Vec<Vec<f64>>,
    /// Joint command of each joint; NaN where none was sent.
    pub cmd: Vec<Vec<f64>>,
}

/// A timed text: a warning, or the ER text of a reply.
#[derive(Clone, Debug, PartialEq)]
pub struct Notice {
    /// When (s).
    pub t: f64,
    /// The text, e.g. "WN22 ...".
    pub text: String,
}

/// Everything the plots use from a log directory.
#[derive(Clone, Debug, Default)]
pub struct Logs {
    /// `state.csv`.
    pub state: StateLog,
    /// `warnings.csv`, and the ER/WN replies of `replies.csv`, in time order.
    pub notices: Vec<Notice>,
}

impl Logs {
    /// Reads `state.csv` (needed) and `warnings.csv` and `replies.csv` (if present) in `dir`.
    pub fn read(dir: &Path) -> Result<Self, LogError> {
        let state = read_state(&dir.join("state.csv"))?;
        let mut notices = Vec::new();
        let warnings = dir.join("warnings.csv");
        if warnings.exists() {
            let table = Table::read(&warnings)?;
            let (t, text) = (table.column("t")?, table.column("text")?);
            for row in &table.rows {
                notices.push(Notice {
                    t: number(row, t),
                    text: field(row, text).to_owned(),
                });
            }
        }
        let replies = dir.join("replies.csv");
        if replies.exists() {
            let table = Table::read(&replies)?;
            let (t, reply) = (table.column("t")?, table.column("reply")?);
            for row in &table.rows {
                let text = field(row, reply);
                let prefix = text.as_bytes().get(..2).and_then(|p| p.try_into().ok());
                if prefix.and_then(Severity::from_prefix).is_some() {
                    notices.push(Notice {
                        t: number(row, t),
                        text: text.to_owned(),
                    });
                }
            }
        }
        notices.sort_by(|a, b| a.t.total_cmp(&b.t));
        Ok(Self { state, notices })
    }
}

fn read_state(path: &Path) -> Result<StateLog, LogError> {
    let table = Table::read(path)?;
    let t = table.column("t")?;
    let mode = table.column("mode")?;
    let tool = [table.column("x")?, table.column("y")?, table.column("z")?];
    let setpoint = ["sp_x", "sp_y", "sp_z"].map(|name| table.find(name));
    // Joints q1, q2, ... and cmd1, cmd2, ... for as many as the header names.
    let numbered = |prefix: &str| -> Vec<Option<usize>> {
        (1..)
            .map(|k| table.find(&format!("{prefix}{k}")))
            .take_while(Option::is_some)
            .collect()
    };
    let q_columns = numbered("q");
    let cmd_columns = numbered("cmd");
    let mut log = StateLog {
        q: vec![Vec::new(); q_columns.len()],
        cmd: vec![Vec::new(); q_columns.len()],
        ..StateLog::default()
    };
    for row in &table.rows {
        log.t.push(number(row, t));
        log.mode.push(field(row, mode).to_owned());
        for (values, column) in log.tool.iter_mut().zip(tool) {
            values.push(number(row, column));
        }
        for (values, column) in log.setpoint.iter_mut().zip(setpoint) {
            values.push(column.map_or(f64::NAN, |c| number(row, c)));
        }
        for (values, column) in log.q.iter_mut().zip(&q_columns) {
            values.push(column.map_or(f64::NAN, |c| number(row, c)));
        }
        for (k, values) in log.cmd.iter_mut().enumerate() {
            let column = cmd_columns.get(k).copied().flatten();
            values.push(column.map_or(f64::NAN, |c| number(row, c)));
        }
    }
    Ok(log)
}

/// A CSV file: its header and rows.
struct Table {
    path: PathBuf,
    header: csv::StringRecord,
    rows: Vec<csv::StringRecord>,
}

impl Table {
    fn read(path: &Path) -> Result<Self, LogError> {
        let file = File::open(path).map_err(|source| LogError::Open {
            path: path.to_owned(),
            source,
        })?;
        let csv_error = |source| LogError::Csv {
            path: path.to_owned(),
            source,
        };
        // Flexible: a row cut short by a crash or with a stray extra field still reads.
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(file);
        let header = reader.headers().map_err(csv_error)?.clone();
        let rows = reader
            .records()
            .collect::<Result<Vec<_>, _>>()
            .map_err(csv_error)?;
        Ok(Self {
            path: path.to_owned(),
            header,
            rows,
        })
    }

    fn find(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    fn column(&self, name: &'static str) -> Result<usize, LogError> {
        self.find(name).ok_or_else(|| LogError::Column {
            path: self.path.clone(),
            column: name,
        })
    }
}

fn field(row: &csv::StringRecord, column: usize) -> &str {
    row.get(column).unwrap_or("")
}

/// The number in a field; NaN if it is empty or not a number.
fn number(row: &csv::StringRecord, column: usize) -> f64 {
    field(row, column).parse().unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_are_found_by_name_and_quoted_texts_read_whole() {
        let dir = std::env::temp_dir().join(format!("armgate-logs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Columns reordered, an extra one, a command missing in the first row.
        std::fs::write(
            dir.join("state.csv"),
            "mode,t,extra,x,y,z,q1,q2,cmd1,cmd2\n\
             off,0.0,7,0.1,0.2,0.3,1.0,2.0,,\n\
             joint,0.01,7,0.1,0.2,0.31,1.1,2.1,1.2,2.2\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("warnings.csv"),
            "t,text\n0.005,\"WN22 IK diverging, stopped\"\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("replies.csv"),
            "t,reply,f0\n0.001,SP,1\n0.002,\"ER20 Cmd BG rejected, mode\",\n",
        )
        .unwrap();
        let logs = Logs::read(&dir).unwrap();
        let s = &logs.state;
        assert_eq!(s.t, [0.0, 0.01]);
        assert_eq!(s.mode, ["off", "joint"]);
        assert_eq!(s.tool[2], [0.3, 0.31]);
        assert!(s.setpoint[0].iter().all(|v| v.is_nan()));
        assert_eq!(s.q, [vec![1.0, 1.1], vec![2.0, 2.1]]);
        assert!(s.cmd[1][0].is_nan());
        assert_eq!(s.cmd[1][1], 2.2);
        let texts: Vec<_> = logs.notices.iter().map(|n| n.text.as_str()).collect();
        assert_eq!(
            texts,
            ["ER20 Cmd BG rejected, mode", "WN22 IK diverging, stopped"]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_missing_state_file_or_column_is_named() {
        let dir = std::env::temp_dir().join(format!("armgate-logs-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = Logs::read(&dir).unwrap_err().to_string();
        assert!(e.contains("state.csv"), "{e}");
        std::fs::write(dir.join("state.csv"), "t,mode,x,y\n").unwrap();
        let e = Logs::read(&dir).unwrap_err().to_string();
        assert!(e.contains("no column `z`"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
