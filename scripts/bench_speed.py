#!/usr/bin/env python3
"""One benchmark run for docs/performance.md: two convshadow release binaries side by side.

    scripts/bench_speed.py OLD_BIN NEW_BIN [--reps N] [--quick] [--new-args "..."] [--pairs-only]
        [--no-scaling]

`--new-args` is appended to the NEW binary's arguments where it runs against OLD (so that both
render the same image: e.g. `--penumbra iterated --guard-band 0` against a release from before
those options); `--pairs-only` stops after the old-vs-new tables; `--no-scaling` leaves out only the
time-against-work tables.

Every comparison alternates the binaries (or paths, or thread counts) run by run, so a shared
machine's load falls on both alike, and reports medians and their ratio, the median of the
per-round ratios (A and B run back to back: steadier when the machine's speed drifts) and the
median per-round ratio of `seconds_sweep` (the sweep alone); only ratios from one run mean
something on a noisy machine. Each case also checks that both runs wrote the same
`image_hash`. Prints Markdown tables: the issue's ratios, every kernel, and how the sweep's time
grows with slabs, pixels and lights (NEW binary only). Times: wall seconds of the whole command
for 2-thread cases, user CPU seconds for 1-thread cases, `seconds_sweep` for the scaling tables.
"""

import argparse
import json
import os
import pathlib
import re
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
TMP = pathlib.Path(tempfile.mkdtemp(prefix="bench-speed-"))


