# SPDX-License-Identifier: GPL-3.0-or-later
"""Fixtures of the Python package's tests: small generated garments, as files and in memory."""

import os
import subprocess

import pytest

import panelize


@pytest.fixture(scope="session")
def bodice():
    """A 2,000-face bodice in memory (millimetres)."""
    return panelize.generate("bodice", faces=2000)


@pytest.fixture(scope="session")
def bodice_result(bodice):
    """run() on that bodice with the defaults."""
    return panelize.run(bodice)


@pytest.fixture(scope="session")
def cli():
    """The panelize command of this build (PZ_BINARY, set by ctest), or a skip."""
    binary = os.environ.get("PZ_BINARY")
    if not binary or not os.access(binary, os.X_OK):
        pytest.skip("no panelize binary (PZ_BINARY)")
    return binary


@pytest.fixture(scope="session")
def bodice_file(cli, tmp_path_factory):
    """The same kind of bodice, written by `panelize generate` as an OBJ file (millimetres)."""
    path = tmp_path_factory.mktemp("garments") / "bodice.obj"
    subprocess.run([cli, "generate", "bodice", "-o", str(path), "--faces", "2000", "--quiet"], check=True)
    return path
