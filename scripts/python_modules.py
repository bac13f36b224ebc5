"""What the Python scripts here share about the interpreter they run under: the modules they need
beyond the standard library come with Debian's /usr/bin/python3 (python3-numpy, -pandas, -scipy)."""
from __future__ import annotations

import importlib
import sys


def cannot_import(*modules: str) -> str | None:
    """None when this Python imports every one of `modules`, else one line naming the first it
    cannot import and the interpreter to use instead."""
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError as err:
            return f"{sys.executable} cannot import {err.name}; use /usr/bin/python3"
    return None
