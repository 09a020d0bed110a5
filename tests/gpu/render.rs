//! On lavapipe the GPU image is bit-identical to the CPU image (same `image_hash`, same alpha,
//! same final light buffers) for every example scene, every kernel, and scenes that reach every shader path
//! (3D and 4D noise of every kind, 3D textures, specular, jitter off, monochrome light, a fixed
//! guard band and an automatic one, different on each side, pre-integrated compositing), with the
//! iterated and the distance penumbra (every kernel family, volumes, a patterned light; the
//! distance penumbra's depth planes are part of the final light buffers compared). On other
//! adapters the images must stay within the thresholds of docs/gpu.md.

use crate::support;
use crate::support::gpu as gpu_common;

use convshadow::common::model::scene::GuardBandSpec;
use convshadow::common::model::scene::{Penumbra, Scene};
use convshadow::io::metrics::compare;
use convshadow::pipeline::{Backend, RenderRequest, Rendered, render};
use convshadow_gpu::GpuContext;

pub(crate) fn run(scene: &Scene, backend: Backend) -> Rendered {
    let req = RenderRequest {
        backend,
        threads: 2,
        allow_open: true,
        // The GPU sweeps every slab: so must the CPU for their final light buffers to compare.
        every_slab: true,
        ..RenderRequest::default()
    };
    render(scene, &req).unwrap_or_else(|f| panic!("{}: {}", scene.source, f))
}

/// Renders on both backends and checks the contract for the adapter; returns the CPU render.
pub(crate) fn check(ctx: &GpuContext, scene: &Scene, what: &str) -> Rendered {
    let cpu = run(scene, Backend::Cpu);
    let gpu = run(scene, Backend::Gpu);
    assert_eq!(cpu.backend, "cpu");
    assert_eq!(gpu.backend, "gpu");
    assert!(gpu.adapter.is_some());
    assert_eq!(cpu.ldi_hash, gpu.ldi_hash, "{what}: ldi_hash");
    let m = compare(&cpu.image, &gpu.image).unwrap();
    eprintln!(
        "{what}: cpu {:016x} gpu {:016x}; max abs {:.3e}, RMSE {:.3e}, {} values differ, ULP \
         histogram {:?}",
        cpu.image_hash,
        gpu.image_hash,
        m.max_abs,
        m.rmse,
        m.values_differ,
        &m.ulp_histogram[..8]
    );
    if ctx.is_software() {
        assert_eq!(
            cpu.image_hash, gpu.image_hash,
            "{what}: on lavapipe the GPU image must be bit-identical ({} values differ, max abs {:e} at {:?})",
            m.values_differ, m.max_abs, m.max_abs_at
        );
        let light_differ = cpu
            .light
            .iter()
            .zip(&gpu.light)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(light_differ, 0, "{what}: final light buffers differ");
        assert_eq!(cpu.light.len(), gpu.light.len());
        // The alpha (the EXR's `A`) too.
        let bits = |a: &[f32]| a.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&cpu.alpha), bits(&gpu.alpha), "{what}: alpha differs");
    } else {
        let alpha_abs = cpu
            .alpha
            .iter()
            .zip(&gpu.alpha)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(alpha_abs <= 1e-3, "{what}: alpha max abs {alpha_abs}");
        assert!(m.rmse <= 1e-4, "{what}: RMSE {}", m.rmse);
        assert!(m.max_abs <= 1e-3, "{what}: max abs {}", m.max_abs);
        assert!(
            m.srgb8_fraction() <= 1e-3,
            "{what}: {} 8-bit pixels differ",
            m.srgb8_pixels_differ
        );
        assert!(
            m.srgb8_max_diff <= 1,
            "{what}: 8-bit difference {}",
            m.srgb8_max_diff
        );
    }
    // A render that shows nothing would pass trivially: require some structure.
    let lo = cpu.image.data.iter().cloned().fold(f32::INFINITY, f32::min);
    let hi = cpu
        .image
        .data
        .iter()
        .cloned()
        .fold(f32::NEG_INFINITY, f32::max);
    assert!(hi - lo > 0.05, "{what}: the image is flat ({lo}..{hi})");
    cpu
}

