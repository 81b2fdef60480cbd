//! Atomic file output: a file appears under its final name complete, or not at all.
//!
//! The content is written to a temporary file in the destination's directory (so that the final rename
//! stays on one file system), flushed and synced, then renamed over the destination. If the writing
//! closure fails, or the process dies half-way, the destination is untouched (a previous version stays
//! intact) and the temporary file is removed (or, after a crash, left as a hidden `.NAME.*.tmp` file).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::IoError;

/// Writes `path` atomically with `write`, which receives a buffered writer.
///
/// The closure returns `std::io::Result`, so `serde_json::to_writer`, `csv::Writer` and friends can be used
/// with `?` (their errors convert into `std::io::Error`); the error is reported with the path.
///
/// ```no_run
/// use std::io::Write;
/// presrs_io::atomic::write_atomic(std::path::Path::new("out.txt"), |w| writeln!(w, "hello"))?;
/// # Ok::<(), presrs_io::IoError>(())
/// ```
pub fn write_atomic<T>(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<T>,
) -> Result<T, IoError> {
    write_atomic_with(path, |w| {
        write(w).map_err(|source| IoError::io("write", path, source))
    })
}

/// Like [`write_atomic`], for closures with their own error type (which must absorb [`IoError`]).
pub fn write_atomic_with<T, E: From<IoError>>(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> Result<T, E>,
) -> Result<T, E> {
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let file_name = path
        .file_name()
        .ok_or_else(|| IoError::format(&path.display().to_string(), "not a file name"))?;
    let prefix = format!(".{}.", file_name.to_string_lossy());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        // NamedTempFile defaults to 0600; ask for the usual 0666 (the umask narrows it as for any file).
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut temp = builder
        .tempfile_in(dir)
        .map_err(|source| IoError::io("create a temporary file in", dir, source))?;
    let value = {
        let mut buffered = BufWriter::with_capacity(1 << 16, temp.as_file_mut());
        let value = write(&mut buffered)?;
        buffered
            .flush()
            .map_err(|source| IoError::io("write", path, source))?;
        value
    };
    sync(temp.as_file()).map_err(|source| IoError::io("sync", path, source))?;
    temp.persist(path)
        .map_err(|err| IoError::io("rename a temporary file to", path, err.error))?;
    Ok(value)
}

/// A file written over time (a recording in progress) that appears under its final name only when
/// [`AtomicFile::commit`] is called: until then it is a hidden temporary file next to it, removed if
/// the `AtomicFile` is dropped uncommitted.
#[derive(Debug)]
pub struct AtomicFile {
    temp: tempfile::NamedTempFile,
    path: std::path::PathBuf,
}

impl AtomicFile {
    /// Creates the temporary file for `path`; returns it and a handle to write through.
    pub fn create(path: &Path) -> Result<(Self, File), IoError> {
        let dir = match path.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent,
            _ => Path::new("."),
        };
        let file_name = path
            .file_name()
            .ok_or_else(|| IoError::format(&path.display().to_string(), "not a file name"))?;
        let prefix = format!(".{}.", file_name.to_string_lossy());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let temp = builder
            .tempfile_in(dir)
            .map_err(|source| IoError::io("create a temporary file in", dir, source))?;
        let handle = temp
            .as_file()
            .try_clone()
            .map_err(|source| IoError::io("open", temp.path(), source))?;
        Ok((
            Self {
                temp,
                path: path.to_path_buf(),
            },
            handle,
        ))
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Syncs the file and renames it to its final name (flush the writing handle first).
    pub fn commit(self) -> Result<(), IoError> {
        sync(self.temp.as_file()).map_err(|source| IoError::io("sync", &self.path, source))?;
        self.temp
            .persist(&self.path)
            .map_err(|err| IoError::io("rename a temporary file to", &self.path, err.error))?;
        Ok(())
    }
}

fn sync(file: &File) -> std::io::Result<()> {
    file.sync_all()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    }

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        write_atomic(&path, |w| w.write_all(b"first")).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "first");
        let n = write_atomic(&path, |w| {
            w.write_all(b"second")?;
            Ok(6)
        })
        .unwrap();
        assert_eq!(n, 6);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "second");
        assert_eq!(leftovers(dir.path()), vec!["out.txt".to_owned()]);
    }

    #[test]
    fn failure_leaves_previous_content_and_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("keep.txt");
        std::fs::write(&path, "old").unwrap();
        let err = write_atomic(&path, |w| {
            w.write_all(b"half of the new cont")?;
            Err::<(), _>(std::io::Error::other("generator failed"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("keep.txt"), "{err}");
        assert!(err.to_string().contains("generator failed"), "{err}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(leftovers(dir.path()), vec!["keep.txt".to_owned()]);
    }

    #[test]
    fn missing_directory_is_reported() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/dir/x.txt");
        let err = write_atomic(&path, |w| w.write_all(b"x")).unwrap_err();
        assert!(err.to_string().contains("no/such/dir"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn output_is_readable_by_others_as_usual() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.txt");
        write_atomic(&path, |w| w.write_all(b"x")).unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode();
        // Owner can read and write; not the 0600 of a bare temporary file unless the umask says so.
        assert_eq!(mode & 0o600, 0o600);
    }

    #[test]
    fn custom_error_type() {
        #[derive(Debug)]
        enum MyErr {
            Io(IoError),
            Mine,
        }
        impl From<IoError> for MyErr {
            fn from(e: IoError) -> Self {
                Self::Io(e)
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.txt");
        let r: Result<(), MyErr> = write_atomic_with(&path, |_| Err(MyErr::Mine));
        assert!(matches!(r, Err(MyErr::Mine)));
        assert!(!path.exists());
        let r: Result<(), MyErr> = write_atomic_with(&dir.path().join("a/b"), |_| Ok(()));
        match r {
            Err(MyErr::Io(err)) => assert!(err.to_string().contains("a"), "{err}"),
            other => panic!("expected an I/O error, got {other:?}"),
        }
    }
}
