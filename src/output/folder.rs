//! The output folder taken by one run at a time (a lock file naming its process), and
//! checked writable before anything in it changes.

use crate::error::PowderError;
use std::collections::HashSet;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, SystemTime};

/// The run's checkpoint in its folder.
pub const CHECKPOINT: &str = "checkpoint.bin";
/// The run's summary in its folder.
pub const SUMMARY: &str = "summary.json";
/// The run's time series in its folder.
pub const SERIES: &str = "series.csv";

/// The lock file's name in an output folder.
pub const LOCK: &str = ".powder.lock";

/// The folders this process holds: its own pid in a lock says nothing by itself (a
/// container's restarted process may have the pid of the run that left the lock).
static HELD: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

/// How long a lock without a readable process id may be in the making before it counts
/// as left by a run killed between creating and writing it.
const UNREADABLE_GRACE: Duration = Duration::from_secs(10);

/// An output folder held by this run: another run into it is refused while the lock
/// exists; dropping it removes the lock.
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
    /// The folder as [`HELD`] names it.
    key: PathBuf,
}

fn held(key: &Path) -> bool {
    let held = HELD.lock().unwrap_or_else(|e| e.into_inner());
    held.as_ref().is_some_and(|h| h.contains(key))
}

impl FolderLock {
    /// Takes `dir` (created if missing): refused while a live process holds it; a lock
    /// whose process has ended (a killed run) is taken over.
    pub fn take(dir: &Path) -> Result<Self, PowderError> {
        fs::create_dir_all(dir)
            .map_err(|e| PowderError::io(format!("cannot create `{}`", dir.display()), e))?;
        let path = dir.join(LOCK);
        let cannot = |e| PowderError::io(format!("cannot create the lock `{}`", path.display()), e);
        let key = fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
        // (twice: once more after removing a stale lock)
        for _ in 0..2 {
            match fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    if let Err(e) = write!(f, "{}", std::process::id()) {
                        let _ = fs::remove_file(&path);
                        return Err(cannot(e));
                    }
                    let mut set = HELD.lock().unwrap_or_else(|e| e.into_inner());
                    set.get_or_insert_with(HashSet::new).insert(key.clone());
                    return Ok(Self { path, key });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = fs::read_to_string(&path)
                        .ok()
                        .and_then(|t| t.trim().parse::<u32>().ok());
                    let age = (fs::metadata(&path).and_then(|m| m.modified()).ok())
                        .and_then(|t| SystemTime::now().duration_since(t).ok())
                        .unwrap_or_default();
                    let stale = match holder {
                        Some(pid) if pid == std::process::id() => !held(&key),
                        Some(pid) => !process_alive(pid),
                        None => age > UNREADABLE_GRACE,
                    };
                    if stale {
                        fs::remove_file(&path).map_err(cannot)?;
                        continue;
                    }
                    // (the process id may be reused by another program, as after a restart)
                    let who = holder.map_or("a run".to_string(), |pid| format!("process {pid}"));
                    return Err(PowderError::Run(format!(
                        "`{}` is held by {who} (its lock `{}`): two runs in one folder would mix their outputs; wait for that run to end or choose another --out (if no powder run is writing there, remove the lock)",
                        dir.display(),
                        path.display()
                    )));
                }
                Err(e) => return Err(cannot(e)),
            }
        }
        Err(PowderError::Run(format!(
            "cannot take `{}`: its lock `{}` reappeared at once (another run starting?)",
            dir.display(),
            path.display()
        )))
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // (only our own lock: another run may have taken it over meanwhile)
        let ours = fs::read_to_string(&self.path)
            .is_ok_and(|t| t.trim() == std::process::id().to_string());
        if ours {
            let _ = fs::remove_file(&self.path);
        }
        let mut held = HELD.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(h) = held.as_mut() {
            h.remove(&self.key);
        }
    }
}

/// Whether another process `pid` runs on this host, where `/proc` tells; without it, no
/// (a lock is then taken over: a killed run must not block its folder for good). A zombie
/// (killed, not yet reaped by its parent) runs no more.
pub fn process_alive(pid: u32) -> bool {
    if !Path::new("/proc/self").exists() {
        return false;
    }
    match fs::read_to_string(format!("/proc/{pid}/status")) {
        Ok(status) => !status
            .lines()
            .any(|l| l.starts_with("State:") && l[6..].trim_start().starts_with('Z')),
        Err(_) => Path::new(&format!("/proc/{pid}")).exists(),
    }
}

