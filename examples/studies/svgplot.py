"""What the studies share (standard library only): a small SVG line plot with a
logarithmic or linear x axis (`panel(...)` draws one set of axes, `figure(...)` puts panels side by
side), `run_powder`, which runs the powder binary, `power_law_fit` and `log_bisect`."""

import math
import os
import subprocess
import sys

# the repository's release build, wherever the study is run from
POWDER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "target", "release", "powder")


# what `powder collide` says when it refuses a pair pressed deeper than a radius (beyond
# the contact laws' geometry; paper 002's maps reach there at low lambda)
TOO_DEEP = "more than the smaller radius"


def run_powder(cmd):
    """Runs `cmd` (the powder binary first); a missing binary is said plainly."""
    try:
        return subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError:
        sys.exit(f"no powder binary at {cmd[0]}: build it with `cargo build --release` or pass --powder PATH")

def power_law_fit(points):
    """Least squares of log y against log x over [(x, y)]: (c, exponent) of y = c x^exponent."""
    xs = [math.log10(x) for x, _ in points]
    ys = [math.log10(y) for _, y in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    return 10 ** (my - slope * mx), slope


def log_bisect(holds, lo, hi, iterations):
    """The x between `lo` (where `holds(x)`) and `hi` (where not) at which it stops holding,
    by `iterations` bisections in log x."""
    for _ in range(iterations):
        mid = math.sqrt(lo * hi)
        if holds(mid):
            lo = mid
        else:
            hi = mid
    return math.sqrt(lo * hi)


COLOURS = ["#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d"]


def _esc(text):
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def panel(title, xlabel, ylabel, series, xlim, ylim, width=520, height=380, ystep=0.2, legend=(0.03, 0.45),
          xstep=None):
    """One panel's SVG elements (a string) and its size. `series`: [(label, [(x, y)], style
    [, colour index])]
    with style "line" (with markers), "curve" (without), "thick" (a wide pale curve) or
    "points"; x is drawn on a log scale, or linear with ticks every `xstep` where given; y
    ticks every `ystep`; the legend's top left corner at `legend`, fractions of the axes
    from the lower left."""
    left, right, top, bottom = 62, 12, 30, 48
    w, h = width - left - right, height - top - bottom
    if xstep is None:
        lx0, lx1 = math.log10(xlim[0]), math.log10(xlim[1])

    def sx(x):
        if xstep is not None:
            return left + (x - xlim[0]) / (xlim[1] - xlim[0]) * w
        return left + (math.log10(x) - lx0) / (lx1 - lx0) * w

    def sy(y):
        return top + (1 - (y - ylim[0]) / (ylim[1] - ylim[0])) * h

    out = [f'<rect x="{left}" y="{top}" width="{w}" height="{h}" fill="none" stroke="#444"/>']
    out.append(f'<text x="{left + w / 2}" y="18" text-anchor="middle" font-size="14">{_esc(title)}</text>')
    if xstep is None:
        for d in range(math.ceil(lx0), math.floor(lx1) + 1):
            x = sx(10 ** d)
            out.append(f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{top + h}" stroke="#ddd"/>')
            out.append(f'<text x="{x:.1f}" y="{top + h + 16}" text-anchor="middle" font-size="11">10<tspan dy="-5" font-size="8">{d}</tspan></text>')
    else:
        for k in range(int(round((xlim[1] - xlim[0]) / xstep)) + 1):
            xv = xlim[0] + k * xstep
            x = sx(xv)
            out.append(f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{top + h}" stroke="#ddd"/>')
            out.append(f'<text x="{x:.1f}" y="{top + h + 16}" text-anchor="middle" font-size="11">{xv:.3g}</text>')
    for k in range(int(round((ylim[1] - ylim[0]) / ystep)) + 1):
        yv = ylim[0] + k * ystep
        y = sy(yv)
        out.append(f'<line x1="{left}" y1="{y:.1f}" x2="{left + w}" y2="{y:.1f}" stroke="#eee"/>')
        out.append(f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end" font-size="11">{yv:.2g}</text>')
    out.append(f'<text x="{left + w / 2}" y="{height - 8}" text-anchor="middle" font-size="12">{_esc(xlabel)}</text>')
    out.append(f'<text transform="translate(14,{top + h / 2}) rotate(-90)" text-anchor="middle" font-size="12">{_esc(ylabel)}</text>')
    for k, item in enumerate(series):
        # (an optional fourth member: the colour's index, else the series')
        label, points, style = item[:3]
        colour = COLOURS[(item[3] if len(item) > 3 else k) % len(COLOURS)]
        pts = [(sx(x), sy(y)) for x, y in points if xlim[0] <= x <= xlim[1]]
        if style in ("line", "curve", "thick") and len(pts) > 1:
            path = " ".join(f"{x:.1f},{y:.1f}" for x, y in pts)
            stroke = 'stroke-width="5" stroke-opacity="0.35"' if style == "thick" else 'stroke-width="1.6"'
            out.append(f'<polyline points="{path}" fill="none" stroke="{colour}" {stroke}/>')
        for x, y in pts if style == "line" or style == "points" else []:
            out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="2.4" fill="{colour}"/>')
        lx = left + legend[0] * w
        ly = top + (1 - legend[1]) * h + 15 * k
        out.append(f'<line x1="{lx:.1f}" y1="{ly - 4:.1f}" x2="{lx + 20:.1f}" y2="{ly - 4:.1f}" stroke="{colour}" stroke-width="2"/>')
        out.append(f'<text x="{lx + 25:.1f}" y="{ly:.1f}" font-size="11">{_esc(label)}</text>')
    return "\n".join(out), (width, height)


def figure(panels, path):
    """Writes the panels side by side to `path`."""
    width = sum(size[0] for _, size in panels)
    height = max(size[1] for _, size in panels)
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif">',
             f'<rect width="{width}" height="{height}" fill="white"/>']
    x = 0
    for body, size in panels:
        parts.append(f'<g transform="translate({x},0)">{body}</g>')
        x += size[0]
    parts.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(parts) + "\n")
