//! OpenVDB textures (issue 44, item 1): files written by OpenVDB itself (Debian's
//! `python3-openvdb`, run with `/usr/bin/python3` in the test; `.ci/run` installs it), read
//! through `convshadow_io::vdb` and rendered by the binary; a sparse 512³ grid within
//! `--max-memory 2048`; malformed files refused with exit code 3, naming the file and the grid.
//!
//! The expected values are the constants the Python scripts write, not anything our code
//! computes. Without the module the tests that need it print a SKIP and pass, except under CI
//! (env `CI` set), where they fail.

use std::path::{Path, PathBuf};

use convshadow_io::vdb::load_vdb;

use crate::support;

/// Exit code of a bad input (docs/errors.md).
const BAD_INPUT: i32 = 3;

/// Debian's Python, whose `pyopenvdb` module `python3-openvdb` installs (not a pyenv one).
const PYTHON: &str = "/usr/bin/python3";

/// Whether `/usr/bin/python3` imports `pyopenvdb`; a loud SKIP when not, a failure under CI.
fn pyopenvdb() -> bool {
    let found = std::process::Command::new(PYTHON)
        .args(["-c", "import pyopenvdb"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        if std::env::var_os("CI").is_some() {
            panic!("pyopenvdb not found (required in CI: apt-get install python3-openvdb)");
        }
        eprintln!(
            "SKIP: pyopenvdb not found (apt-get install python3-openvdb); the OpenVDB files \
             were not written"
        );
    }
    found
}

/// Runs `script` with OpenVDB's Python module in `dir` (`import pyopenvdb as vdb` prepended).
fn openvdb(dir: &Path, script: &str) {
    let out = std::process::Command::new(PYTHON)
        .args(["-c", &format!("import pyopenvdb as vdb\n{script}")])
        .current_dir(dir)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "the OpenVDB script failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Six known voxels across leaves (negative coordinates too) and one active 8³ tile in the
/// grid `density`; `shifted` with voxel size (0.5, 0.25, 2) and a translation; a grid saved as
/// half floats, a vector grid and a rotated grid, which are refused.
const KNOWN: &str = r#"
g = vdb.FloatGrid()
g.name = "density"
a = g.getAccessor()
for ijk, v in [((0, 0, 0), 0.25), ((5, 3, 1), 0.5), ((-7, 12, 9), 0.75), ((20, -4, 33), 1.0),
               ((9, 9, 9), 0.125), ((33, 17, -2), 0.625)]:
    a.setValueOn(ijk, v)
g.fill((40, 40, 40), (47, 47, 47), 0.375, True)
s = vdb.FloatGrid()
s.name = "shifted"
s.transform = vdb.createLinearTransform([[0.5, 0, 0, 0], [0, 0.25, 0, 0], [0, 0, 2, 0], [1, 2, 3, 1]])
s.getAccessor().setValueOn((1, 2, 3), 0.5)
s.getAccessor().setValueOn((4, 2, 3), 0.875)
h = vdb.FloatGrid()
h.name = "half"
h.saveFloatAsHalf = True
h.getAccessor().setValueOn((3, 4, 5), 0.25)
h.getAccessor().setValueOn((-3, 4, 5), 1.5)
v = vdb.Vec3SGrid()
v.name = "velocity"
v.getAccessor().setValueOn((0, 0, 0), (1, 2, 3))
r = vdb.FloatGrid()
r.name = "rotated"
r.transform = vdb.createLinearTransform([[0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
r.getAccessor().setValueOn((0, 0, 0), 1.0)
vdb.write("known.vdb", grids=[g, s, h, v, r])
"#;

/// A scene of one box filled with `file`'s grid `grid`, `size` pixels square, `slabs` slabs.
fn vdb_scene(file: &str, grid: &str, size: u32, slabs: u32) -> String {
    format!(
        r#"
[image]
width = {size}
height = {size}
[camera]
view_width = 3.0
[sweep]
slabs = {slabs}
[[light]]
tilt_deg = [20.0, 10.0]
variance = [0.02, 0.02]
[[mesh]]
shape = "box"
size = [2.0, 2.0, 2.0]
material = "cloud"
[material.cloud]
texture = {{ path = "{file}", grid = "{grid}" }}
gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1.0, 0.9]]
"#
    )
}

#[test]
fn an_openvdb_file_reads_its_known_voxels() {
    if !pyopenvdb() {
        return;
    }
    let dir = support::temp_dir("vdb-known");
    openvdb(&dir, KNOWN);
    let path = dir.join("known.vdb");
    let t = load_vdb(&path, "density").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((t.bbox_min, t.bbox_max), ([-7, -4, -2], [47, 47, 47]));
    assert_eq!(t.texture.dims, [55, 52, 50]);
    assert_eq!(t.voxel_size, [1.0; 3]);
    assert_eq!(
        (t.active_voxels, t.tiles, t.file_version),
        (6 + 512, 1, 224)
    );
    let at = |p: [i32; 3]| {
        t.texture
            .voxel([0, 1, 2].map(|a| (p[a] - t.bbox_min[a]) as u32))
    };
    for (p, v) in [
        ([0, 0, 0], 0.25),
        ([5, 3, 1], 0.5),
        ([-7, 12, 9], 0.75),
        ([20, -4, 33], 1.0),
        ([9, 9, 9], 0.125),
        ([33, 17, -2], 0.625),
        // Inside the active tile, and an inactive voxel (the background).
        ([43, 44, 45], 0.375),
        ([47, 40, 41], 0.375),
        ([1, 1, 1], 0.0),
    ] {
        assert_eq!(at(p), v, "voxel {p:?}");
    }
    // Only bricks holding values take memory: the background brick, one brick per voxel (no
    // two share a brick of the box's brick grid, which starts at the box's corner) and the 8
    // bricks the tile's 8³ voxels straddle on that grid.
    assert_eq!(t.texture.pool.len(), (1 + 6 + 8) * 512);

    let s = load_vdb(&path, "shifted").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.voxel_size, [0.5, 0.25, 2.0]);
    assert_eq!((s.bbox_min, s.bbox_max), ([1, 2, 3], [4, 2, 3]));
    assert_eq!(s.texture.dims, [4, 1, 1]);
    assert_eq!(s.extent(), [2.0, 0.25, 2.0]);
    assert_eq!(s.texture.voxel([0, 0, 0]), 0.5);
    assert_eq!(s.texture.voxel([3, 0, 0]), 0.875);
    assert_eq!(s.texture.voxel([1, 0, 0]), 0.0);

    let need = convshadow_io::vdb::memory_need(&path, "density").unwrap();
    assert!(need >= t.texture.bytes(), "{need} < {}", t.texture.bytes());

    for (grid, says) in [
        ("velocity", "grid type `Tree_vec3s_5_4_3`: only float grids"),
        (
            "half",
            "a float grid saved as half floats, which vdb-rs 0.6 does not read",
        ),
        ("rotated", "cannot read the grid"),
        (
            "nope",
            "no grid of that name; the file's grids: `density`, `half`, `rotated`, `shifted`, \
             `velocity`",
        ),
    ] {
        let e = load_vdb(&path, grid).unwrap_err().to_string();
        assert!(
            e.contains("known.vdb") && e.contains(&format!("texture.grid `{grid}`: {says}")),
            "{grid}: {e}"
        );
    }
}

#[test]
fn a_scene_with_an_openvdb_texture_renders() {
    if !pyopenvdb() {
        return;
    }
    let dir = support::temp_dir("vdb-render");
    openvdb(&dir, KNOWN);
    std::fs::write(
        dir.join("s.toml"),
        vdb_scene("known.vdb", "density", 48, 24),
    )
    .unwrap();
    let (code, _, err) = support::run_cli(&["render", "s.toml", "-o", "s.png"], &dir);
    assert_eq!(code, 0, "{err}");
    assert!(dir.join("s.png").is_file());
    // A grid the scene names that is not there: exit code 3, the file and the key named.
    std::fs::write(dir.join("bad.toml"), vdb_scene("known.vdb", "dens", 48, 24)).unwrap();
    let (code, _, err) = support::run_cli(&["render", "bad.toml", "-o", "b.png"], &dir);
    assert_eq!(code, BAD_INPUT, "{err}");
    assert!(
        err.contains("known.vdb") && err.contains("texture.grid `dens`: no grid of that name"),
        "{err}"
    );
}

/// A 512³ grid with about 1 % of its voxels active (4096 boxes of 7³ voxels on a 32-voxel
/// lattice, and two voxels at opposite corners, so the active box is the whole 512³) renders
/// under `--max-memory 2048`, and its peak RSS stays below what the dense box alone would take
/// (512 MiB of f32).
#[test]
fn a_sparse_512_cubed_grid_renders_within_max_memory_2048() {
    if !pyopenvdb() {
        return;
    }
    let dir = support::temp_dir("vdb-sparse");
    openvdb(
        &dir,
        r#"
g = vdb.FloatGrid()
g.name = "density"
for i in range(16):
    for j in range(16):
        for k in range(16):
            o = (32 * i + 3, 32 * j + 3, 32 * k + 3)
            g.fill(o, (o[0] + 6, o[1] + 6, o[2] + 6), 0.5 + 0.03 * ((i + j + k) % 16), True)
g.getAccessor().setValueOn((0, 0, 0), 1.0)
g.getAccessor().setValueOn((511, 511, 511), 1.0)
assert g.activeVoxelCount() == 4096 * 343 + 2
vdb.write("sparse.vdb", grids=[g])
"#,
    );
    let active = 4096.0 * 343.0 + 2.0;
    let share = active / 512.0f64.powi(3);
    assert!((0.0095..0.0115).contains(&share), "{share}");
    std::fs::write(
        dir.join("s.toml"),
        vdb_scene("sparse.vdb", "density", 64, 16),
    )
    .unwrap();
    let (code, err, peak_kib) = crate::reliability::run_measured(
        &[
            "render",
            "s.toml",
            "-o",
            "s.png",
            "--max-memory",
            "2048",
            "--threads",
            "2",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{err}");
    let peak_mib = peak_kib / 1024;
    eprintln!(
        "sparse 512³ grid, {:.2} % active: peak RSS {peak_mib} MiB",
        100.0 * share
    );
    assert!(peak_mib < 2048, "peak RSS {peak_mib} MiB");
    assert!(
        peak_mib < 512,
        "peak RSS {peak_mib} MiB: the dense box alone would be 512 MiB"
    );
}

/// The committed gallery file (written by scripts/cloud_vdb.py through OpenVDB).
fn cloud() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cloud.vdb")
}

#[test]
fn malformed_openvdb_files_are_refused_naming_the_file_and_grid() {
    let dir = support::temp_dir("vdb-bad");
    let good = std::fs::read(cloud()).unwrap();
    let scene = |name: &str| {
        std::fs::write(dir.join("s.toml"), vdb_scene(name, "density", 16, 4)).unwrap();
        let (code, _, err) = support::run_cli(&["render", "s.toml", "-o", "s.png"], &dir);
        assert_eq!(code, BAD_INPUT, "{name}: {err}");
        assert!(
            err.contains(name) && err.contains("texture.grid `density`"),
            "{name}: {err}"
        );
        assert!(!err.contains("panicked"), "{name}: {err}");
        err
    };
    // Truncated anywhere: in the header, the grid descriptors, the topology, the leaf data.
    for cut in [0, 7, 11, 60, 200, 400, 2000, good.len() / 2, good.len() - 1] {
        std::fs::write(dir.join("cut.vdb"), &good[..cut]).unwrap();
        scene("cut.vdb");
    }
    let mut bad = good.clone();
    bad[0] = b'X';
    std::fs::write(dir.join("magic.vdb"), &bad).unwrap();
    assert!(scene("magic.vdb").contains("not an OpenVDB file"));
    let mut bad = good.clone();
    bad[8..12].copy_from_slice(&300u32.to_le_bytes());
    std::fs::write(dir.join("version.vdb"), &bad).unwrap();
    assert!(scene("version.vdb").contains("file format version 300"));
    std::fs::write(dir.join("empty.vdb"), b"").unwrap();
    scene("empty.vdb");
    // Damaged length fields (vdb-rs sized its buffers from them unchecked: the process aborted
    // on a 64 GiB allocation, found by the vdb_load fuzz target; third_party/vdb-rs/PATCHED.md).
    // The first leaf's blosc block: a header of version 2, version-lz 1, flags, type size 4 and
    // 2048 uncompressed bytes (512 floats), after its compressed length (i64).
    let block = (8..good.len() - 8)
        .find(|&i| {
            good[i] == 2
                && good[i + 1] == 1
                && good[i + 3] == 4
                && good[i + 4..i + 8] == [0, 8, 0, 0]
        })
        .expect("a blosc block of a full leaf in cloud.vdb");
    let length = i64::from_le_bytes(good[block - 8..block].try_into().unwrap());
    assert!(
        (16..2048 + 16).contains(&length),
        "the block's length {length}"
    );
    let mut bad = good.clone();
    bad[block - 8..block].copy_from_slice(&(1i64 << 36).to_le_bytes());
    std::fs::write(dir.join("length.vdb"), &bad).unwrap();
    assert!(scene("length.vdb").contains("Invalid length 68719476736"));
    // The block's header claiming 2 GiB of values for the leaf's 512.
    let mut bad = good.clone();
    bad[block + 4..block + 8].copy_from_slice(&0x7fff_fff0u32.to_le_bytes());
    std::fs::write(dir.join("nbytes.vdb"), &bad).unwrap();
    scene("nbytes.vdb");
    // A grid name the file does not have.
    std::fs::copy(cloud(), dir.join("other.vdb")).unwrap();
    std::fs::write(dir.join("g.toml"), vdb_scene("other.vdb", "smoke", 16, 4)).unwrap();
    let (code, _, err) = support::run_cli(&["render", "g.toml", "-o", "g.png"], &dir);
    assert_eq!(code, BAD_INPUT, "{err}");
    assert!(
        err.contains("other.vdb")
            && err.contains(
                "texture.grid `smoke`: no grid of that name; the file's grids: \
                             `density`"
            ),
        "{err}"
    );
    // The scene keys: `grid` is required, and only for .vdb; `dims`, `type`, `window` refused.
    for (texture, key) in [
        ("{ path = \"other.vdb\" }", "texture.grid"),
        (
            "{ path = \"x.raw\", dims = [2, 2, 2], type = \"u8\", grid = \"d\" }",
            "texture.grid",
        ),
        (
            "{ path = \"other.vdb\", grid = \"density\", window = [0.0, 1.0] }",
            "texture",
        ),
    ] {
        let text = vdb_scene("other.vdb", "density", 16, 4)
            .replace("{ path = \"other.vdb\", grid = \"density\" }", texture);
        std::fs::write(dir.join("k.toml"), text).unwrap();
        let (code, _, err) = support::run_cli(&["render", "k.toml", "-o", "k.png"], &dir);
        assert_eq!(code, BAD_INPUT, "{texture}: {err}");
        assert!(
            err.contains(&format!("material.cloud.{key}")),
            "{texture}: {err}"
        );
    }
}