def run(binary, args):
    """Runs one render; returns (wall s, user s, stats dict)."""
    stats = TMP / "stats.json"
    cmd = [binary, "render", *args, "-o", str(TMP / "out.exr"), "--quiet", "--stats-json", str(stats)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    user = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before
    return wall, user, json.loads(stats.read_text())


def alternate(variants, reps, measure, runs=None):
    """variants: {name: (binary, args)}; runs them in turn `reps` times (order rotating).
    Returns {name: median of measure(wall, user, stats)} and the set of hashes seen per name;
    `runs`, when given, receives per name the list of (measure, seconds_sweep) of every run in
    round order."""
    values = {k: [] for k in variants}
    hashes = {k: set() for k in variants}
    names = list(variants)
    for r in range(reps):
        order = names[r % len(names):] + names[: r % len(names)]
        for k in order:
            b, a = variants[k]
            wall, user, stats = run(b, a)
            values[k].append(measure(wall, user, stats))
            hashes[k].add(stats["image_hash"])
            if runs is not None:
                runs.setdefault(k, []).append((values[k][-1], stats["seconds_sweep"]))
    return {k: statistics.median(v) for k, v in values.items()}, hashes


def scene(name):
    return [] if name == "default" else [str(ROOT / "scenes" / f"{name}.toml")]


def wall(w, u, s):
    """Wall seconds of the whole command."""
    return w


def user(w, u, s):
    """User CPU seconds of the command."""
    return u


def rate(w, u, s):
    """The sweep's pixel·slab·light updates per second, in millions."""
    return s["pixel_slab_lights_per_second"] / 1e6


def lights_scene(n):
    """The default scene with its two lights repeated (directions turned) to n lights."""
    text = (ROOT / "scenes" / "default.toml").read_text()
    head, sep, rest = text.partition("[[light]]")
    blocks = ["[[light]]" + b for b in rest.split("[[light]]")]
    tail_at = re.search(r"\n\[(?!\[light\])", blocks[-1])
    tail = ""
    if tail_at:
        tail = blocks[-1][tail_at.start():]
        blocks[-1] = blocks[-1][: tail_at.start()]
    out = []
    for i in range(n):
        b = blocks[i % len(blocks)]
        if i >= len(blocks):
            # Turn repeated lights a little so they are not copies (same cost either way).
            b = re.sub(r"tilt_deg\s*=\s*\[([^\]]*)\]",
                       lambda m: "tilt_deg = [" + ", ".join(
                           f"{float(x) + 3.0 * i:g}" for x in m.group(1).split(",")) + "]", b)
        out.append(b.rstrip() + "\n\n")
    path = TMP / f"lights{n}.toml"
    path.write_text(head + "".join(out) + tail)
    return [str(path)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="smaller images for a smoke run")
    ap.add_argument("--new-args", default="", help="extra arguments for NEW where it runs against OLD")
    ap.add_argument("--pairs-only", action="store_true", help="only the old-vs-new tables")
    ap.add_argument("--no-scaling", action="store_true",
                    help="every table but the time-against-work ones (the longest part)")
    o = ap.parse_args()
    new_args = shlex.split(o.new_args)
    old, new, reps = os.path.abspath(o.old), os.path.abspath(o.new), o.reps
    size = ["--size", "128x128", "--slabs", "128"] if o.quick else []
    small = ["--size", "256x256", "--slabs", "256"]
    bad = []

    def check(label, hashes):
        seen = set().union(*hashes.values())
        if len(seen) != 1:
            bad.append(f"{label}: different image hashes {sorted(seen)}")

    rows = []

    def pair(label, a, b, measure, unit, names=("old", "new")):
        runs = {}
        med, h = alternate({names[0]: a, names[1]: b}, reps, measure, runs)
        check(label, h)
        x, y = med[names[0]], med[names[1]]
        faster = (lambda p, q: q / p) if unit == "M/s" else (lambda p, q: p / q)
        ratio = faster(x, y)
        # Per round (A and B run back to back): robust to the machine's speed drifting between
        # rounds; and the sweep's own time, without start-up, plan and output.
        rounds = statistics.median(faster(p[0], q[0]) for p, q in zip(runs[names[0]], runs[names[1]]))
        sweep = statistics.median(p[1] / q[1] for p, q in zip(runs[names[0]], runs[names[1]]))
        rows.append(f"| {label} | {x:.3f} {unit} | {y:.3f} {unit} | **{ratio:.2f}×** | {rounds:.2f}× | {sweep:.2f}× |")
        return med

    print(f"# bench_speed.py, {time.strftime('%Y-%m-%d %H:%M')} UTC, reps {reps}\n")
    print(f"old: {old}\nnew: {new} {o.new_args}\n")
    rows.append("| case | A | B | B faster by | per round | sweep, per round |")
    rows.append("|---|---|---|---|---|---|")
    for sc in ["default", "bunny"]:
        pair(f"{sc}: old (A) vs new (B), SIMD, 2 threads, wall",
             (old, scene(sc) + size + ["--threads", "2"]), (new, scene(sc) + size + ["--threads", "2"] + new_args), wall, "s")
        pair(f"{sc}: old (A) vs new (B), SIMD, 1 thread, user",
             (old, scene(sc) + size + ["--threads", "1"]), (new, scene(sc) + size + ["--threads", "1"] + new_args), user, "s")
    if o.pairs_only:
        print("## Old against new\n")
        print("\n".join(rows) + "\n")
    else:
        new_only(pair, new, size)
        print("## The issue's ratios\n")
        print("\n".join(rows) + "\n")

    rows.clear()
    rows.append("| kernel (default scene, 256², 256 slabs, 2 threads) | old (A) | new (B) | B faster by | per round | sweep, per round |")
    rows.append("|---|---|---|---|---|---|")
    for k in ["ellipse2", "ellipse3", "ellipse2:slab", "poisson8", "poisson16", "gaussian:19", "box", "dirac"]:
        pair(f"`{k}`", (old, small + ["--kernel", k, "--threads", "2"]),
             (new, small + ["--kernel", k, "--threads", "2"] + new_args), rate, "M/s")
    print("## Every kernel (pixel·slab·light updates per second of the sweep)\n")
    print("\n".join(rows) + "\n")
    if o.pairs_only or o.no_scaling:
        finish(bad)
        return
    scaling_tables(new, reps, small)
    finish(bad)


def new_only(pair, new, size):
    """The NEW binary against itself: scalar vs SIMD, 1 vs 2 threads."""
    pair("bunny, new: scalar (A) vs SIMD (B), 1 thread, user",
         (new, scene("bunny") + size + ["--threads", "1", "--path", "scalar"]),
         (new, scene("bunny") + size + ["--threads", "1", "--path", "simd"]), user, "s",
         names=("scalar", "simd"))
    pair("bunny, new: 1 thread (A) vs 2 threads (B), SIMD, wall",
         (new, scene("bunny") + size + ["--threads", "1"]),
         (new, scene("bunny") + size + ["--threads", "2"]), wall, "s", names=("t1", "t2"))
    pair("default, new: 1 thread (A) vs 2 threads (B), SIMD, wall",
         (new, size + ["--threads", "1"]), (new, size + ["--threads", "2"]), wall, "s",
         names=("t1", "t2"))


def scaling_tables(new, reps, small):
    """How the NEW binary's sweep time grows with slabs, pixels and lights."""
    def scaling(title, cases):
        print(f"## {title} (new binary, 2 threads, seconds_sweep, median of {reps})\n")
        print("| case | work (M updates) | sweep s | s per M updates |")
        print("|---|---|---|---|")
        for label, args in cases:
            med, h = alternate({label: (new, args + ["--threads", "2"])}, reps,
                               lambda w, u, s: (s["seconds_sweep"], s["width"] * s["height"] * s["slabs"] * s["lights"]))
            secs, work = med[label]
            print(f"| {label} | {work / 1e6:.0f} | {secs:.3f} | {secs / (work / 1e6) * 1e3:.2f} ms |")
        print()

    scaling("Time against slabs (default scene, 256²)",
            [(f"{n} slabs", ["--size", "256x256", "--slabs", str(n)]) for n in [128, 256, 512, 1024]])
    scaling("Time against pixels (default scene, 256 slabs)",
            [(f"{n}²", ["--size", f"{n}x{n}", "--slabs", "256"]) for n in [256, 512, 1024]])
    scaling("Time against lights (default scene's lights repeated, 256², 256 slabs)",
            [(f"{n} lights", lights_scene(n) + small) for n in [1, 2, 4, 8]])


def finish(bad):
    """Exits non-zero if some pair wrote different images."""
    if bad:
        print("MISMATCH:\n" + "\n".join(bad))
        sys.exit(1)


if __name__ == "__main__":
    main()
