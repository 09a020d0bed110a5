//! The GPU buffer layouts: one `#[repr(C)]` Pod struct per element type the host uploads, each
//! mirrored field for field by a WGSL struct of the same name in `shaders/shared/bindings.wgsl`,
//! and the binding slot of every resource.
//!
//! Only 4-byte scalars, `vec2<i32>` and `array<T, N>` of them appear in storage structs, so the
//! WGSL layout rules give the same offsets as `repr(C)`; the test below parses the assembled
//! WGSL with naga and checks every struct's size and member offsets against the Rust side.

use bytemuck::{Pod, Zeroable};
use convshadow_common::model::scene::MAX_MESHES;

/// Uniform parameters of one LDI pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LdiParams {
    /// Invocations that do work: (triangle, row) items, or fragments for the sort.
    pub items: u32,
    /// Grid width.
    pub width: u32,
    /// Grid height.
    pub height: u32,
    /// `width · height`.
    pub pixels: u32,
    /// Invocations per dispatch row (x groups · workgroup size).
    pub stride: u32,
    /// 1 for a perspective camera: planes are inverse depths (`RasterSetup::fragment_depth`).
    pub perspective: u32,
    /// Perspective: the sweep's origin subtracted from `1 / plane`.
    pub depth_origin: f32,
    /// Uniform structs are a multiple of 16 bytes.
    pub _pad0: u32,
}

/// One rasterized triangle as the LDI passes read it (`TriangleSetup` less its normal).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Triangle {
    /// Fixed-point vertices.
    pub v: [[i32; 2]; 3],
    /// Pixel box `[x0, y0, x1, y1]`, inclusive.
    pub bbox: [i32; 4],
    /// Depth at the box's corner pixel.
    pub depth_ref: f32,
    /// Depth step per pixel in x.
    pub depth_dx: f32,
    /// Depth step per pixel in y.
    pub depth_dy: f32,
    /// Mesh index (scene order).
    pub mesh: u32,
}

/// One (triangle, row) work item of the count and fill passes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct WorkItem {
    /// Triangle index.
    pub triangle: u32,
    /// Grid row.
    pub row: u32,
}

/// The slab index of one sweep dispatch (copied into the uniform before each dispatch).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SlabParams {
    /// Slab index.
    pub slab: u32,
    /// Uniform structs are a multiple of 16 bytes.
    pub _pad0: u32,
    /// See `_pad0`.
    pub _pad1: u32,
    /// See `_pad0`.
    pub _pad2: u32,
}

/// The perspective camera's eye pass (`shaders/eye.wgsl`, uniform): the CPU's `EyeView` and
/// the image centre it offsets pixels from.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct EyeParams {
    /// Image width (eye pixels).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Grid pixels per image pixel of offset, per unit of view depth (`EyeView::zoom`).
    pub zoom: f32,
    /// The sweep's origin as a view depth (`EyeView::z_origin`).
    pub z_origin: f32,
    /// Where the view axis meets the slab grid, grid pixel coordinates (`EyeView::axis`).
    pub axis: [f32; 2],
    /// The image centre, `(width · 0.5, height · 0.5)` in f32.
    pub centre: [f32; 2],
    /// 1 in a turned-round pass (`EyeView::turned_round`): x mirrored, depths turned, back to
    /// front.
    pub turned_round: u32,
    /// The grid's pixel size in world units (`RenderPlan::pixel_size` in f32): a light's travel
    /// per slab is (drift · pixel size, slab distance).
    pub pixel_size: f32,
    /// Grid pixels per image pixel of offset at any depth (`EyeView::scale`: an orthographic
    /// camera's light resolution; 0 perspective).
    pub scale: f32,
    /// Uniform structs are a multiple of 16 bytes.
    pub _pad2: u32,
}

