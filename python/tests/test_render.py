"""convshadow.render against the command line: the same image bits, the same stats, the same
errors with the same exit codes, and every way of giving a scene."""

import json
import pathlib
import sys

import numpy as np
import OpenEXR
import pytest

import convshadow
from conftest import REPO, SMALL, flags

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - the suite runs on 3.11 in CI
    import tomli as tomllib

DEFAULT = REPO / "scenes" / "default.toml"


def read_exr(path):
    """The RGB float32 values of an EXR, (H, W, 3), read by OpenEXR (not by convshadow)."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        channels = f.channels()
        rgb = [channels[c].pixels for c in "RGB"]
    for c in rgb:
        assert c.dtype == np.float32, c.dtype
    return np.stack(rgb, axis=-1)


def bits(a):
    """The float32 array's bits, to compare bit for bit (NaN equals NaN, -0 differs from 0)."""
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


@pytest.mark.parametrize(
    "scene, overrides",
    [
        (DEFAULT, SMALL),
        (DEFAULT, {**SMALL, "kernel": "poisson8", "penumbra": "iterated", "seed": 7,
                   "media": "first-order"}),
        (REPO / "scenes" / "gobo.toml", {"width": 40, "height": 40, "slabs": 48}),
        (REPO / "scenes" / "edge.toml", {"width": 40, "height": 40, "slabs": 48,
                                         "subpixel_shadows": False}),
    ],
    ids=["default", "default-overridden", "gobo", "edge-carried"],
)
def test_image_is_the_cli_exr_bit_for_bit(cli, tmp_path, scene, overrides):
    exr, stats_json = tmp_path / "out.exr", tmp_path / "stats.json"
    run = cli("render", scene, *flags(overrides), "-o", exr, "--stats-json", stats_json, "-q")
    assert run.returncode == 0, run.stderr
    image, stats = convshadow.render(scene, **overrides)
    assert image.dtype == np.float32
    assert image.shape == (overrides["height"], overrides["width"], 3)
    expected = read_exr(exr)
    assert expected.shape == image.shape
    np.testing.assert_array_equal(bits(image), bits(expected))
    cli_stats = json.loads(stats_json.read_text())
    for key in ["image_hash", "ldi_hash", "slabs", "slabs_swept", "fragments", "kernel",
                "penumbra", "media", "subpixel_shadows", "guard_band_px", "grid_width", "grid_height", "backend", "path"]:
        assert stats[key] == cli_stats[key], key
    # Every key of --stats-json but the files written.
    assert set(cli_stats) - set(stats) == {"outputs"}
    assert stats["seconds_total"] > 0


def test_stats_are_the_stats_json_numbers():
    image, stats = convshadow.render(**SMALL, threads=1)
    assert stats["width"] == 64 and stats["height"] == 48
    assert stats["slabs"] == 96
    assert stats["threads"] == 1
    assert len(stats["image_hash"]) == 16 and int(stats["image_hash"], 16) >= 0
    assert stats["warnings"] == [] and stats["backend_note"] is None
    # The image hash is the image's: another seed gives another image and another hash.
    other, other_stats = convshadow.render(**SMALL, threads=1, seed=2)
    assert not np.array_equal(image, other)
    assert other_stats["image_hash"] != stats["image_hash"]


def test_threads_and_paths_give_the_same_bits():
    image, stats = convshadow.render(**SMALL, threads=1)
    for kwargs in [{"threads": 2}, {"path": "scalar"}]:
        other, other_stats = convshadow.render(**SMALL, **kwargs)
        np.testing.assert_array_equal(bits(image), bits(other))
        assert other_stats["image_hash"] == stats["image_hash"]


def test_dict_toml_text_and_path_give_the_same_image():
    text = DEFAULT.read_text()
    by_path, stats = convshadow.render(DEFAULT, **SMALL)
    by_str_path, _ = convshadow.render(str(DEFAULT), **SMALL)
    by_text, _ = convshadow.render(text, **SMALL)
    by_dict, dict_stats = convshadow.render(tomllib.loads(text), **SMALL)
    # The embedded default scene is this file.
    embedded, _ = convshadow.render(**SMALL)
    for other in [by_str_path, by_text, by_dict, embedded]:
        np.testing.assert_array_equal(bits(by_path), bits(other))
    assert dict_stats["image_hash"] == stats["image_hash"]