/// `scene` with `sweep.penumbra = "distance"` (re-validated).
fn with_distance(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.sweep.penumbra = Penumbra::Distance;
    s.revalidate().unwrap_or_else(|e| panic!("{e}"));
    s
}

/// [`check`] with the distance penumbra, after checks that it is live: the CPU image differs
/// from the iterated penumbra's (so the comparison is not of a path the mode skips), and the
/// final light buffers hold one depth plane per light after its channels, some of it non-zero
/// (occluders were recorded and read back from the device).
pub(crate) fn check_distance(ctx: &GpuContext, scene: &Scene, what: &str) {
    let mut iterated = scene.clone();
    iterated.sweep.penumbra = Penumbra::Iterated;
    let iterated = run(&iterated, Backend::Cpu);
    let cpu = check(
        ctx,
        &with_distance(scene),
        &format!("{what}, distance penumbra"),
    );
    assert_ne!(
        cpu.image_hash, iterated.image_hash,
        "{what}: the distance penumbra changed nothing"
    );
    let plan = &cpu.plan;
    assert_eq!(plan.penumbra, Penumbra::Distance);
    let (w, ch) = (plan.grid_width as usize, plan.channels as usize);
    let planes = ch + 1;
    assert_eq!(
        cpu.light.len(),
        plan.lights.len() * planes * w * plan.grid_height as usize,
        "{what}: light buffers of lights × (channels + 1 depth plane) × pixels"
    );
    let depth_nonzero = cpu
        .light
        .chunks(w)
        .enumerate()
        .filter(|(p, _)| p % planes == ch)
        .flat_map(|(_, plane)| plane)
        .filter(|&&d| d != 0.0)
        .count();
    assert!(depth_nonzero > 0, "{what}: every depth plane is 0");
}

#[test]
fn gpu_image_equals_cpu_on_every_example_scene() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    for path in gpu_common::example_scenes() {
        let scene = gpu_common::small(&path, 64, 32);
        check(&ctx, &scene, &path.display().to_string());
    }
}

#[test]
fn gpu_image_equals_cpu_for_every_kernel() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let mut scene = Scene::default_scene();
    gpu_common::shrink(&mut scene, 48, 24);
    for kernel in support::kernels() {
        scene.sweep.kernel = kernel.parse().unwrap();
        for compensate in [true, false] {
            scene.sweep.variance_compensation = compensate;
            check(
                &ctx,
                &scene,
                &format!("kernel {kernel}, compensation {compensate}"),
            );
        }
    }
}

/// A scene that reaches the shader paths the example scenes may not: every detail kind in 3D and
/// 4D, a 3D texture, specular highlights (Blinn–Phong and Ashikmin–Shirley, on opaque and
/// translucent crossings), Lambert and flat surfaces, phase functions (forward and backward), no jitter, a guard band and a grey (1-channel) or
/// coloured light buffer, a narrow light (mean carried in whole pixels).
pub(crate) fn path_scene(dir: &std::path::Path, monochrome: bool, jitter: bool) -> Scene {
    support::scene(&support::path_scene_text(dir, monochrome, jitter), dir)
}

