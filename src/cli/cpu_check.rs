//! The processor check that runs before `main`: the release build targets x86-64-v3 (AVX2, FMA,
//! BMI1/2; `.cargo/config.toml`, docs/performance.md), so on a processor without those
//! instructions the binary must say so and exit instead of dying with SIGILL somewhere in the
//! sweep.
//!
//! The check is an ELF constructor (`.init_array`), so it runs before `main` and before any of
//! the program's own vector code. It reads `cpuid` and `xgetbv`, and on a missing extension
//! writes one line and exits with `exit::UNSUPPORTED_CPU` (8).
//! `tests/platform/cpu_check.rs` runs the binary on an emulated processor without AVX2 (qemu-user).

/// The x86-64-v3 extensions with how to find each with `cpuid`: (name, leaf, register index
/// in `[eax, ebx, ecx, edx]`, bit).
#[cfg(target_arch = "x86_64")]
const V3_FEATURES: [(&str, u32, usize, u32); 9] = [
    ("AVX", 1, 2, 28),
    ("AVX2", 7, 1, 5),
    ("BMI1", 7, 1, 3),
    ("BMI2", 7, 1, 8),
    ("F16C", 1, 2, 29),
    ("FMA", 1, 2, 12),
    ("LZCNT", 0x8000_0001, 2, 5),
    ("MOVBE", 1, 2, 22),
    ("XSAVE/OSXSAVE", 1, 2, 27),
];

/// Exits with one line on stderr when this build uses AVX2 and the processor (or the operating
/// system, for the AVX registers) lacks a v3 extension. Written with `cpuid` and `xgetbv`
/// directly: `is_x86_feature_detected!` answers `true` at compile time for every feature the
/// build enables, which would make the check a no-op. No formatting or allocation: only
/// integer code runs before the check has passed.
#[cfg(target_arch = "x86_64")]
extern "C" fn require_compiled_features() {
    use std::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
    use std::io::Write;
    if !cfg!(target_feature = "avx2") {
        return;
    }
    // Leaves above the processor's maximum read as 0 (`cpuid` exists on every x86-64).
    let regs = |leaf: u32| {
        let max = __cpuid(leaf & 0x8000_0000).eax;
        if leaf > max {
            [0; 4]
        } else {
            let r = __cpuid_count(leaf, 0);
            [r.eax, r.ebx, r.ecx, r.edx]
        }
    };
    let has = |&(_, leaf, reg, bit): &(&str, u32, usize, u32)| regs(leaf)[reg] >> bit & 1 == 1;
    let osxsave = has(&V3_FEATURES[8]);
    // SAFETY: `xgetbv` is available when the OSXSAVE bit is set (checked first).
    let os_saves_ymm = osxsave && unsafe { _xgetbv(0) } & 0b110 == 0b110;
    if V3_FEATURES.iter().all(has) && os_saves_ymm {
        return;
    }
    let mut err = std::io::stderr().lock();
    let _ =
        err.write_all(b"error: this convshadow was built for x86-64-v3 but this processor lacks");
    for f in V3_FEATURES.iter().filter(|f| !has(f)) {
        let _ = err.write_all(b" ");
        let _ = err.write_all(f.0.as_bytes());
    }
    if !os_saves_ymm {
        let _ = err.write_all(b" (or its system does not save AVX registers)");
    }
    let _ = err.write_all(
        b"; build for it with RUSTFLAGS=\"-C target-cpu=native\" cargo build --release \
          (same image bits; docs/performance.md)\n",
    );
    drop(err);
    std::process::exit(super::exit::UNSUPPORTED_CPU);
}

/// Registers [`require_compiled_features`] as a constructor: it runs before `main`.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
#[used]
#[unsafe(link_section = ".init_array")]
static REQUIRE_COMPILED_FEATURES: extern "C" fn() = require_compiled_features;
