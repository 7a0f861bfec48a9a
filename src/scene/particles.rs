//! Particle blocks and their generators: explicit lists, lattices and random placement
//! with size distributions.

use super::declared::Section;
use super::hash_grid::{dist2, sq, Grid};
use super::keys::{particle_keys, size_keys, DISTRIBUTIONS, PARTICLE_KINDS};
use super::parse::material_ref;
use super::toml_reader::{fmt_vec, Res, Tbl, AXES};
use super::{ParticleInit, MAX_BLOCK_PARTICLES, MAX_PLACEMENT_ATTEMPTS};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, LogNormal, Normal};
use rand_pcg::Pcg64;

/// Where each particle came from, for messages: the 1-based `[[particles]]` block.
pub(super) type Origin = Vec<usize>;

pub(super) fn parse_particles(root: &Tbl, names: &[&str]) -> Res<(Vec<ParticleInit>, Origin)> {
    let blocks = root.tables("particles")?;
    if blocks.is_empty() {
        return Err(root.src.err(
            None,
            "the scene has no particles: add a [[particles]] block (kind = \"list\", \"lattice\" or \"random\")",
        ));
    }
    let mut particles: Vec<ParticleInit> = Vec::new();
    let mut origin: Origin = Vec::new();
    for (i, (span, entries)) in blocks.into_iter().enumerate() {
        let block = i + 1;
        let mut t = Tbl::new(
            root.src,
            entries,
            Some(span),
            format!("[[particles]] #{block}"),
        );
        let kind = t.choice("kind", PARTICLE_KINDS)?.ok_or_else(|| {
            t.missing(
                "kind",
                "how to create the particles: \"list\", \"lattice\" or \"random\"",
            )
        })?;
        t.ctx = format!("[[particles]] #{block} (kind = \"{kind}\")");
        let before = particles.len();
        let insert_at = t.number_or_default(Section::Particles, "insert_at")?;
        match kind {
            "list" => {
                t.check_keys(&particle_keys(kind), |_| None)?;
                expand_list(&t, names, &mut particles)?;
            }
            "lattice" => {
                t.check_keys(&particle_keys(kind), |_| None)?;
                expand_lattice(&t, names, &mut particles)?;
            }
            _ => {
                t.check_keys(&particle_keys(kind), |_| None)?;
                // pouring: `batches` batches of count/batches, `batch_interval` s apart,
                // each placed afresh in the region
                let batches = t.count_or_default(Section::Particles, "batches")?;
                let interval = t.number_or_default(Section::Particles, "batch_interval")?;
                if batches > 1 && interval <= 0.0 {
                    return Err(t.err_key(
                        "batches",
                        format!(
                            "{}: a pour of several batches needs `batch_interval` > 0 s (the time between them)",
                            t.ctx
                        ),
                    ));
                }
                // (a batch of none is a mistake, and a loop of 10^9 empty ones a hang)
                if let Some(count) = t.u64("count").ok().flatten() {
                    if count > MAX_BLOCK_PARTICLES {
                        return Err(t.err_key(
                            "count",
                            format!(
                                "`count` in {} is {count}, more than the limit {MAX_BLOCK_PARTICLES}",
                                t.ctx
                            ),
                        ));
                    }
                    if batches > count.max(1) {
                        return Err(t.err_key(
                            "batches",
                            format!(
                                "{}: `batches` = {batches} is more than `count` = {count}: every batch must place a particle at least",
                                t.ctx
                            ),
                        ));
                    }
                }
                for k in 0..batches {
                    // (each batch is placed clear of its own time's particles only)
                    let at = insert_at + k as f64 * interval;
                    if k > 0 && at == insert_at + (k - 1) as f64 * interval {
                        return Err(t.err_key(
                            "batch_interval",
                            format!(
                                "{}: batches {} and {k} fall at the same time {at:e} s: `batch_interval` is below the rounding of `insert_at`",
                                t.ctx,
                                k - 1
                            ),
                        ));
                    }
                    expand_random(
                        &t,
                        names,
                        &mut particles,
                        insert_at + k as f64 * interval,
                        (k, batches, before),
                    )?;
                }
            }
        }
        if kind != "random" {
            for p in &mut particles[before..] {
                p.insert_at = insert_at;
            }
        }
        origin.resize(origin.len() + particles.len() - before, block);
    }
    Ok((particles, origin))
}

