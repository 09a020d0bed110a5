//! Test support shared by every crate's tests, benches and fuzz targets: [`TestRng`], a
//! deterministic random sequence, and [`mesh_files`], mesh files in every format the renderer
//! reads, written independently of its loaders. Kept out of the production crates (a
//! dev-dependency only).

pub mod mesh_files;

use std::path::{Path, PathBuf};

use convshadow_common::pixel::hash::mix32;

/// `shared/<name>` beside the repository (`repo_root`: the repository's root folder), or `None`
/// with a loud message when it is missing. Under CI (env `CI` set) a missing folder is a
/// failure, not a skip.
pub fn shared_dir(repo_root: &Path, name: &str) -> Option<PathBuf> {
    let dir = repo_root.join("../shared").join(name);
    if dir.is_dir() {
        Some(dir)
    } else if std::env::var_os("CI").is_some() {
        panic!(
            "../shared/{name} not found at {} (required when CI is set)",
            dir.display()
        );
    } else {
        eprintln!(
            "SKIP: ../shared/{name} not found (looked in {}); tests that read it skipped",
            dir.display()
        );
        None
    }
}

/// `shared/models` beside the repository ([`shared_dir`]).
pub fn models_dir(repo_root: &Path) -> Option<PathBuf> {
    shared_dir(repo_root, "models")
}

/// `shared/volumes` beside the repository ([`shared_dir`]).
pub fn volumes_dir(repo_root: &Path) -> Option<PathBuf> {
    shared_dir(repo_root, "volumes")
}

/// Whether an example scene (its TOML `text`) can be rendered here: every `shared/` folder it
/// reads (`shared/models`, `shared/volumes`) is beside the repository ([`shared_dir`]: a loud
/// skip when missing, a failure under CI).
pub fn shared_inputs_present(repo_root: &Path, text: &str) -> bool {
    ["models", "volumes"].iter().all(|name| {
        !text.contains(&format!("shared/{name}")) || shared_dir(repo_root, name).is_some()
    })
}

/// A deterministic random sequence for tests, benches and fuzzing: a counter hashed by [`mix32`].
/// The renderer never draws from it (its randomness is keyed hashes of seed, light, slab and pixel).
#[derive(Clone, Debug)]
pub struct TestRng {
    /// The next counter value.
    state: u32,
}

impl TestRng {
    /// A generator for `seed`.
    pub fn new(seed: u32) -> TestRng {
        TestRng { state: mix32(seed) }
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        self.state = self.state.wrapping_add(0x9e37_79b9);
        mix32(self.state)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let lo = u64::from(self.next_u32());
        (u64::from(self.next_u32()) << 32) | lo
    }

    /// A uniform integer in `0..n` (`n > 0`; the modulo bias is irrelevant for tests).
    pub fn below(&mut self, n: u32) -> u32 {
        self.next_u32() % n
    }

    /// A uniform integer in `lo..=hi` (`hi - lo` below 2^63).
    pub fn int_range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % (hi - lo + 1) as u64) as i64
    }

    /// A uniform float in `[lo, hi)`, from 53 random bits rounded to f32.
    pub fn float_range(&mut self, lo: f64, hi: f64) -> f32 {
        let u = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        (lo + (hi - lo) * u) as f32
    }
}
