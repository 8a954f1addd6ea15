//! Key files on disk, handled as ssh handles a private key: refused when group or others may
//! read them, with the `chmod` that fixes it.

use std::path::Path;

use super::SigningKey;

/// The key in the file at `path` (64 hex digits on one line, see [`super::parse_key`]). On
/// Unix a file that group or others may read is refused. Errors name the file, never the key.
pub fn read_key_file(path: &Path) -> Result<SigningKey, String> {
    let shown = path.display();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(path)
            .map_err(|e| format!("{shown}: {e}"))?
            .permissions()
            .mode();
        if mode & 0o077 != 0 {
            return Err(format!(
                "{shown}: the key file may be read by others (mode {:o}): chmod 600 {shown}",
                mode & 0o777
            ));
        }
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("{shown}: {e}"))?;
    SigningKey::parse(&text).map_err(|e| format!("{shown}: {e}"))
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    #[test]
    fn a_key_file_others_may_read_is_refused_with_the_chmod_that_fixes_it() {
        let path = std::env::temp_dir().join(format!("armgate-key-{}", std::process::id()));
        std::fs::write(
            &path,
            "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f\n",
        )
        .unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).unwrap();
        let error = read_key_file(&path).unwrap_err();
        assert!(
            error.ends_with(&format!("(mode 644): chmod 600 {}", path.display())),
            "{error}"
        );
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
        assert!(read_key_file(&path).is_ok());
        std::fs::write(&path, "00112233").unwrap();
        let error = read_key_file(&path).unwrap_err();
        assert!(!error.contains("00112233"), "never the key: {error}");
        let _ = std::fs::remove_file(&path);
    }
}
