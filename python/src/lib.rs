//! The `convshadow` Python module (docs/python.md): `render(scene, **overrides)` returns the
//! linear float image as a NumPy array and the numbers of `convshadow render --stats-json`;
//! `diff(a, b)` returns the numbers of `convshadow diff --json`; `load_image(path)` reads an EXR
//! or PNG as `diff` reads it. Failures raise `convshadow.Error`, whose `exit_code` is the one the
//! command line gives for the same failure.
//!
//! Everything the module does goes through the library the binary uses: the scene is parsed
//! by `Scene::parse` (a path by `convshadow_io::load_scene`), the overrides are
//! `convshadow::overrides` (the CLI's flags), the render `convshadow::pipeline::render` (or
//! `render_reference`), the stats `convshadow::stats::render_stats`, the comparison
//! `convshadow::diff::Comparison` and the exit codes `convshadow::exit_code`. This file only
//! converts between Python objects and those.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use convshadow::exit_code;
use convshadow::overrides::{self, OverrideError, RenderBackend, SweepOverrides};
use convshadow::pipeline::{CpuPath, RenderError, RenderRequest, Rendered};
use convshadow_common::model::scene::{GuardBandSpec, Media, Penumbra, Scene, SlabSpec};
use convshadow_io::image::RgbImage;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

create_exception!(
    convshadow,
    Error,
    PyException,
    "A render or a comparison failed. `str(e)` and `e.message` are the message the command \
     line prints; `e.exit_code` is the exit code it gives for the same failure (docs/errors.md: \
     2 a bad argument, 3 a bad scene or image, 4 a resource limit, 5 no GPU adapter, 6 open \
     meshes, 130 interrupted)."
);

/// A `convshadow.Error` with `message` and `exit_code`.
fn error(py: Python<'_>, exit_code: i32, message: impl Into<String>) -> PyErr {
    let message = message.into();
    let err = Error::new_err(message.clone());
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail but for memory.
    let _ = value.setattr("exit_code", exit_code);
    let _ = value.setattr("message", message);
    err
}

/// The `convshadow.Error` of a render's error, with the CLI's exit code.
fn render_error(py: Python<'_>, e: &RenderError) -> PyErr {
    error(py, exit_code::of_render_error(e), e.to_string())
}

/// A bad keyword argument's value (exit code 2, as the CLI's bad flag).
fn bad_argument(py: Python<'_>, name: &str, message: impl std::fmt::Display) -> PyErr {
    error(py, exit_code::BAD_ARGUMENTS, format!("{name}: {message}"))
}

/// The scene of `render`'s first argument: `None` (the embedded default scene), a path (`str`
/// without a newline or `=`, or `os.PathLike`), TOML text (`str` with a newline or `=`), or a
/// `dict` of the TOML's tables. Relative paths inside TOML text or a dict resolve against the
/// current folder, inside a file against the file's folder (as the CLI does).
fn load_scene(py: Python<'_>, scene: Option<&Bound<'_, PyAny>>) -> PyResult<Scene> {
    let bad_input = |e: &dyn std::fmt::Display| error(py, exit_code::BAD_INPUT, e.to_string());
    let Some(scene) = scene.filter(|s| !s.is_none()) else {
        return Ok(Scene::default_scene());
    };
    if let Ok(dict) = scene.cast::<PyDict>() {
        let table = toml_table(dict, "scene")?;
        let text = toml::to_string(&table).map_err(|e| bad_input(&e))?;
        return Scene::parse(&text, "<dict>", Path::new(".")).map_err(|e| bad_input(&e));
    }
    if let Ok(s) = scene.cast::<PyString>() {
        let s = s.to_cow()?;
        if s.contains('\n') || s.contains('=') {
            return Scene::parse(&s, "<string>", Path::new(".")).map_err(|e| bad_input(&e));
        }
    }
    if scene.is_instance_of::<PyString>() || scene.hasattr("__fspath__")? {
        let path: PathBuf = scene.extract()?;
        return convshadow_io::load_scene(&path).map_err(|e| bad_input(&e));
    }
    Err(PyTypeError::new_err(format!(
        "scene: expected a path, TOML text, a dict or None, got {}",
        scene.get_type().name()?
    )))
}

