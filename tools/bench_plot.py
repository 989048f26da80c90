#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Plots `ubersim bench --csv` output of robot-count runs (bench --scaling) as an SVG file.

One panel per drive (per CSV file, or per drive within one): the wall time of a step against
the robots on the field, stacked by where it went (collision, ODE step, plugins, perception,
the rest), and, when the bench counted them (--instructions), the instructions a step executes
on a second axis. Standard library only (no matplotlib), so it runs wherever the bench does.

    tools/bench_plot.py docs/images/scaling-robots.svg omni.csv omni_force.csv \\
        --title "Div A, --profile fast" --note "commit abc1234; AMD EPYC, 2 cores"
"""

import argparse
import csv
import math
import sys
from xml.sax.saxutils import escape

PARTS = [  # CSV column, legend, colour
    ("collision", "collision", "#d62728"),
    ("physics", "ODE step", "#1f77b4"),
    ("plugins", "plugins", "#2ca02c"),
    ("perception", "perception", "#ff7f0e"),
    ("rest", "events, transports, other", "#9a9a9a"),
]
INSTRUCTIONS_COLOUR = "#000000"
PANEL_W, PANEL_H = 400, 300
LEFT, RIGHT, TOP, BOTTOM = 62, 62, 58, 48  # margins of a panel, px
LEGEND_H = 70


def read_rows(paths):
    """Rows grouped by drive, each sorted by robots; the order drives first appear in."""
    groups = {}
    for path in paths:
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                drive = row["drive"]
                r = {
                    "robots": int(row["robots"]),
                    "us": float(row["us_per_step"]),
                    "instructions": float(row["instructions_per_step"]) if row["instructions_per_step"] else None,
                    "contacts": float(row["contacts_per_step"]),
                }
                shares = {p: float(row[p]) for p in ("collision", "physics", "plugins", "perception")}
                shares["rest"] = max(0.0, 1.0 - sum(shares.values()))
                r["shares"] = shares
                groups.setdefault(drive, []).append(r)
    for rows in groups.values():
        rows.sort(key=lambda r: r["robots"])
    return groups


def nice_ceiling(x):
    """The smallest of 1, 2, 2.5, 5 × 10^k at or above x, and a tick step for it."""
    if x <= 0:
        return 1.0, 0.25
    k = math.floor(math.log10(x))
    for m, ticks in ((1, 5), (2, 4), (2.5, 5), (5, 5), (10, 5)):
        top = m * 10**k
        if top >= x * 0.999:
            return top, top / ticks
    return 10 ** (k + 1), 10**k * 2


def number(v):
    return f"{v:g}" if abs(v) >= 1 or v == 0 else f"{v:.2g}"


def panel(out, x0, y0, drive, rows, robots_max):
    w = PANEL_W - LEFT - RIGHT
    h = PANEL_H - TOP - BOTTOM
    left, top = x0 + LEFT, y0 + TOP
    us_top, us_tick = nice_ceiling(max(r["us"] for r in rows))
    has_instructions = all(r["instructions"] is not None for r in rows)
    if has_instructions:
        ins_top, ins_tick = nice_ceiling(max(r["instructions"] for r in rows) / 1e6)

    def px(robots):
        return left + w * robots / robots_max

    def py(us):
        return top + h - h * us / us_top

    out.append(f'<text x="{left + w / 2}" y="{y0 + 24}" text-anchor="middle" font-weight="bold">'
               f'{escape(drive)}</text>')
    # Grid and axes.
    t = 0.0
    while t <= us_top * 1.0001:
        y = py(t)
        out.append(f'<line x1="{left}" y1="{y:.1f}" x2="{left + w}" y2="{y:.1f}" stroke="#e4e4e4"/>')
        out.append(f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end">{number(t)}</text>')
        t += us_tick
    for r in rows:
        x = px(r["robots"])
        out.append(f'<line x1="{x:.1f}" y1="{top + h}" x2="{x:.1f}" y2="{top + h + 4}" stroke="#000"/>')
        out.append(f'<text x="{x:.1f}" y="{top + h + 18}" text-anchor="middle">{r["robots"]}</text>')
    out.append(f'<rect x="{left}" y="{top}" width="{w}" height="{h}" fill="none" stroke="#000"/>')
    out.append(f'<text x="{left + w / 2}" y="{top + h + 38}" text-anchor="middle">robots on the field</text>')
    out.append(f'<text transform="translate({x0 + 16},{top + h / 2}) rotate(-90)" text-anchor="middle">'
               f'µs per step (wall clock)</text>')
    # The parts, stacked: each band between the sum of the parts below it and that sum plus it.
    below = [0.0] * len(rows)
    for key, _, colour in PARTS:
        above = [b + r["us"] * r["shares"][key] for b, r in zip(below, rows)]
        points = [f"{px(r['robots']):.1f},{py(a):.1f}" for r, a in zip(rows, above)]
        points += [f"{px(r['robots']):.1f},{py(b):.1f}" for r, b in reversed(list(zip(rows, below)))]
        out.append(f'<polygon points="{" ".join(points)}" fill="{colour}" fill-opacity="0.75" stroke="none"/>')
        below = above
    if has_instructions:
        def pyi(m):
            return top + h - h * m / ins_top

        t = 0.0
        while t <= ins_top * 1.0001:
            y = pyi(t)
            out.append(f'<text x="{left + w + 6}" y="{y + 4:.1f}">{number(t)}</text>')
            t += ins_tick
        points = " ".join(f"{px(r['robots']):.1f},{pyi(r['instructions'] / 1e6):.1f}" for r in rows)
        out.append(f'<polyline points="{points}" fill="none" stroke="{INSTRUCTIONS_COLOUR}" stroke-width="2" '
                   f'stroke-dasharray="6,4"/>')
        for r in rows:
            out.append(f'<circle cx="{px(r["robots"]):.1f}" cy="{pyi(r["instructions"] / 1e6):.1f}" r="3" '
                       f'fill="{INSTRUCTIONS_COLOUR}"/>')
        out.append(f'<text transform="translate({x0 + PANEL_W - 14},{top + h / 2}) rotate(90)" '
                   f'text-anchor="middle">million instructions per step (callgrind)</text>')


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", help="SVG file to write")
    parser.add_argument("csv", nargs="+", help="CSV files written by `ubersim bench --csv`")
    parser.add_argument("--title", default="Cost of a step against the robots")
    parser.add_argument("--note", default="", help="a line under the title (commit, machine)")
    args = parser.parse_args(argv)
    groups = read_rows(args.csv)
    if not groups:
        sys.exit("bench_plot.py: no rows in " + ", ".join(args.csv))
    robots_max = max(r["robots"] for rows in groups.values() for r in rows)
    width = PANEL_W * len(groups)
    height = 50 + PANEL_H + LEGEND_H
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">',
           f'<rect width="{width}" height="{height}" fill="#fff"/>',
           f'<text x="{width / 2}" y="20" text-anchor="middle" font-size="15">{escape(args.title)}</text>']
    if args.note:
        out.append(f'<text x="{width / 2}" y="38" text-anchor="middle" fill="#555">{escape(args.note)}</text>')
    for i, (drive, rows) in enumerate(groups.items()):
        panel(out, i * PANEL_W, 36, drive, rows, robots_max)
    # Legend.
    y = 36 + PANEL_H + 10
    x = 20
    for _, label, colour in PARTS:
        out.append(f'<rect x="{x}" y="{y}" width="14" height="12" fill="{colour}" fill-opacity="0.75"/>')
        out.append(f'<text x="{x + 20}" y="{y + 11}">{escape(label)}</text>')
        x += 30 + 7 * len(label)
    out.append(f'<line x1="{20}" y1="{y + 34}" x2="{48}" y2="{y + 34}" stroke="{INSTRUCTIONS_COLOUR}" '
               f'stroke-width="2" stroke-dasharray="6,4"/>')
    out.append(f'<text x="{56}" y="{y + 38}">instructions per step (right axis; steady, unlike the wall '
               f'clock)</text>')
    out.append("</svg>")
    with open(args.out, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
