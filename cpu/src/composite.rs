//! Stages 4 and 5: front-to-back compositing and light attenuation with the explicit flush
//! (DESIGN §2 steps 4–5). Mirrors `gpu/src/shaders/composite.wgsl`.

use convshadow_common::plan::FLUSH_BELOW;

/// `C += (1 − A)·α·c`, `A += (1 − A)·α`, in that order.
#[inline(always)]
pub fn composite(color: &mut [f32; 3], alpha: &mut f32, c: [f32; 3], a: f32) {
    let t = (1.0 - *alpha) * a;
    color[0] += t * c[0];
    color[1] += t * c[1];
    color[2] += t * c[2];
    *alpha += t;
}

/// `Iout = Iin · attenuation`, flushed to zero below [`FLUSH_BELOW`].
#[inline(always)]
pub fn attenuate(iin: f32, attenuation: f32) -> f32 {
    let v = iin * attenuation;
    if v < FLUSH_BELOW { 0.0 } else { v }
}

/// The final `C += (1 − A)·background`.
#[inline(always)]
pub fn finish(color: &mut [f32; 3], alpha: f32, background: [f32; 3]) {
    let t = 1.0 - alpha;
    color[0] += t * background[0];
    color[1] += t * background[1];
    color[2] += t * background[2];
}
