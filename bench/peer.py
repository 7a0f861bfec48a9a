#!/usr/bin/env python3
"""powder against the peers: LAMMPS (pair_style granular jkr) and LIGGGHTS (hooke/hysteresis).

Standard library only. One packing (a jittered simple-cubic lattice in which every lattice
neighbour overlaps by about the JKR zero-load overlap, so each particle starts with six
contacts) is written as

  * a powder scene (particles as an explicit list),
  * a LAMMPS data file + input deck (atom_style sphere, pair_style granular jkr, damping
    tsuji, tangential mindlin, fix nve/sphere),
  * a LIGGGHTS input deck (pair_style gran model hooke/hysteresis) for the hysteretic case,

with the same positions (the same decimal strings), radii, density, time step, neighbour skin
(0.1 r_min, rebuild on half-skin displacement) and box (no walls, no gravity, a box two radii
larger than the packing on every side). Then each code steps it and the throughput in
particle-steps/s is compared (best of --repeats; the codes of one size and case take turns,
one run each per round, so a drift of the machine's speed slows them alike):

  python3 bench/peer.py                 # N = 1e4 and 1e5, 2000 steps, best of 3
  python3 bench/peer.py --quick         # N = 1000, 500 steps, once
  python3 bench/peer.py --dry-run       # only write the inputs (needs no peer, no powder)
  python3 bench/peer.py collide         # physics check: one JKR / hysteretic pair collision

Timings: powder's own `wall_seconds` of `powder run --json` (the stepping loop only: scene
parsing, engine and pipeline construction excluded); LAMMPS / LIGGGHTS "Loop time" (the run
loop, setup excluded). GPU runs pass `--no-ledger`: the peers keep no energy ledger, so
powder's GPU step runs without its own (about 20 % of the step) to compare like with like;
the CPU ledger is cheap and always kept.
"""

import argparse
import datetime
import json
import math
import os
import platform
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# ---------------------------------------------------------------------------------------
# Materials (SI)
# ---------------------------------------------------------------------------------------

# JKR micro-spheres (the material of examples/jkr_deposition.toml, without rolling).
JKR = dict(
    radius=5e-6,  # m
    density=2500.0,  # kg/m^3
    youngs=1e8,  # Pa
    poisson=0.3,
    surface_energy=0.01,  # J/m^2 per surface
    restitution=0.5,  # powder's Tsuji target restitution
    friction=0.3,
    impact_velocity=0.1,  # m/s: the time-step rule of the scene
)

# The hysteretic model with the parameters of paper 000 (figures 5-7) and the cohesive
# cluster example.
HYST = dict(
    radius=1.1e-3,
    density=2000.0,
    k1=100.0,  # N/m
    kp=500.0,
    kc=100.0,
    phi_f=0.05,
    gamma0=1e-3,  # kg/s
)

DT_FRACTION = 50.0  # powder's default dt = tc / 50
SKIN_FRACTION = 0.1  # neighbour skin = 0.1 r_min (gpu::engine::SKIN)


def sphere_mass(r, rho):
    return rho * 4.0 / 3.0 * math.pi * r**3


def jkr_derived(m=JKR):
    """E*, R*, m*, Fc, a0, delta0, k_eq for two equal spheres (powder's definitions)."""
    r = m["radius"]
    es = m["youngs"] / (2.0 * (1.0 - m["poisson"] ** 2))
    rs = r / 2.0
    ms = sphere_mass(r, m["density"]) / 2.0
    g = m["surface_energy"]
    fc = 3.0 * math.pi * g * rs
    a0 = (9.0 * math.pi * g * rs**2 / es) ** (1.0 / 3.0)
    d0 = a0**2 / (3.0 * rs)
    return dict(e_star=es, r_star=rs, m_star=ms, fc=fc, a0=a0, delta0=d0, k_eq=1.2 * fc / d0)


def jkr_dt(m=JKR):
    """powder's automatic JKR time step (model::ContactModel::time_step): tc / 50 with tc
    the smallest of the Hertz contact time at the impact velocity, the oscillation time
    about the equilibrium overlap and the time delta0/v to cross the adhesive zone, v the
    impact velocity but at most the adhesion speed sqrt(2 Fc delta0 / m*)."""
    d = jkr_derived(m)
    v = m["impact_velocity"]
    hertz = 2.87 * (d["m_star"] ** 2 / (d["r_star"] * d["e_star"] ** 2 * v)) ** 0.2
    osc = math.pi * math.sqrt(d["m_star"] / d["k_eq"])
    v_adhesion = math.sqrt(2.0 * d["fc"] * d["delta0"] / d["m_star"])
    zone = d["delta0"] / min(v, v_adhesion)
    return min(hertz, osc, zone) / DT_FRACTION


def hyst_dt(m=HYST):
    """tc = pi sqrt(m_r / kp) on the stiffest branch (kca = kc < kp here), dt = tc / 50."""
    mr = sphere_mass(m["radius"], m["density"]) / 2.0
    return math.pi * math.sqrt(mr / m["kp"]) / DT_FRACTION


