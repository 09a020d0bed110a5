//! Convolution kernels: their names, their per-slab moments, and the per-light tap tables that
//! every path (scalar, SIMD, GPU) reads (DESIGN §2 "Kernels", §3 "tables computed once").
//!
//! A kernel is a gather: the light entering slab k at pixel p is
//! `Σ_taps w · I_{k-1}(p + offset)`, each tap read with bilinear interpolation. The offsets are
//! `−(μκ + o)` where `o` is a zero-mean sample of the kernel's pattern, so the light buffer's
//! impulse response moves by `+μκ` per slab and spreads by `Σκ` (DESIGN §2).
//!
//! Because every pixel shares the same sub-pixel offsets for a given phase, a tap is stored as an
//! integer offset plus four bilinear corner weights: no per-pixel `floor`, and the same table on
//! the GPU. All host maths here is f64; only the final weights are rounded to f32.

use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

/// Number of random phases per light for randomized kernels (a power of two: the phase is the
/// top `PHASE_BITS` bits of a hash).
pub const PHASE_BITS: u32 = 6;
/// `2^PHASE_BITS`.
pub const PHASES: usize = 1 << PHASE_BITS;
/// Largest `ellipseN` sample count.
pub const MAX_ELLIPSE_SAMPLES: u32 = 64;
/// Largest `gaussian:K` width.
pub const MAX_GAUSSIAN_WIDTH: u32 = 63;
/// Largest number of taps a single phase may have (bounds per-pixel work).
pub const MAX_TAPS_PER_PHASE: usize = 4096;
/// Tap weights below this (2^-56) are dropped (see `discretise`).
const MIN_WEIGHT: f64 = 1.0 / 72_057_594_037_927_936.0;

/// Which kernel family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelKind {
    /// N points equally spaced in arc length on an ellipse (paper §3.4).
    Ellipse(u32),
    /// Two fixed points, alternating between the principal axes from slab to slab.
    Dirac,
    /// A fixed, whitened Poisson-disk pattern of 8 or 16 points, randomly rotated.
    Poisson(u32),
    /// K×K discrete Gaussian weights.
    Gaussian(u32),
    /// Zhang & Crawfis's top-hat, widths carried from slab to slab.
    Box,
}

/// A kernel as named on the command line or in a scene file (`ellipse2`, `ellipse3:slab`, ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KernelSpec {
    /// Kernel family.
    pub kind: KernelKind,
    /// `:slab`: one random phase per (light, slab) instead of per (light, slab, pixel).
    pub per_slab_phase: bool,
}

impl Default for KernelSpec {
    fn default() -> Self {
        KernelSpec {
            kind: KernelKind::Ellipse(2),
            per_slab_phase: false,
        }
    }
}

impl fmt::Display for KernelSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            KernelKind::Ellipse(n) => write!(f, "ellipse{n}")?,
            KernelKind::Dirac => write!(f, "dirac")?,
            KernelKind::Poisson(n) => write!(f, "poisson{n}")?,
            KernelKind::Gaussian(k) => write!(f, "gaussian:{k}")?,
            KernelKind::Box => write!(f, "box")?,
        }
        if self.per_slab_phase {
            write!(f, ":slab")?;
        }
        Ok(())
    }
}

/// The message for an unknown kernel name.
const KERNEL_NAMES: &str = "expected one of ellipse2, ellipse3, ... ellipse64 (optionally with :slab, \
     e.g. ellipse2:slab), dirac, poisson8, poisson16, gaussian:K (K odd, 3 to 63), box";

impl FromStr for KernelSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("unknown kernel {s:?}: {KERNEL_NAMES}");
        let (base, per_slab_phase) = match s.strip_suffix(":slab") {
            Some(b) => (b, true),
            None => (s, false),
        };
        let kind = if let Some(n) = base.strip_prefix("ellipse") {
            let n: u32 = n.parse().map_err(|_| bad())?;
            if !(2..=MAX_ELLIPSE_SAMPLES).contains(&n) {
                return Err(bad());
            }
            KernelKind::Ellipse(n)
        } else if let Some(k) = base.strip_prefix("gaussian:") {
            let k: u32 = k.parse().map_err(|_| bad())?;
            if k.is_multiple_of(2) || !(3..=MAX_GAUSSIAN_WIDTH).contains(&k) {
                return Err(bad());
            }
            KernelKind::Gaussian(k)
        } else {
            match base {
                "dirac" => KernelKind::Dirac,
                "poisson8" => KernelKind::Poisson(8),
                "poisson16" => KernelKind::Poisson(16),
                "box" => KernelKind::Box,
                _ => return Err(bad()),
            }
        };
        if per_slab_phase && !matches!(kind, KernelKind::Ellipse(_)) {
            return Err(format!(
                "{s:?}: only ellipseN kernels take :slab; {KERNEL_NAMES}"
            ));
        }
        Ok(KernelSpec {
            kind,
            per_slab_phase,
        })
    }
}

/// A light's per-slab kernel moments in pixel units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelMoments {
    /// μκ: where the impulse response moves per slab (pixels).
    pub mean: [f64; 2],
    /// Σκ: how much it spreads per slab (pixels², symmetric 2×2, row-major).
    pub cov: [[f64; 2]; 2],
}

impl KernelMoments {
    /// DESIGN §2: μκ = −e·μl, Σκ = d1·e·R(α)·diag(σx², σy²)·R(α)ᵀ, divided by px and px².
    pub fn for_light(
        tilt_deg: [f64; 2],
        variance: [f64; 2],
        rotation_deg: f64,
        slab_distance: f64,
        optimal_distance: f64,
        pixel_size: f64,
    ) -> KernelMoments {
        let mu_l = [
            tilt_deg[0].to_radians().tan(),
            tilt_deg[1].to_radians().tan(),
        ];
        let mean = [
            -slab_distance * mu_l[0] / pixel_size,
            -slab_distance * mu_l[1] / pixel_size,
        ];
        let (s, c) = rotation_deg.to_radians().sin_cos();
        let k = optimal_distance * slab_distance / (pixel_size * pixel_size);
        let (vx, vy) = (variance[0] * k, variance[1] * k);
        let cov = [
            [c * c * vx + s * s * vy, c * s * (vx - vy)],
            [c * s * (vx - vy), s * s * vx + c * c * vy],
        ];
        KernelMoments { mean, cov }
    }
}

