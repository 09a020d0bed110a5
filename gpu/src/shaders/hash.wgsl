// Integer hashing: mirrors common/src/pixel/hash.rs (lowbias32 and the seed/stream/slab/row/pixel chain).

// `mix32`: Chris Wellons' lowbias32.
fn mix32(x0: u32) -> u32 {
    var x = x0;
    x = x ^ (x >> 16u);
    x = x * 0x7feb352du;
    x = x ^ (x >> 15u);
    x = x * 0x846ca68bu;
    x = x ^ (x >> 16u);
    return x;
}

// `row_hash(slab_hash, y)`.
fn row_hash(slab_hash: u32, y: u32) -> u32 {
    return mix32(slab_hash ^ y);
}

// `pixel_hash(row_hash, x)`.
fn pixel_hash(row: u32, x: u32) -> u32 {
    return mix32(row ^ (x * 0x9e3779b9u));
}

// `unit_float`: the top 24 bits times 2^-24 (exact).
fn unit_float(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// `phase_index`: the top `bits` bits (0 when bits is 0).
fn phase_index(h: u32, bits: u32) -> u32 {
    if bits == 0u {
        return 0u;
    }
    return h >> (32u - bits);
}
