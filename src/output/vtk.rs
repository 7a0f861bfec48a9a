//! ParaView output: one VTK XML PolyData file (`.vtp`) per snapshot, with the particles as
//! vertices carrying radius, velocity, angular velocity and id, and a `.pvd` collection
//! that lists the snapshots with their times. Every file is written atomically.

use crate::error::PowderError;
use crate::output::atomic::write_atomic;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One snapshot's particle data.
pub struct Particles<'a> {
    /// Particle centres, m.
    pub positions: &'a [DVec3],
    /// Particle velocities, m/s.
    pub velocities: &'a [DVec3],
    /// Particle radii, m.
    pub radii: &'a [f64],
    /// Empty when the scene has no rotation.
    pub angular_velocities: &'a [DVec3],
    /// Whether each particle has appeared (it neither moves nor interacts before; its
    /// velocity is the one it will enter with); empty when the scene does not pour.
    pub appeared: &'a [bool],
}

fn vector_array(out: &mut String, name: &str, v: &[DVec3]) {
    let _ = writeln!(
        out,
        r#"        <DataArray type="Float64" Name="{name}" NumberOfComponents="3" format="ascii">"#
    );
    for p in v {
        let _ = writeln!(out, "          {:e} {:e} {:e}", p.x, p.y, p.z);
    }
    out.push_str("        </DataArray>\n");
}