# --- the parameter mappings --------------------------------------------------------------


def tsuji_beta(e):
    """powder: beta = ln e / sqrt(ln^2 e + pi^2) (paper 002 eq. 12)."""
    l = math.log(e)
    return l / math.sqrt(l * l + math.pi**2)


def lammps_tsuji_alpha(e):
    """LAMMPS (29Sep2021) damping tsuji: alpha(e), Tsuji et al.'s polynomial fit."""
    return (1.2728 - 4.2783 * e + 11.087 * e**2 - 22.348 * e**3 + 27.467 * e**4
            - 18.022 * e**5 + 4.8218 * e**6)


def lammps_tsuji_e_for(e_powder):
    """The 'restitution' to give LAMMPS' damping tsuji so that its normal damping
    coefficient equals powder's.

    powder:  c_n = 2 sqrt(5/6) |beta(e)| sqrt(S_n m*),    S_n = 2 E* a
    LAMMPS:  c_n = alpha(e_L) sqrt(k_n m*),               k_n = 4/3 E* a
    equal for alpha(e_L) = sqrt(5) |beta(e)|; alpha is decreasing on (0, 1]: bisection."""
    target = math.sqrt(5.0) * abs(tsuji_beta(e_powder))
    lo, hi = 1e-6, 1.0
    if lammps_tsuji_alpha(lo) < target:
        raise SystemExit(f"restitution {e_powder}: damping beyond LAMMPS' tsuji range")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if lammps_tsuji_alpha(mid) > target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def lammps_tangential_damping_ratio(m=JKR):
    """xgammat of `tangential mindlin NULL xgammat mu`: LAMMPS damps the tangential
    direction with xgammat * c_n; powder with 2 sqrt(5/6)|beta| sqrt(S_t m*), S_t = 8 G* a,
    so xgammat = sqrt(S_t / S_n) = sqrt(4 G* / E*)."""
    nu = m["poisson"]
    e = m["youngs"]
    g = e / (2.0 * (1.0 + nu))
    gs = g / (2.0 * (2.0 - nu))
    es = e / (2.0 * (1.0 - nu**2))
    return math.sqrt(4.0 * gs / es)


def liggghts_hysteresis_params(m=HYST):
    """LIGGGHTS hooke/hysteresis: k1 = kn of its Hooke model,
    kn = 16/15 sqrt(R*) Y* (15 m* v_char^2 / (16 sqrt(R*) Y*))^(1/5), so Young's modulus
    is chosen (with v_char = 1 m/s) to make kn = k1 for this monodisperse packing;
    kp = kn2kcMax * kn, kc = kn2kc * kn, phiF = phi_f; viscous damping
    gamma_n = sqrt(4 m* kn / (1 + (pi / ln e)^2)), so e is chosen to make gamma_n = gamma0."""
    r = m["radius"]
    rs = r / 2.0
    ms = sphere_mass(r, m["density"]) / 2.0
    vchar = 1.0
    nu = 0.3
    a = 16.0 / 15.0 * math.sqrt(rs)
    b = (15.0 * ms * vchar**2 / (16.0 * math.sqrt(rs))) ** 0.2
    y_star = (m["k1"] / (a * b)) ** 1.25
    youngs = 2.0 * (1.0 - nu**2) * y_star
    kn_check = a * y_star * (15.0 * ms * vchar**2 / (16.0 * math.sqrt(rs) * y_star)) ** 0.2
    if m["gamma0"] > 0:
        q = 4.0 * ms * m["k1"] / m["gamma0"] ** 2 - 1.0
        if q <= 0:
            raise SystemExit("gamma0 beyond critical damping: no LIGGGHTS restitution maps to it")
        e = math.exp(-math.pi / math.sqrt(q))
    else:
        e = 1.0
    return dict(youngs=youngs, poisson=nu, characteristic_velocity=vchar, restitution=e,
                kn2kcMax=m["kp"] / m["k1"], kn2kc=m["kc"] / m["k1"], phiF=m["phi_f"],
                kn=kn_check)


# ---------------------------------------------------------------------------------------
# The packing
# ---------------------------------------------------------------------------------------