#[test]
fn gpu_image_equals_cpu_with_open_meshes_as_thin_shells() {
    // An open square (a thin shell) and a closed box share a textured material (the shell's
    // variant reads the same uploaded voxels) and a detail material, over a wall.
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-shells");
    let voxels: Vec<u8> = (0..60u32).map(|i| (i * 53 % 256) as u8).collect();
    std::fs::write(dir.join("tex.raw"), &voxels).unwrap();
    std::fs::write(
        dir.join("square.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let text = r#"
[image]
width = 40
height = 36
[camera]
direction = [0.3, -0.2, 1.0]
view_width = 5.0
[sweep]
slabs = 24
[[light]]
tilt_deg = [-25.0, 15.0]
variance = [0.02, 0.01]
[[mesh]]
shape = "obj"
path = "square.obj"
translate = [-0.8, 0.0, -0.5]
rotate_deg = [30.0, 20.0, 0.0]
material = "tex"
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
translate = [1.0, 0.5, 0.0]
material = "tex"
[[mesh]]
shape = "obj"
path = "square.obj"
scale = 0.6
translate = [0.8, -1.0, -1.0]
material = "cloud"
[[mesh]]
shape = "box"
size = [6.0, 6.0, 0.3]
translate = [0.0, 0.0, 1.5]
material = "wall"
[material.tex]
texture = { path = "tex.raw", dims = [5, 4, 3], type = "u8" }
gradient = [[0.0, 1.0, 1.0, 1.0, 0.1], [1.0, 0.9, 0.6, 0.3, 0.9]]
[material.cloud]
detail = { kind = "fbm", frequency = 2.0, octaves = 3 }
gradient = [[0.0, 0.5, 0.7, 1.0, 0.2], [1.0, 1.0, 1.0, 1.0, 0.8]]
specular = { strength = 0.5, exponent = 8 }
[material.wall]
color = [0.8, 0.8, 0.75]
"#;
    let scene = support::scene(text, &dir);
    let g = convshadow_io::build_geometry(&scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(g.shell_meshes(), vec![0, 2], "the squares are shells");
    check(&ctx, &scene, "thin shells");
}

/// [`check`]s `scene`, and asserts that the CPU image of the scene with `turn_off` applied
/// differs (so what it turns off was exercised; else fails with `unchanged`).
fn check_and_changed_by(
    ctx: &GpuContext,
    scene: &Scene,
    what: &str,
    (turn_off, unchanged): (fn(&mut Scene), &str),
) {
    let with = check(ctx, scene, what);
    let mut without = scene.clone();
    turn_off(&mut without);
    let plain = run(&without, Backend::Cpu);
    assert_ne!(with.image_hash, plain.image_hash, "{what}: {unchanged}");
}

#[test]
fn gpu_image_equals_cpu_with_held_light_on_its_lit_side() {
    // `sweep.held_lit_side`: thin closed plates turned towards and away from the light (held,
    // their held light read only from the lit side: composite.wgsl `hides`, kernels.wgsl
    // `gather_held`), with the distance and the iterated penumbra; each image differs from the
    // one without it, so the held reads are exercised.
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-held-lit-side");
    for (turn, penumbra) in [
        (-60.0, "distance"),
        (-30.0, "distance"),
        (-60.0, "iterated"),
    ] {
        let text = format!(
            "[image]\nwidth = 48\nheight = 36\n[camera]\nview_width = 8.0\n[sweep]\nslabs = 96\n\
             penumbra = \"{penumbra}\"\noptimal_distance = 2.0\nheld_lit_side = true\n[[light]]\ntilt_deg = [-30.0, 10.0]\n\
             variance = [0.004, 0.004]\n[[mesh]]\nshape = \"box\"\nsize = [2.0, 2.0, 0.05]\n\
             rotate_deg = [0.0, {turn}, 0.0]\ntranslate = [-0.5, 0.0, 0.0]\nmaterial = \"clay\"\n\
             [[mesh]]\nshape = \"box\"\nsize = [12.0, 10.0, 0.2]\ntranslate = [0.0, 0.0, 2.6]\n\
             material = \"wall\"\n[material.clay]\ncolor = [0.85, 0.5, 0.32]\n\
             [material.wall]\ncolor = [0.85, 0.85, 0.8]\n"
        );
        let scene = support::scene(&text, &dir);
        let what = format!("plate turned {turn}°, {penumbra}");
        let off = |s: &mut Scene| s.sweep.held_lit_side = false;
        check_and_changed_by(&ctx, &scene, &what, (off, "no held read was hidden"));
    }
}

#[test]
fn gpu_image_equals_cpu_with_released_light_served_on_its_surface() {
    // `sweep.served_releases`: a plate turned 60° about x under an opaque half-plane, its
    // released pixels serving their light to its other pixels in the edge's penumbra
    // (composite.wgsl `keep_release` and `served`, kernels.wgsl `held_fetch`), with both
    // penumbrae, with and without `held_lit_side`, and at 1024 slabs (where the served age is
    // 16 slabs, not 8: `surface_hold::served_release_slabs`); each image differs from the one
    // without served releases, so the served reads are exercised.
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-served-releases");
    for (penumbra, lit_side, slabs) in [
        ("distance", false, 128),
        ("iterated", false, 128),
        ("distance", true, 128),
        ("distance", false, 1024),
    ] {
        let text = format!(
            "[image]\nwidth = 48\nheight = 48\n[camera]\nview_width = 2.0\n[sweep]\nslabs = {slabs}\n\
             penumbra = \"{penumbra}\"\noptimal_distance = 1.0\nheld_lit_side = {lit_side}\n\
             [[light]]\ntilt_deg = [-25.0, 15.0]\nvariance = [0.0025, 0.0025]\n\
             [[mesh]]\nshape = \"box\"\nsize = [4.0, 6.0, 0.02]\ntranslate = [2.0, 0.0, -2.08]\n\
             material = \"white\"\n[[mesh]]\nshape = \"box\"\nsize = [4.0, 6.0, 0.1]\n\
             rotate_deg = [60.0, 0.0, 0.0]\nmaterial = \"white\"\n\
             [material.white]\nopacity = 1.0\nsurface = \"flat\"\n"
        );
        let scene = support::scene(&text, &dir);
        let what = format!("60° receiver, {penumbra}, held_lit_side {lit_side}, {slabs} slabs");
        let off = |s: &mut Scene| s.sweep.served_releases = false;
        check_and_changed_by(&ctx, &scene, &what, (off, "no release was served"));
    }
}

#[test]
fn gpu_image_equals_cpu_on_every_shader_path() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-paths");
    for (monochrome, jitter) in [(false, true), (true, false)] {
        let mut scene = path_scene(&dir, monochrome, jitter);
        assert_eq!(scene.is_monochrome(), monochrome);
        check(
            &ctx,
            &scene,
            &format!("shader paths, monochrome {monochrome}, jitter {jitter}"),
        );
        // The automatic band: a different width on each side (the wall reaches beyond every
        // edge, the lights shift shadows unequally), so the grid origin and the image-keyed
        // hashes are offset differently in x and y.
        scene.sweep.guard_band = GuardBandSpec::Auto;
        let band = run(&scene, Backend::Cpu).plan.guard;
        assert!(
            band.left != band.right && band.top != band.bottom,
            "expected an asymmetric band, got {band}"
        );
        check(
            &ctx,
            &scene,
            &format!("shader paths, monochrome {monochrome}, jitter {jitter}, band {band}"),
        );
    }
}

#[test]
fn gpu_image_equals_cpu_with_preintegration() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-pre");
    // Every detail kind, a 3D texture, constant materials between them (their pixels forget the
    // kept front value), crossings in and out, a grey and a coloured light buffer.
    for (monochrome, jitter) in [(false, true), (true, false)] {
        let mut scene = path_scene(&dir, monochrome, jitter);
        scene.sweep.preintegration = true;
        check(
            &ctx,
            &scene,
            &format!("pre-integration, monochrome {monochrome}, jitter {jitter}"),
        );
    }
}

#[test]
fn gpu_image_equals_cpu_with_a_patterned_light() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-pattern");
    // A coloured 7×5 pattern (non-grey, so three light channels), smaller than the view, with
    // texels that do not align with pixels: bilinear samples, clamped edges.
    let gobo = gpu_common::write_gobo(&dir, (7, 5), (53, 11, 97));
    let mut scene = path_scene(&dir, true, true);
    scene.lights[0].pattern = Some(convshadow::common::model::scene::PatternSpec {
        path: gobo,
        size: [3.1, 2.3],
        center: [0.4, -0.3],
    });
    assert!(
        !scene.is_monochrome(),
        "a pattern takes three light channels"
    );
    check(&ctx, &scene, "patterned light");
}

