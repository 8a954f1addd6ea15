//! The replay reservation in a file (`armgate-sim --state`, the firmware on Linux): the
//! [`ReplayStore`] of the shells that have a file system.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::replay::ReplayStore;
use armgate_protocol::client::signed::ControllerId;

/// A state file: one line, the reservation (a timestamp in 10 µs steps since 2015). Written
/// whole to a temporary file, synced and renamed over the old one, so a crash leaves the old
/// or the new value, never half of one.
#[derive(Clone, Debug)]
pub struct StateFile {
    path: PathBuf,
    loaded: u64,
    /// The last write's error, for the shell to print once.
    error: Option<String>,
}

impl StateFile {
    /// Opens `path`: the reservation it holds, or none if it does not exist yet. A file that
    /// exists but does not read as one is an error: starting as new would serve replays.
    pub fn open(path: &Path) -> Result<Self, String> {
        let loaded = match std::fs::read_to_string(path) {
            Ok(text) => text.trim().parse::<u64>().map_err(|_| {
                format!(
                    "{}: not a replay state file (one number); remove it only if no signed \
                     datagram captured from this controller may be sent again",
                    path.display()
                )
            })?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => 0,
            Err(e) => return Err(format!("{}: {e}", path.display())),
        };
        Ok(Self {
            path: path.to_owned(),
            loaded,
            error: None,
        })
    }

    /// Where a controller keeps its state file unless told: `$XDG_STATE_HOME/armgate/`, else
    /// `$HOME/.local/state/armgate/`, else the working directory, named by the controller's id
    /// (`replay-<id>`: two controllers on one computer have their own).
    pub fn default_path(controller: ControllerId) -> PathBuf {
        let dir = std::env::var_os("XDG_STATE_HOME")
            .filter(|d| !d.is_empty())
            .map(PathBuf::from)
            .or_else(|| {
                std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local").join("state"))
            })
            .map_or_else(PathBuf::new, |d| d.join("armgate"));
        dir.join(format!("replay-{controller}"))
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The last write's error, taken (the shell prints it once).
    pub fn take_error(&mut self) -> Option<String> {
        self.error.take()
    }

    fn write(&self, reserved: u64) -> std::io::Result<()> {
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let mut temporary = self.path.clone().into_os_string();
        temporary.push(".new");
        let mut file = std::fs::File::create(&temporary)?;
        writeln!(file, "{reserved}")?;
        file.sync_all()?;
        std::fs::rename(&temporary, &self.path)
    }
}

impl ReplayStore for StateFile {
    fn load(&mut self) -> u64 {
        self.loaded
    }

    fn keep(&mut self, reserved: u64) -> bool {
        match self.write(reserved) {
            Ok(()) => true,
            Err(e) => {
                self.error = Some(format!("{}: {e}", self.path.display()));
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reservation_survives_in_the_file_and_a_corrupt_file_is_an_error() {
        let dir = std::env::temp_dir().join(format!("armgate-state-{}", std::process::id()));
        let path = dir.join("sub").join("replay-1");
        let mut file = StateFile::open(&path).unwrap();
        assert_eq!(file.load(), 0);
        assert!(file.keep(123_456_789));
        assert_eq!(StateFile::open(&path).unwrap().load(), 123_456_789);
        std::fs::write(&path, "garbage").unwrap();
        assert!(
            StateFile::open(&path)
                .unwrap_err()
                .contains("not a replay state file")
        );
        let _ = std::fs::remove_dir_all(&dir);
        assert!(StateFile::default_path(ControllerId(0xab)).ends_with("armgate/replay-000000ab"));
    }
}