def lattice_dims(n):
    """nx >= ny >= nz, nx*ny*nz = n exactly when n is 1000, 1e4, 1e5, 1e6; else close."""
    table = {1000: (10, 10, 10), 10000: (25, 20, 20), 100000: (50, 50, 40),
             1000000: (100, 100, 100)}
    if n in table:
        return table[n]
    c = max(1, round(n ** (1.0 / 3.0)))
    return (max(1, n // (c * c)), c, c)


def make_packing(n, radius, overlap, seed=1):
    """Simple-cubic lattice with spacing 2r - overlap, each coordinate jittered uniformly
    by up to overlap/3 (pair overlaps stay within overlap*(1/3 ... 5/3)).
    Returns (positions as decimal strings, box lo, box hi)."""
    nx, ny, nz = lattice_dims(n)
    s = 2.0 * radius - overlap
    j = overlap / 3.0
    rng = random.Random(seed)
    margin = 2.0 * radius
    lo = [0.0, 0.0, 0.0]
    hi = [2 * margin + (k - 1) * s for k in (nx, ny, nz)]
    pos = []
    for iz in range(nz):
        for iy in range(ny):
            for ix in range(nx):
                p = [margin + i * s + rng.uniform(-j, j) for i in (ix, iy, iz)]
                pos.append(["%.12e" % c for c in p])
    return pos, lo, hi


# ---------------------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------------------


def fmt(x):
    return "%.12e" % x


def write_powder_scene(path, case, pos, lo, hi, dt, steps):
    m = JKR if case == "jkr" else HYST
    lines = [
        f"# powder against the peers ({case}): generated by bench/peer.py",
        "[domain]",
        f"min = [{fmt(lo[0])}, {fmt(lo[1])}, {fmt(lo[2])}]",
        f"max = [{fmt(hi[0])}, {fmt(hi[1])}, {fmt(hi[2])}]",
        "",
        "[simulation]",
        f"duration = {fmt(dt * (steps + 10))}",
        f"dt = {fmt(dt)}",
        f"output_every = {steps}",
        f"checkpoint_every = {steps}",
        "gravity = [0.0, 0.0, 0.0]",
    ]
    if case == "jkr":
        lines.append(f"impact_velocity = {m['impact_velocity']}")
    lines += ["", "[[material]]", f'name = "{case}"', f"density = {m['density']}"]
    if case == "jkr":
        lines += [
            'model = "jkr"',
            f"youngs = {m['youngs']}",
            f"poisson = {m['poisson']}",
            f"surface_energy = {m['surface_energy']}",
            'dissipation = "tsuji"',
            f"restitution = {m['restitution']}",
            f"friction = {m['friction']}",
            'pulloff = "force"            # LAMMPS breaks the contact where F = -Fc',
        ]
    else:
        lines += [
            'model = "hysteretic"',
            f"k1 = {m['k1']}",
            f"kp = {m['kp']}",
            f"kc = {m['kc']}",
            f"phi_f = {m['phi_f']}",
            f"gamma0 = {m['gamma0']}",
            "fa = 0.0                      # LIGGGHTS has no non-contact adhesion",
        ]
    lines += ["", "[[particles]]", 'kind = "list"', f"radius = {fmt(m['radius'])}",
              "positions = ["]
    lines += [f"  [{p[0]}, {p[1]}, {p[2]}]," for p in pos]
    lines += ["]", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))


def write_data_file(path, case, pos, lo, hi):
    """LAMMPS / LIGGGHTS data file, atom_style sphere / granular: id type diameter density x y z."""
    m = JKR if case == "jkr" else HYST
    d = fmt(2.0 * m["radius"])
    rho = repr(m["density"])
    out = [f"powder against the peers ({case}): generated by bench/peer.py", "",
           f"{len(pos)} atoms", "1 atom types", "",
           f"{fmt(lo[0])} {fmt(hi[0])} xlo xhi", f"{fmt(lo[1])} {fmt(hi[1])} ylo yhi",
           f"{fmt(lo[2])} {fmt(hi[2])} zlo zhi", "", "Atoms", ""]
    out += [f"{i + 1} 1 {d} {rho} {p[0]} {p[1]} {p[2]}" for i, p in enumerate(pos)]
    out.append("")
    with open(path, "w") as f:
        f.write("\n".join(out))


def lammps_jkr_coeff(m=JKR, restitution=None, friction=None, damping=True):
    """The pair_coeff arguments of LAMMPS' granular JKR matching powder's JKR material."""
    mu = m["friction"] if friction is None else friction
    if damping:
        e_l = lammps_tsuji_e_for(m["restitution"] if restitution is None else restitution)
        normal = f"jkr {m['youngs']} {e_l:.10f} {m['poisson']} {m['surface_energy']} damping tsuji"
    else:
        normal = f"jkr {m['youngs']} 0.0 {m['poisson']} {m['surface_energy']} damping velocity"
    xg = lammps_tangential_damping_ratio(m) if damping else 0.0
    # LAMMPS needs a tangential model; without friction mindlin with mu = 0 (zero force).
    # (linear_nohistory would leave JKR with an empty history record, which makes
    # fix neigh/history of this LAMMPS version abort with "Neighbor history overflow".)
    tang = f"tangential mindlin NULL {xg:.10f} {mu}"
    return f"{normal} {tang}"


def write_lammps_deck(path, data_name, dt, skin, steps):
    text = f"""# powder against the peers: LAMMPS, pair_style granular jkr (generated by bench/peer.py)
units           si
atom_style      sphere
atom_modify     map array
boundary        f f f
newton          off
comm_modify     vel yes
read_data       {data_name}
pair_style      granular
pair_coeff      * * {lammps_jkr_coeff()}
timestep        {fmt(dt)}
neighbor        {fmt(skin)} bin
neigh_modify    delay 0 every 1 check yes
fix             integrate all nve/sphere
thermo_style    custom step atoms ke
thermo          {steps}
run             {steps}
"""
    with open(path, "w") as f:
        f.write(text)


def liggghts_material_block(p, pair_style_line):
    # soft_particles: k1 = 100 N/m needs Y ~ 5e5 Pa, below LIGGGHTS' SI sanity limit of 5e6
    return f"""soft_particles  yes
fix             m1 all property/global youngsModulus peratomtype {p['youngs']:.10e}
fix             m2 all property/global poissonsRatio peratomtype {p['poisson']}
fix             m3 all property/global coefficientRestitution peratomtypepair 1 {p['restitution']:.12f}
fix             m4 all property/global coefficientFriction peratomtypepair 1 0.0
fix             m5 all property/global characteristicVelocity scalar {p['characteristic_velocity']}
fix             m6 all property/global coefficientMaxElasticStiffness peratomtypepair 1 {p['kn2kcMax']}
fix             m7 all property/global coefficientAdhesionStiffness peratomtypepair 1 {p['kn2kc']}
fix             m8 all property/global coefficientPlasticityDepth peratomtypepair 1 {p['phiF']}
{pair_style_line}
pair_coeff      * *
"""


LIGGGHTS_PAIR = "pair_style      gran model hooke/hysteresis tangential no_history"


def write_liggghts_deck(path, data_name, dt, skin, steps):
    p = liggghts_hysteresis_params()
    text = f"""# powder against the peers: LIGGGHTS hooke/hysteresis (generated by bench/peer.py)
# k1 = kn = {p['kn']:.6g} N/m from Young's modulus and characteristicVelocity (see peer.py)
atom_style      granular
atom_modify     map array
boundary        f f f
newton          off
communicate     single vel yes
units           si
read_data       {data_name}
neighbor        {fmt(skin)} bin
neigh_modify    delay 0
{liggghts_material_block(p, LIGGGHTS_PAIR)}timestep        {fmt(dt)}
fix             integrate all nve/sphere
thermo_style    custom step atoms ke
thermo          {steps}
run             {steps}
"""
    with open(path, "w") as f:
        f.write(text)


def generate(outdir, n, steps):
    """Writes the inputs for one size; returns a description."""
    os.makedirs(outdir, exist_ok=True)
    files = {}
    info = {}
    for case in ("jkr", "hysteretic"):
        m = JKR if case == "jkr" else HYST
        r = m["radius"]
        if case == "jkr":
            overlap = jkr_derived()["delta0"]  # the zero-load JKR overlap
            dt = jkr_dt()
        else:
            overlap = 0.003 * r
            dt = hyst_dt()
        skin = SKIN_FRACTION * r
        pos, lo, hi = make_packing(n, r, overlap)
        scene = os.path.join(outdir, f"{case}_{n}.toml")
        data = os.path.join(outdir, f"{case}_{n}.data")
        write_powder_scene(scene, case, pos, lo, hi, dt, steps)
        write_data_file(data, case, pos, lo, hi)
        files[case] = {"powder": scene, "data": data}
        if case == "jkr":
            deck = os.path.join(outdir, f"in.lammps_jkr_{n}")
            write_lammps_deck(deck, os.path.basename(data), dt, skin, steps)
            files[case]["lammps"] = deck
        else:
            deck = os.path.join(outdir, f"in.liggghts_hysteresis_{n}")
            write_liggghts_deck(deck, os.path.basename(data), dt, skin, steps)
            files[case]["liggghts"] = deck
        info[case] = dict(particles=len(pos), radius=r, dt=dt, skin=skin, overlap=overlap,
                          box=[lo, hi])
    return files, info


# ---------------------------------------------------------------------------------------
# Runners
# ---------------------------------------------------------------------------------------


def powder_bin(args):
    p = args.powder or os.path.join(ROOT, "target", "release", "powder")
    if not os.path.exists(p):
        raise SystemExit(f"no powder binary at {p}: run `cargo build --release` first")
    return p


def env_single_thread():
    e = dict(os.environ)
    e["OMP_NUM_THREADS"] = "1"
    e.setdefault("NODEVICE_SELECT", "1")
    return e


def run_cmd(cmd, cwd, timeout):
    t = time.time()
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout,
                       env=env_single_thread())
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr[-3000:]}\n{r.stdout[-2000:]}")
    return r.stdout, r.stderr, time.time() - t