#[test]
fn render_backend_gpu_without_scene_names_the_adapter() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-cli");
    let (code, out, err) = support::run_cli(
        &[
            "render",
            "--backend",
            "gpu",
            "--width",
            "48",
            "--height",
            "48",
            "--slabs",
            "16",
            "-o",
            "gpu.png",
            "--stats-json",
            "gpu.json",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains(&ctx.info.name),
        "the summary names the adapter: {out}"
    );
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("gpu.json")).unwrap()).unwrap();
    assert_eq!(stats["backend"], "gpu");
    assert!(stats["adapter"].as_str().unwrap().contains(&ctx.info.name));
    assert!(dir.join("gpu.png").is_file());
    let (code, out, err) = support::run_cli(
        &[
            "ldi",
            "--backend",
            "auto",
            "--width",
            "48",
            "--height",
            "48",
            "--stats-json",
            "ldi.json",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ldi.json")).unwrap()).unwrap();
    // `auto` passes over a software adapter unless it is named.
    let named = std::env::var_os(convshadow_gpu::device::ADAPTER_ENV).is_some();
    let expected = if ctx.is_software() && !named {
        "cpu"
    } else {
        "gpu"
    };
    assert_eq!(stats["backend"], expected, "{err}");
    assert!(stats["ldi_hash"].as_str().is_some_and(|h| h.len() == 16));
}

#[test]
fn auto_renders_on_the_cpu_when_the_only_adapter_is_software() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    if !ctx.is_software() || std::env::var_os(convshadow_gpu::device::ADAPTER_ENV).is_some() {
        eprintln!("SKIP: a hardware adapter (or a named one) is present: auto uses it");
        return;
    }
    let dir = support::temp_dir("gpu-auto-software");
    let json = dir.join("s.json");
    let flags = [
        "--size",
        "32x32",
        "--slabs",
        "8",
        "-o",
        "o.png",
        "--stats-json",
    ];
    let run = |backend: &str| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_convshadow"))
            .args(["render", "--backend", backend])
            .args(flags)
            .arg(&json)
            .current_dir(&dir)
            .env_remove(convshadow_gpu::device::ADAPTER_ENV)
            .output()
            .unwrap();
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
            stats,
        )
    };
    // Only lavapipe: `auto` renders on the CPU and says why.
    let (code, err, stats) = run("auto");
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(stats["backend"], "cpu", "{stats}");
    assert!(
        err.contains("is a software rasterizer") && err.contains("rendering on the CPU"),
        "{err}"
    );
    // `gpu` still runs there, and says that it is software.
    let (code, err, stats) = run("gpu");
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(stats["backend"], "gpu", "{stats}");
    assert!(err.contains("is a software rasterizer"), "{err}");
}

