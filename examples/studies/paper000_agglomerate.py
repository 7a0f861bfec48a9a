#!/usr/bin/env python3
"""Paper 000, appendix F: a cubic agglomerate of 1728 primary particles (d0 = 0.01, radii
uniform within +-10 %), pressure-sintered by walls at d0 ps/kp = 0.02, released to
pr/ps = 1e-3, then tested unconfined (side walls removed) between two adhesive plates:
uniaxial tension (fig. 16) or compression (fig. 18) cycles to an amplitude Dx = |L - L0|/d0
and back, four times each, every test starting from the same released sample; one
amplitude of each again four times slower (the paper's thick lines).

    python3 examples/studies/paper000_agglomerate.py [--backend cpu|gpu] [--powder PATH]
        [--out docs] [--work DIR] [--quick] [--replot]

(about 10 minutes on the CPU here; `--quick`: one amplitude each way, shorter cycles and
a shorter pull, to try it; `--replot`: redraw from the runs in --work). Writes
OUT/paper000_agglomerate.svg (figs. 16 and 18), OUT/paper000_agglomerate_snapshots.svg
(fig. 17), OUT/paper000_agglomerate.csv and prints the tables.

The sample is prepared once (`powder run` of the preparation scene) and each test resumes
its checkpoint under a scene that differs only in the top plate's phases after it (a
branch, docs/checkpoints.md). Walls: the plates (bottom fixed, top moving) are of the
particles' own material, so they adhere (kc) and carry friction; the four side walls are
frictionless and not adhesive (an [[interaction]] with kc = 0) and move away once the
sample is released. Three walls (x+, y+, top) are servo-controlled during preparation:
first a gathering run (its own scene) packs the random cloud at a low force with the
particles frictionless and not adhesive, so it packs densely; the preparation then starts
from the gathered positions with the full law and sinters at ps L0^2, releases to pr L0^2
and removes the side walls, the top plate holding pr.

Parameters (SI numbers in the units the paper leaves free): d0 = 0.01 m, density 2000,
kp = 1e5 N/m, k1/kp = 0.5, kc/kp = 0.2, phi_f = 0.05, gamma0 = 2 kg/s; mu = 1 (sliding),
mu_r = mu_o = 0.2, kt/kp = 0.2, kr/kp = ko/kp = 0.1, gamma_t/gamma0 = 0.2,
gamma_r/gamma0 = gamma_o/gamma0 = 0.1. Paper 000 sets kc/kp, mu_r, mu_o, gamma_r/gamma and
gamma_o/gamma; the rest is "as in Luding 2008, table 2", which could not be checked here
(docs/luding2008_laws.md): the values above are those of Luding's papers of that time as
far as known, stated here so that they can be corrected. Plotted: the top plate's
compression (L0 - L)/d0 (tension negative, as on the paper's fig. 16 axis; L0 the released
sample's height) against the force of the sample on it over kp d0 (compressive positive).
"""

import argparse
import csv
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import svgplot  # noqa: E402

D0 = 0.01
N_SIDE = 12  # 12^3 = 1728 primary particles
KP = 1e5
L0 = 0.115  # the paper's agglomerate, a cube, m (d0 = 0.01): its length at the tests' start
PS = 0.02 * KP / D0  # d0 ps / kp = 0.02, Pa
PR = 1e-3 * PS
BOX = 0.16  # the loose random packing's cube, m
# m/s per N. The servo sets the wall's speed from the last step's force, which holds the
# contacts' damping Σγ·v: each step feeds back -gain·Σγ of the speed, so the gain must stay
# below 1/Σγ (~110 adhesive contacts on a plate at gamma0 = 2 kg/s), and gain·k_bed·dt << 1
SERVO_GAIN = 0.002
# preparation: hold (seats the full-law sample between the walls), sinter (ps), release
# (pr), side walls away, settle
T_SINTER, T_RELEASE, T_FREE, T_AWAY, T_READY = 0.06, 0.2, 0.26, 0.265, 0.28
HOLD_FORCE = 50.0
# the gathering before: frictionless, not adhesive, more damped (it settles sooner), at a
# low force; a fast gain for the approach, then one within the rule above for the last
# T_GATHERING - T_QUIET s
T_GATHERING, T_QUIET, GATHERING_FORCE, GATHERING_DAMPING = 0.5, 0.4, 10.0, 4.0
GATHERING_GAIN, QUIET_GAIN = 0.02, 1e-3

