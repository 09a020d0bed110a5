//! Exact collinearity: Shewchuk-style expansion arithmetic, no error from rounding.

/// `a + b` as an exact pair `(sum, error)`.
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let err = (a - (s - bb)) + (b - bb);
    (s, err)
}

/// Veltkamp's split of `a` into two 26-bit halves whose products are exact.
pub(crate) fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// `a * b` as an exact pair `(product, error)` by Dekker's algorithm: plain multiplications
/// only (the project uses no fused multiply-add anywhere); exact unless it under/overflows.
pub(crate) fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let err = al * bl - (((p - ah * bh) - al * bh) - ah * bl);
    (p, err)
}

/// True iff the 2D orientation determinant of `a, b, c` is exactly zero.
pub(crate) fn orient2d_is_zero(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let (l1, l2) = (b[0] - a[0], c[1] - a[1]);
    let (r1, r2) = (b[1] - a[1], c[0] - a[0]);
    let (l, r) = (l1 * l2, r1 * r2);
    let det = l - r;
    // Shewchuk's ccwerrboundA: beyond it, the floating-point sign is certain.
    let eps = f64::EPSILON * 0.5;
    let bound = (3.0 + 16.0 * eps) * eps * (l.abs() + r.abs());
    if det.abs() > bound {
        return false;
    }
    // Exact: each difference is an exact two-term expansion, products of terms are exact pairs.
    let d = |p: f64, q: f64| two_sum(p, -q);
    let (bx, bxe) = d(b[0], a[0]);
    let (cy, cye) = d(c[1], a[1]);
    let (by, bye) = d(b[1], a[1]);
    let (cx, cxe) = d(c[0], a[0]);
    let mut expansion: Vec<f64> = Vec::with_capacity(32);
    let mut add = |x: f64| {
        // Grow a nonoverlapping expansion (increasing magnitude), dropping zeros.
        let mut q = x;
        let mut out = Vec::with_capacity(expansion.len() + 1);
        for &e in &expansion {
            let (s, err) = two_sum(q, e);
            if err != 0.0 {
                out.push(err);
            }
            q = s;
        }
        if q != 0.0 {
            out.push(q);
        }
        expansion = out;
    };
    for (p, q, sign) in [
        (bx, cy, 1.0),
        (bx, cye, 1.0),
        (bxe, cy, 1.0),
        (bxe, cye, 1.0),
        (by, cx, -1.0),
        (by, cxe, -1.0),
        (bye, cx, -1.0),
        (bye, cxe, -1.0),
    ] {
        let (h, e) = two_product(p, q);
        add(sign * h);
        add(sign * e);
    }
    expansion.is_empty()
}