/// Eigen-decomposition of a symmetric 2×2 matrix: (λ1 ≥ λ2, unit eigenvector of λ1).
pub fn eigen2(cov: [[f64; 2]; 2]) -> (f64, f64, [f64; 2]) {
    let (a, b, d) = (cov[0][0], cov[0][1], cov[1][1]);
    let half_trace = 0.5 * (a + d);
    let disc = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let l1 = half_trace + disc;
    let l2 = (half_trace - disc).max(0.0);
    let angle = 0.5 * (2.0 * b).atan2(a - d);
    (l1.max(0.0), l2, [angle.cos(), angle.sin()])
}

/// One gather tap: an integer offset and the bilinear weights of the four pixels
/// (dx, dy), (dx+1, dy), (dx, dy+1), (dx+1, dy+1), already multiplied by the tap's weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tap {
    /// Integer x offset of the top-left pixel read.
    pub dx: i32,
    /// Integer y offset of the top-left pixel read.
    pub dy: i32,
    /// Weights of the four corners, in the order above.
    pub w: [f32; 4],
}

/// How a slab picks its phase (its row of taps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhaseMode {
    /// A hash of (seed, light, slab, x, y): a different phase per pixel.
    PerPixel,
    /// A hash of (seed, light, slab): one phase per slab, shared by all pixels.
    PerSlab,
    /// `KernelTable::slab_phase[slab]`: a fixed schedule.
    Schedule,
}

/// A light's tap table: built once on the host, read by every path and uploaded to the GPU.
#[derive(Clone, Debug, PartialEq)]
pub struct KernelTable {
    /// Number of phases (rows); a power of two for hashed modes.
    pub phase_count: u32,
    /// Taps per phase (columns).
    pub taps_per_phase: u32,
    /// The taps, phase-major: phase p's taps are `taps[p*taps_per_phase ..][..taps_per_phase]`.
    pub taps: Vec<Tap>,
    /// How a slab picks its phase.
    pub phase_mode: PhaseMode,
    /// For `PhaseMode::Schedule`: the phase of each slab.
    pub slab_phase: Vec<u32>,
    /// Whole-pixel shift added to every tap in each slab (all zero unless a mean carry is used).
    pub slab_shift: Vec<[i32; 2]>,
}

impl KernelTable {
    /// The taps of one phase.
    pub fn phase(&self, p: u32) -> &[Tap] {
        let n = self.taps_per_phase as usize;
        &self.taps[p as usize * n..][..n]
    }

    /// log2 of the phase count for hashed modes (0 for a single phase).
    pub fn phase_bits(&self) -> u32 {
        self.phase_count.trailing_zeros()
    }

    /// Mean and covariance (pixels) of the gather's impulse response per slab, including the
    /// variance the bilinear reads add and the slab's whole-pixel shift, averaged over the slabs.
    /// A slab's response is its phases' mixture (the expected kernel of a randomized one); the
    /// slabs' responses are convolved, so after n slabs the iterated kernel has n times these
    /// moments. Used by tests and reports.
    pub fn response_moments(&self) -> KernelMoments {
        let slabs = self.slab_shift.len().max(1);
        let mut mean = [0.0f64; 2];
        let mut cov = [[0.0f64; 2]; 2];
        for k in 0..slabs {
            let shift = self.slab_shift.get(k).copied().unwrap_or([0, 0]);
            let phases: Vec<u32> = match self.phase_mode {
                PhaseMode::Schedule => vec![self.slab_phase.get(k).copied().unwrap_or(0)],
                _ => (0..self.phase_count).collect(),
            };
            let mut m = [0.0f64; 2];
            let mut s = [[0.0f64; 2]; 2];
            let mut total = 0.0;
            for &p in &phases {
                for t in self.phase(p) {
                    for (c, w) in t.w.iter().enumerate() {
                        let w = f64::from(*w);
                        // The response moves opposite to the read offset.
                        let x = -f64::from(t.dx + shift[0] + (c as i32 & 1));
                        let y = -f64::from(t.dy + shift[1] + (c as i32 >> 1));
                        m[0] += w * x;
                        m[1] += w * y;
                        s[0][0] += w * x * x;
                        s[0][1] += w * x * y;
                        s[1][1] += w * y * y;
                        total += w;
                    }
                }
            }
            let (mx, my) = (m[0] / total, m[1] / total);
            mean[0] += mx;
            mean[1] += my;
            cov[0][0] += s[0][0] / total - mx * mx;
            cov[0][1] += s[0][1] / total - mx * my;
            cov[1][1] += s[1][1] / total - my * my;
        }
        let n = slabs as f64;
        KernelMoments {
            mean: [mean[0] / n, mean[1] / n],
            cov: [
                [cov[0][0] / n, cov[0][1] / n],
                [cov[0][1] / n, cov[1][1] / n],
            ],
        }
    }
}

/// A sample pattern before bilinear discretisation: per phase, (offset x, offset y, weight).
type Pattern = Vec<Vec<([f64; 2], f64)>>;

/// Largest half-width (taps per side) of one axis of the `box` kernel before it is strided.
const MAX_BOX_HALF: u32 = 24;

/// Maps principal-frame coordinates (along e1, along e2 = e1 rotated 90°) to pixel offsets.
fn principal_to_pixels(e1: [f64; 2]) -> impl Fn(f64, f64) -> [f64; 2] {
    let e2 = [-e1[1], e1[0]];
    move |u, v| [u * e1[0] + v * e2[0], u * e1[1] + v * e2[1]]
}

/// `dirac`: two fixed points ±√(2λ) along one principal axis, alternating axes from slab to slab
/// (two slabs together have covariance 2Σκ: a non-randomized pattern, as in the paper's fig. 3).
fn dirac_pattern(l1: f64, l2: f64, e1: [f64; 2]) -> Pattern {
    let to_pixels = principal_to_pixels(e1);
    let a = (2.0 * l1).sqrt();
    let b = (2.0 * l2).sqrt();
    vec![
        vec![(to_pixels(a, 0.0), 0.5), (to_pixels(-a, 0.0), 0.5)],
        vec![(to_pixels(0.0, b), 0.5), (to_pixels(0.0, -b), 0.5)],
    ]
}

