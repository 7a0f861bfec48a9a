//! Scenes for tests built from their parts instead of copied TOML: each method adds the
//! table the file format would hold, so every scene still goes through the parser.

#![allow(dead_code)]

use powder::scene::Scene;

/// The cohesive law most tests use: hysteretic, kp/k1 = 5, kc = k1, φf = 0.05, damped.
pub const COHESIVE: &str =
    "model = \"hysteretic\"\nk1 = 100.0\nkp = 500.0\nkc = 100.0\nphi_f = 0.05\ngamma0 = 1e-3";

/// The cohesive law at half the cohesion (kc = k1/2): between the families of mixed scenes.
pub const HALF_COHESIVE: &str =
    "model = \"hysteretic\"\nk1 = 100.0\nkp = 500.0\nkc = 50.0\nphi_f = 0.05\ngamma0 = 1e-3";

/// The cohesive law with Luding's sliding (μs > μd), rolling and twisting friction.
pub const ROUGH: &str =
    "model = \"hysteretic\"\nk1 = 100.0\nkp = 500.0\nkc = 100.0\nphi_f = 0.05\n\
     gamma0 = 1e-3\nfriction = 0.5\nfriction_dynamic = 0.4\nrolling_friction = 0.1\n\
     twisting_friction = 0.1";

/// STICKY for micro-spheres: a thousand times stiffer, a fifth of the surface energy.
pub const MICRO: &str = "model = \"jkr\"\nyoungs = 1e8\npoisson = 0.3\nsurface_energy = 0.01\n\
     restitution = 0.5\nfriction = 0.3\nrolling_hysteresis = 0.5";

/// Adhesive JKR with Tsuji damping, Mindlin friction and rolling resistance.
pub const STICKY: &str = "model = \"jkr\"\nyoungs = 1e5\npoisson = 0.3\nsurface_energy = 0.05\n\
     restitution = 0.5\nfriction = 0.3\nrolling_hysteresis = 0.5";

/// A scene's tables, in the order the file format reads best.
pub struct SceneBuilder {
    name: String,
    domain: Vec<String>,
    simulation: Vec<String>,
    materials: Vec<String>,
    interactions: Vec<String>,
    walls: Vec<String>,
    particles: Vec<String>,
}

/// A vector as TOML.
pub fn vec3(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

impl SceneBuilder {
    /// A scene named `name` in the box from `min` to `max` (m), one simulated `duration` (s).
    pub fn new(name: &str, min: [f64; 3], max: [f64; 3], duration: f64) -> Self {
        Self {
            name: name.into(),
            domain: vec![
                format!("min = {}", vec3(min)),
                format!("max = {}", vec3(max)),
            ],
            simulation: vec![format!("duration = {duration:?}")],
            materials: Vec::new(),
            interactions: Vec::new(),
            walls: Vec::new(),
            particles: Vec::new(),
        }
    }

    /// Periodic axes.
    pub fn periodic(mut self, axes: [bool; 3]) -> Self {
        self.domain.push(format!(
            "periodic = [{}, {}, {}]",
            axes[0], axes[1], axes[2]
        ));
        self
    }

    /// Earth's gravity along −z.
    pub fn gravity(self) -> Self {
        self.simulation("gravity", "[0.0, 0.0, -9.81]")
    }

    /// Any `[simulation]` key, its value as TOML.
    pub fn simulation(mut self, key: &str, value: &str) -> Self {
        self.simulation.push(format!("{key} = {value}"));
        self
    }

    /// A material: its name, density (kg/m³) and contact law (`model = …` and its keys).
    pub fn material(mut self, name: &str, density: f64, law: &str) -> Self {
        self.materials.push(format!(
            "[[material]]\nname = \"{name}\"\ndensity = {density:?}\n{law}"
        ));
        self
    }

    /// The law between two materials' particles (`[[interaction]]`).
    pub fn interaction(mut self, [a, b]: [&str; 2], law: &str) -> Self {
        self.interactions.push(format!(
            "[[interaction]]\nmaterials = [\"{a}\", \"{b}\"]\n{law}"
        ));
        self
    }

    /// A fixed wall through `point` facing `normal`.
    pub fn wall(mut self, point: [f64; 3], normal: [f64; 3]) -> Self {
        self.walls.push(format!(
            "[[wall]]\npoint = {}\nnormal = {}",
            vec3(point),
            vec3(normal)
        ));
        self
    }

    /// A wall through `point` facing `normal` with more keys (its motion, material, ...) as
    /// TOML.
    pub fn wall_with(mut self, point: [f64; 3], normal: [f64; 3], keys: &str) -> Self {
        self = self.wall(point, normal);
        if let Some(wall) = self.walls.last_mut() {
            wall.push('\n');
            wall.push_str(keys);
        }
        self
    }

    /// The floor: a fixed wall at z = 0 facing up.
    pub fn floor(self) -> Self {
        self.wall([0.0; 3], [0.0, 0.0, 1.0])
    }

    /// The floor, of `material` (its contacts follow that material's law).
    pub fn floor_of(mut self, material: &str) -> Self {
        self = self.floor();
        if let Some(wall) = self.walls.last_mut() {
            wall.push_str(&format!("\nmaterial = \"{material}\""));
        }
        self
    }

    /// A particle block of `kind` ("list", "lattice", "random") with its other keys as TOML.
    pub fn particles(mut self, kind: &str, keys: &str) -> Self {
        self.particles
            .push(format!("[[particles]]\nkind = \"{kind}\"\n{keys}"));
        self
    }

    /// The scene file's text.
    pub fn toml(&self) -> String {
        let mut out = format!(
            "[domain]\n{}\n\n[simulation]\n{}\n",
            self.domain.join("\n"),
            self.simulation.join("\n")
        );
        for table in self
            .materials
            .iter()
            .chain(&self.interactions)
            .chain(&self.walls)
            .chain(&self.particles)
        {
            out.push('\n');
            out.push_str(table);
            out.push('\n');
        }
        out
    }

    /// The scene, parsed (a test scene that does not parse is a bug in the test).
    pub fn build(&self) -> Scene {
        let text = self.toml();
        Scene::from_toml_str(&text, &self.name)
            .unwrap_or_else(|e| panic!("test scene `{}` does not parse: {e}\n{text}", self.name))
    }
}

/// 60 cohesive spheres thrown sideways in a box periodic in x and y, above a floor, under
/// gravity: they cross the periodic faces and touch across them.
pub fn periodic_cluster() -> Scene {
    SceneBuilder::new("periodic_cluster", [0.0; 3], [0.012, 0.012, 0.02], 0.05)
        .periodic([true, true, false])
        .gravity()
        .material("powder", 2000.0, COHESIVE)
        .floor()
        .particles(
            "random",
            "count = 60\nmin = [0.0, 0.0, 0.0012]\nmax = [0.012, 0.012, 0.015]\n\
             radius = 1.0e-3\nvelocity = [0.05, 0.03, 0.0]\nseed = 4",
        )
        .build()
}