def run_powder(args, scene, backend, steps, threads=None):
    cmd = [powder_bin(args), "run", scene, "--backend", backend, "--steps", str(steps),
           "--no-output", "--json"]
    if threads is not None:
        # the CPU engine: every core by default, or this many threads
        cmd += ["--threads", str(threads)]
    if backend == "gpu":
        # the peers keep no energy ledger: time powder's GPU step without its own
        cmd.append("--no-ledger")
    out, err, _ = run_cmd(cmd, os.path.dirname(scene), args.timeout)
    j = json.loads(out[out.index("{"):])
    if j.get("backend") != backend:
        raise RuntimeError(f"powder ran on {j.get('backend')} instead of {backend}: {err[-500:]}")
    return dict(seconds=j["wall_seconds"], particles=j["particles"], steps=steps,
                adapter=j.get("adapter"), rebuilds=j.get("rebuilds"), ledger=j.get("ledger"),
                threads=j.get("threads"))


LOOP_RE = re.compile(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")


def run_peer(args, exe, deck, ranks):
    if ranks > 1:
        cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks), exe,
               "-in", os.path.basename(deck), "-log", "none", "-screen", "none"]
        # screen none suppresses the summary on rank 0; keep the screen and drop the log
        cmd = ["mpirun", "--allow-run-as-root", "-np", str(ranks), exe,
               "-in", os.path.basename(deck), "-log", "none"]
    else:
        cmd = [exe, "-in", os.path.basename(deck), "-log", "none"]
    out, err, _ = run_cmd(cmd, os.path.dirname(deck), args.timeout)
    m = LOOP_RE.search(out)
    if not m:
        raise RuntimeError(f"no 'Loop time' in the output of {' '.join(cmd)}:\n{out[-2000:]}")
    return dict(seconds=float(m.group(1)), particles=int(m.group(4)), steps=int(m.group(3)),
                ranks=int(m.group(2)))