/// Refuses, before anything in `dir` changes, an output the run could not write: a folder
/// where one of `replaced` (written whole through a rename, or removed) or `appended`
/// goes, an `appended` file it may not write, a folder where it may not create files.
pub fn check_writable(
    dir: &Path,
    replaced: &[PathBuf],
    appended: &[PathBuf],
) -> Result<(), PowderError> {
    for (f, append) in
        (replaced.iter().map(|f| (f, false))).chain(appended.iter().map(|f| (f, true)))
    {
        match fs::metadata(f) {
            Ok(m) if m.is_dir() => {
                return Err(PowderError::Run(format!(
                    "`{}` is a folder where the run writes a file: move it away or choose another --out",
                    f.display()
                )))
            }
            Ok(m) if !m.is_file() => {
                return Err(PowderError::Run(format!(
                    "`{}` is not a regular file (a FIFO, socket or device) where the run writes a file: move it away or choose another --out",
                    f.display()
                )))
            }
            Ok(_) if append => {
                fs::OpenOptions::new()
                    .append(true)
                    .open(f)
                    .map_err(|e| PowderError::io(format!("cannot write `{}`", f.display()), e))?;
            }
            Ok(_) => refuse_immutable(f)?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(PowderError::io(format!("cannot read `{}`", f.display()), e)),
        }
    }
    // the folder: a file created and removed again
    let probe = dir.join(format!(".powder-probe.{}", std::process::id()));
    fs::File::create(&probe)
        .and_then(|_| fs::remove_file(&probe))
        .map_err(|e| PowderError::io(format!("cannot write into `{}`", dir.display()), e))
}

/// Refuses an existing regular file that no rename may replace nor unlink remove: one
/// marked immutable or append-only (`chattr +i`, `+a`), which opening it for writing finds
/// (EPERM, where a file's mode, which a rename ignores, gives EACCES). Nothing is written.
fn refuse_immutable(f: &Path) -> Result<(), PowderError> {
    const EPERM: i32 = 1;
    match fs::OpenOptions::new().write(true).open(f) {
        Err(e) if e.raw_os_error() == Some(EPERM) => Err(PowderError::io(
            format!(
                "`{}` cannot be replaced or removed (immutable or append-only: `lsattr` shows which, `chattr -i` or `-a` clears it)",
                f.display()
            ),
            e,
        )),
        _ => Ok(()),
    }
}

/// Refuses, before any work, an output file the command could not write at the end: a
/// folder at `path`, a missing folder for it, or one it may not create files in. `flag`
/// names the option that gave it.
pub fn check_output_file(path: &Path, flag: &str) -> Result<(), PowderError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let problem = if path.is_dir() {
        Some("is a folder: name a file".to_string())
    } else if !dir.is_dir() {
        Some(format!(
            "lies in `{}`, which is not a folder",
            dir.display()
        ))
    } else {
        None
    };
    if let Some(p) = problem {
        return Err(PowderError::Run(format!(
            "`{}` ({flag}) {p}",
            path.display()
        )));
    }
    if path.is_file() {
        refuse_immutable(path)?;
    }
    let probe = dir.join(format!(".powder-probe.{}", std::process::id()));
    fs::File::create(&probe)
        .and_then(|_| fs::remove_file(&probe))
        .map_err(|e| PowderError::io(format!("cannot write `{}` ({flag})", path.display()), e))
}

