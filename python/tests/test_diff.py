"""convshadow.diff: the numbers of `convshadow diff --json`, from arrays or image paths."""

import json

import numpy as np
import pytest

import convshadow
from conftest import SMALL, flags


def test_diff_gives_the_numbers_of_the_cli_json(cli, tmp_path):
    a, b, out = tmp_path / "a.exr", tmp_path / "b.exr", tmp_path / "diff.json"
    for path, seed in [(a, 1), (b, 2)]:
        run = cli("render", *flags({**SMALL, "seed": seed}), "-o", path, "-q")
        assert run.returncode == 0, run.stderr
    run = cli("diff", a, b, "--json", out)
    assert run.returncode == 0, run.stderr
    expected = json.loads(out.read_text())
    assert expected.pop("thresholds_failed") == []
    by_path = convshadow.diff(a, b)
    assert by_path == expected
    assert by_path["values_differ"] > 0 and by_path["rmse"] > 0
    assert not by_path["bit_identical"]
    # The arrays render returns are the EXRs' values: the same numbers.
    image_a, _ = convshadow.render(**SMALL, seed=1)
    image_b, _ = convshadow.render(**SMALL, seed=2)
    assert convshadow.diff(image_a, image_b) == expected
    assert convshadow.diff(str(a), image_b) == expected
    np.testing.assert_array_equal(convshadow.load_image(a), image_a)


def test_identical_images_are_bit_identical_with_infinite_psnr():
    image, _ = convshadow.render(**SMALL)
    d = convshadow.diff(image, image.copy())
    assert d["bit_identical"] and d["values_differ"] == 0
    assert d["rmse"] == 0.0 and d["max_abs_error"] == 0.0 and d["mean_flip"] == 0.0
    assert d["psnr_db"] is None
    assert d["ulp_histogram"][0] == ["0", image.size]


def test_nans_are_counted_and_located():
    a = np.zeros((4, 5, 3), np.float32)
    b = a.copy()
    b[2, 3, 1] = np.nan
    d = convshadow.diff(a, b)
    assert d["nan_a"] == {"count": 0, "first": None}
    assert d["nan_b"] == {"count": 1, "first": [3, 2, 1]}
    assert d["psnr_db"] == "nan"


def test_images_of_different_sizes_or_unreadable_files_raise_error_with_exit_code_3(cli, tmp_path):
    with pytest.raises(convshadow.Error) as info:
        convshadow.diff(np.zeros((4, 4, 3), np.float32), np.zeros((4, 5, 3), np.float32))
    assert info.value.exit_code == 3
    assert "differ in size" in info.value.message
    missing = tmp_path / "missing.exr"
    with pytest.raises(convshadow.Error) as info:
        convshadow.diff(missing, missing)
    assert info.value.exit_code == 3
    run = cli("diff", missing, missing)
    assert run.returncode == 3 and info.value.message in run.stderr


def test_arrays_of_another_type_or_shape_are_refused():
    with pytest.raises(TypeError):
        convshadow.diff(np.zeros((4, 4, 3), np.float64), np.zeros((4, 4, 3), np.float64))
    with pytest.raises(ValueError):
        convshadow.diff(np.zeros((4, 4, 4), np.float32), np.zeros((4, 4, 4), np.float32))