def best_of(runs):
    """The fastest of one code's runs, with all their times."""
    best = min(runs, key=lambda r: r["seconds"])
    best = dict(best)
    best["all_seconds"] = [r["seconds"] for r in runs]
    best["particle_steps_per_second"] = best["particles"] * best["steps"] / best["seconds"]
    return best


def machine_info(args):
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    info = dict(cpu=cpu, cores=os.cpu_count(), os=platform.platform(),
                python=platform.python_version(),
                date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"))
    try:
        out, _, _ = run_cmd([powder_bin(args), "info", "--json"], ROOT, 120)
        a = json.loads(out)
        info["adapter"] = f"{a.get('name')} ({a.get('backend')}, {a.get('driver_info')})"
    except Exception as e:  # noqa: BLE001 - reported, not fatal
        info["adapter"] = f"unavailable: {str(e).splitlines()[0]}"
    versions = {}
    for name, cmd, pat in (
        ("powder", [powder_bin(args), "--version"], r"(.+)"),
        ("lammps", ["lmp", "-h"], r"(Large-scale.*?- .+)"),
        ("liggghts", ["liggghts", "-h"], r"(LIGGGHTS \(Version[^)]*\))"),
        ("mpirun", ["mpirun", "--version"], r"(.+)"),
    ):
        try:
            # cwd: `liggghts -h` leaves a log.liggghts behind
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=60,
                               cwd=tempfile.gettempdir())
            m = re.search(pat, r.stdout + r.stderr)
            versions[name] = m.group(1).strip() if m else "unknown"
        except (OSError, subprocess.TimeoutExpired):
            versions[name] = "not installed"
    info["versions"] = versions
    return info


# ---------------------------------------------------------------------------------------
# The throughput comparison
# ---------------------------------------------------------------------------------------


