# SPDX-License-Identifier: GPL-3.0-or-later
"""run, flatten, field, prepare: round trips and properties of their results."""

import json
import os
import subprocess

import numpy as np
import pytest

import panelize


def test_round_trip_matches_the_command_line(cli, bodice_file, tmp_path):
    """load + run + write gives the pattern `panelize run` gives on the same file."""
    mesh = panelize.load(bodice_file)
    assert mesh.units == "mm" and mesh.vertices.dtype == np.float64 and mesh.faces.shape[1] == 3
    result = panelize.run(mesh)
    result.write(tmp_path / "py", outputs=("json", "dxf"))
    subprocess.run([cli, "run", str(bodice_file), "-o", str(tmp_path / "cli"), "--quiet", "--outputs", "json"],
                   check=True)
    ours = json.loads((tmp_path / "py" / "report.json").read_text())
    theirs = json.loads((tmp_path / "cli" / "report.json").read_text())
    for key in ("panel_count", "seam_count", "dart_count", "goals_met", "max_abs_strain"):
        assert ours["summary"][key] == theirs["summary"][key], key
    assert ours["parameters"] == theirs["parameters"]
    assert sorted(os.listdir(tmp_path / "py")) == [".panelize", "pattern.dxf", "report.json"]


def test_every_face_is_labelled_and_the_pattern_is_finite(bodice, bodice_result):
    result = bodice_result
    m = len(result.faces)
    assert result.face_panel.shape == (m,) and result.face_panel.dtype == np.int32
    assert result.face_panel.min() == 0 and result.face_panel.max() == result.panel_count - 1
    assert len(np.unique(result.face_panel)) == result.panel_count
    assert result.pattern.shape == (m, 3, 2) and np.isfinite(result.pattern).all()
    # the indexed pattern is the same numbers
    assert np.array_equal(result.pattern_uv[result.pattern_faces], result.pattern)
    # each pattern vertex is a copy of a garment vertex, on its face's corner
    assert np.array_equal(result.pattern_vertex[result.pattern_faces], result.faces)
    # the pattern is flat and the right size: each face's 2D area within the strain goal of its 3D area
    corners = result.pattern
    area_2d = 0.5 * np.abs(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))
    v = result.vertices[result.faces]
    area_3d = 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
    assert abs(area_2d.sum() / area_3d.sum() - 1) < 0.05


def test_goals_and_report(bodice_result):
    result = bodice_result
    report = result.report
    assert report["summary"]["goals_met"] is result.goals_met is True
    assert report["summary"]["panel_count"] == result.panel_count
    assert report["segmentation"]["max_strain"] == 0.05 and report["segmentation"]["max_corners"] == 8
    assert result.worst_strain <= 0.05 + 1e-9
    assert abs(report["summary"]["max_abs_strain"] - result.worst_strain) < 1e-6


def test_seams_are_sewn_vertex_to_vertex(bodice_result):
    result = bodice_result
    assert len(result.seams) == result.report["summary"]["seam_count"] > 0
    for seam in result.seams:
        a, b = seam["panels"]
        assert 0 <= a < result.panel_count and 0 <= b < result.panel_count
        # the two sides are the same garment vertices: one seam, two pieces of cloth
        assert np.array_equal(seam["vertices_a"], seam["vertices_b"])
        assert seam["pattern_a"].shape == seam["pattern_b"].shape == (len(seam["vertices_a"]), 2)
        length_a = np.linalg.norm(np.diff(seam["pattern_a"], axis=0), axis=1).sum()
        length_b = np.linalg.norm(np.diff(seam["pattern_b"], axis=0), axis=1).sum()
        assert abs(length_a - length_b) <= 0.005 * max(length_a, length_b) + 1e-6
    assert len(result.curves) == len(result.curve_is_dart) > 0
    assert all(curve.shape[1] == 3 and np.isfinite(curve).all() for curve in result.curves)


def test_options_reach_the_library(bodice):
    result = panelize.run(bodice, max_corners=6, max_strain=0.04, symmetry="off", darts=False, seam_allowance=12)
    segmentation = result.report["segmentation"]
    assert segmentation["max_corners"] == 6 and segmentation["max_strain"] == 0.04
    assert result.report["summary"]["dart_count"] == 0 and result.darts == []


def test_grain_hints_turn_the_piece_they_lie_on(tmp_path):
    """grain_hints= (a file, as --grain-hints): a 45-degree helix stroke on a cylinder turns one piece by 45."""
    import json
    import math

    points = []
    for t in (-30, -15, 0, 15, 30):
        phi = math.pi / 2 + t * math.sin(math.pi / 4) / 150.0
        points.append([150 * math.cos(phi), 150 * math.sin(phi), 200 + t * math.cos(math.pi / 4)])
    hints = tmp_path / "hints.json"
    hints.write_text(json.dumps({"curves": [points]}))
    cylinder = panelize.generate("cylinder", faces=3000)
    result = panelize.run(cylinder, grain_hints=str(hints))
    turns = sorted(round(abs(panel["grain_turn_deg"])) for panel in result.report["panels"])
    assert result.report["parameters"]["grain_hints"] == 1
    assert turns[-1] == 45 and turns[0] == 0


