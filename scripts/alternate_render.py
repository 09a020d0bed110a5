#!/usr/bin/env python3
"""Two convshadow binaries alternated on one render: medians of user CPU time and of the sweep.

    scripts/alternate_render.py OLD NEW [REPS] [render arguments...]

Default render arguments: `--threads 1 --size 384x384 --slabs 256` (the default scene). Runs
alternate (ABBA…) so a shared machine's load falls on both alike; prints each binary's medians,
the image hashes it wrote (they must agree), new/old ratios of the medians, of the fastest runs
and of the 10th percentiles (a second view: the runs least slowed by other load), and the paired
ratios: each round's new/old sweep time (its two runs are adjacent, so slow drifts of the
machine's load cancel), their median and quartiles. For quick checks during speed work;
`scripts/bench_speed.py` makes the tables of docs/performance.md.
"""
import sys, subprocess, resource, json, statistics
bins = sys.argv[1:3]; reps = int(sys.argv[3]) if len(sys.argv) > 3 else 5
extra = sys.argv[4:] or ["--threads","1","--size","384x384","--slabs","256"]
vals = {b: [] for b in bins}; sweeps = {b: [] for b in bins}; hashes = {b:set() for b in bins}
for r in range(reps):
    for b in (bins if r % 2 == 0 else bins[::-1]):
        before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
        subprocess.run([b, "render", "-q", "-o", "/tmp/ab.png", "--stats-json", "/tmp/ab.json", *extra], check=True)
        vals[b].append(resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before)
        d = json.load(open("/tmp/ab.json")); sweeps[b].append(d["seconds_sweep"]); hashes[b].add(d["image_hash"])
m = {b: statistics.median(v) for b, v in vals.items()}
s = {b: statistics.median(v) for b, v in sweeps.items()}
for b in bins: print(f"{b}: user {m[b]:.3f} s  sweep {s[b]:.3f} s  hashes {hashes[b]}")
print(f"new/old user {m[bins[1]]/m[bins[0]]:.3f}  sweep {s[bins[1]]/s[bins[0]]:.3f}")
# The fastest runs: those least slowed by the machine's other load.
lo = {b: sorted(v) for b, v in sweeps.items()}
p10 = {b: v[len(v) // 10] for b, v in lo.items()}
print(f"new/old sweep by the fastest run {lo[bins[1]][0]/lo[bins[0]][0]:.3f}  by the 10th percentile {p10[bins[1]]/p10[bins[0]]:.3f}")
paired = sorted(n / o for o, n in zip(sweeps[bins[0]], sweeps[bins[1]]))
if len(paired) >= 2:
    q = statistics.quantiles(paired, n=4)
    print(f"paired new/old sweep: median {statistics.median(paired):.3f}  quartiles {q[0]:.3f}..{q[2]:.3f}  ({len(paired)} rounds)")