/// Reads an optional `velocity` (for all particles of a block).
fn block_velocity(t: &Tbl) -> Res<[f64; 3]> {
    Ok(t.vec3("velocity")?.unwrap_or([0.0; 3]))
}

fn block_angular_velocity(t: &Tbl) -> Res<[f64; 3]> {
    Ok(t.vec3("angular_velocity")?.unwrap_or([0.0; 3]))
}

fn region(t: &Tbl) -> Res<([f64; 3], [f64; 3])> {
    let min = t.vec3_req("min", "the lower corner [x, y, z] of the region in m")?;
    let max = t.vec3_req("max", "the upper corner [x, y, z] of the region in m")?;
    for a in 0..3 {
        if max[a] <= min[a] {
            return Err(t.err_key(
                "max",
                format!(
                    "the region of {} must have `max` > `min` on every axis, but on axis {} max = {} <= min = {}",
                    t.ctx, AXES[a], max[a], min[a]
                ),
            ));
        }
    }
    Ok((min, max))
}

fn one_of(t: &Tbl, a: &str, b: &str, what: &str) -> Res<()> {
    match (t.has(a), t.has(b)) {
        (true, true) => Err(t.err_key(
            b,
            format!("{} has both `{a}` and `{b}`: give only one ({what})", t.ctx),
        )),
        (false, false) => Err(t.err_table(format!(
            "missing required key in {}: give `{a}` or `{b}` ({what})",
            t.ctx
        ))),
        _ => Ok(()),
    }
}

fn expand_list(t: &Tbl, names: &[&str], out: &mut Vec<ParticleInit>) -> Res<()> {
    let material = material_ref(t, names)?;
    let positions = t
        .vec3_list("positions")?
        .ok_or_else(|| t.missing("positions", "the particle centres [[x, y, z], ...] in m"))?;
    let n = positions.len();
    one_of(
        t,
        "radius",
        "radii",
        "one radius for all particles in m, or one per position",
    )?;
    let radii = match t.number(Section::Particles, "radius")? {
        Some(r) => vec![r; n],
        None => {
            let radii = t.f64_list("radii")?.unwrap_or_default();
            if radii.len() != n {
                return Err(t.err_key(
                    "radii",
                    format!(
                        "`radii` in {} has {} entries but `positions` has {n}: give one radius per position",
                        t.ctx,
                        radii.len()
                    ),
                ));
            }
            if let Some((i, r)) = radii.iter().enumerate().find(|(_, r)| **r <= 0.0) {
                return Err(t.err_key(
                    "radii",
                    format!(
                        "`radii[{i}]` in {} must be > 0 (a radius in m), got {r}",
                        t.ctx
                    ),
                ));
            }
            radii
        }
    };
    if t.has("velocity") && t.has("velocities") {
        return Err(t.err_key(
            "velocities",
            format!(
                "{} has both `velocity` and `velocities`: give only one (one velocity for all, or one per position)",
                t.ctx
            ),
        ));
    }
    let velocities = match t.vec3_list("velocities")? {
        Some(v) => {
            if v.len() != n {
                return Err(t.err_key(
                    "velocities",
                    format!(
                        "`velocities` in {} has {} entries but `positions` has {n}: give one velocity per position",
                        t.ctx,
                        v.len()
                    ),
                ));
            }
            v
        }
        None => vec![block_velocity(t)?; n],
    };
    let angular_velocity = block_angular_velocity(t)?;
    for i in 0..n {
        out.push(ParticleInit {
            position: positions[i],
            velocity: velocities[i],
            angular_velocity,
            radius: radii[i],
            material,
            insert_at: 0.0,
        });
    }
    Ok(())
}