def test_flatten_the_panels_of_a_run(bodice_result):
    """The panels run found, given back to flatten as per-face ids, give the same panels."""
    first = bodice_result
    again = panelize.flatten(first.vertices, first.faces, panels=first.face_panel, backend="lscm")
    assert again.goals_met is None and again.panel_count == first.panel_count
    assert np.array_equal(again.face_panel, first.face_panel)
    assert np.isfinite(again.pattern).all()


def test_field(bodice):
    field = panelize.field(bodice, scales=2)
    m = len(bodice.faces)
    assert field.directions.shape == (m, 3)
    assert np.allclose(np.linalg.norm(field.directions, axis=1), 1, atol=1e-6)
    # each arm lies in its face's plane
    assert np.abs(np.einsum("ij,ij->i", field.directions, field.normals)).max() < 1e-6
    assert field.report["scales"] == 2 and field.report["singularity_count"] == len(field.singular_vertices)
    assert abs(field.singular_indices.sum() - field.report["index_sum"]) < 1e-9


def test_prepare_matches_the_command_line(cli, bodice_file, tmp_path):
    prepared = panelize.prepare(panelize.load(bodice_file), faces_wanted=1000)
    assert 500 < len(prepared.mesh.faces) < 2000
    report = prepared.report
    assert report["counts"]["output_faces"] == len(prepared.mesh.faces)
    assert report["within_bound"] == (report["hausdorff_mm"] <= report["hausdorff_bound_mm"])
    done = subprocess.run([cli, "prepare", str(bodice_file), "-o", str(tmp_path / "p.obj"), "--faces", "1000",
                           "--json", "--quiet"], capture_output=True, text=True, check=True)
    theirs = json.loads(done.stdout)
    assert theirs["counts"] == report["counts"]
    assert abs(theirs["hausdorff_mm"] - report["hausdorff_mm"]) < 1e-3


def test_prepare_refuses_both_sizes(bodice):
    with pytest.raises(panelize.UsageError, match="not both"):
        panelize.prepare(bodice, faces_wanted=1000, edge=10)


def test_docstrings():
    for name in panelize.__all__:
        item = getattr(panelize, name)
        assert item.__doc__ and len(item.__doc__) > 40, name
    assert panelize.Result.write.__doc__


def test_darts_are_sewn_leg_to_leg():
    """The bodice at S = 0.045 takes a dart (as in test_cli_run): its legs meet at the tip and match in
    length on the pattern."""
    result = panelize.run(panelize.generate("bodice", faces=3000), symmetry="off", max_strain=0.045)
    assert len(result.darts) == result.report["summary"]["dart_count"] >= 1
    assert result.curve_is_dart.sum() == len(result.darts)
    for dart in result.darts:
        assert 0 <= dart["panel"] < result.panel_count
        # the two legs are the two sides of one cut: the same garment vertices, apart on the pattern
        assert len(dart["vertices_a"]) == len(dart["vertices_b"]) >= 2
        assert np.array_equal(dart["vertices_a"], dart["vertices_b"])
        assert not np.allclose(dart["pattern_a"], dart["pattern_b"])
        # both legs run up to the tip: their points facing each other are equally far from it
        tip = dart["pattern_tip"]
        to_tip_a = np.linalg.norm(dart["pattern_a"] - tip, axis=1)
        to_tip_b = np.linalg.norm(dart["pattern_b"] - tip, axis=1)
        assert np.allclose(to_tip_a, to_tip_b, rtol=0.02, atol=0.5)
        length_a = np.linalg.norm(np.diff(dart["pattern_a"], axis=0), axis=1).sum()
        length_b = np.linalg.norm(np.diff(dart["pattern_b"], axis=0), axis=1).sum()
        assert abs(length_a - length_b) <= 0.005 * max(length_a, length_b) + 1e-6


def without_timings(value):
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if "timings" not in k and k != "ms"}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


@pytest.mark.parametrize("function", ["run", "field"])
def test_the_documented_defaults_are_the_librarys(function, bodice, tmp_path):
    """Every default the signature shows, given explicitly, changes nothing (the library holds the defaults)."""
    import inspect
    call = getattr(panelize, function)
    defaults = {name: parameter.default for name, parameter in inspect.signature(call).parameters.items()
                if parameter.kind == parameter.KEYWORD_ONLY and parameter.default is not None}
    assert len(defaults) >= (15 if function == "run" else 2)
    implicit = call(bodice, symmetry="off") if function == "run" else call(bodice)
    defaults.update({"symmetry": "off"} if function == "run" else {})
    explicit = call(bodice, **defaults)
    assert without_timings(explicit.report) == without_timings(implicit.report)
    if function == "run":  # the pattern files show the rest: allowances, notches, marker gap, size, paper
        for name, result in (("implicit", implicit), ("explicit", explicit)):
            result.write(tmp_path / name, outputs="svg,dxf,marker,tiled")
        for file in ("pattern.svg", "pattern.dxf", "marker.svg"):
            assert (tmp_path / "implicit" / file).read_bytes() == (tmp_path / "explicit" / file).read_bytes(), file
