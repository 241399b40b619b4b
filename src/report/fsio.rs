//! File access rules shared by every command: crash-safe writes (temporary file in the same
//! directory, flush, fsync, rename), no write through a symbolic link rpod did not make, no
//! folder of its own replaced by a link, and reads only of regular files under a size cap (a FIFO,
//! a device or `/dev/zero` is refused before a byte is read, so nothing hangs or exhausts memory).

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
        let _ = fs::remove_file(&tmp);
        let mut f = create_new_nofollow(&tmp).map_err(|e| with_path(&tmp, "create", e))?;
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

/// `O_NOFOLLOW | O_NONBLOCK` where the platform has them: the last component of the path may not
/// be a symbolic link, and opening a FIFO does not wait for a writer.
fn guarded(opts: &mut fs::OpenOptions) -> &mut fs::OpenOptions {
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
    }
    opts
}

/// Creates a new file for writing; fails if anything (a file, a planted symbolic link) is at
/// `path` already.
pub fn create_new_nofollow(path: &Path) -> io::Result<fs::File> {
    guarded(fs::OpenOptions::new().write(true).create_new(true)).open(path)
}

/// Opens `path` for writing with `opts` (create, append, truncate as set by the caller), refusing a
/// symbolic link at `path` and anything that is not a regular file (a FIFO, a device), with a
/// message naming the path.
pub fn open_write_nofollow(path: &Path, opts: &mut fs::OpenOptions) -> io::Result<fs::File> {
    let f = guarded(opts.write(true)).open(path).map_err(|e| {
        if e.raw_os_error() == Some(libc_eloop()) {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "{} is a symbolic link: rpod writes only its own files in the output folder                      and does not follow links there; remove the link",
                    path.display()
                ),
            )
        } else {
            with_path(path, "open for writing", e)
        }
    })?;
    let m = f.metadata().map_err(|e| with_path(path, "inspect", e))?;
    if !m.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{} is not a regular file (a FIFO, socket or device): rpod writes only regular                  files",
                path.display()
            ),
        ));
    }
    Ok(f)
}

/// `ELOOP`, the error `open` gives for a symbolic link under `O_NOFOLLOW`.
fn libc_eloop() -> i32 {
    #[cfg(unix)]
    {
        libc::ELOOP
    }
    #[cfg(not(unix))]
    {
        -1
    }
}

/// Makes sure `dir` is a real folder rpod may write into: created if missing (its parent must
/// exist), accepted if it is a folder, refused if it is a symbolic link (even to a folder) or
/// anything else. Used for the folders rpod makes inside an output folder (`runs/`, `plots/`,
/// a trial's folder), so a link planted there cannot redirect a write outside.
pub fn ensure_own_dir(dir: &Path) -> io::Result<()> {
    for _ in 0..2 {
        match fs::symlink_metadata(dir) {
            Ok(m) if m.is_dir() => return Ok(()),
            Ok(m) => {
                let what = if m.file_type().is_symlink() {
                    "a symbolic link"
                } else {
                    "not a folder"
                };
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "{} is {what}: rpod writes its outputs only into real folders it made;                          remove it or choose another --out",
                        dir.display()
                    ),
                ));
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => match fs::create_dir(dir) {
                Ok(()) => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(with_path(dir, "create folder", e)),
            },
            Err(e) => return Err(with_path(dir, "inspect", e)),
        }
    }
    Err(io::Error::other(format!(
        "{} changed while rpod was creating it",
        dir.display()
    )))
}

/// Opens a regular file for reading (a streaming reader: no size cap, for files rpod wrote itself
/// and reads row by row). The path may be a symbolic link, but what it names must be a regular
/// file: a FIFO, socket, device or folder is refused before anything is read, and opening never
/// waits on a FIFO.
pub fn open_regular(path: &Path, what: &str) -> io::Result<fs::File> {
    let mut opts = fs::OpenOptions::new();
    opts.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NONBLOCK);
    }
    let f = opts
        .open(path)
        .map_err(|e| with_path(path, &format!("cannot read the {what}"), e))?;
    let m = f
        .metadata()
        .map_err(|e| with_path(path, &format!("cannot read the {what}"), e))?;
    if !m.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "cannot read the {what} {}: not a regular file (a folder, FIFO, socket or \
                 device); rpod reads only regular files",
                path.display()
            ),
        ));
    }
    Ok(f)
}

/// Reads a regular file of at most `cap` bytes. The path may be a symbolic link (input paths are
/// the user's to choose), but what it names must be a regular file: a FIFO, a socket, a device
/// (`/dev/zero`, a terminal) or a folder is refused before anything is read, so a read never
/// blocks and never allocates more than `cap + 1` bytes. `what` names the file in messages.
pub fn read_regular(path: &Path, cap: u64, what: &str) -> io::Result<Vec<u8>> {
    use std::io::Read;
    let f = open_regular(path, what)?;
    let m = f
        .metadata()
        .map_err(|e| with_path(path, &format!("cannot read the {what}"), e))?;
    if m.len() > cap {
        return Err(too_large(path, cap, what));
    }
    let mut bytes = Vec::new();
    f.take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| with_path(path, &format!("cannot read the {what}"), e))?;
    if bytes.len() as u64 > cap {
        return Err(too_large(path, cap, what));
    }
    Ok(bytes)
}

fn too_large(path: &Path, cap: u64, what: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!(
            "the {what} {} is larger than {} MiB, the limit for this kind of file",
            path.display(),
            cap >> 20
        ),
    )
}

/// [`read_regular`], as UTF-8 text (an invalid byte is an error naming the file).
pub fn read_regular_string(path: &Path, cap: u64, what: &str) -> io::Result<String> {
    String::from_utf8(read_regular(path, cap, what)?).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "the {what} {} is not UTF-8 text (byte {})",
                path.display(),
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// The size cap for an output file rpod reads back (`rpod plot`, `rpod trials` resuming, the
/// viewer's replay): 4 GiB, far above any run's file, far below what a link to `/dev/zero` would
/// feed.
pub const MAX_OUTPUT_READ_BYTES: u64 = 4 << 30;

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

    #[cfg(unix)]
    #[test]
    fn regress_no_write_through_a_planted_link_and_no_linked_folder() {
        let d = scratch("nofollow");
        let outside = d.join("outside.txt");
        fs::write(&outside, b"keep me").unwrap();
        let inner = d.join("out");
        fs::create_dir_all(&inner).unwrap();
        let link = inner.join(".rpod.lock");
        std::os::unix::fs::symlink(&outside, &link).unwrap();
        let e = open_write_nofollow(&link, fs::OpenOptions::new().create(true).truncate(true))
            .unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert_eq!(fs::read(&outside).unwrap(), b"keep me");
        let runs = inner.join("runs");
        std::os::unix::fs::symlink(&d, &runs).unwrap();
        let e = ensure_own_dir(&runs).unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        ensure_own_dir(&inner.join("plots")).unwrap();
        assert!(inner.join("plots").is_dir());
    }

    #[cfg(unix)]
    #[test]
    fn regress_special_files_are_refused_before_reading() {
        let e = read_regular(Path::new("/dev/zero"), 1 << 20, "run file").unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let d = scratch("fifo");
        let fifo = d.join("scene.ron");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        let e = read_regular(&fifo, 1 << 20, "scene").unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let big = d.join("big");
        fs::write(&big, vec![b'x'; 2048]).unwrap();
        let e = read_regular(&big, 1024, "scene").unwrap_err();
        assert!(e.to_string().contains("larger than"), "{e}");
        assert_eq!(read_regular(&big, 4096, "scene").unwrap().len(), 2048);
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