fn expand_lattice(t: &Tbl, names: &[&str], out: &mut Vec<ParticleInit>) -> Res<()> {
    let material = material_ref(t, names)?;
    let (min, max) = region(t)?;
    let radius = t.number_req(Section::Particles, "radius")?;
    let spacing = t
        .positive("spacing", "the lattice spacing in m")?
        .unwrap_or(2.0 * radius * (1.0 + 1e-9));
    if spacing < 2.0 * radius {
        return Err(t.err_key(
            "spacing",
            format!(
                "`spacing` in {} ({spacing}) must be >= 2*radius ({}), or neighbours overlap",
                t.ctx,
                2.0 * radius
            ),
        ));
    }
    let jitter = t.number_or_default(Section::Particles, "jitter")?;
    let seed = t.count_or_default(Section::Particles, "seed")?;
    let velocity = block_velocity(t)?;
    let angular_velocity = block_angular_velocity(t)?;
    // (in f64: a count beyond u64, e.g. a radius of 1e-22 m, is refused, not wrapped)
    let mut counts = [0f64; 3];
    for a in 0..3 {
        let free = max[a] - min[a] - 2.0 * radius;
        if free < -1e-9 * radius {
            return Err(t.err_key(
                "radius",
                format!(
                    "the region of {} is narrower than one particle diameter ({}) on axis {}: enlarge the region or reduce `radius`",
                    t.ctx,
                    2.0 * radius,
                    AXES[a]
                ),
            ));
        }
        // the tolerance keeps a region of exactly n diameters at n particles
        counts[a] = (free.max(0.0) / spacing + 1e-6).floor() + 1.0;
    }
    let total = counts[0] * counts[1] * counts[2];
    if total.is_nan() || total > MAX_BLOCK_PARTICLES as f64 {
        return Err(t.err_key(
            "spacing",
            format!(
                "{} would create {total:.3e} particles (more than {MAX_BLOCK_PARTICLES}): check `spacing`, `radius` and the region",
                t.ctx
            ),
        ));
    }
    let mut counts = counts.map(|c| c as u64);
    // A last site the count's tolerance admitted lies up to 10⁻⁶ of the spacing beyond the
    // region: the sites are spread evenly over it instead (clamped, it overlapped its
    // neighbour), or, where that would bring neighbours closer than 2·radius, dropped.
    let mut step = [spacing; 3];
    for a in 0..3 {
        let last = min[a] + radius + (counts[a] - 1) as f64 * spacing;
        if counts[a] > 1 && last > max[a] - radius {
            let even = (max[a] - min[a] - 2.0 * radius) / (counts[a] - 1) as f64;
            if even >= 2.0 * radius * (1.0 - 1e-12) {
                step[a] = even;
            } else {
                counts[a] -= 1;
            }
        }
    }
    let total = counts[0] * counts[1] * counts[2];
    crate::memory::check_particles(
        total + out.len() as u64,
        crate::memory::CPU_BYTES_PER_PARTICLE,
        "this scene",
    )
    .map_err(|m| t.err_key("spacing", format!("{}: {m}", t.ctx)))?;
    let amp = step.map(|h| 0.5 * jitter * (h - 2.0 * radius).max(0.0));
    // (drawn wherever the spacing leaves a gap, so the sequence follows the spacing alone)
    let draws = jitter > 0.0 && spacing > 2.0 * radius;
    let mut rng = Pcg64::seed_from_u64(seed);
    out.reserve(total as usize);
    for iz in 0..counts[2] {
        for iy in 0..counts[1] {
            for ix in 0..counts[0] {
                let idx = [ix, iy, iz];
                let mut p = [0.0; 3];
                for a in 0..3 {
                    let mut x = min[a] + radius + idx[a] as f64 * step[a];
                    if draws {
                        x += amp[a] * (2.0 * rng.random::<f64>() - 1.0);
                    }
                    // (every site lies in [min + r, max − r]: clamping only shortens a
                    // jitter displacement, so it cannot create overlaps; a region narrower
                    // than a diameter by rounding has its one site centred)
                    let (lo, hi) = (min[a] + radius, max[a] - radius);
                    p[a] = if lo <= hi {
                        x.clamp(lo, hi)
                    } else {
                        0.5 * (min[a] + max[a])
                    };
                }
                out.push(ParticleInit {
                    position: p,
                    velocity,
                    angular_velocity,
                    radius,
                    material,
                    insert_at: 0.0,
                });
            }
        }
    }
    Ok(())
}

