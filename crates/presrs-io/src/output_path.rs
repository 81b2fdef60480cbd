//! Output paths checked before the work: a command that writes a file or a folder at its end checks,
//! first, that it will be able to, so that a missing folder or a file in a folder's place fails in the
//! first second rather than after a long search or evaluation.
//!
//! The check creates (and removes) an empty hidden file where the output goes: that is the one way to
//! know a folder is writable (permissions, a read-only file system, a full quota of inodes).

use std::path::{Path, PathBuf};

use crate::error::IoError;

/// Checks that a file can be written at `path`: its folder exists, is a folder and accepts a new file,
/// and `path` itself is not a folder. An existing file at `path` is fine (it is replaced).
///
/// ```
/// let dir = tempfile::tempdir()?;
/// presrs_io::output_path::check_output_file(&dir.path().join("model.json"))?;
/// assert!(presrs_io::output_path::check_output_file(&dir.path().join("no/such/model.json")).is_err());
/// assert!(presrs_io::output_path::check_output_file(dir.path()).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn check_output_file(path: &Path) -> Result<(), IoError> {
    if path.is_dir() {
        return Err(refused(
            path,
            format!(
                "it is a folder; give a file name, e.g. {}",
                path.join("out").display()
            ),
        ));
    }
    if path.file_name().is_none() {
        return Err(refused(path, "it does not end in a file name".to_owned()));
    }
    let folder = folder_of(path);
    if !folder.exists() {
        return Err(refused(
            path,
            format!(
                "the folder {} does not exist (create it first, or write elsewhere)",
                folder.display()
            ),
        ));
    }
    if !folder.is_dir() {
        return Err(refused(
            path,
            format!("{} is a file, not a folder", folder.display()),
        ));
    }
    probe(path, &folder)
}

/// Checks that a folder can be written at `path`: `path` is a folder or does not exist yet (it is then
/// created with its missing parents, so the nearest existing one must be a folder), and that folder
/// accepts a new file.
///
/// ```
/// let dir = tempfile::tempdir()?;
/// presrs_io::output_path::check_output_dir(&dir.path().join("report/figures"))?;
/// let file = dir.path().join("taken");
/// std::fs::write(&file, "x")?;
/// assert!(presrs_io::output_path::check_output_dir(&file).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn check_output_dir(path: &Path) -> Result<(), IoError> {
    if path.exists() && !path.is_dir() {
        return Err(refused(
            path,
            "it is a file, and a folder is wanted here: give the name of a folder (it is created \
             when missing)"
                .to_owned(),
        ));
    }
    let existing = path
        .ancestors()
        .map(|p| {
            if p.as_os_str().is_empty() {
                Path::new(".")
            } else {
                p
            }
        })
        .find(|p| p.exists())
        .unwrap_or(Path::new("."));
    if !existing.is_dir() {
        return Err(refused(
            path,
            format!(
                "{} is a file, so no folder can be made under it",
                existing.display()
            ),
        ));
    }
    probe(path, existing)
}

/// The folder a file at `path` goes into (`.` for a bare name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Creates and removes an empty hidden file in `folder`: whether the output for `path` can be written.
fn probe(path: &Path, folder: &Path) -> Result<(), IoError> {
    tempfile::Builder::new()
        .prefix(".presrs-write-check.")
        .tempfile_in(folder)
        .map(drop)
        .map_err(|source| IoError::io("write to the folder of", path, source))
}

/// The error for an output that cannot be written, with the reason.
fn refused(path: &Path, reason: String) -> IoError {
    IoError::io(
        "write",
        path,
        std::io::Error::new(std::io::ErrorKind::InvalidInput, reason),
    )
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn a_file_output_needs_an_existing_folder_and_no_folder_in_its_place() {
        let dir = tempfile::tempdir().unwrap();
        let fine = dir.path().join("m.json");
        check_output_file(&fine).unwrap();
        assert!(!fine.exists(), "the check leaves nothing behind");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        std::fs::write(&fine, "old").unwrap();
        check_output_file(&fine).unwrap();

        let missing = dir.path().join("no/such/dir/m.json");
        let err = check_output_file(&missing).unwrap_err().to_string();
        assert!(
            err.contains("m.json") && err.contains("does not exist"),
            "{err}"
        );

        let err = check_output_file(dir.path()).unwrap_err().to_string();
        assert!(err.contains("is a folder"), "{err}");

        let under_a_file = fine.join("m.json");
        let err = check_output_file(&under_a_file).unwrap_err().to_string();
        assert!(err.contains("is a file, not a folder"), "{err}");
    }

    #[test]
    fn a_folder_output_may_be_missing_but_not_a_file() {
        let dir = tempfile::tempdir().unwrap();
        check_output_dir(dir.path()).unwrap();
        check_output_dir(&dir.path().join("new/deeper")).unwrap();
        assert!(
            !dir.path().join("new").exists(),
            "the check creates no folder"
        );

        let file = dir.path().join("report");
        std::fs::write(&file, "x").unwrap();
        let err = check_output_dir(&file).unwrap_err().to_string();
        assert!(err.contains("it is a file"), "{err}");
        let err = check_output_dir(&file.join("sub")).unwrap_err().to_string();
        assert!(err.contains("is a file, so no folder"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn a_read_only_folder_is_refused() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let locked = dir.path().join("locked");
        std::fs::create_dir(&locked).unwrap();
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
        let result = check_output_file(&locked.join("m.json"));
        // root writes anywhere: the check is compared with what the file system allows.
        let writable = std::fs::write(locked.join("probe"), "x").is_ok();
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
        assert_eq!(result.is_ok(), writable, "{result:?}");
    }
}