/// A point or spot light's eye pass (`shaders/eye.wgsl` `point_terms`, uniform): the CPU's
/// `EyePoint` and its `PointShading`, vectors padded to four floats (WGSL's `vec4` alignment).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PointParams {
    /// 1 on a point light's grid (the eye reads it projectively and shades with these terms).
    pub on: u32,
    /// 1 for a spot (`axis`, `inner`, `outer`).
    pub spot: u32,
    /// 1 for a spot with a pattern (`pattern_*`, texels at the `spot_pattern` slot).
    pub pattern: u32,
    /// `PointShading::pixel_size`.
    pub pixel_size: f32,
    /// `PointShading::center` (x, y, z) and `PointShading::radius2`.
    pub center: [f32; 4],
    /// `PointShading::color` (r, g, b, 0).
    pub color: [f32; 4],
    /// `ConeCosines::axis`.
    pub axis: [f32; 4],
    /// `PatternPlacement::right`.
    pub right: [f32; 4],
    /// `PatternPlacement::down`.
    pub down: [f32; 4],
    /// `EyePoint::offset`.
    pub offset: [f32; 2],
    /// `EyePoint::depth`.
    pub depth: f32,
    /// `EyePoint::focal`.
    pub focal: f32,
    /// `EyePoint::frame_axis`.
    pub frame_axis: [f32; 2],
    /// `ConeCosines::inner`.
    pub inner: f32,
    /// `ConeCosines::outer`.
    pub outer: f32,
    /// `PatternPlacement::size`.
    pub pattern_size: [f32; 2],
    /// `PatternPlacement::center`.
    pub pattern_centre: [f32; 2],
    /// The pattern's texels across.
    pub pattern_width: u32,
    /// The pattern's texels down.
    pub pattern_height: u32,
    /// 1 in a turned-round pass (`PointShading::turned`: a light behind every mesh).
    pub turned: u32,
    /// Padding before the 16-byte aligned array.
    pub _pad1: u32,
    /// Per mesh, `EyePoint::phase` (1 − g², 1 + g², 2g, 0).
    pub phase: [[f32; 4]; MAX_MESHES],
}

/// Per-render constants of the sweep (uniform).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Globals {
    /// Grid width (image + left and right guard band).
    pub grid_w: u32,
    /// Grid height (image + top and bottom guard band).
    pub grid_h: u32,
    /// Guard band columns left of the image (image x = grid x − guard_left).
    pub guard_left: u32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Slab count.
    pub slabs: u32,
    /// Light count.
    pub lights: u32,
    /// Light-buffer channels (1 or 3).
    pub channels: u32,
    /// 1 when the shading point is jittered inside the slab.
    pub jitter: u32,
    /// Slab thickness.
    pub slab_distance: f32,
    /// Light values below this are flushed to zero.
    pub flush_below: f32,
    /// Scale of the 4D Perlin noise.
    pub perlin4_scale: f32,
    /// Background red.
    pub bg_r: f32,
    /// Background green.
    pub bg_g: f32,
    /// Background blue.
    pub bg_b: f32,
    /// Floats per light-buffer row (`lights · planes · grid_w`).
    pub row_len: u32,
    /// Guard band rows above the image (image y = grid y − guard_top).
    pub guard_top: u32,
    /// 1 with pre-integrated compositing (`pre_front` then holds one word per grid pixel).
    pub preintegration: u32,
    /// Planes per light in the light buffers: its channels, then its depth plane if any.
    pub planes: u32,
    /// Depth planes per light: 1 with the distance penumbra (`RenderPlan::depth_planes`), else 0.
    pub depth_planes: u32,
    /// Distance penumbra: occluded light at or below this has no mean occluder depth
    /// (`plan::OCCLUSION_EPS`, uploaded as its f32 bits).
    pub occlusion_eps: f32,
    /// 1 when some surface is held (`RenderPlan::has_surface_hold`: `hold` then holds one word
    /// per grid pixel, `surface_hold` one per triangle).
    pub surface_holds: u32,
    /// The meshes in the parity test (`Ldi::parity_meshes`, bit i: mesh i): the closed ones; an
    /// open mesh is a thin shell whose crossings toggle nothing.
    pub parity_meshes: u32,
    /// `RenderPlan::inv_slab_distance`: 1/e in f32, for the part of a slab a medium fills.
    pub inv_slab_distance: f32,
    /// 1 with `sweep.media = "second-order"` (`RenderPlan::second_order_media`), else 0.
    pub second_order_media: u32,
    /// 1 when some mesh reads its light at the exact shift (`RenderPlan::subpixel_meshes`;
    /// `MeshHeader::subpixel` says which), else 0.
    pub subpixel_shadows: u32,
    /// 1 in a turned-round pass (`RenderPlan::turned_round`): composite back to front.
    pub back_to_front: u32,
    /// 1 on a point light's grid (`RenderPlan::projective`): a cell's material is read at its
    /// own 3D point, `centre + (xy − centre)·(depth_origin + z)·per_depth`.
    pub projective: u32,
    /// `ProjectiveGrid::centre`.
    pub projective_centre: [f32; 2],
    /// `ProjectiveGrid::depth_origin`.
    pub projective_depth_origin: f32,
    /// `ProjectiveGrid::per_depth`.
    pub projective_per_depth: f32,
    /// 1 on a soft point light's grid (`RenderPlan::depth_scale`): the distance penumbra's
    /// depths in ψ, read from `level_table` at `psi_at`.
    pub depth_scaled: u32,
    /// `level_table` index of ψ at slab coordinate 0 (`DepthScale::psi`, f32 bits).
    pub psi_at: u32,
    /// `DepthScale::psi.len() − 2`: the last slab coordinate whose step is ψ's own.
    pub psi_last: u32,
    /// 1 with `sweep.held_lit_side` where some surface is held (`RenderPlan::held_lit_side`):
    /// gathers read no light from held pixels behind whose surface they lie.
    pub held_lit_side: u32,
    /// `sweep.horizon`: `level_table` index of the horizon's Φ table (`RenderPlan::horizon`,
    /// f32 bits), or [`HORIZON_NONE`].
    pub horizon_at: u32,
    /// Words per grid pixel of `hold` where some surface is held: the hold state, its
    /// held-plane record (`HELD_WORDS`) and its two served releases (`SERVED_HEAD_WORDS` and 4
    /// values per light each); `surface_hold` then keeps three words per triangle (its word,
    /// then its depth slopes' f32 bits, `RenderPlan::hold_slopes`).
    pub hold_stride: u32,
}