/// A radius distribution of a `random` block.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum SizeDist {
    Fixed(f64),
    Uniform {
        min: f64,
        max: f64,
    },
    Normal {
        mean: f64,
        std: f64,
    },
    LogNormal {
        median: f64,
        sigma: f64,
    },
    /// Radii with cumulative normalised weights.
    List {
        radii: Vec<f64>,
        cumulative: Vec<f64>,
    },
}

impl SizeDist {
    /// A radius > 0. Normal radii are redrawn until positive (mean > 0 makes this quick).
    pub(super) fn sample(&self, rng: &mut Pcg64) -> f64 {
        match self {
            Self::Fixed(r) => *r,
            Self::Uniform { min, max } => min + (max - min) * rng.random::<f64>(),
            Self::Normal { mean, std } => {
                let d = Normal::new(*mean, *std).expect("validated normal parameters");
                loop {
                    let r = d.sample(rng);
                    if r > 0.0 {
                        return r;
                    }
                }
            }
            Self::LogNormal { median, sigma } => LogNormal::new(median.ln(), *sigma)
                .expect("validated lognormal parameters")
                .sample(rng),
            Self::List { radii, cumulative } => {
                let u = rng.random::<f64>();
                let i = cumulative.partition_point(|c| *c <= u).min(radii.len() - 1);
                radii[i]
            }
        }
    }
}

fn parse_size(t: &Tbl) -> Res<SizeDist> {
    if let Some(r) = t.number(Section::Particles, "radius")? {
        return Ok(SizeDist::Fixed(r));
    }
    let s = t
        .table("size", format!("`size` of {}", t.ctx))?
        .expect("one_of checked radius or size");
    if !s.has("distribution") {
        s.check_keys(&size_keys(None), |_| None)?;
    }
    let dist = s.choice("distribution", DISTRIBUTIONS)?.ok_or_else(|| {
        s.missing(
            "distribution",
            "\"uniform\", \"normal\", \"lognormal\" or \"list\"",
        )
    })?;
    s.check_keys(&size_keys(Some(dist)), |_| None)?;
    Ok(match dist {
        "uniform" => {
            let min = s.number_req(Section::Size, "min")?;
            let max = s.positive_req("max", "the largest radius in m")?;
            if max < min {
                return Err(s.err_key(
                    "max",
                    format!("`max` ({max}) in {} must be >= `min` ({min})", s.ctx),
                ));
            }
            SizeDist::Uniform { min, max }
        }
        "normal" => SizeDist::Normal {
            mean: s.number_req(Section::Size, "mean")?,
            std: s.number_req(Section::Size, "std")?,
        },
        "lognormal" => SizeDist::LogNormal {
            median: s.number_req(Section::Size, "median")?,
            sigma: s.number_req(Section::Size, "sigma")?,
        },
        _ => {
            let radii = s
                .f64_list("radii")?
                .ok_or_else(|| s.missing("radii", "the possible radii in m"))?;
            if radii.is_empty() {
                return Err(s.err_key("radii", format!("`radii` in {} must not be empty", s.ctx)));
            }
            if let Some((i, r)) = radii.iter().enumerate().find(|(_, r)| **r <= 0.0) {
                return Err(s.err_key(
                    "radii",
                    format!(
                        "`radii[{i}]` in {} must be > 0 (a radius in m), got {r}",
                        s.ctx
                    ),
                ));
            }
            let weights = s.f64_list("weights")?.unwrap_or(vec![1.0; radii.len()]);
            if weights.len() != radii.len() {
                return Err(s.err_key(
                    "weights",
                    format!(
                        "`weights` in {} has {} entries but `radii` has {}: give one weight per radius",
                        s.ctx,
                        weights.len(),
                        radii.len()
                    ),
                ));
            }
            let mut weights = weights;
            // (weights near f64's largest sum to inf: scaled by the largest, they do not)
            if !weights.iter().sum::<f64>().is_finite() {
                let largest = weights.iter().copied().fold(0.0, f64::max);
                if largest.is_finite() && largest > 0.0 {
                    weights.iter_mut().for_each(|w| *w /= largest);
                }
            }
            let sum: f64 = weights.iter().sum();
            if weights.iter().any(|w| *w < 0.0) || sum.is_nan() || sum <= 0.0 {
                return Err(s.err_key(
                    "weights",
                    format!("`weights` in {} must be >= 0 with a positive sum", s.ctx),
                ));
            }
            let mut acc = 0.0;
            let cumulative = weights
                .iter()
                .map(|w| {
                    acc += w / sum;
                    acc
                })
                .collect();
            SizeDist::List { radii, cumulative }
        }
    })
}

