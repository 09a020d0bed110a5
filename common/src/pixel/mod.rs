//! What runs per pixel, under the bit-exactness rules (docs/ARCHITECTURE.md, "Contracts"): no
//! FMA, no libm transcendentals, randomness only from the integer hashes. `tests/contract/rules.rs` holds
//! every file in this folder to them.

pub mod hash;
pub mod lane;
pub mod levels;
pub mod noise;
pub mod texture3d;
pub mod volume;