def bench(args):
    if args.quick:
        sizes, steps, repeats = [1000], 500, 1
    else:
        sizes, steps, repeats = [10000, 100000], 2000, 3
    if args.sizes:
        sizes = [int(float(s)) for s in args.sizes.split(",")]
    steps = args.steps or steps
    repeats = max(1, args.repeats or repeats)
    only = set(args.only.split(",")) if args.only else None
    workdir = args.workdir or tempfile.mkdtemp(prefix="powder-peer-")
    os.makedirs(workdir, exist_ok=True)

    generated = {}
    for n in sizes:
        generated[n] = generate(os.path.join(workdir, str(n)), n, steps)
    if args.dry_run:
        for n, (files, info) in generated.items():
            for case, fs in files.items():
                for kind, p in fs.items():
                    print(f"{n:>8} {case:<11} {kind:<9} {p}")
        print(f"inputs written to {workdir}")
        return 0

    results = dict(machine=machine_info(args), steps=steps, repeats=repeats, workdir=workdir,
                   command=" ".join([os.path.relpath(__file__, ROOT)] + sys.argv[1:]),
                   mapping=mapping_summary(), runs=[])
    have_lmp = shutil.which("lmp") is not None
    have_lig = shutil.which("liggghts") is not None
    have_mpi = shutil.which("mpirun") is not None

    def want(code):
        return only is None or code in only

    plan = []
    for n in sizes:
        files, info = generated[n]
        for case in ("jkr", "hysteretic"):
            scene = files[case]["powder"]
            # the CPU engine on 1 thread and on every core, the GPU engine
            for code, label, backend, threads in (
                    ("powder-cpu-1", "powder cpu 1 thread", "cpu", 1),
                    ("powder-cpu", "powder cpu", "cpu", 0),
                    ("powder-gpu", "powder gpu", "gpu", None)):
                if want(code):
                    plan.append((n, case, label,
                                 lambda s=scene, b=backend, t=threads:
                                 run_powder(args, s, b, steps, t)))
            peer_exe, deck_key, peer = (("lmp", "lammps", "LAMMPS") if case == "jkr"
                                        else ("liggghts", "liggghts", "LIGGGHTS"))
            available = have_lmp if case == "jkr" else have_lig
            for ranks in (1, 2):
                if not want(f"{deck_key}-{ranks}"):
                    continue
                if not available or (ranks > 1 and not have_mpi):
                    print(f"skipping {peer} on {ranks} rank(s): not installed", file=sys.stderr)
                    continue
                plan.append((n, case, f"{peer} {ranks} rank{'s' if ranks > 1 else ''}",
                             lambda d=files[case][deck_key], x=peer_exe, k=ranks:
                             run_peer(args, x, d, k)))
    # the codes of one (N, case) take turns, one run each per round: a VM whose speed
    # drifts over minutes then slows every code alike, and the ratios stay comparable
    groups = {}
    for n, case, label, fn in plan:
        groups.setdefault((n, case), []).append((label, fn))
    for (n, case), codes in groups.items():
        done = {label: [] for label, _ in codes}
        failed = {}
        for round_ in range(repeats):
            for label, fn in codes:
                if label in failed:
                    continue
                print(f"running {label:<16} {case:<10} N = {n} (round {round_ + 1}/{repeats}) ...",
                      file=sys.stderr, flush=True)
                try:
                    done[label].append(fn())
                except Exception as e:  # noqa: BLE001 - one failing code should not lose the others
                    print(f"  failed: {e}", file=sys.stderr)
                    failed[label] = str(e)[:2000]
        for label, _ in codes:
            if label in failed:
                results["runs"].append(dict(n=n, case=case, code=label, error=failed[label]))
                continue
            r = best_of(done[label])
            r.update(n=n, case=case, code=label)
            print(f"  {label}: {r['particle_steps_per_second']:.3e} particle-steps/s "
                  f"(best of {r['all_seconds']})", file=sys.stderr, flush=True)
            results["runs"].append(r)

    table = ratio_table(results["runs"])
    results["ratios"] = table
    print_table(results, table)
    out = args.json or os.path.join(workdir, "peer.json")
    with open(out, "w") as f:
        json.dump(results, f, indent=2)
    print(f"\nJSON written to {out}")
    return 0


def ratio_table(runs):
    """powder/peer throughput ratios per size and case."""
    rows = []
    ok = [r for r in runs if "error" not in r]
    for n in sorted({r["n"] for r in ok}):
        for case in ("jkr", "hysteretic"):
            by = {r["code"]: r["particle_steps_per_second"] for r in ok
                  if r["n"] == n and r["case"] == case}
            peer = "LAMMPS" if case == "jkr" else "LIGGGHTS"
            for mine in ("powder cpu 1 thread", "powder cpu", "powder gpu"):
                for ranks in ("1 rank", "2 ranks"):
                    other = f"{peer} {ranks}"
                    if mine in by and other in by:
                        rows.append(dict(n=n, case=case, powder=mine, peer=other,
                                         ratio=by[mine] / by[other]))
    return rows


def print_table(results, table):
    m = results["machine"]
    print(f"\nmachine: {m['cpu']}, {m['cores']} cores; adapter: {m.get('adapter')}; {m['date']}")
    print(f"versions: {json.dumps(m['versions'])}")
    print(f"{results['steps']} steps, best of {results['repeats']}\n")
    print(f"| N | case | code | particle-steps/s | runs (s) |")
    print(f"| --- | --- | --- | --- | --- |")
    for r in results["runs"]:
        if "error" in r:
            print(f"| {r['n']} | {r['case']} | {r['code']} | failed | |")
        else:
            secs = ", ".join(f"{s:.2f}" for s in r["all_seconds"])
            code = r["code"]
            if code == "powder cpu" and r.get("threads"):
                code += f" ({r['threads']} threads)"
            print(f"| {r['n']} | {r['case']} | {code} | {r['particle_steps_per_second']:.3e} | {secs} |")
    if any(r["code"] == "powder gpu" for r in results["runs"]):
        print("\npowder gpu ran with `powder run --no-ledger` (no energy ledger, as the peers keep none)")
    if table:
        print("\n| N | case | powder | peer | powder/peer |")
        print("| --- | --- | --- | --- | --- |")
        for t in table:
            print(f"| {t['n']} | {t['case']} | {t['powder']} | {t['peer']} | {t['ratio']:.2f} |")


