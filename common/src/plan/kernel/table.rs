//! Tap tables: the bilinear taps every path reads, built once on the host and summed to exactly 1.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use rayon::prelude::*;

use super::*;

/// Limits on building the kernel tables, the one long host step whose size grows with the
/// scene (lights × levels × slabs): a cancel flag looked at before each level, and the bytes the
/// memory budget leaves for the tables, which the built levels count against, so that a scene
/// whose tables cannot fit stops after at most one level per thread past the budget.
#[derive(Debug)]
pub struct TableGuard<'a> {
    /// Raised by a signal: stop before the next level.
    pub cancel: Option<&'a AtomicBool>,
    /// Bytes a tap and a table word (a schedule or level entry, `u32`) take as the backend
    /// holds them (see `pipeline::budget::kernel_table_bytes`).
    pub bytes_per_tap: u64,
    /// See `bytes_per_tap`.
    pub bytes_per_word: u64,
    /// Bytes the tables may take.
    pub limit: u64,
    used: AtomicU64,
}

impl<'a> TableGuard<'a> {
    /// A guard that stops on `cancel` or past `limit` bytes.
    pub fn new(
        cancel: Option<&'a AtomicBool>,
        bytes_per_tap: u64,
        bytes_per_word: u64,
        limit: u64,
    ) -> TableGuard<'a> {
        TableGuard {
            cancel,
            bytes_per_tap,
            bytes_per_word,
            limit,
            used: AtomicU64::new(0),
        }
    }

    /// A guard that never stops.
    pub fn unlimited() -> TableGuard<'static> {
        TableGuard::new(None, 0, 0, u64::MAX)
    }

    /// Whether the build must stop: cancelled, or past the limit.
    pub fn stopped(&self) -> bool {
        self.cancelled() || self.used() > self.limit
    }

    /// Whether the cancel flag is raised.
    pub fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// Bytes counted so far.
    pub fn used(&self) -> u64 {
        self.used.load(Ordering::Relaxed)
    }

    /// Counts `taps` taps and `words` table words; false once past the limit.
    pub fn charge(&self, taps: usize, words: usize) -> bool {
        let bytes = (taps as u64)
            .saturating_mul(self.bytes_per_tap)
            .saturating_add((words as u64).saturating_mul(self.bytes_per_word));
        let used = self
            .used
            .fetch_add(bytes, Ordering::Relaxed)
            .saturating_add(bytes);
        used <= self.limit
    }
}

/// Number of random phases per light for randomized kernels (a power of two: the phase is the
/// top `PHASE_BITS` bits of a hash).
pub const PHASE_BITS: u32 = 6;
/// `2^PHASE_BITS`.
pub const PHASES: usize = 1 << PHASE_BITS;

/// Largest number of taps a single phase may have (bounds per-pixel work).
pub const MAX_TAPS_PER_PHASE: usize = 4096;
/// Tap weights below this (2^-56) are dropped (see `discretise`).
pub(crate) const MIN_WEIGHT: f64 = 1.0 / 72_057_594_037_927_936.0;

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
///
/// The iterated penumbra has one kernel (`levels == 1`). The distance penumbra has one kernel per
/// *level*, a range of distances (in slabs) between a pixel and its mean occluder depth; a pixel
/// reads row `level · phase_count + phase` (see [`KernelTable::level_of`]).
#[derive(Clone, Debug, PartialEq)]
pub struct KernelTable {
    /// Number of phases per level; a power of two for hashed modes.
    pub phase_count: u32,
    /// Number of levels (kernels of different covariance): 1 for the iterated penumbra.
    pub levels: u32,
    /// Taps per phase (columns).
    pub taps_per_phase: u32,
    /// The taps, row-major with rows level-major: row r = level · phase_count + phase has taps
    /// `taps[r*taps_per_phase ..][..taps_per_phase]`.
    pub taps: Vec<Tap>,
    /// How a slab picks its phase.
    pub phase_mode: PhaseMode,
    /// For `PhaseMode::Schedule`: the phase of each slab, per level (`level · slabs + slab`).
    pub slab_phase: Vec<u32>,
    /// Whole-pixel shift added to every tap in each slab (all zero unless a mean carry is used);
    /// the same for every level.
    pub slab_shift: Vec<[i32; 2]>,
    /// Distance penumbra: the level of a pixel whose mean occluder lies `h` slabs in front of the
    /// slab being gathered, for h = 0..=slabs (h is rounded and clamped to 1..=slabs first).
    /// Empty for the iterated penumbra.
    pub level_of: Vec<u32>,
}

