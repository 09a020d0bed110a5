//! Lights from in front of the viewer: the scene split into one pass per end of the sweep
//! ([`Scene::passes`]), each rendered on its own and their images added (the image is linear
//! in each light). A scene whose lights are all behind the viewer is one pass, as before.

use convshadow_common::model::scene::Scene;

use convshadow_cpu::composite::finish;

use super::{Aov, RenderError, Rendered, image_fingerprint};

/// Whether the turned-round pass's image is mirrored back in x: an orthographic camera's is
/// (the turned camera sees the image reversed), a perspective eye's is not (it keeps looking
/// from the eye; only its light is swept from the far end).
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Mirror {
    /// Mirror the turned-round pass's image, alpha and layers back in x.
    Yes,
    /// Add them as they are.
    No,
}

/// Renders `scene` with `render_pass` once per pass it needs: the front pass as it is, the
/// turned-round pass (its image mirrored back in x where `mirror` says) added to it. The requested layers go to
/// the pass that has their light (renumbered there, reported under the scene's numbers); the
/// depth layer is the front pass's, refused when every light is in front of the viewer.
pub fn render_passes(
    scene: &Scene,
    aovs: &[Aov],
    mirror: Mirror,
    mut render_pass: impl FnMut(&Scene, &[Aov]) -> Result<Rendered, RenderError>,
) -> Result<Rendered, RenderError> {
    let passes = scene.passes();
    let Some(back_scene) = &passes.back else {
        return render_pass(scene, aovs);
    };
    let mut pass_aovs = [Vec::new(), Vec::new()];
    for aov in aovs {
        match *aov {
            Aov::Depth if passes.front.is_none() => {
                return Err(RenderError::BadRequest(
                    "the depth layer needs a light from behind the viewer; every light of this \
                     scene travels towards the viewer (its pass sweeps from the far end)"
                        .into(),
                ));
            }
            Aov::Depth => pass_aovs[0].push(Aov::Depth),
            Aov::Light(l) => {
                let (pass, index) = passes.light(scene, l);
                pass_aovs[pass].push(Aov::Light(index));
            }
        }
    }
    let mut front = match &passes.front {
        Some(s) => Some(render_pass(s, &pass_aovs[0])?),
        None => None,
    };
    let mut back = render_pass(back_scene, &pass_aovs[1])?;
    if mirror == Mirror::Yes {
        let width = back.image.width as usize;
        mirror_rows(&mut back.image.data, width, 3);
        mirror_rows(&mut back.alpha, width, 1);
        for (_, layer) in &mut back.light_layers {
            mirror_rows(layer, width, 3);
        }
    }
    // Each layer under the scene's light number, in request order.
    let mut layers = [
        front
            .as_mut()
            .map_or(Vec::new(), |f| std::mem::take(&mut f.light_layers)),
        std::mem::take(&mut back.light_layers),
    ];
    let mut light_layers = Vec::new();
    for aov in aovs {
        if let Aov::Light(l) = *aov {
            let (pass, index) = passes.light(scene, l);
            let at = layers[pass].iter().position(|(i, _)| *i == index);
            let (_, layer) = layers[pass].swap_remove(at.expect("each pass renders its layers"));
            light_layers.push((l, layer));
        }
    }
    let Some(mut front) = front else {
        back.light_layers = light_layers;
        back.image_hash = image_fingerprint(&back.image.data);
        return Ok(back);
    };
    // C_front + (1 − A)·background + C_back: the background once, in the front pass.
    front.turned_round_lights = back.turned_round_lights;
    add_pass(&mut front, back);
    front.light_layers = light_layers;
    front.image_hash = image_fingerprint(&front.image.data);
    Ok(front)
}

/// Adds pass `pass`'s image (its background black) to `total`'s and its counts (slabs, updates,
/// seconds, chunks) to `total`'s; the light layers, the image hash and the turned-round lights
/// are the caller's.
pub fn add_pass(total: &mut Rendered, pass: Rendered) {
    for (f, b) in total.image.data.iter_mut().zip(&pass.image.data) {
        *f += *b;
    }
    add_counts(total, &pass);
}

/// Composites `behind` (an image of the meshes behind those of `total`, both on black) behind
/// `total`, as the eye sees it through `total`'s meshes: colour and each light layer
/// `C + (1 − A)·C_behind`, opacity `A + (1 − A)·A_behind`, the depth layer the nearer first hit;
/// and adds `behind`'s counts. The light layers pair by position (the same lights); the image
/// hash is the caller's.
pub fn composite_over(total: &mut Rendered, behind: Rendered) {
    // Per pixel the sweep's final `C += (1 − A)·background`, with the far image as background.
    let over = |near: &mut [f32], far: &[f32], alpha: &[f32]| {
        for ((n, f), &a) in near.chunks_exact_mut(3).zip(far.chunks_exact(3)).zip(alpha) {
            let far: [f32; 3] = f.try_into().expect("three channels");
            finish(n.try_into().expect("three channels"), a, far);
        }
    };
    over(&mut total.image.data, &behind.image.data, &total.alpha);
    for ((_, near), (_, far)) in total.light_layers.iter_mut().zip(&behind.light_layers) {
        over(near, far, &total.alpha);
    }
    if let (Some(near), Some(far)) = (&mut total.depth, &behind.depth) {
        for (n, f) in near.iter_mut().zip(far) {
            *n = n.min(*f);
        }
    }
    // Last: the layers above are seen through the near opacity.
    for (a, f) in total.alpha.iter_mut().zip(&behind.alpha) {
        *a += (1.0 - *a) * f;
    }
    add_counts(total, &behind);
}

/// Adds `pass`'s counts (slabs, updates, seconds, chunks) to `total`'s.
fn add_counts(total: &mut Rendered, pass: &Rendered) {
    total.slabs_swept += pass.slabs_swept;
    total.updates += pass.updates;
    total.seconds_ldi += pass.seconds_ldi;
    total.seconds_plan += pass.seconds_plan;
    total.seconds_sweep += pass.seconds_sweep;
    total.seconds_total += pass.seconds_total;
    for (f, b) in total.chunks.iter_mut().zip(pass.chunks) {
        *f += b;
    }
}

/// Reverses the order of the pixels in each row of an image of `width` pixels of `channels`
/// floats each.
fn mirror_rows(data: &mut [f32], width: usize, channels: usize) {
    for row in data.chunks_exact_mut(width * channels) {
        for x in 0..width / 2 {
            for c in 0..channels {
                row.swap(x * channels + c, (width - 1 - x) * channels + c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::mirror_rows;

    #[test]
    fn mirroring_reverses_each_row_and_keeps_a_pixels_channels_together() {
        let mut rgb: Vec<f32> = (0..18).map(|v| v as f32).collect(); // 3 × 2 pixels
        mirror_rows(&mut rgb, 3, 3);
        let want = [
            6., 7., 8., 3., 4., 5., 0., 1., 2., 15., 16., 17., 12., 13., 14., 9., 10., 11.,
        ];
        assert_eq!(rgb, want);
    }
}
