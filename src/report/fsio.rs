//! Crash-safe file writing: temporary file in the same directory, flush, fsync, rename.

use std::fs;
use std::io::{self, Write};
use std::path::Path;

/// Wraps an I/O error so that its message names `path` (the kind is kept).
pub(crate) fn with_path(path: &Path, what: &str, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("{what} {}: {e}", path.display()))
}

/// Writes `bytes` to `path` atomically: the data go to a temporary file
/// `.<name>.tmp-<pid>` in the same directory, which is flushed to disk and then renamed over
/// `path`. A crash leaves either the old file, the new file, or a stray temporary file — never
/// a truncated `path`. The parent directory must exist.
///
/// Errors: `std::io::Error` whose message names the path; the temporary file is removed on
/// failure.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("write {}: path has no file name", path.display()),
        )
    })?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut f = fs::File::create(&tmp).map_err(|e| with_path(&tmp, "create", e))?;
        f.write_all(bytes)
            .map_err(|e| with_path(&tmp, "write", e))?;
        f.sync_all().map_err(|e| with_path(&tmp, "sync", e))?;
        drop(f);
        fs::rename(&tmp, path).map_err(|e| with_path(path, "rename into", e))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::report::scratch;

    #[test]
    fn invariant_atomic_write_replaces_whole_file_and_leaves_no_temp() {
        let d = scratch("atomic");
        let p = d.join("a.txt");
        write_atomic(&p, b"first version, longer").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second");
        let names: Vec<_> = fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "only the target remains: {names:?}");
    }

    #[test]
    fn regress_missing_directory_is_an_error_naming_the_path() {
        let d = scratch("atomic-missing");
        let p = d.join("no/such/dir/x.txt");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        assert!(e.to_string().contains("no/such/dir"), "{e}");
    }
}
