//! The CPU oracle of convshadow: LDI, parity cursor, kernels and the slab sweep.
//!
//! Every stage is bit-exact for any thread count: work is split by pixels, never by
//! partial sums, and all randomness comes from integer hashes.

pub mod composite;
pub mod kernels;
pub mod ldi;
pub mod parity;
pub mod shading;
pub mod subpixel;
pub mod sweep;

/// The default memory budget: half the machine's physical memory where it can be read, else 4 GiB.
pub fn default_memory_budget() -> u64 {
    let from_meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        s.lines()
            .find(|l| l.starts_with("MemTotal:"))
            .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
    });
    from_meminfo.map_or(4 << 30, |kib| kib * 1024 / 2)
}
