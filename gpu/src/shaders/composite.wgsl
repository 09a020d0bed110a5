// Stages 4 and 5: mirrors cpu/src/composite.rs (front-to-back compositing, attenuation with the
// explicit flush, the final background).

#import shared/constants
#import shared/bindings
#import shading

// `composite`: t = (1 − A)·α; C += t·c; A += t. `acc` is (C.rgb, A). In a turned-round pass
// (back_to_front) C = α·c + (1 − α)·C, A = α + (1 − α)·A.
fn composite(acc: vec4<f32>, c: vec3<f32>, a: f32) -> vec4<f32> {
    if globals.back_to_front != 0u {
        let keep = 1.0 - a;
        return vec4<f32>(
            a * c.x + keep * acc.x,
            a * c.y + keep * acc.y,
            a * c.z + keep * acc.z,
            a + keep * acc.w,
        );
    }
    let t = (1.0 - acc.w) * a;
    return vec4<f32>(acc.x + t * c.x, acc.y + t * c.y, acc.z + t * c.z, acc.w + t);
}

// Steps 3 and 4 for one shading point of material `mi` (header `m`): its entry `e0` scaled to the
// part of the slab inside the medium (`part`, parity.wgsl `slab_part`), shaded with the light in
// `iin` — at a crossing of fragment `first`, with its triangle's normal, the highlight and where
// opaque the Lambert cosine — and composited into `acc`. Returns the new (C, A) and the scaled
// entry (its attenuation goes into the light buffers). The grid's sweep and the eye pass share it.
struct Sample {
    acc: vec4<f32>,
    entry: TfEntry,
}

fn shade_sample(acc: vec4<f32>, mi: u32, m: MaterialHeader, e0: TfEntry, part: vec2<f32>, crossed: bool, first: u32) -> Sample {
    let surface = crossed && (m.has_specular != SPEC_NONE || m.lambert != 0u || globals.horizon_at != HORIZON_NONE);
    var n = vec3<f32>(0.0, 0.0, 0.0);
    if surface {
        let o = normals[frag_meta[first] >> MESH_BITS];
        n = vec3<f32>(o[0], o[1], o[2]);
    }
    let scaled = part_of_slab(e0, part.x, part.y);
    let shaded = shade(mi, scaled.entry.color, e0.alpha, surface, n) * scaled.light;
    return Sample(composite(acc, shaded, scaled.entry.alpha), scaled.entry);
}

// `attenuate`: Iin·attenuation, flushed to zero below FLUSH_BELOW.
// `taken_out`: what a fraction f of a slab takes out where the whole slab takes out s,
// f·s·(1 + (1 − f)·s/2) (cpu/src/composite.rs).
fn taken_out(s: f32, f: f32) -> f32 {
    return f * s * (1.0 + (1.0 - f) * s * 0.5);
}

// `part_of_slab`: a medium's slab (alpha < 1) scaled to the part `inside` of it the pixel spends
// in the medium; returns the light's attenuation from where it entered the medium to the
// shading point (`lit_from`). Surfaces (alpha 1) are left as they are, with factor 1.
struct SlabPart {
    entry: TfEntry,
    light: vec3<f32>,
}

fn part_of_slab(e: TfEntry, inside: f32, lit_from: f32) -> SlabPart {
    var r = SlabPart(e, vec3<f32>(1.0, 1.0, 1.0));
    if !(e.alpha < 1.0) {
        return r;
    }
    r.light = vec3<f32>(
        1.0 - taken_out(1.0 - e.attenuation.x, lit_from),
        1.0 - taken_out(1.0 - e.attenuation.y, lit_from),
        1.0 - taken_out(1.0 - e.attenuation.z, lit_from),
    );
    if inside < 1.0 {
        r.entry.alpha = taken_out(e.alpha, inside);
        r.entry.attenuation = vec3<f32>(
            1.0 - taken_out(1.0 - e.attenuation.x, inside),
            1.0 - taken_out(1.0 - e.attenuation.y, inside),
            1.0 - taken_out(1.0 - e.attenuation.z, inside),
        );
    }
    return r;
}

fn attenuate(v_in: f32, attenuation: f32) -> f32 {
    let v = v_in * attenuation;
    return select(v, 0.0, v < globals.flush_below);
}

// `deepen` (distance penumbra): the occluder-depth plane after a slab, D + at · removed
// (`removed`: the light the slab took out, summed over channels, at depth `at` in slabs: this
// slab, a released surface's crossing slab, or an opaque crossing's `removal_depth`), flushed
// where its magnitude is below flush_below (negative before slab 0's middle).
fn deepen(depth: f32, at: f32, removed: f32) -> f32 {
    let v = depth + at * removed;
    return select(v, 0.0, abs(v) < globals.flush_below);
}