/// Builds a light's tap table for `slabs` slabs.
///
/// `compensate`: shape the pattern so that pattern + bilinear covariance equals Σκ, and where Σκ
/// is smaller than what a bilinear read of the mean's fraction adds, carry the mean in whole
/// pixels from slab to slab (see docs/accuracy.md).
pub fn build_table(
    spec: KernelSpec,
    moments: &KernelMoments,
    slabs: u32,
    compensate: bool,
) -> KernelTable {
    let slabs_us = slabs as usize;
    let carry = compensate && carry_mean(moments);
    let (pattern_mean, slab_shift) = if carry {
        let step = |i: usize| {
            [
                (moments.mean[0] * i as f64).round() as i64,
                (moments.mean[1] * i as f64).round() as i64,
            ]
        };
        let shifts = (0..slabs_us)
            .map(|k| {
                let (a, b) = (step(k), step(k + 1));
                // A read offset of −move makes the response move by +move.
                [-(b[0] - a[0]) as i32, -(b[1] - a[1]) as i32]
            })
            .collect();
        ([0.0, 0.0], shifts)
    } else {
        (moments.mean, vec![[0, 0]; slabs_us])
    };

    if let KernelKind::Box = spec.kind {
        let (l1, l2, e1) = eigen2(moments.cov);
        let (pat, sched) = box_schedule(l1, l2, e1, slabs, compensate && !carry, pattern_mean);
        return discretise(&pat, pattern_mean, PhaseMode::Schedule, sched, slab_shift);
    }
    let make = |cov: [[f64; 2]; 2]| -> Pattern {
        let (l1, l2, e1) = eigen2(cov);
        match spec.kind {
            KernelKind::Ellipse(n) => ellipse_pattern(n, l1, l2, e1),
            KernelKind::Dirac => dirac_pattern(l1, l2, e1),
            KernelKind::Poisson(n) => poisson_pattern(n, l1, l2, e1),
            KernelKind::Gaussian(k) => vec![gaussian_taps(k, l1, l2, e1)],
            KernelKind::Box => unreachable!("handled above"),
        }
    };
    // With the mean carried in whole pixels the pattern is read around 0, and its own taps still
    // fall between pixels: compensate around mean 0 in that case too.
    let pattern = if compensate {
        compensated_pattern(&make, pattern_mean, moments.cov)
    } else {
        make(moments.cov)
    };
    let (mode, sched) = match spec.kind {
        KernelKind::Ellipse(_) if spec.per_slab_phase => (PhaseMode::PerSlab, Vec::new()),
        KernelKind::Ellipse(_) | KernelKind::Poisson(_) => (PhaseMode::PerPixel, Vec::new()),
        KernelKind::Dirac => (PhaseMode::Schedule, (0..slabs).map(|k| k & 1).collect()),
        _ => (PhaseMode::Schedule, vec![0; slabs_us]),
    };
    discretise(&pattern, pattern_mean, mode, sched, slab_shift)
}

/// Whether the light is narrow enough that its mean is carried in whole pixels: when Σκ is
/// below what a bilinear read of the mean's fraction would add on some axis.
fn carry_mean(m: &KernelMoments) -> bool {
    let bilinear = |v: f64| {
        let f = v - v.floor();
        f * (1.0 - f)
    };
    m.cov[0][0] < bilinear(m.mean[0]) || m.cov[1][1] < bilinear(m.mean[1])
}

/// Outer iterations of [`compensated_pattern`] (each builds one pattern).
const MAX_SHAPE_ITERATIONS: usize = 12;

/// A pattern whose taps, read bilinearly around `mean`, give the response covariance `target`:
/// pattern covariance plus the variance f(1−f) per axis that the reads add (DESIGN §2).
///
/// A bilinear read spreads a tap along the two pixel axes independently, so the response's x
/// variance depends only on the taps' x offsets. The pattern built for a shape covariance C (with
/// C's diagonal = Σκ's) is therefore scaled along x by s_x and along y by s_y, each found by
/// bisection on [0, 1]. Along one axis the response variance is T(s) = Σ w·L(r) − m² with
/// r = m + s·o the read positions and L the piecewise-linear interpolant of r² at the integers
/// (a read at r puts weights 1 − f and f on ⌊r⌋ and ⌊r⌋ + 1: second moment r² + f(1 − f)). L is
/// convex, so T is convex in s, and its slope at s = 0 is ≥ 0 because the union of a pattern's
/// phases is zero-mean: T is non-decreasing on [0, 1], from T(0) = f(1 − f) of the mean's
/// fraction (≤ Σκ, else `build_table` carries the mean and m = 0, T(0) = 0) to
/// T(1) = C + bilinear ≥ Σκ. Bisection converges for every Σκ (the damped fixed point this
/// replaces diverged below Σκ ≈ 0.05 px² per slab).
///
/// Scaling multiplies the correlation by s_x·s_y, so C's off-diagonal is set to Σκ_xy/(s_x·s_y)
/// and the pattern rebuilt; the scales depend only weakly on C's correlation and this settles in a
/// few rounds. Bilinear reads add no correlation: where the compensated pattern is too narrow to
/// carry Σκ_xy (C would stop being positive semi-definite; only when Σκ's smaller eigenvalue is
/// below 1/4 px²), C is capped at correlation ±1 and the response keeps less than Σκ_xy.
fn compensated_pattern(
    make: &dyn Fn([[f64; 2]; 2]) -> Pattern,
    mean: [f64; 2],
    target: [[f64; 2]; 2],
) -> Pattern {
    let scales = |pattern: &Pattern| {
        [
            axis_scale(pattern, mean[0], 0, target[0][0]),
            axis_scale(pattern, mean[1], 1, target[1][1]),
        ]
    };
    let mut shape = target;
    let mut pattern = make(shape);
    let mut scale = scales(&pattern);
    for _ in 1..MAX_SHAPE_ITERATIONS {
        let both = scale[0] * scale[1];
        if target[0][1] == 0.0 || both <= 0.0 {
            break;
        }
        let limit = (shape[0][0] * shape[1][1]).sqrt();
        let want = (target[0][1] / both).clamp(-limit, limit);
        if (want - shape[0][1]).abs() <= 1e-12 * limit {
            break;
        }
        shape[0][1] = want;
        shape[1][0] = want;
        pattern = make(shape);
        scale = scales(&pattern);
    }
    pattern
        .into_iter()
        .map(|phase| {
            phase
                .into_iter()
                .map(|(o, w)| ([o[0] * scale[0], o[1] * scale[1]], w))
                .collect()
        })
        .collect()
}

