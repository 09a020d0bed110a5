//! Device set-up: the Vulkan backend, a hardware adapter when there is one, else a software one
//! (Mesa lavapipe), the adapter's own limits, and one error type for everything GPU-side.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use convshadow_common::contract::ldi::LdiError;

use crate::shader::Program;

/// Environment variable that picks an adapter by a case-insensitive substring of its name
/// (e.g. `llvmpipe` to force lavapipe on a machine that also has a GPU).
pub const ADAPTER_ENV: &str = "CONVSHADOW_ADAPTER";

/// Everything that can go wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan adapter (hardware or software) is available.
    #[error(
        "no GPU adapter available ({detail}); install Mesa's Vulkan driver (lavapipe: \
         `apt-get install mesa-vulkan-drivers libvulkan1`) or use --backend cpu"
    )]
    NoAdapter {
        /// What was tried.
        detail: String,
    },
    /// The adapter refused to create a device.
    #[error("cannot create a device on adapter {adapter}: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// The driver's message.
        message: String,
    },
    /// A buffer would exceed the adapter's per-binding or per-buffer limit.
    #[error(
        "the GPU {what} buffer needs {need_mib} MiB ({bytes} bytes), more than the adapter's \
         limit of {limit_mib} MiB per storage binding; lower the resolution, the slab count or the \
         mesh detail, or use --backend cpu"
    )]
    TooLarge {
        /// Which buffer.
        what: &'static str,
        /// Bytes needed.
        bytes: u64,
        /// MiB needed (rounded up).
        need_mib: u64,
        /// The limit in MiB.
        limit_mib: u64,
    },
    /// A scene property the GPU port does not support (with the reason).
    #[error("the GPU backend cannot render this scene: {0}")]
    Unsupported(String),
    /// The LDI would not fit the memory budget (same check as the CPU builder).
    #[error(transparent)]
    Ldi(#[from] LdiError),
    /// Reading results back from the device failed.
    #[error("GPU read-back failed: {0}")]
    ReadBack(String),
    /// The cancel flag was raised between slabs.
    #[error("interrupted")]
    Interrupted,
}

/// A device and queue on the chosen adapter, with that adapter's limits.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's description.
    pub info: wgpu::AdapterInfo,
    /// The limits the device was created with (the adapter's own, not the defaults).
    pub limits: wgpu::Limits,
    /// Every shader module and compute pipeline made so far: a driver compiles each once per
    /// device, not once per frame or light pass (on lavapipe the sweep's two take about half a
    /// second).
    compiled: Mutex<Compiled>,
    /// Set by the driver's device-lost callback: [`GpuContext::shared`] then opens a new device.
    lost: Arc<AtomicBool>,
}

/// The device [`GpuContext::shared`] hands out, with the adapter name it was opened for.
type SharedSlot = Option<(Option<String>, Arc<GpuContext>)>;

/// The shader modules and pipelines a [`GpuContext`] has compiled.
#[derive(Default)]
struct Compiled {
    modules: HashMap<Program, wgpu::ShaderModule>,
    pipelines: HashMap<(Program, &'static str), wgpu::ComputePipeline>,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.adapter_name())
            .finish()
    }
}

/// The adapter asked for by [`ADAPTER_ENV`], lower-cased; `None` when unset or empty.
fn wanted_adapter() -> Option<String> {
    std::env::var(ADAPTER_ENV)
        .ok()
        .filter(|s| !s.is_empty())
        .map(|s| s.to_lowercase())
}

/// Preference order of device types: hardware first, software last.
fn rank(t: wgpu::DeviceType) -> u32 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

impl GpuContext {
    /// Opens a device on the best Vulkan adapter (see [`ADAPTER_ENV`] to pick one by name).
    pub fn new() -> Result<GpuContext, GpuError> {
        pollster::block_on(Self::new_async())
    }

    /// The device this process shares: opened on first use (as [`GpuContext::new`]) and handed
    /// to every later render, so that a process rendering many frames, light passes or test
    /// cases opens one device and compiles each pipeline once (on lavapipe a device and the
    /// sweep's pipelines take about a second). A new one is opened when [`ADAPTER_ENV`] has
    /// changed or the device was lost; errors are not kept, so a later call tries again.
    pub fn shared() -> Result<Arc<GpuContext>, GpuError> {
        static SHARED: Mutex<SharedSlot> = Mutex::new(None);
        let wanted = wanted_adapter();
        // A poisoned lock only means another thread panicked while opening: the slot is whole.
        let mut slot = SHARED.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((name, ctx)) = slot.as_ref()
            && *name == wanted
            && !ctx.lost.load(Ordering::Acquire)
        {
            return Ok(Arc::clone(ctx));
        }
        let ctx = Arc::new(GpuContext::new()?);
        *slot = Some((wanted, Arc::clone(&ctx)));
        Ok(ctx)
    }

    async fn new_async() -> Result<GpuContext, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let mut adapters = instance.enumerate_adapters(wgpu::Backends::VULKAN).await;
        let wanted = wanted_adapter();
        if let Some(w) = &wanted {
            adapters.retain(|a| a.get_info().name.to_lowercase().contains(w.as_str()));
        }
        adapters.sort_by_key(|a| rank(a.get_info().device_type));
        let Some(adapter) = adapters.into_iter().next() else {
            return Err(GpuError::NoAdapter {
                detail: match wanted {
                    Some(w) => {
                        format!("no Vulkan adapter whose name contains {w:?} ({ADAPTER_ENV})")
                    }
                    None => "no Vulkan adapter found".into(),
                },
            });
        };
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("convshadow"),
                required_limits: limits.clone(),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device {
                adapter: info.name.clone(),
                message: e.to_string(),
            })?;
        let lost = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&lost);
        device.set_device_lost_callback(move |_, _| flag.store(true, Ordering::Release));
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            compiled: Mutex::default(),
            lost,
        })
    }

    /// The compute pipeline of `entry` in `program` (automatic layout), compiled on first use.
    pub(crate) fn pipeline(&self, program: Program, entry: &'static str) -> wgpu::ComputePipeline {
        // A poisoned lock only means another thread panicked mid-insert: the maps are still whole.
        let mut compiled = self.compiled.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(pipeline) = compiled.pipelines.get(&(program, entry)) {
            return pipeline.clone();
        }
        let module = compiled.modules.entry(program).or_insert_with(|| {
            self.device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(program.name()),
                    source: wgpu::ShaderSource::Wgsl(program.source().into()),
                })
        });
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
        compiled
            .pipelines
            .insert((program, entry), pipeline.clone());
        pipeline
    }

    /// The adapter as named in summaries and stats, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)
    /// [Cpu, Vulkan]`.
    pub fn adapter_name(&self) -> String {
        format!(
            "{} [{:?}, {:?}]",
            self.info.name, self.info.device_type, self.info.backend
        )
    }

    /// Whether the adapter is a software rasterizer (lavapipe).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The largest storage binding in bytes.
    pub fn max_binding(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }
}