#[test]
fn auto_counts_the_memory_of_the_backend_it_picks() {
    use convshadow::pipeline::MemoryNeed;
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // `auto` takes a software adapter only when named: name it then, so `auto` opens a GPU.
    let name = ctx.info.name.clone();
    let auto_gpu = ctx.is_software().then_some(name.as_str());
    let dir = support::temp_dir("gpu-auto-budget");
    let text = "[image]\nwidth = 512\nheight = 512\n[camera]\nview_width = 3.0\n[sweep]\n\
                slabs = 8\noptimal_distance = 0.5\n[[mesh]]\nshape = \"box\"\n\
                size = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n[material.m]\nopacity = 0.5\n";
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let scene = convshadow_io::load_scene(&dir.join("s.toml")).unwrap();
    // The box lies inside the view: the automatic guard band is 0, its lower bound.
    let band = scene.sweep.guard_band.lower_bound();
    let cpu = MemoryNeed::for_backend(&scene, band, true, Backend::Cpu).total();
    let gpu = MemoryNeed::for_backend(&scene, band, true, Backend::Gpu).total();
    // A budget (whole MiB, as --max-memory takes it) between the two needs, leaving the CPU
    // several MiB for the box's fragments (about 60k of 17 bytes).
    let mib = (cpu + (gpu - cpu) / 2) >> 20;
    assert!(
        cpu + (4 << 20) <= mib << 20 && mib << 20 < gpu,
        "{cpu} {mib} MiB {gpu}"
    );
    let budget = mib.to_string();
    let args = |backend: &'static str| {
        [
            "render",
            "s.toml",
            "-o",
            "o.png",
            "-q",
            "--backend",
            backend,
            "--max-memory",
        ]
        .into_iter()
        .map(String::from)
        .chain([budget.clone()])
        .collect::<Vec<_>>()
    };
    let run = |backend: &'static str, adapter: Option<&str>| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_convshadow"));
        cmd.args(args(backend)).current_dir(&dir);
        if let Some(a) = adapter {
            cmd.env(convshadow_gpu::device::ADAPTER_ENV, a);
        }
        let out = cmd.output().unwrap();
        let _ = std::fs::remove_file(dir.join("o.png"));
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    // The CPU fits, the GPU is refused naming its device buffers.
    assert_eq!(run("cpu", None).0, Some(0));
    let (code, err) = run("gpu", None);
    assert_eq!(code, Some(4), "{err}");
    assert!(err.contains("GPU buffers"), "{err}");
    // `auto` with an adapter runs on the GPU, so it is counted (and refused) as the GPU.
    let (code, err) = run("auto", auto_gpu);
    assert_eq!(code, Some(4), "auto picked the GPU: {err}");
    assert!(
        err.contains("GPU buffers") && err.contains("--backend auto opened the GPU"),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "--backend cpu needs {} MiB",
            cpu.div_ceil(1 << 20)
        )),
        "{err}"
    );
    // `auto` without one (no adapter has this name) falls back to the CPU, and fits as the CPU.
    let (code, err) = run("auto", Some("no adapter is called this"));
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("rendering on the CPU"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn gpu_image_equals_cpu_with_the_distance_penumbra() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // The default scene (a cloud, a marble sphere, a wall; two coloured lights) with 40 slabs:
    // distance levels of one slab up to 16, of two from 32 (docs/gpu.md), so `level_of` maps
    // several distances to one level.
    let mut scene = Scene::default_scene();
    gpu_common::shrink(&mut scene, 48, 40);
    check_distance(&ctx, &scene, "default scene");
    // A volume of haze under a plate with a window, one hard light (grey: one channel).
    let shaft = gpu_common::small(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/shaft.toml"),
        48,
        32,
    );
    check_distance(&ctx, &shaft, "shaft scene");
    // Every shader path: 4D noise, a 3D texture, specular, three lights (one of zero variance),
    // 1- and 3-channel light, jitter on and off, a fixed and an automatic guard band.
    let dir = support::temp_dir("gpu-distance-paths");
    for (monochrome, jitter) in [(false, true), (true, false)] {
        let mut scene = path_scene(&dir, monochrome, jitter);
        check_distance(
            &ctx,
            &scene,
            &format!("shader paths, monochrome {monochrome}, jitter {jitter}"),
        );
        scene.sweep.guard_band = GuardBandSpec::Auto;
        check_distance(
            &ctx,
            &scene,
            &format!("shader paths, monochrome {monochrome}, jitter {jitter}, automatic band"),
        );
    }
}