/// [`check_output_file`] for each of a command's output files (`(path, flag)`, `None`
/// where not asked for), refusing two flags that name one file (the last written would
/// replace the other).
pub fn check_output_files(files: &[(Option<&Path>, &str)]) -> Result<(), PowderError> {
    let mut seen: Vec<(PathBuf, &str)> = Vec::new();
    for &(path, flag) in files {
        let Some(path) = path else { continue };
        check_output_file(path, flag)?;
        // (the folder resolved: `a.svg` and `./a.svg` are one file)
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let key = match (dir.canonicalize(), path.file_name()) {
            (Ok(d), Some(name)) => d.join(name),
            _ => path.to_path_buf(),
        };
        if let Some((_, first)) = seen.iter().find(|(k, _)| *k == key) {
            return Err(PowderError::Run(format!(
                "{first} and {flag} both name `{}`: the second would replace the first; give each its own file",
                path.display()
            )));
        }
        seen.push((key, flag));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A killed run not yet reaped by its parent (a zombie) holds its folder no more: a
    /// resume right after the kill was refused as "held by process N".
    #[test]
    fn a_killed_unreaped_process_is_not_alive() {
        if !Path::new("/proc/self").exists() {
            return;
        }
        let mut child = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .unwrap();
        let pid = child.id();
        assert!(process_alive(pid));
        child.kill().unwrap();
        // (not reaped: the entry stays, a zombie, until wait)
        let zombie = (0..200).any(|_| {
            std::thread::sleep(std::time::Duration::from_millis(10));
            !process_alive(pid)
        });
        assert!(zombie && Path::new(&format!("/proc/{pid}")).exists());
        child.wait().unwrap();
        assert!(!process_alive(pid));
    }

    #[test]
    fn two_flags_naming_one_file_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.svg");
        let b = dir.path().join(".").join("a.svg");
        let err = check_output_files(&[(Some(&a), "--json"), (None, "--x"), (Some(&b), "--plot")])
            .unwrap_err()
            .to_string();
        assert!(err.contains("--json and --plot both name"), "{err}");
        let c = dir.path().join("c.json");
        assert!(check_output_files(&[(Some(&a), "--plot"), (Some(&c), "--json")]).is_ok());
    }

    #[test]
    fn a_folder_is_held_by_one_run_and_a_dead_ones_lock_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let lock = FolderLock::take(dir.path()).unwrap();
        let err = FolderLock::take(dir.path()).unwrap_err().to_string();
        assert!(err.contains("is held by") && err.contains("--out"), "{err}");
        drop(lock);
        assert!(!dir.path().join(LOCK).exists());
        // a live process's lock (pid 1), and a fresh unreadable one, hold
        fs::write(dir.path().join(LOCK), "1").unwrap();
        assert!(FolderLock::take(dir.path()).is_err());
        fs::write(dir.path().join(LOCK), "").unwrap();
        assert!(FolderLock::take(dir.path()).is_err());
        // a process that is no more (beyond Linux's largest pid), and this process's pid
        // where it holds no lock (a restarted container's run has the old one's pid)
        for stale in ["4194305".to_string(), std::process::id().to_string()] {
            fs::write(dir.path().join(LOCK), &stale).unwrap();
            let lock = FolderLock::take(dir.path()).unwrap();
            let held = fs::read_to_string(dir.path().join(LOCK)).unwrap();
            assert_eq!(held, std::process::id().to_string());
            drop(lock);
        }
        // a lock taken over by another run is not removed by the run that lost it
        let lock = FolderLock::take(dir.path()).unwrap();
        fs::write(dir.path().join(LOCK), "1").unwrap();
        drop(lock);
        assert!(dir.path().join(LOCK).exists());
    }

    #[test]
    fn an_output_that_cannot_be_written_is_refused_first() {
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join("series.csv");
        check_writable(dir.path(), &[], std::slice::from_ref(&csv)).unwrap();
        fs::create_dir(&csv).unwrap();
        let err = check_writable(dir.path(), &[], &[csv])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("is a folder where the run writes a file"),
            "{err}"
        );
    }

    /// A file the run would replace or remove, marked immutable or append-only, is refused
    /// by name before anything changes; one whose mode forbids writing is not (a rename
    /// ignores the mode). Needs `chattr` and the right to use it (root on ext4, as CI).
    #[test]
    fn an_immutable_file_the_run_replaces_is_refused_first() {
        let dir = tempfile::tempdir().unwrap();
        let checkpoint = dir.path().join("checkpoint.bin");
        fs::write(&checkpoint, b"earlier").unwrap();
        use std::os::unix::fs::PermissionsExt;
        let mode = |m| fs::set_permissions(&checkpoint, fs::Permissions::from_mode(m)).unwrap();
        mode(0o444);
        check_writable(dir.path(), std::slice::from_ref(&checkpoint), &[]).unwrap();
        mode(0o644);
        /// Clears the flags again, whatever the test does (a flagged file outlives its folder).
        struct Flags<'a>(&'a Path);
        impl Drop for Flags<'_> {
            fn drop(&mut self) {
                let _ = std::process::Command::new("chattr")
                    .arg("-ia")
                    .arg(self.0)
                    .status();
            }
        }
        for flag in ["+i", "+a"] {
            let set = std::process::Command::new("chattr")
                .args([flag, checkpoint.to_str().unwrap()])
                .output();
            if !set.as_ref().is_ok_and(|o| o.status.success()) {
                return eprintln!("skipping: `chattr {flag}` is not available here ({set:?})");
            }
            let _clear = Flags(&checkpoint);
            let err = check_writable(dir.path(), std::slice::from_ref(&checkpoint), &[])
                .unwrap_err()
                .to_string();
            assert!(
                err.contains(
                    "checkpoint.bin` cannot be replaced or removed (immutable or append-only"
                ),
                "{err}"
            );
            assert_eq!(fs::read(&checkpoint).unwrap(), b"earlier");
        }
        // a file both appended to and replaced (`series.csv`), append-only
        let csv = dir.path().join("series.csv");
        fs::write(&csv, b"rows").unwrap();
        if std::process::Command::new("chattr")
            .arg("+a")
            .arg(&csv)
            .status()
            .is_ok_and(|s| s.success())
        {
            let _clear = Flags(&csv);
            let both = std::slice::from_ref(&csv);
            let err = check_writable(dir.path(), both, both)
                .unwrap_err()
                .to_string();
            assert!(err.contains("series.csv` cannot be replaced"), "{err}");
        }
    }

    /// A FIFO where the run writes a file is refused, not opened (which would wait for a
    /// reader for ever).
    #[test]
    fn a_fifo_where_an_output_goes_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("summary.json");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            return eprintln!("skipping: mkfifo is not available here");
        }
        for (replaced, appended) in [(vec![fifo.clone()], vec![]), (vec![], vec![fifo.clone()])] {
            let err = check_writable(dir.path(), &replaced, &appended)
                .unwrap_err()
                .to_string();
            assert!(err.contains("is not a regular file"), "{err}");
        }
    }
}