/// The `.vtp` text of a snapshot.
pub fn vtp(p: &Particles) -> String {
    let n = p.positions.len();
    let mut s = String::with_capacity(n * 120 + 1024);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str(r#"<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">"#);
    s.push_str("\n  <PolyData>\n");
    let _ = writeln!(
        s,
        r#"    <Piece NumberOfPoints="{n}" NumberOfVerts="{n}" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="0">"#
    );
    s.push_str("      <Points>\n");
    vector_array(&mut s, "position", p.positions);
    s.push_str("      </Points>\n");
    s.push_str("      <PointData Scalars=\"radius\" Vectors=\"velocity\">\n");
    s.push_str("        <DataArray type=\"Float64\" Name=\"radius\" format=\"ascii\">\n");
    for r in p.radii {
        let _ = writeln!(s, "          {r:e}");
    }
    s.push_str("        </DataArray>\n");
    s.push_str("        <DataArray type=\"UInt32\" Name=\"id\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = writeln!(s, "          {i}");
    }
    s.push_str("        </DataArray>\n");
    vector_array(&mut s, "velocity", p.velocities);
    if !p.angular_velocities.is_empty() {
        vector_array(&mut s, "angular_velocity", p.angular_velocities);
    }
    if !p.appeared.is_empty() {
        s.push_str("        <DataArray type=\"UInt8\" Name=\"appeared\" format=\"ascii\">\n");
        for &a in p.appeared {
            let _ = writeln!(s, "          {}", u8::from(a));
        }
        s.push_str("        </DataArray>\n");
    }
    s.push_str("      </PointData>\n");
    s.push_str("      <Verts>\n");
    s.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = writeln!(s, "          {i}");
    }
    s.push_str("        </DataArray>\n");
    s.push_str("        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 1..=n {
        let _ = writeln!(s, "          {i}");
    }
    s.push_str("        </DataArray>\n");
    s.push_str("      </Verts>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
    s
}

/// A series of snapshots in a directory plus their `.pvd` collection.
pub struct Series {
    dir: PathBuf,
    /// The snapshots' folder in `dir`, and their names' prefix.
    folder: String,
    name: String,
    /// The collection's file name in `dir`.
    collection: String,
    entries: Vec<(f64, String)>,
}

impl Series {
    /// Particle snapshots: `dir/snapshots/<name>_<step>.vtp`, collected in `dir/<name>.pvd`.
    pub fn new(dir: &Path, name: &str) -> Result<Self, PowderError> {
        let [particles, _] = Self::both_unopened(dir, name);
        particles.created()
    }

    /// Contact-network snapshots: `dir/contacts/<name>_<step>.vtp`, collected in
    /// `dir/<name>_contacts.pvd`.
    pub fn contacts(dir: &Path, name: &str) -> Result<Self, PowderError> {
        let [_, contacts] = Self::both_unopened(dir, name);
        contacts.created()
    }

    /// Both series of a run named `name` in `dir` (particles, contacts), their folders not
    /// created.
    pub fn both_unopened(dir: &Path, name: &str) -> [Self; 2] {
        [
            Self::unopened(dir, "snapshots", name, &format!("{name}.pvd")),
            Self::unopened(dir, "contacts", name, &format!("{name}_contacts.pvd")),
        ]
    }

    /// The series with its folder created.
    fn created(self) -> Result<Self, PowderError> {
        let snaps = self.folder();
        std::fs::create_dir_all(&snaps).map_err(|e| {
            PowderError::io(
                format!("cannot create the output directory `{}`", snaps.display()),
                e,
            )
        })?;
        Ok(self)
    }

    /// The `.pvd` collection's path.
    pub fn collection_path(&self) -> PathBuf {
        self.dir.join(&self.collection)
    }

    /// Snapshots `dir/<folder>/<name>_<step>.vtp`, collected in `dir/<collection>`, the folder not created (to clear an
    /// earlier run's where this run writes none).
    pub fn unopened(dir: &Path, folder: &str, name: &str, collection: &str) -> Self {
        Self {
            dir: dir.to_path_buf(),
            folder: folder.to_string(),
            name: name.to_string(),
            collection: collection.to_string(),
            entries: Vec::new(),
        }
    }

    /// This series' snapshot files in its folder, with their steps (none without a folder).
    fn files(&self) -> Vec<(u64, PathBuf)> {
        std::fs::read_dir(self.folder())
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| {
                Some((
                    self.step_of_file(&e.file_name().to_string_lossy())?,
                    e.path(),
                ))
            })
            .collect()
    }

    /// The step of a snapshot file of this series (`<name>_<step>.vtp`), by file name.
    fn step_of_file(&self, file: &str) -> Option<u64> {
        let step = file
            .strip_prefix(&self.name)?
            .strip_prefix('_')?
            .strip_suffix(".vtp")?;
        (!step.is_empty() && step.bytes().all(|b| b.is_ascii_digit()))
            .then(|| step.parse().ok())
            .flatten()
    }

    /// Re-opens a series (on resume): keeps the snapshots up to `step` that the earlier
    /// run's collection lists, with its times (a file it does not list is not this run's);
    /// without a collection, those in the folder (times `step · dt`). The series' files of
    /// later steps (a killed or interrupted run's, which the resumed run writes again where
    /// its cadence falls) are removed, and the collection lists only what is kept.
    pub fn keep_until(&mut self, step: u64, dt: f64) -> Result<(), PowderError> {
        let prefix = format!("{}/", self.folder);
        let step_of = |file: &str| self.step_of_file(file.strip_prefix(&prefix)?);
        let mut listed =
            std::fs::read_to_string(self.dir.join(&self.collection)).unwrap_or_default();
        // a cut or garbled collection lists what it still can: the folder tells more
        let damaged = !listed.is_empty() && !listed.contains("</Collection>");
        if damaged {
            listed.clear();
        }
        let mut found: Vec<(u64, f64, String)> = listed
            .lines()
            .filter_map(|l| {
                let attr = |a: &str| l.split(&format!(r#"{a}=""#)).nth(1)?.split('"').next();
                let file = xml_unescape(attr("file")?);
                let time: f64 = attr("timestep")?.parse().ok()?;
                let s = step_of(&file)?;
                (s <= step && self.dir.join(&file).exists()).then_some((s, time, file))
            })
            .collect();
        if listed.is_empty() {
            found = std::fs::read_dir(self.dir.join(&self.folder))
                .map(|rd| {
                    rd.filter_map(|e| e.ok())
                        .filter_map(|e| {
                            let f = format!("{}/{}", self.folder, e.file_name().to_string_lossy());
                            let s = step_of(&f)?;
                            (s <= step).then_some((s, s as f64 * dt, f))
                        })
                        .collect()
                })
                .unwrap_or_default();
        }
        found.sort_by_key(|(s, ..)| *s);
        found.dedup_by_key(|(s, ..)| *s);
        self.entries = found.into_iter().map(|(_, t, f)| (t, f)).collect();
        for (_, path) in self.files().into_iter().filter(|(s, _)| *s > step) {
            remove_if_there(&path, "a later snapshot of the run resumed")?;
        }
        if !listed.is_empty() || damaged {
            self.write_collection()?;
        }
        Ok(())
    }

    /// The latest step of this series' snapshot files in its folder (none without any).
    pub fn last_step(&self) -> Option<u64> {
        self.files().into_iter().map(|(s, _)| s).max()
    }

    /// The snapshot files of this series in its folder.
    pub fn snapshot_count(&self) -> usize {
        self.files().len()
    }

    /// The paths of this series' snapshot files in its folder.
    pub fn snapshot_paths(&self) -> Vec<PathBuf> {
        self.files().into_iter().map(|(_, path)| path).collect()
    }

    /// Removes an earlier run's snapshots of this series (its name's `.vtp` files in the
    /// folder) and its collection (a fresh run starts its own); returns how many snapshots,
    /// and whether there was a collection.
    pub fn clear(&mut self) -> Result<(usize, bool), PowderError> {
        let mut removed = 0;
        for (_, path) in self.files() {
            removed += usize::from(remove_if_there(&path, "the earlier run's")?);
        }
        let collection = remove_if_there(&self.collection_path(), "the earlier run's")?;
        self.entries.clear();
        Ok((removed, collection))
    }

    /// The folder the snapshots go to.
    pub fn folder(&self) -> PathBuf {
        self.dir.join(&self.folder)
    }

    /// The snapshots written so far: (time s, `.vtp` path relative to the output directory).
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// Writes the particle snapshot of `step` and rewrites the collection.
    pub fn write(&mut self, step: u64, time: f64, p: &Particles) -> Result<(), PowderError> {
        self.write_vtp(step, time, vtp(p).as_bytes())
    }

    /// Writes `doc` (a `.vtp` document) as the snapshot of `step` and rewrites the
    /// collection.
    pub fn write_vtp(&mut self, step: u64, time: f64, doc: &[u8]) -> Result<(), PowderError> {
        let file = format!("{}/{}_{step:010}.vtp", self.folder, self.name);
        write_atomic(&self.dir.join(&file), doc)?;
        self.entries.retain(|(_, f)| f != &file);
        self.entries.push((time, file));
        self.write_collection()
    }

    /// Rewrites the collection from the entries.
    fn write_collection(&self) -> Result<(), PowderError> {
        let mut pvd = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (t, f) in &self.entries {
            let _ = writeln!(
                pvd,
                r#"    <DataSet timestep="{t:e}" group="" part="0" file="{}"/>"#,
                xml_escape(f)
            );
        }
        pvd.push_str("  </Collection>\n</VTKFile>\n");
        write_atomic(&self.dir.join(&self.collection), pvd.as_bytes())
    }
}

/// `s` as an XML attribute value (a scene's name may hold `&`, `<`, `>` or `"`).
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The text of an attribute value [`xml_escape`] wrote.
fn xml_unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&gt;", ">")
        .replace("&lt;", "<")
        .replace("&amp;", "&")
}

/// Removes `path` where it exists (whether it did); `whose` names it in the error.
fn remove_if_there(path: &Path, whose: &str) -> Result<bool, PowderError> {
    match std::fs::remove_file(path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(PowderError::io(
            format!("cannot remove {whose} `{}`", path.display()),
            e,
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vtp_has_points_arrays_and_verts() {
        let pos = [DVec3::new(1.0, 2.0, 3.0), DVec3::ZERO];
        let vel = [DVec3::X, DVec3::Y];
        let text = vtp(&Particles {
            positions: &pos,
            velocities: &vel,
            radii: &[0.5, 0.25],
            angular_velocities: &[],
            appeared: &[],
        });
        assert!(text.contains(r#"NumberOfPoints="2""#));
        assert!(text.contains("1e0 2e0 3e0"));
        assert!(text.contains(r#"Name="radius""#) && text.contains(r#"Name="velocity""#));
        assert!(!text.contains("angular_velocity") && !text.contains("appeared"));
        assert!(text.contains(r#"Name="offsets""#));
        // a pouring scene marks the particles that have appeared
        let text = vtp(&Particles {
            positions: &pos,
            velocities: &vel,
            radii: &[0.5, 0.25],
            angular_velocities: &[],
            appeared: &[true, false],
        });
        assert!(text.contains("Name=\"appeared\" format=\"ascii\">\n          1\n          0\n"));
    }

    /// One sphere at rest at the origin.
    fn one_sphere() -> Particles<'static> {
        const AT_REST: [DVec3; 1] = [DVec3::ZERO];
        Particles {
            positions: &AT_REST,
            velocities: &AT_REST,
            radii: &[1.0],
            angular_velocities: &[],
            appeared: &[],
        }
    }

    #[test]
    fn a_resumed_series_keeps_what_its_collection_lists() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = Series::new(dir.path(), "demo").unwrap();
        let p = one_sphere();
        for step in [0, 10, 20] {
            s.write(step, step as f64 * 0.1 + 1e-17, &p).unwrap();
        }
        // a file the collection does not list (another run's) is left out
        std::fs::write(dir.path().join("snapshots/demo_0000000015.vtp"), "x").unwrap();
        let mut again = Series::new(dir.path(), "demo").unwrap();
        again.keep_until(15, 0.1).unwrap();
        // the later snapshot is gone, and the collection lists what is kept
        assert!(!dir.path().join("snapshots/demo_0000000020.vtp").exists());
        let pvd = std::fs::read_to_string(dir.path().join("demo.pvd")).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 2, "{pvd}");
        let files: Vec<&str> = again.entries().iter().map(|(_, f)| f.as_str()).collect();
        assert_eq!(
            files,
            [
                "snapshots/demo_0000000000.vtp",
                "snapshots/demo_0000000010.vtp"
            ]
        );
        // the collection's times, to the bit
        assert_eq!(again.entries()[1].0, 10.0 * 0.1 + 1e-17);
        // without a collection: the folder, times step · dt
        std::fs::remove_file(dir.path().join("demo.pvd")).unwrap();
        again.keep_until(15, 0.5).unwrap();
        assert_eq!(again.entries().len(), 3);
        assert_eq!(again.entries()[2].0, 7.5);
    }

    #[test]
    fn series_writes_snapshots_and_a_collection() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = Series::new(dir.path(), "demo").unwrap();
        let p = one_sphere();
        s.write(0, 0.0, &p).unwrap();
        s.write(10, 0.5, &p).unwrap();
        let pvd = std::fs::read_to_string(dir.path().join("demo.pvd")).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 2);
        assert!(dir.path().join("snapshots/demo_0000000010.vtp").exists());
    }

    /// A name with XML's special characters is escaped in the collection and read back;
    /// a cut collection is rebuilt from the folder, not trusted for what it still lists.
    #[test]
    fn a_collection_escapes_names_and_a_cut_one_is_rebuilt() {
        let dir = tempfile::tempdir().unwrap();
        let name = r#"a&b"<c>"#;
        let mut s = Series::new(dir.path(), name).unwrap();
        let p = one_sphere();
        for step in [0, 10, 20] {
            s.write(step, step as f64, &p).unwrap();
        }
        let path = dir.path().join(format!("{name}.pvd"));
        let pvd = std::fs::read_to_string(&path).unwrap();
        assert!(
            pvd.contains("a&amp;b&quot;&lt;c&gt;_0000000010.vtp"),
            "{pvd}"
        );
        let mut again = Series::new(dir.path(), name).unwrap();
        again.keep_until(20, 1.0).unwrap();
        assert_eq!(again.entries().len(), 3);
        assert_eq!(
            again.entries()[1].1,
            format!("snapshots/{name}_0000000010.vtp")
        );
        // cut after its first entry
        let cut = pvd.find("_0000000010").unwrap();
        std::fs::write(&path, &pvd[..cut]).unwrap();
        let mut again = Series::new(dir.path(), name).unwrap();
        again.keep_until(20, 1.0).unwrap();
        assert_eq!(again.entries().len(), 3);
        let pvd = std::fs::read_to_string(&path).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    }
}