/// A Python dict as a TOML table (keys must be strings; values dicts, lists, tuples, str, bool,
/// int, float). `at` names the place for errors.
fn toml_table(dict: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
    let mut table = toml::Table::new();
    for (k, v) in dict.iter() {
        let key: String = k.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "{at}: keys must be str, got {}",
                k.repr().map_or_else(|_| "?".into(), |r| r.to_string())
            ))
        })?;
        let value = toml_value(&v, &format!("{at}.{key}"))?;
        table.insert(key, value);
    }
    Ok(table)
}

/// One Python value as a TOML value.
fn toml_value(v: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
    // bool before int: Python's bool is an int.
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(toml::Value::Boolean(b.is_true()));
    }
    if v.is_instance_of::<PyInt>() {
        let n: i64 = v.extract()?;
        return Ok(toml::Value::Integer(n));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_cow()?.into_owned()));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(toml_table(d, at)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v
            .try_iter()?
            .enumerate()
            .map(|(i, item)| toml_value(&item?, &format!("{at}[{i}]")))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    if v.hasattr("__fspath__")? {
        let p: PathBuf = v.extract()?;
        return Ok(toml::Value::String(p.display().to_string()));
    }
    Err(PyTypeError::new_err(format!(
        "{at}: a TOML value must be a dict, list, tuple, str, bool, int, float or path, got {}",
        v.get_type().name()?
    )))
}

/// A JSON value (the library's stats and metrics) as a Python object.
fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => py.None().into_bound(py),
        J::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        J::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.into_pyobject(py)?.into_any(),
            (None, Some(i)) => i.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        J::String(s) => PyString::new(py, s).into_any(),
        J::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        J::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// The keyword arguments of `render`, parsed with the CLI's parsers.
struct Options {
    width: Option<u32>,
    height: Option<u32>,
    sweep: SweepOverrides,
    threads: usize,
    backend: RenderBackend,
    path: CpuPath,
    samples: u32,
    budget: u64,
    allow_open: bool,
}

/// `str(value)` of an int or a str keyword argument, for the CLI's parser of that flag.
fn text_of(v: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    if v.is_instance_of::<PyBool>()
        || !(v.is_instance_of::<PyInt>() || v.is_instance_of::<PyString>())
    {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected an int or a str, got {}",
            v.get_type().name()?
        )));
    }
    Ok(v.str()?.to_cow()?.into_owned())
}