def test_a_dict_with_relative_paths_resolves_them_against_the_current_folder(monkeypatch):
    scene = REPO / "scenes" / "gobo.toml"
    small = {"width": 24, "height": 24, "slabs": 32}
    expected, _ = convshadow.render(scene, **small)
    monkeypatch.chdir(scene.parent)
    image, _ = convshadow.render(tomllib.loads(scene.read_text()), **small)
    np.testing.assert_array_equal(bits(expected), bits(image))


@pytest.mark.parametrize(
    "scene",
    [
        "[image]\nwidth = 0\nheight = 8\n",
        {"image": {"width": 8, "height": 8}, "sweep": {"kernel": "nope"}},
        "[image]\nwidht = 8\n",
        "no-such-scene.toml",
    ],
    ids=["zero-width", "bad-kernel-key", "unknown-key", "missing-file"],
)
def test_a_bad_scene_raises_error_with_the_cli_message_and_exit_code_3(cli, tmp_path, scene):
    with pytest.raises(convshadow.Error) as info:
        convshadow.render(scene)
    e = info.value
    assert e.exit_code == 3 == convshadow.EXIT_BAD_INPUT
    assert str(e) == e.message and e.message
    # The command line refuses the same scene with the same code and message.
    if isinstance(scene, str) and "\n" in scene:
        path = tmp_path / "bad.toml"
        path.write_text(scene)
        with pytest.raises(convshadow.Error) as by_path:
            convshadow.render(path)
        run = cli("render", path, "-o", tmp_path / "x.exr", "-q")
        assert run.returncode == 3
        assert by_path.value.message in run.stderr
        assert by_path.value.exit_code == 3
    if scene == "no-such-scene.toml":
        assert "cannot read scene file" in e.message
        run = cli("render", scene, "-o", tmp_path / "x.exr", "-q")
        assert run.returncode == 3 and e.message in run.stderr


@pytest.mark.parametrize(
    "overrides, words",
    [
        ({"kernel": "nope"}, "kernel: unknown kernel"),
        ({"width": 0}, "width: expected an integer from 1"),
        ({"slabs": "many"}, "slabs: expected an integer"),
        ({"slabs": 0}, "override: "),
        ({"penumbra": "sharp"}, "penumbra"),
        ({"media": "exact"}, "media: expected \"second-order\" or \"first-order\""),
        ({"backend": "tpu"}, "backend: expected cpu, gpu, auto or reference"),
        ({"threads": 100000}, "threads: expected 0 (one per core)"),
        ({"reference_samples": 4}, "reference_samples only applies to backend reference"),
    ],
)
def test_bad_overrides_raise_error_with_exit_code_2(overrides, words):
    with pytest.raises(convshadow.Error) as info:
        convshadow.render(**{**SMALL, **overrides})
    assert info.value.exit_code == 2 == convshadow.EXIT_BAD_ARGUMENTS
    assert words in info.value.message


def test_a_memory_budget_too_small_is_a_resource_limit(cli, tmp_path):
    with pytest.raises(convshadow.Error) as info:
        convshadow.render(**SMALL, max_memory=0)
    assert info.value.exit_code == 4
    run = cli("render", *flags(SMALL), "--max-memory", 0, "-o", tmp_path / "x.exr", "-q")
    assert run.returncode == 4 and info.value.message in run.stderr


def test_open_meshes_render_as_thin_shells_with_a_warning(cli, tmp_path):
    # A square of two triangles: open, every pixel it covers has one fragment; a thin shell.
    obj = tmp_path / "square.obj"
    obj.write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n")
    scene = {
        "image": {"width": 16, "height": 16},
        "camera": {"direction": [0.3, -0.2, 1.0], "view_width": 4.0},
        "sweep": {"slabs": 8},
        "mesh": [{"shape": "obj", "path": str(obj), "material": "m"}],
        "material": {"m": {}},
    }
    image, stats = convshadow.render(scene)
    assert stats["odd_pixels"] == 0  # a shell is not a parity defect
    assert any("mesh[0] is not closed" in w and "thin shell" in w for w in stats["warnings"])
    assert (image > 0).any()


def test_the_reference_backend_renders_with_its_sample_count():
    image, stats = convshadow.render(width=12, height=12, slabs=24, backend="reference",
                                     reference_samples=4)
    assert image.shape == (12, 12, 3)
    assert stats["backend"] == "reference" and stats["reference_samples"] == 4
    assert np.isfinite(image).all()


