#!/usr/bin/env python3
"""Paper 001 (figs. 8, 11, 13): the coefficient of restitution e(v) of head-on collisions of
equal Lennard-Jones particles of radius R = 58.9, 88.4, 147 and 294 (LJ units, table II;
29.6, which always coalesces in the paper's MD, is left out as there) for the
JKR theory, Krijt's dissipation (with Thornton-Ning's plastic e_pl beside it), the
stress-dependent dissipation and the power-law dissipation, one panel per radius.

    python3 examples/studies/paper001_restitution.py [--backend cpu|gpu] [--powder PATH] [--out docs]
        [--points 29]

Writes OUT/paper001_restitution.svg and .csv and prints the table. Parameters (paper 001):
gamma = 3.17, nu = 0.25, rho = 1.09, E* from table II (58.4, 65.5, 68.3), Krijt
T_vis = 0.075 R/147 with sigma0 = gamma/1.091 = 2.906 (appendix C), the stress model's
T_vis,0 = C R with C = 2.1e-4, B = 6.2 (the text's fit; fig. 11's caption says 6.4),
zeta = 4, the power law D = 118, alpha = 3, beta = 1.5, Thornton-Ning with v_Y = 0.17 (the
text's value, section IV B; the captions of figs. 7, 8 and 11 write Y = 0.12 E*).
"""

import argparse
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import svgplot  # noqa: E402

GAMMA, NU, RHO = 3.17, 0.25, 1.09
RADII = {58.9: 58.4, 88.4: 63.7, 147.0: 65.5, 294.0: 68.3}  # R: E* (table II)


def models(r):
    """(name, powder collide options, the JSON key plotted)."""
    return [
        ("JKR", ["--dissipation", "none"], "e"),
        ("Krijt", ["--dissipation", "krijt", "--tvis", repr(0.075 * r / 147), "--sigma0", "2.906"], "e"),
        ("Krijt + Thornton-Ning", ["--dissipation", "krijt", "--tvis", repr(0.075 * r / 147), "--sigma0", "2.906",
                                   "--yield-velocity", "0.17"], "e_pl"),
        ("stress-dependent", ["--dissipation", "stress", "--tvis0-per-radius", "2.1e-4", "--B", "6.2", "--zeta", "4",
                              "--sigma0", "2.906"], "e"),
        ("power law", ["--dissipation", "powerlaw", "--D", "118", "--alpha", "3", "--beta", "1.5"], "e"),
    ]


def sweep(powder, backend, r, e_star, options, points):
    cmd = [powder, "collide", "--model", "jkr", "--youngs", repr(2 * (1 - NU * NU) * e_star), "--poisson", repr(NU),
           "--surface-energy", repr(GAMMA), "--radius", repr(r), "--density", repr(RHO),
           "--sweep-velocity", f"0.02:0.3:{points}", "--backend", backend, "--json"] + options
    out = svgplot.run_powder(cmd)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)}\n{out.stderr}")
    return json.loads(out.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--backend", default="cpu", choices=["cpu", "gpu"])
    ap.add_argument("--powder", default=svgplot.POWDER, help="the powder binary (default: the repository's release build)")
    ap.add_argument("--out", default="docs")
    ap.add_argument("--points", type=int, default=29, help="impact velocities from 0.02 to 0.3 (29)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    panels, rows = [], []
    for r, e_star in RADII.items():
        series = []
        for name, options, key in models(r):
            runs = sweep(a.powder, a.backend, r, e_star, options, a.points)
            points = [(x["velocity"], 0.0 if x["stuck"] else x[key]) for x in runs]
            series.append((name, points, "line"))
            rows += [(r, name, v, e) for v, e in points]
            if name == "JKR":
                closed = [(x["velocity"], x["e_analytic"] or 0.0) for x in runs]
                worst = max(abs(e - c) for (_, e), (_, c) in zip(points, closed))
                print(f"R = {r:g}: JKR simulated against the closed form within {worst:.1e}")
        panels.append(svgplot.panel(f"R = {r:g}, E* = {e_star:g} (LJ units)", "impact velocity v", "coefficient of restitution e",
                                    series, (0.02, 0.3), (0.0, 1.0), width=440, height=360,
                                    legend=(0.03, 0.97) if r < 60 else (0.5, 0.33)))
        peaks = {name: max(p, key=lambda q: q[1]) for name, p, _ in series}
        stick = {name: max((v for v, e in p if e == 0.0), default=None) for name, p, _ in series}
        print(f"R = {r:g}:")
        for name, (v, e) in peaks.items():
            s = stick[name]
            sticks = f"{s:.2f}" if s is not None else "-"
            print(f"  {name:22s} peak e = {e:.3f} at v = {v:.2f}; sticks up to v = {sticks}")
    with open(os.path.join(a.out, "paper001_restitution.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["R", "model", "v", "e"])
        w.writerows(rows)
    svgplot.figure(panels, os.path.join(a.out, "paper001_restitution.svg"))
    print(f"wrote {a.out}/paper001_restitution.svg and .csv ({a.backend} backend)")


if __name__ == "__main__":
    main()
