#!/usr/bin/python3
"""Writes scenes/cloud.vdb, the gallery's OpenVDB cloud (scenes/cloud_vdb.toml), with OpenVDB's
own Python module (Debian's python3-openvdb: run it with /usr/bin/python3, whose module it is).

A fog volume (background 0): a cumulus-like union of spheres whose density falls off smoothly
towards each sphere's edge and is modulated by a few octaves of a deterministic value noise, on a
grid of 0.02-unit voxels (about 96 x 64 x 64 voxels active). Only voxels with density above 0.01
are set active, so the grid is sparse. Deterministic: the same file bytes' values every run (the
file's UUID differs).

    /usr/bin/python3 scripts/cloud_vdb.py [out.vdb]
"""
import math
import sys

import pyopenvdb as vdb

OUT = sys.argv[1] if len(sys.argv) > 1 else "scenes/cloud.vdb"
VOXEL = 0.02

# (centre x, y, z, radius) in world units: a flat-bottomed cumulus.
BLOBS = [
    (0.0, 0.0, 0.0, 0.55),
    (-0.5, -0.1, 0.05, 0.42),
    (0.52, -0.08, -0.05, 0.45),
    (0.15, 0.3, 0.1, 0.38),
    (-0.25, 0.25, -0.1, 0.33),
    (0.85, -0.2, 0.1, 0.3),
    (-0.85, -0.22, -0.05, 0.28),
]
FLOOR = -0.32  # densities fade out below this height (a flat base)


def hash3(i, j, k):
    h = (i * 73856093) ^ (j * 19349663) ^ (k * 83492791)
    h = (h ^ (h >> 13)) * 1274126177
    return ((h ^ (h >> 16)) & 0xFFFF) / 65535.0


def smooth(t):
    return t * t * (3.0 - 2.0 * t)


def value_noise(x, y, z):
    i, j, k = math.floor(x), math.floor(y), math.floor(z)
    fx, fy, fz = smooth(x - i), smooth(y - j), smooth(z - k)
    acc = 0.0
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                w = (fx if dx else 1 - fx) * (fy if dy else 1 - fy) * (fz if dz else 1 - fz)
                acc += w * hash3(i + dx, j + dy, k + dz)
    return acc


def fbm(x, y, z):
    total, amp, freq = 0.0, 0.5, 3.0
    for _ in range(4):
        total += amp * value_noise(x * freq, y * freq, z * freq)
        amp *= 0.5
        freq *= 2.0
    return total / 0.9375


def density(x, y, z):
    d = 0.0
    for cx, cy, cz, r in BLOBS:
        q = math.sqrt((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / r
        if q < 1.0:
            d = max(d, 1.0 - q * q)
    if d <= 0.0:
        return 0.0
    base = min(1.0, max(0.0, (y - FLOOR) / 0.12))
    n = fbm(x + 7.0, y + 3.0, z + 11.0)
    return max(0.0, min(1.0, (d * 1.6 - 0.55 + 0.9 * n) * base))


def main():
    grid = vdb.FloatGrid()
    grid.name = "density"
    grid.gridClass = vdb.GridClass.FOG_VOLUME
    grid.transform = vdb.createLinearTransform(voxelSize=VOXEL)
    acc = grid.getAccessor()
    lo = [min(b[a] - b[3] for b in BLOBS) for a in range(3)]
    hi = [max(b[a] + b[3] for b in BLOBS) for a in range(3)]
    rng = [range(math.floor(lo[a] / VOXEL), math.ceil(hi[a] / VOXEL) + 1) for a in range(3)]
    for k in rng[2]:
        for j in rng[1]:
            for i in rng[0]:
                v = density(i * VOXEL, j * VOXEL, k * VOXEL)
                if v > 0.01:
                    acc.setValueOn((i, j, k), v)
    vdb.write(OUT, grids=[grid])
    print(f"{OUT}: {grid.activeVoxelCount()} active voxels, {grid.leafCount()} leaves, "
          f"bbox {grid.evalActiveVoxelBoundingBox()}")


if __name__ == "__main__":
    main()
