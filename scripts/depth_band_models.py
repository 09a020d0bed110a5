#!/usr/bin/env python3
"""How well could depth bands do? Issue 46's several-depth cases in a model (docs/accuracy.md §1c).

Each case of tests/accuracy/several_depths.rs (same blocks, wall, pixels, light variances) is
evaluated in the slope space of the light: a ray reaching the wall at x with slope k (x per unit
depth) hits a convex block iff k lies between the smallest and largest slope to its corners, so
what a block hides from a wall point is an interval of k, and the exact visibility of the Gaussian
light N(drift, var) is one minus the Gaussian mass of the union of those intervals (closed form,
no sampling). Against it, two ways to combine *ideal* depth bands (every band's own visibility
exact, as if each band's light buffer were blurred with exactly its depth's kernel):

- product: the light is the product of the bands' visibilities (the issue's design (b));
- strip:   each band keeps its blocked mass B and the first moment M of the blocked slopes, and
           is replaced by the one interval with that mass and moment; the light is one minus
           the mass of the union of those intervals (exact where each band is one edge or plate).

The fog block of the same test (κ = ln 10 per unit depth, 0.5 deep) is a continuum of depths:
its exact visibility E[exp(−κ·ℓ(k))] (ℓ the depth a ray spends inside) against the product of
the exact visibilities of n equal depth slices of it (ideal bands again) and against the strip
model reading each slice's removed light and its moment as an opaque set's, by Gauss–Legendre
quadrature split at the slices' corner slopes.

Prints, per case, the RMSE over the test's pixels (not hidden by a block, not fully lit).
Standard library only: `python3 scripts/depth_band_models.py`.
"""

from math import erf, exp, inf, log, pi, sqrt

SIZE, VIEW, WALL = 128, 4.0, 0.0
PX = VIEW / SIZE


def cdf(u):
    return 0.5 * (1.0 + erf(u / sqrt(2.0))) if abs(u) != inf else (1.0 if u > 0 else 0.0)


def pdf(u):
    return exp(-0.5 * u * u) / sqrt(2.0 * pi) if abs(u) != inf else 0.0


def plate(x0, x1, d):
    """An opaque plate 0.02 thick whose front face lies d in front of the wall."""
    return (x0, x1, WALL - d, WALL - d + 0.02)


def hidden_slopes(block, x):
    """The interval of slopes k whose ray through (x, WALL) crosses the block."""
    x0, x1, z0, z1 = block
    slopes = [(x - cx) / (WALL - cz) for cx in (x0, x1) for cz in (z0, z1)]
    return min(slopes), max(slopes)


def union(intervals):
    """Disjoint sorted union of intervals."""
    out = []
    for lo, hi in sorted(intervals):
        if out and lo <= out[-1][1]:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    return out


def mass(intervals):
    """Standard-normal mass of a disjoint union of intervals."""
    return sum(cdf(hi) - cdf(lo) for lo, hi in intervals)


def moment(intervals):
    """First moment ∫u·φ(u) over a disjoint union of intervals."""
    return sum(pdf(lo) - pdf(hi) for lo, hi in intervals)


def ppf(p):
    lo, hi = -40.0, 40.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cdf(mid) < p else (lo, mid)
    return 0.5 * (lo + hi)


def strip(b, m):
    """The interval [p, q] of standard-normal mass b and first moment m (clamped to the range
    such an interval can have: a half-line at either end)."""
    if b <= 1e-12:
        return None
    if b >= 1.0 - 1e-12:
        return (-inf, inf)

    def upper(p):
        return ppf(min(1.0, cdf(p) + b))

    def interval_moment(p):  # grows with p: −φ(q) for the lower half-line, φ(p) for the upper
        return pdf(p) - pdf(upper(p))

    lo, hi = -40.0, ppf(1.0 - b)
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if interval_moment(mid) < m else (lo, mid)
    p = 0.5 * (lo + hi)
    return (p, upper(p))


def visibilities(blocks, bands, x, drift, var):
    """Exact, product-of-bands and strip-model visibility at wall point x."""
    s = sqrt(var)
    to_u = lambda iv: ((iv[0] - drift) / s, (iv[1] - drift) / s)  # noqa: E731
    all_sets = union(to_u(hidden_slopes(blocks[i], x)) for band in bands for i in band)
    exact = 1.0 - mass(all_sets)
    product, strips = 1.0, []
    for band in bands:
        sets = union(to_u(hidden_slopes(blocks[i], x)) for i in band)
        b = mass(sets)
        product *= 1.0 - b
        iv = strip(b, moment(sets))
        if iv is not None:
            strips.append(iv)
    return exact, product, 1.0 - mass(union(strips))


def rmse(blocks, bands, lights):
    """RMSE of both models over the test's pixels; lights: (drift, var, rgb weight)."""
    channels = 3 if len(lights) > 1 else 1
    err = {"product": 0.0, "strip": 0.0}
    n = 0
    for i in range(SIZE):
        x = (i + 0.5) * PX - VIEW / 2.0
        if any(x > b[0] - PX and x < b[1] + PX for b in blocks):
            continue
        per_light = [visibilities(blocks, bands, x, d, v) for d, v, _ in lights]
        for c in range(channels):
            total = sum(l[2][c] for l in lights)
            exact, product, strip_v = (
                sum(l[2][c] * v[j] for l, v in zip(lights, per_light)) / total for j in range(3)
            )
            if exact > 1.0 - 1e-6:
                continue
            err["product"] += (product - exact) ** 2
            err["strip"] += (strip_v - exact) ** 2
            n += 1
    return {k: sqrt(v / n) for k, v in err.items()}