/// `Globals::horizon_at` without a horizon (`sweep.horizon = false`).
pub const HORIZON_NONE: u32 = u32::MAX;

/// One slab's faces and jitter hash.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Slab {
    /// Front face (depth relative to the first slab's front).
    pub front: f32,
    /// Back face.
    pub back: f32,
    /// Hash of (seed, jitter stream, slab).
    pub jitter_hash: u32,
}

/// One light's kernel table header and shading constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LightHeader {
    /// Index of the light's first tap in the taps buffer (row r = level · phase_count + phase
    /// starts `taps_per_phase · r` further).
    pub taps: u32,
    /// Taps per phase (per row).
    pub taps_per_phase: u32,
    /// Phases per level (`KernelTable::phase_count`).
    pub phase_count: u32,
    /// Distance penumbra: index in the level-table buffer of `KernelTable::level_of[0]`.
    pub level_of: u32,
    /// Distance penumbra: the largest distance with a level, `level_of.len() − 1`.
    pub level_top: u32,
    /// Distance penumbra, scheduled kernels: index in the level-table buffer of
    /// `KernelTable::slab_phase[0]` (`level · slabs + slab`).
    pub level_phases: u32,
    /// Bits of the phase hash used to pick a phase.
    pub phase_bits: u32,
    /// One of the `PHASE_*` codes.
    pub phase_mode: u32,
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Blinn–Phong half vector.
    pub half_vector: [f32; 3],
    /// Unit direction towards the light (camera space): the Lambert cosine's and
    /// Ashikmin–Shirley's `l`.
    pub to_light: [f32; 3],
    /// Ashikmin–Shirley's Fresnel-over-(h·k) constants (`plan::fresnel_terms`).
    pub fresnel: [f32; 2],
    /// The light's drift per slab in pixels (`LightPlan::drift`).
    pub drift: [f32; 2],
    /// The light's spread for the horizon (`LightPlan::spread`).
    pub spread: [f32; 4],
    /// 1 when the light buffer holds the visible part of the light (`LightPlan::plain`).
    pub plain: u32,
}

/// One light's per-slab values (`light · slabs + slab` in the light-slab buffer).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LightSlab {
    /// Hash of (seed, light, slab).
    pub hash: u32,
    /// The scheduled phase (`PHASE_SCHEDULE` mode).
    pub phase: u32,
    /// The kernel's integer shift in this slab.
    pub shift: [i32; 2],
    /// How far the sweep has moved the light beyond its exact drift after this slab's gather
    /// (`LightPlan::carry_residual`; 0 without sub-pixel shadows).
    pub residual: [f32; 2],
}