def mapping_summary():
    d = jkr_derived()
    lp = liggghts_hysteresis_params()
    return dict(
        jkr=dict(powder=JKR, lammps_pair_coeff=lammps_jkr_coeff(),
                 lammps_tsuji_restitution=lammps_tsuji_e_for(JKR["restitution"]),
                 xgammat=lammps_tangential_damping_ratio(), dt=jkr_dt(), **d),
        hysteretic=dict(powder=HYST, liggghts=lp, dt=hyst_dt()),
    )


# ---------------------------------------------------------------------------------------
# Physics check: one pair collision, powder collide against the peer
# ---------------------------------------------------------------------------------------


def powder_collide(args, extra):
    cmd = [powder_bin(args), "collide"] + extra + ["--json"]
    out, _, _ = run_cmd(cmd, ROOT, args.timeout)
    return json.loads(out[out.index("{"):])


def pair_data_file(path, r, rho, gap, box, v):
    """Two spheres on the x axis, centres 2r + gap apart, in the middle of a cube,
    approaching with relative speed v."""
    c = box / 2.0
    x1, x2 = c - (r + gap / 2.0), c + (r + gap / 2.0)
    d = fmt(2 * r)
    with open(path, "w") as f:
        f.write(f"pair collision\n\n2 atoms\n1 atom types\n\n0 {fmt(box)} xlo xhi\n"
                f"0 {fmt(box)} ylo yhi\n0 {fmt(box)} zlo zhi\n\nAtoms\n\n"
                f"1 1 {d} {rho!r} {fmt(x1)} {fmt(c)} {fmt(c)}\n"
                f"2 1 {d} {rho!r} {fmt(x2)} {fmt(c)} {fmt(c)}\n\nVelocities\n\n"
                f"1 {fmt(v / 2)} 0 0 0 0 0\n2 {fmt(-v / 2)} 0 0 0 0 0\n")
    return x1, x2


def peer_pair_run(exe, workdir, deck_text, data_name):
    deck = os.path.join(workdir, "in.pair")
    with open(deck, "w") as f:
        f.write(deck_text)
    r = subprocess.run([exe, "-in", "in.pair", "-log", "none"], cwd=workdir,
                       capture_output=True, text=True, timeout=600, env=env_single_thread())
    m = re.findall(r"PAIR_RESULT ([-0-9.eE+]+) ([-0-9.eE+]+)", r.stdout)
    if r.returncode != 0 or not m:
        raise RuntimeError(f"{exe} failed:\n{r.stdout[-3000:]}\n{r.stderr[-2000:]}")
    return float(m[-1][0]), float(m[-1][1])


