#!/usr/bin/env python3
"""Per-stage times of two convshadow binaries, alternating them run by run.

    scripts/bench_stages.py OLD_BIN NEW_BIN [--reps N] [--scenes default,bunny,mri] [--threads T]

Each round runs OLD then NEW (NEW then OLD on odd rounds) on every scene with `--stats-json`
and reads the stage times the stats report (`seconds_ldi`: geometry and LDI, `seconds_plan`: the
plan's tables and its files, `seconds_sweep`, `seconds_total`). Prints per scene and stage the
medians and the median of the per-round ratios NEW/OLD (below 1: NEW is faster), and fails if
the two binaries wrote different `image_hash`es. Scenes other than `default` are
`scenes/NAME.toml`; the model and volume scenes need `../shared`.
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
STAGES = ["seconds_ldi", "seconds_plan", "seconds_sweep", "seconds_total"]


def run(binary, scene, threads, out):
    """One render; its stats JSON."""
    args = [binary, "render"]
    if scene != "default":
        args.append(str(ROOT / "scenes" / f"{scene}.toml"))
    stats = out / "stats.json"
    args += ["-o", str(out / "image.exr"), "--stats-json", str(stats), "--quiet",
             "--threads", str(threads)]
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    return json.loads(stats.read_text())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--scenes", default="default,bunny,mri")
    ap.add_argument("--threads", type=int, default=2)
    o = ap.parse_args()
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="bench-stages-"))
    status = 0
    print(f"| scene | stage | old median s | new median s | new/old (median of rounds) |")
    print("|---|---|---|---|---|")
    for scene in o.scenes.split(","):
        times = {"old": {s: [] for s in STAGES}, "new": {s: [] for s in STAGES}}
        hashes = {"old": set(), "new": set()}
        for r in range(o.reps):
            order = ["old", "new"] if r % 2 == 0 else ["new", "old"]
            for which in order:
                st = run(getattr(o, which), scene, o.threads, tmp)
                hashes[which].add(st["image_hash"])
                for s in STAGES:
                    times[which][s].append(st[s])
        if hashes["old"] != hashes["new"] or len(hashes["new"]) != 1:
            print(f"{scene}: image hashes differ: {hashes}", file=sys.stderr)
            status = 1
        for s in STAGES:
            old, new = times["old"][s], times["new"][s]
            ratios = [n / a for a, n in zip(old, new) if a > 0]
            ratio = statistics.median(ratios) if ratios else float("nan")
            print(f"| {scene} | {s[8:]} | {statistics.median(old):.4f} | "
                  f"{statistics.median(new):.4f} | {ratio:.3f} |")
    return status


if __name__ == "__main__":
    sys.exit(main())