impl KernelTable {
    /// The taps of one row (`level · phase_count + phase`; the phase itself when `levels == 1`).
    pub fn phase(&self, p: u32) -> &[Tap] {
        let n = self.taps_per_phase as usize;
        &self.taps[p as usize * n..][..n]
    }

    /// Rows of taps: levels × phases.
    pub fn rows(&self) -> u32 {
        self.levels * self.phase_count
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
pub(crate) type Pattern = Vec<Vec<([f64; 2], f64)>>;

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
    build_table_with_carry(
        spec,
        moments,
        slabs,
        compensate,
        compensate && carry_mean(moments),
    )
}

/// [`build_table`] with the decision to carry the mean in whole pixels given (`carry` implies
/// `compensate`): the distance penumbra's levels all carry, or none does, as their smallest
/// kernel needs, so that every level moves a shadow by the same whole pixels.
fn build_table_with_carry(
    spec: KernelSpec,
    moments: &KernelMoments,
    slabs: u32,
    compensate: bool,
    carry: bool,
) -> KernelTable {
    let (pattern_mean, slab_shift) = mean_carry(moments, slabs, carry);
    build_table_around(
        spec,
        moments,
        slabs,
        compensate,
        carry,
        pattern_mean,
        slab_shift,
    )
}

/// The mean a pattern is read around and the whole-pixel shift of each slab: with `carry`, the
/// mean is carried in whole pixels (round(k·μ) − round((k−1)·μ) in slab k) and the pattern read
/// around 0; else the pattern is read around the mean and no slab shifts.
fn mean_carry(moments: &KernelMoments, slabs: u32, carry: bool) -> ([f64; 2], Vec<[i32; 2]>) {
    let slabs_us = slabs as usize;
    if carry {
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
    }
}

/// [`build_table_with_carry`] with the mean and the slabs' shifts given ([`mean_carry`]).
fn build_table_around(
    spec: KernelSpec,
    moments: &KernelMoments,
    slabs: u32,
    compensate: bool,
    carry: bool,
    pattern_mean: [f64; 2],
    slab_shift: Vec<[i32; 2]>,
) -> KernelTable {
    let slabs_us = slabs as usize;
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

/// Turns sample offsets into bilinear taps; rounds weights to f32 so that, summed in the
/// sweep's order, they give exactly 1.0 (a constant unoccluded buffer then never drifts).
pub(crate) fn discretise(
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
        levels: 1,
        level_of: Vec::new(),
    }
}

impl KernelTable {
    /// The iterated penumbra's one kernel at every level of the distance penumbra's
    /// [`distance_levels`] (`levels` copies of its rows and schedule, and their `level_of`), for
    /// a sweep that keeps a depth plane with the iterated penumbra (sub-pixel shadows): a pixel
    /// gathers the iterated kernel's bits whichever level it reads through, and the level plane
    /// still tells occluders at several depths apart.
    pub fn with_distance_levels(mut self, slabs: u32) -> KernelTable {
        assert_eq!(self.levels, 1, "already a table of levels");
        let ranges = distance_levels(slabs);
        let levels = ranges.len();
        self.taps = self.taps.repeat(levels);
        if self.phase_mode == PhaseMode::Schedule {
            self.slab_phase = self.slab_phase.repeat(levels);
        }
        let mut level_of = vec![0u32; slabs.max(1) as usize + 1];
        for (level, &[a, b]) in ranges.iter().enumerate() {
            level_of[a as usize..=b as usize].fill(level as u32);
        }
        self.levels = levels as u32;
        self.level_of = level_of;
        self
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
pub(crate) fn normalise_exactly(taps: &mut [Tap]) {
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

/// Distance penumbra: distances (in slabs) up to this each have a level of their own; beyond,
/// a level spans `h / LEVEL_RATIO_STEPS` distances (ranges growing by 1/16: about 16 levels per
/// doubling of the distance).
pub const EXACT_LEVELS: u32 = 16;
/// See [`EXACT_LEVELS`].
pub const LEVEL_RATIO_STEPS: u32 = 16;

/// The distance penumbra's levels for a sweep of `slabs` slabs: inclusive ranges `[a, b]` of the
/// distance h (in slabs, 1..=slabs) from a pixel's mean occluder depth to the slab gathered.
pub fn distance_levels(slabs: u32) -> Vec<[u32; 2]> {
    let mut levels = Vec::new();
    let mut a = 1u32;
    let top = slabs.max(1);
    while a <= top {
        let width = if a <= EXACT_LEVELS {
            1
        } else {
            (a / LEVEL_RATIO_STEPS).max(1)
        };
        let b = (a + width - 1).min(top);
        levels.push([a, b]);
        a = b + 1;
    }
    levels
}

/// Builds a light's tap tables for the distance penumbra: one level per range of
/// [`distance_levels`]. A single occluder h slabs in front of the slab being gathered needs the
/// covariance step ((h)² − (h−1)²)·e²·Σl = (2h − 1)·e²·Σl, so that after h slabs its penumbra
/// has h²·e²·Σl; a level spanning [a, b] uses the step of its mean, (a + b − 1)·e²·Σl, whose sum
/// over the range is exactly b² − (a−1)². `per_e2` gives the per-slab moments for a step
/// factor f: mean −e·μl, covariance f·e²·Σl (pixels).
///
/// The mean moves with the slabs, as in the iterated mode: every level reads around the same
/// per-slab mean, so a pixel moves its light by μκ per slab whatever level it sits at (inside a
/// medium a pixel may keep a small level for many slabs). Where the smallest level (h = 1) cannot
/// read the mean's fraction without exceeding its covariance, every level carries the mean in
/// whole pixels from slab to slab (the shift of an occluder in slab j onto slab k is then
/// round(k·μκ) − round(j·μκ): within 1 px, within ½ px for j = 0).
pub fn build_distance_table(
    spec: KernelSpec,
    per_e2: &(dyn Fn(f64) -> KernelMoments + Sync),
    slabs: u32,
    compensate: bool,
    guard: &TableGuard<'_>,
) -> Option<KernelTable> {
    let ranges = distance_levels(slabs);
    let carry = compensate && carry_mean(&per_e2(1.0));
    // One schedule of whole-pixel shifts for all levels (the first level's), not one per level.
    let (_, slab_shift) = mean_carry(&per_e2(1.0), slabs, carry);
    if !guard.charge(0, 2 * slab_shift.len() + ranges.len() + slabs as usize + 1) {
        return None;
    }
    // Levels are independent (their bits do not depend on the thread count): built in parallel,
    // each counted against the guard, none started once it stops.
    let tables: Vec<KernelTable> = ranges
        .par_iter()
        .map(|&[a, b]| {
            if guard.stopped() {
                return None;
            }
            let m = per_e2(f64::from(a + b - 1));
            // Each level reads around its own mean, or around 0 where the mean is carried.
            let mean = if carry { [0.0; 2] } else { m.mean };
            let t = build_table_around(spec, &m, slabs, compensate, carry, mean, Vec::new());
            guard.charge(t.taps.len(), t.slab_phase.len()).then_some(t)
        })
        .collect::<Option<_>>()?;
    let phase_count = tables.iter().map(|t| t.phase_count).max().unwrap_or(1);
    let taps_per_phase = tables.iter().map(|t| t.taps_per_phase).max().unwrap_or(1);
    // The merged table pads every level to the widest (held beside the levels while merged).
    let merged = tables.len() * (phase_count * taps_per_phase) as usize;
    if !guard.charge(merged, 0) {
        return None;
    }
    let zero = Tap {
        dx: 0,
        dy: 0,
        w: [0.0; 4],
    };
    let mut taps = Vec::with_capacity(merged);
    let mut slab_phase = Vec::new();
    for t in &tables {
        for p in 0..phase_count {
            // Levels with fewer phases (schedules) repeat their first; the schedule never
            // picks the copies.
            let row = t.phase(if p < t.phase_count { p } else { 0 });
            taps.extend_from_slice(row);
            // Zero taps after the last one leave the exact sum of 1 unchanged.
            taps.extend(std::iter::repeat_n(
                zero,
                (taps_per_phase - t.taps_per_phase) as usize,
            ));
        }
        slab_phase.extend_from_slice(&t.slab_phase);
    }
    let mut level_of = vec![0u32; slabs.max(1) as usize + 1];
    for (level, &[a, b]) in ranges.iter().enumerate() {
        for h in a..=b {
            level_of[h as usize] = level as u32;
        }
    }
    Some(KernelTable {
        phase_count,
        levels: tables.len() as u32,
        taps_per_phase,
        taps,
        phase_mode: tables[0].phase_mode,
        slab_phase,
        slab_shift,
        level_of,
    })
}