GAMMA = 2.0  # kg/s, normal damping gamma0
# the primary particles' law: paper 000's kc/kp, mu_r, mu_o, gamma_r/gamma, gamma_o/gamma;
# the rest as far as Luding 2008's table 2 is known (docs/luding2008_laws.md)
PRIMARY = {"k1": 0.5 * KP, "kp": KP, "kc": 0.2 * KP, "phi_f": 0.05, "gamma0": GAMMA,
           "friction": 1.0, "kt": 0.2 * KP, "gamma_t": 0.2 * GAMMA,
           "rolling_friction": 0.2, "kr": 0.1 * KP, "gamma_r": 0.1 * GAMMA,
           "twisting_friction": 0.2, "ko": 0.1 * KP, "gamma_o": 0.1 * GAMMA}
# the side walls' law with the particles: neither adhesive nor frictional
SIDE = {**{key: PRIMARY[key] for key in ("k1", "kp", "phi_f", "gamma0")}, "kc": 0.0}
# the gathering's law: the side walls', more damped
GATHERING = {**SIDE, "gamma0": GATHERING_DAMPING * GAMMA}


def law(params):
    return "".join(f"{key} = {value!r}\n" for key, value in params.items())


MATERIAL = f"""
[[material]]
name = "primary"
density = 2000.0
model = "hysteretic"
{law(PRIMARY)}
[[material]]
name = "side"
density = 2000.0
model = "hysteretic"
{law(SIDE)}
[[interaction]]
materials = ["primary", "side"]
model = "hysteretic"
{law(SIDE)}"""


def servo(start, force, speed, gain=SERVO_GAIN):
    return (f"[[wall.phase]]\nfrom = {start!r}\nservo_force = {force!r}\n"
            f"servo_gain = {gain!r}\nservo_max_speed = {speed!r}\n")


def velocity(start, v):
    return f"[[wall.phase]]\nfrom = {start!r}\nvelocity = [{v[0]!r}, {v[1]!r}, {v[2]!r}]\n"


def rest(start):
    return f"[[wall.phase]]\nfrom = {start!r}\n"


def wall(point, normal, phases="", side=True):
    material = 'material = "side"\n' if side else ""
    return (f"[[wall]]\npoint = [{point[0]!r}, {point[1]!r}, {point[2]!r}]\n"
            f"normal = [{normal[0]!r}, {normal[1]!r}, {normal[2]!r}]\n{material}{phases}")


def preparation_walls(far):
    """The six walls up to T_READY, the x+, y+ and top walls starting at `far` (x, y, z);
    the top plate's test phases follow in each test."""
    area = L0 * L0
    press = (servo(0.0, HOLD_FORCE, 0.5) + servo(T_SINTER, PS * area, 0.2)
             + servo(T_RELEASE, PR * area, 0.2))
    away = 1.0  # m/s, for T_AWAY - T_FREE: 5 mm

    def side(point, normal, servoed):
        out = [-n * away for n in normal]
        phases = (press if servoed else "") + velocity(T_FREE, out) + rest(T_AWAY)
        return wall(point, normal, phases)

    return [
        side([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], False),
        side([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], False),
        wall([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], side=False),
        side([far[0], 0.0, 0.0], [-1.0, 0.0, 0.0], True),
        side([0.0, far[1], 0.0], [0.0, -1.0, 0.0], True),
        # the top plate (wall 5): pressed, released, still at pr while the side walls go
        wall([0.0, 0.0, far[2]], [0.0, 0.0, -1.0], press, side=False),
    ]


DOMAIN = """# paper 000 appendix F (examples/studies/paper000_agglomerate.py writes this)
[domain]
min = [-0.02, -0.02, -0.01]
max = [0.18, 0.18, 0.3]
"""