/// Places batch `batch.0` of `batch.1` of a random block (count/batches particles, the
/// first batches taking the remainder) at time `insert_at`, clear of the particles that
/// appear at the same time (those of the blocks before, `out[..batch.2]`: the block's
/// other batches appear at other times).
fn expand_random(
    t: &Tbl,
    names: &[&str],
    out: &mut Vec<ParticleInit>,
    insert_at: f64,
    batch: (u64, u64, usize),
) -> Res<()> {
    let material = material_ref(t, names)?;
    let total = t
        .u64("count")?
        .ok_or_else(|| t.missing("count", "the number of particles to place"))?;
    // (the block's count is held to the limit before its batches)
    let count = total / batch.1 + u64::from(batch.0 < total % batch.1);
    crate::memory::check_particles(
        count + out.len() as u64,
        crate::memory::CPU_BYTES_PER_PARTICLE,
        "this scene",
    )
    .map_err(|m| t.err_key("count", format!("{}: {m}", t.ctx)))?;
    let (min, max) = region(t)?;
    let seed = t
        .count_or_default(Section::Particles, "seed")?
        .wrapping_add(batch.0);
    one_of(
        t,
        "radius",
        "size",
        "a fixed radius in m, or a size distribution",
    )?;
    let size = parse_size(t)?;
    let velocity = block_velocity(t)?;
    let angular_velocity = block_angular_velocity(t)?;

    let mut rng = Pcg64::seed_from_u64(seed);
    let radii: Vec<f64> = (0..count).map(|_| size.sample(&mut rng)).collect();
    let block_rmax = radii.iter().copied().fold(0.0, f64::max);
    for a in 0..3 {
        if 2.0 * block_rmax > max[a] - min[a] {
            return Err(t.err_key(
                "max",
                format!(
                    "the region of {} is narrower on axis {} ({}) than the largest particle diameter drawn ({}): enlarge the region or use smaller particles",
                    t.ctx,
                    AXES[a],
                    crate::error::num(max[a] - min[a]),
                    crate::error::num(2.0 * block_rmax)
                ),
            ));
        }
    }
    let earlier = &out[..batch.2];
    let rmax = earlier.iter().map(|p| p.radius).fold(block_rmax, f64::max);
    let mut grid = Grid::new(2.0 * rmax);
    for (i, p) in earlier.iter().enumerate() {
        // particles that appear at another time may occupy the same place
        if p.insert_at == insert_at {
            grid.insert(i, p.position);
        }
    }
    let before = out.len();
    for (k, &r) in radii.iter().enumerate() {
        let mut placed = false;
        for _ in 0..MAX_PLACEMENT_ATTEMPTS {
            let mut p = [0.0; 3];
            for a in 0..3 {
                p[a] = min[a] + r + (max[a] - min[a] - 2.0 * r) * rng.random::<f64>();
            }
            let free = grid
                .neighbours(p, r + rmax)
                .all(|j| dist2(p, out[j].position) >= sq(r + out[j].radius));
            if free {
                grid.insert(out.len(), p);
                out.push(ParticleInit {
                    position: p,
                    velocity,
                    angular_velocity,
                    radius: r,
                    material,
                    insert_at,
                });
                placed = true;
                break;
            }
        }
        if !placed {
            return Err(t.err_key(
                "count",
                format!(
                    "{} could place only {k} of {count} particles in the region {} to {} ({MAX_PLACEMENT_ATTEMPTS} attempts found no free spot for the next one, avoiding the {before} particle(s) of earlier blocks): use a larger region, fewer or smaller particles (random placement jams near a solid fraction of 0.38), or a lattice",
                    t.ctx,
                    fmt_vec(min),
                    fmt_vec(max)
                ),
            ));
        }
    }
    Ok(())
}
