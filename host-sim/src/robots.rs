//! Finding the robot file: a path as given, else one of the shipped robot files, built into
//! the binary, by name (`--robot ur5`, `--robot robots/ur5.toml` outside the repository), so
//! that `armgate-sim` runs from any folder and after `cargo install` (issue 37).

use std::path::Path;

use armgate_core::config::{ValidRobot, load_file, parse_toml};

/// The shipped robot files (`robots/` of the repository), by name.
const SHIPPED: [(&str, &str); 8] = [
    ("ranger-mk1", include_str!("../../robots/ranger-mk1.toml")),
    (
        "ranger-mk1-jerk",
        include_str!("../../robots/ranger-mk1-jerk.toml"),
    ),
    (
        "ranger-mk1-table21",
        include_str!("../../robots/ranger-mk1-table21.toml"),
    ),
    ("ranger-mk2", include_str!("../../robots/ranger-mk2.toml")),
    ("hybrid", include_str!("../../robots/hybrid.toml")),
    ("puma560", include_str!("../../robots/puma560.toml")),
    ("ur5", include_str!("../../robots/ur5.toml")),
    ("iiwa14", include_str!("../../robots/iiwa14.toml")),
];

/// The built-in copy a path names when it does not exist: its file name is a shipped robot's
/// name, with or without `.toml`.
fn shipped(path: &Path) -> Option<(&'static str, &'static str)> {
    let name = path.file_name()?.to_str()?;
    let name = name.strip_suffix(".toml").unwrap_or(name);
    SHIPPED.into_iter().find(|(n, _)| *n == name)
}

/// Loads the robot file at `path`, or the built-in copy of a shipped robot it names (said on
/// stderr); a missing file that names none lists the built-in ones. Suspicious values are
/// warned about on stderr.
pub fn load(path: &Path) -> Result<ValidRobot, String> {
    let robot = find(path)?;
    for (joint, min, max) in robot.wide_limits() {
        eprintln!(
            "armgate-sim: warning: joint {}: limits {min} .. {max} rad reach beyond a turn each \
             way (±2π): written in degrees?",
            joint + 1
        );
    }
    Ok(robot)
}

/// The file at `path`, else the built-in copy it names.
fn find(path: &Path) -> Result<ValidRobot, String> {
    if path.exists() {
        return load_file(path).map_err(|e| e.to_string());
    }
    match shipped(path) {
        Some((name, text)) => {
            eprintln!(
                "armgate-sim: {} is not here: using the built-in copy of {name}",
                path.display()
            );
            parse_toml(text).map_err(|e| e.to_string())
        }
        None => {
            let names: Vec<&str> = SHIPPED.iter().map(|(n, _)| *n).collect();
            Err(format!(
                "no such file (built in by name: {})",
                names.join(", ")
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_robot_is_built_in_and_found_by_name_from_anywhere() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots");
        let mut files: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        files.sort();
        let mut built_in: Vec<String> = SHIPPED.iter().map(|(n, _)| format!("{n}.toml")).collect();
        built_in.sort();
        assert_eq!(files, built_in, "robots/ and the built-in copies differ");
        for (name, text) in SHIPPED {
            let on_disk = std::fs::read_to_string(format!("{dir}/{name}.toml")).unwrap();
            assert_eq!(on_disk, text);
            let robot = load(Path::new(&format!("/nowhere/robots/{name}.toml"))).unwrap();
            assert_eq!(robot.name.as_str(), name);
            assert_eq!(load(Path::new(name)).unwrap().name.as_str(), name);
        }
        let err = load(Path::new("/nowhere/robots/r2d2.toml")).unwrap_err();
        assert!(
            err.starts_with("no such file (built in by name: ranger-mk1, "),
            "{err}"
        );
    }
}
