//! `series.csv`, written row by row as a run produces it: each row is appended and handed
//! to the operating system at once, so a run killed at any point leaves every row it
//! computed (`tail -f` follows it), and a resumed run drops the rows after its checkpoint.

use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::checkpoint::Fnv;

use crate::error::PowderError;
use crate::output::atomic::write_atomic;

/// The series file of a run, open for appending.
pub struct SeriesCsv {
    path: PathBuf,
    file: File,
    /// The step of the last row, so a step is never written twice.
    last: Option<u64>,
    /// The rows written so far, counted and hashed.
    mark: SeriesMark,
}

/// Which rows a series holds: how many and their FNV-1a hash (a checkpoint keeps the mark
/// of the rows its run had written, so a resume keeps no other run's rows).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeriesMark {
    /// Rows, the header not counted.
    pub rows: u64,
    /// FNV-1a of the rows, each with its line end.
    pub digest: u64,
}

impl Default for SeriesMark {
    fn default() -> Self {
        Self {
            rows: 0,
            digest: Fnv::new().0,
        }
    }
}

impl SeriesMark {
    /// The mark of `rows`.
    pub fn of(rows: &[String]) -> Self {
        let mut mark = Self::default();
        for r in rows {
            mark.add(r);
        }
        mark
    }

    fn add(&mut self, row: &str) {
        let mut h = Fnv(self.digest);
        let _ = writeln!(h, "{row}");
        self.digest = h.0;
        self.rows += 1;
    }
}

impl SeriesCsv {
    /// Starts the series at `path`: the header and `kept` rows (a resumed run's rows up to
    /// its checkpoint), written atomically, then open for appending.
    pub fn start(path: &Path, header: &str, kept: &[String]) -> Result<Self, PowderError> {
        let mut text = format!("{header}\n");
        for r in kept {
            text.push_str(r);
            text.push('\n');
        }
        write_atomic(path, text.as_bytes())?;
        let file = OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| PowderError::io(format!("cannot open `{}`", path.display()), e))?;
        Ok(Self {
            path: path.to_path_buf(),
            file,
            last: kept.last().and_then(|r| row_step(r)),
            mark: SeriesMark::of(kept),
        })
    }

    /// The rows written so far.
    pub fn mark(&self) -> SeriesMark {
        self.mark
    }

    /// Appends the row of `step` in one write (a torn last line, from a kill or a full
    /// disk, is dropped by [`rows_until`] on resume); a step already written is skipped.
    pub fn append(&mut self, step: u64, row: &str) -> Result<(), PowderError> {
        if self.last.is_some_and(|last| step <= last) {
            return Ok(());
        }
        let line = format!("{row}\n");
        self.file
            .write_all(line.as_bytes())
            .map_err(|e| PowderError::io(format!("cannot write `{}`", self.path.display()), e))?;
        self.last = Some(step);
        self.mark.add(row);
        Ok(())
    }

    /// Flushes the rows to the disk (with a checkpoint: a power cut then loses neither).
    pub fn sync(&mut self) -> Result<(), PowderError> {
        self.file
            .sync_data()
            .map_err(|e| PowderError::io(format!("cannot write `{}`", self.path.display()), e))
    }
}

/// The whole rows of an earlier series up to `step` (a resume from a checkpoint of that
/// step), in order; none when there is no file. A line without its end (a write cut by a
/// kill) ends them. A series with another `header` (other columns) is refused.
pub fn rows_until(path: &Path, step: u64, header: &str) -> Result<Vec<String>, PowderError> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => {
            return Err(PowderError::io(
                format!("cannot read the series `{}` to resume it", path.display()),
                e,
            ))
        }
    };
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        PowderError::Run(format!(
            "the series `{}` is not text at byte {} (damaged or not powder's): move it away to resume into this folder (the series then starts at the checkpoint's step), or resume into an empty folder with --out",
            path.display(),
            e.valid_up_to()
        ))
    })?;
    // (a header cut by a kill holds no rows either)
    let first = text
        .split_inclusive('\n')
        .next()
        .and_then(|l| l.strip_suffix('\n'));
    if first.is_some_and(|first| first != header) {
        return Err(PowderError::Run(format!(
            "the series `{}` has other columns than this scene's (a wall that moves only after the checkpoint adds its position): resume into another --out directory",
            path.display()
        )));
    }
    Ok(text
        .split_inclusive('\n')
        .skip(1)
        .map_while(|l| l.strip_suffix('\n'))
        .take_while(|l| row_step(l).is_some_and(|s| s <= step))
        .map(str::to_string)
        .collect())
}

/// The step of the last whole row of the series at `path`; `None` without a file or rows.
pub fn last_row_step(path: &Path) -> Option<u64> {
    let text = std::fs::read(path).ok()?;
    let text = String::from_utf8_lossy(&text);
    text.split_inclusive('\n')
        .skip(1)
        .filter_map(|l| l.strip_suffix('\n'))
        .filter_map(row_step)
        .last()
}

/// Whether `row` is the row of `step`.
pub fn row_is_at(row: &str, step: u64) -> bool {
    row_step(row) == Some(step)
}

/// The step a row starts with.
fn row_step(row: &str) -> Option<u64> {
    row.split(',').next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_appended_once_and_a_restart_keeps_the_earlier_ones() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("series.csv");
        let mut s = SeriesCsv::start(&p, "step,x", &[]).unwrap();
        let rows = [
            (0, "0,a", "0,a"),
            (10, "10,b", "10,b"),
            (10, "10,c", "10,b"),
            (20, "20,d", "20,d"),
        ];
        for (step, row, last) in rows {
            s.append(step, row).unwrap();
            // in the file at once, not at the end of the run
            let text = std::fs::read_to_string(&p).unwrap();
            assert_eq!(text.lines().last(), Some(last));
        }
        assert_eq!(
            std::fs::read_to_string(&p).unwrap(),
            "step,x\n0,a\n10,b\n20,d\n"
        );
        let kept = rows_until(&p, 10, "step,x").unwrap();
        assert_eq!(kept, ["0,a", "10,b"]);
        let mut s = SeriesCsv::start(&p, "step,x", &kept).unwrap();
        s.append(10, "10,z").unwrap();
        s.append(30, "30,e").unwrap();
        s.sync().unwrap();
        assert_eq!(
            std::fs::read_to_string(&p).unwrap(),
            "step,x\n0,a\n10,b\n30,e\n"
        );
        assert!(rows_until(&dir.path().join("none.csv"), 5, "step,x")
            .unwrap()
            .is_empty());
        // a row cut by a kill (here inside its step) is not kept
        std::fs::write(&p, "step,x\n0,a\n10,b\n2").unwrap();
        assert_eq!(rows_until(&p, 30, "step,x").unwrap(), ["0,a", "10,b"]);
        // other columns (a branch whose wall moves only after the checkpoint): refused
        let other = rows_until(&p, 30, "step,x,y").unwrap_err().to_string();
        assert!(other.contains("other columns"), "{other}");
        std::fs::write(&p, "ste").unwrap();
        assert!(rows_until(&p, 30, "step,x,y").unwrap().is_empty());
        std::fs::write(&p, "step,x\n0,a\n10,b\n20,d").unwrap();
        assert_eq!(rows_until(&p, 30, "step,x").unwrap(), ["0,a", "10,b"]);
        std::fs::write(&p, [b's', 0xff, b'\n']).unwrap();
        let e = rows_until(&p, 30, "step,x").unwrap_err().to_string();
        assert!(
            e.contains("is not text at byte 1") && e.contains("move it away"),
            "{e}"
        );
    }
}