def collide(args):
    workdir = args.workdir or tempfile.mkdtemp(prefix="powder-peer-collide-")
    os.makedirs(workdir, exist_ok=True)
    rows = []
    # --- JKR against LAMMPS: E = 1 GPa, nu = 0.3, gamma = 0.05 J/m^2, r = 1 um, 2000 kg/m^3
    jm = dict(radius=1e-6, density=2000.0, youngs=1e9, poisson=0.3, surface_energy=0.05,
              restitution=0.5, friction=0.0, impact_velocity=1.0)
    variants = [
        ("none", 1.0, None),  # the JKR hysteresis alone, powder's default dt
        ("none", 0.1, None),  # the same at dt/10
        ("tsuji", 1.0, "mapped"),  # LAMMPS restitution chosen to give powder's c_n
        ("tsuji", 1.0, "naive"),  # LAMMPS given the same e = 0.5 (a different c_n)
    ]
    for v in (1.0, 2.0, 5.0):
        for damping, dt_scale, how in variants:
            damped = damping == "tsuji"
            extra = ["--model", "jkr", "--youngs", "1e9", "--poisson", "0.3",
                     "--surface-energy", "0.05", "--radius", "1e-6", "--density", "2000",
                     "--velocity", str(v), "--pulloff", "force"]
            if damped:
                extra += ["--restitution", "0.5"]
            if dt_scale != 1.0:
                p0 = powder_collide(args, extra)
                extra += ["--dt", repr(p0["dt"] * dt_scale)]
            p = powder_collide(args, extra)
            dt, steps = p["dt"], p["steps"]
            if how == "naive":
                coeff = lammps_jkr_coeff(jm, damping=True).replace(
                    f"{lammps_tsuji_e_for(0.5):.10f}", "0.5")
            else:
                coeff = lammps_jkr_coeff(jm, damping=damped)
            gap = 2.0 * v * dt  # powder starts two steps' travel outside the range
            pair_data_file(os.path.join(workdir, "pair.data"), 1e-6, 2000.0, gap, 1e-4, v)
            deck = f"""units si
atom_style sphere
atom_modify map array
boundary f f f
newton off
comm_modify vel yes
read_data pair.data
pair_style granular
pair_coeff * * {coeff}
timestep {fmt(dt)}
neighbor {fmt(0.1e-6)} bin
neigh_modify delay 0 every 1 check yes
fix 1 all nve/sphere
thermo 0
run {3 * steps + 200}
variable e equal (vx[2]-vx[1])/{fmt(v)}
variable dx equal x[2]-x[1]
print "PAIR_RESULT ${{e}} ${{dx}}"
"""
            e_l, dx = peer_pair_run("lmp", workdir, deck, "pair.data")
            # still within the pull-off distance at the end: stuck (e = 0), as powder says
            separated = dx - 2e-6 > abs(p["jkr"]["pulloff_overlap"])
            e_peer = e_l if separated else 0.0
            label = damping if not damped else f"tsuji e=0.5 ({how} LAMMPS e)"
            rows.append(dict(model="jkr", damping=label, velocity=v, dt=dt, steps=steps,
                             e_powder=p["e"], stuck_powder=p["stuck"],
                             e_analytic=p.get("e_analytic"), e_peer=e_peer,
                             stuck_peer=not separated, peer="LAMMPS", peer_coeff=coeff))
            print(f"JKR v={v} damping={label} dt={dt:.4e}: powder e = {p['e']:.6f}, "
                  f"LAMMPS e = {e_peer:.6f}{' (stuck)' if not separated else ''}, "
                  f"analytic {p.get('e_analytic')}", flush=True)
    # --- hysteretic against LIGGGHTS: the paper's parameters, gamma0 = 0 and 1e-3
    hm = dict(HYST)
    for v in (0.05, 0.2, 0.5):
        for g0 in (0.0, 1e-3):
            hm["gamma0"] = g0
            p = powder_collide(args, ["--model", "hysteretic", "--k1", "100", "--kp", "500",
                                      "--kc", "100", "--phi-f", "0.05", "--radius", "1.1e-3",
                                      "--density", "2000", "--velocity", str(v),
                                      "--gamma0", str(g0)])
            dt, steps = p["dt"], p["steps"]
            lp = liggghts_hysteresis_params(hm)
            gap = 2.0 * v * dt
            pair_data_file(os.path.join(workdir, "pair.data"), 1.1e-3, 2000.0, gap, 0.05, v)
            deck = f"""atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
read_data pair.data
neighbor {fmt(1.1e-4)} bin
neigh_modify delay 0
{liggghts_material_block(lp, LIGGGHTS_PAIR)}timestep {fmt(dt)}
fix integrate all nve/sphere
thermo 0
run {3 * steps + 200}
variable e equal (vx[2]-vx[1])/{fmt(v)}
variable dx equal x[2]-x[1]
print "PAIR_RESULT ${{e}} ${{dx}}"
"""
            try:
                e_l, dx = peer_pair_run("liggghts", workdir, deck, "pair.data")
                if dx <= 2.2e-3:  # still in contact: stuck
                    e_l = 0.0
            except Exception as ex:  # noqa: BLE001
                print(f"LIGGGHTS pair failed: {ex}", file=sys.stderr)
                e_l = None
            # a stuck pair oscillates: the separation speed at the end is meaningless, e = 0
            rows.append(dict(model="hysteretic", gamma0=g0, velocity=v, dt=dt, steps=steps,
                             e_powder=p["e"], stuck_powder=p["stuck"],
                             e_analytic=p.get("e_analytic"), e_peer=e_l, peer="LIGGGHTS",
                             liggghts=lp))
            print(f"hysteretic v={v} gamma0={g0}: powder e = {p['e']:.6f} (stuck {p['stuck']}), "
                  f"LIGGGHTS e = {e_l}, analytic {p.get('e_analytic')}", flush=True)
    out = args.json or os.path.join(workdir, "collide.json")
    with open(out, "w") as f:
        json.dump(rows, f, indent=2)
    print(f"JSON written to {out}")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", nargs="?", default="bench", choices=["bench", "collide"])
    ap.add_argument("--quick", action="store_true", help="N = 1000, 500 steps, once")
    ap.add_argument("--dry-run", action="store_true", help="only write the input files")
    ap.add_argument("--sizes", help="comma-separated particle counts (default 1e4,1e5)")
    ap.add_argument("--steps", type=int, help="steps per run (default 2000)")
    ap.add_argument("--repeats", type=int, help="runs per code, the best counts (default 3)")
    ap.add_argument("--only", help="comma-separated subset of powder-cpu-1,powder-cpu,powder-gpu,"
                    "lammps-1,lammps-2,liggghts-1,liggghts-2")
    ap.add_argument("--workdir", help="where the inputs go (default a new temporary directory)")
    ap.add_argument("--json", help="where the results go (default WORKDIR/peer.json)")
    ap.add_argument("--powder", help="the powder binary (default target/release/powder)")
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds per run")
    args = ap.parse_args()
    if args.what == "collide":
        return collide(args)
    return bench(args)


if __name__ == "__main__":
    sys.exit(main())