/// One kernel tap: the offset of its top-left pixel and the weights of its four corners.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Tap {
    /// Integer x offset.
    pub dx: i32,
    /// Integer y offset.
    pub dy: i32,
    /// Weights of (0,0), (1,0), (0,1), (1,1).
    pub w: [f32; 4],
}

/// One material's header: where its tables start and its scalar parameters.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MaterialHeader {
    /// Index of the first transfer-function entry.
    pub tf: u32,
    /// Transfer-function entries (1 or `TF_SIZE`).
    pub tf_len: u32,
    /// One of the `DETAIL_*` codes (`DETAIL_NONE` without procedural detail).
    pub detail_kind: u32,
    /// Octaves of the detail.
    pub octave_count: u32,
    /// Index of the first octave.
    pub octaves: u32,
    /// 1 / Σ amplitudes.
    pub inv_amplitude_sum: f32,
    /// 1 when the detail is animated (4D noise at `time`).
    pub animated: u32,
    /// Animation time.
    pub time: f32,
    /// Index of the first texture voxel.
    pub texture: u32,
    /// Texture dimensions (1 without a texture).
    pub dims: [u32; 3],
    /// [`TEXTURE_NONE`], [`TEXTURE_DENSE`] or [`TEXTURE_BRICKED`]: whether the material has a
    /// 3D texture, and its layout.
    pub has_texture: u32,
    /// The specular model: [`SPEC_NONE`], [`SPEC_BLINN_PHONG`] or [`SPEC_ASHIKMIN_SHIRLEY`].
    pub has_specular: u32,
    /// Specular scale (`SpecularPlan::scale`: Blinn–Phong's strength, Ashikmin–Shirley's
    /// strength · (e + 1)/(8π)).
    pub spec_strength: f32,
    /// Specular exponent.
    pub spec_exponent: u32,
    /// Index of the first entry of the pre-integration table (`PI_SIZE²` entries in
    /// `tf_entries`, front-major), or [`NO_PRE`] without one.
    pub pre: u32,
    /// Ashikmin–Shirley's reflectance at normal incidence (0 otherwise).
    pub spec_f0: f32,
    /// 1 when crossed opaque surfaces get the Lambert cosine (`surface = "lambert"`).
    pub lambert: u32,
    /// A bricked texture's bricks along x, y, z (`texture` is then its index table, one exact
    /// f32 integer per brick: the brick's slot); 0 otherwise.
    pub bricks: [u32; 3],
    /// A bricked texture's first pool voxel (slot `s`'s voxels start at `pool + 512·s`).
    pub pool: u32,
}

/// [`MaterialHeader::has_texture`] of a material without a 3D texture.
pub const TEXTURE_NONE: u32 = 0;
/// [`MaterialHeader::has_texture`] of a dense texture: `dims` voxels from `texture`, x fastest.
pub const TEXTURE_DENSE: u32 = 1;
/// [`MaterialHeader::has_texture`] of a bricked texture (`convshadow_common::pixel::volume`).
pub const TEXTURE_BRICKED: u32 = 2;

/// [`MaterialHeader::pre`] of a material without a pre-integration table.
pub const NO_PRE: u32 = u32::MAX;
/// A `pre_front` word that keeps no front value (a NaN pattern: never a detail value's bits).
pub const PRE_NONE: u32 = 0x7fc0_0000;

/// One transfer-function entry.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct TransferEntry {
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Opacity of one slab.
    pub alpha: f32,
    /// Light attenuation per channel.
    pub attenuation: [f32; 3],
}

/// One detail octave.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Octave {
    /// Frequency.
    pub frequency: f32,
    /// Amplitude.
    pub amplitude: f32,
}

/// One mesh's detail transform and material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MeshHeader {
    /// (grid x, grid y, relative depth) → detail coordinates, row-major 3×4.
    pub to_detail: [f32; 12],
    /// Material index.
    pub material: u32,
    /// 1 when a crossing of this mesh reads its light at the exact shift
    /// (`RenderPlan::subpixel_meshes`), else 0.
    pub subpixel: u32,
}

/// A pixel's layer cursor: its next fragment and the inside bit of every mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Cursor {
    /// Index of the next fragment not yet passed.
    pub next: u32,
    /// Bit m set while inside mesh m.
    pub inside: u32,
}