# 8-point Gauss–Legendre nodes and weights on [−1, 1] (as tests/accuracy/several_depths.rs).
GAUSS_LEGENDRE = [
    (-0.9602898564975362, 0.1012285362903763), (-0.7966664774136267, 0.2223810344533745),
    (-0.525532409916329, 0.3137066458778873), (-0.1834346424956498, 0.362683783378362),
    (0.1834346424956498, 0.362683783378362), (0.525532409916329, 0.3137066458778873),
    (0.7966664774136267, 0.2223810344533745), (0.9602898564975362, 0.1012285362903763),
]


def fog_visibility(block, kappa, x, var):
    """(E[exp(−κ·ℓ(k))], E[u·(1 − exp(−κ·ℓ(k)))]) over k = σu ~ N(0, var): the visibility and
    the first moment of the light the block removes; ℓ the depth the ray through (x, WALL) with
    slope k spends in the block; split at its corner slopes, pieces of at most σ/4."""
    x0, x1, z0, z1 = block
    s = sqrt(var)

    def inside(k):
        lo, hi = z0, z1
        if k != 0.0:  # the ray passes depth z at x − k·(WALL − z)
            za, zb = WALL - (x - x0) / k, WALL - (x - x1) / k
            lo, hi = max(lo, min(za, zb)), min(hi, max(za, zb))
        elif not x0 < x < x1:
            return 0.0
        return max(hi - lo, 0.0)

    cuts = sorted({-8.0, 8.0} | {u / s for u in hidden_slopes(block, x) if abs(u / s) < 8.0})
    total, removed_moment = 0.0, 0.0
    for lo, hi in zip(cuts, cuts[1:]):
        pieces = max(1, int((hi - lo) / 0.25 + 0.999))
        step = (hi - lo) / pieces
        for j in range(pieces):
            mid = lo + step * (j + 0.5)
            for node, weight in GAUSS_LEGENDRE:
                u = mid + 0.5 * step * node
                through = exp(-kappa * inside(s * u))
                total += 0.5 * step * weight * pdf(u) * through
                removed_moment += 0.5 * step * weight * pdf(u) * u * (1.0 - through)
    return total, removed_moment


def fog_rmse(block, kappa, slices):
    """RMSE of the product of `slices` equal depth slices' visibilities, and of the strip model
    reading each slice's removed light and its moment as an opaque set's (white light)."""
    x0, x1, z0, z1 = block
    sq, n = [0.0, 0.0], 0
    for i in range(SIZE):
        x = (i + 0.5) * PX - VIEW / 2.0
        if x0 - PX < x < x1 + PX:
            continue
        exact = fog_visibility(block, kappa, x, 0.01)[0]
        if exact > 1.0 - 1e-6:
            continue
        product, strips = 1.0, []
        for j in range(slices):
            za, zb = z0 + (z1 - z0) * j / slices, z0 + (z1 - z0) * (j + 1) / slices
            v, m = fog_visibility((x0, x1, za, zb), kappa, x, 0.01)
            product *= v
            iv = strip(1.0 - v, m)
            if iv is not None:
                strips.append(iv)
        sq[0] += (product - exact) ** 2
        sq[1] += (1.0 - mass(union(strips)) - exact) ** 2
        n += 1
    return sqrt(sq[0] / n), sqrt(sq[1] / n)


def main():
    half = lambda a, d: plate(a, a + 6.0, d)  # noqa: E731
    white = [(0.0, 0.01, (1.0, 1.0, 1.0))]
    # The rotated anisotropic light's x-marginal: cos²30°·0.02 + sin²30°·0.005.
    rotated = [(0.0, 0.75 * 0.02 + 0.25 * 0.005, (1.0, 1.0, 1.0))]
    coloured = [(0.0, 0.01, (1.0, 0.6, 0.3)), (0.0, 0.004, (0.3, 0.6, 1.0))]
    comb = [plate(-1.3 + 0.3 * i + 0.013, -1.3 + 0.3 * i + 0.163, (2.0, 1.0)[i % 2]) for i in range(9)]
    even, odd = [i for i in range(9) if i % 2 == 0], [i for i in range(9) if i % 2 == 1]
    two = [half(0.0, 4.0), half(-0.3, 1.0)]
    cases = [
        ("two half-planes at distances 4 and 1", two, [[0], [1]], white),
        ("the same, rotated anisotropic light", two, [[0], [1]], rotated),
        ("the same, two coloured lights", two, [[0], [1]], coloured),
        ("a slit between half-planes at 4 and 1", [half(0.3, 4.0), plate(-6.0, -0.1, 1.0)],
         [[0], [1]], white),
        ("a small plate at 2 over a larger plate at 1",
         [plate(-0.2, 0.2, 2.0), plate(-1.5, -0.6, 1.0)], [[0], [1]], white),
        ("a comb alternating between distances 2 and 1", comb, [even, odd], white),
    ]
    print(f"{'case':48} {'product':>8} {'strip':>8}")
    for name, blocks, bands, lights in cases:
        e = rmse(blocks, bands, lights)
        print(f"{name:48} {e['product']:8.4f} {e['strip']:8.4f}")
    fog = (-0.8, 0.4, WALL - 1.5, WALL - 1.0)
    print("a fog block (κ = ln 10, 0.5 deep) at distance 1.5 cut into n depth slices:")
    for slices in (1, 2, 4, 8, 32):
        product, strip_v = fog_rmse(fog, log(10.0), slices)
        print(f"  n = {slices:2}{'':38} {product:8.4f} {strip_v:8.4f}")


if __name__ == "__main__":
    main()
