//! What a sweep takes and gives on every backend: the shared options (progress, cancel, initial
//! light), the output buffers, the error, and the per-pixel light limit.
//!
//! Backend-specific knobs (the CPU's code path and quiet-pixel skipping) live with their backend.

use std::sync::atomic::AtomicBool;

use crate::contract::ldi::Ldi;
use crate::plan::point_light::PointShading;
use crate::prepare::raster::RasterSetup;

/// Largest light count × channels handled per pixel (the CPU's stack arrays, the WGSL private
/// array; uploaded into the shader source, never copied).
pub const MAX_LIGHT_CHANNELS: usize = 48;

/// Why a sweep stopped early.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SweepError {
    /// The cancel flag was raised (Ctrl-C / SIGTERM).
    #[error("interrupted")]
    Interrupted,
}

/// The result of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOutput {
    /// Linear RGB, `width·height·3`, the guard band cropped away.
    pub image: Vec<f32>,
    /// The composited opacity `A` of each image pixel (`width·height`, the guard band cropped
    /// away): the front-to-back `A += (1 − A)·α_slab` before the background is added. The image
    /// is `C + (1 − A)·background`, `C` the composited colour.
    pub alpha: Vec<f32>,
    /// The light buffers after the last slab swept (grid-sized, row-major
    /// `[row][light][channel][x]`): the plan's last slab unless the sweep finished early (see
    /// [`SweepOptions::every_slab`]).
    pub light: Vec<f32>,
    /// How many slabs were swept: the plan's slab count, or fewer when the image was final
    /// earlier (every image pixel opaque).
    pub slabs_swept: u32,
}

/// Options of a sweep run that every backend honours.
pub struct SweepOptions<'a> {
    /// Called after every slab swept with the slab index; after an early finish, once more with
    /// the plan's last slab index (nothing is left to sweep).
    pub progress: &'a (dyn Fn(u32) + Sync),
    /// Checked between slabs; when raised the sweep stops with [`SweepError::Interrupted`].
    pub cancel: Option<&'a AtomicBool>,
    /// Initial light value per light and channel (`None` = 1, the unoccluded light).
    pub initial_light: Option<&'a [f32]>,
    /// Sweep every slab, for callers that read [`SweepOutput::light`] as the light after the
    /// plan's last slab. Otherwise (the default) a backend may stop after the first slab after
    /// which every image pixel is opaque (alpha exactly 1): compositing then adds exactly 0 to
    /// every image pixel, so no later slab can change an image bit. The CPU sweep stops there;
    /// the GPU sweep always sweeps every slab.
    pub every_slab: bool,
}

impl Default for SweepOptions<'_> {
    fn default() -> Self {
        SweepOptions {
            progress: &|_| {},
            cancel: None,
            initial_light: None,
            every_slab: false,
        }
    }
}

/// A camera as the eye pass reads it (CPU `sweep_perspective`, GPU `sweep_perspective`): a
/// perspective one (docs/how-it-works.md, "A perspective camera"), or an orthographic one whose
/// light grid has another resolution than its image (`sweep.light_resolution`).
pub struct EyeView<'a> {
    /// The LDI along the eye's rays (the image's pixels, no guard band), depths relative to the
    /// sweep's origin.
    pub ldi: &'a Ldi,
    /// Its rasterizer set-up (the crossed triangles' normals).
    pub raster: &'a RasterSetup,
    /// Image width and height.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Grid pixels per image pixel of offset from the centre, per unit of view depth:
    /// `light_resolution / (focal_px · pixel_size)` (perspective; 0 orthographic).
    pub zoom: f32,
    /// Grid pixels per image pixel of offset from the centre at any depth: an orthographic
    /// camera's `light_resolution` (0 perspective). The read's scale is `scale + depth · zoom`.
    pub scale: f32,
    /// The sweep's origin as a view depth (the eye's depths are relative to it); in a
    /// turned-round pass, minus the turned grid's origin (a view depth is then `z_origin − z`).
    pub z_origin: f32,
    /// Where the view axis meets the slab grid, in grid pixel coordinates (guard band included).
    pub axis: [f32; 2],
    /// The pass of the lights travelling towards the viewer: the grid is swept from the far end
    /// (its camera turned round, x mirrored), `ldi` holds each ray's fragments far to near at
    /// the turned grid's depths ([`Ldi::turned_round`]), `raster`'s normals are the turned
    /// camera's, and each ray composites back to front.
    pub turned_round: bool,
    /// A point or spot light's grid (a perspective view from the light's centre) instead of a
    /// slab grid: the eye's rays read it projectively ([`EyePoint`]) and shade with the
    /// direction to the light per sample; `None`: a slab grid.
    pub point: Option<EyePoint<'a>>,
}

/// How the eye reads a point light's grid ([`EyeView::point`]). The eye's ray at image-pixel
/// offset `o` from the centre and view depth `d` is `o·(scale + d·zoom)` cells of the eye's own
/// slab-grid frame from the view axis; the light's grid pixel there is
/// `axis + (o·(scale + d·zoom) − offset)·(focal / (d − depth))`.
pub struct EyePoint<'a> {
    /// The light's centre, falloff, cone and pattern in f32, in the eye's slab-grid frame (grid
    /// pixels of that frame, relative depths of the sweep).
    pub shading: &'a PointShading,
    /// Per mesh, its material's Henyey–Greenstein constants (`phase_constants`).
    pub phase: &'a [[f32; 3]],
    /// Where the view axis meets the eye's slab-grid frame, its grid pixels: with the ray's
    /// offset, a sample's x and y in `shading`'s coordinates.
    pub frame_axis: [f32; 2],
    /// The light's centre's offset from the view axis, in cells of the eye's frame.
    pub offset: [f32; 2],
    /// The view depth of the light's centre (the eye's view depths).
    pub depth: f32,
    /// The light grid's focal length in its pixels times the eye frame's cell size: grid pixels
    /// per cell of offset at unit view depth from the light.
    pub focal: f32,
}
