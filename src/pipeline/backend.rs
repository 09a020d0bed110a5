//! Where a render runs: the device ([`Backend`], opened as a [`BackendChoice`]), the CPU's code
//! path ([`CpuPath`]) and its worker threads ([`thread_pool`]).

use convshadow_cpu::sweep::SweepPath;
use std::sync::Arc;

use convshadow_gpu::GpuContext;

use super::error::RenderError;

/// Most worker threads a render may ask for: far above any core count, and low enough that
/// starting (and, on a signal, stopping) the pool stays quick.
pub const MAX_THREADS: usize = 1024;

/// A thread pool with `threads` workers (0 = rayon's default: one per core), at most
/// [`MAX_THREADS`].
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, RenderError> {
    if threads > MAX_THREADS {
        return Err(RenderError::Threads(format!(
            "expected at most {MAX_THREADS} worker threads, got {threads}"
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| RenderError::Threads(e.to_string()))
}

/// Which CPU code path runs the sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CpuPath {
    /// One pixel at a time: the readable reference path.
    Scalar,
    /// Eight pixels at a time with `wide`, the same bits as `scalar` (the default).
    Simd,
}

impl CpuPath {
    /// The name used in stats.
    pub fn name(self) -> &'static str {
        match self {
            CpuPath::Scalar => "scalar",
            CpuPath::Simd => "simd",
        }
    }

    /// The sweep's code path.
    pub fn sweep_path(self) -> SweepPath {
        match self {
            CpuPath::Scalar => SweepPath::Scalar,
            CpuPath::Simd => SweepPath::Simd,
        }
    }
}

/// Which device renders (`--backend`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The CPU oracle.
    #[default]
    Cpu,
    /// The wgpu port (Vulkan: a hardware adapter, else Mesa lavapipe); exit code 5 without one.
    Gpu,
    /// A hardware GPU when there is one, else the CPU (and says so): a software adapter
    /// (lavapipe) only when named by `CONVSHADOW_ADAPTER`.
    Auto,
}

/// Whether the user named an adapter (`CONVSHADOW_ADAPTER`): `auto` then uses it, software or
/// not.
fn adapter_named() -> bool {
    std::env::var(convshadow_gpu::device::ADAPTER_ENV).is_ok_and(|s| !s.is_empty())
}

/// The device chosen for a request.
pub struct BackendChoice {
    /// The GPU context (the process's shared device, [`GpuContext::shared`]), or `None` for
    /// the CPU.
    pub gpu: Option<Arc<GpuContext>>,
    /// Why `auto` fell back to the CPU, or that `gpu` runs on a software adapter.
    pub note: Option<String>,
}

impl BackendChoice {
    /// The backend this choice runs on (never `auto`).
    pub fn opened(&self) -> Backend {
        if self.gpu.is_some() {
            Backend::Gpu
        } else {
            Backend::Cpu
        }
    }

    /// Opens the backend: `gpu` fails without an adapter, `auto` falls back to the CPU.
    pub fn open(backend: Backend) -> Result<BackendChoice, RenderError> {
        match backend {
            Backend::Cpu => Ok(BackendChoice {
                gpu: None,
                note: None,
            }),
            Backend::Gpu => {
                let ctx = GpuContext::shared()?;
                let note = ctx.is_software().then(|| {
                    format!(
                        "--backend gpu: {} is a software rasterizer: a correctness reference, \
                         far slower than --backend cpu",
                        ctx.adapter_name()
                    )
                });
                Ok(BackendChoice {
                    gpu: Some(ctx),
                    note,
                })
            }
            Backend::Auto => Ok(match GpuContext::shared() {
                // Software is ranked last: the first adapter is software only when all are. The
                // CPU oracle is faster than any of them; one asked for by name is used.
                Ok(ctx) if ctx.is_software() && !adapter_named() => BackendChoice {
                    note: Some(format!(
                        "--backend auto: the only Vulkan adapter, {}, is a software rasterizer, \
                         slower than the CPU; rendering on the CPU ({}=NAME picks it anyway)",
                        ctx.adapter_name(),
                        convshadow_gpu::device::ADAPTER_ENV
                    )),
                    gpu: None,
                },
                Ok(ctx) => BackendChoice {
                    gpu: Some(ctx),
                    note: None,
                },
                Err(e) => BackendChoice {
                    gpu: None,
                    note: Some(format!("--backend auto: {e}; rendering on the CPU")),
                },
            }),
        }
    }

    /// `"gpu"` or `"cpu"`, as in stats.
    pub fn name(&self) -> &'static str {
        if self.gpu.is_some() { "gpu" } else { "cpu" }
    }

    /// The adapter's name on the GPU backend.
    pub fn adapter(&self) -> Option<String> {
        self.gpu.as_deref().map(GpuContext::adapter_name)
    }
}
