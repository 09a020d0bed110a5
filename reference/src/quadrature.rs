//! Gauss–Legendre quadrature for the references' numerical integrals.

use std::sync::RwLock;

/// Gauss–Legendre nodes and weights on [−1, 1] for `n` points, computed once per process and
/// kept: the references evaluate their integrals per pixel, and finding the nodes (Newton on a
/// degree-n polynomial for each) costs far more than an integral.
pub fn gauss_legendre(n: usize) -> &'static [(f64, f64)] {
    static KEPT: RwLock<Vec<&'static [(f64, f64)]>> = RwLock::new(Vec::new());
    let find = |kept: &[&'static [(f64, f64)]]| kept.iter().copied().find(|t| t.len() == n);
    // A panic elsewhere while the lock was held cannot leave a wrong entry (a push is whole).
    if let Some(t) = find(&KEPT.read().unwrap_or_else(|p| p.into_inner())) {
        return t;
    }
    let mut kept = KEPT.write().unwrap_or_else(|p| p.into_inner());
    if let Some(t) = find(&kept) {
        return t;
    }
    let t: &'static [(f64, f64)] = Box::leak(nodes_by_newton(n).into_boxed_slice());
    kept.push(t);
    t
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the Legendre polynomial).
fn nodes_by_newton(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::gauss_legendre;

    #[test]
    fn sixteen_nodes_integrate_polynomials_to_degree_31() {
        let nodes = gauss_legendre(16);
        let w: f64 = nodes.iter().map(|&(_, w)| w).sum();
        assert!((w - 2.0).abs() < 1e-13);
        for d in [1, 7, 20, 31] {
            // ∫ x^d over [−1, 1]: 0 for odd d, 2/(d + 1) for even d.
            let exact = if d % 2 == 1 {
                0.0
            } else {
                2.0 / f64::from(d + 1)
            };
            let got: f64 = nodes.iter().map(|&(x, w)| w * x.powi(d)).sum();
            assert!((got - exact).abs() < 1e-13, "degree {d}");
        }
    }
}
