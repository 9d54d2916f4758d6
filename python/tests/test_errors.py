# SPDX-License-Identifier: GPL-3.0-or-later
"""The error classes, the command line's categories and messages, and hostile arrays."""

import os
import subprocess

import numpy as np
import pytest

import panelize


def test_the_hierarchy_carries_the_command_lines_exit_codes():
    expected = {panelize.UsageError: 64, panelize.DataError: 65, panelize.OpenError: 66,
                panelize.CreateError: 73, panelize.InternalError: 70, panelize.CancelledError: 130,
                panelize.GoalsNotMetError: 3}
    for cls, code in expected.items():
        assert issubclass(cls, panelize.Error) and cls.exit_code == code
    assert issubclass(panelize.UsageError, ValueError) and issubclass(panelize.DataError, ValueError)


def test_cannot_open(tmp_path):
    with pytest.raises(panelize.OpenError) as caught:
        panelize.load(tmp_path / "missing.obj")
    assert caught.value.exit_code == 66 and "missing.obj" in caught.value.message
    assert "\n" not in str(caught.value)


def test_bad_input(tmp_path):
    path = tmp_path / "broken.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(panelize.DataError) as caught:
        panelize.load(path)
    assert caught.value.exit_code == 65 and "broken.obj" in str(caught.value)


def test_usage_errors_are_the_command_lines(cli, bodice_file, bodice, tmp_path):
    """The same range, the same words: only the option's spelling differs."""
    cases = [("max_strain", 11, "--max-strain", "11"), ("max_corners", 0, "--max-corners", "0"),
             ("iterations", 10001, "--iterations", "10001"), ("seam_allowance", 1000, "--seam-allowance", "1000"),
             ("min_piece_area", 0.6, "--min-piece-area", "0.6")]
    for keyword, value, flag, text in cases:
        with pytest.raises(panelize.UsageError) as caught:
            panelize.run(bodice, **{keyword: value})
        ours = str(caught.value)
        assert ours.startswith("run: " + keyword + ": ") and caught.value.exit_code == 64
        done = subprocess.run([cli, "run", str(bodice_file), "-o", str(tmp_path / "x"), flag, text],
                              capture_output=True, text=True)
        assert done.returncode == 64
        assert done.stderr.strip() == "panelize: " + ours.replace(keyword, flag, 1)
    with pytest.raises(panelize.UsageError, match="backend: 'fast' is not textile, lscm, wirewarp or springmass"):
        panelize.run(bodice, backend="fast")
    with pytest.raises(panelize.UsageError, match="scheme works with"):
        panelize.flatten(bodice, scheme="progressive")
    with pytest.raises(panelize.UsageError, match="scales"):
        panelize.field(bodice, scales=9)


def test_wrong_types_name_the_argument(bodice):
    with pytest.raises(TypeError, match="max_strain"):
        panelize.run(bodice, max_strain="0.05")
    with pytest.raises(TypeError, match="max_corners: expected a whole number"):
        panelize.run(bodice, max_corners=6.5)
    with pytest.raises(TypeError, match="darts"):
        panelize.run(bodice, darts="maybe")
    with pytest.raises(TypeError, match="unexpected keyword argument 'max_stain'"):
        panelize.run(bodice, max_stain=0.05)
    with pytest.raises(ValueError, match="grain: expected a sequence of 3 numbers"):
        panelize.run(bodice, grain=(0, 1))


def test_cannot_create(bodice_result, tmp_path):
    a_file = tmp_path / "a-file"
    a_file.write_text("mine")
    with pytest.raises(panelize.CreateError) as caught:
        bodice_result.write(a_file / "out")
    assert caught.value.exit_code == 73
    with pytest.raises(panelize.UsageError, match="pdff"):
        bodice_result.write(tmp_path / "out", outputs=("svg", "pdff"))
    assert not (tmp_path / "out").exists()


def test_write_is_all_or_nothing(bodice_result, tmp_path):
    folder = tmp_path / "pattern"
    bodice_result.write(folder, outputs="svg,json")
    assert sorted(os.listdir(folder)) == [".panelize", "pattern.svg", "report.json"]
    # a second write replaces the earlier output whole
    bodice_result.write(folder, outputs=["dxf"])
    assert sorted(os.listdir(folder)) == [".panelize", "pattern.dxf"]
    # a folder of someone else's files is refused and left as it was
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "notes.txt").write_text("keep me")
    with pytest.raises(panelize.CreateError):
        bodice_result.write(theirs)
    assert os.listdir(theirs) == ["notes.txt"]
    # nothing half-written stays beside them
    assert sorted(os.listdir(tmp_path)) == ["pattern", "theirs"]


# ---------------------------------------------------------------- hostile arrays

def square():
    vertices = np.array([[0, 0, 0], [100, 0, 0], [100, 100, 0], [0, 100, 0]], dtype=np.float64)
    faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
    return vertices, faces


@pytest.mark.parametrize("vertices, faces, error, name", [
    (np.zeros((4, 2)), np.zeros((1, 3), np.int32), ValueError, "vertices"),
    (np.zeros(12), np.zeros((1, 3), np.int32), ValueError, "vertices"),
    (np.zeros((4, 3)), np.zeros((1, 4), np.int32), ValueError, "faces"),
    (np.zeros((4, 3)), np.zeros((1, 3), np.float64), TypeError, "faces"),
    (np.zeros((4, 3), np.complex128), np.zeros((1, 3), np.int32), TypeError, "vertices"),
    (np.array([["a", "b", "c"]]), np.zeros((1, 3), np.int32), TypeError, "vertices"),
    ("vertices", np.zeros((1, 3), np.int32), TypeError, "vertices"),
])
def test_wrong_shapes_and_dtypes(vertices, faces, error, name):
    for function in (panelize.run, panelize.flatten, panelize.field, panelize.prepare):
        with pytest.raises(error, match=name):
            function(vertices, faces)


def test_bad_content_never_crashes():
    vertices, faces = square()
    with pytest.raises(panelize.DataError, match="faces: entry 5 is 9"):
        panelize.run(vertices, np.array([[0, 1, 2], [0, 2, 9]]))
    with pytest.raises(panelize.DataError, match="faces"):
        panelize.run(vertices, -faces)
    with pytest.raises(panelize.DataError, match="faces"):
        panelize.run(vertices, np.array([[0, 1, 2**40]]))
    with pytest.raises(panelize.DataError, match="no faces"):
        panelize.run(vertices, np.zeros((0, 3), np.int32))
    with pytest.raises(panelize.DataError, match="no vertices"):
        panelize.field(np.zeros((0, 3)), np.zeros((0, 3), np.int32))
    with pytest.raises(ValueError, match="poses"):
        panelize.run(vertices, faces, poses=[vertices[:3]])
    with pytest.raises(ValueError, match="panels"):
        panelize.flatten(vertices, faces, panels=[0])
    with pytest.raises(panelize.DataError, match="panel id 1 is not used|panel"):
        panelize.flatten(vertices, faces, panels=[0, 2])
    # NaN coordinates: refused (or repaired away) as a file's would be, never a crash
    broken = vertices.copy()
    broken[2, 1] = np.nan
    for function in (panelize.run, panelize.flatten, panelize.field, panelize.prepare):
        try:
            function(broken, faces)
        except panelize.Error as error:
            assert error.exit_code in (64, 65)
