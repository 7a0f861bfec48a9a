//! The output folder taken by one run at a time (a lock file naming its process), and
//! checked writable before anything in it changes.

use crate::error::PowderError;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The lock file's name in an output folder.
pub const LOCK: &str = ".powder.lock";

/// An output folder held by this run: another run into it is refused while the lock
/// exists; dropping it removes the lock.
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
}

impl FolderLock {
    /// Takes `dir` (created if missing): refused while a live process holds it; a lock
    /// whose process has ended (a killed run) is taken over.
    pub fn take(dir: &Path) -> Result<Self, PowderError> {
        fs::create_dir_all(dir)
            .map_err(|e| PowderError::io(format!("cannot create `{}`", dir.display()), e))?;
        let path = dir.join(LOCK);
        let cannot = |e| PowderError::io(format!("cannot create the lock `{}`", path.display()), e);
        // (twice: once more after removing a stale lock)
        for _ in 0..2 {
            match fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    write!(f, "{}", std::process::id()).map_err(cannot)?;
                    return Ok(Self { path });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let text = fs::read_to_string(&path).unwrap_or_default();
                    match text.trim().parse::<u32>() {
                        Ok(pid) if !process_alive(pid) => {
                            fs::remove_file(&path).map_err(cannot)?;
                        }
                        holder => {
                            let who = holder.map_or("a powder run".to_string(), |pid| {
                                format!("powder run (process {pid})")
                            });
                            return Err(PowderError::Run(format!(
                                "{who} is writing into `{}`: two runs in one folder would mix their outputs; wait for it to end or choose another --out (if no run is writing there, remove `{}`)",
                                dir.display(),
                                path.display()
                            )));
                        }
                    }
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
        let _ = fs::remove_file(&self.path);
    }
}

/// Whether process `pid` runs on this host (always, where `/proc` cannot tell).
pub fn process_alive(pid: u32) -> bool {
    pid == std::process::id()
        || !Path::new("/proc/self").exists()
        || Path::new(&format!("/proc/{pid}")).exists()
}

/// Refuses, before anything in `dir` changes, an output the run could not write: a folder
/// where one of `files` goes, a file it may not write, a folder where it may not create
/// files.
pub fn check_writable(dir: &Path, files: &[PathBuf]) -> Result<(), PowderError> {
    for f in files {
        match fs::metadata(f) {
            Ok(m) if m.is_dir() => {
                return Err(PowderError::Run(format!(
                    "`{}` is a folder where the run writes a file: move it away or choose another --out",
                    f.display()
                )))
            }
            Ok(_) => {
                fs::OpenOptions::new()
                    .append(true)
                    .open(f)
                    .map_err(|e| PowderError::io(format!("cannot write `{}`", f.display()), e))?;
            }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_is_held_by_one_run_and_a_dead_ones_lock_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let lock = FolderLock::take(dir.path()).unwrap();
        let err = FolderLock::take(dir.path()).unwrap_err().to_string();
        assert!(
            err.contains("is writing into") && err.contains("--out"),
            "{err}"
        );
        drop(lock);
        assert!(!dir.path().join(LOCK).exists());
        // a live process's lock (pid 1), and an unreadable one, hold
        fs::write(dir.path().join(LOCK), "1").unwrap();
        assert!(FolderLock::take(dir.path()).is_err());
        fs::write(dir.path().join(LOCK), "").unwrap();
        assert!(FolderLock::take(dir.path()).is_err());
        // a process that is no more (beyond Linux's largest pid)
        fs::write(dir.path().join(LOCK), "4194305").unwrap();
        let _lock = FolderLock::take(dir.path()).unwrap();
        let held = fs::read_to_string(dir.path().join(LOCK)).unwrap();
        assert_eq!(held, std::process::id().to_string());
    }

    #[test]
    fn an_output_that_cannot_be_written_is_refused_first() {
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join("series.csv");
        check_writable(dir.path(), std::slice::from_ref(&csv)).unwrap();
        fs::create_dir(&csv).unwrap();
        let err = check_writable(dir.path(), &[csv]).unwrap_err().to_string();
        assert!(
            err.contains("is a folder where the run writes a file"),
            "{err}"
        );
    }
}
