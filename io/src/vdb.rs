//! OpenVDB volumes (`.vdb`) as sparse 3D textures, read through the `vdb-rs` crate: one float
//! grid by name, its active voxels and active tiles copied into 8³ bricks
//! ([`BrickedTexture3d`]), so memory follows the active voxels, not the bounding box.
//!
//! What is read: file versions 222 to 224 (OpenVDB 3 to 12 write 224), uncompressed, zip or
//! blosc data, float grids (`Tree_float_5_4_3`; not saved as half floats) with a scale or
//! scale-and-translate transform. The texture covers the grid's active voxel bounding box in
//! index space; its physical extent (box × voxel size) is fitted into the mesh's object-space
//! box like a NIfTI volume's. Active voxels and active tiles carry their values; everything
//! else reads 0, the background of a fog volume (level sets, whose background is not 0, are
//! refused by their grid class).
//!
//! `vdb-rs` 0.6 panics on some malformed input (an unknown transform, a failed assertion);
//! those panics are caught here (silently: the error names the file and the grid) and
//! returned as errors. It may still abort the process on a length field so large its
//! allocation fails (see docs/scene-format.md).

use std::cell::Cell;
use std::io::{BufReader, Read};
use std::panic::AssertUnwindSafe;
use std::path::Path;
use std::sync::Once;
use std::sync::atomic::{AtomicBool, Ordering};

use vdb_rs::{Grid, Map, MetadataValue, VdbReader};

use convshadow_common::pixel::texture3d::{MAX_ABS_VOXEL, TextureError};
use convshadow_common::pixel::volume::{
    BRICK, BRICK_VOXELS, BrickedTexture3d, MAX_BRICK_SLOTS, MAX_BRICKED_DIM, brick_grid,
};

/// The oldest file version read: per-node compression metadata (OpenVDB 3.0, 2014), which the
/// tile values read here rely on.
pub const MIN_FILE_VERSION: u32 = 222;
/// The newest file version read (the one OpenVDB 10 to 12 write).
pub const MAX_FILE_VERSION: u32 = 224;
/// The grid type read: a float tree of the standard 5-4-3 configuration (saved with full floats:
/// vdb-rs 0.6 fails on `Tree_float_5_4_3_HalfFloat`).
pub const FLOAT_GRID: &str = "Tree_float_5_4_3";

/// An OpenVDB grid loaded as a bricked texture, with what the file said of it.
#[derive(Clone, Debug)]
pub struct VdbTexture {
    /// The active box's voxels in 8³ bricks; voxel (0, 0, 0) is index `bbox_min`.
    pub texture: BrickedTexture3d,
    /// Voxel size along x, y, z (from the grid's transform).
    pub voxel_size: [f64; 3],
    /// Smallest index-space coordinate of an active voxel or tile.
    pub bbox_min: [i32; 3],
    /// Largest index-space coordinate of an active voxel or tile.
    pub bbox_max: [i32; 3],
    /// Active voxels, tiles counted by their voxels.
    pub active_voxels: u64,
    /// Leaf nodes read.
    pub leaves: u64,
    /// Active tiles read (8³ and 128³).
    pub tiles: u64,
    /// The file's format version.
    pub file_version: u32,
}

impl VdbTexture {
    /// The physical extent `dims · voxel size`, which the texture's mapping keeps the aspect of.
    pub fn extent(&self) -> [f64; 3] {
        [0, 1, 2].map(|a| f64::from(self.texture.dims[a]) * self.voxel_size[a])
    }
}

/// The error for `path`'s grid `grid`.
fn vdb_err(path: &Path, grid: &str, message: impl Into<String>) -> TextureError {
    TextureError::Vdb {
        path: path.to_path_buf(),
        message: format!("texture.grid `{grid}`: {}", message.into()),
    }
}

