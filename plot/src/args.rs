//! The `--plots DIR` option of the examples, shared so that each parses it the same way.

use std::path::PathBuf;

/// The directory given as `--plots DIR` (or `--plots=DIR`) on the command line, created if
/// missing; none without the option. Other arguments are left to the caller.
pub fn plots_dir_from_args() -> std::io::Result<Option<PathBuf>> {
    let dir = plots_dir(std::env::args().skip(1))
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;
    if let Some(dir) = &dir {
        std::fs::create_dir_all(dir)?;
    }
    Ok(dir)
}

fn plots_dir(mut args: impl Iterator<Item = String>) -> Result<Option<PathBuf>, &'static str> {
    while let Some(arg) = args.next() {
        if arg == "--plots" {
            return args
                .next()
                .map(|dir| Some(PathBuf::from(dir)))
                .ok_or("--plots needs a directory");
        }
        if let Some(dir) = arg.strip_prefix("--plots=") {
            return Ok(Some(PathBuf::from(dir)));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Option<PathBuf>, &'static str> {
        plots_dir(args.iter().map(|s| s.to_string()))
    }

    #[test]
    fn finds_the_directory_in_both_spellings() {
        assert_eq!(parse(&[]), Ok(None));
        assert_eq!(parse(&["--other"]), Ok(None));
        assert_eq!(parse(&["--plots", "out"]), Ok(Some("out".into())));
        assert_eq!(parse(&["x", "--plots=a/b"]), Ok(Some("a/b".into())));
        assert!(parse(&["--plots"]).is_err());
    }
}