#[test]
fn gpu_image_equals_cpu_with_subpixel_shadows_and_the_iterated_penumbra() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // All-opaque scenes under tilted lights: the iterated penumbra with a depth plane and its
    // kernel at every level, the crossing lanes read at their exact shift (the CPU image must
    // differ from the whole-pixel read's, so that path ran).
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in ["edge", "fence", "disk"] {
        let mut scene = gpu_common::small(&scenes.join(format!("{name}.toml")), 48, 40);
        scene.sweep.penumbra = Penumbra::Iterated;
        scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
        let cpu = check(
            &ctx,
            &scene,
            &format!("{name}, iterated, sub-pixel shadows"),
        );
        scene.sweep.subpixel_shadows = false;
        let carried = run(&scene, Backend::Cpu);
        assert_ne!(
            cpu.image_hash, carried.image_hash,
            "{name}: no pixel read at its shift"
        );
    }
}

#[test]
fn gpu_image_equals_cpu_with_the_distance_penumbra_for_every_kernel() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // Per-pixel, per-slab and scheduled phases (a schedule's phase is per level), with and
    // without variance compensation (the mean carried in whole pixels or not).
    let mut scene = Scene::default_scene();
    gpu_common::shrink(&mut scene, 40, 36);
    for (k, kernel) in support::kernels().into_iter().enumerate() {
        scene.sweep.kernel = kernel.parse().unwrap();
        scene.sweep.variance_compensation = k % 2 == 0;
        check_distance(
            &ctx,
            &scene,
            &format!(
                "kernel {kernel}, compensation {}",
                scene.sweep.variance_compensation
            ),
        );
    }
}