/// Runs `f` (a render) with the GIL released, on a thread of its own while this one checks
/// Python's signals every 50 ms: Ctrl-C raises `cancel`, and the signal's exception
/// (`KeyboardInterrupt`) is returned in place of the render's `Interrupted`.
fn detached<T: Send>(
    py: Python<'_>,
    cancel: &AtomicBool,
    f: impl FnOnce() -> Result<T, RenderError> + Send,
) -> PyResult<Result<T, RenderError>> {
    let mut signal: Option<PyErr> = None;
    let result = py.detach(|| {
        std::thread::scope(|s| {
            let worker = s.spawn(f);
            while !worker.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                if signal.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    signal = Some(e);
                    cancel.store(true, Ordering::Relaxed);
                }
            }
            worker.join()
        })
    });
    if let Some(e) = signal {
        return Err(e);
    }
    match result {
        Ok(r) => Ok(r),
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

/// Renders a scene; returns `(image, stats)`.
///
/// `image` is the linear float image, a NumPy float32 array of shape (height, width, 3): the
/// values `convshadow render -o out.exr` writes, bit for bit (exposure and the tone curve apply
/// to PNG only). `stats` is the dict of `convshadow render --stats-json` (less `outputs`), plus
/// `warnings` (mesh warnings, odd pixels) and `backend_note` (why `backend="auto"` fell back).
///
/// `scene`: None (the embedded default scene), a path (`os.PathLike`, or a `str` without a
/// newline or `=`), TOML text, or a dict of the TOML's tables. The keyword arguments mean what
/// the command line's flags of the same name mean: `width`, `height`, `slabs` (int or "auto"),
/// `kernel`, `penumbra`, `surface`, `guard_band` ("auto" or int), `seed`,
/// `variance_compensation`, `preintegration`, `media`, `subpixel_shadows`, `held_lit_side`,
/// `served_releases`, `horizon`, `light_resolution`,
/// `threads` (0: one per core), `backend` ("cpu",
/// "gpu", "auto", "reference"), `path` ("simd", "scalar"), `reference_samples`, `max_memory`
/// (MiB), `allow_open`. `progress=True` shows the CLI's progress bar on a terminal's stderr.
///
/// The GIL is released while it renders; Ctrl-C stops the render (`KeyboardInterrupt`).
/// Raises `convshadow.Error` with the CLI's message and `exit_code`.
#[pyfunction]
#[pyo3(signature = (
    scene = None, *, width = None, height = None, slabs = None, kernel = None, penumbra = None,
    surface = None, guard_band = None, seed = None, variance_compensation = None,
    preintegration = None, media = None, subpixel_shadows = None, held_lit_side = None,
    served_releases = None, horizon = None, light_resolution = None,
    threads = 0, backend = "cpu", path = "simd", reference_samples = None,
    max_memory = None, allow_open = false, progress = false
))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: Option<&Bound<'py, PyAny>>,
    width: Option<u32>,
    height: Option<u32>,
    slabs: Option<&Bound<'py, PyAny>>,
    kernel: Option<String>,
    penumbra: Option<String>,
    surface: Option<String>,
    guard_band: Option<&Bound<'py, PyAny>>,
    seed: Option<u32>,
    variance_compensation: Option<bool>,
    preintegration: Option<bool>,
    media: Option<String>,
    subpixel_shadows: Option<bool>,
    held_lit_side: Option<bool>,
    served_releases: Option<bool>,
    horizon: Option<bool>,
    light_resolution: Option<f64>,
    threads: usize,
    backend: &str,
    path: &str,
    reference_samples: Option<u32>,
    max_memory: Option<u64>,
    allow_open: bool,
    progress: bool,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let bad = |name: &str, e: String| bad_argument(py, name, e);
    let side = |name: &str, v: Option<u32>| -> PyResult<Option<u32>> {
        v.map(|n| overrides::parse_side(&n.to_string()).map_err(|e| bad(name, e)))
            .transpose()
    };
    let backend: RenderBackend = backend.parse().map_err(|e| bad("backend", e))?;
    let options = Options {
        width: side("width", width)?,
        height: side("height", height)?,
        sweep: SweepOverrides {
            slabs: slabs
                .map(|v| -> PyResult<SlabSpec> {
                    overrides::parse_slabs(&text_of(v, "slabs")?).map_err(|e| bad("slabs", e))
                })
                .transpose()?,
            kernel,
            seed,
            penumbra: penumbra
                .map(|p| p.parse::<Penumbra>().map_err(|e| bad("penumbra", e)))
                .transpose()?,
            surface: surface
                .map(|s| overrides::parse_surface(&s).map_err(|e| bad("surface", e)))
                .transpose()?,
            guard_band: guard_band
                .map(|v| -> PyResult<GuardBandSpec> {
                    text_of(v, "guard_band")?
                        .parse()
                        .map_err(|e| bad("guard_band", e))
                })
                .transpose()?,
            variance_compensation,
            preintegration,
            media: media
                .map(|m| m.parse::<Media>().map_err(|e| bad("media", e)))
                .transpose()?,
            subpixel_shadows,
            held_lit_side,
            served_releases,
            horizon,
            light_resolution,
        },
        threads: overrides::parse_threads(&threads.to_string()).map_err(|e| bad("threads", e))?,
        backend,
        path: match path {
            "simd" => CpuPath::Simd,
            "scalar" => CpuPath::Scalar,
            _ => {
                return Err(bad(
                    "path",
                    format!("expected simd or scalar, got {path:?}"),
                ));
            }
        },
        samples: overrides::reference_samples(backend, reference_samples).map_err(|e| {
            error(
                py,
                exit_code::BAD_ARGUMENTS,
                e.message("reference_samples", "backend"),
            )
        })?,
        budget: overrides::memory_budget(max_memory),
        allow_open,
    };
    let mut scene = load_scene(py, scene)?;
    overrides::override_size(&mut scene, options.width, options.height)
        .map_err(|e| error(py, exit_code::BAD_INPUT, e.to_string()))?;
    options.sweep.apply(&mut scene).map_err(|e| match e {
        OverrideError::Kernel(e) => bad("kernel", e),
        OverrideError::Invalid(e) => bad("override", e.to_string()),
    })?;
    let r = render_scene(py, &scene, &options, progress)?;
    let stats = stats_dict(py, &scene, &r, &options)?;
    let image = image_array(py, r.image)?;
    Ok((image, stats))
}

