# SPDX-License-Identifier: GPL-3.0-or-later
"""docs/python.md's examples, run as written: the worked example and the process pool."""

import os
import re
import shutil
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs" / "python.md"


def python_blocks():
    return re.findall(r"```python\n(.*?)```", DOCS.read_text(), re.S)


def test_the_worked_example(bodice_file, tmp_path, monkeypatch, capsys):
    pytest.importorskip("matplotlib")
    block = python_blocks()[0]
    assert "panelize.load(\"bodice.obj\")" in block
    shutil.copy(bodice_file, tmp_path / "bodice.obj")
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "docs/python.md: worked example", "exec"), {})
    assert (tmp_path / "pattern.png").stat().st_size > 1000
    assert sorted(os.listdir(tmp_path / "pattern")) == [".panelize", "pattern.dxf", "pattern.svg", "report.json"]
    assert "goals met: True" in capsys.readouterr().out


def test_the_process_pool_example(bodice_file, tmp_path, monkeypatch, capsys):
    block = next(block for block in python_blocks() if "ProcessPoolExecutor" in block)
    (tmp_path / "garments").mkdir()
    shutil.copy(bodice_file, tmp_path / "garments" / "bodice.obj")
    (tmp_path / "garments" / "broken.obj").write_text("v 0 0 0\nf 1 2 3\n")
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "docs/python.md: process pool", "exec"), {})
    out = capsys.readouterr().out
    assert "garments/bodice.obj" in out and "goals met: True" in out
    assert re.search(r"garments/broken.obj failed: bad input data", out), out
    assert (tmp_path / "patterns" / "bodice" / "report.json").exists()
    assert not (tmp_path / "patterns" / "broken").exists()
