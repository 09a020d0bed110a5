// Every buffer layout and binding the shaders share: the structs mirror the `#[repr(C)]` Pod
// structs of gpu/src/layout.rs field for field (checked by its layout test through naga), and
// the slots are `layout::slot`. Storage structs hold only 4-byte scalars, vec2<i32> and arrays
// of them, so WGSL's layout rules and `repr(C)` give the same offsets. Each pipeline's entry
// points use a subset of the bindings; automatic layouts keep only the slots they use.

// ---- LDI passes (ldi.wgsl) ----

struct LdiParams {
    items: u32,       // invocations that do work: (triangle, row) items, or fragments
    width: u32,       // grid width
    height: u32,      // grid height
    pixels: u32,      // width · height
    stride: u32,      // invocations per dispatch row (x groups · 64)
    perspective: u32, // 1: planes are inverse depths (`RasterSetup::fragment_depth`)
    depth_origin: f32, // perspective: subtracted from 1 / plane
    _pad0: u32,
}

// `TriangleSetup` as rasterized: fixed-point vertices, inclusive pixel box, depth plane, mesh.
struct Triangle {
    v: array<vec2<i32>, 3>,
    bbox: array<i32, 4>,
    depth_ref: f32,
    depth_dx: f32,
    depth_dy: f32,
    mesh: u32,
}

struct WorkItem {
    triangle: u32,
    row: u32,
}

@group(0) @binding(0) var<uniform> ldi_params: LdiParams;
@group(0) @binding(1) var<storage, read> tris: array<Triangle>;
@group(0) @binding(2) var<storage, read> items: array<WorkItem>;
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> key_depth: array<u32>;
@group(0) @binding(6) var<storage, read_write> key_tri: array<u32>;
// CSR offsets of the LDI (`width·height + 1`), read by the sort and by the sweep.
@group(0) @binding(7) var<storage, read> offsets: array<u32>;
@group(0) @binding(8) var<storage, read_write> sorted_depth: array<u32>;
@group(0) @binding(9) var<storage, read_write> sorted_tri: array<u32>;

// ---- The sweep (sweep.wgsl and the stage files it imports) ----

