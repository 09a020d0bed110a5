//! `box`: Zhang & Crawfis's top-hat, widths carried from slab to slab.

use super::*;

/// Largest half-width (taps per side) of one axis of the `box` kernel before it is strided.
pub(crate) const MAX_BOX_HALF: u32 = 24;

/// `box`: a separable top-hat in the principal frame with integer half-widths chosen per slab
/// so that the accumulated variance tracks n·Σκ (Zhang & Crawfis's carry of fractional widths).
pub(crate) fn box_schedule(
    l1: f64,
    l2: f64,
    e1: [f64; 2],
    slabs: u32,
    compensate: bool,
    mean: [f64; 2],
) -> (Pattern, Vec<u32>) {
    let to_pixels = principal_to_pixels(e1);
    // Variance of a discrete top-hat of 2h+1 unit-spaced taps: h(h+1)/3.
    let var_of = |h: u32| f64::from(h) * f64::from(h + 1) / 3.0;
    // Compensation: bilinear reads of the mean's fraction add f(1−f) along each pixel axis to
    // every tap (exactly so for an axis-aligned box, whose taps are whole pixels apart); that
    // covariance diag(bx, by) projected on the box's principal axes e1, e2 is what each axis owes.
    let (interp1, interp2) = if compensate {
        let f = |v: f64| {
            let r = -v;
            let fr = r - r.floor();
            fr * (1.0 - fr)
        };
        let (bx, by) = (f(mean[0]), f(mean[1]));
        let (cx, cy) = (e1[0] * e1[0], e1[1] * e1[1]);
        (bx * cx + by * cy, bx * cy + by * cx)
    } else {
        (0.0, 0.0)
    };
    let schedule_axis = |var: f64, interp: f64| -> Vec<u32> {
        let mut acc = 0.0;
        (0..slabs)
            .map(|k| {
                let want = f64::from(k + 1) * (var - interp).max(0.0) - acc;
                // The half-width whose variance best fills what is owed.
                let mut h = 0u32;
                while var_of(h + 1) <= want + 0.5 * (var_of(h + 1) - var_of(h)) && h < 2000 {
                    h += 1;
                }
                acc += var_of(h);
                h
            })
            .collect()
    };
    let (hx, hy) = (schedule_axis(l1, interp1), schedule_axis(l2, interp2));
    let mut combos: Vec<(u32, u32)> = Vec::new();
    let mut sched = Vec::with_capacity(slabs as usize);
    for (a, b) in hx.iter().zip(&hy) {
        let key = (*a, *b);
        let idx = combos.iter().position(|c| *c == key).unwrap_or_else(|| {
            combos.push(key);
            combos.len() - 1
        });
        sched.push(idx as u32);
    }
    if combos.is_empty() {
        combos.push((0, 0));
    }
    // Wide boxes are sampled with a stride (at most 2·MAX_BOX_HALF+1 taps per axis) keeping the
    // variance: (2h+1) unit taps have h(h+1)/3; h' taps of stride s have s²·h'(h'+1)/3.
    let strided = |h: u32| -> (i32, f64) {
        if h <= MAX_BOX_HALF {
            return (h as i32, 1.0);
        }
        let s = (var_of(h) / var_of(MAX_BOX_HALF)).sqrt();
        (MAX_BOX_HALF as i32, s)
    };
    let pattern = combos
        .iter()
        .map(|&(a, b)| {
            let (ha, sa) = strided(a);
            let (hb, sb) = strided(b);
            let w = 1.0 / f64::from((2 * ha + 1) * (2 * hb + 1));
            let mut taps = Vec::new();
            for v in -hb..=hb {
                for u in -ha..=ha {
                    taps.push((to_pixels(f64::from(u) * sa, f64::from(v) * sb), w));
                }
            }
            taps
        })
        .collect();
    (pattern, sched)
}