#[test]
fn gpu_image_equals_cpu_with_a_patterned_light_and_the_distance_penumbra() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-pattern-distance");
    let gobo = gpu_common::write_gobo(&dir, (5, 4), (41, 7, 89));
    let mut scene = path_scene(&dir, true, true);
    scene.lights[1].pattern = Some(convshadow::common::model::scene::PatternSpec {
        path: gobo,
        size: [2.7, 3.3],
        center: [-0.2, 0.5],
    });
    // The initial light buffer comes from the pattern, with the depth planes at 0.
    check_distance(&ctx, &scene, "patterned light");
}

#[test]
fn render_backend_gpu_with_the_distance_penumbra_matches_the_cpu() {
    let Some(_ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-cli-distance");
    let hash = |backend: &str| {
        let json = format!("{backend}.json");
        let (code, out, err) = support::run_cli(
            &[
                "render",
                "--backend",
                backend,
                "--penumbra",
                "distance",
                "--width",
                "40",
                "--height",
                "40",
                "--slabs",
                "20",
                "-o",
                &format!("{backend}.png"),
                "--stats-json",
                &json,
            ],
            &dir,
        );
        assert_eq!(code, 0, "{out}{err}");
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(&json)).unwrap()).unwrap();
        assert_eq!(stats["backend"], backend);
        assert_eq!(stats["penumbra"], "distance", "{stats}");
        stats["image_hash"].as_str().unwrap().to_string()
    };
    assert_eq!(hash("gpu"), hash("cpu"));
}

#[test]
fn the_renders_of_one_process_share_one_device() {
    // `GpuContext::shared`: every render opens the same device, so each pipeline is compiled
    // once per process (docs/gpu.md), not once per render.
    use convshadow::pipeline::BackendChoice;
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let again = convshadow_gpu::GpuContext::shared().unwrap();
    assert!(std::sync::Arc::ptr_eq(&ctx, &again));
    let choice = BackendChoice::open(Backend::Gpu).unwrap();
    let opened = choice.gpu.as_ref().expect("the GPU backend opens a device");
    assert!(std::sync::Arc::ptr_eq(&ctx, opened));
}