struct SlabParams {
    slab: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// Per-render constants.
struct Globals {
    grid_w: u32,
    grid_h: u32,
    guard_left: u32,  // image x = grid x − guard_left
    width: u32,
    height: u32,
    slabs: u32,
    lights: u32,
    channels: u32,
    jitter: u32,
    slab_distance: f32,
    flush_below: f32,
    perlin4_scale: f32,
    bg_r: f32,
    bg_g: f32,
    bg_b: f32,
    row_len: u32,     // floats per light-buffer row: lights · planes · grid_w
    guard_top: u32,   // image y = grid y − guard_top
    preintegration: u32, // 1: pre-integrated compositing (`pre_front` per grid pixel)
    planes: u32,      // planes per light: channels, then the depth plane (distance penumbra)
    depth_planes: u32, // 1 with the distance penumbra, else 0
    occlusion_eps: f32, // OCCLUSION_EPS (its f32 bits from Rust)
    surface_holds: u32, // 1: some surface is held (`hold` per grid pixel, `surface_hold` per triangle)
    parity_meshes: u32, // the closed meshes (bit i: mesh i); open ones are thin shells
    inv_slab_distance: f32, // 1/e (RenderPlan::inv_slab_distance), for a medium's part of a slab
    second_order_media: u32, // 1: sweep.media = "second-order" (else slab_part is (1, 0))
    subpixel_shadows: u32, // 1: some mesh reads its light at the exact shift (MeshHeader.subpixel)
    back_to_front: u32, // 1: a turned-round pass (RenderPlan::turned_round): composite back to front
    projective: u32,    // 1: a point light's grid (RenderPlan::projective): materials read at a cell's 3D point
    projective_centre: vec2<f32>,
    projective_depth_origin: f32,
    projective_per_depth: f32,
    depth_scaled: u32,  // 1: a soft point light's grid (RenderPlan::depth_scale): depths in ψ
    psi_at: u32,        // level_table index of ψ at slab coordinate 0 (f32 bits)
    psi_last: u32,      // DepthScale::psi.len() − 2
    held_lit_side: u32, // 1: held light read only from its lit side
    horizon_at: u32,    // level_table index of the horizon's Φ table (f32 bits), HORIZON_NONE without
    hold_stride: u32,   // words per grid pixel of `hold` (state, held-plane record, served releases)
}

struct Slab {
    front: f32,
    back: f32,
    jitter_hash: u32,
}

// A light's kernel table (`taps`: its first tap; row level · phase_count + phase), its level
// tables in `level_table` (distance penumbra) and shading constants.
struct LightHeader {
    taps: u32,
    taps_per_phase: u32,
    phase_count: u32,
    level_of: u32,     // level_table index of level_of[0]
    level_top: u32,    // level_of.len() − 1
    level_phases: u32, // level_table index of the per-level slab phases (level · slabs + slab)
    phase_bits: u32,
    phase_mode: u32,  // PHASE_*
    color: array<f32, 3>,
    half_vector: array<f32, 3>,
    to_light: array<f32, 3>, // unit direction towards the light (Lambert, Ashikmin–Shirley)
    fresnel: array<f32, 2>,  // Ashikmin–Shirley: [p/(h·k), (1 − p)/(h·k)], p = (1 − h·k)^5
    drift: array<f32, 2>,    // the light's drift per slab (pixels), for sub-pixel shadows
    spread: array<f32, 4>,   // the horizon's spread: σ² = ((a·fx² + b·fx·fy) + c·fy²) + iso
    plain: u32,              // 1: the light buffer holds the visible part (no pattern)
}

// A light's values in one slab, at `light · slabs + slab`.
struct LightSlab {
    hash: u32,
    phase: u32,       // the scheduled phase (PHASE_SCHEDULE)
    shift: vec2<i32>,
    residual: array<f32, 2>, // the carried drift beyond the exact one after this slab (sub-pixel shadows)
}

// Offset of the top-left pixel read and the weights of corners (0,0), (1,0), (0,1), (1,1).
struct Tap {
    dx: i32,
    dy: i32,
    w: array<f32, 4>,
}

// A material: where its tables start (`tf`, `octaves`, `texture`) and its parameters.
struct MaterialHeader {
    tf: u32,
    tf_len: u32,      // 1 (constant) or TF_SIZE
    detail_kind: u32, // DETAIL_*
    octave_count: u32,
    octaves: u32,
    inv_amplitude_sum: f32,
    animated: u32,
    time: f32,
    texture: u32,
    dims: array<u32, 3>,
    has_texture: u32,  // TEXTURE_NONE, TEXTURE_DENSE or TEXTURE_BRICKED
    has_specular: u32, // SPEC_*
    spec_strength: f32,
    spec_exponent: u32,
    pre: u32,         // first entry of the PI_SIZE² pre-integration table, or NO_PRE
    spec_f0: f32,     // Ashikmin–Shirley reflectance at normal incidence
    lambert: u32,     // 1: Lambert cosine at crossed opaque surfaces
    bricks: array<u32, 3>, // TEXTURE_BRICKED: bricks along x, y, z (`texture`: the index table)
    pool: u32,        // TEXTURE_BRICKED: the first pool voxel
}

struct TransferEntry {
    color: array<f32, 3>,
    alpha: f32,
    attenuation: array<f32, 3>,
}

struct Octave {
    frequency: f32,
    amplitude: f32,
}

// (grid x, grid y, relative depth) → detail coordinates, row-major 3×4, and the material.
struct MeshHeader {
    to_detail: array<f32, 12>,
    material: u32,
    subpixel: u32, // 1: a crossing reads its light at the exact shift (sub-pixel shadows)
}

// A pixel's layer cursor: the next fragment and the inside bit of every mesh.
struct Cursor {
    next: u32,
    inside: u32,
}

@group(0) @binding(10) var<uniform> slab_params: SlabParams;
@group(0) @binding(11) var<uniform> globals: Globals;
@group(0) @binding(12) var<storage, read> light_prev: array<f32>;
@group(0) @binding(13) var<storage, read_write> light_cur: array<f32>;
@group(0) @binding(14) var<storage, read_write> cursors: array<Cursor>;
@group(0) @binding(15) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(16) var<storage, read> frag_depth: array<f32>;
// Fragment meta: `mesh | triangle << MESH_BITS`.
@group(0) @binding(17) var<storage, read> frag_meta: array<u32>;
@group(0) @binding(18) var<storage, read_write> image: array<f32>;
@group(0) @binding(19) var<storage, read> slabs: array<Slab>;
@group(0) @binding(20) var<storage, read> lights: array<LightHeader>;
@group(0) @binding(21) var<storage, read> light_slabs: array<LightSlab>;
@group(0) @binding(22) var<storage, read> taps: array<Tap>;
@group(0) @binding(23) var<storage, read> materials: array<MaterialHeader>;
@group(0) @binding(24) var<storage, read> tf_entries: array<TransferEntry>;
@group(0) @binding(25) var<storage, read> octaves: array<Octave>;
@group(0) @binding(26) var<storage, read> voxels: array<f32>;
@group(0) @binding(27) var<storage, read> meshes: array<MeshHeader>;
// Per rasterized triangle: its unit normal.
@group(0) @binding(28) var<storage, read> normals: array<array<f32, 3>>;
// Per (material, light), at `material · lights + light`: the light's colour times the material's
// phase function (the bare colour for isotropic media), read by the shading's light sum.
@group(0) @binding(29) var<storage, read> light_colors: array<array<f32, 3>>;
// Pre-integration: per grid pixel the bits of the detail value at the next slab's front face
// kept from this slab, or PRE_NONE (one unused word without pre-integration).
@group(0) @binding(30) var<storage, read_write> pre_front: array<u32>;
// Distance penumbra, per light from `LightHeader.level_of` and `.level_phases`: the level of each
// distance in slabs (`KernelTable::level_of`) and, for scheduled kernels, each level's phase per
// slab (`KernelTable::slab_phase`).
@group(0) @binding(31) var<storage, read> level_table: array<u32>;
// Distance penumbra: each light's level per pixel (`pixel_level`, LIT_LEVEL without an occluder),
// `[row][light][x]`, ping-pong like the light buffers: the previous slab's and this slab's.
@group(0) @binding(32) var<storage, read> level_prev: array<u32>;
@group(0) @binding(33) var<storage, read_write> level_cur: array<u32>;
// Surface holds (`RenderPlan::surface_hold`): per grid pixel its packed hold (`hold_step`), and
// per rasterized triangle how many slabs an opaque crossing of it holds (one unused word each
// where no surface is held).
@group(0) @binding(34) var<storage, read_write> hold: array<u32>;
@group(0) @binding(35) var<storage, read> surface_hold: array<u32>;

// ---- The perspective camera's eye pass (eye.wgsl) ----
// It binds the eye's LDI, cursors, colours and triangle normals at the sweep's slots (`offsets`,
// `frag_depth`, `frag_meta`, `cursors`, `accum`, `normals`), so the stage files read them as
// they read the grid's; the grid's light is `light_prev`, its cursors `grid_cursors`.

struct EyeParams {
    width: u32,
    height: u32,
    zoom: f32,      // grid pixels per image pixel of offset, per unit of view depth
    z_origin: f32,  // the sweep's origin as a view depth
    axis: vec2<f32>,   // where the view axis meets the grid (grid pixel coordinates)
    centre: vec2<f32>, // the image centre (width · 0.5, height · 0.5)
    turned_round: u32, // 1: the far end's pass (x mirrored, depth z_origin − z, back to front)
    pixel_size: f32,   // the grid's pixel size (world units): a light's travel per slab is (drift · pixel_size, slab_distance)
    scale: f32,        // grid pixels per image pixel of offset at any depth (orthographic; 0 perspective)
    _pad2: u32,
}

@group(0) @binding(36) var<uniform> eye_params: EyeParams;
// The grid's layer cursors at the slab's front (their inside masks), and its LDI's offsets and
// fragment meta (which thin shells a grid pixel has crossed).
@group(0) @binding(37) var<storage, read> grid_cursors: array<Cursor>;
@group(0) @binding(38) var<storage, read> grid_offsets: array<u32>;
@group(0) @binding(39) var<storage, read> grid_frag_meta: array<u32>;

// A point or spot light's grid (`EyePoint`, `PointShading`): the eye reads the grid
// projectively and shades each sample with the direction to the light and the light its centre
// gives there (eye.wgsl `point_terms`); `on` = 0 elsewhere.
struct PointParams {
    on: u32,
    spot: u32,           // 1: a spot (axis, inner, outer)
    pattern: u32,        // 1: a spot with a pattern (texels in `spot_pattern`)
    pixel_size: f32,     // world units per grid pixel of the eye's frame
    center: vec4<f32>,   // the light's centre, the eye's slab-grid frame (x, y, z); w: its radius² (the horizon's spread)
    color: vec4<f32>,
    axis: vec4<f32>,     // a spot's unit axis, camera space
    right: vec4<f32>,    // a pattern's right axis, camera space
    down: vec4<f32>,     // a pattern's down axis
    offset: vec2<f32>,   // the centre's offset from the view axis, cells of the eye's frame
    depth: f32,          // the centre's view depth
    focal: f32,          // the light grid's focal length times the eye frame's cell size
    frame_axis: vec2<f32>, // where the view axis meets the eye's frame, its grid pixels
    inner: f32,          // cos(cone_deg)
    outer: f32,          // cos(cone_deg + falloff_deg)
    pattern_size: vec2<f32>,   // the pattern's extent on the unit plane along the axis
    pattern_centre: vec2<f32>, // its centre there
    pattern_width: u32,
    pattern_height: u32,
    turned: u32,         // 1: a turned-round pass (a light behind every mesh)
    _pad1: u32,
    phase: array<vec4<f32>, MAX_MESHES>, // per mesh (1 − g², 1 + g², 2g, 0)
}

@group(0) @binding(40) var<uniform> point_params: PointParams;
// A spot's pattern: linear RGB per texel, row-major from the top row (one unused word without).
@group(0) @binding(41) var<storage, read> spot_pattern: array<f32>;