// `owned_depth` (distance penumbra): at a held surface's release the surface owns the pixel's
// darkness, the depth plane `at · occluded` (occluded: channels − Σ outgoing light).
fn owned_depth(at: f32, occluded: f32) -> f32 {
    return deepen(0.0, at, occluded);
}

// `Held`: what step 5 does with a pixel's light under its surface hold.
const HELD_FREE: u32 = 0u;    // the slab's own attenuation
const HELD_PASS: u32 = 1u;    // attenuation 1
const HELD_RELEASE: u32 = 2u; // attenuation 0, removed light recorded at `removed_at`
const HOLD_SHIFT: u32 = 16u;         // a pixel's hold state: crossing slab below, hold above
const HOLD_BARRIER_SHIFT: u32 = 26u; // a pixel's hold state: its barrier above
// A triangle's `surface_hold` word (`surface_hold::pack_holds`): the entry hold in
// ENTRY_HOLD_MASK, the exit hold from EXIT_HOLD_SHIFT, a shell's barrier from BARRIER_SHIFT (at
// most MAX_BARRIER); shared/constants has them from the Rust constants.

struct HoldStep {
    state: u32,
    held: u32,
    removed_at: u32,
}

// `release_slab`: the slab in which a (non-zero) hold state releases its light.
fn release_slab(state: u32) -> u32 {
    return (state & HOLD_SLAB_MASK) + ((state >> HOLD_SHIFT) & HOLD_LENGTH_MASK);
}

// `hold_state`: crossing slab, hold and barrier in one word.
fn hold_state(crossed: u32, hold: u32, barrier: u32) -> u32 {
    return crossed | (hold << HOLD_SHIFT) | (barrier << HOLD_BARRIER_SHIFT);
}

// `hold_step`: a pixel's packed hold `state` through slab `slab`, where it crossed a triangle of
// hold word `crossed` (0: none): a pending hold passes until its release slab, or until
// `ends_hold` (a crossing with fragments left behind it), then removes the light in the release
// slab and, outside every closed mesh, through its barrier (inside one a crossing may hold
// anew); a shell's crossing without a hold bars the slabs after it; else a crossing with a hold
// starts one.
fn hold_step(state: u32, slab: u32, crossed: u32, ends_hold: bool, inside: bool) -> HoldStep {
    let entry = crossed & ENTRY_HOLD_MASK;
    let barrier = (crossed >> BARRIER_SHIFT) & MAX_BARRIER;
    var next = state;
    if state != 0u {
        let start = state & ((1u << HOLD_SHIFT) - 1u);
        var release = release_slab(state);
        var bar = state >> HOLD_BARRIER_SHIFT;
        if slab < release {
            if !ends_hold {
                return HoldStep(state, HELD_PASS, slab);
            }
            release = slab;
            bar = 0u;
        }
        if slab <= release + bar {
            if slab == release + bar {
                next = 0u;
            }
            if slab == release || !inside {
                return HoldStep(next, HELD_RELEASE, start);
            }
            if entry == 0u {
                return HoldStep(next, HELD_FREE, slab);
            }
        }
        next = 0u;
    }
    if entry != 0u {
        return HoldStep(hold_state(slab, entry, barrier), HELD_PASS, slab);
    }
    if barrier != 0u && !inside {
        next = hold_state(slab, 0u, barrier);
    }
    return HoldStep(next, HELD_FREE, slab);
}

// Held-plane records (`surface_hold`'s "Who reads the held light" and "Released light served on
// its own surface"; cpu/src/composite.rs `HeldPlanes`): where a surface holds, `hold` keeps per
// grid pixel (`globals.hold_stride` words) its hold state, then its held-plane record, two slots
// of [from, until, z0 bits, triangle] (the hold's crossing slab, its release or cut, the
// crossing's depth in slabs, the triangle), then per slot its served release: the slab it
// released in and 4 values per light (its channels and depth plane as gathered then);
// `surface_hold` keeps per triangle its word and then its depth slopes' f32 bits.
// (HELD_WORDS, NO_HELD_SLAB, HELD_PART_MAX, HELD_BEHIND_MARGIN, SAME_SURFACE_SLABS,
// SERVED_HEAD_WORDS, SERVED_RELEASE_SLABS, SWEEP_SLABS_PER_SERVED_SLAB and SERVED_SLOPE_TOLERANCE come
// from `shared/constants`.)
const HOLD_SLAB_MASK: u32 = 0xffffu;   // a hold state's crossing slab
const HOLD_LENGTH_MASK: u32 = 1023u;   // a hold state's hold length, once shifted

