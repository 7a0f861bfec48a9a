//! Atomic file replacement: write a sibling temporary file, flush it to disk, then rename it
//! over the target. A crash at any point leaves either the old file or the complete new one,
//! never a truncated file that looks valid.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::PowderError;

/// Distinguishes temporary files made by concurrent calls in one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `bytes` to `path` atomically.
///
/// The data go to a temporary file in the same directory (so the final rename never crosses a
/// file system), which is synced and then renamed over `path`. An existing file at `path` is
/// left untouched until the new content is complete, and keeps its permissions. The parent
/// directory is not created: a missing directory is an error naming `path`. If `path` is a
/// symbolic link, the link itself is replaced.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PowderError> {
    write_atomic_io(path, bytes)
        .map_err(|err| PowderError::io(format!("cannot write `{}`", path.display()), err))
}

fn write_atomic_io(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let file_name = path.file_name().ok_or_else(|| {
        io::Error::new(io::ErrorKind::InvalidInput, "the path does not name a file")
    })?;
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };

    let (tmp_path, mut file) = create_temp(dir, file_name)?;
    let result = (|| {
        file.write_all(bytes)?;
        if let Ok(meta) = fs::metadata(path) {
            if meta.is_file() {
                // Best effort: keep the replaced file's permissions.
                let _ = file.set_permissions(meta.permissions());
            }
        }
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp_path, path)
    })();
    if let Err(err) = result {
        let _ = fs::remove_file(&tmp_path);
        return Err(err);
    }
    sync_dir(dir);
    Ok(())
}

/// Creates a new, uniquely named temporary file next to the target.
fn create_temp(dir: &Path, file_name: &std::ffi::OsStr) -> io::Result<(PathBuf, File)> {
    let pid = std::process::id();
    let mut last_err = None;
    for _ in 0..16 {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut name = std::ffi::OsString::from(".");
        name.push(file_name);
        name.push(format!(".{pid}.{n}.tmp"));
        let tmp_path = dir.join(name);
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp_path)
        {
            Ok(file) => return Ok((tmp_path, file)),
            Err(err) if err.kind() == io::ErrorKind::AlreadyExists => last_err = Some(err),
            Err(err) => return Err(err),
        }
    }
    Err(last_err.unwrap_or_else(|| io::Error::other("cannot create a temporary file")))
}

/// Removes the temporary files that writes into `dir` left when their process was killed
/// before the rename (`.<file>.<pid>.<n>.tmp` of a process that is gone: not this one, not
/// one still running where `/proc` tells); returns how many. Best effort: a file that
/// cannot be removed stays, and nothing else is touched.
pub fn remove_stale_temps(dir: &Path) -> usize {
    let Ok(entries) = fs::read_dir(dir) else {
        return 0;
    };
    let proc = Path::new("/proc/self").exists();
    let mut removed = 0;
    for entry in entries.flatten() {
        let Some(pid) = temp_pid(&entry.file_name().to_string_lossy()) else {
            continue;
        };
        let alive =
            pid == std::process::id() || (proc && Path::new(&format!("/proc/{pid}")).exists());
        if !alive && entry.path().is_file() && fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// The kinds of file the runs write through [`create_temp`] (a temporary file of another
/// name is not a run's, and stays).
const OUTPUT_KINDS: [&str; 5] = [".csv", ".bin", ".json", ".pvd", ".vtp"];

/// The process id in one of [`create_temp`]'s names for a run's output,
/// `.<file>.<pid>.<n>.tmp`.
fn temp_pid(name: &str) -> Option<u32> {
    let stem = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let digits = |p: &&str| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit());
    let mut parts = stem.rsplitn(3, '.');
    parts.next().filter(digits)?;
    let pid = parts.next().filter(digits)?;
    parts.next().filter(|file| {
        OUTPUT_KINDS
            .iter()
            .any(|k| file.len() > k.len() && file.ends_with(k))
    })?;
    pid.parse().ok()
}

/// Makes the rename durable where the platform allows syncing a directory (best effort).
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn stale_temporary_files_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        // besides names of other shapes: this process's own temporary file and a live
        // process's (pid 1) stay
        let own = format!(".series.csv.{}.3.tmp", std::process::id());
        let mut keep = vec![
            "a.csv",
            ".hidden",
            ".x.tmp",
            ".x.1.tmp",
            ".x.1.y.tmp",
            "..1.2.tmp",
            own.as_str(),
            ".w.pvd.1.0.tmp",
        ];
        let gone = u32::MAX - 1;
        // a user's file of that shape that is not a run's output kind
        let notes = format!(".notes.{gone}.1.tmp");
        keep.push(&notes);
        let stale = [
            format!(".checkpoint.bin.{gone}.9.tmp"),
            format!(".run_0000000300.vtp.{gone}.0.tmp"),
        ];
        for f in keep.iter().copied().chain(stale.iter().map(String::as_str)) {
            fs::write(dir.path().join(f), b"x").unwrap();
        }
        let folder = format!(".d.{gone}.2.tmp");
        fs::create_dir(dir.path().join(&folder)).unwrap();
        assert_eq!(remove_stale_temps(dir.path()), 2);
        keep.push(&folder);
        keep.sort();
        assert_eq!(entries(dir.path()), keep);
        assert_eq!(remove_stale_temps(&dir.path().join("none")), 0);
    }

    #[test]
    fn writes_a_new_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        write_atomic(&path, b"hello").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"hello");
        assert_eq!(entries(dir.path()), vec!["out.txt".to_string()]);
    }

    #[test]
    fn replaces_an_existing_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        fs::write(&path, b"a much longer old content").unwrap();
        write_atomic(&path, b"new").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        assert_eq!(entries(dir.path()), vec!["out.txt".to_string()]);
    }

    #[test]
    fn writes_empty_content() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("empty");
        write_atomic(&path, b"").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"");
    }

    #[test]
    fn missing_directory_is_an_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no_such_dir").join("out.txt");
        let err = write_atomic(&path, b"x").unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains(&path.display().to_string()), "{msg}");
        assert!(matches!(err, PowderError::Io { .. }));
        assert!(!dir.path().join("no_such_dir").exists());
    }

    #[test]
    fn failed_rename_keeps_the_target_and_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        // A non-empty directory cannot be replaced by a file.
        let path = dir.path().join("target");
        fs::create_dir(&path).unwrap();
        fs::write(path.join("inner"), b"keep").unwrap();
        let err = write_atomic(&path, b"x").unwrap_err();
        assert!(err.to_string().contains("cannot write"), "{err}");
        assert_eq!(entries(dir.path()), vec!["target".to_string()]);
        assert_eq!(fs::read(path.join("inner")).unwrap(), b"keep");
    }

    #[test]
    fn path_without_file_name_is_an_error() {
        let err = write_atomic(Path::new("/"), b"x").unwrap_err();
        assert!(err.to_string().contains("cannot write `/`"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn keeps_permissions_of_the_replaced_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("perm.txt");
        fs::write(&path, b"old").unwrap();
        fs::set_permissions(&path, fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&path, b"new").unwrap();
        let mode = fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
    }
}
