# SPDX-License-Identifier: Apache-2.0
"""ido: computer-assisted surgery toolkit (Turini et al. 2007). The package re-exports the
compiled extension `ido._ido` (pybind11): every name is `ido.<name>`. Type stubs:
__init__.pyi, with py.typed marking the package as typed (PEP 561)."""
from ._ido import *  # noqa: F401,F403
from ._ido import __doc__, __version__  # noqa: F401