def test_scene_of_another_type_is_a_type_error():
    with pytest.raises(TypeError):
        convshadow.render(42)
    with pytest.raises(TypeError):
        convshadow.render({"image": {"width": object()}})



PERSPECTIVE = """
[image]
width = 24
height = 16
[camera]
projection = "perspective"
eye = [0.0, 1.0, -5.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
[sweep]
slabs = 16
[[mesh]]
shape = "sphere"
size = [1.0, 3]
material = "m"
[material.m]
"""


def test_a_perspective_scene_renders_on_the_sweep_and_the_reference_like_the_command_line(cli, tmp_path):
    image, stats = convshadow.render(PERSPECTIVE, backend="reference", reference_samples=4)
    assert image.shape == (16, 24, 3) and np.isfinite(image).all()
    assert (image > 0).any() and stats["odd_pixels"] == 0
    image, stats = convshadow.render(PERSPECTIVE)
    assert image.shape == (16, 24, 3) and (image > 0).any()
    path = tmp_path / "persp.toml"
    path.write_text(PERSPECTIVE)
    run = cli("render", path, "-o", tmp_path / "x.exr", "-q")
    assert run.returncode == 0
    assert bits(read_exr(tmp_path / "x.exr")).tolist() == bits(image).tolist()
    # A light travelling towards the eye (a second pass from the far end): the command line's bits.
    back_light = PERSPECTIVE + "[[light]]\ndirection = [0.0, 0.0, -1.0]\n"
    image, stats = convshadow.render(back_light)
    path.write_text(back_light)
    run = cli("render", path, "-o", tmp_path / "back.exr", "-q")
    assert run.returncode == 0
    assert bits(read_exr(tmp_path / "back.exr")).tolist() == bits(image).tolist()
    # A bad perspective camera is refused as on the command line.
    with pytest.raises(convshadow.Error) as info:
        convshadow.render(PERSPECTIVE.replace("fov_deg =", "fov_deg = 200.0 #"))
    assert info.value.exit_code == 3 and "fov_deg" in info.value.message


def test_light_resolution_and_point_lights_follow_the_command_line(cli, tmp_path):
    # A coarser light grid for a perspective camera: the command line's bits.
    image, _ = convshadow.render(PERSPECTIVE, light_resolution=0.5)
    path = tmp_path / "persp.toml"
    path.write_text(PERSPECTIVE)
    run = cli("render", path, "--light-resolution", "0.5", "-o", tmp_path / "half.exr", "-q")
    assert run.returncode == 0
    assert bits(read_exr(tmp_path / "half.exr")).tolist() == bits(image).tolist()
    assert bits(image).tolist() != bits(convshadow.render(PERSPECTIVE)[0]).tolist()
    # An orthographic camera's light grid at another resolution: the command line's bits too.
    ortho = PERSPECTIVE.replace('projection = "perspective"', "view_width = 3.0").replace(
        "eye =", "#").replace("look_at =", "#").replace("fov_deg =", "#")
    image, _ = convshadow.render(ortho, light_resolution=2.0)
    path.write_text(ortho)
    run = cli("render", path, "--light-resolution", "2", "-o", tmp_path / "ortho.exr", "-q")
    assert run.returncode == 0
    assert bits(read_exr(tmp_path / "ortho.exr")).tolist() == bits(image).tolist()
    with pytest.raises(convshadow.Error) as info:
        convshadow.render(ortho, light_resolution=32.0)
    assert info.value.exit_code == 2 and "light_resolution" in info.value.message
    # A point light before the sphere: the reference and the sweep render it; one behind the
    # sphere the sweep too (a turned-round pass); one beside it, amid the scene's depths, only
    # the reference, and the sweep says so.
    point = PERSPECTIVE + '[[light]]\nkind = "point"\nposition = [0.0, 3.0, -3.0]\nradius = 0.1\n'
    for image, _ in (convshadow.render(point, backend="reference", reference_samples=4),
                     convshadow.render(point, backend="cpu")):
        assert np.isfinite(image).all() and (image > 0).any()
    behind, stats = convshadow.render(point.replace("[0.0, 3.0, -3.0]", "[0.0, 0.0, 3.0]"))
    assert np.isfinite(behind).all() and stats["lights_toward_viewer"] == 1
    amid = point.replace("[0.0, 3.0, -3.0]", "[2.0, 0.0, 0.0]")
    with pytest.raises(convshadow.Error) as info:
        convshadow.render(amid)
    assert info.value.exit_code == 3 and "--backend reference" in info.value.message