def gathering_scene():
    """The loose random packing gathered by three servo walls (x+, y+, top) at a low force,
    frictionless and not adhesive: the start of the preparation."""
    walls = [wall([0.0, 0.0, 0.0], n, side=False) for n in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0])]
    approach = (servo(0.0, GATHERING_FORCE, 0.5, GATHERING_GAIN)
                + servo(T_QUIET, GATHERING_FORCE, 0.5, QUIET_GAIN))
    walls += [wall(p, n, approach, side=False)
              for p, n in (([BOX, 0.0, 0.0], [-1.0, 0.0, 0.0]), ([0.0, BOX, 0.0], [0.0, -1.0, 0.0]),
                           ([0.0, 0.0, BOX], [0.0, 0.0, -1.0]))]
    return f"""{DOMAIN}
[simulation]
duration = {T_GATHERING!r}
output_every = 32000
contact_output = false

[[material]]
name = "gathering"
density = 2000.0
model = "hysteretic"
{law(GATHERING)}
{"".join(walls)}
[[particles]]
kind = "random"
count = {N_SIDE ** 3}
min = [0.0, 0.0, 0.0]
max = [{BOX!r}, {BOX!r}, {BOX!r}]
size = {{ distribution = "uniform", min = {0.9 * D0 / 2!r}, max = {1.1 * D0 / 2!r} }}
seed = 1
"""


def gathered(out_dir):
    """(positions, radii, (x, y, z) of the x+, y+ and top walls) at the gathering's end."""
    if not os.path.isdir(os.path.join(out_dir, "snapshots")):
        sys.exit(f"no gathering run in {out_dir}: run the study without --replot first")
    files = sorted(f for f in os.listdir(os.path.join(out_dir, "snapshots")) if f.endswith(".vtp"))
    points, radii = read_vtp(os.path.join(out_dir, "snapshots", files[-1]))
    last = read_series(os.path.join(out_dir, "series.csv"))[-1]
    with open(os.path.join(out_dir, "summary.json")) as f:
        steps = json.load(f)["steps"]
    if int(files[-1].rsplit("_", 1)[1].split(".")[0]) != steps or int(last["step"]) != steps:
        sys.exit(f"gathering: no snapshot or series row at its last step {steps} in {out_dir}")
    return points, radii, (float(last["wall3_x"]), float(last["wall4_y"]), float(last["wall5_z"]))


def scene(sample, top_phases, duration, output_every):
    """The preparation from the gathered `sample` (positions, radii, far walls) and the
    top plate's `top_phases` after it."""
    points, radii, far = sample
    walls = preparation_walls(far)
    walls[5] += top_phases
    positions = ", ".join(f"[{x!r}, {y!r}, {z!r}]" for x, y, z in points)
    return f"""{DOMAIN}
[simulation]
duration = {duration!r}
output_every = {output_every}
contact_output = false
{MATERIAL}
{"".join(walls)}
[[particles]]
kind = "list"
material = "primary"
positions = [{positions}]
radii = [{", ".join(repr(r) for r in radii)}]
"""


def cycles(start, amplitude, half, tension):
    """The top plate's phases from `start` on: out to the amplitude and back in `half` s
    each, four times."""
    speed = amplitude * D0 / half * (1.0 if tension else -1.0)
    phases = ""
    for k in range(4):
        t = start + 2 * k * half
        phases += velocity(t, [0.0, 0.0, speed]) + velocity(t + half, [0.0, 0.0, -speed])
    return phases + rest(start + 8 * half)


def run(powder, args, what):
    started = time.time()
    # (the study owns its work folder: a rerun replaces its earlier runs' outputs)
    out = svgplot.run_powder([powder, "run", *args, "--overwrite"])
    if out.returncode != 0:
        sys.exit(f"{what}: powder run {' '.join(args)}\n{out.stderr}")
    return time.time() - started