// The index of grid pixel `p`'s hold state in `hold` (its record follows it).
fn hold_index(p: u32) -> u32 {
    return p * globals.hold_stride;
}

// The index of triangle `t`'s word in `surface_hold` (its slopes follow it).
fn surface_hold_index(t: u32) -> u32 {
    return t * 3u;
}

// `surface_hold::served_release_slabs`: slabs after its release during which a pixel's kept
// light is served.
fn served_age() -> u32 {
    return max(SERVED_RELEASE_SLABS, (globals.slabs + SWEEP_SLABS_PER_SERVED_SLAB - 1u) / SWEEP_SLABS_PER_SERVED_SLAB);
}

// `sweep.served_releases`: `hold` keeps the served releases after the records.
fn serves_releases() -> bool {
    return globals.hold_stride > 1u + HELD_WORDS;
}

// The index in `hold` of pixel p's served release in record slot `slot`.
fn served_index(p: u32, slot: u32) -> u32 {
    return hold_index(p) + 1u + HELD_WORDS + slot * (SERVED_HEAD_WORDS + 4u * globals.lights);
}

// `HeldPlanes::keep_release`: pixel p, released in slab `slab`, keeps light l's 4 values
// (`values`) with the record of the hold it released, if that hold has one.
fn keep_release(p: u32, slab: u32, l: u32, values: vec4<f32>) {
    if !serves_releases() {
        return;
    }
    let slot = newest_slot(p, slab + 1u);
    if slot == 2u || held_word(p, slot, 1u) != slab {
        return;
    }
    let at = served_index(p, slot);
    for (var c = 0u; c < 4u; c++) {
        hold[at + SERVED_HEAD_WORDS + 4u * l + c] = bitcast<u32>(values[c]);
    }
    hold[at] = slab;
}

// The surface a gathering pixel lies on (`pixel::held_fix`): its held crossing, else the
// fragment ahead of its cursor; `ok` false where it has none.
struct ReaderSurface {
    ok: bool,
    z: f32,
    triangle: u32,
}

// `HeldPlanes::served`: plane `plane` of light l (a channel, or the depth plane at `channels`)
// as pixel `c` gathered it in its release slab, where a gather at pixel `q` on `surface` in slab
// `slab` reads it there (`ok`), else not.
struct Served {
    ok: bool,
    value: f32,
}

fn served(q: vec2<i32>, surface: ReaderSurface, c: vec2<i32>, slab: u32, l: u32, plane: u32) -> Served {
    let none = Served(false, 0.0);
    let w = i32(globals.grid_w);
    let h = i32(globals.grid_h);
    if !serves_releases() || c.x < 0 || c.y < 0 || c.x >= w || c.y >= h {
        return none;
    }
    let pc = u32(c.y * w + c.x);
    let slot = newest_slot(pc, slab);
    if slot == 2u {
        return none;
    }
    let until = held_word(pc, slot, 1u);
    let at = served_index(pc, slot);
    if until >= slab || slab - until > served_age() || hold[at] != until {
        return none;
    }
    let z0 = bitcast<f32>(held_word(pc, slot, 2u));
    let t_at = surface_hold_index(held_word(pc, slot, 3u));
    let gx = bitcast<f32>(surface_hold[t_at + 1u]);
    let gy = bitcast<f32>(surface_hold[t_at + 2u]);
    let r_at = surface_hold_index(surface.triangle);
    let hx = bitcast<f32>(surface_hold[r_at + 1u]);
    let hy = bitcast<f32>(surface_hold[r_at + 2u]);
    let dx = f32(q.x - c.x);
    let dy = f32(q.y - c.y);
    let at_reader = z0 + gx * dx + gy * dy;
    let tolerance = SERVED_SLOPE_TOLERANCE + SERVED_SLOPE_TOLERANCE * (abs(gx) + abs(gy));
    if !(abs(surface.z - at_reader) < SAME_SURFACE_SLABS) || !(abs(hx - gx) + abs(hy - gy) < tolerance) {
        return none;
    }
    return Served(true, bitcast<f32>(hold[at + SERVED_HEAD_WORDS + 4u * l + plane]));
}

// `HeldSlot`, or none (`ok` false).
struct HeldSlot {
    ok: bool,
    start: u32, // `HeldSlot::from`
    until: u32,
    z0: f32,
    triangle: u32,
}

fn held_word(p: u32, slot: u32, k: u32) -> u32 {
    return hold[hold_index(p) + 1u + slot * 4u + k];
}

