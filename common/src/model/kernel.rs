//! Kernel names: the families, their parameters and the `ellipse2:slab`-style spelling.

use std::fmt;
use std::str::FromStr;

/// Largest `ellipseN` sample count.
pub const MAX_ELLIPSE_SAMPLES: u32 = 64;
/// Largest `gaussian:K` width.
pub const MAX_GAUSSIAN_WIDTH: u32 = 63;

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

/// Every kernel family once, by the spelling that stands for it (`ellipseN` by 2 and 3 points
/// and by its per-slab phase, `gaussian:K` by K = 19): the one list that the report, the benches
/// and the tests run.
pub const KERNEL_NAMES: [&str; 8] = [
    "ellipse2",
    "ellipse3",
    "ellipse2:slab",
    "dirac",
    "poisson8",
    "poisson16",
    "gaussian:19",
    "box",
];

/// The kernel spellings as help texts list them.
pub const KERNEL_SYNTAX: &str =
    "ellipse2, ellipse3, ellipseN:slab, dirac, poisson8, poisson16, gaussian:K, box";

/// The message for an unknown kernel name.
pub(crate) const UNKNOWN_KERNEL_HINT: &str = "expected one of ellipse2, ellipse3, ... ellipse64 (optionally with :slab, \
     e.g. ellipse2:slab), dirac, poisson8, poisson16, gaussian:K (K odd, 3 to 63), box";

impl FromStr for KernelSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("unknown kernel {s:?}: {UNKNOWN_KERNEL_HINT}");
        // Canonical decimal only: `u32::from_str` also takes "+3" and "02".
        let number = |t: &str| -> Result<u32, String> {
            let canonical = !t.is_empty()
                && t.bytes().all(|b| b.is_ascii_digit())
                && !(t.len() > 1 && t.starts_with('0'));
            if !canonical {
                return Err(bad());
            }
            t.parse().map_err(|_| bad())
        };
        let (base, per_slab_phase) = match s.strip_suffix(":slab") {
            Some(b) => (b, true),
            None => (s, false),
        };
        let kind = if let Some(n) = base.strip_prefix("ellipse") {
            let n = number(n)?;
            if !(2..=MAX_ELLIPSE_SAMPLES).contains(&n) {
                return Err(bad());
            }
            KernelKind::Ellipse(n)
        } else if let Some(k) = base.strip_prefix("gaussian:") {
            let k = number(k)?;
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
                "{s:?}: only ellipseN kernels take :slab; {UNKNOWN_KERNEL_HINT}"
            ));
        }
        Ok(KernelSpec {
            kind,
            per_slab_phase,
        })
    }
}