thread_local! {
    /// Set while `vdb-rs` runs on this thread: its panics are caught and reported as errors,
    /// so the panic hook keeps quiet about them.
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f` (a `vdb-rs` call), turning a panic into `Err(message)` without the panic hook's
/// report on stderr; panics elsewhere (other threads, or this one outside `f`) are reported as
/// before.
fn caught<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let r = std::panic::catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    r.map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "the reader failed".to_string())
    })
}

/// Checks the file's magic number and format version before `vdb-rs` parses it (it checks
/// neither reliably), and that it is a regular file.
fn check_header(path: &Path, grid: &str) -> Result<u32, TextureError> {
    crate::input::check_regular(path).map_err(|source| TextureError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut head = Vec::with_capacity(12);
    std::fs::File::open(path)
        .and_then(|f| f.take(12).read_to_end(&mut head))
        .map_err(|source| TextureError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    if head.len() < 12 || head[..8] != [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0] {
        return Err(vdb_err(
            path,
            grid,
            "not an OpenVDB file (no magic number 0x56444220 \" BDV\" at its start, or \
             shorter than its header)",
        ));
    }
    let version = u32::from_le_bytes([head[8], head[9], head[10], head[11]]);
    if !(MIN_FILE_VERSION..=MAX_FILE_VERSION).contains(&version) {
        return Err(vdb_err(
            path,
            grid,
            format!(
                "file format version {version}: versions {MIN_FILE_VERSION} to \
                 {MAX_FILE_VERSION} are read (OpenVDB 3 to 12)"
            ),
        ));
    }
    Ok(version)
}

/// Opens the file and finds the grid's descriptor: its metadata, checked to be a float grid
/// that is not an instance of another and not a level set.
fn open(
    path: &Path,
    grid: &str,
) -> Result<(VdbReader<BufReader<std::fs::File>>, u32), TextureError> {
    let version = check_header(path, grid)?;
    let file = std::fs::File::open(path).map_err(|source| TextureError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let reader = caught(|| VdbReader::new(BufReader::new(file)))
        .map_err(|p| vdb_err(path, grid, format!("not a valid OpenVDB file: {p}")))?
        .map_err(|e| vdb_err(path, grid, format!("not a valid OpenVDB file: {e}")))?;
    let Some(d) = reader.grid_descriptors.get(grid) else {
        let mut names = reader.available_grids();
        names.sort();
        return Err(vdb_err(
            path,
            grid,
            format!(
                "no grid of that name; the file's grids: {}",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            ),
        ));
    };
    if d.grid_type == format!("{FLOAT_GRID}_HalfFloat") {
        return Err(vdb_err(
            path,
            grid,
            "a float grid saved as half floats, which vdb-rs 0.6 does not read; save it with \
             full floats (OpenVDB: saveFloatAsHalf off)",
        ));
    }
    if d.grid_type != FLOAT_GRID {
        return Err(vdb_err(
            path,
            grid,
            format!(
                "grid type `{}`: only float grids ({FLOAT_GRID}) are read",
                d.grid_type
            ),
        ));
    }
    if !d.instance_parent.is_empty() {
        return Err(vdb_err(
            path,
            grid,
            format!(
                "an instance of grid `{}` (shared trees are not read)",
                d.instance_parent
            ),
        ));
    }
    if let Some(MetadataValue::String(class)) = d.meta_data.0.get("class")
        && class == "level set"
    {
        return Err(vdb_err(
            path,
            grid,
            "a level set (grid class `level set`): its background is not 0; convert it to a \
             fog volume first (OpenVDB's sdfToFogVolume)",
        ));
    }
    Ok((reader, version))
}

/// The grid's metadata integer `name` (OpenVDB writes `file_voxel_count` and `file_mem_bytes`).
fn meta_i64(reader: &VdbReader<BufReader<std::fs::File>>, grid: &str, name: &str) -> Option<i64> {
    match reader.grid_descriptors.get(grid)?.meta_data.0.get(name)? {
        MetadataValue::I64(v) => Some(*v),
        MetadataValue::I32(v) => Some(i64::from(*v)),
        _ => None,
    }
}

/// The grid's metadata box `file_bbox_min`..`file_bbox_max`.
fn meta_bbox(
    reader: &VdbReader<BufReader<std::fs::File>>,
    grid: &str,
) -> Option<([i64; 3], [i64; 3])> {
    let meta = &reader.grid_descriptors.get(grid)?.meta_data.0;
    let v = |k: &str| match meta.get(k)? {
        MetadataValue::Vec3i(v) => Some([v.x, v.y, v.z].map(i64::from)),
        _ => None,
    };
    Some((v("file_bbox_min")?, v("file_bbox_max")?))
}

/// Bytes a load of `grid` from `path` needs at most, from the file's metadata (without reading
/// the tree): `vdb-rs`'s tree (`file_mem_bytes`, OpenVDB's own count of the grid's memory),
/// the brick table over the active box (`file_bbox_min/max`) and a pool of one brick per
/// active voxel (`file_voxel_count`) or per brick of the box, whichever is fewer. `None` when
/// the file or its metadata cannot be read.
pub fn memory_need(path: &Path, grid: &str) -> Option<u64> {
    let (reader, _) = open(path, grid).ok()?;
    let tree = u64::try_from(meta_i64(&reader, grid, "file_mem_bytes")?).ok()?;
    let active = u64::try_from(meta_i64(&reader, grid, "file_voxel_count")?).ok()?;
    let (lo, hi) = meta_bbox(&reader, grid)?;
    let dims: Vec<u32> = (0..3)
        .map(|a| u32::try_from(hi[a] - lo[a] + 1).ok())
        .collect::<Option<_>>()?;
    let (_, bricks) = brick_grid([dims[0], dims[1], dims[2]])?;
    let slots = 1 + bricks.min(active);
    Some(
        tree.saturating_add(4 * bricks)
            .saturating_add(slots.saturating_mul(4 * BRICK_VOXELS as u64)),
    )
}

/// The grid's voxels along x, y, z and voxel size, for `slabs = "auto"` (the whole grid is
/// read: the voxel size is in its transform).
pub fn grid_info(path: &Path, grid: &str) -> Result<([u32; 3], [f64; 3]), TextureError> {
    let t = load_vdb(path, grid)?;
    Ok((t.texture.dims, t.voxel_size))
}

/// Loads grid `grid` of the OpenVDB file `path` as a bricked texture (see the module
/// documentation); errors name the file and the grid.
pub fn load_vdb(path: &Path, grid: &str) -> Result<VdbTexture, TextureError> {
    load_vdb_cancellable(path, grid, None)
}

/// The voxel size of a transform `vdb-rs` read, each finite and positive.
fn voxel_size(path: &Path, grid: &str, map: &Map) -> Result<[f64; 3], TextureError> {
    let v = match map {
        Map::UniformScaleMap { voxel_size, .. } | Map::ScaleTranslateMap { voxel_size, .. } => {
            [voxel_size.x, voxel_size.y, voxel_size.z]
        }
    };
    if v.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(vdb_err(
            path,
            grid,
            format!("voxel size {v:?}: expected finite sizes above 0"),
        ));
    }
    Ok(v.map(f64::abs))
}

/// One run of active values: a leaf's active voxels, or a constant tile.
enum Run<'a> {
    /// A leaf: its origin, its 512 values (z fastest, as OpenVDB stores them) and which are
    /// active.
    Leaf([i64; 3], &'a [f32], Vec<usize>),
    /// A tile of `size`³ voxels of one value.
    Tile([i64; 3], i64, f32),
}

/// Every leaf's active voxels and every active tile below the root (`vdb-rs` 0.6 drops root
/// tiles, which the voxel count check then reports).
fn runs(tree: &Grid<f32>) -> Vec<Run<'_>> {
    let mut out = Vec::new();
    for root in &tree.tree.root_nodes {
        let r = [root.origin.x, root.origin.y, root.origin.z].map(i64::from);
        for idx in root.value_mask.iter_ones() {
            if !root.child_mask[idx]
                && let Some(&v) = root.data.get(idx)
            {
                let i = idx as i64;
                let o = [
                    r[0] + (i >> 10) * 128,
                    r[1] + ((i >> 5) & 31) * 128,
                    r[2] + (i & 31) * 128,
                ];
                out.push(Run::Tile(o, 128, v));
            }
        }
        for idx in root.child_mask.iter_ones() {
            let Some(n4) = root.nodes.get(&(idx as u32)) else {
                continue;
            };
            let o4 = [n4.origin.x, n4.origin.y, n4.origin.z].map(i64::from);
            for i in n4.value_mask.iter_ones() {
                if !n4.child_mask[i]
                    && let Some(&v) = n4.data.get(i)
                {
                    let i = i as i64;
                    let o = [
                        o4[0] + (i >> 8) * 8,
                        o4[1] + ((i >> 4) & 15) * 8,
                        o4[2] + (i & 15) * 8,
                    ];
                    out.push(Run::Tile(o, 8, v));
                }
            }
            for i in n4.child_mask.iter_ones() {
                if let Some(leaf) = n4.nodes.get(&(i as u32))
                    && leaf.buffer.len() == BRICK_VOXELS
                {
                    let on: Vec<usize> = leaf.value_mask.iter_ones().collect();
                    let o = [leaf.origin.x, leaf.origin.y, leaf.origin.z].map(i64::from);
                    out.push(Run::Leaf(o, &leaf.buffer, on));
                }
            }
        }
    }
    out
}

/// Each active voxel of a run: its index-space coordinates and value.
fn each_voxel(
    run: &Run<'_>,
    f: &mut dyn FnMut([i64; 3], f32) -> Result<(), TextureError>,
) -> Result<(), TextureError> {
    match run {
        Run::Leaf(o, values, on) => {
            for &k in on {
                let i = k as i64;
                f(
                    [o[0] + (i >> 6), o[1] + ((i >> 3) & 7), o[2] + (i & 7)],
                    values[k],
                )?;
            }
        }
        Run::Tile(o, s, v) => {
            let s = *s;
            for z in 0..s {
                for y in 0..s {
                    for x in 0..s {
                        f([o[0] + x, o[1] + y, o[2] + z], *v)?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// The index-space box of a run's active voxels.
fn run_box(run: &Run<'_>) -> ([i64; 3], [i64; 3]) {
    match run {
        Run::Leaf(o, _, on) => {
            let mut lo = [i64::MAX; 3];
            let mut hi = [i64::MIN; 3];
            for &k in on {
                let k = k as i64;
                let p = [o[0] + (k >> 6), o[1] + ((k >> 3) & 7), o[2] + (k & 7)];
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            (lo, hi)
        }
        Run::Tile(o, size, _) => (*o, o.map(|c| c + size - 1)),
    }
}

/// [`load_vdb`] that stops with [`TextureError::Interrupted`] once `cancel` is raised (looked
/// at between leaves and tiles).
pub fn load_vdb_cancellable(
    path: &Path,
    grid: &str,
    cancel: Option<&AtomicBool>,
) -> Result<VdbTexture, TextureError> {
    let (mut reader, file_version) = open(path, grid)?;
    let listed_voxels = meta_i64(&reader, grid, "file_voxel_count");
    let tree = caught(|| reader.read_grid::<f32>(grid))
        .map_err(|p| vdb_err(path, grid, format!("cannot read the grid: {p}")))?
        .map_err(|e| vdb_err(path, grid, format!("cannot read the grid: {e}")))?;
    drop(reader);
    let voxel_size = voxel_size(path, grid, &tree.transform)?;
    let runs = runs(&tree);
    let interrupted = || TextureError::Interrupted {
        path: path.to_path_buf(),
    };
    let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
    let mut active = 0u64;
    let (mut leaves, mut tiles) = (0u64, 0u64);
    for run in &runs {
        match run {
            Run::Leaf(_, _, on) => {
                leaves += 1;
                active += on.len() as u64;
                if on.is_empty() {
                    continue;
                }
            }
            Run::Tile(_, size, _) => {
                tiles += 1;
                active += size.unsigned_abs().pow(3);
            }
        }
        let (a, b) = run_box(run);
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
    }
    if active == 0 {
        return Err(vdb_err(path, grid, "the grid has no active voxels"));
    }
    if let Some(listed) = listed_voxels
        && u64::try_from(listed).is_ok_and(|n| n > active)
    {
        return Err(vdb_err(
            path,
            grid,
            format!(
                "the file lists {listed} active voxels, {active} were read (active tiles at the \
                 root level, 4096³ voxels each, are not read by vdb-rs 0.6)"
            ),
        ));
    }
    let span: Vec<i64> = (0..3).map(|a| hi[a] - lo[a] + 1).collect();
    let too_big = || {
        vdb_err(
            path,
            grid,
            format!(
                "active voxels span {}x{}x{} (from {lo:?} to {hi:?}): expected at most \
                 {MAX_BRICKED_DIM} per axis and {} bricks of {BRICK}³ in all",
                span[0],
                span[1],
                span[2],
                convshadow_common::pixel::volume::MAX_TABLE_BRICKS
            ),
        )
    };
    if span.iter().any(|&s| s > i64::from(MAX_BRICKED_DIM)) {
        return Err(too_big());
    }
    let dims = [span[0] as u32, span[1] as u32, span[2] as u32];
    let (bricks, n) = brick_grid(dims).ok_or_else(too_big)?;
    let no_memory = |what: &str| {
        vdb_err(
            path,
            grid,
            format!("cannot allocate the {what} on this machine"),
        )
    };
    let mut table: Vec<u32> = Vec::new();
    table
        .try_reserve_exact(n as usize)
        .map_err(|_| no_memory(&format!("brick table ({n} bricks)")))?;
    table.resize(n as usize, 0);
    // Slot 0: the background brick.
    let mut pool = vec![0.0f32; BRICK_VOXELS];
    for run in &runs {
        if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(interrupted());
        }
        each_voxel(run, &mut |p, v| {
            if v.is_nan() || v.abs() > MAX_ABS_VOXEL {
                return Err(vdb_err(
                    path,
                    grid,
                    format!(
                        "voxel {p:?} is {v}, expected a finite value with magnitude <= \
                         {MAX_ABS_VOXEL:e}"
                    ),
                ));
            }
            // +0.0 is the background: its brick stays unallocated.
            if v.to_bits() == 0 {
                return Ok(());
            }
            let t = [0, 1, 2].map(|a| (p[a] - lo[a]) as u32);
            let b = t.map(|c| c / BRICK);
            let brick = (b[0] + bricks[0] * (b[1] + bricks[1] * b[2])) as usize;
            if table[brick] == 0 {
                let slot = pool.len() / BRICK_VOXELS;
                if slot >= MAX_BRICK_SLOTS {
                    return Err(vdb_err(
                        path,
                        grid,
                        format!("more than {MAX_BRICK_SLOTS} bricks of {BRICK}³ hold values"),
                    ));
                }
                pool.try_reserve(BRICK_VOXELS)
                    .map_err(|_| no_memory("brick pool"))?;
                pool.resize(pool.len() + BRICK_VOXELS, 0.0);
                table[brick] = slot as u32;
            }
            let l = t.map(|c| c % BRICK);
            pool[table[brick] as usize * BRICK_VOXELS
                + (l[0] + BRICK * l[1] + BRICK * BRICK * l[2]) as usize] = v;
            Ok(())
        })?;
    }
    drop(runs);
    drop(tree);
    let low = |a: usize| lo[a] as i32;
    let high = |a: usize| hi[a] as i32;
    Ok(VdbTexture {
        texture: BrickedTexture3d {
            dims,
            bricks,
            table,
            pool,
        },
        voxel_size,
        bbox_min: [low(0), low(1), low(2)],
        bbox_max: [high(0), high(1), high(2)],
        active_voxels: active,
        leaves,
        tiles,
        file_version,
    })
}