/// Renders `scene` with the GIL released (the reference, or the pipeline with a progress bar
/// when asked).
fn render_scene(py: Python<'_>, scene: &Scene, o: &Options, progress: bool) -> PyResult<Rendered> {
    let cancel = AtomicBool::new(false);
    let result = match o.backend.device() {
        None => detached(py, &cancel, || {
            convshadow::pipeline::render_reference(
                scene,
                o.threads,
                o.samples,
                o.budget,
                o.allow_open,
                &[],
                Some(&cancel),
            )
        })?,
        Some(device) => {
            let bar = progress.then(|| {
                let b = indicatif::ProgressBar::new(match scene.sweep.slabs {
                    SlabSpec::Count(n) => u64::from(n),
                    SlabSpec::Distance(_) | SlabSpec::Auto => 0,
                });
                b.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{spinner} slab {pos}/{len} {wide_bar} {eta}",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                b
            });
            let on_slab = |slab: u32| {
                if let Some(b) = &bar {
                    b.set_position(u64::from(slab) + 1);
                }
            };
            let request = RenderRequest {
                backend: device,
                threads: o.threads,
                path: o.path,
                skip_quiet: true,
                memory_budget: o.budget,
                allow_open: o.allow_open,
                progress: &on_slab,
                cancel: Some(&cancel),
                every_slab: false,
                aovs: Vec::new(),
            };
            let r = detached(py, &cancel, || {
                convshadow::pipeline::render(scene, &request)
            })?;
            if let Some(b) = &bar {
                b.finish_and_clear();
            }
            r
        }
    };
    result.map_err(|e| render_error(py, &e))
}

/// The image as a float32 array of shape (height, width, 3), without a copy.
fn image_array(py: Python<'_>, image: RgbImage) -> PyResult<Bound<'_, PyAny>> {
    let shape = [image.height as usize, image.width as usize, 3];
    Ok(PyArray1::from_vec(py, image.data)
        .reshape(shape)?
        .into_any())
}

/// The stats dict: `--stats-json`'s object less `outputs`, with `warnings` and `backend_note`.
fn stats_dict<'py>(
    py: Python<'py>,
    scene: &Scene,
    r: &Rendered,
    o: &Options,
) -> PyResult<Bound<'py, PyAny>> {
    let mut value = convshadow::stats::render_stats(scene, r, o.path, o.samples, &[]);
    if let Some(map) = value.as_object_mut() {
        map.remove("outputs");
        let mut warnings = r.mesh_warnings.clone();
        if r.ldi.odd_pixels > 0 {
            warnings.push(format!(
                "{} pixels have an odd fragment count of a closed mesh (rendered with allow_open)",
                r.ldi.odd_pixels
            ));
        }
        map.insert("warnings".into(), serde_json::json!(warnings));
        map.insert("backend_note".into(), serde_json::json!(r.backend_note));
    }
    json_to_py(py, &value)
}