/// The scale s ∈ [0, 1] of the pattern's offsets along `axis` at which the response variance
/// along that axis equals `target` (see [`compensated_pattern`]: non-decreasing in s), by
/// bisection; 0 or 1 where `target` is out of reach.
fn axis_scale(pattern: &Pattern, mean: f64, axis: usize, target: f64) -> f64 {
    let variance = |s: f64| response_variance(pattern, mean, axis, s);
    if variance(1.0) <= target {
        return 1.0;
    }
    if variance(0.0) >= target {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    // 60 halvings: an interval of 2^-60, below f64's resolution of s near 1.
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if variance(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Variance along `axis` of the response of a pattern (offsets scaled by `s`) read bilinearly
/// around `mean`: a read at r = −(mean + s·o) has second moment r² + f(1 − f), f = r − ⌊r⌋.
fn response_variance(pattern: &Pattern, mean: f64, axis: usize, s: f64) -> f64 {
    let (mut total, mut first, mut second) = (0.0, 0.0, 0.0);
    for phase in pattern {
        for (o, w) in phase {
            let r = -(mean + s * o[axis]);
            let f = r - r.floor();
            total += w;
            first += w * r;
            second += w * (r * r + f * (1.0 - f));
        }
    }
    let m = first / total;
    second / total - m * m
}

/// Turns sample offsets into bilinear taps; rounds weights to f32 so that, summed in the
/// sweep's order, they give exactly 1.0 (a constant unoccluded buffer then never drifts).
fn discretise(
    pattern: &Pattern,
    mean: [f64; 2],
    phase_mode: PhaseMode,
    slab_phase: Vec<u32>,
    slab_shift: Vec<[i32; 2]>,
) -> KernelTable {
    let taps_per_phase = pattern.iter().map(Vec::len).max().unwrap_or(1).max(1);
    let mut taps = Vec::with_capacity(pattern.len() * taps_per_phase);
    for phase in pattern {
        let start = taps.len();
        let mut phase_taps: Vec<(f64, Tap)> = phase
            .iter()
            .map(|(o, wt)| {
                let rx = -(mean[0] + o[0]);
                let ry = -(mean[1] + o[1]);
                let (fx0, fy0) = (rx.floor(), ry.floor());
                let (fx, fy) = (rx - fx0, ry - fy0);
                let w = [
                    (1.0 - fx) * (1.0 - fy) * wt,
                    fx * (1.0 - fy) * wt,
                    (1.0 - fx) * fy * wt,
                    fx * fy * wt,
                ];
                let tap = Tap {
                    dx: fx0 as i32,
                    dy: fy0 as i32,
                    // Weights below 2^-56 are dropped: with light values ≥ FLUSH_BELOW (1e-20)
                    // every product stays above f32's smallest normal (1.2e-38).
                    w: w.map(|x| if x < MIN_WEIGHT { 0.0 } else { x as f32 }),
                };
                (o[0] * o[0] + o[1] * o[1], tap)
            })
            .collect();
        // The tap nearest the pattern's centre goes last: it absorbs the rounding of the weight
        // sum (see `normalise_exactly`), which then moves the mean least.
        let central = (0..phase_taps.len())
            .min_by(|&a, &b| phase_taps[a].0.total_cmp(&phase_taps[b].0))
            .unwrap_or(0);
        let last = phase_taps.remove(central);
        taps.extend(phase_taps.into_iter().map(|(_, t)| t));
        // Pad short phases with zero-weight taps (adding 0·v leaves the sum unchanged).
        while taps.len() - start < taps_per_phase - 1 {
            taps.push(Tap {
                dx: 0,
                dy: 0,
                w: [0.0; 4],
            });
        }
        taps.push(last.1);
        normalise_exactly(&mut taps[start..]);
    }
    KernelTable {
        phase_count: pattern.len() as u32,
        taps_per_phase: taps_per_phase as u32,
        taps,
        phase_mode,
        slab_phase,
        slab_shift,
    }
}

/// The f32 sum of a phase's weights in the sweep's order (tap by tap, corner by corner).
pub fn sequential_weight_sum(taps: &[Tap]) -> f32 {
    let mut acc = 0.0f32;
    for t in taps {
        for w in t.w {
            acc += w;
        }
    }
    acc
}

/// Sets the last weight in the sweep's summation order so that the sequential f32 sum is exactly
/// 1: with S the sum of all earlier terms, S + w steps by at most one ulp of w ≤ ulp(1) as w walks,
/// so some w rounds the sum to exactly 1.0.
fn normalise_exactly(taps: &mut [Tap]) {
    let last = taps.len() - 1;
    let before = {
        let mut acc = 0.0f32;
        for (i, t) in taps.iter().enumerate() {
            for (c, w) in t.w.iter().enumerate() {
                if i == last && c == 3 {
                    break;
                }
                acc += *w;
            }
        }
        acc
    };
    let mut w = (1.0 - f64::from(before)) as f32;
    for _ in 0..256 {
        let s = before + w;
        if s == 1.0 {
            break;
        }
        w = if s > 1.0 { w.next_down() } else { w.next_up() };
    }
    taps[last].w[3] = w;
}

/// Arc-length statistics of an ellipse with semi-axes (1, r): (∮x² ds, ∮y² ds, L), by the
/// midpoint rule in the angle parameter (the integrand is smooth and periodic: converges fast).
fn ellipse_second_moments(r: f64) -> (f64, f64, f64) {
    const STEPS: usize = 4096;
    let (mut sx, mut sy, mut len) = (0.0, 0.0, 0.0);
    for i in 0..STEPS {
        let t = (i as f64 + 0.5) * 2.0 * PI / STEPS as f64;
        let (s, c) = t.sin_cos();
        let ds = (s * s + r * r * c * c).sqrt();
        sx += c * c * ds;
        sy += r * r * s * s * ds;
        len += ds;
    }
    (sx / len, sy / len, len * 2.0 * PI / STEPS as f64)
}

/// The axis ratio r ∈ [0, 1] whose arc-length-uniform point set has Vy/Vx = `ratio` (≤ 1).
pub fn ellipse_ratio_for_variance_ratio(ratio: f64) -> f64 {
    if ratio <= 0.0 {
        return 0.0;
    }
    if ratio >= 1.0 {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let (vx, vy, _) = ellipse_second_moments(mid);
        if vy / vx < ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Points equally spaced in arc length on an ellipse with semi-axes (a, b), starting at
/// arc-length fraction `start` (of the whole circumference), `count` points.
#[cfg(test)]
fn ellipse_points(a: f64, b: f64, start: f64, count: usize) -> Vec<[f64; 2]> {
    ellipse_point_sets(a, b, &[start], count).remove(0)
}

/// [`ellipse_points`] for several start fractions, sharing one arc-length table (building the
/// table dominates: 8192 `sin_cos` per call).
fn ellipse_point_sets(a: f64, b: f64, starts: &[f64], count: usize) -> Vec<Vec<[f64; 2]>> {
    const STEPS: usize = 8192;
    // Cumulative arc length at angle samples, for inverting s(t).
    let mut cum = Vec::with_capacity(STEPS + 1);
    cum.push(0.0);
    let dt = 2.0 * PI / STEPS as f64;
    for i in 0..STEPS {
        let t = (i as f64 + 0.5) * dt;
        let (s, c) = t.sin_cos();
        let ds = (a * a * s * s + b * b * c * c).sqrt() * dt;
        cum.push(cum[i] + ds);
    }
    let total = cum[STEPS];
    let points_from = |start: f64| -> Vec<[f64; 2]> {
        (0..count)
            .map(|i| {
                let frac = (start + i as f64 / count as f64).fract();
                let target = frac * total;
                let t = if total <= 0.0 {
                    0.0
                } else {
                    let j = cum.partition_point(|&c| c <= target).clamp(1, STEPS);
                    let (c0, c1) = (cum[j - 1], cum[j]);
                    let u = if c1 > c0 {
                        (target - c0) / (c1 - c0)
                    } else {
                        0.0
                    };
                    (j as f64 - 1.0 + u) * dt
                };
                [a * t.cos(), b * t.sin()]
            })
            .collect()
    };
    starts.iter().map(|&s| points_from(s)).collect()
}

/// The `ellipseN` pattern: PHASES phases of N arc-length-equispaced points, scaled so that the
/// union of all phases has exactly variances (λ1, λ2) along the principal axes.
fn ellipse_pattern(n: u32, l1: f64, l2: f64, e1: [f64; 2]) -> Pattern {
    let to_pixels = principal_to_pixels(e1);
    let n = n as usize;
    if l1 <= 0.0 {
        return vec![vec![([0.0, 0.0], 1.0)]; PHASES];
    }
    let r = ellipse_ratio_for_variance_ratio(l2 / l1);
    let starts: Vec<f64> = (0..PHASES)
        .map(|p| p as f64 / (PHASES * n) as f64)
        .collect();
    let phases = ellipse_point_sets(1.0, r, &starts, n);
    let (mut sx, mut sy) = (0.0, 0.0);
    for pts in &phases {
        for q in pts {
            sx += q[0] * q[0];
            sy += q[1] * q[1];
        }
    }
    let count = (PHASES * n) as f64;
    let kx = (l1 / (sx / count)).sqrt();
    let ky = if sy > 0.0 {
        (l2 / (sy / count)).sqrt()
    } else {
        0.0
    };
    let w = 1.0 / n as f64;
    phases
        .into_iter()
        .map(|pts| {
            pts.into_iter()
                .map(|q| (to_pixels(q[0] * kx, q[1] * ky), w))
                .collect()
        })
        .collect()
}

/// A fixed Poisson-disk pattern of `n` points (deterministic dart throwing with the hash),
/// centred and whitened to identity covariance.
pub fn poisson_disk_whitened(n: u32) -> Vec<[f64; 2]> {
    let n = n as usize;
    let mut pts: Vec<[f64; 2]> = Vec::new();
    let mut radius = 2.0 / (n as f64).sqrt();
    let mut tries = 0u32;
    let mut counter = 0u32;
    while pts.len() < n {
        counter += 1;
        let u = f64::from(crate::hash::mix32(counter.wrapping_mul(2).wrapping_add(0x51)) >> 8)
            / 16_777_216.0;
        let v = f64::from(crate::hash::mix32(counter.wrapping_mul(2).wrapping_add(0x52)) >> 8)
            / 16_777_216.0;
        let p = [2.0 * u - 1.0, 2.0 * v - 1.0];
        if p[0] * p[0] + p[1] * p[1] > 1.0 {
            continue;
        }
        if pts
            .iter()
            .all(|q| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) >= radius * radius)
        {
            pts.push(p);
            tries = 0;
        } else {
            tries += 1;
            if tries > 1000 {
                radius *= 0.95;
                tries = 0;
            }
        }
    }
    let mean = pts
        .iter()
        .fold([0.0, 0.0], |m, p| [m[0] + p[0], m[1] + p[1]]);
    let mean = [mean[0] / n as f64, mean[1] / n as f64];
    for p in &mut pts {
        p[0] -= mean[0];
        p[1] -= mean[1];
    }
    let mut c = [[0.0; 2]; 2];
    for p in &pts {
        c[0][0] += p[0] * p[0] / n as f64;
        c[0][1] += p[0] * p[1] / n as f64;
        c[1][1] += p[1] * p[1] / n as f64;
    }
    c[1][0] = c[0][1];
    // C^{-1/2} via the eigen-decomposition.
    let (a, b, e) = eigen2(c);
    let f = [-e[1], e[0]];
    let (ia, ib) = (1.0 / a.sqrt(), 1.0 / b.sqrt());
    pts.iter()
        .map(|p| {
            let u = (p[0] * e[0] + p[1] * e[1]) * ia;
            let v = (p[0] * f[0] + p[1] * f[1]) * ib;
            [u * e[0] + v * f[0], u * e[1] + v * f[1]]
        })
        .collect()
}

/// The `poissonN` pattern: the whitened disk rotated by PHASES angles, shaped by Σκ^½.
fn poisson_pattern(n: u32, l1: f64, l2: f64, e1: [f64; 2]) -> Pattern {
    let to_pixels = principal_to_pixels(e1);
    let base = poisson_disk_whitened(n);
    let (s1, s2) = (l1.sqrt(), l2.sqrt());
    let w = 1.0 / f64::from(n);
    (0..PHASES)
        .map(|p| {
            let (s, c) = (2.0 * PI * p as f64 / PHASES as f64).sin_cos();
            base.iter()
                .map(|q| {
                    let (u, v) = (c * q[0] - s * q[1], s * q[0] + c * q[1]);
                    (to_pixels(u * s1, v * s2), w)
                })
                .collect()
        })
        .collect()
}

/// Per-axis variance at or below which `gaussian:K` uses the 3-point pattern (v/2, 1 − v, v/2).
const GAUSSIAN_THREE_POINT: f64 = 0.5;

/// `gaussian:K`: a K×K grid of unit-spaced taps in the principal frame, centred on the mean,
/// weighted by the Gaussian of variances (λ1, λ2), normalised to the exact target variance.
///
/// An axis of variance v ≤ 1/2 uses the 3-point pattern (v/2, 1 − v, v/2) at −1, 0, 1 instead:
/// variance exactly v, and a non-negative spectrum 1 − v + v·cos ω (no checkerboard when
/// iterated). The sampled Gaussian's ±1 weights e^(−1/2v) vanish as v → 0, so rescaling its
/// positions to the exact variance would move its outer taps arbitrarily far (by √(v/got)).
fn gaussian_taps(k: u32, l1: f64, l2: f64, e1: [f64; 2]) -> Vec<([f64; 2], f64)> {
    let to_pixels = principal_to_pixels(e1);
    let h = (k / 2) as i32;
    // 1D weights per axis, then rescaled positions so each axis has exactly its variance.
    let axis = |var: f64| -> Vec<(f64, f64)> {
        if var <= 0.0 {
            return vec![(0.0, 1.0)];
        }
        if var <= GAUSSIAN_THREE_POINT {
            return vec![(-1.0, 0.5 * var), (0.0, 1.0 - var), (1.0, 0.5 * var)];
        }
        let ws: Vec<f64> = (-h..=h)
            .map(|i| (-0.5 * f64::from(i * i) / var).exp())
            .collect();
        let sum: f64 = ws.iter().sum();
        let got: f64 = (-h..=h)
            .zip(&ws)
            .map(|(i, w)| f64::from(i * i) * w / sum)
            .sum();
        // var > 1/2: the ±1 weights are ≥ e^-1 of the centre's, so `got` > 0.
        let stretch = (var / got).sqrt();
        (-h..=h)
            .zip(ws)
            .map(|(i, w)| (f64::from(i) * stretch, w / sum))
            .collect()
    };
    let (ax, ay) = (axis(l1), axis(l2));
    let mut taps = Vec::new();
    for (v, wv) in &ay {
        for (u, wu) in &ax {
            let w = wu * wv;
            if w > 1e-12 {
                taps.push((to_pixels(*u, *v), w));
            }
        }
    }
    taps
}

/// `box`: a separable top-hat in the principal frame with integer half-widths chosen per slab
/// so that the accumulated variance tracks n·Σκ (Zhang & Crawfis's carry of fractional widths).
fn box_schedule(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_names_round_trip_and_bad_names_are_rejected() {
        for name in [
            "ellipse2",
            "ellipse3",
            "ellipse7:slab",
            "dirac",
            "poisson8",
            "poisson16",
            "gaussian:19",
            "box",
        ] {
            assert_eq!(name.parse::<KernelSpec>().unwrap().to_string(), name);
        }
        for bad in [
            "ellipse1",
            "ellipse",
            "gaussian:4",
            "gaussian:x",
            "box:slab",
            "blur",
            "",
        ] {
            assert!(bad.parse::<KernelSpec>().is_err(), "{bad}");
        }
    }

    #[test]
    fn moments_follow_design_formulas() {
        // Tilt 45° → μl = 1; e = 0.1, px = 0.05 → mean −2 px. Variance 0.5·d1·e/px² = 0.5·0.5·0.1/0.0025.
        let m = KernelMoments::for_light([45.0, 0.0], [0.5, 0.5], 0.0, 0.1, 0.5, 0.05);
        assert!((m.mean[0] + 2.0).abs() < 1e-12 && m.mean[1] == 0.0);
        assert!((m.cov[0][0] - 10.0).abs() < 1e-9 && (m.cov[1][1] - 10.0).abs() < 1e-9);
        // Rotation by 90° swaps the axes.
        let r = KernelMoments::for_light([0.0, 0.0], [1.0, 0.0], 90.0, 1.0, 1.0, 1.0);
        assert!(r.cov[0][0].abs() < 1e-12 && (r.cov[1][1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn ellipse_variance_ratio_matches_closed_form_limits() {
        // Circle: a uniform point on a circle of radius 1 has Var x = 1/2.
        let (vx, vy, len) = ellipse_second_moments(1.0);
        assert!((vx - 0.5).abs() < 1e-12 && (vy - 0.5).abs() < 1e-12);
        assert!((len - 2.0 * PI).abs() < 1e-9);
        // Segment [-1, 1] traversed uniformly: Var x = 1/3.
        let (vx, vy, _) = ellipse_second_moments(0.0);
        assert!((vx - 1.0 / 3.0).abs() < 1e-6 && vy == 0.0, "{vx}");
        for ratio in [1e-6, 0.01, 0.3, 0.9] {
            let r = ellipse_ratio_for_variance_ratio(ratio);
            let (vx, vy, _) = ellipse_second_moments(r);
            assert!((vy / vx - ratio).abs() < 1e-9 * ratio.max(1e-3), "{ratio}");
        }
    }

    #[test]
    fn ellipse_points_are_equally_spaced_in_arc_length() {
        let pts = ellipse_points(2.0, 0.5, 0.1, 16);
        let mut d: Vec<f64> = Vec::new();
        for i in 0..16 {
            // Chord lengths of equal arcs on this smooth curve differ only by curvature; compare
            // neighbouring arcs via a fine polyline instead: the arc between points i and i+1.
            let a = pts[i];
            let b = pts[(i + 1) % 16];
            let ta = a[1].atan2(a[0] / 4.0);
            let mut tb = b[1].atan2(b[0] / 4.0);
            if tb < ta {
                tb += 2.0 * PI;
            }
            let mut s = 0.0;
            let steps = 2000;
            for j in 0..steps {
                let t = ta + (tb - ta) * (j as f64 + 0.5) / steps as f64;
                s += (4.0 * t.sin().powi(2) + 0.25 * t.cos().powi(2)).sqrt() * (tb - ta)
                    / steps as f64;
            }
            d.push(s);
        }
        let mean = d.iter().sum::<f64>() / 16.0;
        assert!(d.iter().all(|x| (x - mean).abs() < 1e-3 * mean), "{d:?}");
    }

    fn check_table(spec: &str, m: KernelMoments, tol: f64) {
        let t = build_table(spec.parse().unwrap(), &m, 8, false);
        for p in 0..t.phase_count {
            assert_eq!(sequential_weight_sum(t.phase(p)), 1.0, "{spec} phase {p}");
        }
        let r = t.response_moments();
        // Without compensation the response has the pattern's covariance plus bilinear variance,
        // which is at most 1/4 per axis; the mean is exact.
        assert!((r.mean[0] - m.mean[0]).abs() < 1e-6, "{spec} {r:?}");
        assert!((r.mean[1] - m.mean[1]).abs() < 1e-6, "{spec} {r:?}");
        for i in 0..2 {
            let extra = r.cov[i][i] - m.cov[i][i];
            assert!(
                (-tol..=0.25 + tol).contains(&extra),
                "{spec} axis {i}: {r:?} vs {m:?}"
            );
        }
    }

    #[test]
    fn tables_have_exact_unit_weight_and_target_moments() {
        let cases = [
            KernelMoments::for_light([20.0, -10.0], [0.02, 0.005], 30.0, 0.01, 0.5, 0.005),
            KernelMoments::for_light([0.0, 0.0], [0.0, 0.0], 0.0, 0.01, 0.5, 0.005),
            KernelMoments::for_light([60.0, 0.0], [0.01, 0.0], 10.0, 0.01, 0.5, 0.005),
        ];
        for m in cases {
            for spec in [
                "ellipse2",
                "ellipse3",
                "ellipse5:slab",
                "dirac",
                "poisson8",
                "poisson16",
                "gaussian:19",
            ] {
                check_table(spec, m, 1e-3 * (1.0 + m.cov[0][0] + m.cov[1][1]));
            }
        }
    }

    #[test]
    fn poisson_pattern_is_white() {
        for n in [8, 16] {
            let p = poisson_disk_whitened(n);
            let (mut m, mut c) = ([0.0; 2], [0.0; 3]);
            for q in &p {
                m[0] += q[0];
                m[1] += q[1];
                c[0] += q[0] * q[0];
                c[1] += q[0] * q[1];
                c[2] += q[1] * q[1];
            }
            let k = f64::from(n);
            assert!(m[0].abs() < 1e-9 && m[1].abs() < 1e-9);
            assert!(
                (c[0] / k - 1.0).abs() < 1e-9
                    && (c[1] / k).abs() < 1e-9
                    && (c[2] / k - 1.0).abs() < 1e-9
            );
        }
    }

    /// Kernels whose compensated response must hit Σκ exactly (`box` has its own schedule).
    const COMPENSATED: [&str; 7] = [
        "ellipse2",
        "ellipse3",
        "ellipse5:slab",
        "dirac",
        "poisson8",
        "poisson16",
        "gaussian:19",
    ];

    /// The bound on a response moment's error that rounding the weights to f32 allows: each of a
    /// phase's N corner weights is off by at most ε/2 relative, and the last one absorbs the f32
    /// sum's rounding (at most N·ε/2 absolute), so the weight misplaced is ≤ N·ε and it sits at
    /// most R px from the mean: the variance moves by ≤ N·ε·R².
    fn rounding_bound(t: &KernelTable, mean: [f64; 2]) -> f64 {
        let shift = t.slab_shift.first().copied().unwrap_or([0, 0]);
        let mut r2: f64 = 1.0;
        for tap in &t.taps {
            for (c, w) in tap.w.iter().enumerate() {
                if *w != 0.0 {
                    let x = -f64::from(tap.dx + shift[0] + (c as i32 & 1));
                    let y = -f64::from(tap.dy + shift[1] + (c as i32 >> 1));
                    // Carried tables: the slab's mean is within 1 px of μκ.
                    let d = (x - mean[0]).abs().max((y - mean[1]).abs()) + 1.0;
                    r2 = r2.max(2.0 * d * d);
                }
            }
        }
        4.0 * f64::from(t.taps_per_phase) * f64::from(f32::EPSILON) * r2
    }

    /// Σκ = R(α) diag(a, b) R(α)ᵀ.
    fn rotated(a: f64, b: f64, deg: f64) -> [[f64; 2]; 2] {
        let (s, c) = deg.to_radians().sin_cos();
        [
            [c * c * a + s * s * b, c * s * (a - b)],
            [c * s * (a - b), s * s * a + c * c * b],
        ]
    }

    /// Builds a compensated table and checks the iterated moments: after n slabs the variance is
    /// n·Σκ per axis (within the rounding bound) and the mean n·μκ (carried: within ½ px, the
    /// rounding of n·μκ). Returns the table and its per-slab response.
    fn compensated(spec: &str, m: KernelMoments) -> (KernelTable, KernelMoments, f64) {
        const SLABS: u32 = 8;
        let t = build_table(spec.parse().unwrap(), &m, SLABS, true);
        for p in 0..t.phase_count {
            assert_eq!(sequential_weight_sum(t.phase(p)), 1.0, "{spec} phase {p}");
        }
        let r = t.response_moments();
        let tol = rounding_bound(&t, m.mean);
        let carried = t.slab_shift.iter().any(|s| *s != [0, 0]);
        let n = f64::from(SLABS);
        for ax in 0..2 {
            let (got, want) = (n * r.mean[ax], n * m.mean[ax]);
            let bound = if carried { 0.5 + 1e-9 } else { n * tol };
            assert!(
                (got - want).abs() <= bound,
                "{spec} {m:?}: iterated mean {got} vs {want} (carried {carried})"
            );
            assert!(
                (r.cov[ax][ax] - m.cov[ax][ax]).abs() <= tol,
                "{spec} {m:?}: axis {ax} variance {} vs {} (bound {tol:e}, carried {carried})",
                r.cov[ax][ax],
                m.cov[ax][ax]
            );
        }
        (t, r, tol)
    }

    #[test]
    fn compensated_response_variance_is_sigma_kappa_from_a_thousandth_to_a_hundred_px2() {
        // Means with a fractional part (μκ at tilts 20° and −10°, a half pixel, 2.37 px) and an
        // integer one; Σκ below f(1−f) of the fraction carries the mean, above it does not.
        let means = [[-0.364, 0.176], [0.5, -0.5], [-2.373, 0.0], [-1.0, 2.0]];
        let variances = [
            0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.25, 0.5, 1.0, 3.0, 10.0, 30.0, 100.0,
        ];
        let mut carried = 0;
        for spec in COMPENSATED {
            for mean in means {
                for v in variances {
                    for cov in [[[v, 0.0], [0.0, v]], [[v, 0.0], [0.0, 4.0 * v]]] {
                        let (t, _, _) = compensated(spec, KernelMoments { mean, cov });
                        carried += usize::from(t.slab_shift.iter().any(|s| *s != [0, 0]));
                    }
                }
            }
        }
        assert!(carried > 0, "some cases must carry the mean");
    }

    #[test]
    fn compensated_response_keeps_the_correlation_when_sigma_kappa_allows_it() {
        // Σκ − I/4 positive semi-definite: P = Σκ − diag(bilinear) ⪰ 0 exists (reads add at most
        // 1/4 px² per axis), so the whole covariance is reached.
        let mean = [-0.364, 0.176];
        for (a, b, deg) in [
            (0.25, 2.0, 65.0),
            (0.3, 2.0, 30.0),
            (1.0, 10.0, 45.0),
            (5.0, 50.0, 20.0),
        ] {
            let cov = rotated(a, b, deg);
            for spec in COMPENSATED {
                let (_, r, tol) = compensated(spec, KernelMoments { mean, cov });
                assert!(
                    (r.cov[0][1] - cov[0][1]).abs() <= tol,
                    "{spec} ({a}, {b}, {deg}°): covariance {} vs {}",
                    r.cov[0][1],
                    cov[0][1]
                );
            }
        }
        // Narrower rotated lights: the diagonal is still exact (checked in `compensated`) and
        // the correlation is never exaggerated or flipped.
        for (a, b, deg) in [(0.01, 0.2, 45.0), (0.001, 1.0, 30.0), (0.05, 0.1, 60.0)] {
            let cov = rotated(a, b, deg);
            for spec in COMPENSATED {
                let (_, r, tol) = compensated(spec, KernelMoments { mean, cov });
                assert!(
                    r.cov[0][1] * cov[0][1] >= -tol && r.cov[0][1].abs() <= cov[0][1].abs() + tol,
                    "{spec} ({a}, {b}, {deg}°): covariance {} vs {}",
                    r.cov[0][1],
                    cov[0][1]
                );
            }
        }
    }

    #[test]
    fn carried_mean_compensates_the_pattern_around_zero() {
        // Σκ = 0.05 px² < f(1−f) = 0.24 of μκ = −0.6: the mean is carried. The pattern is read
        // around 0, where its own taps add bilinear variance: uncompensated, ellipse2's two points
        // at ±√(2·0.05)·(cos, sin) add E|x|·(1 − |x|) ≈ 0.18 px² per axis (+360 %).
        let m = KernelMoments {
            mean: [-0.6, 0.3],
            cov: [[0.05, 0.0], [0.0, 0.05]],
        };
        let (t, _, _) = compensated("ellipse2", m);
        assert!(
            t.slab_shift.iter().any(|s| *s != [0, 0]),
            "the mean is carried"
        );
        // Over 8 slabs the shifts add up to round(8·μκ) = (−5, 2) (read offsets are −moves).
        let total = t
            .slab_shift
            .iter()
            .fold([0, 0], |a, s| [a[0] - s[0], a[1] - s[1]]);
        assert_eq!(total, [-5, 2]);
    }

    #[test]
    fn gaussian_taps_of_small_variance_are_three_points() {
        let var_x =
            |taps: &[([f64; 2], f64)]| taps.iter().map(|(o, w)| w * o[0] * o[0]).sum::<f64>();
        for v in [1e-9, 1e-3, 0.05, 0.25, 0.5] {
            // Axis-aligned, y variance 0: one row of (v/2, 1 − v, v/2) at −1, 0, 1.
            let taps = gaussian_taps(19, v, 0.0, [1.0, 0.0]);
            let mut xs: Vec<(f64, f64)> = taps.iter().map(|(o, w)| (o[0], *w)).collect();
            xs.sort_by(|a, b| a.0.total_cmp(&b.0));
            assert_eq!(
                xs,
                vec![(-1.0, 0.5 * v), (0.0, 1.0 - v), (1.0, 0.5 * v)],
                "{v}"
            );
            assert!(taps.iter().all(|(o, _)| o[1] == 0.0));
            assert!((var_x(&taps) - v).abs() <= 1e-15, "{v}");
        }
        // Above 1/2 the sampled Gaussian: variance exact, positions i·√(v/got). By Poisson
        // summation the integer-sampled Gaussian's variance is v·(1 − O(e^(−2π²v))): got is
        // within 1e-4 of v for v ≥ 1/2 (and the ±9 truncation is > 4 std away for v ≤ 4), so
        // the stretch stays within 1 %.
        for v in [0.5001, 1.0, 4.0] {
            let taps = gaussian_taps(19, v, 0.0, [1.0, 0.0]);
            assert!((var_x(&taps) - v).abs() <= 1e-12 * v, "{v}");
            let stretch = taps
                .iter()
                .map(|(o, _)| o[0])
                .filter(|x| *x > 0.0)
                .fold(f64::INFINITY, f64::min);
            assert!((stretch - 1.0).abs() <= 0.01, "{v}: stretch {stretch}");
        }
        // The case the old stretch broke: Σκ = 0.25 px², μκ = −0.364 (pattern variance ≈ 0.02):
        // every read stays within |μκ| + 1 px (scale ≤ 1 of taps at ≤ 1 px, plus the bilinear
        // neighbour).
        let m = KernelMoments {
            mean: [-0.364, 0.176],
            cov: [[0.25, 0.0], [0.0, 0.25]],
        };
        let (t, _, _) = compensated("gaussian:19", m);
        for tap in t.taps.iter().filter(|t| t.w != [0.0; 4]) {
            assert!(
                (-2..=1).contains(&tap.dx) && (-2..=1).contains(&tap.dy),
                "{tap:?}"
            );
        }
    }
}