/// Mesh ids take this many low bits of a fragment's meta word, the triangle index the rest.
pub const MESH_BITS: u32 = MAX_MESHES.trailing_zeros();
const _: () = assert!(MAX_MESHES.is_power_of_two() && MAX_MESHES <= 32);

/// `phase_mode` codes.
pub const PHASE_PER_PIXEL: u32 = 0;
/// See [`PHASE_PER_PIXEL`].
pub const PHASE_PER_SLAB: u32 = 1;
/// See [`PHASE_PER_PIXEL`].
pub const PHASE_SCHEDULE: u32 = 2;
/// [`MaterialHeader::has_specular`] codes: no highlight.
pub const SPEC_NONE: u32 = 0;
/// See [`SPEC_NONE`]: Blinn–Phong.
pub const SPEC_BLINN_PHONG: u32 = 1;
/// See [`SPEC_NONE`]: Ashikmin–Shirley.
pub const SPEC_ASHIKMIN_SHIRLEY: u32 = 2;
/// `detail_kind` codes.
pub const DETAIL_NONE: u32 = 0;
/// See [`DETAIL_NONE`].
pub const DETAIL_PERLIN: u32 = 1;
/// See [`DETAIL_NONE`].
pub const DETAIL_FBM: u32 = 2;
/// See [`DETAIL_NONE`].
pub const DETAIL_RIDGED: u32 = 3;
/// See [`DETAIL_NONE`].
pub const DETAIL_TURBULENCE: u32 = 4;

/// Declares the binding slots (group 0) as constants and as a (WGSL name, slot) table.
macro_rules! slots {
    ($($konst:ident = $name:literal, $slot:literal;)*) => {
        $(
            #[doc = concat!("Slot of `", $name, "` in `shaders/shared/bindings.wgsl`.")]
            pub const $konst: u32 = $slot;
        )*
        /// Every slot as (WGSL variable name, binding number).
        #[cfg(test)]
        pub const ALL: &[(&str, u32)] = &[$(($name, $slot)),*];
    };
}

/// Binding slots of group 0, one numbering for every pipeline (auto layouts keep only the slots
/// an entry point uses, so the LDI and sweep resources share the group without clashing).
pub mod slot {
    slots! {
        LDI_PARAMS = "ldi_params", 0;
        TRIS = "tris", 1;
        ITEMS = "items", 2;
        COUNTS = "counts", 3;
        CURSOR = "cursor", 4;
        KEY_DEPTH = "key_depth", 5;
        KEY_TRI = "key_tri", 6;
        OFFSETS = "offsets", 7;
        SORTED_DEPTH = "sorted_depth", 8;
        SORTED_TRI = "sorted_tri", 9;
        SLAB_PARAMS = "slab_params", 10;
        GLOBALS = "globals", 11;
        LIGHT_PREV = "light_prev", 12;
        LIGHT_CUR = "light_cur", 13;
        CURSORS = "cursors", 14;
        ACCUM = "accum", 15;
        FRAG_DEPTH = "frag_depth", 16;
        FRAG_META = "frag_meta", 17;
        IMAGE = "image", 18;
        SLABS = "slabs", 19;
        LIGHTS = "lights", 20;
        LIGHT_SLABS = "light_slabs", 21;
        TAPS = "taps", 22;
        MATERIALS = "materials", 23;
        TF_ENTRIES = "tf_entries", 24;
        OCTAVES = "octaves", 25;
        VOXELS = "voxels", 26;
        MESHES = "meshes", 27;
        NORMALS = "normals", 28;
        LIGHT_COLORS = "light_colors", 29;
        PRE_FRONT = "pre_front", 30;
        LEVEL_TABLE = "level_table", 31;
        LEVEL_PREV = "level_prev", 32;
        LEVEL_CUR = "level_cur", 33;
        HOLD = "hold", 34;
        SURFACE_HOLD = "surface_hold", 35;
        EYE_PARAMS = "eye_params", 36;
        GRID_CURSORS = "grid_cursors", 37;
        GRID_OFFSETS = "grid_offsets", 38;
        GRID_FRAG_META = "grid_frag_meta", 39;
        POINT_PARAMS = "point_params", 40;
        SPOT_PATTERN = "spot_pattern", 41;
    }
}

#[cfg(test)]
mod tests;