def read_series(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def curve(released, rows, start):
    """(time since `start`, compression (L0 - L)/d0, force/(kp d0)) of the top plate: the
    released state's row, then the test's from time `start` on."""
    rows = [released] + [r for r in rows if float(r["time"]) > start]
    z0 = float(released["wall5_z"])
    return [(max(float(r["time"]) - start, 0.0), (z0 - float(r["wall5_z"])) / D0,
             float(r["wall5_fz"]) / (KP * D0)) for r in rows]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--backend", default="cpu", choices=["cpu", "gpu"])
    ap.add_argument("--powder", default=svgplot.POWDER)
    ap.add_argument("--out", default="docs")
    ap.add_argument("--work", default=os.path.join("out", "paper000_agglomerate"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--replot", action="store_true", help="only redraw from the runs in --work")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    os.makedirs(a.out, exist_ok=True)
    half = 0.01 if a.quick else 0.04  # s a half cycle (the sample's elastic wave crosses it in ~1 ms)
    tension = [0.1] if a.quick else [0.025, 0.05, 0.1, 0.2]
    compression = [0.3] if a.quick else [0.1, 0.3, 1.0]
    slower_tests = [] if a.quick else [(0.1, True)]
    shots = SNAPSHOTS[:3] if a.quick else SNAPSHOTS
    tests = [(dx, True, 1) for dx in tension] + [(dx, False, 1) for dx in compression]
    tests += [(dx, t, 4) for dx, t in slower_tests]

    gather_dir = os.path.join(a.work, "gathered")
    if not a.replot:
        path = os.path.join(a.work, "gathered.toml")
        with open(path, "w") as f:
            f.write(gathering_scene())
        took = run(a.powder, [path, "--backend", a.backend, "--out", gather_dir], "gathering")
        print(f"gathered (frictionless, not adhesive) in {took:.0f} s")
    sample = gathered(gather_dir)
    prep_dir = os.path.join(a.work, "prepared")
    if not a.replot:
        path = os.path.join(a.work, "prepared.toml")
        with open(path, "w") as f:
            f.write(scene(sample, "", T_READY, 2000))
        took = run(a.powder, [path, "--backend", a.backend, "--out", prep_dir, "--no-snapshots"],
                   "preparation")
        print(f"prepared (sintered, released, side walls away) in {took:.0f} s")
    prep = read_series(os.path.join(prep_dir, "series.csv"))
    describe_preparation(sample, prep)
    checkpoint = os.path.join(prep_dir, "checkpoint.bin")
    # the tests' phases start where the checkpoint is (the first step at or after T_READY)
    with open(os.path.join(prep_dir, "summary.json")) as f:
        summary = json.load(f)
    start, dt = summary["time"], summary["dt"]
    every = max(1, round(half / 40 / dt))  # ~40 rows a half cycle

    results = []
    for dx, is_tension, slower in tests:
        name = f"{'tension' if is_tension else 'compression'}_{dx:g}" + ("_slow" if slower > 1 else "")
        out_dir = os.path.join(a.work, name)
        if not a.replot:
            h = half * slower
            path = os.path.join(a.work, name + ".toml")
            with open(path, "w") as f:
                f.write(scene(sample, cycles(start, dx, h, is_tension), start + 8 * h, every * slower))
            took = run(a.powder, [path, "--backend", a.backend, "--out", out_dir, "--resume", checkpoint,
                                  "--no-snapshots"], name)
            print(f"{name}: {took:.0f} s")
        points = curve(prep[-1], read_series(os.path.join(out_dir, "series.csv")), start)
        results.append((name, dx, is_tension, slower, points, half * slower))

    # fig. 17: one pull to beyond the paper's last snapshot, side views on the way (a
    # snapshot every 0.05 d0 of the fast part)
    out_dir = os.path.join(a.work, "pull")
    if not a.replot:
        path = os.path.join(a.work, "pull.toml")
        phases, t, dx = "", start, 0.0
        for speed, span in PULL_RAMP:
            phases += velocity(t, [0.0, 0.0, speed])
            t, dx = t + span * D0 / speed, dx + span
        phases += velocity(t, [0.0, 0.0, PULL_FAST])
        with open(path, "w") as f:
            f.write(scene(sample, phases, t + (shots[-1] - dx) * D0 / PULL_FAST * 1.02,
                          max(1, round(0.05 * D0 / PULL_FAST / dt))))
        took = run(a.powder, [path, "--backend", a.backend, "--out", out_dir, "--resume", checkpoint], "pull")
        print(f"pull to Dx = {shots[-1]}: {took:.0f} s")
    views = snapshots(out_dir, prep[-1], start, shots)
    pulled = curve(prep[-1], read_series(os.path.join(out_dir, "series.csv")), start)

    write_outputs(a.out, prep, results, views, pulled)


def describe_preparation(sample, prep):
    """Prints the sample's size and solid fraction gathered, sintered (the last row before
    the release) and released (the last row before the side walls go)."""
    volume = sum(4.0 / 3.0 * math.pi * r ** 3 for r in sample[1])

    def state(what, x, y, z, contacts=None):
        count = "" if contacts is None else f", {contacts} contacts"
        print(f"{what}: {x / D0:.2f} x {y / D0:.2f} x {z / D0:.2f} d0, solid fraction "
              f"{volume / (x * y * z):.3f}{count}")

    state("gathered (frictionless, not adhesive)", *sample[2])
    for what, until in (("sintered", T_RELEASE), ("released", T_FREE)):
        row = [r for r in prep if float(r["time"]) <= until][-1]
        state(what, float(row["wall3_x"]), float(row["wall4_y"]), float(row["wall5_z"]), row["contacts"])


# the pull: (m/s, over so many d0) in turn, then PULL_FAST m/s. It starts as slow as the
# Dx = 0.1 tension test (0.025 m/s), where the sample carries its largest tension: at the
# fast speed the plate's damping alone would be comparable to it. The steps keep the jumps
# of the plate's speed, and the damping force each one kicks, small.
PULL_RAMP = [(0.02, 0.5), (0.05, 0.5), (0.1, 0.5)]
PULL_FAST = 0.2
# fig. 17's tensile deformations Dx = (L - L0)/d0
SNAPSHOTS = [0.0, 0.81, 1.8, 3.1, 4.7, 7.4, 8.6]


def read_vtp(path):
    """(positions, radii) of a particle snapshot (ASCII VTK PolyData)."""
    with open(path) as f:
        text = f.read()

    def array(name):
        at = text.index(f'Name="{name}"')
        body = text[text.index(">", at) + 1:text.index("</DataArray>", at)]
        return [float(v) for v in body.split()]

    xyz = array("position")
    points = [tuple(xyz[k:k + 3]) for k in range(0, len(xyz), 3)]
    return points, array("radius")


def snapshots(out_dir, released, start, shots):
    """The pull's snapshots nearest each of `shots`: [(Dx, plate z, points, radii)]."""
    z0 = float(released["wall5_z"])
    rows = read_series(os.path.join(out_dir, "series.csv"))
    # the plate's height at each snapshot's step, from its row
    by_step = {int(r["step"]): float(r["wall5_z"]) for r in rows}
    files = sorted(f for f in os.listdir(os.path.join(out_dir, "snapshots")) if f.endswith(".vtp"))
    steps = [int(f.rsplit("_", 1)[1].split(".")[0]) for f in files]
    views = []
    for dx in shots:
        best = min((k for k in range(len(files)) if steps[k] in by_step),
                   key=lambda k: abs((by_step[steps[k]] - z0) / D0 - dx))
        points, radii = read_vtp(os.path.join(out_dir, "snapshots", files[best]))
        views.append(((by_step[steps[best]] - z0) / D0, by_step[steps[best]], points, radii))
    return views


def bridged(points, radii, plate, gap=0.025 * D0):
    """Whether particles closer than `gap` (surface to surface) chain from the bottom plate
    (z = 0) to the top plate at `plate`."""
    parent = list(range(len(points)))

    def root(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    cell = 1.1 * D0 + gap
    grid = {}
    for i, p in enumerate(points):
        grid.setdefault(tuple(int(math.floor(c / cell)) for c in p), []).append(i)
    for i, p in enumerate(points):
        c = tuple(int(math.floor(x / cell)) for x in p)
        for near in ((c[0] + a, c[1] + b, c[2] + d) for a in (-1, 0, 1) for b in (-1, 0, 1) for d in (-1, 0, 1)):
            for j in grid.get(near, []):
                if j > i and math.dist(p, points[j]) < radii[i] + radii[j] + gap:
                    parent[root(i)] = root(j)
    bottom = {root(i) for i, p in enumerate(points) if p[2] - radii[i] < gap}
    return any(plate - p[2] - radii[i] < gap and root(i) in bottom for i, p in enumerate(points))


def side_views(views, path):
    """Fig. 17: the sample seen along y between its plates, nearer particles red, farther
    blue, drawn far to near."""
    size, pad = 150, 8
    zmax = max(v[1] for v in views) + 0.005
    xs = [p[0] for v in views for p in v[2]]
    x0, x1 = min(xs) - 0.006, max(xs) + 0.006
    scale = min((size * 1.8 - 2 * pad) / zmax, (size - 2 * pad) / (x1 - x0))
    width, height = len(views) * size, int(size * 1.8) + 24
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif">',
             f'<rect width="{width}" height="{height}" fill="white"/>']
    ys = [p[1] for v in views for p in v[2]]
    y0, y1 = min(ys), max(ys)
    for k, (dx, plate, points, radii) in enumerate(views):
        ox = k * size + pad - x0 * scale
        base = int(size * 1.8) - pad

        def px(x):
            return ox + x * scale

        def pz(z):
            return base - z * scale

        parts.append(f'<line x1="{k * size + 4}" y1="{pz(0.0):.1f}" x2="{(k + 1) * size - 4}" y2="{pz(0.0):.1f}" stroke="#444" stroke-width="2"/>')
        parts.append(f'<line x1="{k * size + 4}" y1="{pz(plate):.1f}" x2="{(k + 1) * size - 4}" y2="{pz(plate):.1f}" stroke="#444" stroke-width="2"/>')
        for i in sorted(range(len(points)), key=lambda i: -points[i][1]):
            x, y, z = points[i]
            t = (y - y0) / max(y1 - y0, 1e-12)
            # red (near) - green - blue (far)
            r, g, b = (1 - 2 * t, 2 * t, 0) if t < 0.5 else (0, 2 - 2 * t, 2 * t - 1)
            colour = f"#{int(255 * max(r, 0)):02x}{int(255 * max(g, 0)):02x}{int(255 * max(b, 0)):02x}"
            parts.append(f'<circle cx="{px(x):.1f}" cy="{pz(z):.1f}" r="{radii[i] * scale:.2f}" fill="{colour}" stroke="#222" stroke-width="0.2"/>')
        parts.append(f'<text x="{k * size + size / 2}" y="{height - 6}" text-anchor="middle" font-size="12">Dx = {dx:.2f}</text>')
    parts.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(parts) + "\n")


def write_outputs(out, prep, results, views, pulled):
    """The figures, the tables and the CSV of every test's curve. A result: (name, Dx,
    tension?, slower, [(t, x, force)], half cycle s)."""
    side_views(views, os.path.join(out, "paper000_agglomerate_snapshots.svg"))
    with open(os.path.join(out, "paper000_agglomerate.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["test", "amplitude_dx", "slower", "time_s", "compression_over_d0", "force_over_kp_d0"])
        for name, dx, _, slower, points, _ in results:
            for t, x, y in points:
                w.writerow([name, dx, slower, f"{t:.6e}", f"{x:.6e}", f"{y:.6e}"])
    panels = []
    for is_tension in (True, False):
        chosen = [r for r in results if r[2] == is_tension]
        amplitudes = sorted({r[1] for r in chosen})
        series = []
        for name, dx, _, slower, points, _ in chosen:
            colour = amplitudes.index(dx)
            label = f"Dx = {dx:g}" + (" (4x slower)" if slower > 1 else "")
            series.append((label, [(x, y) for _, x, y in points], "thick" if slower > 1 else "curve", colour))
        xs = [x for r in chosen for _, x, _ in r[4]]
        ys = [y for r in chosen for _, _, y in r[4]]
        span = max(abs(v) for v in xs) if xs else 1.0
        step = 0.05 if span <= 0.25 else 0.25
        xlim = (-step * (int(span / step) + 1), step) if is_tension else (-step, step * (int(span / step) + 1))
        lo, hi = min(ys), max(ys)
        ystep = nice_step(hi - lo)
        ylim = (ystep * int(lo / ystep - 1), ystep * int(hi / ystep + 1))
        title = "unconfined tension cycles (fig. 16)" if is_tension else "unconfined compression cycles (fig. 18)"
        panels.append(svgplot.panel(title, "(L0 - L)/d0", "force / (kp d0)", series, xlim, ylim,
                                    width=560, height=420, ystep=ystep, xstep=step,
                                    legend=(0.03, 0.97)))
    svgplot.figure(panels, os.path.join(out, "paper000_agglomerate.svg"))
    # the table: what each test's cycles show
    last = prep[-1]
    print(f"\nreleased sample: {last['contacts']} contacts, top plate force "
          f"{float(last['wall5_fz']) / (KP * D0):.3e} kp d0 at z = {float(last['wall5_z']):.5f} m")
    print("| test | Dx | first extreme force | force back at 0, cycle 1 | cycle 4 | extreme force, cycle 2 | cycle 4 |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name, dx, is_tension, slower, points, half in results:
        cyc = [[p for p in points if 2 * k * half <= p[0] <= 2 * (k + 1) * half] for k in range(4)]
        ext = [min(c, key=lambda p: p[2])[2] if is_tension else max(c, key=lambda p: p[2])[2] for c in cyc]
        back = [at(points, 2 * (k + 1) * half)[2] for k in range(4)]
        print(f"| {name} | {dx:g} | {ext[0]:.3e} | {back[0]:.3e} | {back[-1]:.3e} | {ext[1]:.3e} | {ext[-1]:.3e} |")
    by_name = {r[0]: r for r in results}
    for name, *_ in results:
        if name.endswith("_slow"):
            fast, slow = by_name[name[:-5]], by_name[name]
            # the two compared at the same fraction of the test
            length = 8 * fast[5]
            diff = [at(fast[4], length * k / 400)[2] - at(slow[4], 4 * length * k / 400)[2] for k in range(401)]
            span = max(p[2] for p in fast[4]) - min(p[2] for p in fast[4])
            rms = math.sqrt(sum(d * d for d in diff) / len(diff))
            print(f"{name}: four times slower, the force differs by {rms:.2e} kp d0 rms "
                  f"({rms / span:.1%} of the cycles' range), {max(abs(d) for d in diff):.2e} at most")
    slow_part = PULL_RAMP[0][1]
    peak = min((p for p in pulled if -p[1] <= slow_part), key=lambda p: p[2])
    extreme = min(pulled, key=lambda p: p[2])
    # the force over windows of 0.5 d0: (start Dx, mean, largest |force|); the sample rings
    # once the plate has sped up, so single samples swing about the mean
    windows = []
    for k in range(int(-pulled[-1][1] / 0.5)):
        w = [p[2] for p in pulled if 0.5 * k <= -p[1] < 0.5 * (k + 1)]
        if w:
            windows.append((0.5 * k, sum(w) / len(w), max(abs(v) for v in w)))
    held = [w for w in windows if abs(w[1]) > 1e-3]
    free = held[-1][0] + 0.5 if held else 0.0
    after = [w[2] for w in windows if w[0] >= free]
    if after:
        let_go = (f"the force averaged over 0.5 d0 stays within 1e-3 kp d0 of zero beyond Dx = {free:.1f} "
                  f"(single samples there up to {max(after):.1e}: the sample ringing)")
    else:
        let_go = "the force averaged over 0.5 d0 still exceeds 1e-3 kp d0 at the end"
    print(f"pull: largest tension {peak[2]:.3e} kp d0 at Dx = {-peak[1]:.3f} (the first {slow_part:g} d0; "
          f"the whole pull's {extreme[2]:.3e} at Dx = {-extreme[1]:.3f}); {let_go}; the pull ends at "
          f"Dx = {-pulled[-1][1]:.2f}")
    chained = [f"{dx:.2f} {'yes' if bridged(points, radii, plate) else 'no'}" for dx, plate, points, radii in views]
    print(f"pull: particles chain the plates (surface gaps < 0.025 d0) at the snapshots' Dx: {', '.join(chained)}")
    for start, mean, top in windows:
        print(f"  Dx {start:.1f}-{start + 0.5:.1f}: mean {mean:+.2e}, largest |force| {top:.1e}")


def at(points, t):
    """The (t, x, force) of a test at time `t` since its start, interpolated."""
    for a, b in zip(points, points[1:]):
        if a[0] <= t <= b[0]:
            f = (t - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 0.0
            return tuple(u * (1 - f) + v * f for u, v in zip(a, b))
    return points[-1] if t > points[-1][0] else points[0]


def nice_step(span):
    for s in (0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0):
        if span / s <= 10:
            return s
    return 10.0


if __name__ == "__main__":
    main()
