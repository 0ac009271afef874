# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures of the Python module's tests (run by ctest as python.pytest)."""
import os
import pathlib

import pytest


@pytest.fixture
def shared_data():
    """../shared/data beside the checkout (or $IDO_SHARED_DATA); the test is skipped without it."""
    path = pathlib.Path(os.environ.get("IDO_SHARED_DATA", pathlib.Path(__file__).parents[3] / "shared" / "data"))
    if not path.is_dir():
        pytest.skip("../shared/data is not present")
    return path


@pytest.fixture
def ido_bin():
    """The `ido` command-line tool of the same build ($IDO_BIN); skipped when unknown."""
    path = os.environ.get("IDO_BIN")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("IDO_BIN does not name the ido executable")
    return path
