#!/usr/bin/env python3
"""Paper 002, section 6.2 and fig. 13: a PSL sphere (d = 1.27 um, rho = 1026 kg/m^3) hits
polished quartz at 5 m/s (E* = 271 MPa, gamma = 0.11 J/m^2, e = 0.86: the collision
properties of the paper's fig. 5); its stiffness is reduced by S = E_mod/E = 1, 0.1, 0.01,
0.001 with gamma_mod = gamma S^(2/5) (rule 24). The rebound speed stays; the collision lasts
Delta t_col,mod = Delta t_col (E/E_mod)^(2/5).

    python3 examples/studies/paper002_collision_time.py [--backend cpu|gpu] [--powder PATH] [--out docs]

Writes OUT/paper002_collision_time.svg (the sphere's normal velocity against the time since
it touched, CPU traces) and prints the table (restitution and contact time on the chosen
backend). Paper 002's JKR as in paper002_binary.py: zero-overlap break, Tsuji damping on
Sn = 2E* sqrt(R* delta). The wall is of the sphere's material, so E = 2(1 - nu^2) E* gives
the sphere-wall pair E* = 271 MPa (nu = 0.3).
"""

import argparse
import csv
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import svgplot  # noqa: E402

E_STAR, NU, GAMMA, E_REST = 271e6, 0.3, 0.11, 0.86
RADIUS, RHO, V = 0.635e-6, 1026.0, 5.0
SCALES = [1.0, 0.1, 0.01, 0.001]
REFINE = 8  # the time step: powder's default / 8 (as in paper002_binary.py)


def run(cmd):
    out = svgplot.run_powder(cmd)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)}\n{out.stderr}")
    return json.loads(out.stdout)


def collide(powder, backend, scale, trace=None):
    cmd = [powder, "collide", "--model", "jkr", "--youngs", repr(2 * (1 - NU * NU) * E_STAR),
           "--poisson", repr(NU), "--surface-energy", repr(GAMMA), "--restitution", repr(E_REST),
           "--tsuji-stiffness", "hertz", "--pulloff", "zero", "--stiffness-scale", repr(scale),
           "--radius", repr(RADIUS), "--density", repr(RHO), "--velocity", repr(V), "--wall", "--json"]
    dt = run(cmd + ["--backend", "cpu"])["dt"] / REFINE
    extra = ["--trace", trace] if trace else []
    return run(cmd + ["--backend", backend, "--dt", repr(dt)] + extra)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--backend", default="cpu", choices=["cpu", "gpu"])
    ap.add_argument("--powder", default=svgplot.POWDER, help="the powder binary (default: the repository's release build)")
    ap.add_argument("--out", default="docs")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    series, table = [], []
    for s in SCALES:
        with tempfile.TemporaryDirectory() as tmp:
            trace = os.path.join(tmp, "trace.csv")
            collide(a.powder, "cpu", s, trace)
            with open(trace) as f:
                rows = [(float(r["t"]), float(r["delta"]), -float(r["delta_dot"])) for r in csv.DictReader(f)]
        touch = next(t for t, d, _ in rows if d > 0)
        series.append((f"E_mod/E = {s:g}", [(t - touch, v) for t, d, v in rows if t > touch], "curve"))
        r = collide(a.powder, a.backend, s)
        table.append((s, r["e"], r["contact_duration"]))
    base = table[0][2]
    print(f"{'E_mod/E':>8} {'e_eff':>10} {'contact time (s)':>17} {'ratio':>10} {'(E/E_mod)^(2/5)':>16}")
    for s, e, t in table:
        print(f"{s:8g} {e:10.7f} {t:17.7e} {t / base:10.6f} {s ** -0.4:16.6f}")
    svgplot.figure([svgplot.panel(
        "PSL on quartz at 5 m/s, stiffness reduced by rule (24) (paper 002 fig. 13)",
        "time since the touch, s", "normal velocity, m/s (away from the wall)",
        series, (1e-10, 1e-6), (-6.0, 6.0), width=760, height=420, ystep=2.0, legend=(0.03, 0.95))],
        os.path.join(a.out, "paper002_collision_time.svg"))
    print(f"wrote {a.out}/paper002_collision_time.svg ({a.backend} backend for the table)")


if __name__ == "__main__":
    main()