// `HeldPlanes::newest_slot`: pixel p's slot whose hold started last before slab `slab`
// (NO_HELD_SLAB: any), or 2 when none did (an empty slot's start is NO_HELD_SLAB).
fn newest_slot(p: u32, slab: u32) -> u32 {
    let a = held_word(p, 0u, 0u);
    let b = held_word(p, 1u, 0u);
    if a >= slab && b >= slab {
        return 2u;
    }
    if a >= slab || (b < slab && b > a) {
        return 1u;
    }
    return 0u;
}

// `HeldPlanes::latest_before`: pixel p's hold with the latest start before slab `slab`.
fn latest_before(p: u32, slab: u32) -> HeldSlot {
    let slot = newest_slot(p, slab);
    if slot == 2u {
        return HeldSlot(false, 0u, 0u, 0.0, 0u);
    }
    return HeldSlot(true, held_word(p, slot, 0u), held_word(p, slot, 1u), bitcast<f32>(held_word(p, slot, 2u)), held_word(p, slot, 3u));
}

// `HeldSlot::held_before`: it passed its light in slab `slab − 1`.
fn slot_held_before(s: HeldSlot, slab: u32) -> bool {
    return s.ok && s.start < slab && slab - 1u < s.until;
}

// `HeldPlanes::start`: into the empty slot or the older hold's.
fn held_start(p: u32, s: HeldSlot) {
    let a = held_word(p, 0u, 0u);
    let b = held_word(p, 1u, 0u);
    var slot = 0u;
    if a != NO_HELD_SLAB && (b == NO_HELD_SLAB || b < a) {
        slot = 1u;
    }
    let at = hold_index(p) + 1u + slot * 4u;
    hold[at + 1u] = s.until;
    hold[at + 2u] = bitcast<u32>(s.z0);
    hold[at + 3u] = s.triangle;
    hold[at] = s.start;
}

// `HeldPlanes::cut`: the latest hold stops passing in slab `slab`.
fn held_cut(p: u32, slab: u32) {
    let slot = newest_slot(p, NO_HELD_SLAB);
    if slot != 2u {
        hold[hold_index(p) + 1u + slot * 4u + 1u] = slab;
    }
}

// `HeldPlanes::hides`: the crossing slab of pixel `c`'s hold when a gather at pixel `q` in slab
// `slab` reads no light from it (held in slab − 1, q more than HELD_BEHIND_MARGIN slabs behind
// its surface's plane, and the column the light reaching it came from crossed that surface),
// else NO_HELD_SLAB. The caller has checked that q is not held.
fn hides(q: vec2<i32>, c: vec2<i32>, slab: u32, drift: array<f32, 2>) -> u32 {
    let w = i32(globals.grid_w);
    let h = i32(globals.grid_h);
    if c.x < 0 || c.y < 0 || c.x >= w || c.y >= h {
        return NO_HELD_SLAB;
    }
    let held = latest_before(u32(c.y * w + c.x), slab);
    if !slot_held_before(held, slab) {
        return NO_HELD_SLAB;
    }
    let t_at = surface_hold_index(held.triangle);
    let gx = bitcast<f32>(surface_hold[t_at + 1u]);
    let gy = bitcast<f32>(surface_hold[t_at + 2u]);
    let k = f32(slab);
    let dx = f32(q.x - c.x);
    let dy = f32(q.y - c.y);
    let at_reader = held.z0 + gx * dx + gy * dy;
    if at_reader >= k - HELD_BEHIND_MARGIN {
        return NO_HELD_SLAB;
    }
    let a = 1.0 - (gx * drift[0] + gy * drift[1]);
    let t = ((k - 1.0) - held.z0 + 0.5) / max(a, 1.0e-6);
    let ux = floor(f32(c.x) - t * drift[0] + 0.5);
    let uy = floor(f32(c.y) - t * drift[1] + 0.5);
    if ux < 0.0 || uy < 0.0 || ux >= f32(w) || uy >= f32(h) {
        return NO_HELD_SLAB;
    }
    let there = latest_before(u32(uy) * u32(w) + u32(ux), slab);
    if !there.ok {
        return NO_HELD_SLAB;
    }
    let plane = held.z0 + gx * (ux - f32(c.x)) + gy * (uy - f32(c.y));
    if abs(there.z0 - plane) < SAME_SURFACE_SLABS {
        return held.start;
    }
    return NO_HELD_SLAB;
}

// `finish`: C += (1 − A)·background.
fn finish(acc: vec4<f32>) -> vec3<f32> {
    let t = 1.0 - acc.w;
    return vec3<f32>(acc.x + t * globals.bg_r, acc.y + t * globals.bg_g, acc.z + t * globals.bg_b);
}
