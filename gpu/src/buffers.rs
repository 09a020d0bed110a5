//! Buffer helpers: size checks against the adapter's limits, uploads, zeroed buffers, read-back,
//! and 1D/2D dispatch sizing.

use wgpu::util::DeviceExt;

use crate::device::{GpuContext, GpuError};

/// Smallest buffer created (a binding of size 0 is invalid).
const MIN_BYTES: u64 = 16;

/// Refuses a storage buffer of `bytes` if it exceeds the adapter's per-binding limit.
pub fn check_size(ctx: &GpuContext, what: &'static str, bytes: u64) -> Result<(), GpuError> {
    let limit = ctx.max_binding();
    if bytes > limit {
        return Err(GpuError::TooLarge {
            what,
            bytes,
            need_mib: bytes.div_ceil(1 << 20),
            limit_mib: limit >> 20,
        });
    }
    Ok(())
}

/// A storage buffer holding `data`, zero-padded to at least one element and [`MIN_BYTES`] (a
/// binding of a runtime-sized array must hold one element).
pub fn upload<T: bytemuck::Pod>(
    ctx: &GpuContext,
    what: &'static str,
    data: &[T],
    copy_src: bool,
) -> Result<wgpu::Buffer, GpuError> {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    check_size(ctx, what, bytes.len() as u64)?;
    let mut usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    if copy_src {
        usage |= wgpu::BufferUsages::COPY_SRC;
    }
    let least = std::mem::size_of::<T>().max(MIN_BYTES as usize);
    let mut padded;
    let contents: &[u8] = if bytes.len() < least {
        padded = bytes.to_vec();
        padded.resize(least, 0);
        &padded
    } else {
        bytes
    };
    Ok(ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(what),
            contents,
            usage,
        }))
}

/// A zero-filled storage buffer of `words` 32-bit words.
pub fn zeroed(ctx: &GpuContext, what: &'static str, words: u64) -> Result<wgpu::Buffer, GpuError> {
    let bytes = words * 4;
    check_size(ctx, what, bytes)?;
    Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size: bytes.max(MIN_BYTES),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

/// A uniform buffer holding `value` (its WGSL struct is padded to a multiple of 16 bytes).
pub fn uniform<T: bytemuck::Pod>(ctx: &GpuContext, what: &'static str, value: &T) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(what),
            contents: bytemuck::bytes_of(value),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        })
}

/// Copies the first `words` words of `src` to the host (waits for all submitted work).
pub fn read_back(ctx: &GpuContext, src: &wgpu::Buffer, words: u64) -> Result<Vec<u32>, GpuError> {
    if words == 0 {
        return Ok(Vec::new());
    }
    let bytes = words * 4;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("read-back"),
        });
    encoder.copy_buffer_to_buffer(src, 0, &staging, 0, bytes);
    ctx.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    wait(ctx)?;
    rx.recv()
        .map_err(|e| GpuError::ReadBack(e.to_string()))?
        .map_err(|e| GpuError::ReadBack(e.to_string()))?;
    let out = {
        let view = staging
            .get_mapped_range(..)
            .map_err(|e| GpuError::ReadBack(e.to_string()))?;
        bytemuck::cast_slice::<u8, u32>(&view).to_vec()
    };
    staging.unmap();
    Ok(out)
}

/// Blocks until the queue is idle.
pub fn wait(ctx: &GpuContext) -> Result<(), GpuError> {
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|e| GpuError::ReadBack(e.to_string()))
}

/// Workgroup counts (x, y) for `groups` workgroups of a 1D kernel: x ≤ 65535; the shader
/// linearises `gid.x + gid.y · (x · workgroup size)`.
pub fn groups_1d(groups: u32) -> (u32, u32) {
    let x = groups.clamp(1, 65535);
    (x, groups.div_ceil(x).max(1))
}

/// A bind group for group 0 of `pipeline` with `(binding, buffer)` entries.
pub fn bind(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    entries: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = entries
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}

/// Submits one compute pass (`label`) that dispatches `pipeline` with bind group `group` over
/// `workgroups` (x, y) workgroups.
pub fn dispatch_once(
    ctx: &GpuContext,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    workgroups: (u32, u32),
) {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(workgroups.0, workgroups.1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
}