/// An image argument of `diff`: a float32 array of shape (H, W, 3), or a path to an EXR or PNG.
fn image_arg(py: Python<'_>, v: &Bound<'_, PyAny>, name: &str) -> PyResult<(RgbImage, String)> {
    if let Ok(a) = v.extract::<PyReadonlyArray3<'_, f32>>() {
        let shape = a.shape();
        if shape[2] != 3 {
            return Err(PyValueError::new_err(format!(
                "{name}: expected an array of shape (height, width, 3), got {shape:?}"
            )));
        }
        let too_big = || PyValueError::new_err(format!("{name}: the image is too large"));
        let height = u32::try_from(shape[0]).map_err(|_| too_big())?;
        let width = u32::try_from(shape[1]).map_err(|_| too_big())?;
        let data: Vec<f32> = a.as_array().iter().copied().collect();
        let image = RgbImage {
            width,
            height,
            data,
        };
        return Ok((image, name.to_string()));
    }
    if v.is_instance_of::<PyString>() || v.hasattr("__fspath__")? {
        let path: PathBuf = v.extract()?;
        let image =
            RgbImage::load(&path).map_err(|e| error(py, exit_code::BAD_INPUT, e.to_string()))?;
        return Ok((image, path.display().to_string()));
    }
    Err(PyTypeError::new_err(format!(
        "{name}: expected a float32 array of shape (height, width, 3) or an image path, got {}",
        v.get_type().name()?
    )))
}

/// Compares image `b` with the reference `a`; returns the dict of `convshadow diff --json`
/// (less `thresholds_failed`): `max_abs_error`, `max_abs_error_at`, `rmse`, `psnr_db` (None
/// when identical, "nan" with NaN values), `mean_flip`, `srgb8_pixels_differ`,
/// `srgb8_pixels_differ_fraction`, `srgb8_max_diff`, `values_differ`, `bit_identical`,
/// `ulp_histogram`, `nan_a`, `nan_b`, `width`, `height`.
///
/// `a` and `b`: float32 arrays of shape (height, width, 3) (as `render` returns), or paths to
/// EXR (linear) or PNG (sRGB, decoded to linear) files. Images of different sizes, or
/// unreadable files, raise `convshadow.Error` with exit code 3, as `convshadow diff` exits.
#[pyfunction]
fn diff<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let (a, a_name) = image_arg(py, a, "a")?;
    let (b, b_name) = image_arg(py, b, "b")?;
    let c = py
        .detach(|| convshadow::diff::Comparison::of(&a, &b))
        .map_err(|e| {
            error(
                py,
                exit_code::BAD_INPUT,
                format!("{a_name} vs {b_name}: {e}"),
            )
        })?;
    json_to_py(py, &c.to_json())
}

/// Reads an EXR (linear float) or a PNG (sRGB, decoded to linear) as `convshadow diff` reads
/// it: a float32 array of shape (height, width, 3). An unreadable file raises
/// `convshadow.Error` with exit code 3.
#[pyfunction]
fn load_image<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let image =
        RgbImage::load(&path).map_err(|e| error(py, exit_code::BAD_INPUT, e.to_string()))?;
    image_array(py, image)
}

/// Renders soft shadows with iterative convolution shadows (convshadow's library, the same
/// bits as the command line). See `render`, `diff`, `load_image` and `Error`.
#[pymodule]
#[pyo3(name = "convshadow")]
fn convshadow_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(diff, m)?)?;
    m.add_function(wrap_pyfunction!(load_image, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    for (name, code) in [
        ("EXIT_INTERNAL", exit_code::INTERNAL),
        ("EXIT_BAD_ARGUMENTS", exit_code::BAD_ARGUMENTS),
        ("EXIT_BAD_INPUT", exit_code::BAD_INPUT),
        ("EXIT_RESOURCE_LIMIT", exit_code::RESOURCE_LIMIT),
        ("EXIT_GPU_UNAVAILABLE", exit_code::GPU_UNAVAILABLE),
        ("EXIT_MESH_DEFECT", exit_code::MESH_DEFECT),
        ("EXIT_INTERRUPTED", exit_code::INTERRUPTED),
    ] {
        m.add(name, code)?;
    }
    Ok(())
}
